// The warp kernels' cases (warp/src/kernels.hpp and the public reprojection and splat entry
// points): random frames and their worst cases.
#include <algorithm>
#include <atomic>
#include <cmath>
#include <optional>
#include <utility>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "generators.hpp"
#include "reprise/core/camera_math.hpp"
#include "reprise/core/frame.hpp"
#include "reprise/core/parallel.hpp"
#include "reprise/warp/reproject.hpp"
#include "reprise/warp/splat.hpp"
#include "warp/src/kernels.hpp"

namespace reprise::kernels {

namespace {

using namespace reprise::warp;

// ---------------------------------------------------------------------------------------------

class BlendCase final : public KernelCase {
public:
    void generate(int w, int h, KernelInputs inputs, uint32_t seed) override {
        std::mt19937 rng(seed);
        width_ = w, height_ = h;
        const std::size_t n = std::size_t(w) * std::size_t(h);
        covered_a_.resize(n), covered_b_.resize(n), depth_a_.resize(n), color_a_.resize(n);
        motion_a_.resize(n), depth_b_.resize(n), color_b_.resize(n), motion_b_.resize(n);
        const bool worst = inputs == KernelInputs::WorstCase;
        s_ = uniform(rng, 0.05f, 0.95f);
        scale_ = worst ? -1e30f : uniform(rng, 0.5f, 2.0f);
        for (std::size_t i = 0; i < n; ++i) {
            // 0, 1 or kCoveredStretched (a: any byte in the worst case)
            covered_a_[i] = uint8_t(rng() % 8 ? (worst ? 1 + rng() % 255 : 1 + rng() % 2) : 0);
            covered_b_[i] = uint8_t(rng() % 8 ? 1 + rng() % 2 : 0);
            const float z = uniform(rng, 0.5f, 50.0f);
            depth_a_[i] = z;
            switch (rng() % 4) {  // same surface, nearer, farther, background on both
                case 0:
                    depth_b_[i] = z * uniform(rng, 0.8f, 1.2f);
                    break;  // about the kSameSurface line
                case 1:
                    depth_b_[i] = z * 0.5f;
                    break;
                case 2:
                    depth_b_[i] = z * 2.0f;
                    break;
                default:
                    depth_a_[i] = depth_b_[i] = kInf;
                    break;
            }
            for (int c = 0; c < 4; ++c) {
                color_a_[i][c] = uniform(rng, 0.0f, 4.0f);
                color_b_[i][c] = uniform(rng, 0.0f, 4.0f);
            }
            motion_a_[i] = {uniform(rng, -20, 20), uniform(rng, -20, 20)};
            motion_b_[i] = {uniform(rng, -20, 20), uniform(rng, -20, 20)};
            if (!worst || rng() % 3) continue;
            switch (rng() % 5) {
                case 0:
                    depth_a_[i] = worst_value(rng);
                    break;
                case 1:
                    depth_b_[i] = worst_value(rng);
                    break;
                case 2:
                    color_a_[i][int(rng() % 4)] = worst_value(rng);
                    break;
                case 3:
                    motion_a_[i][int(rng() % 2)] = worst_value(rng);
                    break;
                default:
                    depth_a_[i] = rng() % 2 ? 0.0f : -0.0f;
                    depth_b_[i] = rng() % 2 ? 0.0f : -0.0f;
            }
        }
    }
    // b is blended in place: the outputs start as b.
    void reset() override { start(optimized_); }
    void reset_reference() override { start(reference_); }
    void run_reference() override { run_into(reference_, blend_row_reference); }
    void run() override { run_into(optimized_, blend_row); }
    std::string compare() const override {
        if (optimized_.holes != reference_.holes)
            return "holes " + std::to_string(optimized_.holes) + ", reference " +
                   std::to_string(reference_.holes);
        if (optimized_.valid != reference_.valid) return "valid differs";
        std::string d = compare_floats("colour", optimized_.color, reference_.color);
        if (d.empty()) d = compare_floats("depth", optimized_.depth, reference_.depth);
        if (d.empty()) d = compare_floats("motion", optimized_.motion, reference_.motion);
        return d;
    }

private:
    struct Output {
        std::vector<float> depth;
        std::vector<glm::vec4> color;
        std::vector<glm::vec2> motion;
        std::vector<uint8_t> valid;
        std::size_t holes = 0;
    };
    void start(Output& out) const {
        out.depth = depth_b_, out.color = color_b_, out.motion = motion_b_;
        out.valid.resize(depth_b_.size());
    }
    template <class Kernel>
    void run_into(Output& out, Kernel kernel) {
        std::atomic<std::size_t> holes{0};
        const int w = width_;
        parallel_for(0, height_, [&](int y0, int y1) {
            std::size_t local = 0;
            for (int y = y0; y < y1; ++y) {
                const std::size_t o = std::size_t(y) * std::size_t(w);
                local += kernel({.covered_a = covered_a_.data() + o,
                                 .covered_b = covered_b_.data() + o,
                                 .depth_a = depth_a_.data() + o,
                                 .color_a = color_a_.data() + o,
                                 .motion_a = motion_a_.data() + o,
                                 .depth = out.depth.data() + o,
                                 .color = out.color.data() + o,
                                 .motion = out.motion.data() + o,
                                 .valid = out.valid.data() + o,
                                 .width = w,
                                 .s = s_,
                                 .motion_scale = scale_});
            }
            holes += local;
        });
        out.holes = holes.load();
    }

