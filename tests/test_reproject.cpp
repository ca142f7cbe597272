// Reverse reprojection, refresh policies and amortized sampling on hand-built frames.
#include <gtest/gtest.h>

#include <cfloat>
#include <cmath>
#include <cstring>
#include <glm/gtc/constants.hpp>
#include <glm/gtc/matrix_transform.hpp>
#include <limits>
#include <random>
#include <vector>

#include "reprise/warp/reproject.hpp"
#include "support/frames.hpp"

namespace {

using namespace reprise;
using namespace reprise::warp;

using test::kInf;
using test::kNaN;

struct Buffer {
    int w = 0, h = 0, c = 0;
    std::vector<float> v;
    Buffer(int width, int height, int channels, float fill = 0.0f)
        : w(width), h(height), c(channels), v(std::size_t(width) * height * channels, fill) {}
    Payload view() { return {v.data(), w, h, c, std::ptrdiff_t(w) * c}; }
    ConstPayload cview() const { return {v.data(), w, h, c, std::ptrdiff_t(w) * c}; }
    float& at(int x, int y, int k = 0) { return v[(std::size_t(y) * w + x) * c + k]; }
    float at(int x, int y, int k = 0) const { return v[(std::size_t(y) * w + x) * c + k]; }
};

Frame make_frame(int w, int h, float depth, glm::vec2 motion, uint32_t id = 1) {
    Frame f = test::constant_frame(w, h, depth, motion);
    f.normal.resize(w, h);
    f.id.assign(w, h, id);
    return f;
}

float uniform(std::mt19937& rng, float a, float b) {
    return a + (b - a) * float(rng() >> 8) * (1.0f / 16777216.0f);
}

Buffer random_payload(int w, int h, int c, uint32_t seed) {
    std::mt19937 rng(seed);
    Buffer b(w, h, c);
    for (float& x : b.v) x = uniform(rng, -4.0f, 4.0f);
    return b;
}

using Size = std::pair<int, int>;

std::size_t total(const ReprojectCounts& c) { return c.hits + c.misses(); }

// ---------------------------------------------------------------------------------------------
// Analytic cases

// The camera slides parallel to a fronto-parallel plane by exactly (k, j) pixels at its depth.
TEST(Reproject, PanParallelToPlaneIsAnExactShift) {
    const int w = 64, h = 48, k = 3, j = 2;
    const float D = 10.0f;
    const glm::mat4 proj = glm::perspective(glm::radians(60.0f), float(w) / h, 0.1f, 100.0f);
    const double dx = k * 2.0 * D / (proj[0][0] * w), dy = j * 2.0 * D / (proj[1][1] * h);
    Frame prev = make_frame(w, h, D, {0, 0});
    Frame cur = make_frame(w, h, D, {float(k), -float(j)});  // camera right/up: content left/down
    for (Frame* f : {&prev, &cur}) f->camera.projection = f->camera.prev_projection = proj;
    cur.camera.view = glm::translate(glm::mat4(1.0f), glm::vec3(-dx, -dy, 0.0));
    const Buffer payload = random_payload(w, h, 4, 7);
    Buffer out(w, h, 4, -99.0f);
    Image<uint8_t> hit(w, h, 7);
    const ReprojectOptions tight{.depth_tolerance = 1e-5f, .match_ids = false};
    ReprojectCounts c = reproject(cur, prev, payload.cview(), out.view(), hit.view(), tight);
    EXPECT_EQ(c.hits, std::size_t(w - k) * (h - j));
    EXPECT_EQ(c.offscreen, std::size_t(w * h) - c.hits);
    EXPECT_EQ(total(c), std::size_t(w * h));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            bool inside = x + k < w && y - j >= 0;
            ASSERT_EQ(hit(x, y), inside) << x << "," << y;
            for (int ch = 0; ch < 4; ++ch)
                ASSERT_EQ(out.at(x, y, ch), inside ? payload.at(x + k, y - j, ch) : -99.0f);
        }
}

TEST(Reproject, ZeroMotionIsABitExactCopy) {
    const int w = 37, h = 19;
    std::mt19937 rng(3);
    Frame prev = make_frame(w, h, 1, {0, 0}), cur = make_frame(w, h, 1, {0, 0});
    for (Frame* f : {&prev, &cur}) {
        f->camera.projection = glm::perspective(1.0f, 2.0f, 0.01f, 1e4f);
        f->camera.view = f->camera.prev_view =
            glm::lookAt(glm::vec3(1, 2, 3), glm::vec3(0), glm::vec3(0, 1, 0));
    }
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) cur.depth(x, y) = prev.depth(x, y) = uniform(rng, 0.02f, 5e3f);
    for (int channels : {1, 3, 4, 5}) {
        Buffer payload = random_payload(w, h, channels, 11);
        payload.at(3, 3, 0) = 1e-40f;  // denormals and extremes are copied too
        payload.at(4, 3, 0) = -FLT_MAX;
        Buffer out(w, h, channels);
        ReprojectCounts c = reproject(cur, prev, payload.cview(), out.view(), {});
        EXPECT_EQ(c.hits, std::size_t(w * h));
        EXPECT_EQ(0, std::memcmp(out.v.data(), payload.v.data(), out.v.size() * sizeof(float)));
    }
}

