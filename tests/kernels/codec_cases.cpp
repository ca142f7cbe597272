// The codec's kernels' cases (codec/src/kernels.hpp): the encoder and decoder must agree, so
// every case is bit-exact.
#include <algorithm>
#include <cmath>
#include <vector>

#include <glm/gtc/matrix_transform.hpp>

#include "codec/src/kernels.hpp"
#include "generators.hpp"
#include "reprise/core/parallel.hpp"

namespace reprise::kernels {

namespace {

using namespace reprise::codec;

// Catmull-Rom prediction of a plane (luma, or 4:2:0 chroma from luma motion). Random: a camera
// pan's smooth motion with 1/64 steps and a depth edge; worst case: NaN/Inf and huge motion,
// whole-pixel motion, the plane's value extremes.
class PredictCase final : public KernelCase {
public:
    explicit PredictCase(bool subsampled) : subsampled_(subsampled) {}
    void generate(int w, int h, KernelInputs inputs, uint32_t seed) override {
        std::mt19937 rng(seed);
        width_ = w, height_ = h;
        motion_width_ = subsampled_ ? std::max(1, 2 * w - int(rng() % 2)) : w;
        motion_height_ = subsampled_ ? 2 * h : h;
        const bool worst = inputs == KernelInputs::WorstCase;
        lo_ = subsampled_ ? -255 : 0;
        plane_.resize(std::size_t(w) * h);
        for (int16_t& v : plane_)
            v = worst && rng() % 4 == 0 ? int16_t(rng() % 2 ? 32767 : -32768)
                                        : int16_t(lo_ + int(rng() % uint32_t(256 - lo_)));
        motion_.resize(std::size_t(motion_width_) * motion_height_);
        const glm::vec2 pan{uniform(rng, -9, 9), uniform(rng, -5, 5)};
        for (int y = 0; y < motion_height_; ++y)
            for (int x = 0; x < motion_width_; ++x) {
                // The vertical motion changes along a row too: a vector's windows span two rows.
                glm::vec2 m =
                    pan + glm::vec2(0.01f * float(x), 0.04f * float(x) - 0.005f * float(y));
                if (x > motion_width_ / 2) m *= 1.5f;                    // a depth edge
                if (y % 4 == 1) m = {std::round(m.x), std::round(m.y)};  // whole pixels
                if (worst && rng() % 3 == 0) m[int(rng() % 2)] = worst_value(rng);
                motion_[std::size_t(y) * motion_width_ + x] = m;
            }
    }
    void run_reference() override {
        run_into(reference_, [](const PredictRow& r) { predict_row_reference(r, 0, r.width); });
    }
    void run() override { run_into(optimized_, predict_row); }
    std::string compare() const override {
        return compare_elements("prediction", optimized_, reference_);
    }

private:
    template <class Kernel>
    void run_into(std::vector<int16_t>& out, Kernel kernel) {
        out.assign(plane_.size(), 0);
        const int s = subsampled_ ? 1 : 0;
        parallel_for(0, height_, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y)
                kernel(
                    {.reference = plane_.data(),
                     .width = width_,
                     .height = height_,
                     .y = y,
                     .motion0 = motion_.data() +
                                std::size_t(std::min(y << s, motion_height_ - 1)) * motion_width_,
                     .motion1 =
                         motion_.data() +
                         std::size_t(std::min((y << s) + s, motion_height_ - 1)) * motion_width_,
                     .motion_width = motion_width_,
                     .subsampled = subsampled_,
                     .lo = lo_,
                     .hi = 255,
                     .out = out.data() + std::size_t(y) * width_});
        });
    }

    bool subsampled_;
    int width_ = 0, height_ = 0, motion_width_ = 0, motion_height_ = 0, lo_ = 0;
    std::vector<int16_t> plane_;
    std::vector<glm::vec2> motion_;
    std::vector<int16_t> reference_, optimized_;
};

// Revealed pixels of each row. Random: depth with a near band the motion moves by 3-12 px (its
// uncovered strip is revealed), landings inside and outside the picture; worst case: NaN/Inf depth
// and motion, huge motion, zero and negative depth.
class RevealCase final : public KernelCase {
public:
    void generate(int w, int h, KernelInputs inputs, uint32_t seed) override {
        std::mt19937 rng(seed);
        width_ = w, height_ = h;
        const bool worst = inputs == KernelInputs::WorstCase;
        random_ = !worst;
        const std::size_t n = std::size_t(w) * h;
        depth_.resize(n), reference_depth_.resize(n), motion_.resize(n);
        const glm::vec2 pan{uniform(rng, 3, 12), uniform(rng, -2, 2)};
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const std::size_t i = std::size_t(y) * w + x;
                const bool near = x > w / 3 && x < w / 2;
                depth_[i] = near ? 2.0f : uniform(rng, 9.5f, 10.5f);
                reference_depth_[i] = (x + int(pan.x)) > w / 3 && (x + int(pan.x)) < w / 2
                                          ? 2.0f
                                          : uniform(rng, 9.0f, 11.0f);
                motion_[i] = near ? glm::vec2(0.0f) : pan + glm::vec2(uniform(rng, -0.5f, 0.5f));
                if (worst && rng() % 3 == 0) {
                    const int what = int(rng() % 3);
                    if (what == 0) motion_[i][int(rng() % 2)] = worst_value(rng);
                    if (what == 1) depth_[i] = worst_value(rng);
                    if (what == 2) reference_depth_[i] = worst_value(rng);
                }
            }
    }
    void run_reference() override {
        run_into(reference_,
                 [](const RevealRow& r) { return reveal_row_reference(r, 0, r.width); });
    }
    void run() override {
        run_into(optimized_, [](const RevealRow& r) { return reveal_row(r); });
    }
    std::string compare() const override {
        if (random_ && width_ >= 32 && counts_[0] == 0)
            return "no pixel revealed: the case tests nothing";
        if (counts_[0] != counts_[1])
            return "revealed counts " + std::to_string(counts_[1]) + " against the reference's " +
                   std::to_string(counts_[0]);
        return compare_elements("revealed", optimized_, reference_);
    }