    int width_ = 0, height_ = 0;
    float s_ = 0.5f, scale_ = 1.0f;
    std::vector<uint8_t> covered_a_, covered_b_;
    std::vector<float> depth_a_, depth_b_;
    std::vector<glm::vec4> color_a_, color_b_;
    std::vector<glm::vec2> motion_a_, motion_b_;
    Output reference_, optimized_;
};

// ---------------------------------------------------------------------------------------------

class StaticLayerCase final : public KernelCase {
public:
    void generate(int w, int h, KernelInputs inputs, uint32_t seed) override {
        std::mt19937 rng(seed);
        width_ = w, height_ = h;
        const bool worst = inputs == KernelInputs::WorstCase;
        // Worst case: the previous camera moved far forward, so near points are behind it.
        const Camera c = random_camera(rng, w, h, seed % 3 == 2, worst ? 60.0f : 1.0f);
        const StaticReprojection previous = camera_only_motion(c, w, h);
        const glm::mat4 future_view = glm::translate(
            c.view, glm::vec3(uniform(rng, -0.1f, 0.1f), 0.0f, uniform(rng, -0.1f, 0.1f)));
        const StaticReprojection future(c, future_view, c.projection, w, h);
        test_.emplace(previous, future, w, h, uniform(rng, 0.25f, 1.0f));
        const std::size_t n = std::size_t(w) * std::size_t(h);
        depth_.resize(n), motion_.resize(n);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const std::size_t i = std::size_t(y) * std::size_t(w) + std::size_t(x);
                float z = rng() % 10 == 0 ? kInf : uniform(rng, 0.2f, 60.0f);
                const glm::vec2 p(float(x) + 0.5f, float(y) + 0.5f);
                glm::vec2 before(0.0f);
                const bool lands = previous.land(p.x, p.y, z, before);
                // Most pixels static (their motion is the camera's, give or take), some moving.
                glm::vec2 m = lands && rng() % 4
                                  ? before - p
                                  : glm::vec2(uniform(rng, -30, 30), uniform(rng, -30, 30));
                m += glm::vec2(uniform(rng, -0.3f, 0.3f), uniform(rng, -0.3f, 0.3f));
                if (worst && rng() % 3 == 0 && !spoil_depth_or_motion(rng, rng() % 4, z, m))
                    z = -uniform(rng, 0.1f, 10.0f);  // behind this camera
                depth_[i] = z, motion_[i] = m;
            }
    }
    void run_reference() override {
        run_into(reference_, [](const StaticLayerTest& t, int y, int width, const float* d,
                                const glm::vec2* m, float* d_out, glm::vec2* m_out) {
            return static_layer_row_reference(t, y, 0, width, d, m, d_out, m_out);
        });
    }
    void run() override { run_into(optimized_, static_layer_row); }
    std::string compare() const override {
        if (optimized_.dynamic != reference_.dynamic)
            return "moving pixels " + std::to_string(optimized_.dynamic) + ", reference " +
                   std::to_string(reference_.dynamic);
        std::string d = compare_floats("depth", optimized_.depth, reference_.depth);
        if (d.empty()) d = compare_floats("motion", optimized_.motion, reference_.motion);
        return d;
    }

private:
    struct Output {
        std::vector<float> depth;
        std::vector<glm::vec2> motion;
        std::size_t dynamic = 0;
    };
    template <class Kernel>
    void run_into(Output& out, Kernel kernel) {
        out.depth.resize(depth_.size()), out.motion.resize(motion_.size());
        std::atomic<std::size_t> dynamic{0};
        const int w = width_;
        parallel_for(0, height_, [&](int y0, int y1) {
            std::size_t local = 0;
            for (int y = y0; y < y1; ++y) {
                const std::size_t o = std::size_t(y) * std::size_t(w);
                local += kernel(*test_, y, w, depth_.data() + o, motion_.data() + o,
                                out.depth.data() + o, out.motion.data() + o);
            }
            dynamic += local;
        });
        out.dynamic = dynamic.load();
    }

