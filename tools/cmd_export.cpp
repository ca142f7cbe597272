// reprise export: a sequence as a PNG contact sheet, one PNG per frame, or an MP4.
#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>

#include "args.hpp"
#include "commands.hpp"
#include "outputs.hpp"
#include "reprise/core/exr.hpp"
#include "reprise/core/video.hpp"
#include "reprise/core/visualize.hpp"
#include "reprise/stereo/compose.hpp"

namespace reprise::cli {

namespace {

namespace fs = std::filesystem;

enum class Channel { Color, Depth, Motion, Normal, Id };
constexpr const char* kChannelNames[] = {"color", "depth", "motion", "normal", "id"};
constexpr int kSheetRows = 6;
constexpr int kSheetTileWidth = 480;
constexpr float kMotionQuantile = 0.98f;  // of the moving pixels, shown fully saturated

struct Options {
    std::string dir, png, mp4, channel = "color", stereo;
    double fps = 0.0;
    double motion_max = 0.0;
};

// Display ranges shared by all frames of one export, so that the pictures are comparable.
struct Ranges {
    DepthRange depth;
    float motion = 0.0f;
};

bool present(const Frame& f, Channel c) {
    switch (c) {
        case Channel::Color:
            return !f.color.empty();
        case Channel::Depth:
            return !f.depth.empty();
        case Channel::Motion:
            return !f.motion.empty();
        case Channel::Normal:
            return !f.normal.empty();
        case Channel::Id:
            return !f.id.empty();
    }
    return false;
}

void widen(Ranges& r, const Frame& f) {
    if (!f.depth.empty()) {
        DepthRange d = depth_range(f.depth.view());
        if (d.far > 0.0f) {
            r.depth = r.depth.far > 0.0f
                          ? DepthRange{std::min(r.depth.near, d.near), std::max(r.depth.far, d.far)}
                          : d;
        }
    }
    if (!f.motion.empty())
        r.motion = std::max(r.motion, motion_length(f.motion.view(), kMotionQuantile));
}

Status display(const Frame& f, const std::string& file, Channel c, const Ranges& r,
               Image<Rgb8>& out) {
    if (!present(f, c))
        return Status::error(file + ": has no " + kChannelNames[int(c)] + " channel");
    auto sized = [&](const auto& image) {
        return image.width() == f.width() && image.height() == f.height();
    };
    bool same = c == Channel::Depth    ? sized(f.depth)
                : c == Channel::Motion ? sized(f.motion)
                : c == Channel::Normal ? sized(f.normal)
                : c == Channel::Id     ? sized(f.id)
                                       : true;
    if (!same)
        return Status::error(file + ": the " + kChannelNames[int(c)] +
                             " channel's size differs from the colour's");
    out.resize(f.width(), f.height());
    switch (c) {
        case Channel::Color:
            if (f.ui.empty() || !sized(f.ui)) {
                visualize_color(f.color.view(), out.view());
            } else {  // the UI layer drawn over the scene, as it is shown
                Image<glm::vec4> shown(f.width(), f.height());
                composite_ui(f.color.view(), f.ui.view(), shown.view());
                visualize_color(shown.view(), out.view());
            }
            break;
        case Channel::Depth:
            visualize_depth(f.depth.view(), out.view(), r.depth);
            break;
        case Channel::Motion:
            visualize_motion(f.motion.view(), out.view(), r.motion);
            break;
        case Channel::Normal:
            visualize_normal(f.normal.view(), out.view());
            break;
        case Channel::Id:
            visualize_id(f.id.view(), out.view());
            break;
    }
    return {};
}

std::string stem(const std::string& file) { return fs::path(file).stem().string(); }

class Progress {
public:
    Progress(const char* what, std::size_t total)
        : what_(what), total_(total), tty_(::isatty(::fileno(stderr))) {}
    void step(std::size_t done) const {
        if (tty_) std::fprintf(stderr, "\r[%s] %zu/%zu", what_, done, total_);
    }
    void finish(const std::string& result) const {
        if (tty_) std::fputs("\r\033[K", stderr);
        std::fprintf(stderr, "[%s] %zu frames -> %s\n", what_, total_, result.c_str());
    }

private:
    const char* what_;
    std::size_t total_;
    bool tty_;
};

// The first frame fixes the display ranges for the whole video or folder, unless given.
Ranges first_ranges(const Frame& first, const Options& o) {
    Ranges r;
    widen(r, first);
    if (o.motion_max > 0.0) r.motion = float(o.motion_max);
    return r;
}

Status export_mp4(const Options& o, const Sequence& seq, Channel channel) {
    double fps = o.fps > 0.0 ? o.fps : seq.fps > 0.0 ? seq.fps : 30.0;
    Frame frame;
    Image<Rgb8> picture;
    Ranges ranges;
    VideoWriter writer;
    Progress progress("export", seq.files.size());
    for (std::size_t i = 0; i < seq.files.size(); ++i) {
        const std::string& file = seq.files[i];
        REPRISE_TRY(read_frame(file, frame));
        if (i == 0) {
            ranges = first_ranges(frame, o);
            REPRISE_TRY(writer.open(o.mp4, frame.width(), frame.height(), {.fps = fps}));
        }
        REPRISE_TRY(display(frame, file, channel, ranges, picture));
        REPRISE_TRY(writer.write(picture.view()));
        progress.step(i + 1);
    }
    REPRISE_TRY(writer.close());
    progress.finish(o.mp4);
    return {};
}

Status export_png_folder(const Options& o, const Sequence& seq, Channel channel) {
    std::error_code ec;
    fs::create_directories(o.png, ec);
    if (ec) return Status::error(o.png + ": cannot create the folder: " + ec.message());
    Frame frame;
    Image<Rgb8> picture;
    Ranges ranges;
    Progress progress("export", seq.files.size());
    for (std::size_t i = 0; i < seq.files.size(); ++i) {
        const std::string& file = seq.files[i];
        REPRISE_TRY(read_frame(file, frame));
        if (i == 0) ranges = first_ranges(frame, o);
        REPRISE_TRY(display(frame, file, channel, ranges, picture));
        REPRISE_TRY(write_png((fs::path(o.png) / (stem(file) + ".png")).string(), picture.view()));
        progress.step(i + 1);
    }
    progress.finish(o.png);
    return {};
}

// Rows: frames sampled evenly (up to kSheetRows); columns: colour, depth, motion.
Status export_sheet(const Options& o, const Sequence& seq) {
    const std::size_t n = seq.files.size();
    const std::size_t rows = std::min<std::size_t>(n, kSheetRows);
    std::vector<std::size_t> picks;
    for (std::size_t r = 0; r < rows; ++r)
        picks.push_back(rows == 1 ? 0 : std::size_t(std::lround(double(r) * (n - 1) / (rows - 1))));

    std::vector<Frame> frames(rows);
    Ranges ranges;
    Progress progress("export", rows);
    for (std::size_t r = 0; r < rows; ++r) {
        REPRISE_TRY(read_frame(seq.files[picks[r]], frames[r]));
        if (frames[r].width() != frames[0].width() || frames[r].height() != frames[0].height())
            return Status::error(seq.files[picks[r]] + ": frame size differs from " +
                                 seq.files[picks[0]]);
        widen(ranges, frames[r]);
        progress.step(r + 1);
    }

    // Depth shares one range; motion is scaled per frame (its scale in the label) so that one
    // fast frame does not wash out the others, unless --motion-max fixes it.
    char depth_label[64];
    std::snprintf(depth_label, sizeof depth_label, "depth %.3g..%.3g", ranges.depth.near,
                  ranges.depth.far);
    std::vector<Image<Rgb8>> pictures;
    pictures.reserve(rows * 3);
    std::vector<Tile> tiles;
    for (std::size_t r = 0; r < rows; ++r) {
        const std::string& file = seq.files[picks[r]];
        Ranges row = ranges;
        row.motion = o.motion_max > 0.0 ? float(o.motion_max) : first_ranges(frames[r], o).motion;
        char motion_label[64];
        std::snprintf(motion_label, sizeof motion_label, "motion %.3g px", row.motion);
        for (Channel c : {Channel::Color, Channel::Depth, Channel::Motion}) {
            pictures.emplace_back();
            if (!present(frames[r], c)) {
                tiles.push_back({{}, std::string("no ") + kChannelNames[int(c)]});
                continue;
            }
            REPRISE_TRY(display(frames[r], file, c, row, pictures.back()));
            tiles.push_back({pictures.back().view(), c == Channel::Color   ? stem(file)
                                                     : c == Channel::Depth ? depth_label
                                                                           : motion_label});
        }
    }
    const int tile_width = std::min(frames[0].width(), kSheetTileWidth);
    Image<Rgb8> sheet = contact_sheet(tiles, {.columns = 3, .tile_width = tile_width});
    REPRISE_TRY(write_png(o.png, sheet.view()));
    progress.finish(o.png);
    return {};
}

bool names_folder(const std::string& path) {
    std::error_code ec;
    return path.back() == '/' || fs::is_directory(path, ec);
}

// DIR/left and DIR/right composed frame by frame: a video, a PNG per frame (--png DIR/) or the
// first pair as one PNG.
Status export_stereo(const Options& o, stereo::Layout layout) {
    Sequence left, right;
    REPRISE_TRY(open_sequence((fs::path(o.dir) / "left").string(), left));
    REPRISE_TRY(open_sequence((fs::path(o.dir) / "right").string(), right));
    if (left.files.size() != right.files.size())
        return Status::error(o.dir + ": left/ has " + std::to_string(left.files.size()) +
                             " frames, right/ " + std::to_string(right.files.size()));
    const bool folder = o.mp4.empty() && names_folder(o.png);
    const std::size_t n = o.mp4.empty() && !folder ? 1 : left.files.size();
    if (folder) {
        std::error_code ec;
        fs::create_directories(o.png, ec);
        if (ec) return Status::error(o.png + ": cannot create the folder: " + ec.message());
    }
    const double fps = o.fps > 0.0 ? o.fps : left.fps > 0.0 ? left.fps : 30.0;
    Frame l, r;
    Image<Rgb8> picture;
    VideoWriter writer;
    Progress progress("export", n);
    for (std::size_t i = 0; i < n; ++i) {
        REPRISE_TRY(read_frame(left.files[i], l));
        REPRISE_TRY(read_frame(right.files[i], r));
        if (l.width() != r.width() || l.height() != r.height())
            return Status::error(right.files[i] + ": size differs from " + left.files[i]);
        stereo::compose(l.color.view(), r.color.view(), layout, picture);
        if (!o.mp4.empty()) {
            if (i == 0)
                REPRISE_TRY(writer.open(o.mp4, picture.width(), picture.height(), {.fps = fps}));
            REPRISE_TRY(writer.write(picture.view()));
        } else if (folder) {
            REPRISE_TRY(write_png((fs::path(o.png) / (stem(left.files[i]) + ".png")).string(),
                                  picture.view()));
        } else {
            REPRISE_TRY(write_png(o.png, picture.view()));
        }
        progress.step(i + 1);
    }
    if (!o.mp4.empty()) REPRISE_TRY(writer.close());
    progress.finish(o.mp4.empty() ? o.png : o.mp4);
    return {};
}

Status run(const Options& o, Channel channel) {
    const bool mp4 = !o.mp4.empty();
    REPRISE_TRY(check_output(mp4 ? "--mp4" : "--png", mp4 ? o.mp4 : o.png, false,
                             {.inputs = {o.dir}, .overwrite_inputs = false}));
    if (!o.stereo.empty())
        return export_stereo(o, o.stereo == "sbs"  ? stereo::Layout::SideBySide
                                : o.stereo == "tb" ? stereo::Layout::TopBottom
                                                   : stereo::Layout::Anaglyph);
    Sequence seq;
    REPRISE_TRY(open_sequence(o.dir, seq));
    if (!o.mp4.empty()) return export_mp4(o, seq, channel);
    if (names_folder(o.png)) return export_png_folder(o, seq, channel);
    return export_sheet(o, seq);
}

}  // namespace

int command_export(int argc, char** argv) {
    Options o;
    Args args(
        "export",
        "Pictures of a sequence: --png FILE.png writes a contact sheet (up to 6 frames\n"
        "sampled evenly; colour, depth, motion), --png DIR/ one PNG of --channel per frame,\n"
        "--mp4 FILE an H.264 video of --channel through the ffmpeg executable.\n"
        "Depth is grey on a log scale (near white, background black); motion is a flow wheel\n"
        "(hue = direction, white = still). Depth and motion ranges come from the first frame\n"
        "(for a sheet: depth from all its frames, motion per frame).");
    args.positional("DIR", &o.dir, "sequence: folder of EXR frames or one .exr");
    args.option("--png", &o.png, "contact sheet FILE.png, or a folder (DIR/ or existing)");
    args.option("--mp4", &o.mp4, "video file");
    args.option("--channel", &o.channel, "color|depth|motion|normal|id (default color)");
    args.option("--fps", &o.fps, "video frame rate (default: the sequence's, else 30)");
    args.option("--motion-max", &o.motion_max, "motion length shown fully saturated, pixels");
    args.option("--stereo", &o.stereo,
                "sbs|tb|anaglyph: DIR holds left/ and right/; side by side, top-bottom or red-cyan "
                "(Dubois) colour pictures (--png FILE: the first pair only)");
    Status parsed = args.parse(argc, argv);
    Channel channel = Channel::Color;
    if (parsed.ok() && !args.help_requested()) {
        auto name = std::find(std::begin(kChannelNames), std::end(kChannelNames), o.channel);
        if (o.png.empty() == o.mp4.empty())
            parsed = Status::error("export: give exactly one of --png and --mp4");
        else if (name == std::end(kChannelNames))
            parsed = Status::error("export: --channel: '" + o.channel +
                                   "' is not color, depth, motion, normal or id");
        else if (args.given("--fps") && !(o.fps > 0.0 && o.fps <= 1000.0))
            parsed = Status::error("export: --fps must be in (0, 1000]");
        else if (!o.stereo.empty() && o.stereo != "sbs" && o.stereo != "tb" &&
                 o.stereo != "anaglyph")
            parsed =
                Status::error("export: --stereo: '" + o.stereo + "' is not sbs, tb or anaglyph");
        else if (o.motion_max < 0.0)
            parsed = Status::error("export: --motion-max must not be negative");
        else
            channel = Channel(name - std::begin(kChannelNames));
    }
    if (!parsed.ok() || args.help_requested()) return report(args, parsed, {});
    return report(args, parsed, run(o, channel));
}

}  // namespace reprise::cli
