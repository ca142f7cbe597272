// The second eye from one rendered eye.
#include <pybind11/stl.h>

#include "common.hpp"
#include "reprise/gpu/context.hpp"
#include "reprise/stereo/alternate.hpp"
#include "reprise/stereo/rig.hpp"
#include "reprise/stereo/synthesize.hpp"

namespace reprise::python {
namespace {

stereo::StereoRig make_rig(float ipd, float convergence, const std::string& rig) {
    if (!std::isfinite(ipd) || !(convergence > 0.0f) || !std::isfinite(convergence))
        value_error("ipd must be finite and convergence > 0");
    stereo::StereoRig r{.ipd = ipd, .convergence = convergence};
    if (rig == "parallel")
        r.rig = stereo::Rig::Parallel;
    else if (rig == "offaxis")
        r.rig = stereo::Rig::OffAxis;
    else
        value_error("rig must be 'parallel' or 'offaxis', got '" + rig + "'");
    return r;
}

stereo::Anchor make_anchor(const std::string& anchor) {
    if (anchor == "centre" || anchor == "center") return stereo::Anchor::Centre;
    if (anchor == "left") return stereo::Anchor::Left;
    if (anchor == "right") return stereo::Anchor::Right;
    value_error("anchor must be 'centre', 'left' or 'right', got '" + anchor + "'");
}

stereo::StereoOptions make_options(const std::string& warp_method, const std::string& fill,
                                   bool widen_silhouettes, bool perceptual) {
    stereo::StereoOptions o;
    o.widen_silhouettes = widen_silhouettes;
    o.perceptual = perceptual;
    if (warp_method == "grid")
        o.warp = stereo::StereoWarp::Grid;
    else if (warp_method == "grid-bicubic" || warp_method == "grid-bilinear")
        o.warp = stereo::StereoWarp::Grid, o.grid.bicubic = warp_method == "grid-bicubic";
    else if (warp_method == "splat")
        o.warp = stereo::StereoWarp::Splat;
    else
        value_error("warp must be 'grid', 'grid-bicubic', 'grid-bilinear' or 'splat', got '" +
                    warp_method + "'");
    if (fill == "pullpush")
        o.fill = stereo::StereoFill::PullPush;
    else if (fill == "andreev")
        o.fill = stereo::StereoFill::Andreev;
    else if (fill == "patch")
        o.fill = stereo::StereoFill::Patch;
    else if (fill == "none")
        o.fill = stereo::StereoFill::None;
    else
        value_error("fill must be 'pullpush', 'andreev', 'patch' or 'none', got '" + fill + "'");
    return o;
}

// The synthesizer asserts colour and depth of one size; from Python that is a ValueError.
void require_color_and_depth(const Frame& f, const char* what) {
    if (f.color.empty() || f.depth.empty())
        value_error(std::string(what) + ": needs colour and depth");
    if (f.depth.width() != f.width() || f.depth.height() != f.height())
        value_error(std::string(what) + ": depth size differs from colour");
}

py::dict stats_dict(const stereo::StereoStats& s) {
    py::dict d;
    d["covered"] = s.covered;
    d["holes"] = s.holes;
    d["stretched"] = s.stretched;
    d["from_history"] = s.from_history;
    d["history_moving"] = s.history_moving;
    d["border"] = s.border;
    d["filled"] = s.filled;
    d["unfilled"] = s.unfilled;
    d["cells"] = s.cells;
    d["nonfinite"] = nonfinite_dict(s.nonfinite);
    return d;
}

// (frame, stats) of `make(out)`, run without the GIL; the frame keeps the rendered one's rate.
template <class Make>
py::tuple made_eye(const Frame& rendered, Make&& make) {
    Frame out;
    out.fps = rendered.fps;
    stereo::StereoStats stats;
    {
        py::gil_scoped_release release;
        stats = make(out);
    }
    return py::make_tuple(std::move(out), stats_dict(stats));
}

// backend "gles": the eye made by OpenGL ES (gpu::Context::stereo_eye: fill pullpush or none),
// the CPU's eye within 50 dB.
struct Synthesizer {
    explicit Synthesizer(const std::string& backend = "cpu") {
        if (backend == "gles")
            check(gpu::Context::create(gpu));
        else if (backend != "cpu")
            value_error("backend '" + backend + "': expected cpu or gles");
    }
    py::tuple synthesize(const Frame& rendered, const Camera& target, const std::string& warp,
                         const std::string& fill, const Frame* history, bool widen_silhouettes,
                         bool perceptual) {
        require_color_and_depth(rendered, "rendered");
        if (history) require_color_and_depth(*history, "history");
        const stereo::StereoOptions options =
            make_options(warp, fill, widen_silhouettes, perceptual);
        if (!gpu)
            return made_eye(rendered, [&](Frame& out) {
                return synthesizer.synthesize(rendered, target, out, options, history);
            });
        Status made;
        py::tuple result = made_eye(rendered, [&](Frame& out) {
            stereo::StereoStats stats;
            const GBufferView history_view = history ? history->view() : GBufferView{};
            made = gpu->stereo_eye(rendered, target, out, stats, options,
                                   history ? &history_view : nullptr);
            return stats;
        });
        if (!made.ok()) value_error("backend gles: " + made.message());
        return result;
    }
    stereo::StereoSynthesizer synthesizer;
    std::unique_ptr<gpu::Context> gpu;
};

stereo::Eye make_eye(const std::string& eye) {
    if (eye != "left" && eye != "right")
        value_error("eye must be 'left' or 'right', got '" + eye + "'");
    return eye == "left" ? stereo::Eye::Left : stereo::Eye::Right;
}

struct Alternation {
    py::tuple next(const Frame& rendered, const std::string& eye, const Camera& target,
                   const std::string& warp, const std::string& fill, bool widen_silhouettes,
                   bool perceptual) {
        require_color_and_depth(rendered, "rendered");
        const stereo::StereoOptions options =
            make_options(warp, fill, widen_silhouettes, perceptual);
        const stereo::Eye e = make_eye(eye);
        return made_eye(rendered, [&](Frame& out) {
            return alternation.next(rendered, e, target, out, options);
        });
    }
    stereo::EyeAlternation alternation;
};

}  // namespace

void bind_stereo(py::module_& m) {
    m.def(
        "eye_cameras",
        [](const Camera& camera, float ipd, float convergence, const std::string& rig,
           const std::string& anchor) {
            const stereo::EyeCameras eyes =
                stereo::eye_cameras(camera, make_rig(ipd, convergence, rig), make_anchor(anchor));
            return py::make_tuple(eyes.left, eyes.right);
        },
        py::arg("camera"), py::arg("ipd") = 0.064f, py::arg("convergence") = 10.0f,
        py::arg("rig") = "parallel", py::arg("anchor") = "centre",
        "(left, right) cameras of a stereo rig around `camera` (anchor 'centre'), or with "
        "`camera` as the left/right eye.");

    py::class_<Synthesizer>(m, "StereoSynthesizer",
                            "Makes another view from a rendered one; keeps its scratch between "
                            "frames of one size.")
        .def(py::init<const std::string&>(), py::arg("backend") = "cpu",
             "backend 'gles': eyes made by OpenGL ES (fill 'pullpush' or 'none')")
        .def("synthesize", &Synthesizer::synthesize, py::arg("rendered"), py::arg("target"),
             py::arg("warp") = "grid", py::arg("fill") = "pullpush", py::arg("history") = nullptr,
             py::arg("widen_silhouettes") = true, py::arg("perceptual") = true,
             "(frame, stats): the view of camera `target` from `rendered` (colour, depth, "
             "camera); `history` (e.g. the previous frame's other eye) fills holes first; "
             "widen_silhouettes: pixels beside a nearer surface move with it; perceptual: colour "
             "warped and filled as the square root of linear light (off: in linear light; the "
             "gles backend works in linear light).");

    py::class_<Alternation>(m, "EyeAlternation",
                            "Temporal eye alternation (Didyk et al. 2010): each frame renders one "
                            "eye, the two taking turns, and the other is made from it with that "
                            "eye's last rendered frame as history.")
        .def(py::init<>())
        .def_static(
            "rendered_eye",
            [](long long index) {
                return stereo::EyeAlternation::rendered_eye(index) == stereo::Eye::Left ? "left"
                                                                                        : "right";
            },
            py::arg("index"), "The eye to render at frame `index`: 'left' on even frames.")
        .def("next", &Alternation::next, py::arg("rendered"), py::arg("eye"), py::arg("target"),
             py::arg("warp") = "grid", py::arg("fill") = "pullpush",
             py::arg("widen_silhouettes") = true, py::arg("perceptual") = true,
             "(frame, stats): the other eye, seen from camera `target`, from `rendered` (eye "
             "'left' or 'right' of this frame), with that other eye's last render as history "
             "(none across a shot change); keeps `rendered` as its eye's history.")
        .def(
            "reset", [](Alternation& a) { a.alternation.reset(); }, "Forgets both histories.");

    m.def(
        "synthesize_eye",
        [](const Frame& rendered, float ipd, float convergence, const std::string& rig,
           const std::string& rendered_eye, const std::string& warp, const std::string& fill,
           const Frame* history, bool widen_silhouettes, bool perceptual) {
            if (rendered_eye != "left" && rendered_eye != "right")
                value_error("rendered_eye must be 'left' or 'right'");
            const stereo::EyeCameras eyes = stereo::eye_cameras(
                rendered.camera, make_rig(ipd, convergence, rig), make_anchor(rendered_eye));
            const Camera& target = rendered_eye == "left" ? eyes.right : eyes.left;
            Synthesizer s;
            const py::tuple made =
                s.synthesize(rendered, target, warp, fill, history, widen_silhouettes, perceptual);
            return py::object(made[0]);
        },
        py::arg("rendered"), py::arg("ipd") = 0.064f, py::arg("convergence") = 10.0f,
        py::arg("rig") = "parallel", py::arg("rendered_eye") = "left", py::arg("warp") = "grid",
        py::arg("fill") = "pullpush", py::arg("history") = nullptr,
        py::arg("widen_silhouettes") = true, py::arg("perceptual") = true,
        "The other eye of a rendered eye (its camera is that eye's).");
}

}  // namespace reprise::python
