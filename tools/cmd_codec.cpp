// reprise encode / decode, and `reprise info FILE.rps` — the scene-aware codec on EXR sequences.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "args.hpp"
#include "bench_report.hpp"
#include "commands.hpp"
#include "outputs.hpp"
#include "reprise/codec/codec.hpp"
#include "reprise/core/exr.hpp"

namespace reprise::cli {

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
    return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

constexpr std::uintmax_t kMaxStreamBytes = std::uintmax_t(4) << 30;

Status read_file(const std::string& path, std::vector<uint8_t>& bytes) {
    std::error_code ec;
    const std::uintmax_t size = std::filesystem::file_size(path, ec);
    if (ec) return Status::error(path + ": " + ec.message());
    if (size > kMaxStreamBytes) return Status::error(path + ": larger than 4 GiB");
    std::ifstream in(path, std::ios::binary);
    bytes.resize(std::size_t(size));
    if (!in.read(reinterpret_cast<char*>(bytes.data()), std::streamsize(size)))
        return Status::error(path + ": cannot read");
    return {};
}

Status parse_depth_mode(const std::string& text, codec::EncoderOptions& o) {
    if (text == "lossless") {
        o.depth = codec::DepthMode::Lossless;
    } else if (text == "none") {
        o.depth = codec::DepthMode::None;
    } else if (text == "bounded" || text.starts_with("bounded:")) {
        o.depth = codec::DepthMode::Bounded;
        if (text != "bounded") {
            char* end = nullptr;
            o.depth_error = std::strtof(text.c_str() + 8, &end);
            if (text.size() == 8 || *end || !(o.depth_error >= 1e-7f && o.depth_error <= 0.1f))
                return Status::error("encode: --depth " + text +
                                     ": the bound must be a number in 1e-7..0.1");
        }
    } else if (text == "view" || text.starts_with("view:")) {
        o.depth = codec::DepthMode::View;
        if (text != "view") {
            const char* error = text.c_str() + 5;
            char* end = nullptr;
            o.view_error_px = std::strtof(error, &end);
            bool parsed = end != error;
            if (parsed && *end == ',') {
                const char* displacement = end + 1;
                o.view_displacement = std::strtof(displacement, &end);
                parsed = end != displacement;
            }
            if (!parsed || *end || !(o.view_error_px >= 1e-3f && o.view_error_px <= 100.0f) ||
                !(o.view_displacement > 0.0f && o.view_displacement <= 1e6f))
                return Status::error("encode: --depth " + text +
                                     ": expected view:E[,B] with E in 0.001..100 px and B in "
                                     "(0, 1e6] scene units");
        }
    } else {
        return Status::error("encode: --depth " + text +
                             ": expected view[:E[,B]], lossless, bounded[:E] or none");
    }
    return {};
}

void print_stats(const codec::StreamStats& s, double fps) {
    const double n = double(std::max<std::size_t>(1, s.frames));
    auto line = [&](const char* what, std::size_t bits) {
        std::printf("  %-7s %12.1f kbit %10.0f bits/frame %9.1f kbit/s %6.1f %%\n", what,
                    bits / 1e3, bits / n, bits / n * fps / 1e3,
                    100.0 * double(bits) / double(std::max<std::size_t>(1, s.total_bits())));
    };
    line("header", s.header_bits);
    line("camera", s.camera_bits);
    line("depth", s.depth_bits);
    line("motion", s.motion_bits);
    line("colour", s.color_bits);
    line("total", s.total_bits());
    std::printf(
        "  left out: %zu of %zu colour blocks skipped (%.1f %%), %zu depth blocks predicted "
        "exactly (%zu depth blocks by a plane), "
        "motion beyond the cameras' on %zu pixels (%zu rigid objects, %zu models, %zu pixels "
        "alone)\n",
        s.blocks_skipped, s.blocks,
        100.0 * double(s.blocks_skipped) / double(std::max<std::size_t>(1, s.blocks)),
        s.depth_zero_blocks, s.depth_plane_blocks, s.motion_residual_pixels, s.motion_objects,
        s.motion_models, s.motion_own_pixels);
    if (const codec::StreamStats::DepthBits& d = s.depth_parts; d.total() > 0.0) {
        const double all = double(std::max<std::size_t>(1, s.depth_bits));
        auto share = [&](double bits) { return 100.0 * bits / all; };
        std::printf(
            "  depth bits: block flags %.1f %%, plane parameters %.1f %%, pixels of key frames "
            "%.1f %%, of moving objects at their finer step %.1f %%, revealed %.1f %%, the "
            "reference saw %.1f %%, section headers %.1f %%\n",
            share(d.flags), share(d.planes), share(d.key), share(d.objects), share(d.revealed),
            share(d.seen), share(std::max(0.0, all - d.total())));
    }
    if (const codec::StreamStats::MotionBits& m = s.motion_parts; m.total() > 0.0) {
        const double all = double(std::max<std::size_t>(1, s.motion_bits));
        std::printf(
            "  motion bits: quadtree flags %.1f %%, affine models %.1f %%, 4x4 cells pixel by "
            "pixel %.1f %%, rigid objects' list %.1f %%, section headers %.1f %%\n",
            100.0 * m.tree / all, 100.0 * m.models / all, 100.0 * m.pixels / all,
            100.0 * m.objects / all, 100.0 * std::max(0.0, all - m.total()) / all);
    }
    std::printf(
        "  %zu frames: %zu key, %zu predicted from an older reference, %zu intra macroblocks, "
        "%zu pixels the reference did not see predicted from the surface beside them\n",
        s.frames, s.key_frames, s.older_reference, s.intra_blocks, s.revealed_pixels);
    if (s.cameras_fitted > 0)
        std::printf("  %zu frames without a camera coded with one fitted to depth and motion\n",
                    s.cameras_fitted);
}

constexpr const char* kFrameStatsColumns =
    "frame,type,bytes,header_bits,camera_bits,depth_bits,motion_bits,colour_bits,blocks,"
    "blocks_skipped,intra_blocks,depth_zero_blocks,motion_residual_pixels,revealed_pixels";

// One frame's row of --frame-stats: the difference of the encoder's running counts.
void write_frame_stats(CsvFile& csv, std::size_t frame, std::size_t bytes,
                       const codec::StreamStats& a, const codec::StreamStats& b) {
    auto d = [](std::size_t after, std::size_t before) { return std::to_string(after - before); };
    csv.row({std::to_string(frame), b.key_frames > a.key_frames ? "key" : "inter",
             std::to_string(bytes), d(b.header_bits, a.header_bits),
             d(b.camera_bits, a.camera_bits), d(b.depth_bits, a.depth_bits),
             d(b.motion_bits, a.motion_bits), d(b.color_bits, a.color_bits), d(b.blocks, a.blocks),
             d(b.blocks_skipped, a.blocks_skipped), d(b.intra_blocks, a.intra_blocks),
             d(b.depth_zero_blocks, a.depth_zero_blocks),
             d(b.motion_residual_pixels, a.motion_residual_pixels),
             d(b.revealed_pixels, a.revealed_pixels)});
    csv.flush();
}

struct EncodeJob {
    std::string in, out, chroma = "420", depth = "view", frame_stats;
    int qp = 28, quality = 0, bitrate = 0, keyint = 0, skip = 2, slices = 0;
    double motion_error = 0.25;
    bool quality_given = false, overwrite_inputs = false, resume = false, no_objects = false;
    bool fixed_bounds = false;
    std::string line;  // the options given, recorded for --resume
};

// Bad option values are argument errors (exit 2), checked before anything is read.
Status encoder_options(const EncodeJob& job, codec::EncoderOptions& o) {
    if (job.in.empty()) return Status::error("encode: --in DIR is required");
    if (job.out.empty()) return Status::error("encode: --out FILE.rps is required");
    o.qp = job.qp;
    if (job.quality_given) {
        if (job.quality < 0 || job.quality > 100)
            return Status::error("encode: --quality must be in 0..100");
        o.qp = (51 * (100 - job.quality) + 50) / 100;
    }
    if (o.qp < 0 || o.qp > 51) return Status::error("encode: --qp must be in 0..51");
    if (job.bitrate < 0) return Status::error("encode: --bitrate must be positive");
    if (job.keyint < 0) return Status::error("encode: --keyint must be 0 or more");
    if (job.skip < 0 || job.skip > 255) return Status::error("encode: --skip must be in 0..255");
    if (job.slices < 0 || job.slices > 64)
        return Status::error("encode: --slices must be in 0..64 (0: one per 24 macroblock rows)");
    o.slices = job.slices;
    o.bitrate_kbps = job.bitrate;
    o.keyint = job.keyint;
    o.skip_threshold = job.skip;
    if (!(job.motion_error == 0.0 || (job.motion_error >= 0.1 && job.motion_error <= 8.0)))
        return Status::error(
            "encode: --motion-error must be 0 (per pixel, 1/8 px) or in 0.1..8 px");
    o.motion_error_px = float(job.motion_error);
    o.rigid_objects = !job.no_objects;
    o.bounds_follow_qp = !job.fixed_bounds;
    if (job.chroma == "420")
        o.chroma = codec::Chroma::C420;
    else if (job.chroma == "444")
        o.chroma = codec::Chroma::C444;
    else
        return Status::error("encode: --chroma " + job.chroma + ": expected 420 or 444");
    return parse_depth_mode(job.depth, o);
}

// --resume: the packets a killed encode left in `partial` (whole ones; a torn last one is
// dropped) are decoded into the encoder's state, with their frames' rates from the sequence's
// headers (rate control's, which the stream does not hold), and `prefix` keeps their bytes.
Status resume_stream(const EncodeJob& job, const std::string& partial, const Sequence& sequence,
                     double fps, codec::Encoder& encoder, std::vector<uint8_t>& prefix,
                     codec::StreamInfo& info, std::size_t& frames) {
    std::error_code ec;
    if (!std::filesystem::exists(partial, ec)) return {};
    const std::string recorded = read_text(partial + ".run");
    if (recorded != job.line)
        return Status::error("--resume: " + partial + " was written by another run (" + recorded +
                             "); resume it with the same arguments");
    REPRISE_TRY(read_file(partial, prefix));
    std::vector<std::span<const uint8_t>> packets;
    const Status split = codec::split_stream(prefix, info, packets);
    if (packets.empty()) {  // not even one whole packet: start again
        prefix.clear();
        return {};
    }
    if (packets.size() > sequence.files.size())
        return Status::error("--resume: " + partial + " holds " + std::to_string(packets.size()) +
                             " frames, more than " + job.in + " has");
    std::vector<double> rates(packets.size());
    for (std::size_t i = 0; i < packets.size(); ++i) {
        FrameHeader header;
        REPRISE_TRY(read_frame_header(sequence.files[i], header));
        rates[i] = header.fps > 0 ? header.fps : fps;  // as run_encode sends them
    }
    REPRISE_TRY(encoder.resume(packets, rates));
    prefix.resize(std::size_t(packets.back().data() + packets.back().size() - prefix.data()));
    frames = packets.size();
    std::fprintf(stderr, "[encode] resuming after %zu whole packets%s\n", frames,
                 split.ok() ? "" : " (a torn last packet dropped)");
    return {};
}

// The stream grows in a hidden .OUT.partial beside OUT, flushed after every packet, and is renamed
// to OUT when the last frame is in: a killed encode leaves whole packets for --resume.
Status run_encode(const EncodeJob& job, const codec::EncoderOptions& o) {
    std::error_code ec;
    if (std::filesystem::is_directory(job.out, ec))
        return Status::error("--out " + job.out + " is a folder; the stream is one file (.rps)");
    REPRISE_TRY(check_output("--out", job.out, false,
                             {.inputs = {job.in}, .overwrite_inputs = job.overwrite_inputs}));
    CsvFile frame_stats;
    if (!job.frame_stats.empty()) {
        REPRISE_TRY(
            check_output("--frame-stats", job.frame_stats, false, {.inputs = {job.in, job.out}}));
        REPRISE_TRY(frame_stats.open(job.frame_stats, kFrameStatsColumns));
    }
    Sequence sequence;
    REPRISE_TRY(open_sequence(job.in, sequence));
    REPRISE_TRY(check_one_size(sequence, "encode"));
    codec::Encoder encoder;
    REPRISE_TRY(codec::Encoder::create(o, encoder));
    const std::string partial = partial_path(job.out);
    std::vector<uint8_t> prefix;
    codec::StreamInfo resumed;
    std::size_t first = 0;
    const double fps = sequence.fps > 0 ? sequence.fps : 30.0;
    if (job.resume)
        REPRISE_TRY(resume_stream(job, partial, sequence, fps, encoder, prefix, resumed, first));
    std::ofstream(partial + ".run", std::ios::trunc) << job.line;
    std::ofstream stream(partial, std::ios::binary | std::ios::trunc);
    std::size_t bytes = prefix.size();
    if (!stream.write(reinterpret_cast<const char*>(prefix.data()), std::streamsize(bytes)))
        return Status::error(job.out + ": cannot write " + partial);
    prefix = {};
    Frame frame;
    double busy_ms = 0.0;
    const std::size_t n = sequence.files.size();
    for (std::size_t i = first; i < n; ++i) {
        REPRISE_TRY(read_frame(sequence, i, frame));
        if (frame.fps <= 0) frame.fps = fps;
        if (i == first && first > 0 &&
            (frame.width() != resumed.width || frame.height() != resumed.height))
            return Status::error("--resume: " + partial + " holds " +
                                 std::to_string(resumed.width) + "x" +
                                 std::to_string(resumed.height) + " frames, " + sequence.files[i] +
                                 " is another size");
        std::vector<uint8_t> out;
        if (i == 0)
            REPRISE_TRY(codec::write_stream_header(out, frame.width(), frame.height(), fps));
        const codec::StreamStats before = encoder.stats();
        const auto start = Clock::now();
        const Status sent = encoder.send_frame(frame);
        busy_ms += ms_since(start);
        if (!sent.ok()) return Status::error(sequence.files[i] + ": " + sent.message());
        codec::Packet packet;
        std::size_t packet_bytes = 0;
        while (encoder.receive_packet(packet) == Result::Ok) {
            out.insert(out.end(), packet.data.begin(), packet.data.end());
            packet_bytes += packet.data.size();
        }
        if (!stream.write(reinterpret_cast<const char*>(out.data()), std::streamsize(out.size()))
                 .flush())
            return Status::error(job.out + ": cannot write " + partial);
        bytes += out.size();
        if (frame_stats.file())
            write_frame_stats(frame_stats, i, packet_bytes, before, encoder.stats());
        std::fprintf(stderr, "\r[encode] %zu/%zu frames, %zu bytes", i + 1, n, bytes);
    }
    std::fprintf(stderr, "\n");
    stream.close();
    REPRISE_TRY(commit_partial(job.out, bool(stream)));
    std::filesystem::remove(partial + ".run", ec);
    std::printf(
        "encoded %zu frames (%dx%d at %.3g fps) into %s: %zu bytes, %.2f ms per frame (without "
        "file I/O)\n",
        n, frame.width(), frame.height(), fps, job.out.c_str(), bytes,
        busy_ms / double(std::max<std::size_t>(1, n - first)));
    print_stats(encoder.stats(), fps);
    if (encoder.stats().nonfinite.total() > 0)
        std::fprintf(stderr, "[encode] input: %s\n",
                     describe_nonfinite(encoder.stats().nonfinite).c_str());
    return {};
}

Status run_decode(const std::string& in, const std::string& out, bool overwrite_inputs) {
    if (out.empty()) return Status::error("--out DIR is required");
    OutputFolder output;
    REPRISE_TRY(output.open(out, {.inputs = {in}, .overwrite_inputs = overwrite_inputs},
                            "decode " + in, false));
    std::vector<uint8_t> bytes;
    REPRISE_TRY(read_file(in, bytes));
    // Frames are named by their number in the stream: frames lost to damage leave gaps.
    codec::Decoder decoder;
    codec::StreamInfo info;
    codec::StreamReport report;
    int written = 0;
    int64_t last = -1;
    double sink_ms = 0.0;
    const auto start = Clock::now();
    const Status decoded = codec::decode_stream(
        bytes, decoder, info, report, [&](uint32_t number, Frame& frame) -> Status {
            const auto sink_start = Clock::now();
            if (number > uint32_t(INT32_MAX) || int64_t(number) <= last)
                return Status::error("frame " + std::to_string(number) + " follows frame " +
                                     std::to_string(last) + ": no file name for it");
            last = number;
            REPRISE_TRY(output.write(int(number), frame));
            std::fprintf(stderr, "\r[decode] %d frames written (frame %u)", ++written, number);
            sink_ms += ms_since(sink_start);
            return {};
        });
    const double busy_ms = ms_since(start) - sink_ms;
    if (!decoded.ok()) return Status::error(in + ": " + decoded.message());
    REPRISE_TRY(output.finish());
    std::fprintf(stderr, "\n");
    std::printf("decoded %d frames of %zu packets into %s, %.2f ms per frame (without file I/O)\n",
                written, report.packets, out.c_str(), busy_ms / double(std::max(1, written)));
    print_stats(decoder.stats(), info.fps > 0 ? info.fps : 30.0);
    if (!report.ok())
        return Status::error(in + ": " + report.summary() + "; " + std::to_string(written) +
                             " frames written to " + out);
    return {};
}

}  // namespace

