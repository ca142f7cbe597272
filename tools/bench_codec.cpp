// reprise bench codec — error against bits against run time: reprise's scene-aware codec beside
// x264, x265 and SVT-AV1 (through libavcodec) on the same 8-bit display frames, Bjøntegaard
// delta rates, the depth coders (reprise lossless, zstd -3, RVL), the views a client makes from
// the decoded depth (synthesized_views.hpp) and the speed ratios at 1080p.
//
// OUT/codec.csv: scene,codec,setting,frame,bits,psnr,ssim,flip,encode_ms,decode_ms (display
// values against the original colour; codec "reprise" counts all its bits, "reprise-color" the
// same frames with its colour bits only). OUT/bd_rate.csv, OUT/depth.csv, OUT/speed.csv,
// OUT/index.html (rate-distortion curves and time bars).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <memory>
#include <span>
#include <string>
#include <tuple>
#include <vector>

#include "args.hpp"
#include "bd_rate.hpp"
#include "bench.hpp"
#include "bench_report.hpp"
#include "codec_peers.hpp"
#include "depth_peers.hpp"
#include "depth_video_peer.hpp"
#include "reprise/codec/codec.hpp"
#include "reprise/core/exr.hpp"
#include "reprise/core/metrics.hpp"
#include "reprise/core/nonfinite.hpp"
#include "reprise/core/parallel.hpp"
#include "reprise/server/builtin_scenes.hpp"
#include "reprise/server/renderer.hpp"
#include "synthesized_views.hpp"

