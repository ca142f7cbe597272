// The scene-aware codec: frames to packets (bytes) and back.
#include <pybind11/stl.h>

#include <cstring>
#include <span>

#include "common.hpp"
#include "reprise/codec/codec.hpp"

namespace reprise::python {
namespace {

// A bytes-like object's bytes, in place.
std::span<const uint8_t> byte_span(const py::buffer& data, py::buffer_info& info) {
    info = data.request();
    if (info.ndim != 1 || info.itemsize != 1 || (info.ndim == 1 && info.strides[0] != 1))
        type_error("expected a contiguous bytes-like object");
    return {static_cast<const uint8_t*>(info.ptr), std::size_t(info.size)};
}

codec::EncoderOptions encoder_options(int qp, int bitrate_kbps, double fps, int keyint,
                                      const std::string& chroma, const std::string& depth,
                                      float depth_error, float view_error_px,
                                      float view_displacement, float motion_error_px,
                                      int skip_threshold, bool detect_cuts, bool bounds_follow_qp,
                                      int slices) {
    codec::EncoderOptions o{.qp = qp,
                            .bitrate_kbps = bitrate_kbps,
                            .fps = fps,
                            .keyint = keyint,
                            .depth_error = depth_error,
                            .view_error_px = view_error_px,
                            .view_displacement = view_displacement,
                            .motion_error_px = motion_error_px,
                            .bounds_follow_qp = bounds_follow_qp,
                            .skip_threshold = skip_threshold,
                            .detect_cuts = detect_cuts,
                            .slices = slices};
    if (chroma == "420")
        o.chroma = codec::Chroma::C420;
    else if (chroma == "444")
        o.chroma = codec::Chroma::C444;
    else
        value_error("chroma must be '420' or '444'");
    if (depth == "view")
        o.depth = codec::DepthMode::View;
    else if (depth == "lossless")
        o.depth = codec::DepthMode::Lossless;
    else if (depth == "bounded")
        o.depth = codec::DepthMode::Bounded;
    else if (depth == "none")
        o.depth = codec::DepthMode::None;
    else
        value_error("depth must be 'view', 'lossless', 'bounded' or 'none'");
    return o;
}

py::dict stats_dict(const codec::StreamStats& s) {
    py::dict d;
    d["frames"] = s.frames;
    d["key_frames"] = s.key_frames;
    d["older_reference"] = s.older_reference;
    d["header_bits"] = s.header_bits;
    d["camera_bits"] = s.camera_bits;
    d["depth_bits"] = s.depth_bits;
    d["motion_bits"] = s.motion_bits;
    d["color_bits"] = s.color_bits;
    d["total_bits"] = s.total_bits();
    d["blocks"] = s.blocks;
    d["blocks_skipped"] = s.blocks_skipped;
    d["intra_blocks"] = s.intra_blocks;
    d["depth_zero_blocks"] = s.depth_zero_blocks;
    d["depth_plane_blocks"] = s.depth_plane_blocks;
    py::dict parts;  // encoder: the depth section's bits by what they code
    parts["flags"] = s.depth_parts.flags;
    parts["planes"] = s.depth_parts.planes;
    parts["key"] = s.depth_parts.key;
    parts["objects"] = s.depth_parts.objects;
    parts["revealed"] = s.depth_parts.revealed;
    parts["seen"] = s.depth_parts.seen;
    d["depth_parts"] = parts;
    py::dict motion_parts;  // encoder: the motion section's bits by what they code
    motion_parts["tree"] = s.motion_parts.tree;
    motion_parts["models"] = s.motion_parts.models;
    motion_parts["pixels"] = s.motion_parts.pixels;
    motion_parts["objects"] = s.motion_parts.objects;
    d["motion_parts"] = motion_parts;
    d["revealed_pixels"] = s.revealed_pixels;
    d["motion_residual_pixels"] = s.motion_residual_pixels;
    d["motion_objects"] = s.motion_objects;
    d["motion_models"] = s.motion_models;
    d["motion_own_pixels"] = s.motion_own_pixels;
    d["cameras_fitted"] = s.cameras_fitted;
    py::dict ms;  // milliseconds by stage, summed over the frames
    ms["input"] = s.ms.input;
    ms["convert"] = s.ms.convert;
    ms["objects"] = s.ms.objects;
    ms["reproject"] = s.ms.reproject;
    ms["depth"] = s.ms.depth;
    ms["motion"] = s.ms.motion;
    ms["predict"] = s.ms.predict;
    ms["color"] = s.ms.color;
    d["ms"] = ms;
    return d;
}

struct PyEncoder {
    explicit PyEncoder(const codec::EncoderOptions& options) {
        if (const Status made = codec::Encoder::create(options, encoder); !made)
            value_error(made.message());
    }

