// `reprise connect --window`'s OpenGL ES drawing (StreamWindow, Drawing::GlEs), headless through
// SDL's offscreen driver on Mesa: the GPU backend works in the window's context, and what the
// window shows is visualize_color of the frame, from CPU pixels and from a texture the GPU made.
#include <gtest/gtest.h>

#include <GLES3/gl32.h>

#include <cmath>
#include <cstdlib>
#include <limits>

#include "reprise/core/visualize.hpp"
#include "reprise/gpu/context.hpp"
#include "reprise/gpu/fruc_backend.hpp"
#include "stream_window.hpp"
#include "support/nonfinite.hpp"

namespace {

using namespace reprise;
using cli::StreamWindow;

// The window's pixels, top row first (glReadPixels starts at the bottom).
Image<Rgb8> read_window(int w, int h) {
    std::vector<uint8_t> rgba(std::size_t(w) * h * 4);
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glReadPixels(0, 0, w, h, GL_RGBA, GL_UNSIGNED_BYTE, rgba.data());
    Image<Rgb8> out(w, h);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const uint8_t* p = &rgba[(std::size_t(h - 1 - y) * w + x) * 4];
            out(x, y) = {p[0], p[1], p[2]};
        }
    return out;
}

// The largest difference, in 8-bit steps, between the window and the frame's display values
// scaled to it by the nearest pixel.
int largest_difference(const Image<Rgb8>& window, ImageView<const glm::vec4> frame) {
    Image<Rgb8> expected(frame.width, frame.height);
    visualize_color(frame, expected.view());
    int largest = 0;
    for (int y = 0; y < window.height(); ++y)
        for (int x = 0; x < window.width(); ++x) {
            const int fx = int((x + 0.5) / window.width() * frame.width);
            const int fy = int((y + 0.5) / window.height() * frame.height);
            const Rgb8 a = window(x, y), b = expected(fx, fy);
            for (int c = 0; c < 3; ++c)
                largest = std::max(largest, std::abs(int(a[c]) - int(b[c])));
        }
    return largest;
}

TEST(CliWindow, DrawsDisplayValuesFromThePixelsAndFromTheGpusTexture) {
    ::setenv("SDL_VIDEODRIVER", "offscreen", 1);
    std::unique_ptr<StreamWindow> window;
    const Status opened =
        StreamWindow::open(false, glm::mat4(1.0f), StreamWindow::Drawing::GlEs, window);
    ASSERT_TRUE(opened.ok()) << opened.message();
    std::unique_ptr<gpu::Context> gpu;
    const Status adopted = gpu::Context::adopt_current(gpu);
    ASSERT_TRUE(adopted.ok()) << adopted.message();
    GLint viewport[4] = {};
    glGetIntegerv(GL_VIEWPORT, viewport);
    const int ww = viewport[2], wh = viewport[3];
    ASSERT_GT(ww, 0);

    // CPU pixels, with values a display clamps and a NaN: drawn as visualize_color draws them.
    NonfiniteCounts spoiled;
    const std::vector<Frame> frames = test::spoiled_sequence(2, spoiled);
    Frame shown = frames[0];
    shown.color(0, 0) = glm::vec4(2.0f, -1.0f, std::numeric_limits<float>::quiet_NaN(), 1.0f);
    const Status drawn = window->show(shown.view());
    ASSERT_TRUE(drawn.ok()) << drawn.message();
    // Read after the swap: the offscreen driver's surface is a single-buffered pbuffer.
    EXPECT_LE(largest_difference(read_window(ww, wh), shown.color.view()), 1);

    // An extrapolated frame left on the GPU: drawn from its texture, nothing downloaded.
    {
        gpu::FrucBackend backend(*gpu);
        backend.keep_extrapolated_on_gpu(true);
        const warp::FrucOptions options{.mode = warp::FrucMode::Extrapolate,
                                        .warp = warp::WarpMethod::Splat};
        const Camera& to = frames[0].camera;
        Frame out;
        warp::FrucCounters counters;
        const Status made = backend.extrapolate(frames[1], to.view, to.projection, 0.5f, 1.0f,
                                                options, out, counters, 0);
        ASSERT_TRUE(made.ok()) << made.message();
        EXPECT_TRUE(out.color.empty());
        EXPECT_TRUE(window->draws_textures());
        const Status drawn_made = window->show(backend.made());
        ASSERT_TRUE(drawn_made.ok()) << drawn_made.message();
        const Image<Rgb8> from_texture = read_window(ww, wh);
        Frame downloaded;
        gpu::ExtrapolateStats stats;
        ASSERT_TRUE(
            gpu->extrapolate(frames[1], to.view, to.projection, 0.5f, downloaded, stats, options)
                .ok());
        EXPECT_LE(largest_difference(from_texture, downloaded.color.view()), 1);
    }
    EXPECT_FALSE(window->show(gpu::MadeTextures{}).ok()) << "nothing to draw";
    gpu.reset();  // the GPU's objects go while the window's context is current
}

}  // namespace
