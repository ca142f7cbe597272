// libFuzzer target: the codec decoder on a sequence of packets. Input: records of a 16-bit
// little-endian length and that many bytes. Each record's header gets its length field and CRC
// made consistent, so the fuzzer reaches the section parsers behind the checksum.
#include <cstdint>
#include <cstring>
#include <vector>

#include "../codec/src/internal.hpp"
#include "reprise/codec/codec.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    reprise::codec::Decoder decoder;
    REPRISE_ASSERT(reprise::codec::Decoder::create(
                       reprise::codec::DecoderOptions{.max_pixels = 512 * 512}, decoder)
                       .ok());
    std::size_t at = 0;
    std::vector<uint8_t> packet;
    reprise::Frame frame;
    while (at + 2 <= size) {
        const std::size_t length = std::size_t(data[at]) | std::size_t(data[at + 1]) << 8;
        at += 2;
        const std::size_t n = std::min(length, size - at);
        packet.assign(data + at, data + at + n);
        at += n;
        (void)reprise::codec::reseal_packet(packet);
        (void)decoder.send_packet(packet);
        while (decoder.receive_frame(frame) == reprise::Result::Ok) {
        }
    }
    return 0;
}