// The camera backs away from a plane: every pixel's depth grows from D to D + d, which only the
// depth model (current camera -> world -> previous camera) predicts.
TEST(Reproject, DepthModelFollowsCameraAlongItsAxis) {
    const int w = 40, h = 30;
    const double D = 5.0, d = 1.0, scale = D / (D + d);
    const glm::mat4 proj = glm::perspective(glm::radians(50.0f), float(w) / h, 0.1f, 100.0f);
    Frame prev = make_frame(w, h, float(D + d), {0, 0}), cur = make_frame(w, h, float(D), {0, 0});
    cur.camera.projection = proj;
    cur.camera.prev_view = glm::translate(glm::mat4(1.0f), glm::vec3(0, 0, -float(d)));
    Buffer payload(w, h, 1);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            payload.at(x, y) = 0.25f * x + 0.5f * y;
            double px = x + 0.5, py = y + 0.5;
            cur.motion(x, y) = glm::vec2(float(w / 2.0 + (px - w / 2.0) * scale - px),
                                         float(h / 2.0 + (py - h / 2.0) * scale - py));
        }
    Buffer out(w, h, 1, -1.0f);
    const ReprojectOptions tight{.depth_tolerance = 1e-4f, .match_ids = false};
    ReprojectCounts c = reproject(cur, prev, payload.cview(), out.view(), {}, tight);
    EXPECT_EQ(c.hits, std::size_t(w * h));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            glm::vec2 q = glm::vec2(x + 0.5f, y + 0.5f) + cur.motion(x, y) - 0.5f;
            ASSERT_NEAR(out.at(x, y), 0.25f * q.x + 0.5f * q.y, 1e-4f);
        }
    // The previous depth buffer of a camera that did not move: every pixel is occluded.
    prev.depth.assign(w, h, float(D));
    c = reproject(cur, prev, payload.cview(), out.view(), {}, tight);
    EXPECT_EQ(c.occluded, std::size_t(w * h));
}

// The previous camera is yawed: expected depth now varies along x, and both frames are jittered,
// so the unprojection position (p + 0.5 + jitter) and the lookup (minus the previous jitter) show.
TEST(Reproject, RotatedCameraWithJitter) {
    const int w = 64, h = 36;
    const double D = 4.0;
    const glm::dmat4 proj = glm::perspective(glm::radians(60.0), double(w) / h, 0.1, 100.0);
    const glm::dmat4 prev_view =
        glm::rotate(glm::dmat4(1.0), glm::radians(8.0), glm::dvec3(0, 1, 0));
    const glm::dvec2 jitter(0.3, -0.2), prev_jitter(-0.4, 0.3);
    Frame prev = make_frame(w, h, 0, {0, 0}), cur = make_frame(w, h, float(D), {0, 0});
    cur.camera.projection = glm::mat4(proj);
    cur.camera.prev_view = glm::mat4(prev_view);
    cur.camera.jitter = glm::vec2(jitter);
    prev.camera.jitter = glm::vec2(prev_jitter);
    auto ndc = [&](glm::dvec2 px) {
        return glm::dvec2(2.0 * px.x / w - 1.0, 1.0 - 2.0 * px.y / h);
    };
    auto ramp = [](glm::dvec2 u) { return 0.125 * u.x - 0.25 * u.y; };
    Buffer payload(w, h, 1);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            // Previous frame: the ray through its jittered sample hits the plane z = -D.
            glm::dvec2 u = glm::dvec2(x + 0.5, y + 0.5) + prev_jitter;
            glm::dvec2 n = ndc(u);
            glm::dvec3 dir_view(n.x / proj[0][0], n.y / proj[1][1], -1.0);
            glm::dvec3 dir_world = glm::transpose(glm::dmat3(prev_view)) * dir_view;
            prev.depth(x, y) = float(D / -dir_world.z);
            payload.at(x, y) = float(ramp(u));
            // Current frame: identity view, depth D; where that point was in the previous image.
            glm::dvec2 p = glm::dvec2(x + 0.5, y + 0.5) + jitter;
            glm::dvec2 m = ndc(p);
            glm::dvec4 world(m.x / proj[0][0] * D, m.y / proj[1][1] * D, -D, 1.0);
            glm::dvec4 clip = proj * prev_view * world;
            glm::dvec2 there((clip.x / clip.w * 0.5 + 0.5) * w, (0.5 - 0.5 * clip.y / clip.w) * h);
            cur.motion(x, y) = glm::vec2(there - p);
        }
    Buffer out(w, h, 1, kNaN);
    Image<uint8_t> hit(w, h);
    const ReprojectOptions tight{.depth_tolerance = 2e-4f, .match_ids = false};
    ReprojectCounts c = reproject(cur, prev, payload.cview(), out.view(), hit.view(), tight);
    EXPECT_EQ(c.invalid + c.behind + c.other_id, 0u);
    EXPECT_GT(c.hits, std::size_t(w * h) * 8 / 10);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            glm::dvec2 there = glm::dvec2(x + 0.5, y + 0.5) + jitter + glm::dvec2(cur.motion(x, y));
            // Within half a pixel of the border the taps are clamped: nearest, not bilinear.
            glm::dvec2 index = there - prev_jitter - 0.5;
            if (index.x < 0 || index.y < 0 || index.x > w - 1 || index.y > h - 1) continue;
            ASSERT_TRUE(hit(x, y)) << x << "," << y;
            ASSERT_NEAR(out.at(x, y), ramp(there), 1e-4);
        }
    // Ignoring the previous frame's jitter looks up the wrong depth.
    prev.camera.jitter = {0, 0};
    c = reproject(cur, prev, payload.cview(), out.view(), {}, tight);
    EXPECT_LT(c.hits, std::size_t(w * h) / 10);
}