    int width_ = 0, height_ = 0;
    std::optional<StaticLayerTest> test_;
    std::vector<float> depth_;
    std::vector<glm::vec2> motion_;
    Output reference_, optimized_;
};

// ---------------------------------------------------------------------------------------------

// Pull-push's first pull (image -> level 1), every coarse row, with and without depth.
class PullCase final : public KernelCase {
public:
    void generate(int w, int h, KernelInputs inputs, uint32_t seed) override {
        std::mt19937 rng(seed);
        const bool worst = inputs == KernelInputs::WorstCase;
        width_ = w, height_ = h;
        use_depth_ = seed % 4 != 3;
        const std::size_t n = std::size_t(w) * std::size_t(h);
        color_.resize(n), valid_.resize(n), depth_.resize(n);
        for (std::size_t i = 0; i < n; ++i) {
            const int x = int(i % std::size_t(w)), y = int(i / std::size_t(w));
            // A few percent holes: disocclusion strips beside depth edges, and single pixels;
            // worst case: a third of the pixels, and depth edges everywhere.
            const bool strip =
                worst ? (x / 3 + y / 2) % 3 == 0 : (x / 48 + y / 32) % 11 == 0 && x % 48 < 6;
            valid_[i] = uint8_t(strip || rng() % 64 == 0 ? 0 : worst ? 1 + rng() % 255 : 1);
            for (int c = 0; c < 4; ++c) color_[i][c] = uniform(rng, 0.0f, 4.0f);
            const float base = ((worst ? x / 2 : x / 48) + y / 32) % 3 == 0 ? 2.0f : 20.0f;
            depth_[i] = y < h / 8 ? kInf : base * uniform(rng, 0.95f, 1.15f);
            if (!worst || rng() % 3) continue;
            switch (rng() % 3) {
                case 0:
                    color_[i][int(rng() % 4)] = worst_value(rng);
                    break;
                case 1:
                    depth_[i] = worst_value(rng);
                    break;
                default:
                    color_[i] = glm::vec4(3e38f);
                    break;  // finite, the sum of four is not
            }
        }
    }
    void run_reference() override {
        run_into(reference_,
                 [](const PullRow& r) { return pull_row_reference(r, 0, (r.fine_width + 1) / 2); });
    }
    void run() override { run_into(optimized_, pull_row); }
    std::string compare() const override {
        if (optimized_.holes != reference_.holes || optimized_.empty != reference_.empty)
            return "counts differ";
        if (optimized_.bits != reference_.bits) return "hole bits differ";
        std::string d = compare_floats("level 1", optimized_.color, reference_.color);
        if (d.empty()) d = compare_floats("level 1 depth", optimized_.depth, reference_.depth);
        return d;
    }

private:
    struct Output {
        std::vector<glm::vec4> color;
        std::vector<float> depth;
        std::vector<uint8_t> bits;
        std::size_t holes = 0, empty = 0;
    };
    template <class Kernel>
    void run_into(Output& out, Kernel kernel) {
        const int w = width_, h = height_, cw = (w + 1) / 2, ch = (h + 1) / 2;
        const std::size_t cn = std::size_t(cw) * std::size_t(ch);
        out.color.resize(cn), out.depth.resize(use_depth_ ? cn : 0), out.bits.resize(cn);
        std::atomic<std::size_t> holes{0}, empty{0};
        parallel_for(0, ch, [&](int j0, int j1) {
            PullCounts local;
            for (int j = j0; j < j1; ++j) {
                const int y0 = 2 * j, y1 = std::min(y0 + 1, h - 1);
                const std::size_t o0 = std::size_t(y0) * std::size_t(w),
                                  o1 = std::size_t(y1) * std::size_t(w);
                const std::size_t oc = std::size_t(j) * std::size_t(cw);
                const PullCounts c =
                    kernel({.row0 = color_.data() + o0,
                            .row1 = color_.data() + o1,
                            .valid0 = valid_.data() + o0,
                            .valid1 = valid_.data() + o1,
                            .depth0 = use_depth_ ? depth_.data() + o0 : nullptr,
                            .depth1 = use_depth_ ? depth_.data() + o1 : nullptr,
                            .fine_width = w,
                            .rows = y1 - y0 + 1,
                            .out = out.color.data() + oc,
                            .out_depth = use_depth_ ? out.depth.data() + oc : nullptr,
                            .hole_bits = out.bits.data() + oc});
                local.holes += c.holes, local.empty += c.empty;
            }
            holes += local.holes, empty += local.empty;
        });
        out.holes = holes.load(), out.empty = empty.load();
    }