private:
    template <class Kernel>
    void run_into(std::vector<uint8_t>& out, Kernel kernel) {
        out.assign(depth_.size(), 7);
        std::vector<std::size_t> rows(std::size_t(height_), 0);
        parallel_for(0, height_, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y)
                rows[std::size_t(y)] = kernel({.depth = depth_.data() + std::size_t(y) * width_,
                                               .motion = motion_.data() + std::size_t(y) * width_,
                                               .reference_depth = reference_depth_.data(),
                                               .width = width_,
                                               .height = height_,
                                               .y = y,
                                               .reference_stride = width_,
                                               .out = out.data() + std::size_t(y) * width_});
        });
        std::size_t total = 0;
        for (std::size_t c : rows) total += c;
        counts_[&out == &optimized_] = total;
    }

    int width_ = 0, height_ = 0;
    bool random_ = true;
    std::vector<float> depth_, reference_depth_;
    std::vector<glm::vec2> motion_;
    std::vector<uint8_t> reference_, optimized_;
    std::size_t counts_[2] = {0, 0};
};

// Camera motion of each row. Random: depths of a scene in front of both cameras with some
// background; worst case: NaN/Inf/negative/signed-zero depths, points behind the other camera,
// an orthographic row.
class CameraMotionCase final : public KernelCase {
public:
    void generate(int w, int h, KernelInputs inputs, uint32_t seed) override {
        std::mt19937 rng(seed);
        width_ = w, height_ = h;
        const bool worst = inputs == KernelInputs::WorstCase;
        depth_.resize(std::size_t(w) * h);
        for (float& z : depth_) z = random_depth(rng, 0.5f, 80.0f, worst);
        auto v4 = [&](float range) {
            return glm::vec4(uniform(rng, -range, range), uniform(rng, -range, range),
                             uniform(rng, -range, range), uniform(rng, -range, range));
        };
        rows_.resize(std::size_t(h));
        for (int y = 0; y < h; ++y) {
            CameraMotionRow& r = rows_[std::size_t(y)];
            r.a0 = v4(2.0f), r.a1 = v4(0.01f), r.b0 = v4(1.0f), r.b1 = v4(0.01f);
            r.a0.w = uniform(rng, worst ? -1.0f : 0.5f, 2.0f);
            r.b0.w = uniform(rng, worst ? -1.0f : 0.5f, 1.5f);
            r.projection = glm::mat4(1.0f);
            r.projection[0][0] = uniform(rng, 0.5f, 2.0f);
            r.projection[1][1] = uniform(rng, 0.5f, 2.0f);
            r.perspective = !(worst && y % 4 == 3);
            r.projection[2][3] = r.perspective ? -1.0f : 0.0f;
            r.projection[3][3] = r.perspective ? 0.0f : 1.0f;
            r.projection[2][2] = -1.002f;
            r.projection[3][2] = -0.2f;
            for (int c = 0; c < 4; ++c) r.to_clip[c] = v4(1.5f);
            r.far_plane = 100.0f;
            r.y = y, r.width = w, r.height = h;
            r.depth = depth_.data() + std::size_t(y) * w;
        }
    }
    void run_reference() override {
        run_into(reference_,
                 [](const CameraMotionRow& r) { camera_motion_row_reference(r, 0, r.width); });
    }
    void run() override { run_into(optimized_, camera_motion_row); }
    std::string compare() const override {
        return compare_floats("motion", optimized_, reference_);
    }

private:
    template <class Kernel>
    void run_into(std::vector<glm::vec2>& out, Kernel kernel) {
        out.assign(depth_.size(), glm::vec2(0.0f));
        parallel_for(0, height_, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y) {
                CameraMotionRow r = rows_[std::size_t(y)];
                r.out = out.data() + std::size_t(y) * width_;
                kernel(r);
            }
        });
    }

    int width_ = 0, height_ = 0;
    std::vector<float> depth_;
    std::vector<CameraMotionRow> rows_;
    std::vector<glm::vec2> reference_, optimized_;
};

