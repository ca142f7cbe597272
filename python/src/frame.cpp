// Camera, Frame (numpy views of its channels) and EXR frames and sequences.
#include <pybind11/stl.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <limits>
#include <optional>

#include "common.hpp"
#include "reprise/core/exr.hpp"

namespace reprise::python {
namespace {

// What values a channel accepts from Python.
enum class Values { Finite, Depth, Id };

bool acceptable(float v, Values values) {
    if (values == Values::Depth) return !std::isnan(v) && v >= 0.0f;  // +inf = background
    return std::isfinite(v);
}

const char* rule(Values values) {
    return values == Values::Depth ? "NaN or negative depth (background is +inf)" : "NaN or Inf";
}

// Copies a numpy array of shape (height, width[, components]) into `image`: a floating-point
// array for float channels, an integer one for ids; a wrong dtype, shape or value raises.
// An image that already has pixels keeps its buffer, so views handed out stay valid.
// `height` < 0: the array sets the size. `alt_components`: another accepted last axis
// (RGB for RGBA colour: alpha 1).
template <class T>
void assign_image(Image<T>& image, const py::handle& value, const char* what, int height, int width,
                  Values values, int alt_components = 0) {
    using L = PixelLayout<T>;
    using S = typename L::Scalar;
    const py::array raw = py::module_::import("numpy").attr("asarray")(value);
    const char kind = raw.dtype().kind();
    const bool integral = std::is_integral_v<S>;
    if (integral ? (kind != 'i' && kind != 'u') : kind != 'f')
        type_error(std::string(what) + ": expected " +
                   (integral ? "an integer" : "a floating-point") + " array, got dtype " +
                   py::str(raw.dtype()).cast<std::string>());
    const int ndim = L::components > 1 ? 3 : 2;
    std::string shape_text =
        "(height, width" + (L::components > 1 ? ", " + std::to_string(L::components) : "") + ")";
    if (raw.ndim() != ndim)
        value_error(std::string(what) + ": expected shape " + shape_text + ", got " +
                    std::to_string(raw.ndim()) + " dimensions");
    const int components = ndim == 3 ? int(raw.shape(2)) : 1;
    if (ndim == 3 && components != L::components && components != alt_components)
        value_error(std::string(what) + ": expected shape " + shape_text + ", got " +
                    std::to_string(components) + " components");
    if (raw.shape(0) > kMaxImageSide || raw.shape(1) > kMaxImageSide || raw.shape(0) < 1 ||
        raw.shape(1) < 1)
        value_error(std::string(what) + ": size " + std::to_string(raw.shape(1)) + "x" +
                    std::to_string(raw.shape(0)) + " is outside 1.." +
                    std::to_string(kMaxImageSide));
    const int h = int(raw.shape(0)), w = int(raw.shape(1));
    if (height >= 0 && (h != height || w != width))
        value_error(std::string(what) + ": " + std::to_string(w) + "x" + std::to_string(h) +
                    " but the frame is " + std::to_string(width) + "x" + std::to_string(height));
    if (!image.empty() && (image.width() != w || image.height() != h))
        value_error(std::string(what) + ": the channel's size cannot change");

    using Wide = std::conditional_t<integral, int64_t, float>;
    const auto array = py::array_t<Wide, py::array::c_style | py::array::forcecast>::ensure(raw);
    if (!array) type_error(std::string(what) + ": cannot convert the array");
    const Wide* from = array.data();
    const std::size_t n = std::size_t(w) * h * components;
    for (std::size_t i = 0; i < n; ++i) {
        bool good;
        if constexpr (integral)
            good = from[i] >= 0 && from[i] <= int64_t(std::numeric_limits<uint32_t>::max());
        else
            good = acceptable(from[i], values);
        if (!good) {
            const std::size_t pixel = i / components;
            value_error(std::string(what) + ": " +
                        (integral ? std::string("id outside 0..2^32-1") : rule(values)) +
                        " at pixel (" + std::to_string(pixel % w) + ", " +
                        std::to_string(pixel / w) + ")");
        }
    }
    image.resize(w, h);
    S* to = reinterpret_cast<S*>(image.data());
    for (std::size_t p = 0; p < std::size_t(w) * h; ++p)
        for (int c = 0; c < L::components; ++c)
            to[p * L::components + c] = c < components ? S(from[p * components + c]) : S(1);
}

// Camera::cut as Python sees it: None (unknown: tested on the pixels), True or False.
Cut cut_of(std::optional<bool> cut) { return !cut ? Cut::Unknown : *cut ? Cut::Yes : Cut::No; }
std::optional<bool> cut_value(Cut cut) {
    if (cut == Cut::Unknown) return std::nullopt;
    return cut == Cut::Yes;
}

Camera make_camera(const py::object& view, const py::object& projection,
                   const py::object& prev_view, const py::object& prev_projection, float near,
                   float far, std::pair<float, float> jitter, double time,
                   std::optional<bool> cut) {
    Camera c;
    if (!view.is_none()) c.view = matrix_from(view, "view");
    if (!projection.is_none()) c.projection = matrix_from(projection, "projection");
    c.prev_view = prev_view.is_none() ? c.view : matrix_from(prev_view, "prev_view");
    c.prev_projection =
        prev_projection.is_none() ? c.projection : matrix_from(prev_projection, "prev_projection");
    if (!(near > 0.0f) || !(far > near)) value_error("camera: need 0 < near < far");
    c.near = near;
    c.far = far;
    if (!std::isfinite(jitter.first) || !std::isfinite(jitter.second))
        value_error("camera: jitter must be finite");
    c.jitter = {jitter.first, jitter.second};
    c.time = time;
    c.cut = cut_of(cut);
    return c;
}

void set_channels(Frame& f, const py::object& depth, const py::object& motion,
                  const py::object& normal, const py::object& id) {
    const int h = f.height(), w = f.width();
    if (!depth.is_none()) assign_image(f.depth, depth, "depth", h, w, Values::Depth);
    if (!motion.is_none()) assign_image(f.motion, motion, "motion", h, w, Values::Finite);
    if (!normal.is_none()) assign_image(f.normal, normal, "normal", h, w, Values::Finite);
    if (!id.is_none()) assign_image(f.id, id, "id", h, w, Values::Finite);
}

// A channel property: reading gives a view into the frame; writing copies into it.
template <class T>
void channel(py::class_<Frame>& c, const char* name, Image<T> Frame::*member, Values values,
             const char* doc, int alt_components = 0) {
    c.def_property(
        name, [member](py::object self) { return image_array(self.cast<Frame&>().*member, self); },
        [member, name, values, alt_components](Frame& f, const py::object& value) {
            if (value.is_none()) {
                if (!(f.*member).empty())
                    value_error(std::string(name) +
                                ": a channel cannot be dropped (views of it may exist); make a "
                                "new Frame without it");
                return;
            }
            constexpr bool is_color = std::is_same_v<T, glm::vec4>;
            if (f.color.empty() && !is_color)
                value_error(std::string(name) + ": set the colour first");
            const bool sized = !is_color || !f.color.empty();
            assign_image(f.*member, value, name, sized ? f.height() : -1, sized ? f.width() : -1,
                         values, alt_components);
        },
        doc);
}

py::dict header_dict(const FrameHeader& h) {
    py::dict d;
    d["width"] = h.width;
    d["height"] = h.height;
    d["channels"] = h.channels;
    d["channel_types"] = h.channel_types;
    d["blender"] = h.blender;
    d["has_camera"] = h.has_camera;
    d["camera"] = h.camera;
    d["fps"] = h.fps;
    return d;
}

ExrLayout parse_layout(const std::string& layout) {
    if (layout == "reprise") return ExrLayout::Reprise;
    if (layout == "blender") return ExrLayout::Blender;
    value_error("layout must be 'reprise' or 'blender', got '" + layout + "'");
}

}  // namespace

py::array_t<float> matrix_array(const glm::mat4& m) {
    py::array_t<float> a({4, 4});
    auto r = a.mutable_unchecked<2>();
    for (int row = 0; row < 4; ++row)
        for (int column = 0; column < 4; ++column) r(row, column) = m[column][row];
    return a;
}

glm::mat4 matrix_from(const py::handle& value, const char* what) {
    const py::array raw = py::module_::import("numpy").attr("asarray")(value);
    if (raw.dtype().kind() != 'f' && raw.dtype().kind() != 'i' && raw.dtype().kind() != 'u')
        type_error(std::string(what) + ": expected a numeric 4x4 matrix");
    if (raw.ndim() != 2 || raw.shape(0) != 4 || raw.shape(1) != 4)
        value_error(std::string(what) + ": expected a 4x4 matrix");
    const auto a = py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(raw);
    glm::mat4 m;
    for (int row = 0; row < 4; ++row)
        for (int column = 0; column < 4; ++column) {
            const double v = a.at(row, column);
            if (!std::isfinite(v)) value_error(std::string(what) + ": NaN or Inf in the matrix");
            m[column][row] = float(v);
        }
    return m;
}

void bind_frame(py::module_& m) {
    py::class_<Camera>(m, "Camera",
                       "View and projection of one instant and the previous one (OpenGL "
                       "conventions, matrices indexed [row, column], column vectors).")
        .def(py::init(&make_camera), py::arg("view") = py::none(),
             py::arg("projection") = py::none(), py::arg("prev_view") = py::none(),
             py::arg("prev_projection") = py::none(), py::arg("near") = 0.1f,
             py::arg("far") = 1000.0f, py::arg("jitter") = std::pair<float, float>(0.0f, 0.0f),
             py::arg("time") = 0.0, py::arg("cut") = py::none())
        .def_property(
            "view", [](const Camera& c) { return matrix_array(c.view); },
            [](Camera& c, const py::object& v) { c.view = matrix_from(v, "view"); })
        .def_property(
            "projection", [](const Camera& c) { return matrix_array(c.projection); },
            [](Camera& c, const py::object& v) { c.projection = matrix_from(v, "projection"); })
        .def_property(
            "prev_view", [](const Camera& c) { return matrix_array(c.prev_view); },
            [](Camera& c, const py::object& v) { c.prev_view = matrix_from(v, "prev_view"); })
        .def_property(
            "prev_projection", [](const Camera& c) { return matrix_array(c.prev_projection); },
            [](Camera& c, const py::object& v) {
                c.prev_projection = matrix_from(v, "prev_projection");
            })
        .def_readwrite("near", &Camera::near)
        .def_readwrite("far", &Camera::far)
        .def_property(
            "jitter", [](const Camera& c) { return std::make_pair(c.jitter.x, c.jitter.y); },
            [](Camera& c, std::pair<float, float> j) {
                c.jitter = {j.first, j.second};
            })
        .def_readwrite("time", &Camera::time)
        .def_property(
            "cut", [](const Camera& c) { return cut_value(c.cut); },
            [](Camera& c, std::optional<bool> cut) { c.cut = cut_of(cut); },
            "Whether a cut lies between the previous frame and this one: True, False, or None "
            "(unknown: the converter and the encoder test the pixels).")
        .def("__repr__", [](const Camera& c) {
            return "<reprise.Camera near=" + std::to_string(c.near) +
                   " far=" + std::to_string(c.far) + " time=" + std::to_string(c.time) + ">";
        });

    py::class_<Frame> frame(m, "Frame",
                            "One rendered instant: colour (H, W, 4) linear RGBA, depth (H, W), "
                            "motion (H, W, 2) backward in pixels, normal (H, W, 3), id (H, W) "
                            "uint32, camera and fps. Reading a channel gives a numpy view of the "
                            "frame's own buffer (no copy); assigning copies into it.");
    frame
        .def(py::init([](const py::object& color, const py::object& depth, const py::object& motion,
                         const py::object& normal, const py::object& id, const py::object& camera,
                         double fps) {
                 Frame f;
                 assign_image(f.color, color, "color", -1, -1, Values::Finite, 3);
                 set_channels(f, depth, motion, normal, id);
                 if (!camera.is_none()) f.camera = camera.cast<Camera>();
                 if (!(fps >= 0.0) || !std::isfinite(fps)) value_error("fps must be >= 0");
                 f.fps = fps;
                 return f;
             }),
             py::arg("color"), py::arg("depth") = py::none(), py::arg("motion") = py::none(),
             py::arg("normal") = py::none(), py::arg("id") = py::none(),
             py::arg("camera") = py::none(), py::arg("fps") = 0.0)
        .def_property_readonly("width", &Frame::width)
        .def_property_readonly("height", &Frame::height)
        .def_property(
            "camera", [](Frame& f) -> Camera& { return f.camera; },
            [](Frame& f, const Camera& c) { f.camera = c; },
            py::return_value_policy::reference_internal)
        .def_readwrite("fps", &Frame::fps)
        .def(
            "copy", [](const Frame& f) { return Frame(f); }, "A deep copy.")
        .def("__repr__", [](const Frame& f) {
            std::string channels = "color";
            if (!f.depth.empty()) channels += ",depth";
            if (!f.motion.empty()) channels += ",motion";
            if (!f.normal.empty()) channels += ",normal";
            if (!f.id.empty()) channels += ",id";
            if (!f.ui.empty()) channels += ",ui";
            return "<reprise.Frame " + std::to_string(f.width()) + "x" +
                   std::to_string(f.height()) + " " + channels + ">";
        });
    channel(frame, "color", &Frame::color, Values::Finite, "(H, W, 4) float32, linear RGBA", 3);
    channel(frame, "depth", &Frame::depth, Values::Depth,
            "(H, W) float32 linear view depth, background +inf; None when absent");
    channel(frame, "motion", &Frame::motion, Values::Finite,
            "(H, W, 2) float32 backward motion in pixels; None when absent");
    channel(frame, "normal", &Frame::normal, Values::Finite,
            "(H, W, 3) float32 world-space normals; None when absent");
    channel(frame, "id", &Frame::id, Values::Finite, "(H, W) uint32 object ids; None when absent");
    channel(frame, "ui", &Frame::ui, Values::Finite,
            "(H, W, 4) float32 UI/HUD layer, premultiplied RGBA, never warped; None when absent");

    m.def(
        "read_frame",
        [](const std::string& path) {
            Frame f;
            Status status;
            {
                py::gil_scoped_release release;
                status = read_frame(path, f);
            }
            check(status);
            return f;
        },
        py::arg("path"),
        "Reads a reprise EXR frame or a Blender multilayer render (docs/exr_format.md).");
    m.def(
        "write_frame",
        [](const std::string& path, const Frame& f, const std::string& layout) {
            const WriteOptions options{.layout = parse_layout(layout)};
            Status status;
            {
                py::gil_scoped_release release;
                status = write_frame(path, f, options);
            }
            check(status);
        },
        py::arg("path"), py::arg("frame"), py::arg("layout") = "reprise",
        "Writes a frame as OpenEXR; layout 'blender' names channels as Blender's multilayer "
        "renders (ViewLayer.Combined.R, ...).");
    m.def(
        "read_header",
        [](const std::string& path) {
            FrameHeader h;
            check(read_frame_header(path, h));
            return header_dict(h);
        },
        py::arg("path"), "What a frame file's header says, without its pixels.");
    m.def(
        "open_sequence",
        [](const std::string& path) {
            Sequence s;
            check(open_sequence(path, s));
            return py::make_tuple(s.files, s.fps);
        },
        py::arg("path"), "(files sorted naturally, fps) of a folder of EXR frames.");
    m.def(
        "read_sequence",
        [](const std::string& path, int start, int count) {
            Sequence s;
            check(open_sequence(path, s));
            if (start < 0) value_error("start must be >= 0");
            std::vector<Frame> frames;
            const std::size_t end =
                count < 0 ? s.files.size()
                          : std::min(s.files.size(), std::size_t(start) + std::size_t(count));
            for (std::size_t i = std::size_t(start); i < end; ++i) {
                Frame& f = frames.emplace_back();
                Status status;
                {
                    py::gil_scoped_release release;
                    status = read_frame(s, i, f);
                }
                check(status);
                if (f.fps <= 0.0) f.fps = s.fps;
            }
            return frames;
        },
        py::arg("path"), py::arg("start") = 0, py::arg("count") = -1,
        "Reads frames [start, start + count) of a sequence (all by default).");
    m.def(
        "write_sequence",
        [](const std::string& dir, const std::vector<const Frame*>& frames,
           const std::string& layout) {
            const WriteOptions options{.layout = parse_layout(layout)};
            std::error_code ec;
            std::filesystem::create_directories(dir, ec);
            if (ec) throw Error(dir + ": cannot create the folder: " + ec.message());
            std::vector<std::string> paths;
            for (std::size_t i = 0; i < frames.size(); ++i) {
                if (!frames[i]) type_error("write_sequence: None in the frame list");
                paths.push_back(frame_path(dir, int(i)));
                Status status;
                {
                    py::gil_scoped_release release;
                    status = write_frame(paths.back(), *frames[i], options);
                }
                check(status);
            }
            return paths;
        },
        py::arg("dir"), py::arg("frames"), py::arg("layout") = "reprise",
        "Writes DIR/frame_00000.exr, ... and returns their paths.");
}

}  // namespace reprise::python