    int width_ = 0, height_ = 0;
    bool use_depth_ = true;
    std::vector<glm::vec4> color_;
    std::vector<uint8_t> valid_;
    std::vector<float> depth_;
    Output reference_, optimized_;
};

// ---------------------------------------------------------------------------------------------

// Pull-push's coarser pulls: one level from the one below (weights in alpha, depth sanitised).
class PullLevelCase final : public KernelCase {
public:
    void generate(int w, int h, KernelInputs inputs, uint32_t seed) override {
        std::mt19937 rng(seed);
        const bool worst = inputs == KernelInputs::WorstCase;
        width_ = w, height_ = h;
        use_depth_ = seed % 4 != 3;
        const std::size_t n = std::size_t(w) * std::size_t(h);
        level_.resize(n), depth_.resize(n);
        for (std::size_t i = 0; i < n; ++i) {
            const int x = int(i % std::size_t(w)), y = int(i / std::size_t(w));
            const bool partial =
                worst ? rng() % 3 == 0
                      : ((x / 24 + y / 16) % 11 == 0 && x % 24 < 4) || rng() % 97 == 0;
            const float weight = !partial ? 1.0f : rng() % 2 ? 0.0f : uniform(rng, 0.25f, 1.0f);
            for (int c = 0; c < 3; ++c) level_[i][c] = weight * uniform(rng, 0.0f, 4.0f);
            level_[i].a = weight;
            const float base = ((worst ? x / 2 : x / 24) + y / 16) % 3 == 0 ? 2.0f : 20.0f;
            depth_[i] = y < h / 8        ? kInf
                        : weight == 0.0f ? 0.0f
                                         : base * uniform(rng, 0.95f, 1.15f);
            if (worst && rng() % 5 == 0) level_[i][int(rng() % 3)] = rng() % 2 ? 3e38f : -0.0f;
            if (worst && rng() % 7 == 0) level_[i].a = std::nextafter(1.0f, 0.0f);
        }
    }
    void run_reference() override {
        run_into(reference_, [](const PullLevelRow& r) {
            return pull_level_row_reference(r, 0, (r.fine_width + 1) / 2);
        });
    }
    void run() override { run_into(optimized_, pull_level_row); }
    std::string compare() const override {
        if (optimized_.empty != reference_.empty) return "empty counts differ";
        std::string d = compare_floats("level", optimized_.color, reference_.color);
        if (d.empty()) d = compare_floats("level depth", optimized_.depth, reference_.depth);
        return d;
    }

private:
    struct Output {
        std::vector<glm::vec4> color;
        std::vector<float> depth;
        std::size_t empty = 0;
    };
    template <class Kernel>
    void run_into(Output& out, Kernel kernel) {
        const int w = width_, h = height_, cw = (w + 1) / 2, ch = (h + 1) / 2;
        const std::size_t cn = std::size_t(cw) * std::size_t(ch);
        out.color.resize(cn), out.depth.resize(use_depth_ ? cn : 0);
        std::atomic<std::size_t> empty{0};
        parallel_for(0, ch, [&](int j0, int j1) {
            std::size_t local = 0;
            for (int j = j0; j < j1; ++j) {
                const int y0 = 2 * j, y1 = std::min(y0 + 1, h - 1);
                const std::size_t o0 = std::size_t(y0) * std::size_t(w),
                                  o1 = std::size_t(y1) * std::size_t(w);
                const std::size_t oc = std::size_t(j) * std::size_t(cw);
                local += kernel({.row0 = level_.data() + o0,
                                 .row1 = level_.data() + o1,
                                 .depth0 = use_depth_ ? depth_.data() + o0 : nullptr,
                                 .depth1 = use_depth_ ? depth_.data() + o1 : nullptr,
                                 .fine_width = w,
                                 .rows = y1 - y0 + 1,
                                 .out = out.color.data() + oc,
                                 .out_depth = use_depth_ ? out.depth.data() + oc : nullptr});
            }
            empty += local;
        });
        out.empty = empty.load();
    }