// Colour to YCoCg-R planes. Random: linear colour over [0, 1.2] (codes near 0 and above 255
// included); worst case: NaN, Inf, negative, denormal and values just around the thresholds.
class ToPlanesCase final : public KernelCase {
public:
    explicit ToPlanesCase(bool display) : display_(display) {}
    void generate(int w, int h, KernelInputs inputs, uint32_t seed) override {
        std::mt19937 rng(seed);
        width_ = w, height_ = h;
        if (display_) {  // every byte value in every channel
            display_color_.resize(std::size_t(w) * h);
            for (glm::u8vec4& c : display_color_)
                for (int k = 0; k < 4; ++k) c[k] = uint8_t(rng());
            return;
        }
        color_.resize(std::size_t(w) * h);
        const float* thresholds = srgb_tables().thresholds;
        for (glm::vec4& c : color_)
            for (int k = 0; k < 4; ++k) {
                float v = uniform(rng, 0.0f, 1.2f);
                if (rng() % 4 == 0) v = v * v * v * 0.01f;  // the steep part near black
                if (inputs == KernelInputs::WorstCase && rng() % 2) {
                    const float t = thresholds[rng() % 255];
                    const float choices[] = {
                        worst_value(rng),        t,    std::nextafter(t, 0.0f),
                        std::nextafter(t, 2.0f), 1.0f, std::nextafter(1.0f, 0.0f)};
                    v = choices[rng() % std::size(choices)];
                }
                c[k] = v;
            }
    }
    void run_reference() override {
        run_into(reference_, [](const ToPlanesRow& r) { to_planes_row_reference(r, 0, r.width); });
    }
    void run() override { run_into(optimized_, to_planes_row); }
    std::string compare() const override {
        return compare_elements("planes", optimized_, reference_);
    }

private:
    template <class Kernel>
    void run_into(std::vector<int16_t>& out, Kernel kernel) {
        const std::size_t n = std::size_t(width_) * height_;
        out.assign(3 * n, 0);
        parallel_for(0, height_, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y) {
                const std::size_t o = std::size_t(y) * width_;
                kernel({.color = display_ ? nullptr : color_.data() + o,
                        .width = width_,
                        .display = display_ ? display_color_.data() + o : nullptr,
                        .y = out.data() + o,
                        .co = out.data() + n + o,
                        .cg = out.data() + 2 * n + o});
            }
        });
    }

    bool display_;
    int width_ = 0, height_ = 0;
    std::vector<glm::vec4> color_;
    std::vector<glm::u8vec4> display_color_;
    std::vector<int16_t> reference_, optimized_;
};

// YCoCg-R planes to linear colour. Random: the codec's value ranges; worst case: values beyond
// them (every clamp) and NaN/Inf depths.
class FromPlanesCase final : public KernelCase {
public:
    explicit FromPlanesCase(bool display) : display_(display) {}
    void generate(int w, int h, KernelInputs inputs, uint32_t seed) override {
        std::mt19937 rng(seed);
        width_ = w, height_ = h;
        const bool worst = inputs == KernelInputs::WorstCase;
        const std::size_t n = std::size_t(w) * h;
        planes_.resize(3 * n);
        depth_.resize(n);
        for (std::size_t i = 0; i < n; ++i) {
            const int range = worst ? 2000 : 256;
            planes_[i] = int16_t(int(rng() % uint32_t(range)) - (worst ? 1000 : 0));
            planes_[n + i] = int16_t(int(rng() % uint32_t(2 * range)) - range);
            planes_[2 * n + i] = int16_t(int(rng() % uint32_t(2 * range)) - range);
            depth_[i] = rng() % 8 == 0 ? kInf : uniform(rng, 0.1f, 50.0f);
            if (worst && rng() % 3 == 0) depth_[i] = worst_value(rng);
        }
    }
    void run_reference() override {
        run_into(reference_,
                 [](const FromPlanesRow& r) { from_planes_row_reference(r, 0, r.width); });
    }
    void run() override { run_into(optimized_, from_planes_row); }
    std::string compare() const override {
        return compare_floats("colour", optimized_, reference_);
    }

private:
    // The display values are compared as floats, one per channel.
    template <class Kernel>
    void run_into(std::vector<glm::vec4>& out, Kernel kernel) {
        const std::size_t n = depth_.size();
        out.assign(n, glm::vec4(0.0f));
        std::vector<glm::u8vec4> display(display_ ? n : 0);
        parallel_for(0, height_, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y) {
                const std::size_t o = std::size_t(y) * width_;
                kernel({.y = planes_.data() + o,
                        .co = planes_.data() + n + o,
                        .cg = planes_.data() + 2 * n + o,
                        .depth = y % 2 ? depth_.data() + o : nullptr,
                        .width = width_,
                        .out = display_ ? nullptr : out.data() + o,
                        .display = display_ ? display.data() + o : nullptr});
            }
        });
        for (std::size_t i = 0; i < display.size(); ++i) out[i] = glm::vec4(display[i]);
    }

    bool display_;
    int width_ = 0, height_ = 0;
    std::vector<int16_t> planes_;
    std::vector<float> depth_;
    std::vector<glm::vec4> reference_, optimized_;
};

