// FrameRateConverter: frames in, K times as many out.
#include <pybind11/stl.h>

#include <memory>

#include "common.hpp"
#include "reprise/gpu/fruc_backend.hpp"
#include "reprise/warp/fruc.hpp"

namespace reprise::python {
namespace {

warp::FrucOptions fruc_options(const std::string& mode, const std::string& warp_method,
                               const std::string& fill, bool refine, bool true_motion,
                               bool widen_silhouettes) {
    warp::FrucOptions o;
    o.refine.enabled = refine;
    o.true_motion = true_motion;
    o.widen_silhouettes = widen_silhouettes;
    const Status parsed = warp::fruc_options_from_names(mode, warp_method, fill, o);
    if (!parsed.ok()) value_error(parsed.message());
    return o;
}

struct Converter {
    Converter(int factor, const std::string& mode, const std::string& warp_method,
              const std::string& fill, bool refine, bool true_motion, const std::string& backend,
              bool widen_silhouettes, int border_run, bool perceptual) {
        warp::FrucOptions options =
            fruc_options(mode, warp_method, fill, refine, true_motion, widen_silhouettes);
        if (border_run < 0) value_error("border_run must be >= 0");
        options.border_run = border_run;
        options.perceptual = perceptual;
        if (backend == "gles") {
            if (const Status s = gpu::FrucBackend::check(options, options.splat); !s.ok())
                value_error("backend gles: " + s.message());
            if (const Status s = gpu::Context::create(gpu); !s.ok()) check(s);
            gpu_backend = std::make_unique<gpu::FrucBackend>(*gpu, options.splat);
            options.backend = gpu_backend.get();
        } else if (backend != "cpu") {
            value_error("backend '" + backend + "': expected cpu or gles");
        }
        const Status made = warp::FrameRateConverter::create(factor, options, converter);
        if (!made) value_error(made.message());
    }

    void send(const Frame& frame) {
        Status status;
        {
            py::gil_scoped_release release;
            status = converter.send(frame);
        }
        check(status);
    }
    std::optional<Frame> receive() {
        Frame out;
        if (!converter.receive(out)) return std::nullopt;
        return out;
    }
    std::vector<Frame> convert(const std::vector<const Frame*>& frames) {
        std::vector<Frame> out;
        for (const Frame* f : frames) {
            if (!f) type_error("convert: None in the frame list");
            send(*f);
            while (auto made = receive()) out.push_back(std::move(*made));
        }
        return out;
    }
    py::dict counters() const {
        const warp::FrucCounters& c = converter.counters();
        py::dict d;
        d["inputs"] = c.inputs;
        d["outputs"] = c.outputs;
        d["copied_still"] = c.copied_still;
        d["fills"] = c.fills;
        d["fills_skipped"] = c.fills_skipped;
        d["hole_pixels"] = c.hole_pixels;
        d["border_pixels"] = c.border_pixels;
        d["dynamic_layers"] = c.dynamic_layers;
        d["dynamic_skipped"] = c.dynamic_skipped;
        d["cuts"] = c.cuts;
        d["cut_tests_skipped"] = c.cut_tests_skipped;
        d["grid_cells"] = c.grid_cells;
        d["true_motion"] = c.true_motion;
        d["linear_motion"] = c.linear_motion;
        d["refined_frames"] = c.refined_frames;
        d["refine_skipped"] = c.refine_skipped;
        d["refine_tiles"] = c.refine_tiles;
        d["refine_tiles_left_out"] = c.refine_tiles_left_out;
        d["flow_pixels"] = c.flow_pixels;
        d["refined_pixels"] = c.refined_pixels;
        d["refine_ms"] = c.refine_ms;
        d["ui_frames"] = c.ui_frames;
        d["silhouette_pixels"] = c.silhouette_pixels;
        d["nonfinite"] = nonfinite_dict(c.nonfinite);
        py::dict chosen, left_out;
        for (int k = 0; k < warp::kAutoCandidates; ++k) {
            chosen[warp::auto_candidate_name(k)] = c.auto_chosen[k];
            left_out[warp::auto_candidate_name(k)] = c.auto_left_out[k];
        }
        d["auto_chosen"] = chosen;
        d["auto_left_out"] = left_out;
        return d;
    }

    // Declared before the converter, which holds a pointer to the backend: destroyed after it.
    std::unique_ptr<gpu::Context> gpu;
    std::unique_ptr<gpu::FrucBackend> gpu_backend;
    warp::FrameRateConverter converter;
};

}  // namespace

void bind_fruc(py::module_& m) {
    py::class_<Converter>(
        m, "FrameRateConverter",
        "Frame-rate upconversion, K output frames per input frame. "
        "interpolate: after each frame (but the first), the K-1 frames "
        "between it and its predecessor, then the frame itself; extrapolate: "
        "the frame, then K-1 frames beyond it. refine: optical flow where the "
        "rendered motion is not what is seen (moving shadows, reflections). "
        "true_motion: each side goes where it truly is at the in-between "
        "instant (off: linearly). backend 'gles': the made frames on the "
        "GPU (OpenGL ES), with warp 'grid', 'splat' or 'reverse' and fill 'pullpush' "
        "(extrapolation also 'none'), as the CPU's (refinement's optical flow runs on the CPU); "
        "it is used from the thread that made it "
        "(another thread gets an error). widen_silhouettes: pixels beside a nearer "
        "surface warp with it, so the anti-aliasing blended into them travels with the "
        "silhouette. border_run: px of each row's border strip a made frame continues from "
        "the row before its fill (0: the fill alone). perceptual: colour warped, blended and "
        "filled as the square root of linear light (close to the display's scale; off: in "
        "linear light).")
        .def(py::init<int, const std::string&, const std::string&, const std::string&, bool, bool,
                      const std::string&, bool, int, bool>(),
             py::arg("factor") = 2, py::arg("mode") = "interpolate", py::arg("warp") = "grid",
             py::arg("fill") = "pullpush", py::arg("refine") = true, py::arg("true_motion") = true,
             py::arg("backend") = "cpu", py::arg("widen_silhouettes") = true,
             py::arg("border_run") = warp::kMadeFrameBorderRun, py::arg("perceptual") = true)
        .def("send", &Converter::send, py::arg("frame"), "Feeds the next rendered frame.")
        .def("receive", &Converter::receive, "The next output frame, or None.")
        .def("convert", &Converter::convert, py::arg("frames"),
             "Sends each frame and returns every output frame made.")
        .def_property_readonly("counters", &Converter::counters);
}

}  // namespace reprise::python