TEST(Reproject, PointsBehindThePreviousCamera) {
    const int w = 8, h = 6;
    Frame prev = make_frame(w, h, 3, {0, 0}), cur = make_frame(w, h, 3, {0, 0});
    cur.camera.projection = glm::perspective(1.0f, 1.0f, 0.1f, 10.0f);
    cur.camera.prev_view = glm::rotate(glm::mat4(1.0f), glm::pi<float>(), glm::vec3(0, 1, 0));
    Buffer payload = random_payload(w, h, 4, 1), out(w, h, 4);
    ReprojectCounts c = reproject(cur, prev, payload.cview(), out.view(), {});
    EXPECT_EQ(c.behind, std::size_t(w * h));
    EXPECT_EQ(c, reproject_reference(cur, prev, payload.cview(), out.view(), {}));
}

TEST(Reproject, IdMismatchMisses) {
    const int w = 20, h = 16;
    Frame prev = make_frame(w, h, 2, {0, 0}), cur = make_frame(w, h, 2, {0, 0});
    for (int y = 4; y < 9; ++y)
        for (int x = 5; x < 12; ++x) prev.id(x, y) = 2;
    Buffer payload = random_payload(w, h, 3, 2), out(w, h, 3);
    ReprojectCounts c = reproject(cur, prev, payload.cview(), out.view(), {});
    EXPECT_EQ(c.other_id, 35u);
    EXPECT_EQ(c.hits, std::size_t(w * h) - 35);
    EXPECT_EQ(reproject(cur, prev, payload.cview(), out.view(), {}, {.match_ids = false}).hits,
              std::size_t(w * h));
    prev.id.clear();  // ids in one frame only: no id test
    EXPECT_EQ(reproject(cur, prev, payload.cview(), out.view(), {}).hits, std::size_t(w * h));
}

TEST(Reproject, DepthTestCatchesAnOccluder) {
    const int w = 24, h = 12, bx = 6, bw = 5, by = 3, bh = 4;
    Frame prev = make_frame(w, h, 4, {0, 0}), cur = make_frame(w, h, 4, {0.5f, 0});
    for (int y = by; y < by + bh; ++y)
        for (int x = bx; x < bx + bw; ++x) {
            prev.depth(x, y) = 2;
            prev.id(x, y) = 9;
        }
    Buffer payload = random_payload(w, h, 4, 5), out(w, h, 4, 0.0f);
    Image<uint8_t> hit(w, h);
    ReprojectCounts c = reproject(cur, prev, payload.cview(), out.view(), hit.view());
    // Half-pixel motion: the column left of the occluder mixes it into its bilinear depth.
    EXPECT_EQ(c.occluded, std::size_t((bw + 1) * bh));
    EXPECT_EQ(c.hits, std::size_t(w * h) - c.occluded);  // the last column looks up q = W: inside
    for (int y = by; y < by + bh; ++y)
        for (int x = bx - 1; x < bx + bw; ++x) {
            EXPECT_EQ(hit(x, y), 0);
            EXPECT_EQ(out.at(x, y, 2), 0.0f);
        }
}

