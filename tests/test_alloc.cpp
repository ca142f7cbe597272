// The per-frame paths allocate nothing once their scratch is sized: every operator new in this
// binary is counted while a frame is converted or an eye synthesized.
#include <gtest/gtest.h>

#include <execinfo.h>

#include <atomic>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <new>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "reprise/stereo/synthesize.hpp"
#include "reprise/warp/fruc.hpp"
#include "reprise/warp/upsample.hpp"

namespace {

std::atomic<bool> counting{false};
std::atomic<long> allocations{0};

// REPRISE_ALLOC_TRACE=1 prints the stack of every counted allocation.
void trace() {
    thread_local bool inside = false;
    if (inside || !std::getenv("REPRISE_ALLOC_TRACE")) return;
    inside = true;
    void* frames[32];
    const int n = backtrace(frames, 32);
    backtrace_symbols_fd(frames, n, 2);
    std::fputs("----\n", stderr);
    inside = false;
}

void* allocate(std::size_t size, std::size_t alignment = 0) {
    if (counting.load(std::memory_order_relaxed)) {
        allocations.fetch_add(1, std::memory_order_relaxed);
        trace();
    }
    if (size == 0) size = 1;
    void* p = alignment
                  ? std::aligned_alloc(alignment, (size + alignment - 1) / alignment * alignment)
                  : std::malloc(size);
    if (!p) throw std::bad_alloc();
    return p;
}

// Counts the allocations made while `body` runs (on any thread).
template <class F>
long allocations_during(F&& body) {
    allocations = 0;
    counting = true;
    body();
    counting = false;
    return allocations.load();
}

}  // namespace

void* operator new(std::size_t size) { return allocate(size); }
void* operator new[](std::size_t size) { return allocate(size); }
void* operator new(std::size_t size, std::align_val_t a) { return allocate(size, std::size_t(a)); }
void* operator new[](std::size_t size, std::align_val_t a) {
    return allocate(size, std::size_t(a));
}
void* operator new(std::size_t size, const std::nothrow_t&) noexcept {
    try {
        return allocate(size);
    } catch (...) {
        return nullptr;
    }
}
void* operator new[](std::size_t size, const std::nothrow_t&) noexcept {
    try {
        return allocate(size);
    } catch (...) {
        return nullptr;
    }
}
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }

using namespace reprise;

namespace {

constexpr int kW = 256, kH = 144, kStep = 3;  // content moves kStep px left per frame
constexpr float kDepth = 5.0f;

// A textured plane at depth kDepth seen by an orthographic camera (1 scene unit = 1 px) that
// moves kStep units to the right per frame: motion (+kStep, 0) everywhere, explained by the
// camera alone.
Camera camera_at(int frame) {
    Camera c;
    c.projection = glm::ortho(-kW / 2.0f, kW / 2.0f, -kH / 2.0f, kH / 2.0f, 0.1f, 100.0f);
    c.view = glm::translate(glm::mat4(1.0f), glm::vec3(-float(kStep * frame), 0.0f, 0.0f));
    c.prev_view =
        glm::translate(glm::mat4(1.0f), glm::vec3(-float(kStep * (frame - 1)), 0.0f, 0.0f));
    c.prev_projection = c.projection;
    c.time = frame / 30.0;
    return c;
}

// Noise (every pixel its own value), or with `smooth` a slow gradient whose warped sides agree.
Frame make_frame(int index, bool smooth = false) {
    Frame f;
    f.color.resize(kW, kH);
    f.depth.assign(kW, kH, kDepth);
    f.motion.assign(kW, kH, glm::vec2(float(kStep), 0.0f));
    f.id.assign(kW, kH, 1u);
    f.camera = camera_at(index);
    f.fps = 30.0;
    for (int y = 0; y < kH; ++y)
        for (int x = 0; x < kW; ++x) {
            const unsigned u = unsigned(x + kStep * index) * 2654435761u ^ unsigned(y) * 40503u;
            const float v = smooth ? 0.5f + 0.4f * std::sin(0.02f * float(x + kStep * index))
                                   : float(u >> 24) / 255.0f;
            f.color(x, y) = {v, 1.0f - v, 0.5f * v, 1.0f};
        }
    return f;
}

// Motion refinement's optical flow (OpenCV DIS) allocates inside OpenCV: `refine` runs it on
// smooth frames, where its survey finds the sides agreeing and nothing more runs.
void run_converter(warp::FrucMode mode, bool refine = false,
                   warp::WarpMethod method = warp::WarpMethod::Grid, bool owned = false) {
    std::vector<Frame> inputs;
    for (int i = 0; i < 12; ++i) inputs.push_back(make_frame(i, refine));
    warp::FrucOptions options{.mode = mode, .warp = method};
    options.refine.enabled = refine;
    warp::FrameRateConverter converter;
    EXPECT_TRUE(warp::FrameRateConverter::create(2, options, converter).ok());
    Frame in, out;
    bool ok = true;
    int made = 0;
    auto feed = [&](int i) {
        if (owned) {
            in = inputs[std::size_t(i)];  // into the buffers the converter handed back
            ok = ok && converter.send(std::move(in)).ok();
        } else {
            ok = ok && converter.send(inputs[std::size_t(i)]).ok();
        }
        while (converter.receive(out)) ++made;
    };
    // Sizes the scratch, the queue and every frame that circulates through it (queued frames
    // trade places with the caller's, so each needs a few rounds to have held every channel).
    for (int i = 0; i < 8; ++i) feed(i);
    const long counted = allocations_during([&] {
        for (int i = 8; i < 12; ++i) feed(i);
    });
    EXPECT_TRUE(ok);
    EXPECT_EQ(made, mode == warp::FrucMode::Interpolate ? 23 : 24);
    EXPECT_EQ(converter.counters().cuts, 0u);
    EXPECT_EQ(counted, 0) << "allocations in 4 steady-state send/receive rounds";
    if (refine) {
        EXPECT_EQ(converter.counters().refined_frames, 0u);
        EXPECT_EQ(converter.counters().refine_skipped, 11u);
    }
}

}  // namespace

