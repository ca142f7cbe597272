// The GPU backend (OpenGL ES 3.1 compute on the renderer's EGL context kind) against the CPU
// reference: reverse reprojection on every built-in scene, NaN/Inf input, the survey step, and
// the texture entry point.
#include <gtest/gtest.h>

#include <bit>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <map>
#include <memory>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include <GLES3/gl32.h>

#include "reprise/gl/context.hpp"
#include "reprise/gpu/context.hpp"
#include "reprise/gpu/fruc_backend.hpp"
#include "reprise/gpu/upsampler.hpp"
#include "reprise/server/builtin_scenes.hpp"
#include "reprise/stereo/rig.hpp"
#include "reprise/stereo/synthesize.hpp"
#include "reprise/warp/extrapolate.hpp"
#include "reprise/warp/fill.hpp"
#include "reprise/warp/fruc.hpp"
#include "reprise/warp/grid_warp.hpp"
#include "reprise/warp/reproject.hpp"
#include "reprise/warp/shot_change.hpp"
#include "reprise/warp/silhouettes.hpp"
#include "reprise/warp/splat.hpp"
#include "reprise/warp/true_motion.hpp"
#include "reprise/warp/upsample.hpp"
#include "support/frames.hpp"
#include "support/nonfinite.hpp"
#include "support/renderer.hpp"

namespace {

using namespace reprise;

constexpr int kWidth = 96, kHeight = 64;

gpu::Context& shared_gpu() {
    static std::unique_ptr<gpu::Context> context = [] {
        std::unique_ptr<gpu::Context> made;
        const Status status = gpu::Context::create(made);
        if (!status.ok()) ADD_FAILURE() << status.message();
        return made;
    }();
    return *context;
}

// Frames 3 and 4 of a built-in scene, rendered once per test binary.
const std::vector<Frame>& scene_frames(const std::string& name) {
    static std::map<std::string, std::vector<Frame>> rendered;
    auto [at, added] = rendered.try_emplace(name);
    if (added) at->second = test::render_scene(name, 2, kWidth, kHeight, 30.0, 3);
    return at->second;
}

// One run of a path: its output colour, its hit mask and counts.
struct Reprojected {
    Image<glm::vec4> out;
    Image<uint8_t> hit;
    warp::ReprojectCounts counts;
};

Reprojected cpu_reproject(const Frame& current, const Frame& previous,
                          const warp::ReprojectOptions& options = {}) {
    Reprojected r;
    r.out.assign(current.width(), current.height(), glm::vec4(0.0f));
    r.hit.assign(current.width(), current.height(), 7);
    r.counts = warp::reproject(current, previous, warp::payload_of(previous.color.view()),
                               warp::payload_of(r.out.view()), r.hit.view(), options);
    return r;
}

Reprojected gpu_reproject(const Frame& current, const Frame& previous,
                          const warp::ReprojectOptions& options = {}) {
    Reprojected r;
    r.out.assign(current.width(), current.height(), glm::vec4(0.0f));
    r.hit.assign(current.width(), current.height(), 7);
    const Status status =
        shared_gpu().reproject(current, previous, warp::payload_of(previous.color.view()),
                               warp::payload_of(r.out.view()), r.hit.view(), options, r.counts);
    EXPECT_TRUE(status.ok()) << status.message();
    return r;
}

std::size_t mask_differences(const Image<uint8_t>& a, const Image<uint8_t>& b) {
    std::size_t n = 0;
    for (std::size_t i = 0; i < a.pixel_count(); ++i) n += a.data()[i] != b.data()[i];
    return n;
}

// The issue's tolerance: >= 50 dB on display values, holes within 0.1 % of the pixels, each
// outcome's count too. Returns what is out of it ("" when nothing is).
std::string out_of_tolerance(const Reprojected& cpu, const Reprojected& gpu) {
    const std::size_t pixels = cpu.hit.pixel_count();
    const std::size_t allowed = pixels / 1000;
    std::string out;
    auto check = [&](const char* what, std::size_t a, std::size_t b) {
        if ((a > b ? a - b : b - a) > allowed)
            out += std::string(what) + " cpu " + std::to_string(a) + " gpu " + std::to_string(b) +
                   "; ";
    };
    check("hit mask differences", 0, mask_differences(cpu.hit, gpu.hit));
    check("hits", cpu.counts.hits, gpu.counts.hits);
    check("offscreen", cpu.counts.offscreen, gpu.counts.offscreen);
    check("behind", cpu.counts.behind, gpu.counts.behind);
    check("occluded", cpu.counts.occluded, gpu.counts.occluded);
    check("other id", cpu.counts.other_id, gpu.counts.other_id);
    check("invalid", cpu.counts.invalid, gpu.counts.invalid);
    if (gpu.counts.hits + gpu.counts.misses() != cpu.counts.hits + cpu.counts.misses())
        out += "looked-up pixels differ; ";
    const double db = test::display_psnr(cpu.out, gpu.out);
    if (!(db >= 50.0)) out += "colour " + std::to_string(db) + " dB; ";
    return out;
}

void expect_equal_within_tolerance(const Reprojected& cpu, const Reprojected& gpu,
                                   const char* what) {
    EXPECT_EQ(out_of_tolerance(cpu, gpu), "") << what;
}

TEST(Gpu, ReprojectionMatchesTheCpuOnEveryBuiltInScene) {
    for (const server::SceneInfo& info : server::builtin_scenes()) {
        SCOPED_TRACE(info.name);
        const std::vector<Frame> frames =
            test::render_scene(info.name, 2, kWidth, kHeight, 30.0, 3);
        const Reprojected cpu = cpu_reproject(frames[1], frames[0]);
        const Reprojected gpu = gpu_reproject(frames[1], frames[0]);
        // Not vacuous: most of a frame 1/30 s on is found in the one before.
        EXPECT_GT(cpu.counts.hits, cpu.hit.pixel_count() / 2);
        expect_equal_within_tolerance(cpu, gpu, info.name);
        std::printf("%-10s hits cpu %zu gpu %zu, hit masks differ at %zu, %.1f dB\n", info.name,
                    cpu.counts.hits, gpu.counts.hits, mask_differences(cpu.hit, gpu.hit),
                    test::display_psnr(cpu.out, gpu.out));
    }
}

TEST(Gpu, ReprojectionWithoutIdsAndWithTheSurveyStep) {
    std::vector<Frame> frames = test::render_scene("crossing", 2, kWidth, kHeight, 30.0, 5);
    for (Frame& f : frames) f.id = {};
    expect_equal_within_tolerance(cpu_reproject(frames[1], frames[0]),
                                  gpu_reproject(frames[1], frames[0]), "no ids");
    const warp::ReprojectOptions survey{.step = 8};
    const Reprojected cpu = cpu_reproject(frames[1], frames[0], survey);
    const Reprojected gpu = gpu_reproject(frames[1], frames[0], survey);
    EXPECT_EQ(cpu.counts.hits + cpu.counts.misses(), std::size_t(12 * 8));
    expect_equal_within_tolerance(cpu, gpu, "step 8");
    // Pixels off the survey grid keep what they had (7).
    EXPECT_EQ(gpu.hit(1, 1), 7);
}

TEST(Gpu, NonFiniteInputIsCountedAsOnTheCpu) {
    NonfiniteCounts expected;
    const std::vector<Frame> frames = test::spoiled_sequence(2, expected);
    const Reprojected cpu = cpu_reproject(frames[1], frames[0]);
    const Reprojected gpu = gpu_reproject(frames[1], frames[0]);
    EXPECT_GT(cpu.counts.invalid, 0u);
    EXPECT_EQ(gpu.counts.invalid, cpu.counts.invalid);
    expect_equal_within_tolerance(cpu, gpu, "NaN/Inf");
    for (std::size_t i = 0; i < gpu.out.pixel_count(); ++i)
        ASSERT_TRUE(test::finite(gpu.out.data()[i])) << "pixel " << i;
}

// Worst cases: motion of 1e30 and of a few pixels, depth 0, negative, denormal, huge and +inf,
// projections that put points behind the previous camera, jitter on both frames.
TEST(Gpu, ReprojectionOnExtremeValues) {
    std::vector<Frame> frames = test::sequence(2);
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.0f, 1.0f);
    const float depths[] = {0.0f, -1.0f, 1e-40f, 1e30f, test::kInf, 0.05f, 3.0f, 20.0f};
    const float motions[] = {1e30f, -1e30f, 0.0f, 0.5f, -3.25f, 40.0f, 1e-7f, -0.5f};
    for (Frame& f : frames) {
        f.id.assign(f.width(), f.height(), 1);
        for (int y = 0; y < f.height(); ++y)
            for (int x = 0; x < f.width(); ++x) {
                if (u(rng) < 0.3f) f.depth(x, y) = depths[rng() % 8];
                if (u(rng) < 0.3f) f.motion(x, y) = {motions[rng() % 8], motions[rng() % 8]};
                if (u(rng) < 0.05f) f.id(x, y) = 2;
            }
    }
    frames[1].camera.jitter = {0.25f, -0.125f};
    frames[0].camera.jitter = {-0.375f, 0.5f};
    // The previous camera turned half round: much of the frame is behind it.
    Frame turned = frames[1];
    turned.camera.prev_view = glm::rotate(turned.camera.view, 2.5f, glm::vec3(0, 1, 0));
    // GPUs may flush subnormal floats to zero (GLSL ES allows it; NVIDIA's driver does, llvmpipe
    // does not): a depth of 1e-40 is then a depth of 0, which lands elsewhere. The GPU must match
    // the CPU on the input as given or on the input with subnormals flushed.
    auto flushed = [](Frame f) {
        for (std::size_t i = 0; i < f.depth.pixel_count(); ++i)
            if (std::fpclassify(f.depth.data()[i]) == FP_SUBNORMAL) f.depth.data()[i] = 0.0f;
        return f;
    };
    for (const Frame* current : {&frames[1], &turned}) {
        const Reprojected cpu = cpu_reproject(*current, frames[0]);
        const Reprojected gpu = gpu_reproject(*current, frames[0]);
        EXPECT_GT(cpu.counts.invalid + cpu.counts.offscreen, 0u);
        const std::string as_given = out_of_tolerance(cpu, gpu);
        const std::string as_flushed =
            out_of_tolerance(cpu_reproject(flushed(*current), flushed(frames[0])), gpu);
        EXPECT_TRUE(as_given.empty() || as_flushed.empty())
            << "as given: " << as_given << "\nsubnormals flushed: " << as_flushed;
    }
    EXPECT_GT(cpu_reproject(turned, frames[0]).counts.behind, 0u);
}

// The texture entry point: the application's textures in, its textures written.
struct Textures {
    std::vector<GLuint> names;
    GLuint make(GLenum format, int w, int h, GLenum pixel_format, GLenum type, const void* data) {
        GLuint t = 0;
        glGenTextures(1, &t);
        glBindTexture(GL_TEXTURE_2D, t);
        glTexStorage2D(GL_TEXTURE_2D, 1, format, w, h);
        glPixelStorei(GL_UNPACK_ALIGNMENT, 1);
        if (data) glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, w, h, pixel_format, type, data);
        names.push_back(t);
        return t;
    }
    gpu::GBufferTextures gbuffer(const Frame& f) {
        const int w = f.width(), h = f.height();
        return {.depth = make(GL_R32F, w, h, GL_RED, GL_FLOAT, f.depth.data()),
                .motion = make(GL_RG32F, w, h, GL_RG, GL_FLOAT, f.motion.data()),
                .id = make(GL_R32UI, w, h, GL_RED_INTEGER, GL_UNSIGNED_INT, f.id.data()),
                .width = w,
                .height = h,
                .camera = f.camera};
    }
    // A frame's colour as GL_RGBA32F; empty textures of the test size.
    GLuint color(const Frame& f) {
        return make(GL_RGBA32F, f.width(), f.height(), GL_RGBA, GL_FLOAT, f.color.data());
    }
    GLuint rgba() { return make(GL_RGBA32F, kWidth, kHeight, GL_RGBA, GL_FLOAT, nullptr); }
    GLuint r32f() { return make(GL_R32F, kWidth, kHeight, GL_RED, GL_FLOAT, nullptr); }
    ~Textures() { glDeleteTextures(GLsizei(names.size()), names.data()); }
};

// A GL_RGBA32F texture read back as the application would (through a framebuffer).
Image<glm::vec4> read_rgba(GLuint texture, int width = kWidth, int height = kHeight) {
    Image<glm::vec4> pixels(width, height);
    GLuint framebuffer = 0;
    glGenFramebuffers(1, &framebuffer);
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, texture, 0);
    glReadPixels(0, 0, width, height, GL_RGBA, GL_FLOAT, pixels.data());
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDeleteFramebuffers(1, &framebuffer);
    return pixels;
}

TEST(Gpu, TextureEntryPointWritesTheCallersTextures) {
    const std::vector<Frame>& frames = scene_frames("pan");
    const Reprojected cpu = cpu_reproject(frames[1], frames[0]);
    gpu::Context& context = shared_gpu();
    context.make_current();
    Textures t;
    const gpu::GBufferTextures current = t.gbuffer(frames[1]), previous = t.gbuffer(frames[0]);
    const GLuint payload = t.color(frames[0]);
    const Image<glm::vec4> zeros(kWidth, kHeight, glm::vec4(0.0f));
    const GLuint out = t.make(GL_RGBA32F, kWidth, kHeight, GL_RGBA, GL_FLOAT, zeros.data());
    const GLuint hit = t.make(GL_R32UI, kWidth, kHeight, GL_RED_INTEGER, GL_UNSIGNED_INT, nullptr);
    Reprojected gpu;
    const Status status = context.reproject(current, previous, payload, out, hit, {}, gpu.counts);
    ASSERT_TRUE(status.ok()) << status.message();
    EXPECT_EQ(context.timings().upload_ms, 0.0);

    // Read the caller's textures back here, as the application would.
    GLuint framebuffer = 0;
    glGenFramebuffers(1, &framebuffer);
    glBindFramebuffer(GL_FRAMEBUFFER, framebuffer);
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, out, 0);
    gpu.out.resize(kWidth, kHeight);
    glReadPixels(0, 0, kWidth, kHeight, GL_RGBA, GL_FLOAT, gpu.out.data());
    glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, hit, 0);
    std::vector<glm::uvec4> hits(std::size_t(kWidth) * kHeight);
    glReadPixels(0, 0, kWidth, kHeight, GL_RGBA_INTEGER, GL_UNSIGNED_INT, hits.data());
    glBindFramebuffer(GL_FRAMEBUFFER, 0);
    glDeleteFramebuffers(1, &framebuffer);
    gpu.hit.resize(kWidth, kHeight);
    for (std::size_t i = 0; i < hits.size(); ++i) gpu.hit.data()[i] = uint8_t(hits[i].x);
    expect_equal_within_tolerance(cpu, gpu, "textures");
}

