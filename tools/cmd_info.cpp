// reprise info FILE.exr|DIR: size, channels, camera, frame rate and value statistics.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <string>
#include <type_traits>

#include "args.hpp"
#include "commands.hpp"
#include "reprise/core/exr.hpp"

namespace reprise::cli {
namespace {

struct ChannelStats {
    double min = std::numeric_limits<double>::infinity();
    double max = -std::numeric_limits<double>::infinity();
    std::size_t nan = 0;
    std::size_t inf = 0;

    void add(double v) {
        if (std::isnan(v))
            ++nan;
        else if (std::isinf(v))
            ++inf;
        else {
            min = std::min(min, v);
            max = std::max(max, v);
        }
    }
};

void print_stats(const char* name, const ChannelStats& s) {
    if (s.min <= s.max)
        std::printf("  %-9s %16.10g %16.10g %9zu %9zu\n", name, s.min, s.max, s.nan, s.inf);
    else
        std::printf("  %-9s %16s %16s %9zu %9zu\n", name, "-", "-", s.nan, s.inf);
}

// Component `k` of every pixel; T is a glm vector or a scalar.
template <class T>
ChannelStats stats(const Image<T>& image, int k) {
    ChannelStats s;
    for (std::size_t i = 0; i < image.pixel_count(); ++i) {
        if constexpr (std::is_arithmetic_v<T>)
            s.add(double(image.data()[i]));
        else
            s.add(double(image.data()[i][k]));
    }
    return s;
}

void print_matrix(const char* name, const glm::mat4& m) {
    for (int row = 0; row < 4; ++row)
        std::printf("  %-16s [%12.6g %12.6g %12.6g %12.6g ]\n", row == 0 ? name : "", m[0][row],
                    m[1][row], m[2][row], m[3][row]);
}

Status run(const std::string& path, int frame_index) {
    Sequence sequence;
    REPRISE_TRY(open_sequence(path, sequence));
    const int count = int(sequence.files.size());
    if (frame_index < 0 || frame_index >= count)
        return Status::error(path + ": --frame " + std::to_string(frame_index) + " is outside 0.." +
                             std::to_string(count - 1));
    const std::string& file = sequence.files[frame_index];

    FrameHeader header;
    REPRISE_TRY(read_frame_header(file, header));
    Frame frame;
    REPRISE_TRY(read_frame(file, frame));

    if (std::filesystem::is_directory(path))
        std::printf("%s: %d frame%s, %s .. %s\n", path.c_str(), count, count == 1 ? "" : "s",
                    std::filesystem::path(sequence.files.front()).filename().c_str(),
                    std::filesystem::path(sequence.files.back()).filename().c_str());
    std::printf("%s: %dx%d, %s\n", file.c_str(), header.width, header.height,
                header.blender ? "Blender multilayer render" : "reprise frame");
    std::printf("channels:");
    for (std::size_t c = 0; c < header.channels.size(); ++c)
        std::printf(" %s(%s)", header.channels[c].c_str(), header.channel_types[c].c_str());
    std::printf("\n");
    if (header.fps > 0)
        std::printf("frame rate: %g fps\n", header.fps);
    else
        std::printf("frame rate: not recorded\n");

    if (header.has_camera) {
        const Camera& c = header.camera;
        std::printf("camera:\n");
        print_matrix("view", c.view);
        print_matrix("projection", c.projection);
        print_matrix("prev view", c.prev_view);
        print_matrix("prev projection", c.prev_projection);
        std::printf("  near %g  far %g  jitter (%g, %g) px  time %.9g s\n", c.near, c.far,
                    c.jitter.x, c.jitter.y, c.time);
    } else {
        std::printf("camera: not recorded\n");
    }

    std::printf("values of frame %d (min and max of finite values):\n", frame_index);
    std::printf("  %-9s %16s %16s %9s %9s\n", "buffer", "min", "max", "NaN", "Inf");
    const char* color_names[] = {"R", "G", "B", "A"};
    for (int k = 0; k < 4; ++k) print_stats(color_names[k], stats(frame.color, k));
    if (!frame.depth.empty()) print_stats("Z", stats(frame.depth, 0));
    if (!frame.motion.empty()) {
        print_stats("motion.x", stats(frame.motion, 0));
        print_stats("motion.y", stats(frame.motion, 1));
    }
    if (!frame.normal.empty()) {
        print_stats("N.X", stats(frame.normal, 0));
        print_stats("N.Y", stats(frame.normal, 1));
        print_stats("N.Z", stats(frame.normal, 2));
    }
    if (!frame.id.empty()) print_stats("id", stats(frame.id, 0));
    return {};
}

}  // namespace

int command_info(int argc, char** argv) {
    std::string path;
    int frame_index = 0;
    Args args("info",
              "Size, channels, camera and frame rate of an EXR frame or a folder of them,\n"
              "with min/max/NaN/Inf of every buffer of one frame.");
    args.positional("PATH", &path, "an .exr frame, a folder of frames, or an .rps stream");
    args.option("--frame", &frame_index, "which frame of a folder to describe (default 0)");
    const Status parsed = args.parse(argc, argv);
    if (!parsed.ok() || args.help_requested()) return report(args, parsed, {});
    if (path.size() > 4 && path.compare(path.size() - 4, 4, ".rps") == 0)
        return report(args, parsed, describe_stream(path));
    return report(args, parsed, run(path, frame_index));
}

}  // namespace reprise::cli