    int width_ = 0, height_ = 0;
    bool use_depth_ = true;
    std::vector<glm::vec4> level_;
    std::vector<float> depth_;
    Output reference_, optimized_;
};

// ---------------------------------------------------------------------------------------------

// Reverse reprojection of an RGBA payload: the SSE2 path (threaded) against the scalar reference.
class ReprojectCase final : public KernelCase {
public:
    void generate(int w, int h, KernelInputs inputs, uint32_t seed) override {
        std::mt19937 rng(seed);
        const bool worst = inputs == KernelInputs::WorstCase;
        for (Frame* f : {&current_, &previous_}) {
            f->depth.assign(w, h, 1.0f);
            f->motion.assign(w, h, glm::vec2(0.0f));
            f->id.assign(w, h, 1u);
        }
        current_.camera = random_camera(rng, w, h, seed % 3 == 2, worst ? 60.0f : 1.0f);
        options_ = {.match_ids = seed % 2 == 0, .background = seed % 5 != 4};
        payload_.assign(w, h, glm::vec4(0.0f));
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const float z =
                    5.0f + 2.0f * std::sin(float(x) * 0.1f) * std::cos(float(y) * 0.13f);
                const bool block = (x / 7 + y / 5) % 4 == 0;
                current_.depth(x, y) = block ? z * 0.5f : z;
                previous_.depth(x, y) = z * uniform(rng, 0.97f, 1.03f);
                current_.id(x, y) = block ? 2 : 1;
                previous_.id(x, y) = (x / 6 + y / 6) % 5 == 0 ? 2 : 1;
                current_.motion(x, y) = {
                    1.5f * std::sin(float(y) * 0.07f) + uniform(rng, -0.5f, 0.5f),
                    std::cos(float(x) * 0.05f) + uniform(rng, -0.5f, 0.5f)};
                for (int c = 0; c < 4; ++c) payload_(x, y)[c] = uniform(rng, -4.0f, 4.0f);
                if (!worst || rng() % 3) continue;
                switch (rng() % 6) {
                    case 0:
                        current_.depth(x, y) = worst_value(rng);
                        break;
                    case 1:
                        previous_.depth(x, y) = worst_value(rng);
                        break;
                    case 2:
                        current_.motion(x, y)[int(rng() % 2)] = worst_value(rng);
                        break;
                    case 3:
                        current_.motion(x, y) = {1e30f, -1e30f};
                        break;
                    case 4:
                        payload_(x, y)[int(rng() % 4)] = worst_value(rng);
                        break;
                    default:
                        current_.depth(x, y) = kInf, previous_.depth(x, y) = kInf;
                }
            }
    }
    // A miss leaves its pixel as it was.
    void reset() override { start(optimized_out_, optimized_hit_); }
    void reset_reference() override { start(reference_out_, reference_hit_); }
    void run_reference() override { reference_ = run_into(reference_out_, reproject_reference); }
    void run() override { optimized_ = run_into(optimized_out_, reproject); }
    std::string compare() const override {
        if (!(optimized_ == reference_)) return "counts differ";
        if (!(optimized_hit_ == reference_hit_)) return "hits differ";
        std::vector<glm::vec4> a(optimized_out_.data(),
                                 optimized_out_.data() + optimized_out_.pixel_count());
        std::vector<glm::vec4> b(reference_out_.data(),
                                 reference_out_.data() + reference_out_.pixel_count());
        return compare_floats("payload", a, b);
    }

private:
    void start(Image<glm::vec4>& out, Image<uint8_t>& hit) const {
        out.assign(payload_.width(), payload_.height(), glm::vec4(-3.0f));
        hit.assign(payload_.width(), payload_.height(), 0);
    }
    template <class Kernel>
    ReprojectCounts run_into(Image<glm::vec4>& out, Kernel kernel) {
        Image<uint8_t>& hit = &out == &optimized_out_ ? optimized_hit_ : reference_hit_;
        return kernel(current_, previous_, payload_of(std::as_const(payload_).view()),
                      payload_of(out.view()), hit.view(), options_);
    }

    Frame current_, previous_;
    ReprojectOptions options_;
    Image<glm::vec4> payload_, optimized_out_, reference_out_;
    Image<uint8_t> optimized_hit_, reference_hit_;
    ReprojectCounts optimized_, reference_;
};

class DisplacementCase final : public KernelCase {
public:
    void generate(int w, int h, KernelInputs inputs, uint32_t seed) override {
        std::mt19937 rng(seed);
        width_ = w, height_ = h;
        const bool worst = inputs == KernelInputs::WorstCase;
        // An eye a few centimetres aside; worst case: a target far ahead, so near points are
        // behind it.
        const Camera c = random_camera(rng, w, h, seed % 3 == 2, 1.0f);
        const glm::mat4 target_view =
            glm::translate(c.view, worst ? glm::vec3(0.3f, 0.0f, 30.0f)
                                         : glm::vec3(uniform(rng, -0.1f, 0.1f), 0.0f, 0.0f));
        test_.emplace(StaticReprojection(c, target_view, c.projection, w, h), w, h);
        depth_.resize(std::size_t(w) * std::size_t(h));
        for (float& z : depth_) {
            z = rng() % 10 == 0 ? kInf : uniform(rng, 0.2f, 60.0f);
            if (worst && rng() % 3 == 0)
                z = rng() % 2 ? worst_value(rng) : -uniform(rng, 0.1f, 10.0f);
        }
    }
    void run_reference() override {
        run_into(reference_, [](const DisplacementTest& t, int y, int width, const float* d,
                                glm::vec2* out, float* out_depth) {
            displacement_row_reference(t, y, 0, width, d, out, out_depth);
        });
    }
    void run() override { run_into(optimized_, displacement_row); }
    std::string compare() const override {
        std::string d =
            compare_floats("displacement", optimized_.displacement, reference_.displacement);
        if (d.empty()) d = compare_floats("target depth", optimized_.depth, reference_.depth);
        return d;
    }

private:
    struct Output {
        std::vector<glm::vec2> displacement;
        std::vector<float> depth;
    };
    template <class Kernel>
    void run_into(Output& out, Kernel kernel) {
        out.displacement.resize(depth_.size()), out.depth.resize(depth_.size());
        const int w = width_;
        parallel_for(0, height_, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y) {
                const std::size_t o = std::size_t(y) * std::size_t(w);
                kernel(*test_, y, w, depth_.data() + o, out.displacement.data() + o,
                       out.depth.data() + o);
            }
        });
    }

    int width_ = 0, height_ = 0;
    std::optional<DisplacementTest> test_;
    std::vector<float> depth_;
    Output reference_, optimized_;
};