// Forward projection of depth into another camera. Random: a scene in front of both cameras
// (perspective or orthographic) with background; worst case: NaN/Inf/negative/signed-zero
// depths and a camera that moved far forward, so that points fall behind it.
class ForwardCase final : public KernelCase {
public:
    void generate(int w, int h, KernelInputs inputs, uint32_t seed) override {
        std::mt19937 rng(seed);
        width_ = w, height_ = h;
        const bool worst = inputs == KernelInputs::WorstCase;
        depth_.resize(std::size_t(w) * h);
        for (float& z : depth_) z = random_depth(rng, 0.2f, 60.0f, worst);
        projection_ = random_projection(rng, w, h, seed % 3 == 0);
        const float forward = worst ? uniform(rng, 5.0f, 30.0f) : uniform(rng, -0.3f, 0.3f);
        to_camera_ = glm::rotate(
            glm::translate(glm::mat4(1.0f), glm::vec3(uniform(rng, -0.5f, 0.5f),
                                                      uniform(rng, -0.2f, 0.2f), forward)),
            uniform(rng, -0.1f, 0.1f), glm::vec3(0, 1, 0));
        to_clip_ = projection_ * to_camera_;
    }
    void run_reference() override {
        run_into(reference_, [](const ForwardRow& r) { forward_row_reference(r, 0, r.count); });
    }
    void run() override { run_into(optimized_, forward_row); }
    std::string compare() const override {
        for (std::size_t i = 0; i < reference_.slot.size(); ++i) {
            if (optimized_.slot[i] != reference_.slot[i])
                return "pixel " + std::to_string(i) + " lands at " +
                       std::to_string(optimized_.slot[i]) + ", reference " +
                       std::to_string(reference_.slot[i]);
            if (reference_.slot[i] >= 0 &&
                std::memcmp(&optimized_.z[i], &reference_.z[i], sizeof(float)) != 0)
                return "pixel " + std::to_string(i) + ": depth differs";
            if (reference_.slot[i] >= 0 &&
                (std::memcmp(&optimized_.px[i], &reference_.px[i], sizeof(float)) != 0 ||
                 std::memcmp(&optimized_.py[i], &reference_.py[i], sizeof(float)) != 0))
                return "pixel " + std::to_string(i) + ": landing point differs";
            if (reference_.slot[i] >= 0 && i / width_ % 2 == 1 &&
                std::memcmp(&optimized_.inverse[i], &reference_.inverse[i], sizeof(float)) != 0)
                return "pixel " + std::to_string(i) + ": inverse depth differs";
        }
        return {};
    }

private:
    struct Output {
        std::vector<int32_t> slot;
        std::vector<float> z, px, py, inverse;
    };
    template <class Kernel>
    void run_into(Output& out, Kernel kernel) {
        out.slot.assign(depth_.size(), 0);
        out.z.assign(depth_.size(), 0.0f);
        out.px.assign(depth_.size(), 0.0f);
        out.py.assign(depth_.size(), 0.0f);
        out.inverse.assign(depth_.size(), 0.0f);
        parallel_for(0, height_, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y) {
                const std::size_t o = std::size_t(y) * width_;
                kernel({.projection = projection_,
                        .to_clip = to_clip_,
                        .to_camera = to_camera_,
                        .x0 = 0,
                        .y = y,
                        .count = width_,
                        .width = width_,
                        .height = height_,
                        .depth = depth_.data() + o,
                        .slot = out.slot.data() + o,
                        .z = out.z.data() + o,
                        .px = out.px.data() + o,
                        .py = out.py.data() + o,
                        .inverse = y % 2 ? out.inverse.data() + o : nullptr});
            }
        });
    }

    int width_ = 0, height_ = 0;
    std::vector<float> depth_;
    glm::mat4 projection_{1.0f}, to_clip_{1.0f}, to_camera_{1.0f};
    Output reference_, optimized_;
};

// An object's usable and unexplained pixels, run by run. Random: motion equal to the camera's or
// off by about the 0.25 px bound, some depth behind the camera or missing; worst case: NaN/Inf
// in depth, motion and the camera motion.
class ObjectPixelsCase final : public KernelCase {
public:
    void generate(int w, int h, KernelInputs inputs, uint32_t seed) override {
        std::mt19937 rng(seed);
        width_ = w, height_ = h;
        const bool worst = inputs == KernelInputs::WorstCase;
        const std::size_t n = std::size_t(w) * h;
        depth_.resize(n), motion_.resize(n), base_.resize(n);
        for (std::size_t i = 0; i < n; ++i) {
            depth_[i] = rng() % 16 == 0 ? -uniform(rng, 0, 5) : uniform(rng, 0.1f, 100);
            base_[i] = {uniform(rng, -30, 30), uniform(rng, -30, 30)};
            const float off = rng() % 2 ? 0.0f : uniform(rng, 0.15f, 0.35f);
            motion_[i] = base_[i] + glm::vec2(off, rng() % 2 ? off : -off) * 0.7071f;
            if (worst && rng() % 4 == 0) {
                const int which = int(rng() % 3);
                if (which == 0) depth_[i] = worst_value(rng);
                if (which == 1) motion_[i][int(rng() % 2)] = worst_value(rng);
                if (which == 2) base_[i][int(rng() % 2)] = worst_value(rng);
            }
        }
    }
    void run_reference() override {
        run_into(reference_, [](const ObjectPixelsRow& r) {
            return object_pixels_row_reference(r, 0, r.count);
        });
    }
    void run() override { run_into(optimized_, object_pixels_row); }
    std::string compare() const override {
        return compare_elements("usable and unexplained pixels", optimized_, reference_);
    }

private:
    template <class Kernel>
    void run_into(std::vector<int>& out, Kernel kernel) {
        out.assign(std::size_t(2) * height_, 0);
        parallel_for(0, height_, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y) {
                const std::size_t o = std::size_t(y) * width_;
                const int start = std::min(y % 3, width_);  // runs start anywhere in the row
                const ObjectPixels p =
                    kernel({depth_.data() + o + start, motion_.data() + o + start,
                            base_.data() + o + start, width_ - start, 0.25f});
                out[2 * std::size_t(y)] = p.usable;
                out[2 * std::size_t(y) + 1] = p.unexplained;
            }
        });
    }

    int width_ = 0, height_ = 0;
    std::vector<float> depth_;
    std::vector<glm::vec2> motion_, base_;
    std::vector<int> reference_, optimized_;
};