TEST(Gpu, BadTexturesAndPayloadsAreNamed) {
    const std::vector<Frame>& frames = scene_frames("pan");
    gpu::Context& context = shared_gpu();
    context.make_current();
    Textures t;
    const gpu::GBufferTextures current = t.gbuffer(frames[1]), previous = t.gbuffer(frames[0]);
    const GLuint small = t.make(GL_RGBA32F, 8, 8, GL_RGBA, GL_FLOAT, nullptr);
    const GLuint out = t.rgba();
    warp::ReprojectCounts counts;
    Status status = context.reproject(current, previous, small, out, 0, {}, counts);
    EXPECT_EQ(status.message(), "gpu: texture " + std::to_string(small) +
                                    " (previous payload) is 8x8, expected 96x64");
    status = context.reproject(current, previous, current.depth, out, 0, {}, counts);
    EXPECT_EQ(status.message(), "gpu: texture " + std::to_string(current.depth) +
                                    " (previous payload) has internal format 0x822e, expected "
                                    "GL_RGBA32F");
    status = context.reproject(current, previous, 4242, out, 0, {}, counts);
    EXPECT_EQ(status.message(), "gpu: texture 4242 (previous payload) is not a texture");

    std::vector<float> rgb(std::size_t(kWidth) * kHeight * 3, 0.5f);
    std::vector<float> rgb_out(rgb.size());
    status = context.reproject(
        frames[1], frames[0], {rgb.data(), kWidth, kHeight, 3, std::ptrdiff_t(kWidth) * 3},
        {rgb_out.data(), kWidth, kHeight, 3, std::ptrdiff_t(kWidth) * 3}, {}, {}, counts);
    EXPECT_EQ(status.message(),
              "gpu reproject: the payload has 3 channels; the GPU path takes RGBA (4)");
}

}  // namespace

namespace {

// The renderer and gpu/ share one EGL display: a Context that goes must not end the other's.
TEST(Gpu, ContextsComeAndGoBesideTheRenderer) {
    const std::vector<Frame> before = test::render_scene("pan", 1, kWidth, kHeight, 30.0, 3);
    for (int i = 0; i < 2; ++i) {
        std::unique_ptr<gpu::Context> another;
        const Status status = gpu::Context::create(another);
        ASSERT_TRUE(status.ok()) << status.message();
    }
    const std::vector<Frame> after = test::render_scene("pan", 1, kWidth, kHeight, 30.0, 3);
    EXPECT_EQ(std::memcmp(before[0].color.data(), after[0].color.data(),
                          before[0].color.pixel_count() * sizeof(glm::vec4)),
              0);
    // And the shared GPU context still works.
    const std::vector<Frame> frames = test::render_scene("pan", 2, kWidth, kHeight, 30.0, 3);
    expect_equal_within_tolerance(cpu_reproject(frames[1], frames[0]),
                                  gpu_reproject(frames[1], frames[0]), "after");
}

}  // namespace

namespace {

// Pull-push on the GPU against warp::PullPush::fill on one image: same stats, >= 50 dB, and
// valid pixels (and every alpha) untouched.
void expect_same_fill(const Image<glm::vec4>& color, const Image<uint8_t>& valid,
                      const Image<float>* depth, const char* what) {
    Image<glm::vec4> cpu = color, gpu = color;
    warp::PullPush pull_push;
    const warp::FillStats expected =
        pull_push.fill(cpu.view(), valid.view(), depth ? depth->view() : ImageView<const float>{});
    warp::FillStats got;
    const Status status = shared_gpu().fill(gpu.view(), valid.view(),
                                            depth ? depth->view() : ImageView<const float>{}, got);
    ASSERT_TRUE(status.ok()) << status.message();
    EXPECT_EQ(got.holes, expected.holes) << what;
    EXPECT_EQ(got.unfilled, expected.unfilled) << what;
    EXPECT_EQ(got.levels, expected.levels) << what;
    EXPECT_GE(test::display_psnr(cpu, gpu), 50.0) << what;
    std::size_t changed_valid = 0;
    for (int y = 0; y < color.height(); ++y)
        for (int x = 0; x < color.width(); ++x) {
            const bool hole = !valid(x, y) || !test::finite(glm::vec4(glm::vec3(color(x, y)), 0));
            changed_valid += !hole && std::memcmp(&gpu(x, y), &color(x, y), sizeof(glm::vec4));
            changed_valid += std::memcmp(&gpu(x, y).a, &color(x, y).a, sizeof(float)) != 0 &&
                             !std::isnan(color(x, y).a);
        }
    EXPECT_EQ(changed_valid, 0u) << what;
    std::printf("%-22s holes %zu, %d levels, %.1f dB, %.1f ms\n", what, got.holes, got.levels,
                test::display_psnr(cpu, gpu), shared_gpu().timings().compute_ms);
}

TEST(Gpu, PullPushMatchesTheCpuOnReprojectionHolesOfEveryBuiltInScene) {
    for (const server::SceneInfo& info : server::builtin_scenes()) {
        SCOPED_TRACE(info.name);
        // The misses of reprojection are the holes to fill.
        const std::vector<Frame>& frames = scene_frames(info.name);
        const Frame& current = frames[1];
        Reprojected r = cpu_reproject(current, frames[0]);
        expect_same_fill(r.out, r.hit, &current.depth, info.name);
        expect_same_fill(r.out, r.hit, nullptr, info.name);
    }
}

TEST(Gpu, PullPushOnSparseOddAndEmptyImages) {
    std::mt19937 rng(5);
    // Each new texture shape costs llvmpipe a shader compile (~1 s on a busy core): few shapes.
    // 96x64 pulls its levels from 24x16 down in one work group, 130x70 from 17x9.
    for (const auto& [w, h, share] :
         {std::tuple{37, 23, 0.5f}, std::tuple{96, 64, 0.002f}, std::tuple{1, 9, 0.5f},
          std::tuple{16, 16, 0.0f}, std::tuple{1, 1, 0.0f}, std::tuple{130, 70, 0.001f}}) {
        Image<glm::vec4> color(w, h);
        Image<uint8_t> valid(w, h);
        Image<float> depth(w, h);
        std::uniform_real_distribution<float> u(0.0f, 1.0f);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                color(x, y) = {u(rng), u(rng), u(rng), 1.0f};
                valid(x, y) = u(rng) < share;
                depth(x, y) = u(rng) < 0.5f ? 1.0f : 5.0f + u(rng);
            }
        if (share > 0.0f) valid(w / 2, h / 2) = 1;
        const std::string what = std::to_string(w) + "x" + std::to_string(h);
        expect_same_fill(color, valid, &depth, what.c_str());
        if (w > 1) expect_same_fill(color, valid, nullptr, what.c_str());
    }
}

TEST(Gpu, PullPushTreatsNonFiniteColorAsHoles) {
    NonfiniteCounts expected;
    const std::vector<Frame> frames = test::spoiled_sequence(1, expected);
    Image<uint8_t> valid(frames[0].width(), frames[0].height(), 1);
    expect_same_fill(frames[0].color, valid, &frames[0].depth, "NaN/Inf colour and depth");
}

TEST(Gpu, PullPushOnTexturesWritesTheOutputTexture) {
    const std::vector<Frame>& frames = scene_frames("fence");
    const Reprojected r = cpu_reproject(frames[1], frames[0]);
    Image<glm::vec4> cpu = r.out;
    warp::PullPush pull_push;
    const warp::FillStats expected =
        pull_push.fill(cpu.view(), r.hit.view(), frames[1].depth.view());

    gpu::Context& context = shared_gpu();
    context.make_current();
    Textures t;
    const GLuint color = t.make(GL_RGBA32F, kWidth, kHeight, GL_RGBA, GL_FLOAT, r.out.data());
    const GLuint valid =
        t.make(GL_R8UI, kWidth, kHeight, GL_RED_INTEGER, GL_UNSIGNED_BYTE, r.hit.data());
    const GLuint depth = t.make(GL_R32F, kWidth, kHeight, GL_RED, GL_FLOAT, frames[1].depth.data());
    const GLuint out = t.rgba();
    warp::FillStats got;
    Status status = context.fill(color, valid, depth, kWidth, kHeight, out, got);
    ASSERT_TRUE(status.ok()) << status.message();
    EXPECT_EQ(got.holes, expected.holes);
    EXPECT_GT(got.holes, 0u);
    EXPECT_GE(test::display_psnr(cpu, read_rgba(out)), 50.0);

    status = context.fill(color, depth, 0, kWidth, kHeight, out, got);
    EXPECT_NE(status.message().find("(valid) has internal format"), std::string::npos)
        << status.message();
    status = context.fill(color, valid, 0, kWidth, kHeight, color, got);
    EXPECT_EQ(status.message(), "gpu pull-push: the output is the colour texture");
}

}  // namespace