// z_expected assumes a static world; an object that moved 5 % away keeps hitting through its id.
TEST(Reproject, MovingObjectIsCarriedByItsId) {
    const int w = 10, h = 10;
    Frame prev = make_frame(w, h, 10.5f, {0, 0}, 7), cur = make_frame(w, h, 10, {0, 0}, 7);
    Buffer payload = random_payload(w, h, 2, 8), out(w, h, 2);
    EXPECT_EQ(reproject(cur, prev, payload.cview(), out.view(), {}).hits, std::size_t(w * h));
    EXPECT_EQ(reproject(cur, prev, payload.cview(), out.view(), {}, {.match_ids = false}).occluded,
              std::size_t(w * h));
    EXPECT_EQ(reproject(cur, prev, payload.cview(), out.view(), {}, {.id_depth_tolerance = 0.02f})
                  .occluded,
              std::size_t(w * h));
}

TEST(Reproject, BackgroundFollowsBackground) {
    const int w = 9, h = 7;
    Frame prev = make_frame(w, h, kInf, {0, 0}, 0), cur = make_frame(w, h, kInf, {1, 0}, 0);
    prev.depth(4, 3) = 1;
    prev.id(4, 3) = 3;
    Buffer payload = random_payload(w, h, 4, 9), out(w, h, 4);
    ReprojectCounts c = reproject(cur, prev, payload.cview(), out.view(), {});
    EXPECT_EQ(c.offscreen, std::size_t(h));
    EXPECT_EQ(c.occluded, 1u);  // disoccluded sky: the previous frame had geometry there
    EXPECT_EQ(c.hits, std::size_t(w * h - h - 1));
    EXPECT_EQ(out.at(0, 0, 1), payload.at(1, 0, 1));
    c = reproject(cur, prev, payload.cview(), out.view(), {}, {.background = false});
    EXPECT_EQ(c.invalid, std::size_t(w * h));
}

TEST(Reproject, NonFinitePayloadMisses) {
    const int w = 6, h = 5;
    Frame prev = make_frame(w, h, 1, {0, 0}), cur = make_frame(w, h, 1, {0, 0});
    Buffer payload = random_payload(w, h, 4, 10), out(w, h, 4, 0.5f);
    payload.at(2, 2, 3) = kNaN;
    payload.at(4, 1, 0) = kInf;
    Image<uint8_t> hit(w, h);
    ReprojectCounts c = reproject(cur, prev, payload.cview(), out.view(), hit.view());
    EXPECT_EQ(c.invalid, 2u);
    EXPECT_EQ(hit(2, 2), 0);
    EXPECT_EQ(out.at(2, 2, 0), 0.5f);  // a miss leaves the whole pixel as it was
    EXPECT_EQ(out.at(4, 1, 3), 0.5f);
}

// ---------------------------------------------------------------------------------------------
// The fast path against the scalar reference

struct Case {
    const char* name;
    Frame cur, prev;
    Buffer payload;
    ReprojectOptions options;
};

void expect_same(Case& k) {
    SCOPED_TRACE(k.name);
    const int w = k.cur.depth.width(), h = k.cur.depth.height(), c = k.payload.c;
    Buffer a(w, h, c, -3.0f), b(w, h, c, -3.0f);
    Image<uint8_t> hit_a(w, h, 9), hit_b(w, h, 7);
    ReprojectCounts fast =
        reproject(k.cur, k.prev, k.payload.cview(), a.view(), hit_a.view(), k.options);
    ReprojectCounts ref =
        reproject_reference(k.cur, k.prev, k.payload.cview(), b.view(), hit_b.view(), k.options);
    EXPECT_EQ(total(fast), std::size_t(w) * h);
    EXPECT_EQ(fast.hits, ref.hits);
    EXPECT_EQ(fast.offscreen, ref.offscreen);
    EXPECT_EQ(fast.behind, ref.behind);
    EXPECT_EQ(fast.occluded, ref.occluded);
    EXPECT_EQ(fast.other_id, ref.other_id);
    EXPECT_EQ(fast.invalid, ref.invalid);
    EXPECT_TRUE(hit_a == hit_b);
    EXPECT_EQ(0, std::memcmp(a.v.data(), b.v.data(), a.v.size() * sizeof(float)));
    std::size_t hits = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) hits += hit_a(x, y);
    EXPECT_EQ(hits, fast.hits);
}