namespace reprise::cli {

namespace {

namespace fs = std::filesystem;

constexpr const char* kOurs = "reprise";
constexpr const char* kOursColor = "reprise-color";
// Total bits of the default stream: depth to the view bound, motion within 0.25 px.
constexpr const char* kOursStream = "reprise-stream";
constexpr double kColorBdTarget = -20.0;       // % against x264 veryfast, PSNR, mean over scenes
constexpr double kStreamBdTarget = 0.0;        // all bits of the default stream, the same
constexpr double kGeometryShareTarget = 20.0;  // % of the default stream for depth + motion
constexpr double kDecodeOverEncodeTarget = 2.0;
constexpr double kDepthRatioTarget = 2.0;  // zstd -3 bytes / reprise lossless depth bytes
constexpr double kViewLossTarget = 0.2;    // dB, views from decoded depth against rendered depth

// One encoded frame, scored.
struct Sample {
    int frame = 0;
    double bits = 0.0;
    ImageError error;
    double encode_ms = 0.0, decode_ms = 0.0;
};

// One codec at one rate point on one sequence.
struct RunResult {
    std::string codec, setting, group;  // group: the curve it belongs to ("x264 veryfast")
    std::vector<Sample> samples;
    // The mean over the samples from `first` on.
    double mean(double Sample::*field, std::size_t first = 0) const {
        double sum = 0.0;
        for (std::size_t i = first; i < samples.size(); ++i) sum += samples[i].*field;
        return samples.size() <= first ? NAN : sum / double(samples.size() - first);
    }
    double mean_error(double ImageError::*field) const {
        double sum = 0.0;
        for (const Sample& s : samples) sum += s.error.*field;
        return samples.empty() ? NAN : sum / double(samples.size());
    }
};

struct Sequence {
    std::string name, note;
    bool builtin = false;
    double fps = 30.0;
    std::vector<Frame> frames;            // the G-buffers (colour, depth, motion, camera)
    std::vector<Image<Rgb8>> shown;       // 8-bit display values: what every codec gets
    std::vector<Image<glm::vec3>> truth;  // display values of the original colour
    // Built-in scenes and glTF files: what rendered them, for views at other instants and eyes.
    std::shared_ptr<server::Scene> scene;
    server::CameraPath path;
};

struct DepthResult {
    std::string coder;
    std::vector<double> bytes, encode_ms, decode_ms;
    bool lossless = true;
    double total_bytes() const {
        double sum = 0.0;
        for (double b : bytes) sum += b;
        return sum;
    }
};

void add_frame(Sequence& seq, Frame&& frame) {
    frame.normal.clear();  // no codec reads them; a 30-frame 1080p sequence stays under 2 GB
    Image<glm::vec3> display(frame.width(), frame.height());
    to_display(frame.color.view(), display.view());
    Image<Rgb8> shown(frame.width(), frame.height());
    visualize_color(frame.color.view(), shown.view());
    seq.truth.push_back(std::move(display));
    seq.shown.push_back(std::move(shown));
    seq.frames.push_back(std::move(frame));
}

Status render_sequence(server::Renderer& renderer, const std::string& scene_name, int frames, int w,
                       int h, Sequence& seq) {
    seq.scene = std::make_shared<server::Scene>();
    const server::Scene& scene = *seq.scene;
    const server::CameraPath& path = seq.path;
    REPRISE_TRY(server::load_scene(scene_name, *seq.scene, seq.path));
    seq.name = fs::path(scene_name).stem().string();
    seq.fps = 30.0;
    for (const server::SceneInfo& info : server::builtin_scenes())
        if (info.name == scene_name) seq.note = info.stresses, seq.builtin = true;
    for (int i = 0; i < frames; ++i) {
        Frame frame;
        REPRISE_TRY(
            renderer.render_frame(scene, path, i, seq.fps, {.width = w, .height = h}, frame));
        add_frame(seq, std::move(frame));
        std::fprintf(stderr, "\r[codec] %s: rendering %d/%d   ", seq.name.c_str(), i + 1, frames);
    }
    std::fprintf(stderr, "\n");
    return {};
}

Status read_sequence(const std::string& dir, int frames, Sequence& seq) {
    reprise::Sequence files;
    REPRISE_TRY(open_sequence(dir, files));
    seq.name = fs::path(dir).filename().string();
    if (seq.name.empty()) seq.name = fs::path(dir).parent_path().filename().string();
    seq.note = "sequence folder " + dir;
    seq.fps = files.fps > 0.0 ? files.fps : 30.0;
    const int n = std::min<int>(frames, int(files.files.size()));
    for (int i = 0; i < n; ++i) {
        Frame frame;
        REPRISE_TRY(read_frame(files, i, frame));
        if (i > 0 &&
            (frame.width() != seq.frames[0].width() || frame.height() != seq.frames[0].height()))
            return Status::error(files.files[i] + ": size differs from the first frame");
        add_frame(seq, std::move(frame));
        std::fprintf(stderr, "\r[codec] %s: reading %d/%d   ", seq.name.c_str(), i + 1, n);
    }
    std::fprintf(stderr, "\n");
    if (seq.frames.empty()) return Status::error(dir + ": no frames");
    return {};
}

ImageError score(const Image<glm::vec3>& truth, const Image<Rgb8>& decoded,
                 Image<glm::vec3>& scratch) {
    from_rgb8(decoded.view(), scratch);
    return image_error(truth.view(), scratch.view());
}

std::string peer_group(const PeerConfig& c) {
    return peer_name(c.kind) + " " + (c.kind == PeerKind::SvtAv1 ? "p" : "") + c.preset;
}

Status run_peer(const Sequence& seq, const PeerConfig& config, RunResult& run,
                double* convert_ms = nullptr) {
    std::vector<PeerFrame> out;
    REPRISE_TRY(encode_decode_peer(seq.shown, config, seq.fps, out));
    if (convert_ms) {
        convert_ms[0] = convert_ms[1] = 0.0;
        for (const PeerFrame& f : out)
            convert_ms[0] += f.encode_convert_ms / double(out.size()),
                convert_ms[1] += f.decode_convert_ms / double(out.size());
    }
    run = {peer_name(config.kind), peer_setting(config), peer_group(config), {}};
    Image<glm::vec3> scratch;
    for (std::size_t i = 0; i < out.size(); ++i)
        run.samples.push_back({int(i), 8.0 * double(out[i].bytes),
                               score(seq.truth[i], out[i].decoded, scratch), out[i].encode_ms,
                               out[i].decode_ms});
    return {};
}

// Frame i through reprise's encoder (its colour as `display` values when given) and decoder,
// each timed.
Status code_frame(codec::Encoder& encoder, codec::Decoder& decoder, const Frame& frame,
                  ImageView<const glm::u8vec4> display, std::size_t i, codec::Packet& packet,
                  codec::DecodedFrame& decoded, double& encode_ms, double& decode_ms) {
    auto start = BenchClock::now();
    REPRISE_TRY(display.empty() ? encoder.send_frame(frame) : encoder.send_frame(frame, display));
    if (encoder.receive_packet(packet) != Result::Ok)
        return Status::error("reprise codec: no packet for frame " + std::to_string(i));
    encode_ms = ms_since(start);
    start = BenchClock::now();
    REPRISE_TRY(decoder.send_packet(packet.data));
    if (decoder.receive_frame(decoded) != Result::Ok)
        return Status::error("reprise codec: no decoded frame for frame " + std::to_string(i));
    decode_ms = ms_since(start);
    return {};
}

// reprise's codec at one qp: every frame encoded, its packet decoded, the decoded colour scored.
// `color` gets the same frames counted with their colour bits only; `depth_bits` the depth
// stream's bits per frame.
Status run_ours(const Sequence& seq, int qp, bool default_stream, RunResult& total,
                RunResult& color, std::vector<double>* depth_bits,
                codec::StreamStats* encoder_stats = nullptr,
                codec::StreamStats* decoder_stats = nullptr) {
    const std::string setting = "qp " + std::to_string(qp);
    const char* name = default_stream ? kOursStream : kOurs;
    total = {name, setting, name, {}};
    color = {kOursColor, setting, kOursColor, {}};
    codec::EncoderOptions options{.qp = qp, .fps = seq.fps, .depth = codec::DepthMode::View};
    if (!default_stream) options.depth = codec::DepthMode::Lossless, options.motion_error_px = 0;
    codec::Encoder encoder;
    REPRISE_TRY(codec::Encoder::create(options, encoder));
    codec::Decoder decoder;
    codec::Packet packet;
    codec::DecodedFrame decoded;
    Image<glm::vec3> display;
    for (std::size_t i = 0; i < seq.frames.size(); ++i) {
        double encode_ms = 0.0, decode_ms = 0.0;
        REPRISE_TRY(code_frame(encoder, decoder, seq.frames[i], {}, i, packet, decoded, encode_ms,
                               decode_ms));
        const codec::StreamStats& stats = encoder.last_frame_stats();
        if (8 * packet.data.size() < stats.total_bits() && i == 0)
            std::fprintf(stderr,
                         "[codec] note: reprise's stream stats count %zu bits, its packet "
                         "has %zu\n",
                         stats.total_bits(), 8 * packet.data.size());
        display.resize(decoded.color.width(), decoded.color.height());
        to_display(decoded.color.view(), display.view());
        Sample s{int(i), 8.0 * double(packet.data.size()),
                 image_error(seq.truth[i].view(), display.view()), encode_ms, decode_ms};
        total.samples.push_back(s);
        s.bits = double(stats.color_bits);
        color.samples.push_back(s);
        if (depth_bits) depth_bits->push_back(double(stats.depth_bits));
    }
    if (encoder_stats) *encoder_stats = encoder.stats();
    if (decoder_stats) *decoder_stats = decoder.stats();
    return {};
}

// reprise's default stream fed and read as the peers are: 8-bit sRGB in (the RGB they get, as
// RGBA8), 8-bit sRGB out (DecoderOptions::display); the same codes as from linear colour.
Status run_ours_display(const Sequence& seq, int qp, RunResult& run) {
    run = {kOursStream, "qp " + std::to_string(qp) + " 8-bit", kOursStream, {}};
    codec::Encoder encoder;
    REPRISE_TRY(codec::Encoder::create({.qp = qp, .fps = seq.fps, .depth = codec::DepthMode::View},
                                       encoder));
    codec::Decoder decoder;
    REPRISE_TRY(codec::Decoder::create({.display = true}, decoder));
    codec::Packet packet;
    codec::DecodedFrame decoded;
    Image<glm::u8vec4> input;
    Image<glm::vec3> display;
    for (std::size_t i = 0; i < seq.frames.size(); ++i) {
        const Image<Rgb8>& shown = seq.shown[i];
        input.resize(shown.width(), shown.height());
        for (std::size_t p = 0; p < shown.pixel_count(); ++p)
            input.data()[p] = glm::u8vec4(shown.data()[p], 255);
        double encode_ms = 0.0, decode_ms = 0.0;
        REPRISE_TRY(code_frame(encoder, decoder, seq.frames[i], input.view(), i, packet, decoded,
                               encode_ms, decode_ms));
        display.resize(decoded.display.width(), decoded.display.height());
        for (std::size_t p = 0; p < display.pixel_count(); ++p)
            display.data()[p] = glm::vec3(decoded.display.data()[p]) / 255.0f;
        run.samples.push_back({int(i), 8.0 * double(packet.data.size()),
                               image_error(seq.truth[i].view(), display.view()), encode_ms,
                               decode_ms});
    }
    return {};
}

// Depth to the view bound (DepthMode::View, default E and B) at one qp: its bits beside the
// total, and the reprojection error its decoded depth causes against the rendered depth.
struct ViewDepthRun {
    std::string scene;
    double depth_bytes = 0.0, total_bytes = 0.0, lossless_depth_bytes = NAN;
    double camera_bytes = 0.0, motion_bytes = 0.0, color_bytes = 0.0, per_pixel_motion_bytes = 0.0;
    double max_error_px = 0.0, max_motion_error_px = 0.0;
    std::size_t motion_objects = 0, motion_models = 0, motion_own_pixels = 0, frames = 0;
    std::size_t background_mismatches = 0, finite_pixels = 0, pixels_over_bound = 0;
    float step = 0.0f;
    codec::StreamStats::DepthBits depth_parts;  // where the depth bits go (ideal lengths)
    codec::StreamStats::MotionBits motion_parts;
    std::vector<DepthVideoRun>
        video_peers;         // 1/z as grey video, as immersive-video systems send it
    SynthesizedViews views;  // rendered sequences only
};

// reprise's depth at the view bound beside the grey-video depth peer, per scene, and the target:
// ours smaller than every peer setting whose decoded depth is as good (no larger share of
// pixels beyond E, no more background wrong).
std::string depth_video_text(const std::vector<ViewDepthRun>& rows,
                             const codec::EncoderOptions& defaults) {
    std::string text = strf(
        "\ndepth as 10-bit grey video (1/z over the sequence's depth range, x265 veryfast 4:0:0, "
        "as immersive-video systems send it) beside reprise's depth at the view bound; error: "
        "reprojection of decoded against rendered depth for cameras displaced by up to B = %.3f\n"
        "%-10s %-30s %12s %11s %9s %9s\n",
        defaults.view_displacement, "scene", "coder", "bytes/frame", "max err px", "over E",
        "bg wrong");
    for (const ViewDepthRun& v : rows) {
        if (v.video_peers.empty()) continue;
        const double n = double(std::max<std::size_t>(1, v.frames));
        const double ours_over =
            v.finite_pixels ? double(v.pixels_over_bound) / double(v.finite_pixels) : 0.0;
        text +=
            strf("%-10s %-30s %12.0f %11.3f %8.3f%% %9zu\n", v.scene.c_str(), "reprise view bound",
                 v.depth_bytes / n, v.max_error_px, 100.0 * ours_over, v.background_mismatches);
        double smallest_as_good = INFINITY;
        for (const DepthVideoRun& p : v.video_peers) {
            text += strf("%-10s %-30s %12.0f %11.3f %8.3f%% %9zu\n", v.scene.c_str(),
                         p.setting.c_str(), p.bytes / n, p.max_error_px, 100.0 * p.share_over_bound,
                         p.background_mismatches);
            if (p.share_over_bound <= ours_over &&
                p.background_mismatches <= v.background_mismatches)
                smallest_as_good = std::min(smallest_as_good, p.bytes);
        }
        text += std::isfinite(smallest_as_good)
                    ? strf(
                          "%-10s reprise's depth = %.3fx the smallest grey video as good (<= 1 "
                          "wanted): %s\n",
                          v.scene.c_str(), v.depth_bytes / smallest_as_good,
                          v.depth_bytes <= smallest_as_good ? "met" : "NOT met")
                    : strf("%-10s no grey-video setting reached reprise's error: met\n",
                           v.scene.c_str());
    }
    return text;
}

// The client's views from decoded depth against the same views from rendered depth, per scene.
std::string synthesized_views_text(const std::vector<ViewDepthRun>& rows) {
    std::string text = strf(
        "\nviews the client makes from the default stream's decoded colour, warped with its "
        "decoded "
        "depth and motion (dec) and with the rendered ones (ren): extrapolated 1, 2 and 3 display "
        "periods ahead at 4x the frame rate and the other eye %.0f mm to the right, PSNR against "
        "the scene rendered there, mean over frames; target: dec within %.1f dB of ren\n%-10s",
        64.0, kViewLossTarget, "scene");
    for (int k = 0; k < SynthesizedViews::kViews; ++k)
        text += strf(" %23s", SynthesizedViews::name(k));
    text += "\n";
    for (const ViewDepthRun& v : rows) {
        if (v.views.frames == 0) continue;
        text += strf("%-10s", v.scene.c_str());
        for (int k = 0; k < SynthesizedViews::kViews; ++k)
            text += strf("  %6.2f/%6.2f %+6.2f dB", v.views.decoded_psnr[k] / v.views.frames,
                         v.views.rendered_psnr[k] / v.views.frames, v.views.loss_db(k));
        text += "\n";
    }
    return text;
}

Status run_view_depth(server::Renderer& renderer, const Sequence& seq, int qp, ViewDepthRun& run) {
    const codec::EncoderOptions options{.qp = qp, .fps = seq.fps, .depth = codec::DepthMode::View};
    const float bound_px = codec::coded_bounds(options).view_error_px;
    codec::Encoder encoder;
    REPRISE_TRY(codec::Encoder::create(options, encoder));
    codec::Decoder decoder;
    codec::Packet packet;
    codec::DecodedFrame decoded;
    run.scene = seq.name;
    run.frames = seq.frames.size();
    std::unique_ptr<SynthesizedViewScorer> views;
    if (seq.scene)
        views = std::make_unique<SynthesizedViewScorer>(renderer, *seq.scene, seq.path, seq.fps);
    for (std::size_t i = 0; i < seq.frames.size(); ++i) {
        const Frame& frame = seq.frames[i];
        REPRISE_TRY(encoder.send_frame(frame));
        if (encoder.receive_packet(packet) != Result::Ok)
            return Status::error("reprise codec: no packet for frame " + std::to_string(i));
        REPRISE_TRY(decoder.send_packet(packet.data));
        if (decoder.receive_frame(decoded) != Result::Ok)
            return Status::error("reprise codec: no decoded frame for frame " + std::to_string(i));
        const codec::ViewDepthError e = codec::measure_view_depth_error(
            frame.camera, frame.depth.view(), decoded.depth(), options.view_displacement, bound_px);
        if (views) {
            REPRISE_TRY(views->add(int(i), frame, decoded.view(), run.views));
            std::fprintf(stderr, "\r[codec] %s: views from decoded depth %zu/%zu   ",
                         seq.name.c_str(), i + 1, seq.frames.size());
        }
        run.max_error_px = std::max(run.max_error_px, e.max_px);
        run.background_mismatches += e.background_mismatches;
        run.finite_pixels += e.pixels;
        run.pixels_over_bound += e.pixels_over_bound;
        const codec::StreamStats& bits = encoder.last_frame_stats();
        run.depth_bytes += bits.depth_bits / 8.0;
        run.depth_parts += bits.depth_parts;
        run.motion_parts += bits.motion_parts;
        run.camera_bytes += bits.camera_bits / 8.0;
        run.motion_bytes += bits.motion_bits / 8.0;
        run.color_bytes += bits.color_bits / 8.0;
        run.motion_objects += bits.motion_objects;
        run.motion_models += bits.motion_models;
        run.motion_own_pixels += bits.motion_own_pixels;
        run.total_bytes += double(packet.data.size());
        Frame given = frame;  // the motion the encoder codes: NaN repaired at its door
        NonfiniteRepair().repair(given);
        const ImageView<const glm::vec2> motion = decoded.motion();
        for (std::size_t p = 0; p < given.motion.pixel_count() && !motion.empty(); ++p) {
            const glm::vec2 d = motion.data[p] - given.motion.data()[p];
            const double err = std::sqrt(double(d.x) * d.x + double(d.y) * d.y);
            if (std::isfinite(err))
                run.max_motion_error_px = std::max(run.max_motion_error_px, err);
        }
    }
    // The same stream with every pixel's motion to 1/8 px, for what the models save.
    codec::EncoderOptions per_pixel = options;
    per_pixel.motion_error_px = 0.0f;
    codec::Encoder reference;
    REPRISE_TRY(codec::Encoder::create(per_pixel, reference));
    for (const Frame& frame : seq.frames) {
        REPRISE_TRY(reference.send_frame(frame));
        if (reference.receive_packet(packet) != Result::Ok)
            return Status::error("reprise codec: no packet");
    }
    run.per_pixel_motion_bytes = reference.stats().motion_bits / 8.0;
    run.step = codec::view_depth_step(seq.frames[0].camera.projection, seq.frames[0].width(),
                                      seq.frames[0].height(), bound_px, options.view_displacement);
    // The immersive-video depth peer: x265 Main 10 (4:0:0) of 1/z, lossless and at four rates.
    if (!peer_available(PeerKind::X265)) return {};
    for (int crf : {-1, 8, 16, 24, 32}) {
        const PeerConfig config{.kind = PeerKind::X265,
                                .preset = "veryfast",
                                .crf = std::max(crf, 0),
                                .lossless = crf < 0};
        DepthVideoRun peer;
        REPRISE_TRY(run_depth_video_peer(seq.frames, seq.fps, config, 10, options.view_displacement,
                                         bound_px, peer));
        run.video_peers.push_back(peer);
    }
    return {};
}

void run_depth_peers(const Sequence& seq, std::vector<DepthResult>& results) {
    DepthResult zstd{"zstd-3"}, rvl{"rvl-float"}, rvl16{"rvl-16bit-inverse (lossy)"};
    rvl16.lossless = false;
    std::vector<uint8_t> bytes;
    std::vector<float> back;
    for (const Frame& frame : seq.frames) {
        const std::span<const float> depth(frame.depth.data(), frame.depth.pixel_count());
        auto start = BenchClock::now();
        zstd_compress_depth(depth, 3, bytes);
        zstd.encode_ms.push_back(ms_since(start));
        zstd.bytes.push_back(double(bytes.size()));
        start = BenchClock::now();
        Status ok = zstd_decompress_depth(bytes, depth.size(), back);
        zstd.decode_ms.push_back(ms_since(start));
        REPRISE_ASSERT(ok.ok());
        for (DepthResult* r : {&rvl, &rvl16}) {
            const RvlOptions options{.mode = r == &rvl ? RvlMode::FloatBits : RvlMode::Inverse16,
                                     .near = frame.camera.near,
                                     .far = frame.camera.far};
            start = BenchClock::now();
            rvl_encode(depth, options, bytes);
            r->encode_ms.push_back(ms_since(start));
            r->bytes.push_back(double(bytes.size()));
            start = BenchClock::now();
            ok = rvl_decode(bytes, depth.size(), options, back);
            r->decode_ms.push_back(ms_since(start));
            REPRISE_ASSERT(ok.ok());
        }
    }
    results.push_back(std::move(zstd));
    results.push_back(std::move(rvl));
    results.push_back(std::move(rvl16));
}

std::vector<int> parse_qps(const std::string& list, Status& status) {
    std::vector<int> qps;
    for (const std::string& item : split_list(list)) {
        char* end = nullptr;
        const long qp = std::strtol(item.c_str(), &end, 10);
        if (!end || *end || qp < 0 || qp > 51) {
            status = Status::error("bench codec: --qps: '" + item + "' is not a qp in 0..51");
            return {};
        }
        qps.push_back(int(qp));
    }
    if (qps.size() < 2) status = Status::error("bench codec: --qps needs at least two qp values");
    return qps;
}

// A rate-distortion curve: one point per rate point of one codec group.
std::vector<RatePoint> rd_curve(const std::vector<RunResult>& runs, const std::string& group,
                                bool flip) {
    std::vector<RatePoint> points;
    for (const RunResult& r : runs)
        if (r.group == group)
            points.push_back({r.mean(&Sample::bits), flip ? -r.mean_error(&ImageError::flip)
                                                          : r.mean_error(&ImageError::psnr)});
    return points;
}

std::vector<std::string> groups_of(const std::vector<RunResult>& runs) {
    std::vector<std::string> groups;
    for (const RunResult& r : runs)
        if (std::find(groups.begin(), groups.end(), r.group) == groups.end())
            groups.push_back(r.group);
    return groups;
}

struct BdRow {
    std::string scene, peer;
    bool builtin = false;
    double psnr_color = NAN, psnr_total = NAN, flip_color = NAN, flip_total = NAN;
    double psnr_stream = NAN, flip_stream = NAN;  // all bits of the default stream
};

std::string pct(double v) { return std::isnan(v) ? std::string("n/a") : strf("%+.1f%%", v); }

std::string verdict(bool known, bool met) { return !known ? "n/a" : met ? "met" : "NOT met"; }

struct SpeedResult {
    bool measured = false;
    int w = 0, h = 0, frames = 0, rounds = 0;
    double ours_encode = NAN, ours_decode = NAN;          // mean ms per frame, the default stream
    double lossless_encode = NAN, lossless_decode = NAN;  // lossless depth, per-pixel motion
    double x264_veryfast_encode = NAN, x264_veryfast_decode = NAN;
    double rgb_to_yuv = NAN, yuv_to_rgb = NAN;  // x264 veryfast's conversions, inside its times
    double x264_ultrafast_encode = NAN;
    // The same over the frames after the first kWarmFrom: a long-running encoder's rate, once
    // its pictures and buffers exist (the first frames also pay for touching their memory).
    static constexpr std::size_t kWarmFrom = 5;
    double ours_encode_warm = NAN, ours_decode_warm = NAN;
    // The default stream from 8-bit sRGB and to it, as x264 is fed and read (run_ours_display).
    double display_encode = NAN, display_decode = NAN;
    double display_encode_warm = NAN, display_decode_warm = NAN;
    double x264_veryfast_encode_warm = NAN, x264_veryfast_decode_warm = NAN;
    double x264_ultrafast_encode_warm = NAN;
    // The default stream's coders over all frames: their stages' milliseconds.
    codec::StreamStats encoder_stats, decoder_stats;
};

// `slot` keeps the smallest of the values given it (NaN: none yet).
void keep_fastest(double& slot, double value) {
    if (std::isnan(slot) || value < slot) slot = value;
}

// The speed run: each codec timed in `rounds` rounds that alternate between them, so that a
// machine whose load changes during the run slows them alike; each figure is its fastest round's
// (the stages' milliseconds those of the default stream's fastest encode). Lossless depth once.
Status measure_speed(server::Renderer& renderer, const BenchOptions& job, int threads, int mid_qp,
                     SpeedResult& speed) {
    REPRISE_TRY(parse_size(job.speed_size, speed.w, speed.h));
    Sequence seq;
    REPRISE_TRY(
        render_sequence(renderer, job.speed_scene, job.speed_frames, speed.w, speed.h, seq));
    seq.name = "speed-" + seq.name;
    speed.frames = int(seq.frames.size());
    speed.rounds = std::max(1, job.repeat);
    const std::size_t warm = SpeedResult::kWarmFrom;
    RunResult run, color;
    std::fprintf(stderr, "[codec] speed: reprise qp %d, lossless depth and per-pixel motion\n",
                 mid_qp);
    REPRISE_TRY(run_ours(seq, mid_qp, false, run, color, nullptr));
    speed.lossless_encode = run.mean(&Sample::encode_ms);
    speed.lossless_decode = run.mean(&Sample::decode_ms);
    for (int round = 1; round <= speed.rounds; ++round) {
        std::fprintf(stderr, "[codec] speed: round %d/%d, x264 veryfast and ultrafast at %dx%d\n",
                     round, speed.rounds, speed.w, speed.h);
        double convert_ms[2] = {NAN, NAN};
        REPRISE_TRY(run_peer(
            seq, {.kind = PeerKind::X264, .preset = "veryfast", .crf = 26, .threads = threads}, run,
            convert_ms));
        keep_fastest(speed.rgb_to_yuv, convert_ms[0]);
        keep_fastest(speed.yuv_to_rgb, convert_ms[1]);
        keep_fastest(speed.x264_veryfast_encode, run.mean(&Sample::encode_ms));
        keep_fastest(speed.x264_veryfast_decode, run.mean(&Sample::decode_ms));
        keep_fastest(speed.x264_veryfast_encode_warm, run.mean(&Sample::encode_ms, warm));
        keep_fastest(speed.x264_veryfast_decode_warm, run.mean(&Sample::decode_ms, warm));
        REPRISE_TRY(run_peer(
            seq, {.kind = PeerKind::X264, .preset = "ultrafast", .crf = 26, .threads = threads},
            run));
        keep_fastest(speed.x264_ultrafast_encode, run.mean(&Sample::encode_ms));
        keep_fastest(speed.x264_ultrafast_encode_warm, run.mean(&Sample::encode_ms, warm));
        std::fprintf(stderr, "[codec] speed: round %d/%d, reprise qp %d\n", round, speed.rounds,
                     mid_qp);
        codec::StreamStats encoder_stats, decoder_stats;
        REPRISE_TRY(
            run_ours(seq, mid_qp, true, run, color, nullptr, &encoder_stats, &decoder_stats));
        if (!(speed.ours_encode <= run.mean(&Sample::encode_ms)))
            speed.encoder_stats = encoder_stats, speed.decoder_stats = decoder_stats;
        keep_fastest(speed.ours_encode, run.mean(&Sample::encode_ms));
        keep_fastest(speed.ours_decode, run.mean(&Sample::decode_ms));
        keep_fastest(speed.ours_encode_warm, run.mean(&Sample::encode_ms, warm));
        keep_fastest(speed.ours_decode_warm, run.mean(&Sample::decode_ms, warm));
        const double linear_bits = run.mean(&Sample::bits);
        REPRISE_TRY(run_ours_display(seq, mid_qp, run));
        if (round == 1 && run.mean(&Sample::bits) != linear_bits)  // visualize_color's rounding
            std::fprintf(stderr,
                         "[codec] note: from 8-bit sRGB %.0f bits/frame, from linear light %.0f\n",
                         run.mean(&Sample::bits), linear_bits);
        keep_fastest(speed.display_encode, run.mean(&Sample::encode_ms));
        keep_fastest(speed.display_decode, run.mean(&Sample::decode_ms));
        keep_fastest(speed.display_encode_warm, run.mean(&Sample::encode_ms, warm));
        keep_fastest(speed.display_decode_warm, run.mean(&Sample::decode_ms, warm));
    }
    speed.measured = true;
    return {};
}

// Lossless depth coders' bytes over a sequence.
struct DepthSummary {
    std::string scene;
    double raw = 0, zstd = 0, rvl = 0, rvl16 = 0, ours = NAN;
};

// reprise's BD-rates against each peer group of one sequence, as rows and in bd_rate.csv.
void add_bd_rows(const Sequence& seq, const std::vector<RunResult>& runs,
                 std::vector<BdRow>& bd_rows, CsvFile& bd_csv) {
    const std::vector<std::string> groups = groups_of(runs);
    for (const std::string& g : groups) {
        if (g == kOurs || g == kOursColor || g == kOursStream) continue;
        BdRow row{seq.name, g, seq.builtin};
        row.psnr_color = bd_rate(rd_curve(runs, g, false), rd_curve(runs, kOursColor, false));
        row.psnr_total = bd_rate(rd_curve(runs, g, false), rd_curve(runs, kOurs, false));
        row.flip_color = bd_rate(rd_curve(runs, g, true), rd_curve(runs, kOursColor, true));
        row.flip_total = bd_rate(rd_curve(runs, g, true), rd_curve(runs, kOurs, true));
        row.psnr_stream = bd_rate(rd_curve(runs, g, false), rd_curve(runs, kOursStream, false));
        row.flip_stream = bd_rate(rd_curve(runs, g, true), rd_curve(runs, kOursStream, true));
        for (auto [metric, bits, v] : {std::tuple{"psnr", "color", row.psnr_color},
                                       {"psnr", "total", row.psnr_total},
                                       {"flip", "color", row.flip_color},
                                       {"flip", "total", row.flip_total},
                                       {"psnr", "total-stream", row.psnr_stream},
                                       {"flip", "total-stream", row.flip_stream}})
            bd_csv.row({seq.name, g, metric, bits, strf("%.3f", v)});
        bd_rows.push_back(row);
    }
    bd_csv.flush();
}

// One sequence's table (printed) and report section: rate-distortion curves and time bars.
void sequence_report(const Sequence& seq, const std::vector<RunResult>& runs, Report& report) {
    const int sw = seq.frames[0].width(), sh = seq.frames[0].height();
    const std::vector<std::string> groups = groups_of(runs);
    std::string table = strf("%s (%dx%d, %zu frames)\n%-22s %-16s %12s %8s %8s %8s %9s %9s\n",
                             seq.name.c_str(), sw, sh, seq.frames.size(), "codec", "setting",
                             "bits/frame", "PSNR", "SSIM", "FLIP", "enc ms", "dec ms");
    ReportSection section{seq.name, seq.note};
    std::vector<PlotSeries> psnr_series, flip_series;
    std::vector<BarRow> bars;
    for (const std::string& g : groups) {
        PlotSeries ps{g}, fs_{g};
        ps.dashed = fs_.dashed = g == kOursColor;
        double enc = 0.0, dec = 0.0;
        int n = 0;
        for (const RunResult& r : runs) {
            if (r.group != g) continue;
            const double bits = r.mean(&Sample::bits);
            ps.x.push_back(bits), ps.y.push_back(r.mean_error(&ImageError::psnr));
            fs_.x.push_back(bits), fs_.y.push_back(r.mean_error(&ImageError::flip));
            enc += r.mean(&Sample::encode_ms), dec += r.mean(&Sample::decode_ms), ++n;
            table += strf("%-22s %-16s %12.0f %8.2f %8.4f %8.4f %9.2f %9.2f\n", r.codec.c_str(),
                          r.setting.c_str(), bits, r.mean_error(&ImageError::psnr),
                          r.mean_error(&ImageError::ssim), r.mean_error(&ImageError::flip),
                          r.mean(&Sample::encode_ms), r.mean(&Sample::decode_ms));
            if (r.codec != kOursColor)
                section.points.push_back(
                    {r.codec == kOurs ? std::string(kOurs) : r.group, r.setting,
                     r.mean_error(&ImageError::psnr), r.mean_error(&ImageError::ssim),
                     r.mean_error(&ImageError::flip), r.mean(&Sample::encode_ms)});
        }
        psnr_series.push_back(std::move(ps));
        flip_series.push_back(std::move(fs_));
        if (g != kOursColor) bars.push_back({g, {enc / n, dec / n}});
    }
    section.html = "<p>PSNR against bits per frame</p>\n" +
                   line_plot_svg(psnr_series, {"bits per frame", "PSNR, dB (higher is better)"}) +
                   "<p>FLIP against bits per frame</p>\n" +
                   line_plot_svg(flip_series, {"bits per frame", "LDR-FLIP (lower is better)"}) +
                   "<p>Time per frame, mean over the rate points</p>\n" +
                   bar_chart_svg(bars, {"encode", "decode"}, "ms per frame");
    section.time_label = "encode ms per frame (log scale)";
    report.sections.push_back(std::move(section));
    std::printf("%s\n", table.c_str());
    std::fflush(stdout);
}

// The BD-rate table with the mean over the built-in scenes (also in bd_rate.csv).
std::string bd_rate_text(const std::vector<BdRow>& bd_rows, CsvFile& bd_csv) {
    std::string bd_text = strf(
        "BD-rate of reprise against each peer (negative = reprise needs fewer bits "
        "for the same quality; total: all bits with lossless depth and per-pixel motion, and "
        "all bits of the default stream: depth to the view bound, motion within 0.25 px)\n"
        "%-10s %-20s %12s %12s %12s %12s %14s %14s\n",
        "scene", "anchor", "PSNR colour", "PSNR total", "FLIP colour", "FLIP total", "PSNR stream",
        "FLIP stream");
    std::map<std::string, std::vector<const BdRow*>> by_peer;
    for (const BdRow& r : bd_rows) {
        bd_text +=
            strf("%-10s %-20s %12s %12s %12s %12s %14s %14s\n", r.scene.c_str(), r.peer.c_str(),
                 pct(r.psnr_color).c_str(), pct(r.psnr_total).c_str(), pct(r.flip_color).c_str(),
                 pct(r.flip_total).c_str(), pct(r.psnr_stream).c_str(), pct(r.flip_stream).c_str());
        if (r.builtin) by_peer[r.peer].push_back(&r);
    }
    for (const auto& [peer, rows] : by_peer) {
        double sums[6] = {0, 0, 0, 0, 0, 0};
        int counts[6] = {0, 0, 0, 0, 0, 0};
        for (const BdRow* r : rows) {
            const double v[6] = {r->psnr_color, r->psnr_total,  r->flip_color,
                                 r->flip_total, r->psnr_stream, r->flip_stream};
            for (int k = 0; k < 6; ++k)
                if (!std::isnan(v[k])) sums[k] += v[k], ++counts[k];
        }
        double m[6];
        for (int k = 0; k < 6; ++k) m[k] = counts[k] ? sums[k] / counts[k] : NAN;
        bd_text += strf("%-10s %-20s %12s %12s %12s %12s %14s %14s\n", "mean", peer.c_str(),
                        pct(m[0]).c_str(), pct(m[1]).c_str(), pct(m[2]).c_str(), pct(m[3]).c_str(),
                        pct(m[4]).c_str(), pct(m[5]).c_str());
        for (auto [metric, bits, v] : {std::tuple{"psnr", "color", m[0]},
                                       {"psnr", "total", m[1]},
                                       {"flip", "color", m[2]},
                                       {"flip", "total", m[3]},
                                       {"psnr", "total-stream", m[4]},
                                       {"flip", "total-stream", m[5]}})
            bd_csv.row({"mean-builtin", peer, metric, bits, strf("%.3f", v)});
    }
    return bd_text;
}

// The depth tables (lossless coders, the view bound, the depth-video peer), the bits by section
// and the synthesized views; `depth_ratio` gets the mean of zstd -3's bytes over ours.
std::string depth_text(const std::vector<DepthSummary>& depth_rows,
                       const std::vector<ViewDepthRun>& view_rows, int qp, double& depth_ratio) {
    std::string depth_text = strf(
        "depth, bytes over all frames (raw float = 4 bytes/pixel)\n"
        "%-10s %12s %12s %12s %12s %14s %12s\n",
        "scene", "raw", "zstd -3", "rvl float", "rvl 16 lossy", "reprise lossl.", "zstd/reprise");
    double depth_ratio_sum = 0.0;
    int depth_ratio_n = 0;
    for (const DepthSummary& d : depth_rows) {
        const double ratio = d.zstd / d.ours;
        depth_text +=
            strf("%-10s %12.0f %12.0f %12.0f %12.0f %14s %12s\n", d.scene.c_str(), d.raw, d.zstd,
                 d.rvl, d.rvl16, std::isnan(d.ours) ? "n/a" : strf("%.0f", d.ours).c_str(),
                 std::isnan(ratio) ? "n/a" : strf("%.2fx", ratio).c_str());
        if (!std::isnan(ratio)) depth_ratio_sum += ratio, ++depth_ratio_n;
    }

    const codec::EncoderOptions view_defaults{.qp = qp, .depth = codec::DepthMode::View};
    const codec::CodedBounds bounds = codec::coded_bounds(view_defaults);
    depth_text += strf(
        "\ndepth to the view bound (--depth view): 1/z step from the intrinsics so that a camera "
        "displaced by up to B = %.3f scene units moves no reprojected pixel by more than E = %.2f "
        "px; qp %d; measured: largest reprojection error of decoded against rendered depth over "
        "28 displacements of length B\n"
        "%-10s %12s %12s %12s %10s %12s %12s %10s\n",
        view_defaults.view_displacement, bounds.view_error_px, qp, "scene", "1/z step",
        "view bytes", "lossless", "ratio", "depth share", "max err px", "bg wrong");
    std::string motion_text = strf(
        "\nbits per frame by section at qp %d (depth to the view bound, motion within %.2f px: "
        "rigid objects and affine models per block, pixels alone where none fits; per-pixel = "
        "every pixel to 1/8 px)\n%-10s %9s %9s %9s %9s %9s %8s %8s %11s %8s %9s %9s %10s\n",
        qp, bounds.motion_error_px, "scene", "total", "camera", "depth", "motion", "colour",
        "depth%", "motion%", "per-pixel", "objects", "models", "alone px", "max err px");
    for (const ViewDepthRun& v : view_rows) {
        const double n = 8.0 / double(std::max<std::size_t>(1, v.frames));
        motion_text += strf(
            "%-10s %9.0f %9.0f %9.0f %9.0f %9.0f %7.1f%% %7.1f%% %11.0f %8.1f %9.1f %9.1f %10.4f  "
            "%s\n",
            v.scene.c_str(), v.total_bytes * n, v.camera_bytes * n, v.depth_bytes * n,
            v.motion_bytes * n, v.color_bytes * n, 100.0 * v.depth_bytes / v.total_bytes,
            100.0 * v.motion_bytes / v.total_bytes, v.per_pixel_motion_bytes * n,
            double(v.motion_objects) * n / 8.0, double(v.motion_models) * n / 8.0,
            double(v.motion_own_pixels) * n / 8.0, v.max_motion_error_px,
            v.max_motion_error_px <= bounds.motion_error_px ? "within the bound"
                                                            : "OUTSIDE the bound");
    }
    for (const ViewDepthRun& v : view_rows)
        depth_text +=
            strf("%-10s %12.3g %12.0f %12.0f %9.3fx %11.1f%% %12.4f %10zu  %s\n", v.scene.c_str(),
                 double(v.step), v.depth_bytes, v.lossless_depth_bytes,
                 v.depth_bytes / v.lossless_depth_bytes, 100.0 * v.depth_bytes / v.total_bytes,
                 v.max_error_px, v.background_mismatches,
                 v.max_error_px <= bounds.view_error_px && v.background_mismatches == 0
                     ? "within the bound"
                     : "OUTSIDE the bound");
    depth_text += depth_video_text(view_rows, view_defaults);
    depth_text += motion_text;
    depth_text += strf(
        "\nwhere the depth bits go at qp %d, %% of the depth section (the range coder's ideal "
        "lengths): block flags, plane parameters, then pixels of blocks with residuals: of the "
        "key frame; in inter frames of moving objects held to their finer step, of pixels nothing "
        "of the reference landed on (revealed), of the rest (the reference saw them); section "
        "headers\n%-10s %11s %7s %7s %7s %8s %9s %7s %8s\n",
        qp, "scene", "bits/frame", "flags", "planes", "key", "objects", "revealed", "seen",
        "headers");
    for (const ViewDepthRun& v : view_rows) {
        const double all = std::max(8.0 * v.depth_bytes, 1.0);
        const codec::StreamStats::DepthBits& d = v.depth_parts;
        auto pct = [&](double bits) { return 100.0 * bits / all; };
        depth_text += strf("%-10s %11.0f %6.1f%% %6.1f%% %6.1f%% %7.1f%% %8.1f%% %6.1f%% %7.1f%%\n",
                           v.scene.c_str(), all / double(std::max<std::size_t>(1, v.frames)),
                           pct(d.flags), pct(d.planes), pct(d.key), pct(d.objects), pct(d.revealed),
                           pct(d.seen), pct(std::max(0.0, all - d.total())));
    }
    depth_text += strf(
        "\nwhere the motion bits go at qp %d, %% of the motion bits: the quadtree's flags, new "
        "affine models, 4x4 cells pixel by pixel, the rigid objects' list; section headers\n"
        "%-10s %11s %7s %7s %7s %8s %8s\n",
        qp, "scene", "bits/frame", "tree", "models", "pixels", "objects", "headers");
    for (const ViewDepthRun& v : view_rows) {
        const double all = std::max(8.0 * v.motion_bytes, 1.0);
        const codec::StreamStats::MotionBits& m = v.motion_parts;
        auto pct = [&](double bits) { return 100.0 * bits / all; };
        depth_text +=
            strf("%-10s %11.0f %6.1f%% %6.1f%% %6.1f%% %7.1f%% %7.1f%%\n", v.scene.c_str(),
                 all / double(std::max<std::size_t>(1, v.frames)), pct(m.tree), pct(m.models),
                 pct(m.pixels), pct(m.objects), pct(std::max(0.0, all - m.total())));
    }
    depth_text += synthesized_views_text(view_rows);
    depth_ratio = depth_ratio_n ? depth_ratio_sum / depth_ratio_n : NAN;
    return depth_text;
}

// Every codec on one sequence: reprise at each qp (all bits with lossless depth, its colour
// alone, the default stream) and each peer, into `runs` and codec.csv; `our_depth_bits` gets
// reprise's lossless depth bits per frame.
Status run_codecs(const Sequence& seq, const std::vector<int>& qps,
                  const std::vector<PeerConfig>& peers, CsvFile& csv, std::vector<RunResult>& runs,
                  std::vector<double>& our_depth_bits) {
    for (int qp : qps) {
        RunResult total, color;
        REPRISE_TRY(run_ours(seq, qp, false, total, color,
                             our_depth_bits.empty() ? &our_depth_bits : nullptr));
        std::fprintf(stderr,
                     "[codec] %s: reprise qp %2d: %9.0f bits/frame (colour %9.0f) %6.2f dB "
                     "%8.2f ms enc %8.2f ms dec\n",
                     seq.name.c_str(), qp, total.mean(&Sample::bits), color.mean(&Sample::bits),
                     total.mean_error(&ImageError::psnr), total.mean(&Sample::encode_ms),
                     total.mean(&Sample::decode_ms));
        runs.push_back(std::move(total));
        runs.push_back(std::move(color));
        RunResult stream, unused;
        REPRISE_TRY(run_ours(seq, qp, true, stream, unused, nullptr));
        std::fprintf(stderr, "[codec] %s: reprise stream qp %2d: %9.0f bits/frame %6.2f dB\n",
                     seq.name.c_str(), qp, stream.mean(&Sample::bits),
                     stream.mean_error(&ImageError::psnr));
        runs.push_back(std::move(stream));
    }
    for (const PeerConfig& config : peers) {
        RunResult run;
        REPRISE_TRY(run_peer(seq, config, run));
        std::fprintf(stderr,
                     "[codec] %s: %-8s %-18s %9.0f bits/frame %6.2f dB %8.2f ms enc %8.2f ms dec\n",
                     seq.name.c_str(), run.codec.c_str(), run.setting.c_str(),
                     run.mean(&Sample::bits), run.mean_error(&ImageError::psnr),
                     run.mean(&Sample::encode_ms), run.mean(&Sample::decode_ms));
        runs.push_back(std::move(run));
    }
    for (const RunResult& r : runs)
        for (const Sample& s : r.samples)
            csv.row({seq.name, r.codec, r.setting, std::to_string(s.frame), strf("%.0f", s.bits),
                     strf("%.4f", s.error.psnr), strf("%.6f", s.error.ssim),
                     strf("%.6f", s.error.flip), strf("%.4f", s.encode_ms),
                     strf("%.4f", s.decode_ms)});
    csv.flush();
    return {};
}

// The lossless depth coders on one sequence (ours from `our_depth_bits`), into depth.csv.
DepthSummary depth_coders(const Sequence& seq, const std::vector<double>& our_depth_bits,
                          CsvFile& depth_csv) {
    const int sw = seq.frames[0].width(), sh = seq.frames[0].height();
    std::vector<DepthResult> depth;
    run_depth_peers(seq, depth);
    if (!our_depth_bits.empty()) {
        DepthResult ours{"reprise-lossless"};
        for (double b : our_depth_bits) ours.bytes.push_back(b / 8.0);
        ours.encode_ms.assign(ours.bytes.size(), NAN);  // inside the codec's frame time
        ours.decode_ms.assign(ours.bytes.size(), NAN);
        depth.insert(depth.begin(), std::move(ours));
    }
    DepthSummary ds{seq.name};
    ds.raw = 4.0 * double(sw) * sh * double(seq.frames.size());
    for (const DepthResult& d : depth) {
        for (std::size_t i = 0; i < d.bytes.size(); ++i)
            depth_csv.row({seq.name, d.coder, std::to_string(i), strf("%.0f", d.bytes[i]),
                           strf("%.4f", d.encode_ms[i]), strf("%.4f", d.decode_ms[i])});
        if (d.coder == "zstd-3") ds.zstd = d.total_bytes();
        if (d.coder == "rvl-float") ds.rvl = d.total_bytes();
        if (d.coder == "rvl-16bit-inverse (lossy)") ds.rvl16 = d.total_bytes();
        if (d.coder == "reprise-lossless") ds.ours = d.total_bytes();
    }
    return ds;
}

Report codec_report(const BenchOptions& job, int w, int h) {
    Report report;
    report.title = "reprise bench codec: error against bits against run time";
    report.paragraphs.push_back(strf(
        "Every codec gets the same 8-bit sRGB display frames (reprise's codec its G-buffers: "
        "linear colour, depth, motion, cameras) and is scored on display values of its decoded "
        "frames against the original colour (PSNR, SSIM, LDR-FLIP). %dx%d, %d frames per built-in "
        "scene at 30 Hz; %d threads per codec. Peers through libavcodec, low delay as streaming "
        "uses them: x264 (ultrafast, veryfast, medium; tune zerolatency, no B-frames), x265 "
        "ultrafast zerolatency, SVT-AV1 preset 10 with its low-delay prediction structure "
        "(which SVT-AV1 1.4 calls work in progress), CRF at four rate points each; yuv420p via "
        "swscale (BT.601, limited range).",
        w, h, job.frames, job.threads));
    report.paragraphs.push_back(
        "Times are wall-clock ms per frame on this machine: encode = RGB to YUV conversion + "
        "send_frame + receive_packet (peers), send_frame + receive_packet (reprise); decode = "
        "send_packet + receive_frame (+ YUV to RGB for peers). Bits include every header (x264's "
        "SPS/PPS in band). BD-rate: Bjøntegaard delta rate of reprise against each peer over the "
        "common quality interval (monotone cubic interpolation of log rate), counting reprise's "
        "colour bits alone and its total bits (camera, depth, motion, colour, headers).");
    return report;
}

// The speed run at 1080p (when --speed-frames > 0): its CSV rows and its text.
// One coder's stages, mean ms per frame; "other" is what the stages leave of `whole_ms`
// (packet framing, the decoder's frame hand-out, the bench's own calls).
std::string stage_line(const char* coder, const codec::StreamStats& stats, double whole_ms) {
    const codec::StreamStats::Milliseconds& t = stats.ms;
    const double n = double(std::max<std::size_t>(stats.frames, 1));
    return strf(
        "    %s: input %.1f, colour conversion %.1f, objects %.1f, depth reprojection %.1f, "
        "depth %.1f, motion %.1f, colour prediction %.1f, colour %.1f, other %.1f\n",
        coder, t.input / n, t.convert / n, t.objects / n, t.reproject / n, t.depth / n,
        t.motion / n, t.predict / n, t.color / n, whole_ms - t.total() / n);
}

Status speed_run(server::Renderer& renderer, const BenchOptions& job, int qp, CsvFile& speed_csv,
                 SpeedResult& speed, std::string& speed_text) {
    if (job.speed_frames > 0) {
        REPRISE_TRY(measure_speed(renderer, job, job.threads, qp, speed));
        const std::string size = strf("%dx%d", speed.w, speed.h);
        const std::string frames = std::to_string(speed.frames);
        auto ms = [](double v) { return v == v ? strf("%.3f", v) : std::string(); };
        speed_csv.row({size, frames, "x264", "veryfast crf 26", ms(speed.x264_veryfast_encode),
                       ms(speed.x264_veryfast_decode), ms(speed.x264_veryfast_encode_warm),
                       ms(speed.x264_veryfast_decode_warm)});
        speed_csv.row({size, frames, "x264", "ultrafast crf 26", ms(speed.x264_ultrafast_encode),
                       "", ms(speed.x264_ultrafast_encode_warm), ""});
        speed_csv.row({size, frames, kOursStream, strf("qp %d", qp), ms(speed.ours_encode),
                       ms(speed.ours_decode), ms(speed.ours_encode_warm),
                       ms(speed.ours_decode_warm)});
        speed_csv.row({size, frames, kOursStream, strf("qp %d 8-bit", qp), ms(speed.display_encode),
                       ms(speed.display_decode), ms(speed.display_encode_warm),
                       ms(speed.display_decode_warm)});
        speed_csv.row({size, frames, kOurs, strf("qp %d", qp), ms(speed.lossless_encode),
                       ms(speed.lossless_decode), "", ""});
    }
    if (speed.measured) {
        speed_text = strf(
            "speed at %dx%d, %d frames, %d threads per codec (reprise: %d pool threads), mean ms "
            "per frame, the fastest of %d alternating rounds\n  x264 veryfast zerolatency: "
            "encode %8.2f  decode %8.2f  (of which swscale RGB->YUV %.2f, YUV->RGB %.2f)\n"
            "  x264 ultrafast zerolatency: encode %7.2f\n",
            speed.w, speed.h, speed.frames, job.threads, thread_count(), speed.rounds,
            speed.x264_veryfast_encode, speed.x264_veryfast_decode, speed.rgb_to_yuv,
            speed.yuv_to_rgb, speed.x264_ultrafast_encode);
        speed_text += strf(
            "  reprise qp %d, the default stream: encode %8.2f  decode %8.2f  (lossless depth "
            "and per-pixel motion: encode %.2f  decode %.2f)\n"
            "  encode speed reprise / x264 veryfast = %.2fx (>= 1 wanted), / ultrafast = %.2fx\n"
            "  reprise decode speed / its encode speed = %.2fx (>= 2 wanted)\n"
            "  the same stream from 8-bit sRGB and to it, as x264 is fed and read: encode %.2f  "
            "decode %.2f; / x264 veryfast = %.2fx, / ultrafast = %.2fx, decode / encode = %.2fx\n",
            qp, speed.ours_encode, speed.ours_decode, speed.lossless_encode, speed.lossless_decode,
            speed.x264_veryfast_encode / speed.ours_encode,
            speed.x264_ultrafast_encode / speed.ours_encode, speed.ours_encode / speed.ours_decode,
            speed.display_encode, speed.display_decode,
            speed.x264_veryfast_encode / speed.display_encode,
            speed.x264_ultrafast_encode / speed.display_encode,
            speed.display_encode / speed.display_decode);
        if (speed.ours_encode_warm == speed.ours_encode_warm)
            speed_text += strf(
                "  from frame %zu on (every picture and buffer already made): x264 veryfast encode "
                "%.2f decode %.2f, ultrafast encode %.2f; reprise encode %.2f decode %.2f; "
                "encode speed / x264 veryfast = %.2fx, / ultrafast = %.2fx, decode / encode = "
                "%.2fx\n",
                SpeedResult::kWarmFrom, speed.x264_veryfast_encode_warm,
                speed.x264_veryfast_decode_warm, speed.x264_ultrafast_encode_warm,
                speed.ours_encode_warm, speed.ours_decode_warm,
                speed.x264_veryfast_encode_warm / speed.ours_encode_warm,
                speed.x264_ultrafast_encode_warm / speed.ours_encode_warm,
                speed.ours_encode_warm / speed.ours_decode_warm);
        speed_text += "  where reprise's milliseconds go (mean per frame):\n" +
                      stage_line("encode", speed.encoder_stats, speed.ours_encode) +
                      stage_line("decode", speed.decoder_stats, speed.ours_decode);
    }
    return {};
}

// What bench codec prints against the targets of issue 8 §7 and issue 18 §6.
std::string targets_text(const BenchOptions& job, int qp, const std::vector<BdRow>& bd_rows,
                         const std::vector<ViewDepthRun>& view_rows, const SpeedResult& speed,
                         double depth_ratio) {
    // Mean BD-rate against x264 veryfast over the built-in scenes, of the colour (issue 8 §7) or
    // of all bits of the default stream (issue 18 §6).
    auto mean_vs_veryfast = [&](double BdRow::*metric) {
        double sum = 0.0;
        int n = 0;
        for (const BdRow& r : bd_rows)
            if (r.builtin && r.peer == "x264 veryfast" && !std::isnan(r.*metric))
                sum += r.*metric, ++n;
        return n ? sum / n : NAN;
    };
    const double bd_vf = mean_vs_veryfast(&BdRow::psnr_color);
    const double bd_stream = mean_vs_veryfast(&BdRow::psnr_stream);
    std::string views_over;
    bool views_known = false;
    for (const ViewDepthRun& v : view_rows)
        for (int k = 0; k < SynthesizedViews::kViews && v.views.frames > 0; ++k) {
            views_known = true;
            if (v.views.loss_db(k) < -kViewLossTarget)
                views_over += strf(" %s %s %+.2f dB", v.scene.c_str(), SynthesizedViews::name(k),
                                   v.views.loss_db(k));
        }
    std::string geometry_over;
    for (const ViewDepthRun& v : view_rows) {
        const double share = 100.0 * (v.depth_bytes + v.motion_bytes) / v.total_bytes;
        if (share > kGeometryShareTarget)
            geometry_over += strf(" %s %.1f%%", v.scene.c_str(), share);
    }
    // Speed from the input x264 gets (8-bit sRGB), beside the linear-light input's.
    const double enc_ratio = speed.x264_veryfast_encode / speed.display_encode;
    const double dec_ratio = speed.display_encode / speed.display_decode;
    const std::string linear_ratios =
        strf("from linear light %.2fx", speed.x264_veryfast_encode / speed.ours_encode);
    const std::string linear_decode =
        strf("from linear light %.2fx", speed.ours_encode / speed.ours_decode);
    const bool full_hd = speed.w == 1920 && speed.h == 1080;
    std::string targets = "targets (issue 8 §7, issue 18 §6)\n";
    targets += strf(
        "  colour BD-rate (PSNR) vs x264 veryfast, mean over built-in scenes: %s (<= %.0f%%): %s\n",
        pct(bd_vf).c_str(), kColorBdTarget,
        verdict(!std::isnan(bd_vf), bd_vf <= kColorBdTarget).c_str());
    targets += strf(
        "  all bits of the default stream, BD-rate (PSNR) vs x264 veryfast, mean over built-in "
        "scenes: %s (<= %.0f%%): %s\n",
        pct(bd_stream).c_str(), kStreamBdTarget,
        verdict(!std::isnan(bd_stream), bd_stream <= kStreamBdTarget).c_str());
    targets +=
        strf("  depth + motion <= %.0f%% of the default stream at qp %d, every scene: %s%s\n",
             kGeometryShareTarget, qp, verdict(!view_rows.empty(), geometry_over.empty()).c_str(),
             geometry_over.empty() ? "" : (" (over:" + geometry_over + ")").c_str());
    targets += strf(
        "  views from decoded depth within %.1f dB of the same views from rendered depth, every "
        "scene and view: %s%s\n",
        kViewLossTarget, verdict(views_known, views_over.empty()).c_str(),
        views_over.empty() ? "" : (" (" + views_over.substr(1) + ")").c_str());
    targets += strf(
        "  encode at least as fast as x264 veryfast at 1920x1080, %d threads, both from 8-bit "
        "sRGB: %.2fx (%s): %s%s\n",
        job.threads, enc_ratio, linear_ratios.c_str(),
        verdict(!std::isnan(enc_ratio), enc_ratio >= 1.0).c_str(),
        full_hd || !speed.measured ? "" : strf(" (measured at %dx%d)", speed.w, speed.h).c_str());
    targets += strf("  decode >= %.0fx our encode speed, 8-bit sRGB in and out: %.2fx (%s): %s\n",
                    kDecodeOverEncodeTarget, dec_ratio, linear_decode.c_str(),
                    verdict(!std::isnan(dec_ratio), dec_ratio >= kDecodeOverEncodeTarget).c_str());
    targets += strf(
        "  lossless depth >= %.0fx smaller than zstd -3 (mean ratio over sequences): %.2fx: %s\n",
        kDepthRatioTarget, depth_ratio,
        verdict(!std::isnan(depth_ratio), depth_ratio >= kDepthRatioTarget).c_str());

    return targets;
}

}  // namespace

Status bench_codec(const BenchOptions& job) {
    if (job.frames < 2 || job.frames > 1000)
        return Status::error("bench codec: --frames must be in 2..1000");
    if (job.threads < 1 || job.threads > 64)
        return Status::error("bench codec: --threads must be in 1..64");
    if (job.speed_frames < 0 || job.speed_frames > 1000)
        return Status::error("bench codec: --speed-frames must be in 0..1000 (0 = no speed run)");
    int w = 0, h = 0;
    REPRISE_TRY(parse_size(job.size, w, h));
    Status parsed;
    const std::vector<int> qps = parse_qps(job.qps, parsed);
    REPRISE_TRY(parsed);
    std::vector<std::string> scenes = split_list(job.scenes);
    if (scenes.empty() && job.in.empty())
        for (const server::SceneInfo& s : server::builtin_scenes()) scenes.push_back(s.name);
    const std::string out_dir = job.out.empty() ? "out/bench-codec" : job.out;
    std::error_code ec;
    fs::create_directories(out_dir, ec);
    if (ec) return Status::error(out_dir + ": cannot create the folder: " + ec.message());

    std::vector<PeerConfig> peers;
    for (const PeerConfig& c : standard_peer_configs(job.threads)) {
        if (peer_available(c.kind))
            peers.push_back(c);
        else if (peers.empty() || peers.back().kind != c.kind)
            std::printf("note: libavcodec lacks %s; that peer is skipped\n",
                        peer_name(c.kind).c_str());
    }

    CsvFile csv, bd_csv, depth_csv, speed_csv;
    REPRISE_TRY(csv.open(out_dir + "/codec.csv",
                         "scene,codec,setting,frame,bits,psnr,ssim,flip,encode_ms,decode_ms"));
    REPRISE_TRY(
        bd_csv.open(out_dir + "/bd_rate.csv", "scene,anchor,metric,reprise_bits,bd_rate_percent"));
    REPRISE_TRY(
        depth_csv.open(out_dir + "/depth.csv", "scene,coder,frame,bytes,encode_ms,decode_ms"));
    REPRISE_TRY(speed_csv.open(
        out_dir + "/speed.csv",
        "size,frames,codec,setting,encode_ms,decode_ms,encode_ms_warm,decode_ms_warm"));

    std::unique_ptr<server::Renderer> renderer;
    REPRISE_TRY(server::Renderer::create(renderer));

    Report report = codec_report(job, w, h);

    std::vector<BdRow> bd_rows;
    std::vector<DepthSummary> depth_rows;
    std::vector<ViewDepthRun> view_rows;

    std::vector<std::string> inputs = scenes;
    if (!job.in.empty()) inputs.push_back("in:" + job.in);
    for (const std::string& input : inputs) {
        Sequence seq;
        if (input.rfind("in:", 0) == 0)
            REPRISE_TRY(read_sequence(input.substr(3), job.frames, seq));
        else
            REPRISE_TRY(render_sequence(*renderer, input, job.frames, w, h, seq));

        std::vector<RunResult> runs;
        std::vector<double> our_depth_bits;
        REPRISE_TRY(run_codecs(seq, qps, peers, csv, runs, our_depth_bits));

        const DepthSummary ds = depth_coders(seq, our_depth_bits, depth_csv);
        depth_rows.push_back(ds);
        ViewDepthRun view;
        REPRISE_TRY(run_view_depth(*renderer, seq, qps[qps.size() / 2], view));
        view.lossless_depth_bytes = ds.ours;
        view_rows.push_back(view);
        depth_csv.flush();

        add_bd_rows(seq, runs, bd_rows, bd_csv);
        sequence_report(seq, runs, report);
    }

    const std::string bd_text = bd_rate_text(bd_rows, bd_csv);

    double depth_ratio = NAN;
    const std::string depth_text =
        cli::depth_text(depth_rows, view_rows, qps[qps.size() / 2], depth_ratio);

    SpeedResult speed;
    std::string speed_text;
    REPRISE_TRY(speed_run(*renderer, job, qps[qps.size() / 2], speed_csv, speed, speed_text));

    const std::string targets =
        targets_text(job, qps[qps.size() / 2], bd_rows, view_rows, speed, depth_ratio);
    const std::string text = bd_text + (bd_text.empty() ? "" : "\n") + depth_text + "\n" +
                             speed_text + (speed_text.empty() ? "" : "\n") + targets;
    std::printf("%s", text.c_str());
    report.preformatted = text;
    const std::string html_path = out_dir + "/index.html";
    REPRISE_TRY(write_html_report(html_path, report));
    std::printf("report: %s\nrows: %s\n", html_path.c_str(), csv.path().c_str());
    return {};
}

}  // namespace reprise::cli