namespace {

// --- The splat and the stereo eye (StereoWarp::Splat) against the CPU.

struct Splatted {
    Image<glm::vec4> color;
    Image<float> depth;
    Image<glm::vec2> motion;
    Image<uint8_t> covered;
    std::size_t count = 0;
    explicit Splatted(int w, int h) : color(w, h), depth(w, h), motion(w, h), covered(w, h) {}
    warp::WarpTarget target() {
        return {color.view(), depth.view(), motion.view(), covered.view()};
    }
};

// The colour of covered pixels (others 0), as a display-PSNR input.
Image<glm::vec4> covered_color(const Splatted& s) {
    Image<glm::vec4> c(s.color.width(), s.color.height(), glm::vec4(0.0f));
    for (std::size_t i = 0; i < c.pixel_count(); ++i)
        if (s.covered.data()[i]) c.data()[i] = s.color.data()[i];
    return c;
}

TEST(Gpu, SplatMatchesTheCpuOnEveryBuiltInScene) {
    const std::size_t allowed = std::size_t(kWidth) * kHeight / 1000;
    for (const server::SceneInfo& info : server::builtin_scenes()) {
        SCOPED_TRACE(info.name);
        const Frame& f = scene_frames(info.name)[1];
        for (int footprint : {1, 2})
            for (float factor : {-0.5f, 1.0f}) {
                Splatted cpu(kWidth, kHeight), gpu(kWidth, kHeight);
                cpu.count = warp::splat(f, factor, cpu.target(), {.footprint = footprint});
                const Status status = shared_gpu().splat(f, factor, gpu.target(),
                                                         {.footprint = footprint}, gpu.count);

                ASSERT_TRUE(status.ok()) << status.message();
                EXPECT_GT(cpu.count, std::size_t(kWidth) * kHeight / 2);
                EXPECT_LE(mask_differences(cpu.covered, gpu.covered), allowed);
                const double db = test::display_psnr(covered_color(cpu), covered_color(gpu));
                EXPECT_GE(db, 50.0) << "footprint " << footprint << " factor " << factor;
                std::size_t motion_off = 0;
                for (std::size_t i = 0; i < gpu.motion.pixel_count(); ++i)
                    motion_off += gpu.covered.data()[i] && cpu.covered.data()[i] &&
                                  gpu.motion.data()[i] != cpu.motion.data()[i];
                EXPECT_LE(motion_off, allowed);
                std::printf(
                    "%-10s splat %d x%+.1f covered cpu %zu gpu %zu, masks differ at %zu, "
                    "%.1f dB\n",
                    info.name, footprint, factor, cpu.count, gpu.count,
                    mask_differences(cpu.covered, gpu.covered), db);
            }
    }
}

// The cells grown by the compute shader: the CPU's, in its order, to the bit.
TEST(Gpu, GridCellsAreTheCpusOnEveryBuiltInScene) {
    warp::GridWarper grid;
    std::size_t total = 0, stretched = 0, edges = 0;
    for (const server::SceneInfo& info : server::builtin_scenes()) {
        SCOPED_TRACE(info.name);
        const Frame& f = scene_frames(info.name)[1];
        for (const warp::GridOptions& options :
             {warp::GridOptions{}, warp::GridOptions{.cell = 16, .min_cell = 2},
              warp::GridOptions{.depth_threshold = 0.001f, .motion_threshold = 0.05f}})
            for (float factor : {-0.5f, 1.0f, 0.0f}) {
                std::vector<warp::GridCell> cpu, gpu;
                grid.cells(f, factor, options, cpu);
                const Status status = shared_gpu().grid_cells(f, factor, options, gpu);
                ASSERT_TRUE(status.ok()) << status.message();
                ASSERT_EQ(gpu.size(), cpu.size()) << "factor " << factor;
                std::size_t differ = 0;
                for (std::size_t i = 0; i < cpu.size(); ++i) {
                    const warp::GridCell &a = cpu[i], &b = gpu[i];
                    bool same = a.perspective == b.perspective && a.coverage[0] == b.coverage[0] &&
                                a.coverage[1] == b.coverage[1];
                    for (int k = 0; k < 4; ++k)
                        same = same && std::memcmp(&a.v[k], &b.v[k], sizeof a.v[k]) == 0;
                    differ += !same;
                    stretched += a.coverage[0] == warp::kCoveredStretched;
                    edges += !a.perspective;
                }
                EXPECT_EQ(differ, 0u) << "factor " << factor << " cell " << options.cell;
                total += cpu.size();
            }
    }
    std::printf("grid cells: %zu grown on the GPU as on the CPU, %zu edge cells, %zu stretched\n",
                total, edges, stretched);
    EXPECT_GT(stretched, 0u);  // not vacuous: edge cells and stretched triangles among them
}

// Vertices far away (motion times a huge factor): triangles whose edges span more than 2^19 px,
// where the edge functions need all 64 bits.
TEST(Gpu, GridWarpOfFarAwayVerticesIsTheCpus) {
    warp::GridWarper grid;
    std::size_t covered = 0;
    for (const char* name : {"pan", "crossing", "fast"})
        for (float factor : {3e5f, -2e5f, 5e4f}) {
            SCOPED_TRACE(std::string(name) + " " + std::to_string(factor));
            const Frame& f = scene_frames(name)[1];
            Splatted cpu(kWidth, kHeight), gpu(kWidth, kHeight);
            const warp::GridStats expected = grid.warp(f, factor, cpu.target());
            warp::GridStats stats;
            ASSERT_TRUE(shared_gpu().grid_warp(f, factor, gpu.target(), {}, stats).ok());
            EXPECT_EQ(stats.cells, expected.cells);
            EXPECT_LE(mask_differences(cpu.covered, gpu.covered), cpu.covered.pixel_count() / 1000);
            EXPECT_GE(test::display_psnr(covered_color(cpu), covered_color(gpu)), 50.0);
            covered += expected.covered;
            std::printf("%-10s x%g: %zu cells, covered cpu %zu gpu %zu, masks differ at %zu\n",
                        name, double(factor), expected.cells, expected.covered, stats.covered,
                        mask_differences(cpu.covered, gpu.covered));
        }
    EXPECT_GT(covered, 0u);  // not vacuous: far-away triangles crossed the image
}

// The grid's cells drawn by GL's rasteriser: the CPU's coverage, depth and colour.
TEST(Gpu, GridWarpMatchesTheCpuOnEveryBuiltInScene) {
    const std::size_t allowed = std::size_t(kWidth) * kHeight / 1000;
    warp::GridWarper grid;
    std::size_t exact = 0, compared = 0, stretched = 0;
    for (const server::SceneInfo& info : server::builtin_scenes()) {
        SCOPED_TRACE(info.name);
        const Frame& f = scene_frames(info.name)[1];
        for (bool bicubic : {false, true})
            for (float factor : {-0.5f, 1.0f}) {
                // Two-pixel cells draw stretched triangles (one-pixel ones tear instead).
                const warp::GridOptions options{.min_cell = bicubic ? 1 : 2, .bicubic = bicubic};
                Splatted cpu(kWidth, kHeight), gpu(kWidth, kHeight);
                const warp::GridStats expected = grid.warp(f, factor, cpu.target(), options);
                warp::GridStats stats;
                const Status status =
                    shared_gpu().grid_warp(f, factor, gpu.target(), options, stats);
                ASSERT_TRUE(status.ok()) << status.message();
                EXPECT_EQ(stats.cells, expected.cells);
                EXPECT_GT(expected.covered, std::size_t(kWidth) * kHeight * 8 / 10);
                EXPECT_LE(mask_differences(cpu.covered, gpu.covered), allowed);
                EXPECT_LE(std::max(stats.covered, expected.covered) -
                              std::min(stats.covered, expected.covered),
                          allowed);
                const double db = test::display_psnr(covered_color(cpu), covered_color(gpu));
                EXPECT_GE(db, 50.0) << "bicubic " << bicubic << " factor " << factor;
                std::size_t depth_off = 0, motion_off = 0;
                for (std::size_t i = 0; i < gpu.color.pixel_count(); ++i) {
                    if (!gpu.covered.data()[i] || !cpu.covered.data()[i]) continue;
                    const float a = cpu.depth.data()[i], b = gpu.depth.data()[i];
                    // Edge triangles drawn as slivers have steep planes whose large terms round
                    // apart (the CPU steps along a span, the GPU evaluates each pixel): up to
                    // 4e-4 of the depth on `fast`.
                    depth_off += !(a == b || std::abs(a - b) <= 1e-3f * a);
                    // Where two triangles tie in depth within an ulp the GPU may keep the other
                    // (its depth test compares depth halved): up to 0.02 px apart on `fast`.
                    motion_off += glm::length(cpu.motion.data()[i] - gpu.motion.data()[i]) > 0.05f;
                    ++compared;
                    exact += cpu.color.data()[i] == gpu.color.data()[i] && a == b;
                    stretched += cpu.covered.data()[i] == warp::kCoveredStretched;
                }
                EXPECT_LE(depth_off, allowed);
                EXPECT_LE(motion_off, allowed);
                std::printf(
                    "%-10s grid %s x%+.1f cells %zu covered cpu %zu gpu %zu, masks differ at %zu, "
                    "%.1f dB\n",
                    info.name, bicubic ? "bicubic" : "bilinear", factor, expected.cells,
                    expected.covered, stats.covered, mask_differences(cpu.covered, gpu.covered),
                    db);
            }
    }
    std::printf(
        "grid: %zu of %zu pixels covered on both sides have the CPU's colour and depth "
        "to the bit; %zu stretched\n",
        exact, compared, stretched);
    EXPECT_GT(stretched, 50u);  // not vacuous: stretched triangles were drawn
}

// (The GPU's eye works in linear light: StereoOptions::perceptual is the CPU's alone.)
const stereo::StereoOptions kSplatEye{.warp = stereo::StereoWarp::Splat, .perceptual = false};

TEST(Gpu, StereoEyeMatchesTheCpuOnEveryBuiltInScene) {
    std::size_t holes = 0;
    for (const server::SceneInfo& info : server::builtin_scenes()) {
        SCOPED_TRACE(info.name);
        const Frame& f = scene_frames(info.name)[1];
        const Camera right = stereo::eye_cameras(f.camera, {}, stereo::Anchor::Left).right;
        Frame cpu, gpu;
        const stereo::StereoStats expected = stereo::synthesize_eye(f, right, kSplatEye, cpu);
        stereo::StereoStats stats;
        const Status status = shared_gpu().stereo_eye(f, right, gpu, stats, kSplatEye);
        ASSERT_TRUE(status.ok()) << status.message();
        const std::size_t allowed = cpu.color.pixel_count() / 1000;
        holes += expected.holes;
        EXPECT_LE(std::max(stats.holes, expected.holes) - std::min(stats.holes, expected.holes),
                  allowed);
        EXPECT_EQ(stats.filled + stats.unfilled, stats.holes);
        const double db = test::display_psnr(cpu.color, gpu.color);
        EXPECT_GE(db, 50.0);
        EXPECT_EQ(gpu.camera.view, right.view);
        std::printf("%-10s eye holes cpu %zu gpu %zu, %.1f dB\n", info.name, expected.holes,
                    stats.holes, db);
    }
    EXPECT_GT(holes, 50u);  // not vacuous: pull-push had holes to fill (84 at 96x64)
}

// The default eye (the grid, bicubic, its border strip continued, pull-push) and the bilinear
// grid without a fill.
TEST(Gpu, GridEyeMatchesTheCpuOnEveryBuiltInScene) {
    std::size_t stretched = 0, border = 0;
    struct Setting {
        stereo::StereoOptions options;
        float ipd;
    };
    for (const Setting& setting :
         {Setting{{}, 0.064f}, Setting{{.grid = {.min_cell = 2, .bicubic = true}}, 0.5f},
          Setting{{.fill = stereo::StereoFill::None, .grid = {.bicubic = false}}, 0.064f}})
        for (const server::SceneInfo& info : server::builtin_scenes()) {
            SCOPED_TRACE(info.name);
            const stereo::StereoOptions& options = setting.options;
            const Frame& f = scene_frames(info.name)[1];
            const Camera right =
                stereo::eye_cameras(f.camera, {.ipd = setting.ipd}, stereo::Anchor::Left).right;
            Frame cpu, gpu;
            stereo::StereoOptions on_cpu = options;
            on_cpu.perceptual = false;  // the GPU's eye works in linear light
            const stereo::StereoStats expected = stereo::synthesize_eye(f, right, on_cpu, cpu);
            stereo::StereoStats stats;
            const Status status = shared_gpu().stereo_eye(f, right, gpu, stats, options);
            ASSERT_TRUE(status.ok()) << status.message();
            const std::size_t allowed = cpu.color.pixel_count() / 1000;
            EXPECT_EQ(stats.cells, expected.cells);
            EXPECT_LE(std::max(stats.holes, expected.holes) - std::min(stats.holes, expected.holes),
                      allowed);
            EXPECT_LE(std::max(stats.stretched, expected.stretched) -
                          std::min(stats.stretched, expected.stretched),
                      allowed);
            EXPECT_LE(
                std::max(stats.border, expected.border) - std::min(stats.border, expected.border),
                allowed);
            EXPECT_EQ(stats.filled + stats.unfilled + stats.border,
                      stats.holes + stats.stretched * (options.fill != stereo::StereoFill::None));
            const double db = test::display_psnr(cpu.color, gpu.color);
            EXPECT_GE(db, 50.0);
            stretched += expected.stretched;
            border += expected.border;
            std::printf(
                "%-10s grid eye (%s, ipd %.3f) holes cpu %zu gpu %zu, stretched %zu / %zu, "
                "border %zu / %zu, %.1f dB\n",
                info.name, options.fill == stereo::StereoFill::None ? "no fill" : "default",
                setting.ipd, expected.holes, stats.holes, expected.stretched, stats.stretched,
                expected.border, stats.border, db);
        }
    EXPECT_GT(stretched, 50u);  // not vacuous: stretched pixels and border strips were made
    EXPECT_GT(border, 50u);

    // A skewed projection: the GPU cannot displace, so the cells are grown on the CPU.
    Frame skewed = scene_frames("crossing")[1];
    skewed.camera.projection[1][0] = 0.1f;
    skewed.camera.prev_projection = skewed.camera.projection;
    const Camera right = stereo::eye_cameras(skewed.camera, {}, stereo::Anchor::Left).right;
    Frame cpu, gpu;
    const stereo::StereoStats expected =
        stereo::synthesize_eye(skewed, right, {.perceptual = false}, cpu);
    stereo::StereoStats stats;
    ASSERT_TRUE(shared_gpu().stereo_eye(skewed, right, gpu, stats, {}).ok());
    EXPECT_EQ(stats.cells, expected.cells);
    EXPECT_GT(shared_gpu().timings().cpu_ms, 0.0);
    EXPECT_GE(test::display_psnr(cpu.color, gpu.color), 50.0);
}

// Every source pixel onto one target pixel: more candidates than the shader sorts, taken by the
// rule (nearest depth, closest landing, first in source order), which agrees with the CPU here.
TEST(Gpu, SplatOfTheWholeImageOntoOnePixel) {
    Frame f = scene_frames("crossing")[1];
    for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; ++x) {
            f.motion(x, y) = {float(40 - x), float(30 - y)};
            if (std::isfinite(f.depth(x, y))) f.depth(x, y) = 5.0f;
        }
    Splatted cpu(kWidth, kHeight), gpu(kWidth, kHeight);
    cpu.count = warp::splat(f, 1.0f, cpu.target());
    ASSERT_TRUE(shared_gpu().splat(f, 1.0f, gpu.target(), {}, gpu.count).ok());
    EXPECT_EQ(cpu.count, 1u);
    EXPECT_EQ(gpu.count, 1u);
    EXPECT_EQ(mask_differences(cpu.covered, gpu.covered), 0u);
    EXPECT_EQ(gpu.color(40, 30), cpu.color(40, 30));
    EXPECT_EQ(gpu.depth(40, 30), 5.0f);
}

// warp::widen_silhouettes on textures, bit for bit: NaN, zeros, negatives, infinities, denormals
// and depths from 1e-30 to 1e30 beside each other, odd and one-pixel sizes, with and without
// motion, and a rendered frame.
TEST(Gpu, WidenedSilhouettesAreTheCpusOnExtremeDepths) {
    const float nan = std::numeric_limits<float>::quiet_NaN(), inf = INFINITY;
    const float extremes[] = {nan,    -nan,  0.0f, -0.0f, -1.0f, inf,   -inf,   1e-42f,
                              1e-30f, 1e30f, 1.0f, 0.86f, 0.85f, 1.17f, 3.4e38f};
    std::mt19937 random(7);
    auto frame_of = [&](int w, int h) {
        Frame f;
        f.color.resize(w, h);
        f.depth.resize(w, h);
        f.motion.resize(w, h);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const unsigned pick = random() % 24;
                f.depth(x, y) = pick < std::size(extremes)
                                    ? extremes[pick]
                                    : std::ldexp(1.0f + float(random() % 1000) / 1000.0f,
                                                 int(random() % 8) - 2);
                f.motion(x, y) = {float(int(random() % 200) - 100) / 8.0f,
                                  pick == 3 ? nan : float(y)};
            }
        return f;
    };
    gpu::Context& context = shared_gpu();
    std::size_t widened = 0;
    std::vector<Frame> frames;
    for (const glm::ivec2 size : {glm::ivec2(1, 1), glm::ivec2(1, 7), glm::ivec2(9, 1),
                                  glm::ivec2(37, 23), glm::ivec2(64, 64)})
        frames.push_back(frame_of(size.x, size.y));
    frames.push_back(scene_frames("fence")[1]);
    for (const Frame& f : frames)
        for (const bool moves : {true, false}) {
            const int w = f.width(), h = f.height();
            SCOPED_TRACE(std::to_string(w) + "x" + std::to_string(h) +
                         (moves ? "" : ", no motion"));
            GBufferView view = f.view();
            if (!moves) view.motion = {};
            Image<float> cpu_depth;
            Image<glm::vec2> cpu_motion;
            std::size_t cpu_changed = 0;
            warp::widen_silhouettes(view, cpu_depth, cpu_motion, &cpu_changed);
            context.make_current();
            Textures t;
            gpu::GBufferTextures in = t.gbuffer(f);
            in.width = w, in.height = h;
            if (!moves) in.motion = 0;
            const GLuint depth = t.make(GL_R32F, w, h, GL_RED, GL_FLOAT, nullptr);
            const GLuint motion = t.make(GL_RGBA32F, w, h, GL_RGBA, GL_FLOAT, nullptr);
            std::size_t changed = 0;
            const Status status = context.widen_silhouettes(in, depth, motion, changed);
            ASSERT_TRUE(status.ok()) << status.message();
            EXPECT_EQ(changed, cpu_changed);
            widened += changed;
            const Image<glm::vec4> gpu_depth = read_rgba(depth, w, h);
            const Image<glm::vec4> gpu_motion = read_rgba(motion, w, h);
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    ASSERT_EQ(std::bit_cast<uint32_t>(gpu_depth(x, y).x),
                              std::bit_cast<uint32_t>(cpu_depth(x, y)))
                        << x << "," << y << ": " << f.depth(x, y);
                    if (!moves) continue;
                    for (int k = 0; k < 2; ++k)
                        ASSERT_EQ(std::bit_cast<uint32_t>(gpu_motion(x, y)[k]),
                                  std::bit_cast<uint32_t>(cpu_motion(x, y)[k]))
                            << x << "," << y;
                }
        }
    EXPECT_GT(widened, 1000u);  // not vacuous

    context.make_current();
    Textures t;
    const Frame& f = scene_frames("fence")[1];
    const gpu::GBufferTextures in = t.gbuffer(f);
    std::size_t changed = 0;
    EXPECT_NE(context.widen_silhouettes(in, in.depth, t.rgba(), changed)
                  .message()
                  .find("the output depth is the input depth"),
              std::string::npos);
    EXPECT_NE(
        context.widen_silhouettes(in, t.r32f(), t.r32f(), changed).message().find("output motion"),
        std::string::npos);
}