// Plausible frames: smooth depth with occluder blocks, smooth sub-pixel motion, id patches, a
// moving camera, and a sprinkling of NaN/Inf.
Case random_case(const char* name, int w, int h, int channels, uint32_t seed, bool ortho) {
    std::mt19937 rng(seed);
    Case k{name,
           make_frame(w, h, 0, {0, 0}),
           make_frame(w, h, 0, {0, 0}),
           random_payload(w, h, channels, seed + 1),
           {}};
    Camera& cam = k.cur.camera;
    cam.projection = ortho ? glm::ortho(-4.0f, 4.0f, -3.0f, 3.0f, 0.1f, 50.0f)
                           : glm::perspective(uniform(rng, 0.5f, 1.5f), float(w) / h, 0.1f, 100.0f);
    cam.view =
        glm::translate(glm::mat4(1.0f), glm::vec3(uniform(rng, -1, 1), 0, uniform(rng, -1, 1)));
    cam.prev_view = glm::rotate(glm::translate(cam.view, glm::vec3(0.05f, -0.02f, 0.1f)),
                                uniform(rng, -0.05f, 0.05f), glm::vec3(0, 1, 0));
    cam.jitter = {uniform(rng, -0.5f, 0.5f), uniform(rng, -0.5f, 0.5f)};
    k.prev.camera.jitter = {uniform(rng, -0.5f, 0.5f), uniform(rng, -0.5f, 0.5f)};
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            float z = 5.0f + 2.0f * std::sin(x * 0.1f) * std::cos(y * 0.13f);
            bool block = (x / 7 + y / 5) % 4 == 0;
            k.cur.depth(x, y) = block ? z * 0.5f : z;
            k.prev.depth(x, y) = z * uniform(rng, 0.97f, 1.03f);
            k.cur.id(x, y) = block ? 2 : 1;
            k.prev.id(x, y) = (x / 6 + y / 6) % 5 == 0 ? 2 : 1;
            k.cur.motion(x, y) = {1.5f * std::sin(y * 0.07f) + uniform(rng, -0.5f, 0.5f),
                                  std::cos(x * 0.05f) + uniform(rng, -0.5f, 0.5f)};
            uint32_t r = rng() % 200;
            if (r == 0) k.cur.depth(x, y) = kNaN;
            if (r == 1) k.cur.depth(x, y) = kInf;
            if (r == 2) k.prev.depth(x, y) = kInf;
            if (r == 3) k.cur.motion(x, y).y = kNaN;
            if (r == 4) k.payload.at(x, y, int(rng() % channels)) = kInf;
            if (r == 5) k.cur.depth(x, y) = -1.0f;
            if (r == 6) k.cur.motion(x, y).x = float(x % 3) - 1.0f;  // integer: collapsed taps
        }
    return k;
}

TEST(Reproject, FastMatchesReferenceOnRandomFrames) {
    uint32_t seed = 100;
    for (bool ortho : {false, true})
        for (int channels : {1, 2, 3, 4, 5})
            for (auto [w, h] : std::vector<Size>{{1, 1}, {7, 3}, {64, 48}, {301, 97}}) {
                Case k = random_case("random", w, h, channels, seed++, ortho);
                expect_same(k);
                k.options = {.depth_tolerance = 0.05f, .match_ids = false, .background = false};
                expect_same(k);
            }
}

TEST(Reproject, StepLooksUpOnlyTheSampledPixelsAndAgreesWithTheFullRun) {
    for (int step : {2, 4, 5}) {
        Case k = random_case("step", 301, 97, 4, 900u + unsigned(step), false);
        const int w = 301, h = 97;
        Buffer full(w, h, 4, -3.0f), sampled(w, h, 4, -3.0f), sampled_ref(w, h, 4, -3.0f);
        Image<uint8_t> hit_full(w, h, 9), hit_sampled(w, h, 9), hit_ref(w, h, 9);
        reproject(k.cur, k.prev, k.payload.cview(), full.view(), hit_full.view());
        ReprojectOptions options{.step = step};
        const ReprojectCounts counts = reproject(k.cur, k.prev, k.payload.cview(), sampled.view(),
                                                 hit_sampled.view(), options);
        const ReprojectCounts ref = reproject_reference(
            k.cur, k.prev, k.payload.cview(), sampled_ref.view(), hit_ref.view(), options);
        EXPECT_EQ(counts, ref);
        EXPECT_TRUE(hit_sampled == hit_ref);
        EXPECT_EQ(0, std::memcmp(sampled.v.data(), sampled_ref.v.data(),
                                 sampled.v.size() * sizeof(float)));
        std::size_t looked = 0, hits = 0;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const bool on = x % step == 0 && y % step == 0;
                if (!on) {  // untouched
                    ASSERT_EQ(hit_sampled(x, y), 9) << x << "," << y;
                    ASSERT_EQ(sampled.at(x, y, 0), -3.0f);
                    continue;
                }
                ++looked;
                hits += hit_full(x, y);
                ASSERT_EQ(hit_sampled(x, y), hit_full(x, y)) << x << "," << y;
                if (hit_full(x, y)) {
                    for (int c = 0; c < 4; ++c) ASSERT_EQ(sampled.at(x, y, c), full.at(x, y, c));
                }
            }
        EXPECT_EQ(total(counts), looked);
        EXPECT_EQ(counts.hits, hits);
        EXPECT_GT(hits, 0u);
    }
}

