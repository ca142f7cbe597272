// Test support: one headless renderer per test binary, created on first use.
#pragma once

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "reprise/server/builtin_scenes.hpp"
#include "reprise/server/renderer.hpp"

namespace reprise::test {

// The renderer every test of this binary shares; without one the binary stops with the reason.
inline server::Renderer& shared_renderer() {
    static std::unique_ptr<server::Renderer> renderer = [] {
        std::unique_ptr<server::Renderer> made;
        Status status = server::Renderer::create(made);
        if (!status.ok()) {  // every test here needs it: stop with the reason, not a crash
            std::fprintf(stderr, "no renderer: %s\n", status.message().c_str());
            std::exit(1);
        }
        return made;
    }();
    return *renderer;
}

// Frames first .. first + count - 1 of a built-in scene (or glTF file) on its camera path.
inline std::vector<Frame> render_scene(const std::string& name, int count, int w, int h,
                                       double fps = 30.0, int first = 0) {
    server::Scene scene;
    server::CameraPath path;
    Status s = server::load_scene(name, scene, path);
    EXPECT_TRUE(s.ok()) << s.message();
    std::vector<Frame> frames(count);
    for (int i = 0; i < count; ++i) {
        s = shared_renderer().render_frame(scene, path, first + i, fps, {.width = w, .height = h},
                                           frames[i]);
        EXPECT_TRUE(s.ok()) << s.message();
    }
    return frames;
}

}  // namespace reprise::test