TEST(Gpu, StereoEyeRepairsNonFiniteInputAsTheCpu) {
    NonfiniteCounts spoiled;
    const std::vector<Frame> frames = test::spoiled_sequence(1, spoiled);
    const Frame& f = frames[0];
    const Camera right = stereo::eye_cameras(f.camera, {}, stereo::Anchor::Left).right;
    Frame cpu, gpu;
    const stereo::StereoStats expected = stereo::synthesize_eye(f, right, kSplatEye, cpu);
    stereo::StereoStats stats;
    ASSERT_TRUE(shared_gpu().stereo_eye(f, right, gpu, stats, kSplatEye).ok());
    EXPECT_GT(stats.nonfinite.total(), 0u);
    EXPECT_EQ(stats.nonfinite.total(), expected.nonfinite.total());
    for (std::size_t i = 0; i < gpu.color.pixel_count(); ++i)
        ASSERT_TRUE(test::finite(gpu.color.data()[i])) << "pixel " << i;
    EXPECT_GE(test::display_psnr(cpu.color, gpu.color), 50.0);
}

TEST(Gpu, StereoEyeOnTexturesAndOptionsTheGpuLacks) {
    const Frame& f = scene_frames("fence")[1];
    const Camera right = stereo::eye_cameras(f.camera, {}, stereo::Anchor::Left).right;
    Frame from_images;
    stereo::StereoStats image_stats, texture_stats;
    gpu::Context& context = shared_gpu();
    // Both entries widen the silhouettes on the GPU.
    const stereo::StereoOptions& splat = kSplatEye;
    ASSERT_TRUE(context.stereo_eye(f, right, from_images, image_stats, splat).ok());
    context.make_current();
    Textures t;
    const gpu::GBufferTextures rendered = t.gbuffer(f);
    const GLuint color = t.color(f);
    const GLuint out = t.rgba();
    const GLuint depth = t.r32f();
    const Status status =
        context.stereo_eye(rendered, color, right, out, depth, texture_stats, splat);
    ASSERT_TRUE(status.ok()) << status.message();
    EXPECT_EQ(texture_stats.holes, image_stats.holes);
    EXPECT_EQ(context.timings().upload_ms, 0.0);
    const Image<glm::vec4> read = read_rgba(out);
    EXPECT_EQ(test::display_psnr(read, from_images.color), INFINITY);

    // The grid eye (its cells grown on the GPU) on textures: the CPU-image entry's eye.
    const stereo::StereoOptions grid;
    ASSERT_TRUE(context.stereo_eye(f, right, from_images, image_stats, grid).ok());
    context.make_current();
    ASSERT_TRUE(context.stereo_eye(rendered, color, right, out, depth, texture_stats, grid).ok());
    EXPECT_EQ(texture_stats.cells, image_stats.cells);
    EXPECT_EQ(texture_stats.border, image_stats.border);
    EXPECT_GT(texture_stats.border, 0u);
    EXPECT_EQ(test::display_psnr(read_rgba(out), from_images.color), INFINITY);

    Frame unused;
    stereo::StereoStats s;
    const Status andreev = context.stereo_eye(
        f, right, unused, s,
        {.warp = stereo::StereoWarp::Splat, .fill = stereo::StereoFill::Andreev});
    EXPECT_NE(andreev.message().find("Andreev"), std::string::npos);
    const Status same_texture =
        context.stereo_eye(rendered, color, right, color, depth, s, kSplatEye);
    EXPECT_NE(same_texture.message().find("the output is the rendered or the history colour"),
              std::string::npos);
}

}  // namespace

