// libFuzzer target: the codec decoder on a sequence of packets. Input: records of a 16-bit
// little-endian length and that many bytes. Each record's header gets its length field and CRC
// made consistent, so the fuzzer reaches the section parsers behind the checksum.
#include <cstdint>
#include <cstring>
#include <vector>

#include "../codec/src/crc32c.hpp"
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
        if (packet.size() >= 32) {
            const uint32_t payload = uint32_t(packet.size() - 32);
            std::memcpy(packet.data() + 24, &payload, 4);
            uint32_t crc = reprise::codec::crc32c(std::span(packet).first(28), 0);
            crc = reprise::codec::crc32c(std::span(packet).subspan(32), crc);
            std::memcpy(packet.data() + 28, &crc, 4);
        }
        (void)decoder.send_packet(packet);
        while (decoder.receive_frame(frame) == reprise::Result::Ok) {
        }
    }
    return 0;
}