TEST(Reproject, FastMatchesReferenceOnWorstCases) {
    std::vector<Case> cases;
    auto add = [&](const char* name, auto&& edit) {
        Case k = random_case(name, 53, 41, 4, uint32_t(cases.size() + 7), false);
        edit(k);
        cases.push_back(std::move(k));
    };
    auto fill = [](auto& image, auto value) {
        for (int y = 0; y < image.height(); ++y)
            for (int x = 0; x < image.width(); ++x) image(x, y) = value;
    };
    add("NaN everywhere", [&](Case& k) {
        fill(k.cur.depth, kNaN);
        fill(k.prev.depth, kNaN);
        fill(k.cur.motion, glm::vec2(kNaN));
        std::fill(k.payload.v.begin(), k.payload.v.end(), kNaN);
    });
    add("NaN payload", [&](Case& k) { std::fill(k.payload.v.begin(), k.payload.v.end(), kNaN); });
    add("Inf everywhere", [&](Case& k) {
        fill(k.cur.depth, kInf);
        fill(k.prev.depth, kInf);
        fill(k.cur.motion, glm::vec2(kInf, -kInf));
        std::fill(k.payload.v.begin(), k.payload.v.end(), kInf);
    });
    add("background everywhere", [&](Case& k) {
        fill(k.cur.depth, kInf);
        fill(k.prev.depth, kInf);
        fill(k.cur.id, 0u);
        fill(k.prev.id, 0u);
    });
    add("motion 1e4", [&](Case& k) { fill(k.cur.motion, glm::vec2(1e4f, -1e4f)); });
    add("motion +1e30", [&](Case& k) { fill(k.cur.motion, glm::vec2(1e30f, 0.25f)); });
    add("motion -1e30", [&](Case& k) { fill(k.cur.motion, glm::vec2(0.25f, -1e30f)); });
    add("motion FLT_MAX", [&](Case& k) { fill(k.cur.motion, glm::vec2(FLT_MAX, -FLT_MAX)); });
    add("behind (previous camera turned around)", [&](Case& k) {
        k.cur.camera.prev_view =
            glm::rotate(k.cur.camera.view, glm::pi<float>(), glm::vec3(0, 1, 0));
    });
    add("near/far 1e6", [&](Case& k) {
        k.cur.camera.projection = glm::perspective(1.0f, 1.3f, 1e-3f, 1e3f);
        std::mt19937 rng(5);
        for (int y = 0; y < 41; ++y)
            for (int x = 0; x < 53; ++x) {
                float z = std::pow(10.0f, uniform(rng, -3.0f, 3.0f));
                k.cur.depth(x, y) = z;
                k.prev.depth(x, y) = z * uniform(rng, 0.99f, 1.01f);
            }
    });
    add("huge depths", [&](Case& k) { fill(k.cur.depth, 3e38f); });
    add("all miss (previous depth elsewhere)", [&](Case& k) { fill(k.prev.depth, 1e-3f); });
    add("degenerate projection", [&](Case& k) { k.cur.camera.projection = glm::mat4(0.0f); });
    add("non-finite view", [&](Case& k) { k.cur.camera.view[3][0] = kNaN; });
    add("projective last row", [&](Case& k) { k.cur.camera.projection[0][3] = 0.5f; });
    add("previous smaller", [&](Case& k) {
        k.prev = make_frame(20, 9, 5, {0, 0});
        k.payload = random_payload(20, 9, 4, 77);
    });
    add("no ids", [&](Case& k) {
        k.cur.id.clear();
        k.prev.id.clear();
    });
    for (Case& k : cases) expect_same(k);
}