// The colour encoder's per-block differences (sum and largest). Random: a source and a
// prediction mostly within a few levels, a few blocks far off; worst case: the planes' extremes
// (-255 against 255 and back) on whole blocks.
class BlockDifferencesCase final : public KernelCase {
public:
    void generate(int w, int h, KernelInputs inputs, uint32_t seed) override {
        std::mt19937 rng(seed);
        blocks_ = std::max(1, w / 8), rows_ = std::max(1, h / 8);
        stride_ = 8 * blocks_ + int(rng() % 3) * 8;  // planes wider than the blocks coded
        const bool worst = inputs == KernelInputs::WorstCase;
        source_.resize(std::size_t(stride_) * 8 * rows_);
        prediction_.resize(source_.size());
        for (std::size_t i = 0; i < source_.size(); ++i) {
            const int s = int(rng() % 511) - 255;
            source_[i] = int16_t(s);
            const int off = rng() % 16 == 0 ? int(rng() % 511) - 255 : int(rng() % 7) - 3;
            prediction_[i] = int16_t(std::clamp(s + off, -255, 255));
            if (worst && (i / 8) % 3 == 0) {
                source_[i] = int16_t(i % 2 ? 255 : -255);
                prediction_[i] = int16_t(-source_[i]);
            }
        }
    }
    void run_reference() override {
        run_into(reference_, [](const BlockDifferencesRow& r) {
            block_differences_row_reference(r, 0, r.blocks);
        });
    }
    void run() override { run_into(optimized_, block_differences_row); }
    std::string compare() const override {
        return compare_elements("block sum and largest difference", optimized_, reference_);
    }

private:
    template <class Kernel>
    void run_into(std::vector<int32_t>& out, Kernel kernel) {
        out.assign(std::size_t(2) * blocks_ * rows_, 0);
        parallel_for(0, rows_, [&](int r0, int r1) {
            for (int r = r0; r < r1; ++r) {
                const std::size_t at = std::size_t(r) * 8 * stride_;
                int32_t* o = out.data() + std::size_t(2) * blocks_ * r;
                kernel({source_.data() + at, prediction_.data() + at, stride_, blocks_, o,
                        o + blocks_});
            }
        });
    }

    int blocks_ = 0, rows_ = 0, stride_ = 0;
    std::vector<int16_t> source_, prediction_;
    std::vector<int32_t> reference_, optimized_;
};

// The motion residual test, row by row. Random: the renderer's motion equal to the camera's, or
// off by less than, about, or more than 1/16 pixel (only some rows differ); worst case: NaN/Inf
// on either side and differences beyond the residual's range. Within: the motion models' test
// (0.25 px) instead.
template <bool Within>
class MotionResidualCase final : public KernelCase {
public:
    void generate(int w, int h, KernelInputs inputs, uint32_t seed) override {
        std::mt19937 rng(seed);
        width_ = w, height_ = h;
        const bool worst = inputs == KernelInputs::WorstCase;
        source_.resize(std::size_t(w) * h);
        base_.resize(source_.size());
        for (int y = 0; y < h; ++y) {
            const float spread = y % 3 == 0 ? 0.0f : y % 3 == 1 ? 0.0624f : 0.5f;
            for (int x = 0; x < w; ++x) {
                const std::size_t i = std::size_t(y) * w + x;
                base_[i] = {uniform(rng, -30, 30), uniform(rng, -30, 30)};
                source_[i] = base_[i];
                if (rng() % 4 == 0)
                    source_[i] +=
                        glm::vec2(uniform(rng, -spread, spread), uniform(rng, -spread, spread));
                if (worst && rng() % 4 == 0) {
                    glm::vec2& v = rng() % 2 ? source_[i] : base_[i];
                    v[int(rng() % 2)] = worst_value(rng);
                }
            }
        }
    }
    void run_reference() override {
        if constexpr (Within)
            run_into(reference_, [](const MotionWithinRow& r) {
                return motion_within_row_reference(r, 0, r.width);
            });
        else
            run_into(reference_, [](const MotionResidualRow& r) {
                return motion_residual_row_reference(r, 0, r.width);
            });
    }
    void run() override {
        if constexpr (Within)
            run_into(optimized_, motion_within_row);
        else
            run_into(optimized_, motion_residual_row);
    }
    std::string compare() const override {
        return compare_elements("row needs a residual", optimized_, reference_);
    }

private:
    template <class Kernel>
    void run_into(std::vector<uint8_t>& out, Kernel kernel) {
        out.assign(std::size_t(height_), 0);
        parallel_for(0, height_, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y) {
                const std::size_t o = std::size_t(y) * width_;
                if constexpr (Within)
                    out[std::size_t(y)] =
                        kernel({source_.data() + o, base_.data() + o, width_, 0.25f});
                else
                    out[std::size_t(y)] = kernel({source_.data() + o, base_.data() + o, width_});
            }
        });
    }

    int width_ = 0, height_ = 0;
    std::vector<glm::vec2> source_, base_;
    std::vector<uint8_t> reference_, optimized_;
};