namespace {

// Pixels whose depth differs in bits, the largest motion difference and the pixels whose motion
// differs by more than 1e-4 px.
struct Differences {
    std::size_t depth = 0;
    float motion = 0.0f;
    std::size_t motion_pixels = 0;
};
Differences differences(const Frame& cpu, const Frame& gpu) {
    Differences d;
    EXPECT_EQ(gpu.depth.pixel_count(), cpu.depth.pixel_count());
    EXPECT_EQ(gpu.motion.pixel_count(), cpu.motion.pixel_count());
    if (gpu.depth.pixel_count() != cpu.depth.pixel_count() ||
        gpu.motion.pixel_count() != cpu.motion.pixel_count())
        return {.depth = cpu.depth.pixel_count(), .motion = INFINITY};
    for (std::size_t i = 0; i < cpu.depth.pixel_count(); ++i) {
        d.depth += std::memcmp(&cpu.depth.data()[i], &gpu.depth.data()[i], sizeof(float)) != 0;
        const glm::vec2 m = cpu.motion.data()[i] - gpu.motion.data()[i];
        const float worst = std::max(std::abs(m.x), std::abs(m.y));
        d.motion = std::max(d.motion, worst);
        d.motion_pixels += worst > 1e-4f;
    }
    return d;
}

// --- The in-between frame against the CPU converter with the same options.

// (The GPU blends in linear light: FrucOptions::perceptual is the CPU's alone.)
const warp::FrucOptions kSplatInterpolation{.warp = warp::WarpMethod::Splat,
                                            .perceptual = false,
                                            .true_motion = false,
                                            .refine = {.enabled = false}};

// The frame the CPU makes halfway between `a` and `b` with `options` (their silhouettes widened
// on the CPU, as Context::interpolate widens them on the GPU).
Frame cpu_between_with(const Frame& a, const Frame& b, const warp::FrucOptions& options,
                       warp::FrucCounters* counters = nullptr) {
    warp::FrameRateConverter converter;
    EXPECT_TRUE(warp::FrameRateConverter::create(2, options, converter).ok());
    std::vector<Frame> outputs;
    for (const Frame* f : {&a, &b}) {
        EXPECT_TRUE(converter.send(Frame(*f)).ok());
        Frame out;
        while (converter.receive(out)) outputs.push_back(std::move(out));
    }
    EXPECT_EQ(converter.counters().outputs, 1u);
    EXPECT_EQ(outputs.size(), 3u);  // a, the made frame, b
    if (counters) *counters = converter.counters();
    return outputs.size() == 3 ? outputs[1] : Frame{};
}

Frame cpu_between(const Frame& a, const Frame& b, bool true_motion = false,
                  warp::FrucCounters* counters = nullptr,
                  warp::WarpMethod method = warp::WarpMethod::Splat) {
    warp::FrucOptions options = kSplatInterpolation;
    options.true_motion = true_motion;
    options.warp = method;
    return cpu_between_with(a, b, options, counters);
}

// The in-between frame by the grid (refinement off): both sides' cells grown and drawn on the
// GPU, blended with the stretched sides' rule.
TEST(Gpu, GridInterpolationMatchesTheCpuOnEveryBuiltInScene) {
    std::size_t holes = 0, cells = 0;
    for (const server::SceneInfo& info : server::builtin_scenes()) {
        const std::vector<Frame>& frames = scene_frames(info.name);
        for (const int min_cell : {1, 2})
            for (const bool follow : {false, true}) {
                SCOPED_TRACE(std::string(info.name) + ", cells " + std::to_string(min_cell) +
                             (follow ? ", true motion" : ""));
                const warp::FrucOptions options{.warp = warp::WarpMethod::Grid,
                                                .grid = {.min_cell = min_cell, .bicubic = true},
                                                .perceptual = false,
                                                .true_motion = follow,
                                                .refine = {.enabled = false}};
                warp::FrucCounters counters;
                const Frame cpu = cpu_between_with(frames[0], frames[1], options, &counters);
                Frame gpu;
                gpu::InterpolateStats stats;
                ASSERT_TRUE(shared_gpu()
                                .interpolate(frames[0], frames[1], 0.5f, gpu, stats,
                                             {.grid = true,
                                              .grid_options = options.grid,
                                              .true_motion = follow,
                                              .motion_scale = 0.5f})
                                .ok());
                if (counters.copied_still == 0)  // both sides' cells, as the CPU counts them
                    EXPECT_EQ(stats.grid_cells, counters.grid_cells);
                cells += stats.grid_cells;
                const double db = test::display_psnr(cpu.color, gpu.color);
                EXPECT_GE(db, 50.0);
                std::size_t motion_off = 0;
                for (std::size_t i = 0; i < cpu.motion.pixel_count(); ++i)
                    motion_off += glm::length(cpu.motion.data()[i] - gpu.motion.data()[i]) > 0.05f;
                EXPECT_LE(motion_off, cpu.motion.pixel_count() / 1000);
                holes += stats.holes;
                std::printf("%-10s between by the grid (%d-px cells%s): holes %zu, %.1f dB\n",
                            info.name, min_cell, stats.true_motion ? ", true motion" : "",
                            stats.holes, db);
            }
    }
    EXPECT_GT(holes, 0u);  // not vacuous: some holes filled
    EXPECT_GT(cells, 0u);
}

// The default in-between frame (the grid, true motion, refinement): the survey, the crops, the
// flow's evaluation and the choice on the GPU, the flow on the CPU from the GPU's crops.
TEST(Gpu, RefinedInterpolationMatchesTheCpuOnEveryBuiltInScene) {
    std::size_t refined = 0, skipped = 0;
    for (const server::SceneInfo& info : server::builtin_scenes()) {
        const std::vector<Frame>& frames = scene_frames(info.name);
        // The defaults, and a survey that flags more (smaller tiles, a lower threshold).
        for (const bool eager : {false, true}) {
            SCOPED_TRACE(std::string(info.name) + (eager ? ", eager" : ""));
            warp::FrucOptions options;
            options.perceptual = false;
            if (eager) options.refine = {.tile = 8, .threshold = 0.02f};
            warp::FrucCounters counters;
            const Frame cpu = cpu_between_with(frames[0], frames[1], options, &counters);
            if (counters.copied_still) continue;  // a still pair whose pictures agree: copied
            Frame gpu;
            gpu::InterpolateStats stats;
            const Status status =
                shared_gpu().interpolate(frames[0], frames[1], 0.5f, gpu, stats,
                                         {.grid = options.warp == warp::WarpMethod::Grid,
                                          .grid_options = options.grid,
                                          .true_motion = options.true_motion,
                                          .static_tolerance = options.static_tolerance,
                                          .motion_scale = 0.5f,
                                          .refine = options.refine});
            ASSERT_TRUE(status.ok()) << status.message();
            // The survey's threshold may flip a tile where a GPU's sqrt rounds otherwise.
            EXPECT_EQ(std::size_t(stats.refine_skipped), counters.refine_skipped);
            EXPECT_LE(std::max(stats.refine_tiles, counters.refine_tiles) -
                          std::min(stats.refine_tiles, counters.refine_tiles),
                      1u);
            if (stats.refine_tiles == counters.refine_tiles)
                EXPECT_EQ(stats.flow_pixels, counters.flow_pixels);
            const std::size_t pixels = cpu.color.pixel_count();
            const std::size_t apart = stats.refined_pixels > counters.refined_pixels
                                          ? stats.refined_pixels - counters.refined_pixels
                                          : counters.refined_pixels - stats.refined_pixels;
            EXPECT_LE(apart, pixels / 1000);
            const double db = test::display_psnr(cpu.color, gpu.color);
            EXPECT_GE(db, 50.0);
            refined += stats.refined_pixels;
            skipped += stats.refine_skipped;
            std::printf(
                "%-10s refined%s: tiles %zu, flow over %zu px, refined CPU %zu GPU %zu, "
                "%.1f dB\n",
                info.name, eager ? " (eager)" : "", stats.refine_tiles, stats.flow_pixels,
                counters.refined_pixels, stats.refined_pixels, db);
        }
    }
    EXPECT_GT(refined, 0u);  // not vacuous: some pixels took the flow's colour
    EXPECT_GT(skipped, 0u);  // ... and some frames needed no flow
}

TEST(Gpu, InterpolationMatchesTheCpuOnEveryBuiltInScene) {
    std::size_t holes = 0, true_motion = 0, widened = 0;
    for (const server::SceneInfo& info : server::builtin_scenes()) {
        const std::vector<Frame>& frames = scene_frames(info.name);
        for (const bool reverse : {false, true}) {
            for (const bool follow : {false, true}) {
                SCOPED_TRACE(std::string(info.name) + (reverse ? ", reverse" : "") +
                             (follow ? ", true motion" : ""));
                warp::FrucCounters counters;
                const Frame cpu =
                    cpu_between(frames[0], frames[1], follow, &counters,
                                reverse ? warp::WarpMethod::Reverse : warp::WarpMethod::Splat);
                Frame gpu;
                gpu::InterpolateStats stats;
                const Status status = shared_gpu().interpolate(
                    frames[0], frames[1], 0.5f, gpu, stats,
                    {.reverse = reverse, .true_motion = follow, .motion_scale = 0.5f});
                ASSERT_TRUE(status.ok()) << status.message();
                if (counters.copied_still == 0) {  // (shadows: a still pair, the CPU copies it)
                    EXPECT_EQ(stats.border, counters.border_pixels);
                    EXPECT_EQ(stats.silhouette_a + stats.silhouette_b, counters.silhouette_pixels);
                    widened += stats.silhouette_a + stats.silhouette_b;
                    EXPECT_EQ(std::size_t(stats.true_motion), counters.true_motion);
                    EXPECT_EQ(std::size_t(stats.linear_motion), counters.linear_motion);
                }
                true_motion += stats.true_motion;
                const double db = test::display_psnr(cpu.color, gpu.color);
                EXPECT_GE(db, 50.0);
                // Motion as the CPU's but where its SIMD blend rounds the same-surface test
                // otherwise.
                const Differences d = differences(cpu, gpu);
                EXPECT_LE(d.motion_pixels, cpu.motion.pixel_count() / 1000);
                holes += stats.holes;
                std::printf(
                    "%-10s between%s%s: covered a %zu b %zu, holes %zu, %.1f dB, motion "
                    "of %zu pixels differs (at most %g px)\n",
                    info.name, reverse ? " reverse" : "", stats.true_motion ? " (true motion)" : "",
                    stats.covered_a, stats.covered_b, stats.holes, db, d.motion_pixels,
                    double(d.motion));
            }
        }
    }
    EXPECT_GT(holes, 0u);        // not vacuous: some holes filled
    EXPECT_GT(true_motion, 0u);  // ... and some pairs followed their true motion
    EXPECT_GT(widened, 0u);      // ... and some silhouettes widened on the GPU
}

TEST(Gpu, InterpolationRepairsNonFiniteInputAsTheCpu) {
    NonfiniteCounts spoiled;
    const std::vector<Frame> frames = test::spoiled_sequence(2, spoiled);
    const Frame cpu = cpu_between(frames[0], frames[1]);
    Frame gpu;
    gpu::InterpolateStats stats;
    ASSERT_TRUE(shared_gpu().interpolate(frames[0], frames[1], 0.5f, gpu, stats).ok());
    EXPECT_GT(spoiled.total(), 0u);
    EXPECT_EQ(stats.nonfinite.total(), spoiled.total());
    for (std::size_t i = 0; i < gpu.color.pixel_count(); ++i)
        ASSERT_TRUE(test::finite(gpu.color.data()[i])) << "pixel " << i;
    EXPECT_GE(test::display_psnr(cpu.color, gpu.color), 50.0);
}

// Every output of a converter at `factor` over `frames`, and its counters.
std::vector<Frame> convert(const std::vector<Frame>& frames, int factor,
                           const warp::FrucOptions& options, warp::FrucCounters& counters) {
    warp::FrameRateConverter converter;
    const Status made = warp::FrameRateConverter::create(factor, options, converter);
    EXPECT_TRUE(made.ok()) << made.message();
    std::vector<Frame> outputs;
    for (const Frame& f : frames) {
        const Status sent = converter.send(f);
        EXPECT_TRUE(sent.ok()) << sent.message();
        Frame out;
        while (converter.receive(out)) outputs.push_back(std::move(out));
    }
    counters = converter.counters();
    return outputs;
}

// The converter with the GPU making its in-between frames: the CPU's frames at factor 3 (s = 1/3,
// 2/3), inputs passed through, a cut continued from the old shot on the CPU as before.
TEST(Gpu, TheConverterWithTheGpuBackendMakesTheCpusFrames) {
    std::vector<Frame> frames = test::render_scene("crossing", 4, kWidth, kHeight, 30.0, 3);
    frames[3].camera.cut = Cut::Yes;
    gpu::FrucBackend backend(shared_gpu());
    warp::FrucOptions with_gpu = kSplatInterpolation;
    with_gpu.backend = &backend;
    warp::FrucCounters cpu_counters, gpu_counters;
    const std::vector<Frame> cpu = convert(frames, 3, kSplatInterpolation, cpu_counters);
    const std::vector<Frame> gpu = convert(frames, 3, with_gpu, gpu_counters);
    ASSERT_EQ(cpu.size(), 10u);  // 4 inputs, 2 frames after each of the first 3
    ASSERT_EQ(gpu.size(), cpu.size());
    for (std::size_t i = 0; i < cpu.size(); ++i) {
        SCOPED_TRACE("output " + std::to_string(i));
        EXPECT_GE(test::display_psnr(cpu[i].color, gpu[i].color), 50.0);
        EXPECT_EQ(gpu[i].camera.view, cpu[i].camera.view);
    }
    EXPECT_EQ(backend.frames(), 6u);  // the pairs 0-1 and 1-2, and the cut's two extrapolated
    // Inputs uploaded once: a pair's second frame keeps both (2 + 2), pair 1-2 takes 1 from 0-1's
    // b (1), the cut's second extrapolated frame keeps the first's upload (1).
    EXPECT_EQ(backend.uploads_kept(), 6u);
    EXPECT_LE(differences(cpu[1], gpu[1]).motion_pixels,
              cpu[1].motion.pixel_count() / 1000);  // per output period, as the CPU's
    EXPECT_EQ(gpu_counters.cuts, 1u);
    EXPECT_EQ(gpu_counters.hole_pixels, cpu_counters.hole_pixels);
    // Widened on the GPU once per upload, as the CPU widens once per input.
    EXPECT_EQ(gpu_counters.silhouette_pixels, cpu_counters.silhouette_pixels);
    EXPECT_EQ(gpu_counters.fills + gpu_counters.fills_skipped,
              cpu_counters.fills + cpu_counters.fills_skipped);

    // The defaults (the grid with refinement): the CPU's frames, refinement counted alike.
    warp::FrucOptions defaults, defaults_on_gpu;
    defaults.perceptual = false;
    defaults_on_gpu.backend = &backend;
    const std::vector<Frame> cpu_defaults = convert(frames, 3, defaults, cpu_counters);
    const std::vector<Frame> gpu_defaults = convert(frames, 3, defaults_on_gpu, gpu_counters);
    ASSERT_EQ(gpu_defaults.size(), cpu_defaults.size());
    for (std::size_t i = 0; i < cpu_defaults.size(); ++i)
        EXPECT_GE(test::display_psnr(cpu_defaults[i].color, gpu_defaults[i].color), 50.0) << i;
    EXPECT_EQ(gpu_counters.refined_frames + gpu_counters.refine_skipped,
              cpu_counters.refined_frames + cpu_counters.refine_skipped);
    EXPECT_EQ(gpu_counters.grid_cells, cpu_counters.grid_cells);  // the backend adds them up
    EXPECT_GT(cpu_counters.grid_cells, 0u);
    // Within 0.1 % of the pixels: llvmpipe's are the CPU's; a GPU's sqrt and division need not
    // round as the CPU's, and a grey one step off changes the flow a little.
    EXPECT_EQ(gpu_counters.refined_frames, cpu_counters.refined_frames);
    EXPECT_LE(std::max(gpu_counters.refined_pixels, cpu_counters.refined_pixels) -
                  std::min(gpu_counters.refined_pixels, cpu_counters.refined_pixels),
              frames[0].color.pixel_count() / 1000);
    // Andreev's fill: refused, named.
    defaults_on_gpu.fill = warp::FillMethod::Andreev;
    warp::FrameRateConverter refused;
    const Status status = warp::FrameRateConverter::create(2, defaults_on_gpu, refused);
    EXPECT_NE(status.message().find("fill pullpush only"), std::string::npos) << status.message();
}

// After a cut the converter makes the next frame on the CPU (from the new shot's first frame,
// widened there); the GPU then uploads that frame as its next pair's a: its widened pixels are
// counted once, as the CPU converter counts them.
TEST(Gpu, EachInputsWidenedPixelsAreCountedOnceAcrossACut) {
    std::vector<Frame> frames = test::render_scene("crossing", 5, kWidth, kHeight, 30.0, 3);
    frames[2].camera.cut = Cut::Yes;
    gpu::FrucBackend backend(shared_gpu());
    // (The converter with a backend works in linear light, the cut's frame on the CPU too.)
    const warp::FrucOptions cpu_options{
        .warp = warp::WarpMethod::Splat, .perceptual = false, .refine = {.enabled = false}};
    warp::FrucOptions gpu_options = cpu_options;
    gpu_options.perceptual = true;
    gpu_options.backend = &backend;
    warp::FrucCounters cpu_counters, gpu_counters;
    const std::vector<Frame> cpu = convert(frames, 2, cpu_options, cpu_counters);
    const std::vector<Frame> gpu = convert(frames, 2, gpu_options, gpu_counters);
    ASSERT_EQ(gpu.size(), cpu.size());
    EXPECT_EQ(gpu_counters.cuts, 1u);
    EXPECT_EQ(backend.frames(), 3u);  // pairs 0-1, 2-3 and 3-4; the cut's frame on the CPU
    EXPECT_GT(cpu_counters.silhouette_pixels, 0u);
    EXPECT_EQ(gpu_counters.silhouette_pixels, cpu_counters.silhouette_pixels);
    for (std::size_t i = 0; i < cpu.size(); ++i)
        EXPECT_GE(test::display_psnr(cpu[i].color, gpu[i].color), 50.0) << i;
}

// A context serves one thread at a time: another thread gets an error, not a crash.
TEST(Gpu, AnotherThreadGetsAnErrorWhileTheContextIsHeld) {
    const std::vector<Frame>& frames = scene_frames("crossing");
    gpu::Context& context = shared_gpu();
    Frame out;
    gpu::InterpolateStats stats;
    ASSERT_TRUE(context.interpolate(frames[0], frames[1], 0.5f, out, stats).ok());
    Status elsewhere;
    std::thread([&] {
        elsewhere = context.interpolate(frames[0], frames[1], 0.5f, out, stats);
    }).join();
    EXPECT_NE(elsewhere.message().find("another thread holds it"), std::string::npos)
        << elsewhere.message();
    EXPECT_TRUE(context.interpolate(frames[0], frames[1], 0.5f, out, stats).ok());
}

TEST(Gpu, InterpolationOnTexturesAndBadArguments) {
    const std::vector<Frame>& frames = scene_frames("crossing");
    gpu::Context& context = shared_gpu();
    Frame from_images;
    gpu::InterpolateStats image_stats, texture_stats;
    ASSERT_TRUE(context.interpolate(frames[0], frames[1], 0.25f, from_images, image_stats).ok());
    context.make_current();
    Textures t;
    const gpu::GBufferTextures a = t.gbuffer(frames[0]), b = t.gbuffer(frames[1]);
    const GLuint a_color = t.color(frames[0]);
    const GLuint b_color = t.color(frames[1]);
    const GLuint out = t.rgba();
    const GLuint depth = t.r32f();
    const Status status =
        context.interpolate(a, a_color, b, b_color, 0.25f, out, depth, texture_stats);
    ASSERT_TRUE(status.ok()) << status.message();
    EXPECT_EQ(texture_stats.holes, image_stats.holes);
    const Image<glm::vec4> read = read_rgba(out);
    EXPECT_EQ(test::display_psnr(read, from_images.color), INFINITY);

    EXPECT_NE(context.interpolate(a, a_color, b, b_color, 0.5f, a_color, depth, texture_stats)
                  .message()
                  .find("the output is an input colour"),
              std::string::npos);
    Frame unused;
    EXPECT_NE(context.interpolate(frames[0], frames[1], 1.5f, unused, texture_stats)
                  .message()
                  .find("s must lie in [0, 1]"),
              std::string::npos);
}

// Refinement on textures: the same survey, flow and choices as from CPU images (mirror's
// reflection moves against its surface: 874 pixels take the flow's colour at 96x64).
TEST(Gpu, RefinementOnTexturesIsTheImageEntrys) {
    const std::vector<Frame>& frames = scene_frames("mirror");
    gpu::Context& context = shared_gpu();
    const gpu::InterpolateOptions options{.grid = true, .refine = {}};
    Frame from_images;
    gpu::InterpolateStats image_stats, texture_stats;
    ASSERT_TRUE(
        context.interpolate(frames[0], frames[1], 0.5f, from_images, image_stats, options).ok());
    EXPECT_GT(image_stats.refined_pixels, 0u);
    context.make_current();
    Textures t;
    const gpu::GBufferTextures a = t.gbuffer(frames[0]), b = t.gbuffer(frames[1]);
    const GLuint a_color = t.color(frames[0]), b_color = t.color(frames[1]);
    const GLuint out = t.rgba(), depth = t.r32f();
    const Status status =
        context.interpolate(a, a_color, b, b_color, 0.5f, out, depth, texture_stats, options);
    ASSERT_TRUE(status.ok()) << status.message();
    EXPECT_EQ(texture_stats.refine_tiles, image_stats.refine_tiles);
    EXPECT_EQ(texture_stats.refined_pixels, image_stats.refined_pixels);
    EXPECT_EQ(test::display_psnr(read_rgba(out), from_images.color), INFINITY);
    EXPECT_GT(context.timings().cpu_ms, 0.0);  // the flow's, on the CPU
}

// True motion on textures: the linearity survey reads back the sampled pixels alone and decides
// as on CPU images (crossing's cars move: true motion; pan's camera alone: linear).
TEST(Gpu, TrueMotionOnTexturesDecidesAndWarpsAsTheImageEntry) {
    gpu::Context& context = shared_gpu();
    for (const char* scene : {"crossing", "pan"}) {
        SCOPED_TRACE(scene);
        const std::vector<Frame>& frames = scene_frames(scene);
        const gpu::InterpolateOptions options{.true_motion = true, .motion_scale = 0.5f};
        Frame from_images;
        gpu::InterpolateStats image_stats, texture_stats;
        ASSERT_TRUE(
            context.interpolate(frames[0], frames[1], 0.5f, from_images, image_stats, options)
                .ok());
        EXPECT_EQ(image_stats.true_motion, std::string(scene) == "crossing");
        EXPECT_EQ(image_stats.linear_motion, std::string(scene) == "pan");
        context.make_current();
        Textures t;
        const gpu::GBufferTextures a = t.gbuffer(frames[0]), b = t.gbuffer(frames[1]);
        const GLuint a_color = t.color(frames[0]);
        const GLuint b_color = t.color(frames[1]);
        const GLuint out = t.rgba();
        const GLuint depth = t.r32f();
        const GLuint motion = t.rgba();
        const Status status = context.interpolate(a, a_color, b, b_color, 0.5f, out, depth,
                                                  texture_stats, options, motion);
        ASSERT_TRUE(status.ok()) << status.message();
        EXPECT_EQ(texture_stats.true_motion, image_stats.true_motion);
        EXPECT_EQ(texture_stats.linear_motion, image_stats.linear_motion);
        EXPECT_EQ(texture_stats.holes, image_stats.holes);
        EXPECT_EQ(test::display_psnr(read_rgba(out), from_images.color), INFINITY);
        const Image<glm::vec4> read_motion = read_rgba(motion);
        std::size_t differ = 0;
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x)
                differ += glm::vec2(read_motion(x, y)) != from_images.motion(x, y);
        EXPECT_EQ(differ, 0u);
    }
}