TEST(Reproject, TinyImages) {
    for (auto [w, h] : std::vector<Size>{{1, 1}, {7, 3}, {3, 7}, {1, 9}}) {
        for (float m : {0.0f, 0.49f, -0.5f, 0.5f, 1.0f, 3.0f}) {
            Frame prev = make_frame(w, h, 1, {0, 0}), cur = make_frame(w, h, 1, {m, m});
            Buffer payload = random_payload(w, h, 4, 4), out(w, h, 4);
            Case k{"tiny", cur, prev, payload, {}};
            expect_same(k);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Refresh policies (Nehab §5)

TEST(Refresh, EveryPixelOncePerPeriod) {
    for (Refresh policy : {Refresh::Tiled, Refresh::Random2x2, Refresh::Interleaved})
        for (auto [w, h] : std::vector<Size>{{64, 48}, {33, 17}, {7, 3}, {1, 1}, {2, 200}})
            for (int n : {1, 2, 3, 4, 7, 16})
                for (int64_t t0 : {int64_t(0), int64_t(-5), int64_t(1000000000003)}) {
                    SCOPED_TRACE(testing::Message() << int(policy) << " " << w << "x" << h
                                                    << " n=" << n << " t0=" << t0);
                    Image<int> count(w, h, 0);
                    Image<uint8_t> mask(w, h);
                    for (int64_t t = t0; t < t0 + n; ++t) {
                        refresh_mask(policy, n, t, mask.view());
                        std::size_t on = 0;
                        for (int y = 0; y < h; ++y)
                            for (int x = 0; x < w; ++x) {
                                ASSERT_LE(mask(x, y), 1);
                                count(x, y) += mask(x, y);
                                on += mask(x, y);
                            }
                        // Interleaved: one pixel; Random2x2: one block (even sizes); Tiled: a row
                        // and a column of rounding in the tile's size.
                        double slack = 1.0;
                        if (policy == Refresh::Random2x2)
                            slack = w % 2 == 0 && h % 2 == 0 ? 4.0 : 1e9;
                        if (policy == Refresh::Tiled) slack = w + h + 1.0;
                        EXPECT_LE(std::abs(double(on) - double(w) * h / n), slack);
                    }
                    for (int y = 0; y < h; ++y)
                        for (int x = 0; x < w; ++x) ASSERT_EQ(count(x, y), 1) << x << "," << y;
                }
}

TEST(Refresh, ShapesOfTheRegions) {
    const int w = 48, h = 32, n = 6;
    Image<uint8_t> mask(w, h);
    for (int t = 0; t < n; ++t) {
        refresh_mask(Refresh::Tiled, n, t, mask.view());
        int x0 = w, x1 = -1, y0 = h, y1 = -1, on = 0;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x)
                if (mask(x, y)) {
                    x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y),
                    y1 = std::max(y1, y);
                    ++on;
                }
        EXPECT_EQ(on, (x1 - x0 + 1) * (y1 - y0 + 1)) << "tile " << t << " is a rectangle";
        EXPECT_EQ(on, w * h / n);
        refresh_mask(Refresh::Random2x2, n, t, mask.view(), 42);
        for (int y = 0; y < h; y += 2)
            for (int x = 0; x < w; x += 2) {
                ASSERT_EQ(mask(x, y), mask(x + 1, y));
                ASSERT_EQ(mask(x, y), mask(x, y + 1));
                ASSERT_EQ(mask(x, y), mask(x + 1, y + 1));
            }
    }
    Image<uint8_t> other(w, h);
    refresh_mask(Refresh::Random2x2, n, 0, mask.view(), 1);
    refresh_mask(Refresh::Random2x2, n, 0, other.view(), 2);
    EXPECT_FALSE(mask == other) << "the seed changes the pattern";
    refresh_mask(Refresh::None, n, 0, mask.view());
    EXPECT_TRUE(mask == Image<uint8_t>(w, h, 0));
    refresh_mask(Refresh::Interleaved, 1, 12345, mask.view());
    EXPECT_TRUE(mask == Image<uint8_t>(w, h, 1));
}

// ---------------------------------------------------------------------------------------------
// Amortized sampling (Nehab §6)

// One frame of a still scene: reproject the history, then blend the new sample in.
struct StillLoop {
    int w, h, c;
    Frame prev, cur;
    Buffer history, reprojected, sample;
    Image<uint8_t> hit;
    StillLoop(int width, int height, int channels, glm::vec2 motion = {0, 0})
        : w(width),
          h(height),
          c(channels),
          prev(make_frame(w, h, 1, {0, 0})),
          cur(make_frame(w, h, 1, motion)),
          history(w, h, c),
          reprojected(w, h, c),
          sample(w, h, c),
          hit(w, h) {}
    void step(float alpha) {
        reproject(cur, prev, history.cview(), reprojected.view(), hit.view(), {});
        accumulate(sample.cview(), reprojected.cview(), hit.view(), alpha, {}, history.view());
    }
};

TEST(Amortized, StationaryVarianceOfWhiteNoise) {
    for (float alpha : {0.1f, 0.25f, 0.6f}) {
        StillLoop loop(16, 1, 1);
        std::mt19937 rng(1234);
        const int burn_in = int(40 / alpha), frames = 10000;
        double sum = 0, sum2 = 0, noise_sum = 0, noise_sum2 = 0;
        std::size_t count = 0;
        for (int t = 0; t < burn_in + frames; ++t) {
            for (float& s : loop.sample.v) s = uniform(rng, -1.0f, 1.0f);
            loop.step(alpha);
            if (t < burn_in) continue;
            for (std::size_t i = 0; i < loop.history.v.size(); ++i) {
                double f = loop.history.v[i], s = loop.sample.v[i];
                sum += f, sum2 += f * f, noise_sum += s, noise_sum2 += s * s;
                ++count;
            }
        }
        ASSERT_GE(count, 100000u);
        double var = sum2 / count - (sum / count) * (sum / count);
        double noise_var = noise_sum2 / count - (noise_sum / count) * (noise_sum / count);
        double expected = alpha / (2.0 - alpha);
        EXPECT_NEAR(var / noise_var / expected, 1.0, 0.05) << "alpha " << alpha;
    }
}

// Bilinear resampling of a constant sub-pixel pan v spreads an impulse into a binomial kernel with
// variance n v (1 - v) after n frames (STAR §4.2).
TEST(Amortized, RepeatedResamplingBlur) {
    const int w = 96, h = 3;
    for (float v : {0.25f, 0.5f, 0.7f})
        for (int n : {1, 4, 16}) {
            Frame prev = make_frame(w, h, 2, {0, 0}), cur = make_frame(w, h, 2, {v, 0});
            Buffer a(w, h, 1), b(w, h, 1);
            a.at(w / 2, 1) = 1.0f;
            for (int i = 0; i < n; ++i) {
                b = a;
                reproject(cur, prev, a.cview(), b.view(), {});
                std::swap(a, b);
            }
            double mass = 0, mean = 0, m2 = 0;
            for (int x = 0; x < w; ++x) mass += a.at(x, 1), mean += x * double(a.at(x, 1));
            mean /= mass;
            for (int x = 0; x < w; ++x) m2 += (x - mean) * (x - mean) * a.at(x, 1);
            m2 /= mass;
            EXPECT_NEAR(mass, 1.0, 1e-5);
            EXPECT_NEAR(mean, w / 2 - n * v, 1e-4);
            EXPECT_NEAR(m2 / (n * v * (1 - v)), 1.0, 0.05) << "v " << v << " n " << n;
        }
}

TEST(Amortized, TinyAlphaDoesNotDrift) {
    for (float value : {0.7f, 123.456f, 1e-3f, -3.3f}) {
        StillLoop loop(8, 4, 3,
                       {0.37f, -0.21f});  // a sub-pixel pan: resampling of a constant is exact
        std::fill(loop.sample.v.begin(), loop.sample.v.end(), value);
        loop.step(1.0f);
        for (int t = 0; t < 10000; ++t) loop.step(1e-4f);
        double drift = 0;
        for (float f : loop.history.v) drift = std::max(drift, std::abs(double(f) - value));
        EXPECT_LT(drift, 1e-6) << value;
    }
}

TEST(Amortized, DecayToZeroWithoutDenormals) {
    StillLoop loop(4, 4, 1);
    std::fill(loop.history.v.begin(), loop.history.v.end(), 1.0f);
    for (int t = 0; t < 400; ++t) {
        loop.step(0.5f);
        for (float f : loop.history.v) ASSERT_NE(std::fpclassify(f), FP_SUBNORMAL) << t;
    }
    for (float f : loop.history.v) EXPECT_EQ(f, 0.0f);
}

TEST(Amortized, RestartsAndPerPixelAlpha) {
    const int w = 4, h = 1;
    Buffer sample(w, h, 2, 1.0f), history(w, h, 2, 3.0f), out(w, h, 2);
    history.at(2, 0, 1) = kNaN;
    Image<uint8_t> hit(w, h, 1);
    hit(1, 0) = 0;
    Image<float> alphas(w, h, 0.25f);
    alphas(3, 0) = kNaN;
    accumulate(sample.cview(), history.cview(), hit.view(), 0.5f, alphas.view(), out.view());
    EXPECT_EQ(out.at(0, 0, 0), 2.5f);  // 3 + 0.25 (1 - 3)
    EXPECT_EQ(out.at(1, 0, 0), 1.0f);  // miss: restart
    EXPECT_EQ(out.at(2, 0, 0), 2.5f);
    EXPECT_EQ(out.at(2, 0, 1), 1.0f);  // non-finite history: restart
    EXPECT_EQ(out.at(3, 0, 0), 1.0f);  // NaN alpha counts as 1
    accumulate(sample.cview(), history.cview(), {}, 0.5f, {}, out.view());
    EXPECT_EQ(out.at(1, 0, 0), 2.0f);  // no hit mask: every pixel continues its history
}

}  // namespace