// ---------------------------------------------------------------------------------------------

class RefetchCase final : public KernelCase {
public:
    void generate(int w, int h, KernelInputs inputs, uint32_t seed) override {
        std::mt19937 rng(seed);
        const bool worst = inputs == KernelInputs::WorstCase;
        factor_ = worst && seed % 3 == 0 ? -1e30f : uniform(rng, -1.0f, 1.0f);
        color_.resize(w, h), motion_.resize(w, h), covered_.resize(w, h);
        target_motion_.resize(w, h);
        const float reach = worst ? 40.0f : 6.0f;
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                for (int c = 0; c < 4; ++c) color_(x, y)[c] = uniform(rng, 0.0f, 4.0f);
                motion_(x, y) = {uniform(rng, -reach, reach), uniform(rng, -reach, reach)};
                target_motion_(x, y) = {uniform(rng, -reach, reach), uniform(rng, -reach, reach)};
                covered_(x, y) = uint8_t(rng() % 8 ? (worst ? 1 + rng() % 255 : 1) : 0);
                if (!worst || rng() % 3) continue;
                switch (rng() % 4) {
                    case 0:
                        color_(x, y)[int(rng() % 4)] = worst_value(rng);
                        break;
                    case 1:
                        motion_(x, y)[int(rng() % 2)] = worst_value(rng);
                        break;
                    case 2:
                        target_motion_(x, y)[int(rng() % 2)] = worst_value(rng);
                        break;
                    default:
                        target_motion_(x, y) = {1e30f, -1e30f};
                }
            }
    }
    void reset() override { optimized_.assign(color_.width(), color_.height(), glm::vec4(-3.0f)); }
    void reset_reference() override {
        reference_.assign(color_.width(), color_.height(), glm::vec4(-3.0f));
    }
    void run_reference() override {
        run_into(reference_, [](const RefetchRow& r) { refetch_row_reference(r, 0, r.width); });
    }
    void run() override { run_into(optimized_, refetch_row); }
    std::string compare() const override {
        const std::vector<glm::vec4> a(optimized_.data(),
                                       optimized_.data() + optimized_.pixel_count());
        const std::vector<glm::vec4> b(reference_.data(),
                                       reference_.data() + reference_.pixel_count());
        return compare_floats("colour", a, b);
    }

private:
    template <class Kernel>
    void run_into(Image<glm::vec4>& out, Kernel kernel) {
        parallel_for(0, out.height(), [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y)
                kernel({.color = std::as_const(color_).view(),
                        .motion = std::as_const(motion_).view(),
                        .factor = factor_,
                        .y = y,
                        .width = out.width(),
                        .covered = &covered_(0, y),
                        .target_motion = &target_motion_(0, y),
                        .out = &out(0, y)});
        });
    }

    float factor_ = 0.5f;
    Image<glm::vec4> color_, optimized_, reference_;
    Image<glm::vec2> motion_, target_motion_;
    Image<uint8_t> covered_;
};

// ---------------------------------------------------------------------------------------------

class BicubicCase final : public KernelCase {
public:
    void generate(int w, int h, KernelInputs inputs, uint32_t seed) override {
        std::mt19937 rng(seed);
        const bool worst = inputs == KernelInputs::WorstCase;
        color_.resize(w, h), positions_.resize(w, h);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                for (int c = 0; c < 4; ++c)
                    color_(x, y)[c] =
                        worst && rng() % 5 == 0 ? worst_value(rng) : uniform(rng, -0.5f, 4.0f);
                // Near the pixel itself, as a warp reads.
                glm::vec2 p(std::clamp(float(x) + uniform(rng, -2.5f, 3.5f), 0.0f, float(w)),
                            std::clamp(float(y) + uniform(rng, -2.5f, 3.5f), 0.0f, float(h)));
                if (worst && rng() % 2) {  // on and near the borders and pixel centres
                    const float xs[] = {0.0f,
                                        0.5f,
                                        1.0f,
                                        1.5f,
                                        float(w) - 1.5f,
                                        float(w) - 0.5f,
                                        float(w),
                                        std::nextafter(float(w), 0.0f),
                                        p.x};
                    const float ys[] = {0.0f,
                                        0.5f,
                                        1.5f,
                                        2.0f,
                                        float(h) - 2.5f,
                                        float(h) - 0.5f,
                                        float(h),
                                        std::nextafter(0.5f, 1.0f),
                                        p.y};
                    p = {std::max(0.0f, xs[rng() % std::size(xs)]),
                         std::max(0.0f, ys[rng() % std::size(ys)])};
                }
                positions_(x, y) = p;
            }
    }
    void run_reference() override { run_into(reference_, bicubic_row_reference); }
    void run() override { run_into(optimized_, bicubic_row); }
    std::string compare() const override {
        const std::vector<glm::vec4> a(optimized_.data(),
                                       optimized_.data() + optimized_.pixel_count());
        const std::vector<glm::vec4> b(reference_.data(),
                                       reference_.data() + reference_.pixel_count());
        return compare_floats("colour", a, b, /*any_nan=*/true);
    }

