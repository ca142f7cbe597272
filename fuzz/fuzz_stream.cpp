// libFuzzer target: a damaged .rps file through the resynchronising reader and the decoder. Input:
// the bytes after a fixed 24-byte file header (64x48), so mutations land on the packets.
#include <cstdint>
#include <vector>

#include "reprise/codec/codec.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static std::vector<uint8_t> file;
    file.clear();
    if (!reprise::codec::write_stream_header(file, 64, 48, 30.0).ok()) __builtin_trap();
    file.insert(file.end(), data, data + size);
    reprise::codec::Decoder decoder;
    REPRISE_ASSERT(reprise::codec::Decoder::create(
                       reprise::codec::DecoderOptions{.max_pixels = 512 * 512}, decoder)
                       .ok());
    reprise::codec::StreamInfo info;
    reprise::codec::StreamReport report;
    std::size_t frames = 0;
    const reprise::Status s =
        reprise::codec::decode_stream(file, decoder, info, report, [&](uint32_t, reprise::Frame&) {
            ++frames;
            return reprise::Status{};
        });
    // Every byte after the header is in a packet or a damaged stretch, and the summary is built.
    std::size_t skipped = 0;
    for (const auto& d : report.damage) skipped += d.bytes;
    if (!s.ok() || frames != report.frames || skipped > size || report.summary().empty())
        __builtin_trap();
    return 0;
}