TEST(Gpu, LinearitySurveyOfSamplesIsTheSurveyOfTheFrame) {
    for (const char* scene : {"crossing", "pan", "fast"}) {
        const Frame& f = scene_frames(scene)[1];
        const Camera to = warp::camera_between(scene_frames(scene)[0].camera, f.camera, 0.5f);
        const int cw = warp::linear_survey_samples(kWidth),
                  ch = warp::linear_survey_samples(kHeight);
        Image<glm::vec4> samples(cw, ch);
        for (int j = 0; j < ch; ++j)
            for (int i = 0; i < cw; ++i) {
                const int x = 4 + 8 * i, y = 4 + 8 * j;
                samples(i, j) = {f.depth(x, y), f.motion(x, y), 0.0f};
            }
        for (const float tolerance : {0.25f, 1e-6f, 100.0f})
            EXPECT_EQ(warp::motion_is_linear(f.camera, kWidth, kHeight,
                                             std::as_const(samples).view(), to, 0.5f, tolerance),
                      warp::motion_is_linear(f.view(), to, 0.5f, tolerance))
                << scene << " " << tolerance;
    }
    EXPECT_EQ(warp::linear_survey_samples(4), 0);
    EXPECT_EQ(warp::linear_survey_samples(5), 1);
    EXPECT_EQ(warp::linear_survey_samples(13), 2);
    EXPECT_EQ(warp::linear_survey_samples(0), 0);
}

// --- Extrapolation against warp::PoseExtrapolator and the converter with the same options.

const warp::FrucOptions kSplatExtrapolation{
    .mode = warp::FrucMode::Extrapolate, .warp = warp::WarpMethod::Splat, .perceptual = false};

// `frame` seen by the next frame's camera `periods` on, on the CPU and on the GPU: colour within
// 50 dB, depth in bits on all but 0.1 % of the pixels, motion within 1e-4 px.
// The CPU gets `frame` with its NaN/Inf repaired (the converter repairs, PoseExtrapolator does
// not).
void expect_extrapolation_matches(const Frame& frame, const Camera& to, float periods,
                                  gpu::ExtrapolateStats& stats,
                                  warp::WarpMethod method = warp::WarpMethod::Splat) {
    warp::FrucOptions options = kSplatExtrapolation;
    options.warp = method;
    warp::PoseExtrapolator extrapolator(options);
    Frame cpu, gpu;
    NonfiniteRepair repair;
    NonfiniteCounts found;
    const GBufferView repaired = repair.clean(frame, found);
    ASSERT_TRUE(extrapolator.extrapolate(repaired, to.view, to.projection, periods, cpu).ok());
    const Status status =
        shared_gpu().extrapolate(frame, to.view, to.projection, periods, gpu, stats, options);
    ASSERT_TRUE(status.ok()) << status.message();
    ASSERT_EQ(gpu.motion.width(), cpu.motion.width());
    const double db = test::display_psnr(cpu.color, gpu.color);
    EXPECT_GE(db, 50.0);
    const Differences d = differences(cpu, gpu);
    const std::size_t allowed = cpu.depth.pixel_count() / 1000;
    if (method == warp::WarpMethod::Grid) {
        // The grid's planes are evaluated per pixel on the GPU and stepped along a span on the
        // CPU: depth within 1e-3 of itself and motion within 0.05 px (GridWarpMatchesTheCpu...).
        std::size_t depth_off = 0, motion_off = 0;
        for (std::size_t i = 0; i < cpu.depth.pixel_count(); ++i) {
            const float a = cpu.depth.data()[i], b = gpu.depth.data()[i];
            depth_off += !(a == b || std::abs(a - b) <= 1e-3f * a);
            motion_off += glm::length(cpu.motion.data()[i] - gpu.motion.data()[i]) > 0.05f;
        }
        EXPECT_LE(depth_off, allowed);
        EXPECT_LE(motion_off, allowed);
        EXPECT_LE(std::max(stats.holes, extrapolator.counters().hole_pixels) -
                      std::min(stats.holes, extrapolator.counters().hole_pixels),
                  allowed);
        EXPECT_LE(std::max(stats.border, extrapolator.counters().border_pixels) -
                      std::min(stats.border, extrapolator.counters().border_pixels),
                  allowed);
        EXPECT_EQ(stats.grid_cells, extrapolator.counters().grid_cells);
        EXPECT_GT(stats.grid_cells, 0u);
    } else {
        EXPECT_LE(d.depth, allowed);
        EXPECT_LE(d.motion, 1e-4f);
        EXPECT_EQ(stats.holes, extrapolator.counters().hole_pixels);
        EXPECT_EQ(stats.border, extrapolator.counters().border_pixels);
    }
    if (has_projection(frame.camera)) {
        EXPECT_EQ(stats.moving > 0, extrapolator.counters().dynamic_layers == 1);
    }
    EXPECT_EQ(stats.silhouette_pixels, extrapolator.counters().silhouette_pixels);
    std::printf(
        "  %.2f periods on: moving %zu, covered %zu, border %zu, holes %zu, %.1f dB, depth %zu "
        "differ, motion within %g\n",
        periods, stats.moving, stats.covered, stats.border, stats.holes, db, d.depth,
        double(d.motion));
}

TEST(Gpu, ExtrapolationMatchesTheCpuOnEveryBuiltInScene) {
    std::size_t moving = 0, holes = 0, grid_holes = 0, border = 0;
    for (const server::SceneInfo& info : server::builtin_scenes()) {
        SCOPED_TRACE(info.name);
        std::printf("%s\n", info.name);
        const std::vector<Frame>& frames = scene_frames(info.name);
        for (float periods : {0.5f, 1.0f}) {
            gpu::ExtrapolateStats stats;
            expect_extrapolation_matches(frames[0], frames[1].camera, periods, stats);
            expect_extrapolation_matches(frames[0], frames[1].camera, periods, stats,
                                         warp::WarpMethod::Reverse);
            moving += stats.moving;
            holes += stats.holes;
            border += stats.border;
            expect_extrapolation_matches(frames[0], frames[1].camera, periods, stats,
                                         warp::WarpMethod::Grid);
            grid_holes += stats.holes;
        }
    }
    EXPECT_GT(moving, 0u);  // not vacuous: objects moved on their own and holes were filled
    EXPECT_GT(holes, 0u);
    EXPECT_GT(grid_holes, 0u);
    EXPECT_GT(border, 0u);  // ... and border strips continued
}

TEST(Gpu, ExtrapolationWithoutACameraAndOnNonFiniteInput) {
    // Without a projection every pixel goes along its own motion.
    Frame cameraless = scene_frames("crossing")[0];
    cameraless.camera = Camera{};
    gpu::ExtrapolateStats stats;
    for (warp::WarpMethod method : {warp::WarpMethod::Splat, warp::WarpMethod::Grid}) {
        expect_extrapolation_matches(cameraless, scene_frames("crossing")[1].camera, 1.0f, stats,
                                     method);
        EXPECT_EQ(stats.moving, cameraless.color.pixel_count());
    }

    NonfiniteCounts spoiled;
    const std::vector<Frame> frames = test::spoiled_sequence(2, spoiled);
    for (warp::WarpMethod method : {warp::WarpMethod::Splat, warp::WarpMethod::Grid}) {
        expect_extrapolation_matches(frames[1], frames[0].camera, 1.0f, stats, method);
        EXPECT_GT(stats.nonfinite.total(), 0u);
        EXPECT_GT(stats.holes, 0u);
    }
}

// A frame extrapolated again under the same key is not uploaded again; the frame is the same.
TEST(Gpu, ExtrapolationKeepsTheUploadOfTheSameFrameKey) {
    NonfiniteCounts spoiled;
    const std::vector<Frame> frames = test::spoiled_sequence(2, spoiled);
    const Camera& to = frames[0].camera;
    gpu::Context& context = shared_gpu();
    Frame fresh, again, other;
    gpu::ExtrapolateStats first, second, third;
    ASSERT_TRUE(context
                    .extrapolate(frames[1], to.view, to.projection, 0.5f, fresh, first,
                                 kSplatExtrapolation, 1.0f, 41)
                    .ok());
    EXPECT_FALSE(first.upload_kept);
    ASSERT_TRUE(context
                    .extrapolate(frames[1], to.view, to.projection, 1.0f, again, second,
                                 kSplatExtrapolation, 1.0f, 41)
                    .ok());
    EXPECT_TRUE(second.upload_kept);
    EXPECT_EQ(second.nonfinite.total(), first.nonfinite.total());
    EXPECT_GT(second.nonfinite.total(), 0u);
    Frame keyless;
    gpu::ExtrapolateStats keyless_stats;
    ASSERT_TRUE(context
                    .extrapolate(frames[1], to.view, to.projection, 1.0f, keyless, keyless_stats,
                                 kSplatExtrapolation)
                    .ok());
    EXPECT_FALSE(keyless_stats.upload_kept);
    EXPECT_EQ(test::display_psnr(again.color, keyless.color), INFINITY);
    EXPECT_EQ(differences(again, keyless).motion, 0.0f);
    // A keyless call in between replaced the upload: key 41 is uploaded again.
    ASSERT_TRUE(context
                    .extrapolate(frames[1], to.view, to.projection, 1.0f, other, third,
                                 kSplatExtrapolation, 1.0f, 41)
                    .ok());
    EXPECT_FALSE(third.upload_kept);
}

// Left on the GPU: the textures hold the frame the CPU-image entry downloads; the backend kept
// that way empties its output; any other call ends what made() names.
TEST(Gpu, ExtrapolationKeptOnTheGpuIsTheFrameDownloaded) {
    NonfiniteCounts spoiled;
    const std::vector<Frame> frames = test::spoiled_sequence(2, spoiled);
    const Camera& to = frames[0].camera;
    gpu::Context& context = shared_gpu();
    Frame downloaded;
    gpu::ExtrapolateStats stats;
    ASSERT_TRUE(context
                    .extrapolate(frames[1], to.view, to.projection, 0.75f, downloaded, stats,
                                 kSplatExtrapolation)
                    .ok());
    EXPECT_GT(stats.covered, 0u);
    ASSERT_TRUE(context
                    .extrapolate_on_gpu(frames[1], to.view, to.projection, 0.75f, stats,
                                        kSplatExtrapolation)
                    .ok());
    context.make_current();
    const gpu::MadeTextures made = context.made();
    ASSERT_NE(made.color, 0u);
    const int w = frames[1].width(), h = frames[1].height();
    EXPECT_EQ(made.width, w);
    EXPECT_EQ(made.height, h);
    EXPECT_EQ(test::display_psnr(downloaded.color, read_rgba(made.color, w, h)), INFINITY);
    const Image<glm::vec4> depth = read_rgba(made.depth, w, h);
    const Image<glm::vec4> motion = read_rgba(made.motion, w, h);
    int depth_differs = 0, motion_differs = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            depth_differs += std::bit_cast<uint32_t>(depth(x, y).r) !=
                             std::bit_cast<uint32_t>(downloaded.depth(x, y));
            motion_differs += glm::vec2(motion(x, y)) != downloaded.motion(x, y);
        }
    EXPECT_EQ(depth_differs, 0);
    EXPECT_EQ(motion_differs, 0);

    gpu::FrucBackend backend(context);
    backend.keep_extrapolated_on_gpu(true);
    Frame out = frames[0];
    warp::FrucCounters counters;
    ASSERT_TRUE(backend
                    .extrapolate(frames[1], to.view, to.projection, 0.75f, 1.0f,
                                 kSplatExtrapolation, out, counters, 0)
                    .ok());
    EXPECT_TRUE(out.color.empty() && out.depth.empty() && out.motion.empty());
    EXPECT_EQ(test::display_psnr(downloaded.color, read_rgba(backend.made().color, w, h)),
              INFINITY);
    Image<glm::vec4> color = downloaded.color;
    Image<uint8_t> valid(w, h);
    std::fill(valid.data(), valid.data() + valid.pixel_count(), uint8_t(1));
    valid(3, 4) = 0;
    warp::FillStats filled;
    ASSERT_TRUE(context.fill(color.view(), valid.view(), {}, filled).ok());
    EXPECT_EQ(filled.holes, 1u);
    EXPECT_EQ(backend.made().color, 0u);
    // A call that fails names nothing either.
    ASSERT_TRUE(context
                    .extrapolate_on_gpu(frames[1], to.view, to.projection, 0.75f, stats,
                                        kSplatExtrapolation)
                    .ok());
    EXPECT_NE(context.made().color, 0u);
    EXPECT_FALSE(context
                     .extrapolate_on_gpu(frames[1], to.view, to.projection, -1.0f, stats,
                                         kSplatExtrapolation)
                     .ok());
    EXPECT_EQ(context.made().color, 0u);
}