// View-mode depth: which pixels keep their temporal prediction. Random: predictions within two
// steps of the depth's own code (the bound's edge among them), missing ones, code 0; worst case:
// NaN, Inf, negative and zero depth, codes around and above 2^30, a displacement of 0 or 10^6.
// With a displacement of 0 the step is a power of two and a quarter of the depths too, their
// predictions exactly one step from their own code or one code beyond: the bound itself, exact
// in binary64.
class ViewKeepCase final : public KernelCase {
public:
    void generate(int w, int h, KernelInputs inputs, uint32_t seed) override {
        std::mt19937 rng(seed);
        width_ = w, height_ = h;
        const bool worst = inputs == KernelInputs::WorstCase;
        step_ = double(uniform(rng, 1e-5f, 1e-3f));
        displacement_ = worst && seed % 3 == 0 ? (seed % 2 ? 0.0 : 1e6) : uniform(rng, 0.0f, 0.5f);
        const bool exact_edges = displacement_ == 0.0;
        if (exact_edges) step_ = 0x1p-12;
        source_.resize(std::size_t(w) * h);
        temporal_.resize(source_.size());
        share_.clear();  // per-pixel multiples of the bound on every other seed
        if (seed % 2)
            for (std::size_t i = 0; i < source_.size(); ++i)
                share_.push_back(rng() % 2 ? 1.0f : uniform(rng, 1.0f, 20.0f));
        for (std::size_t i = 0; i < source_.size(); ++i) {
            const float z = random_depth(rng, 0.2f, 60.0f, worst);
            source_[i] = z;
            // The depth's own code, at most 2^30 (a denormal depth's would overflow int64).
            const double own = z > 0.0f && z < kInf
                                   ? std::min(std::nearbyint(1.0 / double(z) / step_), 0x1p30)
                                   : 0.0;
            const int64_t near_own =
                int64_t(own) + int64_t(rng() % (4 * kViewCodesPerStep + 1)) - 2 * kViewCodesPerStep;
            const uint32_t choices[] = {uint32_t(std::clamp<int64_t>(near_own, 0, 1 << 30)),
                                        uint32_t(std::clamp<int64_t>(near_own, 0, 1 << 30)),
                                        0xFFFFFFFFu, 0u};
            temporal_[i] = choices[rng() % 4];
            if (worst && rng() % 4 == 0) {
                const uint32_t extremes[] = {1u << 30,    (1u << 30) + 1, (1u << 30) + 2,
                                             0x7FFFFFFFu, 0x80000000u,    0xFFFFFFFEu};
                temporal_[i] = extremes[rng() % std::size(extremes)];
            }
            if (exact_edges && rng() % 4 == 0) {
                const int e = int(rng() % 11) - 4;  // depth 2^e: 1/z = 2^(12 - e) steps exactly
                source_[i] = std::ldexp(1.0f, e);
                const int64_t edge = kViewCodesPerStep + int64_t(rng() % 2);
                temporal_[i] = uint32_t((int64_t(1) << (12 - e)) + (rng() % 2 ? edge : -edge));
            }
        }
    }
    void run_reference() override {
        run_into(reference_, [](const ViewKeepRow& r) { view_keep_row_reference(r, 0, r.count); });
    }
    void run() override { run_into(optimized_, view_keep_row); }
    std::string compare() const override {
        return compare_elements("keeps its prediction", optimized_, reference_);
    }

private:
    template <class Kernel>
    void run_into(std::vector<uint8_t>& out, Kernel kernel) {
        out.assign(source_.size(), 2);
        parallel_for(0, height_, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y) {
                const std::size_t o = std::size_t(y) * width_;
                kernel({.source = source_.data() + o,
                        .temporal = temporal_.data() + o,
                        .count = width_,
                        .step = step_,
                        .displacement = displacement_,
                        .keep = out.data() + o,
                        .share = share_.empty() ? nullptr : share_.data() + o});
            }
        });
    }

    int width_ = 0, height_ = 0;
    double step_ = 1e-4, displacement_ = 0.164;
    std::vector<float> source_, share_;
    std::vector<uint32_t> temporal_;
    std::vector<uint8_t> reference_, optimized_;
};

