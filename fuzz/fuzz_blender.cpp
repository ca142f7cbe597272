// libFuzzer target: the Blender multilayer importer behind read_frame. The input names the
// channels of a small, well-formed EXR that OpenImageIO writes, so the fuzzer works on the layer,
// pass, view and channel names (and the values: 1e10 depth, NaN ids) rather than on OpenEXR's
// container, which fuzz_exr covers.
// Input: channel names separated by '\n', then a 0 byte, then [width, height, one type byte per
// channel (even: float, odd: half)], then pixel bytes, repeated to fill the image.
#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "oiio_scratch.hpp"
#include "reprise/core/exr.hpp"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
    const uint8_t* end = data + size;
    const uint8_t* names_end = std::find(data, end, uint8_t(0));
    std::vector<std::string> channels;
    for (const uint8_t* at = data; at < names_end;) {
        const uint8_t* line = std::find(at, names_end, uint8_t('\n'));
        channels.emplace_back(at, line);
        at = line + 1;
    }
    if (channels.empty() || channels.size() > 64) return 0;
    const uint8_t* rest = names_end == end ? end : names_end + 1;
    auto next = [&](uint8_t fallback) { return rest < end ? *rest++ : fallback; };
    const int width = 1 + next(2) % 5, height = 1 + next(1) % 5;
    OIIO::ImageSpec spec(width, height, int(channels.size()), OIIO::TypeFloat);
    spec.channelnames = channels;
    spec.channelformats.clear();
    for (size_t c = 0; c < channels.size(); ++c)
        spec.channelformats.push_back(next(0) % 2 ? OIIO::TypeHalf : OIIO::TypeFloat);
    std::vector<float> pixels(size_t(width) * height * channels.size());
    const size_t available = size_t(end - rest);
    for (size_t i = 0; i < pixels.size() && available >= 4; ++i)
        for (size_t b = 0; b < 4; ++b)
            reinterpret_cast<uint8_t*>(&pixels[i])[b] = rest[(4 * i + b) % available];

    static const std::string path = fuzz_scratch_path("blender-");
    auto out = OIIO::ImageOutput::create(path);
    if (!out || !out->open(path, spec)) return 0;  // e.g. duplicate or empty channel names
    const bool written = out->write_image(OIIO::TypeFloat, pixels.data()) && out->close();
    if (written) {
        reprise::FrameHeader header;
        (void)reprise::read_frame_header(path, header);
        reprise::Frame frame;
        (void)reprise::read_frame(path, frame);
    }
    std::remove(path.c_str());
    return 0;
}