private:
    template <class Kernel>
    void run_into(Image<glm::vec4>& out, Kernel kernel) {
        out.resize(color_.width(), color_.height());
        parallel_for(0, out.height(), [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y)
                kernel({.color = std::as_const(color_).view(),
                        .positions = &positions_(0, y),
                        .count = out.width(),
                        .out = &out(0, y)});
        });
    }

    Image<glm::vec4> color_, optimized_, reference_;
    Image<glm::vec2> positions_;
};

// ---------------------------------------------------------------------------------------------

// FrucOptions::perceptual: colour encoded, and the encoded colour decoded back.
class PerceptualCase final : public KernelCase {
public:
    void generate(int w, int h, KernelInputs inputs, uint32_t seed) override {
        std::mt19937 rng(seed);
        const bool worst = inputs == KernelInputs::WorstCase;
        width_ = w, height_ = h;
        color_.resize(std::size_t(w) * std::size_t(h));
        for (glm::vec4& c : color_)
            for (int k = 0; k < 4; ++k)
                c[k] = worst && rng() % 5 == 0 ? worst_value(rng) : uniform(rng, -0.5f, 4.0f);
    }
    void run_reference() override {
        run_into(reference_, perceptual_encode_row_reference, perceptual_decode_row_reference);
    }
    void run() override { run_into(optimized_, perceptual_encode_row, perceptual_decode_row); }
    std::string compare() const override {
        std::string d =
            compare_floats("encoded", optimized_.encoded, reference_.encoded, /*any_nan=*/true);
        if (d.empty()) d = compare_floats("decoded", optimized_.decoded, reference_.decoded, true);
        return d;
    }

private:
    struct Output {
        std::vector<glm::vec4> encoded, decoded;
    };
    template <class Encode, class Decode>
    void run_into(Output& out, Encode encode, Decode decode) {
        out.encoded.resize(color_.size());
        const int w = width_;
        parallel_for(0, height_, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y) {
                const std::size_t o = std::size_t(y) * std::size_t(w);
                encode(color_.data() + o, out.encoded.data() + o, w);
            }
        });
        out.decoded = out.encoded;
        parallel_for(0, height_, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y) decode(out.decoded.data() + std::size_t(y) * w, w);
        });
    }

    int width_ = 0, height_ = 0;
    std::vector<glm::vec4> color_;
    Output reference_, optimized_;
};

// ---------------------------------------------------------------------------------------------