// What inter-frame depth's temporal prediction shows at each pixel (reprojection_class), in the
// rows of 8-row block rows. Random: a surface's codes stepping by up to twice the step, a second
// surface far off, nothing landed one time in twenty, held bytes 0..2; worst case: codes at
// 0, 2^32 - 2 and around 2^30 (lossless depth's codes span all 32 bits), steps of exactly the
// step and one more, a step of 0 and of 2^32 - 1.
class ShowsCase final : public KernelCase {
public:
    void generate(int w, int h, KernelInputs inputs, uint32_t seed) override {
        std::mt19937 rng(seed);
        width_ = w, height_ = h;
        const bool worst = inputs == KernelInputs::WorstCase;
        step_ = worst && seed % 3 == 0 ? (seed % 2 ? 0u : 0xFFFFFFFFu) : 1 + rng() % 64;
        temporal_.resize(std::size_t(w) * h);
        held_.resize(temporal_.size());
        uint32_t surface = 1u << 20;
        for (std::size_t i = 0; i < temporal_.size(); ++i) {
            surface += uint32_t(rng() % (4 * std::min(step_, 64u) + 1)) - 2 * std::min(step_, 64u);
            uint32_t t = rng() % 8 == 0 ? surface + (1u << 24) : surface;
            if (rng() % 20 == 0) t = kNoPrediction;
            if (worst && rng() % 4 == 0) {
                const uint32_t extremes[] = {
                    0u,           0xFFFFFFFEu,     kMaxViewCode,        kInfCode,
                    kInvalidCode, surface + step_, surface + step_ + 1, surface - step_};
                t = extremes[rng() % std::size(extremes)];
            }
            temporal_[i] = t;
            held_[i] = uint8_t(rng() % 3);
        }
    }
    void run_reference() override {
        run_into(reference_, [](const ShowsRow& r) { shows_row_reference(r, 0, r.count); });
    }
    void run() override { run_into(optimized_, shows_row); }
    std::string compare() const override {
        return compare_elements("what the prediction shows", optimized_, reference_);
    }

private:
    template <class Kernel>
    void run_into(std::vector<uint8_t>& out, Kernel kernel) {
        out = held_;
        parallel_for(0, height_, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y) {
                const std::size_t o = std::size_t(y) * width_;
                kernel({.temporal = temporal_.data() + o,
                        .above = y % 8 ? temporal_.data() + o - width_ : nullptr,
                        .count = width_,
                        .step = step_,
                        .out = out.data() + o});
            }
        });
    }

    int width_ = 0, height_ = 0;
    uint32_t step_ = 33;
    std::vector<uint32_t> temporal_;
    std::vector<uint8_t> held_, reference_, optimized_;
};

// View-mode codes of reprojected depth and the depth of codes. Random: depth of a scene (and
// nothing landed one time in eight); codes near a depth's own and the background's; worst case:
// NaN/Inf/zero/negative/denormal depths, codes around 2^30 and above 2^31, halfway quotients
// (1 / z / step ties, which round to even).
class ViewCodeCase final : public KernelCase {
public:
    void generate(int w, int h, KernelInputs inputs, uint32_t seed) override {
        std::mt19937 rng(seed);
        width_ = w, height_ = h;
        const bool worst = inputs == KernelInputs::WorstCase;
        // Every third seed: a step for which depth 1 is a halfway quotient, 1 / 1 / step = k + 1/2.
        step_ = double(uniform(rng, 1e-6f, 1e-2f));
        const bool ties = seed % 3 == 0;
        for (int k = 1 + int(rng() % 4000); ties; ++k)
            if (step_ = 2.0 / double(2 * k + 1); 1.0 / 1.0 / step_ - double(k) == 0.5) break;
        depth_.resize(std::size_t(w) * h);
        codes_.resize(depth_.size());
        for (std::size_t i = 0; i < depth_.size(); ++i) {
            float z = rng() % 8 == 0 ? kNaN : random_depth(rng, 0.05f, 500.0f, worst);
            if (worst && rng() % 8 == 0) {
                const float extremes[] = {0.0f, -0.0f, -1.0f, 1e-45f, 1e-38f, 3e38f, -kInf};
                z = extremes[rng() % std::size(extremes)];
            }
            if (ties && rng() % 4 == 0) z = 1.0f;  // rounds to the even neighbour
            depth_[i] = z;
            uint32_t c = rng() % 3 ? uint32_t(rng() % (1u << 20)) : kInfCode;
            if (worst && rng() % 4 == 0) {
                const uint32_t extremes[] = {0u,           1u,          kMaxViewCode, kInfCode,
                                             kInvalidCode, 0x7FFFFFFFu, 0x80000000u,  0xFFFFFFFFu};
                c = extremes[rng() % std::size(extremes)];
            }
            codes_[i] = c;
        }
    }
    void run_reference() override {
        run_into(
            codes_reference_, depth_reference_,
            [](const ViewCodeRow& r) { view_code_row_reference(r, 0, r.count); },
            [](const ViewDepthRow& r) { view_depth_row_reference(r, 0, r.count); });
    }
    void run() override {
        run_into(codes_optimized_, depth_optimized_, view_code_row, view_depth_row);
    }
    std::string compare() const override {
        const std::string codes = compare_elements("code", codes_optimized_, codes_reference_);
        return codes.empty() ? compare_floats("depth of a code", depth_optimized_, depth_reference_)
                             : codes;
    }

private:
    template <class CodeKernel, class DepthKernel>
    void run_into(std::vector<uint32_t>& codes, std::vector<float>& depth, CodeKernel code_kernel,
                  DepthKernel depth_kernel) {
        codes.assign(depth_.size(), 7u);
        depth.assign(depth_.size(), -7.0f);
        parallel_for(0, height_, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y) {
                const std::size_t o = std::size_t(y) * width_;
                code_kernel({.depth = depth_.data() + o,
                             .count = width_,
                             .step = step_,
                             .out = codes.data() + o});
                depth_kernel({.codes = codes_.data() + o,
                              .count = width_,
                              .step = step_,
                              .out = depth.data() + o});
            }
        });
    }

    int width_ = 0, height_ = 0;
    double step_ = 1e-4;
    std::vector<float> depth_, depth_reference_, depth_optimized_;
    std::vector<uint32_t> codes_, codes_reference_, codes_optimized_;
};

