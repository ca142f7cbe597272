// Doubles the frame rate of an EXR sequence: reads every frame of IN, makes one frame between
// each pair with reprise's frame-rate converter, and writes the result to OUT.
//   upconvert IN OUT
#include <cstdio>
#include <filesystem>
#include <utility>

#include "reprise/core/exr.hpp"
#include "reprise/warp/fruc.hpp"

namespace {

reprise::Status upconvert(const std::string& in_dir, const std::string& out_dir, int& written) {
    reprise::Sequence sequence;
    REPRISE_TRY(reprise::open_sequence(in_dir, sequence));
    std::error_code error;
    std::filesystem::create_directories(out_dir, error);
    if (error) return reprise::Status::error(out_dir + ": " + error.message());

    reprise::warp::FrameRateConverter converter;
    REPRISE_TRY(reprise::warp::FrameRateConverter::create(
        2,
        {.mode = reprise::warp::FrucMode::Interpolate, .fill = reprise::warp::FillMethod::PullPush},
        converter));
    reprise::Frame in, out;
    for (const std::string& file : sequence.files) {
        REPRISE_TRY(reprise::read_frame(file, in));
        if (in.fps <= 0) in.fps = sequence.fps;
        REPRISE_TRY(converter.send(std::move(in)));  // kept, not copied; `in` gets buffers back
        while (converter.receive(out))
            REPRISE_TRY(reprise::write_frame(reprise::frame_path(out_dir, written++), out));
    }
    return {};
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 3) {
        std::fprintf(stderr, "usage: upconvert IN OUT\n");
        return 2;
    }
    int written = 0;
    const reprise::Status status = upconvert(argv[1], argv[2], written);
    if (!status.ok()) {
        std::fprintf(stderr, "upconvert: %s\n", status.message().c_str());
        return 1;
    }
    std::printf("upconvert: %d frames written to %s\n", written, argv[2]);
    return 0;
}