Status describe_stream(const std::string& path) {
    std::vector<uint8_t> bytes;
    REPRISE_TRY(read_file(path, bytes));
    codec::StreamInfo info;
    std::vector<std::span<const uint8_t>> packets;
    std::vector<codec::StreamDamage> damage;
    const Status split = codec::split_stream(bytes, info, packets, damage);
    if (!split.ok()) return Status::error(path + ": " + split.message());
    std::printf("%s: reprise stream, %dx%d, %.3g fps, %zu packets, %zu bytes\n", path.c_str(),
                info.width, info.height, info.fps, packets.size(), bytes.size());
    std::size_t keys = 0, older = 0, key_bytes = 0, inter_bytes = 0, bad = 0, largest = 0;
    for (std::size_t i = 0; i < packets.size(); ++i) {
        codec::Packet p;
        int64_t ts = 0;
        const Status s = codec::inspect_packet(packets[i], p, ts);
        if (!s.ok()) {
            std::printf("  packet %zu: %s\n", i, s.message().c_str());
            ++bad;
            continue;
        }
        const bool key = p.type == codec::PacketType::Key;
        keys += key;
        older += !key && p.reference + 1 != p.frame;
        (key ? key_bytes : inter_bytes) += packets[i].size();
        largest = std::max(largest, packets[i].size());
    }
    std::printf(
        "  key frames: %zu (%zu bytes), inter frames: %zu (%zu bytes), %zu from an older "
        "reference\n",
        keys, key_bytes, packets.size() - keys - bad, inter_bytes, older);
    const double fps = info.fps > 0 ? info.fps : 30.0;
    std::printf(
        "  mean %.1f kbit/s, largest packet %zu bytes\n",
        packets.empty() ? 0.0 : 8.0 * double(bytes.size()) / double(packets.size()) * fps / 1e3,
        largest);
    for (const codec::StreamDamage& d : damage)
        std::printf("  damaged: %zu bytes at byte %zu (%s)\n", d.bytes, d.offset, d.reason.c_str());
    if (bad || !damage.empty())
        return Status::error(path + ": " + std::to_string(bad) + " packets and " +
                             std::to_string(damage.size()) + " stretches of bytes are damaged");
    return {};
}