TEST(Allocations, CounterSeesAnAllocation) {
    // The counter itself works: a vector growing in the counted region is seen.
    std::vector<int>* v = nullptr;
    const long counted = allocations_during([&] { v = new std::vector<int>(100); });
    delete v;
    EXPECT_GE(counted, 2);
}

TEST(Allocations, InterpolationSteadyStateAllocatesNothing) {
    run_converter(warp::FrucMode::Interpolate);
}

TEST(Allocations, OwnedFramesSteadyStateAllocatesNothing) {
    run_converter(warp::FrucMode::Interpolate, false, warp::WarpMethod::Grid, true);
    run_converter(warp::FrucMode::Extrapolate, false, warp::WarpMethod::Grid, true);
}

TEST(Allocations, InterpolationSurveyForRefinementAllocatesNothing) {
    run_converter(warp::FrucMode::Interpolate, true);
}

TEST(Allocations, ReverseWarpInterpolationSteadyStateAllocatesNothing) {
    run_converter(warp::FrucMode::Interpolate, false, warp::WarpMethod::Reverse);
}

TEST(Allocations, ExtrapolationSteadyStateAllocatesNothing) {
    run_converter(warp::FrucMode::Extrapolate);
}

TEST(Allocations, StereoSynthesisSteadyStateAllocatesNothing) {
    const Frame left = make_frame(0), history = make_frame(1);
    Camera target = left.camera;
    target.view = glm::translate(glm::mat4(1.0f), glm::vec3(-2.5f, 0.0f, 0.0f)) * left.camera.view;
    Camera history_camera = target;
    Frame history_eye = history;
    history_eye.camera = history_camera;
    stereo::StereoSynthesizer synthesizer;
    Frame out;
    std::size_t covered = 0;
    for (stereo::StereoFill fill : {stereo::StereoFill::PullPush, stereo::StereoFill::Andreev}) {
        const stereo::StereoOptions options{.fill = fill};
        auto both = [&] {
            covered += synthesizer.synthesize(left, target, out, options).covered;
            covered += synthesizer.synthesize(left, target, out, options, &history_eye).covered;
        };
        both();
        const long counted = allocations_during([&] {
            for (int i = 0; i < 3; ++i) both();
        });
        EXPECT_EQ(counted, 0) << "allocations in 6 steady-state syntheses, fill " << int(fill);
    }
    EXPECT_GT(covered, 0u);
}

TEST(Allocations, UpsamplingSteadyStateAllocatesNothing) {
    std::vector<Frame> frames;
    for (int i = 0; i < 4; ++i) frames.push_back(make_frame(i));
    Image<glm::vec4> low(kW / 2, kH / 2), out(kW, kH);
    for (int y = 0; y < kH / 2; ++y)
        for (int x = 0; x < kW / 2; ++x) low(x, y) = frames[0].color(2 * x, 2 * y);
    warp::SpatioTemporalUpsampler upsampler;
    warp::UpsampleStats stats;
    upsampler.upsample(low.view(), {-0.5f, -0.5f}, frames[0], out.view(), &stats);
    const long counted = allocations_during([&] {
        for (int i = 1; i < 4; ++i)
            upsampler.upsample(low.view(), {0.5f * (i & 1) - 0.25f, 0.25f}, frames[std::size_t(i)],
                               out.view(), &stats);
    });
    EXPECT_GT(stats.history_used, 0);
    EXPECT_EQ(counted, 0) << "allocations in 3 steady-state upsampled frames";
}