// The plane fit of depth reprojection. Random: landings of one tilted surface, stretched and
// shifted, with holes (no landing) and a second object; worst case: NaN/Inf/zero/negative and
// huge inverse depths, landings on a pixel's edge and degenerate planes (neighbours landing on
// one point).
class PlaneCase final : public KernelCase {
public:
    void generate(int w, int h, KernelInputs inputs, uint32_t seed) override {
        std::mt19937 rng(seed);
        width_ = w, height_ = h;
        span_ = 2 + int(seed % 5);
        step_ = seed % 3 == 0 ? 0.0f : uniform(rng, 0.0f, 0.01f);  // the view step, or none
        const bool worst = inputs == KernelInputs::WorstCase;
        const std::size_t n = std::size_t(w) * h;
        slot_.assign(n, -1), object_.assign(n, 0);
        inverse_.assign(n, 0.0f), z_.assign(n, 0.0f), px_.assign(n, 0.0f), py_.assign(n, 0.0f);
        const float base = uniform(rng, 0.02f, 2.0f), gx = uniform(rng, -0.01f, 0.01f);
        const float gy = uniform(rng, -0.01f, 0.01f), stretch = uniform(rng, 0.7f, 1.4f);
        const float shift = uniform(rng, -3.0f, 3.0f);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                const std::size_t i = std::size_t(y) * w + x;
                if (rng() % 8 == 0) continue;  // nothing landed
                float px = float(x) * stretch + shift + uniform(rng, -0.2f, 0.2f);
                float py = float(y) + uniform(rng, -0.3f, 0.3f);
                if (worst && rng() % 6 == 0) px = float(int(px));  // on the pixel's edge
                if (worst && rng() % 6 == 0 && x > 0) px = px_[i - 1], py = py_[i - 1];
                px_[i] = std::clamp(px, 0.0f, std::nextafter(float(w), 0.0f));
                py_[i] = std::clamp(py, 0.0f, std::nextafter(float(h), 0.0f));
                slot_[i] = int32_t(py_[i]) * w + int32_t(px_[i]);
                object_[i] = x > w / 2 && y > h / 3 ? 1 : rng() % 16 == 0 ? -1 : 0;
                float v = base + gx * float(x) + gy * float(y) + uniform(rng, -0.002f, 0.002f);
                if (worst && rng() % 5 == 0) v = worst_value(rng);
                inverse_[i] = v;
                z_[i] = worst && rng() % 7 == 0 ? worst_value(rng) : 1.0f / v;
            }
    }
    void run_reference() override {
        run_into(reference_, [](const PlaneRow& r) { plane_row_reference(r, 0, r.width); });
    }
    void run() override { run_into(optimized_, plane_row); }
    std::string compare() const override {
        return compare_floats("depth at the pixel centre", optimized_, reference_, true);
    }

private:
    template <class Kernel>
    void run_into(std::vector<float>& out, Kernel kernel) {
        out.assign(slot_.size(), -7.0f);
        parallel_for(0, height_, [&](int y0, int y1) {
            for (int y = y0; y < y1; ++y)
                kernel({.slot = slot_.data(),
                        .object = object_.data(),
                        .inverse = inverse_.data(),
                        .z = z_.data(),
                        .px = px_.data(),
                        .py = py_.data(),
                        .width = width_,
                        .height = height_,
                        .span = span_,
                        .y = y,
                        .step = step_,
                        .out = out.data() + std::size_t(y) * width_});
        });
    }

    int width_ = 0, height_ = 0, span_ = 2;
    float step_ = 0.0f;
    std::vector<int32_t> slot_;
    std::vector<int> object_;
    std::vector<float> inverse_, z_, px_, py_, reference_, optimized_;
};

constexpr KernelEntry kEntries[] = {
    {"codec prediction, luma", "bit-exact", true, make<PredictCase, false>},
    {"codec prediction, 4:2:0 chroma", "bit-exact", true, make<PredictCase, true>},
    {"codec revealed pixels", "bit-exact", true, make<RevealCase>},
    {"codec camera motion", "bit-exact", true, make<CameraMotionCase>},
    {"codec depth forward projection", "bit-exact", true, make<ForwardCase>},
    {"codec depth plane fit", "bit-exact", true, make<PlaneCase>},
    {"codec motion residual test", "bit-exact", true, make<MotionResidualCase<false>>},
    {"codec motion within the models' bound", "bit-exact", true, make<MotionResidualCase<true>>},
    {"codec colour block differences", "bit-exact", true, make<BlockDifferencesCase>},
    {"codec an object's usable and unexplained pixels", "bit-exact", true, make<ObjectPixelsCase>},
    {"codec view depth keeps its prediction", "bit-exact", true, make<ViewKeepCase>},
    {"codec what depth's temporal prediction shows", "bit-exact", true, make<ShowsCase>},
    {"codec view depth codes and their depth", "bit-exact", true, make<ViewCodeCase>},
    {"codec colour to YCoCg-R", "bit-exact", true, make<ToPlanesCase, false>},
    {"codec display colour to YCoCg-R", "bit-exact", true, make<ToPlanesCase, true>},
    {"codec YCoCg-R to colour", "bit-exact", true, make<FromPlanesCase, false>},
    {"codec YCoCg-R to display colour", "bit-exact", true, make<FromPlanesCase, true>},
};

}  // namespace

std::span<const KernelEntry> codec_kernels() { return kEntries; }

}  // namespace reprise::kernels
