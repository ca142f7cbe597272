// The headless G-buffer renderer: built-in scenes and glTF files to Frames.
#include <pybind11/stl.h>

#include <memory>

#include "common.hpp"
#include "reprise/server/builtin_scenes.hpp"
#include "reprise/server/renderer.hpp"

namespace reprise::python {
namespace {

struct PyScene {
    PyScene(const std::string& name, const std::string& camera, bool allow_outside_paths) {
        Status status;
        {
            py::gil_scoped_release release;
            status =
                server::load_scene(name, scene, path, {.allow_outside_paths = allow_outside_paths});
        }
        check(status);
        if (!camera.empty()) set_camera(camera);
    }
    void set_camera(const std::string& spec) {
        const server::CameraPath fallback = server::default_camera_path(scene);
        server::CameraPath parsed;
        check(server::parse_camera_spec(spec, scene, fallback, parsed));
        path = parsed;
    }
    server::Scene scene;
    server::CameraPath path;
};

server::RenderSettings settings(int width, int height, const std::string& shading, int aa) {
    check(check_image_size(width, height, "render size"));
    if (!server::aa_samples_valid(aa))
        value_error("aa must be 1, 2, 4, 8 or 16 samples per pixel, got " + std::to_string(aa));
    server::RenderSettings s{.width = width, .height = height, .aa_samples = aa};
    if (shading == "lit")
        s.shading = server::Shading::Lit;
    else if (shading == "unlit")
        s.shading = server::Shading::Unlit;
    else
        value_error("shading must be 'lit' or 'unlit', got '" + shading + "'");
    return s;
}

void check_fps(double fps) {
    if (!(fps > 0.0 && fps <= 10000.0)) value_error("fps must be in (0, 10000]");
}

struct PyRenderer {
    PyRenderer() { check(server::Renderer::create(renderer)); }

    // GL calls stay on the thread holding the GIL: the context is current there.
    Frame render(const PyScene& s, int frame, double fps, int width, int height,
                 const std::string& shading, int aa) {
        check_fps(fps);
        Frame out;
        check(renderer->render_frame(s.scene, s.path, frame, fps,
                                     settings(width, height, shading, aa), out));
        return out;
    }
    std::vector<Frame> render_sequence(const PyScene& s, int frames, int start, double fps,
                                       int width, int height, const std::string& shading, int aa) {
        if (frames < 0 || frames > 100000) value_error("frames must be in 0..100000");
        std::vector<Frame> out;
        for (int i = 0; i < frames; ++i)
            out.push_back(render(s, start + i, fps, width, height, shading, aa));
        return out;
    }
    // The scene at `time` seen by `camera`; motion towards `prev_time` with the camera's
    // previous view and projection.
    Frame render_camera(const PyScene& s, const Camera& camera, int width, int height, double time,
                        double prev_time, const std::string& shading, int aa) {
        server::Instant now{.time = time,
                            .view = camera.view,
                            .projection = camera.projection,
                            .jitter = camera.jitter,
                            .near = camera.near,
                            .far = camera.far};
        server::Instant before = now;
        before.time = prev_time;
        before.view = camera.prev_view;
        before.projection = camera.prev_projection;
        Frame out;
        check(renderer->render(s.scene, now, before, settings(width, height, shading, aa), out));
        return out;
    }

    std::unique_ptr<server::Renderer> renderer;
};

}  // namespace

void bind_render(py::module_& m) {
    m.def(
        "builtin_scenes",
        [] {
            std::vector<std::pair<std::string, std::string>> out;
            for (const server::SceneInfo& s : server::builtin_scenes())
                out.emplace_back(s.name, s.stresses);
            return out;
        },
        "[(name, what it stresses)] of the scenes built in code.");

    py::class_<PyScene>(m, "Scene",
                        "A built-in scene by name ('pan', 'fence', ...) or a .gltf/.glb file, "
                        "with its camera path ('orbit:speed=2', 'pan', 'static', ...).")
        .def(py::init<const std::string&, const std::string&, bool>(), py::arg("name"),
             py::arg("camera") = "", py::arg("allow_outside_paths") = false)
        .def_property_readonly("name", [](const PyScene& s) { return s.scene.name; })
        .def("set_camera", &PyScene::set_camera, py::arg("spec"),
             "Replaces the camera path ('orbit', 'pan:speed=2', 'static', 'gltf[:N]', ...).");

    py::class_<PyRenderer>(m, "Renderer",
                           "Headless OpenGL ES renderer (a GPU's EGL device, or Mesa llvmpipe).")
        .def(py::init<>())
        .def_property_readonly("device", [](const PyRenderer& r) { return r.renderer->device(); })
        .def("render", &PyRenderer::render, py::arg("scene"), py::arg("frame") = 0,
             py::arg("fps") = 30.0, py::arg("width") = 640, py::arg("height") = 360,
             py::arg("shading") = "lit", py::arg("aa") = 4,
             "Frame `frame` of the scene's camera path at `fps` (time = frame / fps); `aa` "
             "anti-aliases colour with 1, 2, 4, 8 or 16 samples per pixel (depth, motion, "
             "normals and ids stay single samples at the pixel centre).")
        .def("render_sequence", &PyRenderer::render_sequence, py::arg("scene"), py::arg("frames"),
             py::arg("start") = 0, py::arg("fps") = 30.0, py::arg("width") = 640,
             py::arg("height") = 360, py::arg("shading") = "lit", py::arg("aa") = 4)
        .def("render_camera", &PyRenderer::render_camera, py::arg("scene"), py::arg("camera"),
             py::arg("width") = 640, py::arg("height") = 360, py::arg("time") = 0.0,
             py::arg("prev_time") = 0.0, py::arg("shading") = "lit", py::arg("aa") = 4,
             "The scene at `time` seen by `camera` (motion towards prev_time and its previous "
             "view).");
}

}  // namespace reprise::python
