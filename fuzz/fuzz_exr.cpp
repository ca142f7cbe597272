// libFuzzer target: read_frame_header and read_frame on one whole EXR file (reprise frames and
// Blender renders as seeds). read_frame takes a file name, so each input is written to a file in
// /dev/shm (RAM) first.
#include <cstdint>
#include <cstdio>
#include <string>

#include "oiio_scratch.hpp"
#include "reprise/core/exr.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    static const std::string path = fuzz_scratch_path("");
    std::FILE* file = std::fopen(path.c_str(), "wb");
    if (!file) return 0;
    const bool written = std::fwrite(data, 1, size, file) == size;
    std::fclose(file);
    if (!written) return 0;
    reprise::FrameHeader header;
    if (reprise::read_frame_header(path, header).ok()) {
        // Frames far larger than any seed only measure memory, not parsing.
        if (uint64_t(header.width) * uint64_t(header.height) <= 256 * 256) {
            reprise::Frame frame;
            (void)reprise::read_frame(path, frame);
        }
    }
    std::remove(path.c_str());
    return 0;
}