    py::bytes encode(const Frame& frame, const py::object& display) {
        Status status;
        codec::Packet packet;
        py::array_t<uint8_t, py::array::c_style> rgba;
        ImageView<const glm::u8vec4> display_view;
        if (!display.is_none()) {
            rgba = py::array_t<uint8_t, py::array::c_style>::ensure(display);
            if (!rgba || py::array(display).dtype().kind() != 'u' ||
                py::array(display).dtype().itemsize() != 1 || rgba.ndim() != 3 ||
                rgba.shape(2) != 4)
                value_error("display: expected a uint8 array of shape (height, width, 4)");
            if (rgba.shape(0) < 1 || rgba.shape(1) < 1 || rgba.shape(0) > kMaxImageSide ||
                rgba.shape(1) > kMaxImageSide)
                value_error("display: size outside 1.." + std::to_string(kMaxImageSide));
            display_view = {reinterpret_cast<const glm::u8vec4*>(rgba.data()), int(rgba.shape(1)),
                            int(rgba.shape(0)), std::ptrdiff_t(rgba.shape(1))};
        }
        {
            py::gil_scoped_release release;
            status = display_view.empty() ? encoder.send_frame(frame)
                                          : encoder.send_frame(frame, display_view);
            if (status.ok() && encoder.receive_packet(packet) != Result::Ok)
                status = Status::error("encoder: no packet for the frame");
        }
        check(status);
        return py::bytes(reinterpret_cast<const char*>(packet.data.data()), packet.data.size());
    }
    codec::Encoder encoder;
};

struct PyDecoder {
    PyDecoder(int64_t max_pixels, bool display_values) : display(display_values) {
        if (const Status made =
                codec::Decoder::create({.max_pixels = max_pixels, .display = display}, decoder);
            !made)
            value_error(made.message());
    }
    // One packet in, the frame it completes out (false: none yet), the GIL released meanwhile.
    template <class Out>
    bool next(const py::buffer& packet, Out& out) {
        py::buffer_info info;
        const std::span<const uint8_t> bytes = byte_span(packet, info);
        Status status;
        bool made = false;
        {
            py::gil_scoped_release release;
            status = decoder.send_packet(bytes);
            if (status.ok()) made = decoder.receive_frame(out) == Result::Ok;
        }
        check(status);
        return made;
    }
    std::optional<Frame> decode(const py::buffer& packet) {
        Frame frame;
        if (!next(packet, frame)) return std::nullopt;
        return frame;
    }
    // With display: the frame (no colour) and its 8-bit sRGB display values, (height, width, 4).
    std::optional<std::pair<Frame, py::array_t<uint8_t>>> decode_display(const py::buffer& packet) {
        if (!display) value_error("decode_display: the decoder was made without display=True");
        codec::DecodedFrame decoded;
        if (!next(packet, decoded)) return std::nullopt;
        Frame frame;
        frame.depth.assign(decoded.depth());
        frame.motion.assign(decoded.motion());
        frame.camera = decoded.camera;
        frame.fps = decoded.fps;
        const Image<glm::u8vec4>& d = decoded.display;
        py::array_t<uint8_t> rgba(
            {py::ssize_t(d.height()), py::ssize_t(d.width()), py::ssize_t(4)});
        std::memcpy(rgba.mutable_data(), d.data(), d.pixel_count() * sizeof(glm::u8vec4));
        return std::pair{std::move(frame), std::move(rgba)};
    }
    bool display;
    codec::Decoder decoder;
};

}  // namespace

void bind_codec(py::module_& m) {
    auto options_init = [](int qp, int bitrate_kbps, double fps, int keyint,
                           const std::string& chroma, const std::string& depth, float depth_error,
                           float view_error_px, float view_displacement, float motion_error_px,
                           int skip_threshold, bool detect_cuts, bool bounds_follow_qp,
                           int slices) {
        return std::make_unique<PyEncoder>(
            encoder_options(qp, bitrate_kbps, fps, keyint, chroma, depth, depth_error,
                            view_error_px, view_displacement, motion_error_px, skip_threshold,
                            detect_cuts, bounds_follow_qp, slices));
    };
    py::class_<PyEncoder>(m, "Encoder",
                          "Scene-aware predictive encoder: one packet (bytes) per frame "
                          "(docs/bitstream.md).")
        .def(py::init(options_init), py::arg("qp") = 28, py::arg("bitrate_kbps") = 0,
             py::arg("fps") = 30.0, py::arg("keyint") = 0, py::arg("chroma") = "420",
             py::arg("depth") = "view", py::arg("depth_error") = 1e-4f,
             py::arg("view_error_px") = 0.25f, py::arg("view_displacement") = 0.164f,
             py::arg("motion_error_px") = 0.25f, py::arg("skip_threshold") = 2,
             py::arg("detect_cuts") = true, py::arg("bounds_follow_qp") = true,
             py::arg("slices") = 0)
        .def("encode", &PyEncoder::encode, py::arg("frame"), py::arg("display") = py::none(),
             "The packet of the next frame; `display` (uint8, (height, width, 4), alpha not "
             "read): its colour as 8-bit sRGB display values, coded as they are instead of "
             "frame.color.")
        .def("request_key_frame", [](PyEncoder& e) { e.encoder.request_key_frame(); })
        .def_property_readonly(
            "reconstruction", [](const PyEncoder& e) { return e.encoder.reconstruction(); },
            "What the decoder holds after the last packet (a copy).")
        .def_property_readonly("stats",
                               [](const PyEncoder& e) { return stats_dict(e.encoder.stats()); })
        .def_property_readonly("last_qp", [](const PyEncoder& e) { return e.encoder.last_qp(); });

    py::class_<PyDecoder>(m, "Decoder",
                          "Decodes packets; a bad packet raises reprise.Error and the decoder "
                          "stays usable.")
        .def(py::init<int64_t, bool>(), py::arg("max_pixels") = int64_t(8192) * 4320,
             py::arg("display") = false)
        .def("decode", &PyDecoder::decode, py::arg("packet"),
             "The frame of one packet (bytes-like), or None when it needs more (made with "
             "display=True: no colour).")
        .def("decode_display", &PyDecoder::decode_display, py::arg("packet"),
             "Made with display=True: (frame without colour, its 8-bit sRGB display values as "
             "uint8 (height, width, 4), alpha 0 on background), or None when it needs more.")
        .def_property_readonly("stats",
                               [](const PyDecoder& d) { return stats_dict(d.decoder.stats()); });

    m.def(
        "inspect_packet",
        [](const py::buffer& packet) {
            py::buffer_info info;
            const std::span<const uint8_t> bytes = byte_span(packet, info);
            codec::Packet p;
            int64_t timestamp_us = 0;
            check(codec::inspect_packet(bytes, p, timestamp_us));
            py::dict d;
            d["frame"] = p.frame;
            d["reference"] = p.reference;
            d["key"] = p.type == codec::PacketType::Key;
            d["timestamp_us"] = timestamp_us;
            return d;
        },
        py::arg("packet"), "Header of one packet (length, version and CRC checked).");

    m.def(
        "encode_stream",
        [options_init](const std::vector<const Frame*>& frames, int qp, int bitrate_kbps,
                       double fps, int keyint, const std::string& chroma, const std::string& depth,
                       float depth_error, float view_error_px, float view_displacement,
                       float motion_error_px, int skip_threshold, bool detect_cuts,
                       bool bounds_follow_qp, int slices) {
            if (frames.empty()) value_error("encode_stream: no frames");
            for (const Frame* f : frames)
                if (!f) type_error("encode_stream: None in the frame list");
            auto encoder = options_init(qp, bitrate_kbps, fps, keyint, chroma, depth, depth_error,
                                        view_error_px, view_displacement, motion_error_px,
                                        skip_threshold, detect_cuts, bounds_follow_qp, slices);
            std::vector<uint8_t> file;
            const double stream_fps = frames[0]->fps > 0.0 ? frames[0]->fps : fps;
            check(codec::write_stream_header(file, frames[0]->width(), frames[0]->height(),
                                             stream_fps));
            for (const Frame* f : frames) {
                const std::string packet = encoder->encode(*f, py::none());
                file.insert(file.end(), packet.begin(), packet.end());
            }
            return py::bytes(reinterpret_cast<const char*>(file.data()), file.size());
        },
        py::arg("frames"), py::arg("qp") = 28, py::arg("bitrate_kbps") = 0, py::arg("fps") = 30.0,
        py::arg("keyint") = 0, py::arg("chroma") = "420", py::arg("depth") = "view",
        py::arg("depth_error") = 1e-4f, py::arg("view_error_px") = 0.25f,
        py::arg("view_displacement") = 0.164f, py::arg("motion_error_px") = 0.25f,
        py::arg("skip_threshold") = 2, py::arg("detect_cuts") = true,
        py::arg("bounds_follow_qp") = true, py::arg("slices") = 0,
        "A whole .rps stream (file header + packets) of the frames.");
    m.def(
        "decode_stream",
        [error_type = py::object(m.attr("Error"))](const py::buffer& data,
                                                   const std::string& errors) -> py::object {
            if (errors != "raise" && errors != "return")
                value_error("decode_stream: errors='" + errors + "': expected 'raise' or 'return'");
            py::buffer_info info;
            const std::span<const uint8_t> bytes = byte_span(data, info);
            codec::Decoder decoder;
            codec::StreamInfo stream;
            codec::StreamReport report;
            std::vector<Frame> frames;
            check(codec::decode_stream(bytes, decoder, stream, report, [&](uint32_t, Frame& f) {
                if (f.fps <= 0.0) f.fps = stream.fps;
                frames.push_back(std::move(f));
                return Status{};
            }));
            py::list found;
            for (const codec::StreamDamage& d : report.damage) {
                py::dict e;
                e["kind"] = "bytes";
                e["offset"] = d.offset;
                e["length"] = d.bytes;
                e["reason"] = d.reason;
                found.append(e);
            }
            for (const codec::LostFrames& l : report.lost) {
                py::dict e;
                e["kind"] = "frames";
                e["first"] = l.first;
                e["last"] = l.open ? py::object(py::none()) : py::int_(l.last);
                e["reason"] = l.reason;
                found.append(e);
            }
            py::object decoded = py::cast(std::move(frames));
            if (errors == "return") return py::make_tuple(decoded, found);
            if (report.ok()) return decoded;
            py::object error = error_type(report.summary());
            error.attr("frames") = decoded;
            error.attr("errors") = found;
            PyErr_SetObject(error_type.ptr(), error.ptr());
            throw py::error_already_set();
        },
        py::arg("data"), py::arg("errors") = "raise",
        "The frames of a whole .rps stream (bytes-like). Damage (a torn tail, a bad packet, "
        "garbage between packets) does not stop the walk: every frame that can still be decoded "
        "is, the rest are skipped (docs/bitstream.md, 'Damaged files').\n"
        "errors='raise' (default): a damaged stream raises reprise.Error naming what was lost; "
        "the exception's .frames holds the frames decoded and .errors what was lost.\n"
        "errors='return': returns (frames, errors) and never raises for damage; errors is [] for "
        "an intact stream. Each error is a dict: {'kind': 'bytes', 'offset', 'length', 'reason'} "
        "for skipped bytes, {'kind': 'frames', 'first', 'last', 'reason'} for frames not decoded "
        "(last None: every frame after first - 1). A bad file header raises in both modes.");
}

}  // namespace reprise::python