// The converter extrapolating at factor 3 through a cut: the CPU's frames, made on the GPU.
TEST(Gpu, TheExtrapolatingConverterWithTheGpuBackendMakesTheCpusFrames) {
    std::vector<Frame> frames = test::render_scene("crossing", 3, kWidth, kHeight, 30.0, 3);
    frames[2].camera.cut = Cut::Yes;
    const warp::FrucOptions& cpu_options = kSplatExtrapolation;
    gpu::FrucBackend backend(shared_gpu());
    warp::FrucOptions gpu_options = cpu_options;
    gpu_options.backend = &backend;
    warp::FrucCounters cpu_counters, gpu_counters;
    const std::vector<Frame> cpu = convert(frames, 3, cpu_options, cpu_counters);
    const std::vector<Frame> gpu = convert(frames, 3, gpu_options, gpu_counters);
    ASSERT_EQ(cpu.size(), 9u);  // each input and two frames beyond it
    ASSERT_EQ(gpu.size(), cpu.size());
    for (std::size_t i = 0; i < cpu.size(); ++i) {
        SCOPED_TRACE("output " + std::to_string(i));
        EXPECT_GE(test::display_psnr(cpu[i].color, gpu[i].color), 50.0);
        EXPECT_LE(differences(cpu[i], gpu[i]).motion, 1e-4f);
        EXPECT_EQ(gpu[i].camera.view, cpu[i].camera.view);
    }
    EXPECT_EQ(backend.frames(), 4u);        // the cut's two are copies
    EXPECT_EQ(backend.uploads_kept(), 2u);  // each input's second frame warps its first upload
    EXPECT_EQ(gpu_counters.hole_pixels, cpu_counters.hole_pixels);
    EXPECT_EQ(gpu_counters.silhouette_pixels, cpu_counters.silhouette_pixels);
    EXPECT_GT(gpu_counters.silhouette_pixels, 0u);
    EXPECT_EQ(gpu_counters.dynamic_layers, cpu_counters.dynamic_layers);
    EXPECT_EQ(gpu_counters.fills, cpu_counters.fills);

    warp::FrucOptions andreev = gpu_options;
    andreev.fill = warp::FillMethod::Andreev;
    warp::FrameRateConverter refused;
    const Status status = warp::FrameRateConverter::create(2, andreev, refused);
    EXPECT_NE(status.message().find("extrapolated frames with fill pullpush or none"),
              std::string::npos)
        << status.message();
}

TEST(Gpu, ExtrapolationOnTexturesAndBadArguments) {
    const std::vector<Frame>& frames = scene_frames("crossing");
    const Camera& to = frames[1].camera;
    gpu::Context& context = shared_gpu();
    Frame from_images;
    gpu::ExtrapolateStats image_stats, texture_stats;
    ASSERT_TRUE(context
                    .extrapolate(frames[0], to.view, to.projection, 1.0f, from_images, image_stats,
                                 kSplatExtrapolation)
                    .ok());
    context.make_current();
    Textures t;
    const gpu::GBufferTextures frame = t.gbuffer(frames[0]);
    const GLuint color = t.color(frames[0]);
    const GLuint out = t.rgba();
    const GLuint depth = t.r32f();
    const GLuint motion = t.rgba();
    const Status status = context.extrapolate(frame, color, to.view, to.projection, 1.0f, out,
                                              depth, motion, texture_stats, kSplatExtrapolation);
    ASSERT_TRUE(status.ok()) << status.message();
    EXPECT_EQ(texture_stats.holes, image_stats.holes);
    EXPECT_EQ(texture_stats.moving, image_stats.moving);
    EXPECT_EQ(texture_stats.silhouette_pixels, image_stats.silhouette_pixels);
    EXPECT_GT(texture_stats.silhouette_pixels, 0u);
    EXPECT_EQ(test::display_psnr(read_rgba(out), from_images.color), INFINITY);
    const Image<glm::vec4> read_motion = read_rgba(motion);
    for (std::size_t i = 0; i < read_motion.pixel_count(); ++i)
        ASSERT_EQ(glm::vec2(read_motion.data()[i]), from_images.motion.data()[i]) << "pixel " << i;

    auto message = [&](const warp::FrucOptions& options, float periods, const Frame& f) {
        Frame unused;
        gpu::ExtrapolateStats unused_stats;
        return context
            .extrapolate(f, to.view, to.projection, periods, unused, unused_stats, options)
            .message();
    };
    warp::FrucOptions unresolved = kSplatExtrapolation;
    unresolved.warp = warp::WarpMethod::Auto;
    EXPECT_NE(message(unresolved, 1.0f, frames[0]).find("warp grid, splat or reverse only"),
              std::string::npos);
    // The grid (its cells grown on the GPU) on textures: the CPU-image entry's frame.
    warp::FrucOptions grid = kSplatExtrapolation;
    grid.warp = warp::WarpMethod::Grid;
    ASSERT_TRUE(
        context.extrapolate(frames[0], to.view, to.projection, 1.0f, from_images, image_stats, grid)
            .ok());
    context.make_current();
    ASSERT_TRUE(context
                    .extrapolate(frame, color, to.view, to.projection, 1.0f, out, depth, motion,
                                 texture_stats, grid)
                    .ok());
    EXPECT_EQ(texture_stats.holes, image_stats.holes);
    EXPECT_EQ(test::display_psnr(read_rgba(out), from_images.color), INFINITY);
    const Image<glm::vec4> grid_motion = read_rgba(motion);
    for (std::size_t i = 0; i < grid_motion.pixel_count(); ++i)
        ASSERT_EQ(glm::vec2(grid_motion.data()[i]), from_images.motion.data()[i]) << "pixel " << i;
    EXPECT_NE(message(kSplatExtrapolation, -1.0f, frames[0]).find("periods"), std::string::npos);
    Frame skewed = frames[0];
    skewed.camera.projection[1][0] = 0.1f;
    skewed.camera.prev_projection = skewed.camera.projection;
    EXPECT_NE(message(kSplatExtrapolation, 1.0f, skewed).find("skewed"), std::string::npos);
    // The grid takes a skewed projection: its displacement and cells made on the CPU.
    gpu::ExtrapolateStats skewed_stats;
    expect_extrapolation_matches(skewed, to, 1.0f, skewed_stats, warp::WarpMethod::Grid);
    EXPECT_GT(context.timings().cpu_ms, 0.0);
    EXPECT_NE(context
                  .extrapolate(frame, color, to.view, to.projection, 1.0f, color, depth, motion,
                               texture_stats, kSplatExtrapolation)
                  .message()
                  .find("an output is an input"),
              std::string::npos);
}

// --- Spatio-temporal upsampling against warp::SpatioTemporalUpsampler.

struct Lowres {
    std::vector<Frame> full;
    std::vector<Image<glm::vec4>> low;
    std::vector<glm::vec2> jitter;
};

Lowres render_lowres(const std::string& name, int frames, int factor) {
    server::Scene scene;
    server::CameraPath path;
    EXPECT_TRUE(server::load_scene(name, scene, path).ok());
    Lowres r;
    r.full.resize(std::size_t(frames));
    r.low.resize(std::size_t(frames));
    r.jitter.resize(std::size_t(frames));
    for (int i = 0; i < frames; ++i) {
        const Status status = test::shared_renderer().render_frame_lowres(
            scene, path, i, 30.0, {.width = kWidth, .height = kHeight}, factor, r.full[i], r.low[i],
            r.jitter[i]);
        EXPECT_TRUE(status.ok()) << status.message();
    }
    return r;
}

// Every frame of `r` through the CPU's upsampler and the GPU's with `options`: colour within
// 50 dB, the history's counts within 0.1 % of the pixels. Returns the history pixels used.
int64_t expect_upsampling_matches(const Lowres& r, const warp::UpsampleOptions& options) {
    warp::SpatioTemporalUpsampler cpu(options);
    std::unique_ptr<gpu::Upsampler> gpu;
    const Status made = gpu::Upsampler::create(shared_gpu(), options, gpu);
    EXPECT_TRUE(made.ok()) << made.message();
    if (!gpu) return 0;
    Image<glm::vec4> cpu_out(kWidth, kHeight), gpu_out(kWidth, kHeight);
    const int64_t allowed = kWidth * kHeight / 1000;
    int64_t used = 0;
    for (std::size_t i = 0; i < r.full.size(); ++i) {
        SCOPED_TRACE("frame " + std::to_string(i));
        warp::UpsampleStats a, b;
        cpu.upsample(r.low[i].view(), r.jitter[i], r.full[i], cpu_out.view(), &a);
        const Status status =
            gpu->upsample(r.low[i].view(), r.jitter[i], r.full[i], gpu_out.view(), &b);
        EXPECT_TRUE(status.ok()) << status.message();
        const double db = test::display_psnr(cpu_out, gpu_out);
        EXPECT_GE(db, 50.0);
        EXPECT_LE(std::abs(a.history_rejected - b.history_rejected), allowed);
        EXPECT_LE(std::abs(a.history_used - b.history_used), allowed);
        EXPECT_EQ(a.unresolved, b.unresolved);
        EXPECT_EQ(a.nonfinite_samples, b.nonfinite_samples);
        EXPECT_EQ(a.nonfinite.total(), b.nonfinite.total());
        if (i + 1 == r.full.size())
            std::printf("  frame %zu: history used %lld (cpu %lld), rejected %lld, %.1f dB\n", i,
                        (long long)b.history_used, (long long)a.history_used,
                        (long long)b.history_rejected, db);
        used += b.history_used;
    }
    return used;
}

TEST(Gpu, UpsamplingMatchesTheCpuOnBuiltInScenes) {
    int64_t used = 0;
    for (const char* name : {"pan", "crossing", "fast", "hud"})
        for (int factor : {2, 4}) {
            SCOPED_TRACE(std::string(name) + " factor " + std::to_string(factor));
            std::printf("%s, 1/%d of the pixels\n", name, factor);
            used += expect_upsampling_matches(render_lowres(name, 5, factor), {});
        }
    EXPECT_GT(used, 0);  // not vacuous: the history was used
}

TEST(Gpu, UpsamplingOptionsAndNonFiniteSamples) {
    Lowres r = render_lowres("crossing", 4, 4);
    const warp::UpsampleOptions unsteered{.gradient_steering = false, .history_clamp = -1.0f};
    EXPECT_GT(expect_upsampling_matches(r, unsteered), 0);
    EXPECT_GT(expect_upsampling_matches(r, {.recompute_taps = true, .separable_filter = false}), 0);
    // NaN and infinite low samples are skipped; spoiled guides are repaired first, as on the CPU.
    for (std::size_t i = 0; i < r.low.size(); ++i) {
        r.low[i](1, 1) = glm::vec4(NAN);
        r.low[i](5, 3) = glm::vec4(INFINITY);
        r.full[i].depth(7, 7) = NAN;
        r.full[i].motion(9, 9) = glm::vec2(INFINITY);
    }
    expect_upsampling_matches(r, {});
    // Textures in and out: the CPU-image entry's frames, history included.
    const Lowres clean = render_lowres("crossing", 3, 4);
    std::unique_ptr<gpu::Upsampler> from_images, from_textures;
    ASSERT_TRUE(gpu::Upsampler::create(shared_gpu(), {}, from_images).ok());
    ASSERT_TRUE(gpu::Upsampler::create(shared_gpu(), {}, from_textures).ok());
    Image<glm::vec4> expected(kWidth, kHeight);
    for (std::size_t i = 0; i < clean.full.size(); ++i) {
        warp::UpsampleStats a, b;
        ASSERT_TRUE(
            from_images
                ->upsample(clean.low[i].view(), clean.jitter[i], clean.full[i], expected.view(), &a)
                .ok());
        shared_gpu().make_current();
        Textures t;
        const Image<glm::vec4>& low = clean.low[i];
        const GLuint low_color =
            t.make(GL_RGBA32F, low.width(), low.height(), GL_RGBA, GL_FLOAT, low.data());
        const GLuint normal =
            t.make(GL_RGB32F, kWidth, kHeight, GL_RGB, GL_FLOAT, clean.full[i].normal.data());
        const GLuint out = t.rgba();
        const Status status =
            from_textures->upsample(low_color, low.width(), low.height(), clean.jitter[i],
                                    t.gbuffer(clean.full[i]), normal, out, &b);
        ASSERT_TRUE(status.ok()) << status.message();
        EXPECT_EQ(test::display_psnr(read_rgba(out), expected), INFINITY) << "frame " << i;
        EXPECT_EQ(b.history_used, a.history_used);
        EXPECT_NE(from_textures
                      ->upsample(low_color, low.width(), low.height(), clean.jitter[i],
                                 t.gbuffer(clean.full[i]), normal, low_color, &b)
                      .message()
                      .find("(output colour) is"),
                  std::string::npos);
        EXPECT_NE(from_textures
                      ->upsample(out, kWidth, kHeight, clean.jitter[i], t.gbuffer(clean.full[i]),
                                 normal, out, &b)
                      .message()
                      .find("the output is the low colour"),
                  std::string::npos);
    }
    std::unique_ptr<gpu::Upsampler> refused;
    EXPECT_NE(
        gpu::Upsampler::create(shared_gpu(), {.epsilon = 0.0f}, refused).message().find("epsilon"),
        std::string::npos);
}