int command_encode(int argc, char** argv) {
    EncodeJob job;
    Args args(
        "encode",
        "Encodes an EXR sequence with reprise's scene-aware codec: each frame predicted by "
        "reprojecting\n"
        "the previous decoded frame with the rendered depth and motion; prints bits per stream.\n"
        "Frames without a camera (no cameras.json) are coded with one fitted to their depth and\n"
        "motion.");
    args.option("--in", &job.in, "input sequence (folder of EXR frames)");
    args.option("--out", &job.out, "output stream (.rps)");
    args.option("--qp", &job.qp, "quantiser 0 (finest) .. 51 (default 28), constant quality");
    args.option("--quality", &job.quality, "0..100 (100 best), instead of --qp");
    args.option("--bitrate", &job.bitrate,
                "target kbit/s with bounded frame sizes (default: constant quality)");
    args.option("--keyint", &job.keyint,
                "a key frame at least every N frames (default 0: cuts and requests only)");
    args.option("--chroma", &job.chroma, "420 | 444 (default 420)");
    args.option(
        "--depth", &job.depth,
        "view[:E[,B]] (default: 1/z to within E px of reprojection, default 0.25, for camera "
        "displacements up to B scene units, default 0.164) | lossless | bounded[:E] "
        "(relative error E, default 1e-4) | none");
    args.option("--motion-error", &job.motion_error,
                "largest error of the decoded motion in px: affine models per block where they "
                "hold (default 0.25; 0: every pixel to 1/8 px)");
    args.flag("--fixed-bounds", &job.fixed_bounds,
              "the view and motion bounds as given at every qp (default: above qp 34 both double "
              "every 6 qp, as the colour quantiser's step does)");
    args.flag("--no-objects", &job.no_objects,
              "no rigid object motions (default: each object id that moves on its own gets one, "
              "with motion models and depth)");
    args.option("--skip", &job.skip,
                "blocks within this many 8-bit levels of their prediction are skipped (default 2)");
    args.option("--slices", &job.slices,
                "slices coded in parallel, each with its own models (default 0: one per 24 "
                "macroblock rows, 720p: 2, 1080p: 3; more for many-core decoders, fewer bits with "
                "fewer)");
    args.option("--frame-stats", &job.frame_stats,
                "CSV of each frame's bits by section (header, camera, depth, motion, colour) and "
                "blocks left out");
    args.flag("--overwrite-inputs", &job.overwrite_inputs,
              "allow --out to replace an input file (written after all are read)");
    args.flag("--resume", &job.resume,
              "continue an interrupted encode of the same arguments from its partial stream");
    const Status parsed = args.parse(argc, argv);
    if (!parsed.ok() || args.help_requested()) return report(args, parsed, {});
    job.quality_given = args.given("--quality");
    job.line = args.given_line({"--resume"});
    codec::EncoderOptions options;
    const Status checked = encoder_options(job, options);
    if (!checked.ok()) return report(args, checked, {});
    return report(args, parsed, run_encode(job, options));
}

int command_decode(int argc, char** argv) {
    std::string in, out;
    bool overwrite_inputs = false;
    Args args(
        "decode",
        "Decodes a reprise stream (.rps) into an EXR sequence (colour, depth, motion, camera).");
    args.positional("FILE", &in, "the .rps stream");
    args.option("--out", &out, "output folder");
    args.flag("--overwrite-inputs", &overwrite_inputs,
              "allow --out to be the folder of the stream (written after it is read)");
    const Status parsed = args.parse(argc, argv);
    if (!parsed.ok() || args.help_requested()) return report(args, parsed, {});
    return report(args, parsed, run_decode(in, out, overwrite_inputs));
}

}  // namespace reprise::cli
