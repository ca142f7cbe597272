// Spatio-temporal upsampling (Herzog et al. 2010): low-resolution jittered colour to the full
// resolution of its G-buffer, on the CPU or the GPU.
#include <pybind11/stl.h>

#include <memory>

#include "common.hpp"
#include "reprise/core/memory_limit.hpp"
#include "reprise/gpu/upsampler.hpp"
#include "reprise/warp/upsample.hpp"

namespace reprise::python {
namespace {

py::dict stats_dict(const warp::UpsampleStats& s) {
    py::dict d;
    d["history_used"] = s.history_used;
    d["history_rejected"] = s.history_rejected;
    d["nonfinite_samples"] = s.nonfinite_samples;
    d["unresolved"] = s.unresolved;
    d["nonfinite"] = nonfinite_dict(s.nonfinite);
    return d;
}

struct Upsampler {
    Upsampler(const std::string& backend, float history_weight, bool gradient_steering,
              bool id_test, float history_clamp)
        : options{.history_weight = history_weight,
                  .gradient_steering = gradient_steering,
                  .id_test = id_test,
                  .history_clamp = history_clamp},
          cpu(options) {
        if (!(history_weight >= 0.0f && history_weight <= 1.0f))
            value_error("history_weight must be in [0, 1]");
        if (backend == "gles") {
            check(gpu::Context::create(context));
            check(gpu::Upsampler::create(*context, options, gpu));
        } else if (backend != "cpu") {
            value_error("backend '" + backend + "': expected cpu or gles");
        }
    }

    py::tuple upsample(const Frame& low, const Frame& full, std::pair<float, float> jitter) {
        const int w = full.width(), h = full.height();
        if (low.color.empty()) value_error("low: needs colour");
        if (full.depth.empty() || full.depth.width() != w || full.depth.height() != h)
            value_error("full: needs depth of its size");
        if (low.width() > w || low.height() > h) value_error("low: larger than the full frame");
        // History, taps, gradients and the output: measured 298 bytes a full pixel (reprise
        // upsample's estimate).
        check(check_image_memory(w, h, 300, "upsample"));
        GBufferView guides = full.view();
        auto sized = [&](const auto& image) { return image.width() == w && image.height() == h; };
        if (!sized(full.motion)) guides.motion = {};
        if (!sized(full.normal)) guides.normal = {};
        if (!sized(full.id)) guides.id = {};
        Frame out;
        out.color.resize(w, h);
        out.camera = full.camera;
        out.fps = full.fps;
        warp::UpsampleStats stats;
        Status made;
        {
            py::gil_scoped_release release;
            const glm::vec2 j(jitter.first, jitter.second);
            if (gpu)
                made = gpu->upsample(low.color.view(), j, guides, out.color.view(), &stats);
            else
                cpu.upsample(low.color.view(), j, guides, out.color.view(), &stats);
        }
        check(made);
        return py::make_tuple(std::move(out), stats_dict(stats));
    }

    void reset() {
        cpu.reset();
        if (gpu) gpu->reset();
    }

    warp::UpsampleOptions options;
    warp::SpatioTemporalUpsampler cpu;
    std::unique_ptr<gpu::Context> context;  // declared before the upsampler that uses it
    std::unique_ptr<gpu::Upsampler> gpu;
};

}  // namespace

void bind_upsample(py::module_& m) {
    py::class_<Upsampler>(m, "Upsampler",
                          "Spatio-temporal upsampling (Herzog et al. 2010): colour rendered at a "
                          "fraction of the pixels with a per-frame sub-pixel jitter, to the full "
                          "resolution of its G-buffer, with a history across frames.")
        .def(py::init<const std::string&, float, bool, bool, float>(), py::arg("backend") = "cpu",
             py::arg("history_weight") = 1.0f, py::arg("gradient_steering") = true,
             py::arg("id_test") = true, py::arg("history_clamp") = 0.25f,
             "backend 'gles': the same passes as OpenGL ES compute shaders (the CPU's frames)")
        .def("upsample", &Upsampler::upsample, py::arg("low"), py::arg("full"),
             py::arg("jitter") = std::pair<float, float>(0.0f, 0.0f),
             "(frame, stats): `low`'s colour (any size up to the full one; its pixel (u, v) "
             "sampled the full image at ((u + 0.5) W/w + jitter.x, (v + 0.5) H/h + jitter.y), "
             "jitter in full pixels) at the size of `full`, guided by its depth, motion, normals "
             "and ids. Frames in order; reset() after a cut or a skip.")
        .def("reset", &Upsampler::reset, "Forgets the history.");
}

}  // namespace reprise::python