// The lowres client's hand-off (Upsampler::keep_output, FrucBackend::inputs_from): the kept
// colour never comes to the CPU image it was asked for, the depth and motion that guided the
// upsampler are not uploaded again, and the frames extrapolated from the textures are those
// extrapolated from the downloaded colour and the uploaded depth and motion, to the bit.
TEST(Gpu, UpsampledColourKeptForTheExtrapolationIsTheDownloadedOne) {
    const Lowres r = render_lowres("crossing", 3, 2);
    std::unique_ptr<gpu::Upsampler> downloading, keeping;
    ASSERT_TRUE(gpu::Upsampler::create(shared_gpu(), {}, downloading).ok());
    ASSERT_TRUE(gpu::Upsampler::create(shared_gpu(), {}, keeping).ok());
    keeping->keep_output(true);
    gpu::FrucBackend uploading(shared_gpu()), handed(shared_gpu());
    ASSERT_TRUE(handed.inputs_from(keeping.get()).ok());
    const warp::FrucOptions options{.mode = warp::FrucMode::Extrapolate};
    const Camera& to = r.full[2].camera;
    Image<glm::vec4> upsampled(kWidth, kHeight), kept(kWidth, kHeight);
    for (std::size_t i = 0; i < r.full.size(); ++i) {
        SCOPED_TRACE("frame " + std::to_string(i));
        ASSERT_TRUE(
            downloading->upsample(r.low[i].view(), r.jitter[i], r.full[i], upsampled.view()).ok());
        kept.fill(glm::vec4(NAN));
        Frame guides = r.full[i];
        ASSERT_TRUE(keeping->upsample(r.low[i].view(), r.jitter[i], guides, kept.view()).ok());
        EXPECT_TRUE(keeping->output_kept());
        EXPECT_TRUE(std::isnan(kept(3, 3).r));               // left unwritten
        EXPECT_EQ(keeping->kept_for(upsampled.view()), 0u);  // another image: nothing kept for it
        GBufferView frame = r.full[i];
        frame.color = upsampled.view();
        Frame expected, got;
        warp::FrucCounters c1, c2;
        ASSERT_TRUE(
            uploading
                .extrapolate(frame, to.view, to.projection, 0.5f, 1.0f, options, expected, c1, 0)
                .ok());
        // NaN colour, flat depth and no motion on the CPU: the textures must be what is warped.
        guides.depth.fill(1.0f);
        guides.motion.fill(glm::vec2(0.0f));
        GBufferView handed_frame = guides.view();
        handed_frame.color = kept.view();
        const gpu::FrameOnGpu on_gpu = keeping->on_gpu(handed_frame);
        EXPECT_NE(on_gpu.color, 0u);
        EXPECT_NE(on_gpu.depth, 0u);
        EXPECT_NE(on_gpu.motion, 0u);
        EXPECT_EQ(keeping->on_gpu(frame).depth, 0u);  // other images: not these
        ASSERT_TRUE(
            handed
                .extrapolate(handed_frame, to.view, to.projection, 0.5f, 1.0f, options, got, c2, 0)
                .ok());
        ASSERT_EQ(got.color.width(), kWidth);
        EXPECT_EQ(test::display_psnr(expected.color, got.color), INFINITY);
        EXPECT_EQ(std::memcmp(expected.depth.data(), got.depth.data(),
                              expected.depth.pixel_count() * sizeof(float)),
                  0);
        EXPECT_EQ(c1.hole_pixels, c2.hole_pixels);
        EXPECT_EQ(c1.silhouette_pixels, c2.silhouette_pixels);  // widened on the GPU alike
        EXPECT_GT(c1.silhouette_pixels, 0u);
        ASSERT_TRUE(keeping->download_kept(kept.view()).ok());
        EXPECT_EQ(
            std::memcmp(kept.data(), upsampled.data(), kept.pixel_count() * sizeof(glm::vec4)), 0);
        EXPECT_FALSE(keeping->output_kept());  // downloaded: the CPU image holds it now
        EXPECT_NE(keeping->download_kept(kept.view()).message().find("nothing kept"),
                  std::string::npos);
    }
    // A frame key extrapolated from the handed-over depth and motion, then again with nothing
    // handed over (the upsampler reset, its colour on the CPU): uploaded then, not warped from
    // source textures the first call never filled (widening off: the copy of the handed-over
    // textures is not what the second call warps).
    const warp::FrucOptions as_they_are{.mode = warp::FrucMode::Extrapolate,
                                        .widen_silhouettes = false};
    Frame guides = r.full[0];
    ASSERT_TRUE(keeping->upsample(r.low[0].view(), r.jitter[0], guides, kept.view()).ok());
    GBufferView frame = guides.view();
    frame.color = kept.view();
    Frame first, again;
    warp::FrucCounters counters;
    ASSERT_TRUE(handed
                    .extrapolate(frame, to.view, to.projection, 0.5f, 1.0f, as_they_are, first,
                                 counters, 77)
                    .ok());
    ASSERT_TRUE(keeping->download_kept(kept.view()).ok());
    keeping->reset();
    EXPECT_EQ(keeping->on_gpu(frame).depth, 0u);
    ASSERT_TRUE(handed
                    .extrapolate(frame, to.view, to.projection, 0.5f, 1.0f, as_they_are, again,
                                 counters, 77)
                    .ok());
    EXPECT_EQ(test::display_psnr(first.color, again.color), INFINITY);
    EXPECT_EQ(std::memcmp(first.depth.data(), again.depth.data(),
                          first.depth.pixel_count() * sizeof(float)),
              0);
}

// --- The eye with history: the previous frame warped into the rendered eye's holes.

TEST(Gpu, StereoEyeWithHistoryMatchesTheCpuOnEveryBuiltInScene) {
    std::size_t from_history = 0, moving = 0, grid_from_history = 0;
    for (const server::SceneInfo& info : server::builtin_scenes()) {
        SCOPED_TRACE(info.name);
        const std::vector<Frame>& frames = scene_frames(info.name);
        const Camera right =
            stereo::eye_cameras(frames[1].camera, {.ipd = 0.2f}, stereo::Anchor::Left).right;
        for (const stereo::StereoOptions& options :
             {stereo::StereoOptions{.warp = stereo::StereoWarp::Splat},
              stereo::StereoOptions{.warp = stereo::StereoWarp::Splat,
              .fill = stereo::StereoFill::None,
              .history_replaces = true},
              stereo::StereoOptions{}, stereo::StereoOptions{.grid = {.min_cell = 2}}}) {
            Frame cpu, gpu;
            stereo::StereoSynthesizer synthesizer;
            const GBufferView history = frames[0].view();
            stereo::StereoOptions on_cpu = options;
            on_cpu.perceptual = false;  // the GPU's eye works in linear light
            const stereo::StereoStats a =
                synthesizer.synthesize(frames[1], right, cpu, on_cpu, &history);
            stereo::StereoStats b;
            const Status status =
                shared_gpu().stereo_eye(frames[1], right, gpu, b, options, &history);
            ASSERT_TRUE(status.ok()) << status.message();
            EXPECT_GE(test::display_psnr(cpu.color, gpu.color), 50.0);
            EXPECT_EQ(b.history_moving, a.history_moving);
            // The grid's counts within the issue's 0.1 % of the pixels; the splat's exactly.
            const std::size_t allowed =
                options.warp == stereo::StereoWarp::Grid ? cpu.color.pixel_count() / 1000 : 0;
            for (auto [x, y] : {std::pair{a.from_history, b.from_history},
                                {a.holes, b.holes},
                                {a.filled, b.filled},
                                {a.unfilled, b.unfilled},
                                {a.stretched, b.stretched},
                                {a.border, b.border}})
                EXPECT_LE(std::max(x, y) - std::min(x, y), allowed);
            from_history += b.from_history;
            moving += b.history_moving;
            grid_from_history += options.warp == stereo::StereoWarp::Grid ? b.from_history : 0;
        }
    }
    EXPECT_GT(from_history, 0u);  // not vacuous: holes were filled from the history
    EXPECT_GT(moving, 0u);        // ... and moving history pixels left out
    EXPECT_GT(grid_from_history, 0u);
}

TEST(Gpu, StereoEyeWithHistoryOnTexturesIsTheImageEntrys) {
    // Mirror: holes filled from the history (55 pixels) and moving history pixels left out (897).
    const std::vector<Frame>& frames = scene_frames("mirror");
    const Camera right =
        stereo::eye_cameras(frames[1].camera, {.ipd = 0.2f}, stereo::Anchor::Left).right;
    // Silhouettes widened on the GPU by both entries.
    const stereo::StereoOptions options{.warp = stereo::StereoWarp::Splat};
    gpu::Context& context = shared_gpu();
    Frame from_images;
    stereo::StereoStats image_stats, texture_stats;
    const GBufferView history_view = frames[0].view();
    ASSERT_TRUE(
        context.stereo_eye(frames[1], right, from_images, image_stats, options, &history_view)
            .ok());
    ASSERT_GT(image_stats.from_history, 0u);
    ASSERT_GT(image_stats.history_moving, 0u);
    context.make_current();
    Textures t;
    const gpu::GBufferTextures rendered = t.gbuffer(frames[1]), history = t.gbuffer(frames[0]);
    const GLuint color = t.color(frames[1]);
    const GLuint history_color = t.color(frames[0]);
    const GLuint out = t.rgba();
    const GLuint depth = t.r32f();
    const Status status = context.stereo_eye(rendered, color, right, out, depth, texture_stats,
                                             options, &history, history_color);
    ASSERT_TRUE(status.ok()) << status.message();
    EXPECT_EQ(texture_stats.from_history, image_stats.from_history);
    EXPECT_EQ(texture_stats.history_moving, image_stats.history_moving);
    EXPECT_EQ(texture_stats.holes, image_stats.holes);
    EXPECT_EQ(test::display_psnr(read_rgba(out), from_images.color), INFINITY);
    // A history of another size, or whose colour is the output, is refused.
    gpu::GBufferTextures small = history;
    small.width = kWidth / 2;
    EXPECT_NE(context
                  .stereo_eye(rendered, color, right, out, depth, texture_stats, options, &small,
                              history_color)
                  .message()
                  .find("the history is"),
              std::string::npos);
    EXPECT_NE(context
                  .stereo_eye(rendered, color, right, history_color, depth, texture_stats, options,
                              &history, history_color)
                  .message()
                  .find("the history colour"),
              std::string::npos);
}

// --- The shot-change test.

TEST(Gpu, ShotChangeDecidesAsTheCpu) {
    gpu::Context& context = shared_gpu();
    std::size_t cuts = 0, kept = 0;
    auto check = [&](const Frame& frame, const Frame& previous, float misses, float color,
                     const std::string& what) -> warp::ShotChange {
        SCOPED_TRACE(what);
        warp::ShotChangeScratch scratch;
        const warp::ShotChange cpu = warp::shot_change(frame, previous, misses, color, scratch);
        warp::ShotChange gpu;
        const Status status = context.shot_change(frame, previous, misses, color, gpu);
        EXPECT_TRUE(status.ok()) << status.message();
        EXPECT_EQ(gpu.counts, cpu.counts);
        EXPECT_EQ(gpu.difference, cpu.difference);
        EXPECT_EQ(gpu.cut, cpu.cut);
        ++(cpu.cut ? cuts : kept);
        return cpu;
    };
    for (const server::SceneInfo& info : server::builtin_scenes()) {
        const std::vector<Frame>& frames = scene_frames(info.name);
        const warp::ShotChange same = check(frames[1], frames[0], 0.6f, 0.12f, info.name);
        EXPECT_FALSE(same.cut);
        // Just under the pair's mean colour difference: a cut by colour alone.
        if (same.counts.hits > 0 && same.difference > 0) {
            const double mean = double(same.difference) / 1048576.0 / (3.0 * same.counts.hits);
            EXPECT_TRUE(check(frames[1], frames[0], 0.6f, float(mean * 0.99),
                              std::string(info.name) + ", colour threshold")
                            .cut);
        }
    }
    // The cut scene across its cut, and two unrelated scenes.
    const std::vector<Frame> across = test::render_scene("cut", 2, kWidth, kHeight, 30.0, 14);
    EXPECT_TRUE(check(across[1], across[0], 0.6f, 0.12f, "cut scene across the cut").cut);
    EXPECT_TRUE(check(scene_frames("fence")[1], scene_frames("shadows")[1], 0.6f, 0.12f,
                      "fence after shadows")
                    .cut);
    // NaN/Inf in colour, depth and motion (the entry does not repair): alike too.
    NonfiniteCounts spoiled;
    const std::vector<Frame> nonfinite = test::spoiled_sequence(2, spoiled);
    const warp::ShotChange spoiled_change =
        check(nonfinite[1], nonfinite[0], 0.6f, 0.12f, "NaN/Inf input");
    EXPECT_GT(spoiled_change.counts.invalid, 0u);
    std::printf("shot changes: %zu cuts, %zu kept, decided alike\n", cuts, kept);
    EXPECT_GT(cuts, 10u);
    EXPECT_GT(kept, 10u);

    // On textures: the same counts, sum and decision.
    const std::vector<Frame>& frames = scene_frames("crossing");
    warp::ShotChange images, textures;
    ASSERT_TRUE(context.shot_change(frames[1], frames[0], 0.6f, 0.12f, images).ok());
    context.make_current();
    Textures t;
    const gpu::GBufferTextures a = t.gbuffer(frames[0]), b = t.gbuffer(frames[1]);
    const Status status =
        context.shot_change(b, t.color(frames[1]), a, t.color(frames[0]), 0.6f, 0.12f, textures);
    ASSERT_TRUE(status.ok()) << status.message();
    EXPECT_EQ(textures.counts, images.counts);
    EXPECT_EQ(textures.difference, images.difference);
    EXPECT_GT(textures.difference, 0u);
    EXPECT_EQ(context.timings().upload_ms, 0.0);
    gpu::GBufferTextures no_motion = b;
    no_motion.motion = 0;
    EXPECT_NE(context
                  .shot_change(no_motion, t.color(frames[1]), a, t.color(frames[0]), 0.6f, 0.12f,
                               textures)
                  .message()
                  .find("frame motion"),
              std::string::npos);
}

// --- A gpu::Context working in the application's own OpenGL ES context.

TEST(Gpu, AContextAdoptedFromTheApplication) {
    const std::vector<Frame>& frames = scene_frames("crossing");
    Frame expected;
    gpu::InterpolateStats expected_stats, stats;
    ASSERT_TRUE(
        shared_gpu().interpolate(frames[0], frames[1], 0.5f, expected, expected_stats).ok());
    // The application's context (made here as an engine would have one), current on this thread.
    std::unique_ptr<gl::Context> application;
    ASSERT_TRUE(gl::Context::create(application).ok());
    std::unique_ptr<gpu::Context> adopted;
    const Status made = gpu::Context::adopt_current(adopted);
    ASSERT_TRUE(made.ok()) << made.message();
    {
        Textures t;  // the application's textures, used as they are
        const gpu::GBufferTextures a = t.gbuffer(frames[0]), b = t.gbuffer(frames[1]);
        const GLuint a_color = t.color(frames[0]);
        const GLuint b_color = t.color(frames[1]);
        const GLuint out = t.rgba();
        const GLuint depth = t.r32f();
        const Status status = adopted->interpolate(a, a_color, b, b_color, 0.5f, out, depth, stats);
        ASSERT_TRUE(status.ok()) << status.message();
        EXPECT_EQ(test::display_psnr(read_rgba(out), expected.color), INFINITY);
        EXPECT_EQ(stats.holes, expected_stats.holes);
        // With another context current the adopted one refuses, and makes nothing current.
        shared_gpu().make_current();
        EXPECT_NE(adopted->interpolate(a, a_color, b, b_color, 0.5f, out, depth, stats)
                      .message()
                      .find("not current on this thread"),
                  std::string::npos);
        application->make_current();
    }
    adopted.reset();  // its objects deleted in the application's context, which stays
    EXPECT_EQ(glGetError(), GLenum(GL_NO_ERROR));
    application.reset();  // nothing current now
    EXPECT_NE(gpu::Context::adopt_current(adopted).message().find("no EGL context is current"),
              std::string::npos);
}

}  // namespace