// The forward splat (banded, threaded, its row kernels at the current level) against the scalar
// reference, both footprints. Random: blocks of one motion each (sub-pixel, whole-pixel, still,
// a zoom, per-pixel noise) over a few depth levels, so that runs land side by side and ties,
// the depth tolerance and overlaps are exercised; worst case adds NaN/Inf/huge motion and depth.
class SplatCase final : public KernelCase {
public:
    void generate(int w, int h, KernelInputs inputs, uint32_t seed) override {
        std::mt19937 rng(seed);
        const bool worst = inputs == KernelInputs::WorstCase;
        const float factors[] = {-0.5f, 1.0f, 0.3f, -1.0f};
        factor_ = worst && seed % 3 == 0 ? -1e30f : factors[seed % 4];
        // Some targets of another size than the source.
        target_w_ = seed % 5 == 4 ? w + 3 : seed % 5 == 3 ? std::max(1, w - 2) : w;
        target_h_ = seed % 5 == 4 ? std::max(1, h - 1) : seed % 5 == 3 ? h + 9 : h;
        source_.color.resize(w, h), source_.depth.resize(w, h), source_.motion.resize(w, h);
        std::vector<glm::vec2> block_motion(std::size_t((w / 16 + 1) * (h / 4 + 1)));
        std::vector<int> block_kind(block_motion.size());
        for (std::size_t b = 0; b < block_motion.size(); ++b) {
            const int pick = int(rng() % 20);  // mostly whole runs of one motion
            block_kind[b] = pick < 7 ? 0 : pick < 10 ? 1 : pick < 14 ? 2 : pick < 18 ? 3 : 4;
            block_motion[b] = {uniform(rng, -6.0f, 6.0f), uniform(rng, -3.0f, 3.0f)};
            if (block_kind[b] == 1) block_motion[b] = glm::round(block_motion[b]);
            if (block_kind[b] == 2) block_motion[b] = glm::vec2(0.0f);
        }
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const std::size_t b = std::size_t((y / 4) * (w / 16 + 1) + x / 16);
                glm::vec2 m = block_motion[b];
                if (block_kind[b] == 3) m += 0.05f * glm::vec2(float(x - w / 2), float(y - h / 2));
                if (block_kind[b] == 4) m = {uniform(rng, -8.0f, 8.0f), uniform(rng, -8.0f, 8.0f)};
                const float r = uniform(rng, 0.0f, 1.0f);
                float z = r < 0.1f ? kInf : 1.0f + float(int(r * 4.0f));
                if (rng() % 4 == 0) z *= uniform(rng, 0.995f, 1.005f);  // about the tolerance
                for (int c = 0; c < 4; ++c) source_.color(x, y)[c] = uniform(rng, 0.0f, 4.0f);
                if (worst && rng() % 3 == 0) {
                    const unsigned kind = rng() % 6;
                    if (kind == 3)
                        z = rng() % 2 ? 0.0f : -0.0f;
                    else if (kind == 4)
                        z = rng() % 2 ? 1e30f : -uniform(rng, 0.1f, 10.0f);
                    else if (kind == 5)
                        source_.color(x, y)[int(rng() % 4)] = worst_value(rng);
                    else
                        spoil_depth_or_motion(rng, kind, z, m);
                }
                source_.depth(x, y) = z, source_.motion(x, y) = m;
            }
    }
    void reset() override {
        for (Output& o : optimized_) o.start(target_w_, target_h_);
    }
    void reset_reference() override {
        for (Output& o : reference_) o.start(target_w_, target_h_);
    }
    void run_reference() override { run_into(reference_, splat_reference); }
    void run() override { run_into(optimized_, splat); }
    std::string compare() const override {
        for (int f = 0; f < 2; ++f) {
            const Output &a = optimized_[f], &b = reference_[f];
            const std::string footprint = "footprint " + std::to_string(f + 1) + ": ";
            if (a.count != b.count)
                return footprint + "covered " + std::to_string(a.count) + ", reference " +
                       std::to_string(b.count);
            if (!(a.covered == b.covered)) return footprint + "coverage differs";
            std::string d = compare_floats("colour", pixels(a.color), pixels(b.color));
            if (d.empty()) d = compare_floats("depth", pixels(a.depth), pixels(b.depth));
            if (d.empty()) d = compare_floats("motion", pixels(a.motion), pixels(b.motion));
            if (!d.empty()) return footprint + d;
        }
        return {};
    }

private:
    struct Output {
        Image<glm::vec4> color;
        Image<float> depth;
        Image<glm::vec2> motion;
        Image<uint8_t> covered;
        std::size_t count = 0;
        void start(int w, int h) {  // what the splat must overwrite
            color.assign(w, h, glm::vec4(-3.0f)), depth.assign(w, h, -3.0f);
            motion.assign(w, h, glm::vec2(-3.0f)), covered.assign(w, h, 7);
        }
        WarpTarget target() { return {color.view(), depth.view(), motion.view(), covered.view()}; }
    };
    template <class T>
    static std::vector<T> pixels(const Image<T>& image) {
        return {image.data(), image.data() + image.pixel_count()};
    }
    template <class Kernel>
    void run_into(Output (&out)[2], Kernel kernel) {
        for (int f = 0; f < 2; ++f)
            out[f].count = kernel(source_, factor_, out[f].target(), {.footprint = f + 1});
    }

    Frame source_;
    float factor_ = -0.5f;
    int target_w_ = 0, target_h_ = 0;
    Output reference_[2], optimized_[2];
};

// ---------------------------------------------------------------------------------------------

constexpr KernelEntry kEntries[] = {
    {"interpolate blend", "bit-exact", true, make<BlendCase>},
    {"extrapolate static layer", "bit-exact", true, make<StaticLayerCase>},
    {"pull-push first pull", "bit-exact", true, make<PullCase>},
    {"pull-push coarser pull", "bit-exact", true, make<PullLevelCase>},
    {"reverse reprojection", "bit-exact", true, make<ReprojectCase>},
    {"reverse warp refetch", "bit-exact", true, make<RefetchCase>},
    {"bicubic fetch (grid, refetch)", "bit-exact (NaN: any NaN)", true, make<BicubicCase>},
    {"stereo displacement", "bit-exact", true, make<DisplacementCase>},
    {"forward splat", "bit-exact", true, make<SplatCase>},
    {"perceptual colour encode, decode", "bit-exact (NaN: any NaN)", true, make<PerceptualCase>},
};

}  // namespace

std::span<const KernelEntry> warp_kernels() { return kEntries; }

}  // namespace reprise::kernels
