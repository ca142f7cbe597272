// Spatio-temporal upsampling (Herzog et al. 2010); equations and conventions in upsample.hpp.
// Three passes per frame: (A) the history at p + motion with its disocclusion test and the raw
// temporal gradient, (B) the gradient's spatial low-pass, (C) the steered spatial filter blended
// with the history.
#include "reprise/warp/upsample.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>

#include "reprise/core/camera_math.hpp"
#include "reprise/core/parallel.hpp"

namespace reprise::warp {

namespace {

bool finite3(const glm::vec4& c) {
    return std::isfinite(c.x) && std::isfinite(c.y) && std::isfinite(c.z);
}

float luminance(const glm::vec4& c) { return 0.2126f * c.x + 0.7152f * c.y + 0.0722f * c.z; }

// log2 and exp2 to about 1e-4 relative with short polynomials (powf dominated the filter).
float fast_log2(float x) {  // x > 0, finite
    uint32_t bits;
    std::memcpy(&bits, &x, sizeof bits);
    const float exponent = float(int((bits >> 23) & 0xff) - 127);
    bits = (bits & 0x007fffffu) | 0x3f800000u;  // mantissa in [1, 2)
    float m;
    std::memcpy(&m, &bits, sizeof m);
    const float t = (m - 1.0f) / (m + 1.0f), t2 = t * t;  // log2 m = 2 atanh(t) / ln 2
    return exponent +
           t * (2.8853900818f + t2 * (0.9617966939f + t2 * (0.5770780164f + t2 * 0.4121985232f)));
}

float fast_exp2(float e) {  // e <= 0
    if (e < -126.0f) return 0.0f;
    const float whole = std::floor(e), frac = e - whole;
    const float p =
        1.0f +
        frac * (0.6931471806f +
                frac * (0.2402265070f +
                        frac * (0.0555041087f + frac * (0.0096181291f + frac * 0.0013333558f))));
    const uint32_t scale_bits = uint32_t(int(whole) + 127) << 23;
    float scale;
    std::memcpy(&scale, &scale_bits, sizeof scale);
    return p * scale;
}

float fast_pow(float base, float gamma) { return fast_exp2(gamma * fast_log2(base)); }

// base^gamma of eq. 3 for base = max(eps, 1 - x / sigma).
float falloff_of_base(float base, float gamma) {
    if (gamma == 3.0f) return base * base * base;
    if (gamma == 1.0f) return base;
    if (gamma <= 0.0f) return 1.0f;
    return fast_pow(base, gamma);
}

// base^gamma for the steered fall-off of k (gamma in [0, 8]): exact at whole gammas, linear in
// gamma between them (multiplications only; the per-tap powf dominated the filter).
float steered_power(float base, float gamma) {
    if (!(gamma > 0.0f)) return 1.0f;
    if (gamma > 8.0f) return fast_pow(base, gamma);
    const int whole = int(gamma);
    float lower = 1.0f;
    for (int i = 0; i < whole; ++i) lower *= base;
    const float frac = gamma - float(whole);
    return frac > 0.0f ? lower * (1.0f - frac + frac * base) : lower;
}

// g(x, sigma, gamma) of eq. 3 with x and sigma already divided: max(eps, 1 - ratio)^gamma.
float falloff(float ratio, float epsilon, float gamma) {
    return falloff_of_base(std::max(epsilon, 1.0f - ratio), gamma);
}

enum class DepthKind { Surface, Background, Invalid };

DepthKind depth_kind(float z) {
    if (z == INFINITY) return DepthKind::Background;
    return std::isfinite(z) && z > 0.0f ? DepthKind::Surface : DepthKind::Invalid;
}

// Everything the per-pixel filters read, fixed for one frame.
struct FrameContext {
    ImageView<const glm::vec4> low;
    const GBufferView* full = nullptr;
    glm::vec2 jitter{0.0f};       // of the low samples, full-resolution pixels
    glm::vec2 full_jitter{0.0f};  // of the full G-buffer (0 as reprise renders it)
    glm::vec2 scale{1.0f};        // full pixels per low pixel
    float diagonal = 1.0f;        // r: the low pixel's diagonal in full pixels
    int width = 0, height = 0;
    const UpsampleOptions* options = nullptr;
    float floor3 = 0.0f;  // eps^3: the weight of a failed geometric test
    bool ids = false;     // the id test applies
};

// What the geometric weights read of one full pixel.
struct Guide {
    float depth;
    DepthKind kind;
    glm::vec3 normal;
    uint32_t id;
};

Guide guide_at(const GBufferView& g, int x, int y) {
    const float z = g.depth(x, y);
    return {z, depth_kind(z), g.normal.empty() ? glm::vec3(0.0f) : g.normal(x, y),
            g.id.empty() ? 0u : g.id(x, y)};
}

// Geometric part of w_s (eq. 2) between full pixels i and j, and the id test.
float geometric_weight(const FrameContext& f, const Guide& i, const Guide& j) {
    const UpsampleOptions& o = *f.options;
    float w = 1.0f;
    if (i.kind == DepthKind::Surface && j.kind == DepthKind::Surface) {
        const float dz = (i.depth - j.depth) / (o.depth_sigma * i.depth);
        w *= falloff(dz * dz, o.epsilon, 3.0f);
    } else if (!(i.kind == DepthKind::Background && j.kind == DepthKind::Background)) {
        return f.floor3;
    }
    if (!f.full->normal.empty()) {
        const float d = i.normal.x * j.normal.x + i.normal.y * j.normal.y + i.normal.z * j.normal.z;
        if (!std::isfinite(d)) return f.floor3 * w;
        const bool zero_i = i.normal == glm::vec3(0.0f), zero_j = j.normal == glm::vec3(0.0f);
        if (zero_i != zero_j) {
            w *= f.floor3;
        } else if (!zero_i) {
            const float a = std::max(0.0f, 1.0f - d);
            w *= falloff(a * a / (o.normal_sigma * o.normal_sigma), o.epsilon, 3.0f);
        }
    }
    if (f.ids && i.id != j.id) w *= f.floor3;
    return w;
}

// The 2x2 nearest low samples of full pixel (x, y): their geometric weights and the base of the
// image-space filter, max(eps, 1 - distance / r); k = base^gamma_k. Fixed for a
// frame, so the gradient pass computes them once for the final pass.
struct Taps {
    glm::vec4 geometric{0.0f};
    glm::vec4 base{0.0f};
};

struct TapOrigin {
    int u0, v0;
};

TapOrigin tap_origin(const FrameContext& f, int x, int y) {
    const glm::vec2 q =
        (glm::vec2(float(x) + 0.5f, float(y) + 0.5f) + f.full_jitter - f.jitter) / f.scale - 0.5f;
    return {int(std::floor(q.x)), int(std::floor(q.y))};
}

Taps compute_taps(const FrameContext& f, int x, int y) {
    const TapOrigin o = tap_origin(f, x, y);
    const Guide here = guide_at(*f.full, x, y);
    // Positions in the unjittered full image: pixel (x, y) saw x + 0.5 + full jitter.
    const float px = float(x) + 0.5f + f.full_jitter.x, py = float(y) + 0.5f + f.full_jitter.y;
    Taps t;
    for (int dv = 0; dv < 2; ++dv) {
        const int v = std::clamp(o.v0 + dv, 0, f.low.height - 1);
        const float sy = (float(v) + 0.5f) * f.scale.y + f.jitter.y;
        const int gy = std::clamp(int(std::floor(sy - f.full_jitter.y)), 0, f.height - 1);
        for (int du = 0; du < 2; ++du) {
            const int u = std::clamp(o.u0 + du, 0, f.low.width - 1);
            const float sx = (float(u) + 0.5f) * f.scale.x + f.jitter.x;
            const int gx = std::clamp(int(std::floor(sx - f.full_jitter.x)), 0, f.width - 1);
            const float dx = sx - px, dy = sy - py;
            const float eps = f.options->epsilon;
            t.base[dv * 2 + du] =
                f.options->separable_filter
                    ? std::max(eps, 1.0f - std::abs(dx) / f.scale.x) *
                          std::max(eps, 1.0f - std::abs(dy) / f.scale.y)
                    : std::max(eps, 1.0f - std::sqrt(dx * dx + dy * dy) / f.diagonal);
            t.geometric[dv * 2 + du] = geometric_weight(f, here, guide_at(*f.full, gx, gy));
        }
    }
    return t;
}

struct SpatialResult {
    glm::vec4 color{0.0f};  // normalized
    float weight = 0.0f;    // w~ = sum w_s
    int nonfinite = 0;
    glm::vec3 lo{INFINITY}, hi{-INFINITY};  // colour box of the samples on the same surface
};

// Eq. 6 over the 2x2 nearest low samples with image-space fall-off gamma_k.
SpatialResult combine(const FrameContext& f, int x, int y, const Taps& t, float gamma_k) {
    const TapOrigin o = tap_origin(f, x, y);
    SpatialResult r;
    glm::vec4 sum(0.0f);
    for (int dv = 0; dv < 2; ++dv) {
        const int v = std::clamp(o.v0 + dv, 0, f.low.height - 1);
        for (int du = 0; du < 2; ++du) {
            const int u = std::clamp(o.u0 + du, 0, f.low.width - 1);
            const glm::vec4 c = f.low(u, v);
            if (!finite3(c)) {
                ++r.nonfinite;
                continue;
            }
            const int tap = dv * 2 + du;
            const float geometric = t.geometric[tap];
            const float w = geometric * steered_power(t.base[tap], gamma_k);
            sum += w * glm::vec4(c.x, c.y, c.z, 0.0f);
            r.weight += w;
            if (geometric > f.floor3) {
                r.lo = glm::min(r.lo, glm::vec3(c));
                r.hi = glm::max(r.hi, glm::vec3(c));
            }
        }
    }
    if (r.weight > 0.0f) r.color = sum / r.weight;
    return r;
}

struct Counters {
    std::atomic<int64_t> rejected{0}, used{0}, nonfinite{0}, unresolved{0};
};

}  // namespace

SpatioTemporalUpsampler::SpatioTemporalUpsampler(UpsampleOptions options) : options_(options) {}

void SpatioTemporalUpsampler::reset() { has_history_ = false; }

// One frame's pass: what every stage reads, and what they count.
struct SpatioTemporalUpsampler::Pass {
    FrameContext f;
    GBufferView full;           // the guides, repaired
    bool temporal = false;      // the history is fetched
    bool history_ids = false;   // ... and tested on ids
    StaticReprojection camera;  // this frame's pixels into the previous view
    glm::mat4 to_previous_view{1.0f};
    Counters counters;

    Pass(const GBufferView& guides, int width, int height)
        : full(guides),
          camera(guides.camera, guides.camera.prev_view, guides.camera.prev_projection, width,
                 height),
          to_previous_view(camera.to_view()) {}
};

void SpatioTemporalUpsampler::upsample(ImageView<const glm::vec4> low_color, glm::vec2 jitter_px,
                                       const GBufferView& given, ImageView<glm::vec4> out,
                                       UpsampleStats* stats) {
    const UpsampleOptions& o = options_;
    // The guides with NaN and infinities (but background depth) repaired; their colour is unused.
    GBufferView guides = given;
    guides.color = {};
    NonfiniteCounts input_nonfinite;
    const GBufferView full = guide_repair_.clean(guides, input_nonfinite);
    input_nonfinite.color = count_nonfinite({.color = low_color}).color;
    input_nonfinite.frames = input_nonfinite.total() > 0;
    const int width = full.depth.width, height = full.depth.height;
    REPRISE_ASSERT(!full.depth.empty() && !low_color.empty());
    REPRISE_ASSERT(out.width == width && out.height == height);
    REPRISE_ASSERT(low_color.width <= width && low_color.height <= height);
    REPRISE_ASSERT(full.normal.empty() ||
                   (full.normal.width == width && full.normal.height == height));
    REPRISE_ASSERT(full.id.empty() || (full.id.width == width && full.id.height == height));
    REPRISE_ASSERT(full.motion.empty() ||
                   (full.motion.width == width && full.motion.height == height));
    REPRISE_ASSERT(o.depth_sigma > 0.0f && o.normal_sigma > 0.0f && o.epsilon > 0.0f &&
                   o.epsilon < 1.0f);
    resize(width, height);

    Pass pass(full, width, height);
    FrameContext& f = pass.f;
    f.low = low_color;
    f.full = &pass.full;
    // Offsets beyond any image are nonsense; bounding them keeps every index computation in range.
    auto bounded = [](glm::vec2 v) {
        const float limit = float(kMaxImageSide);
        if (!std::isfinite(v.x) || !std::isfinite(v.y)) return glm::vec2(0.0f);
        return glm::clamp(v, glm::vec2(-limit), glm::vec2(limit));
    };
    f.jitter = bounded(jitter_px);
    f.full_jitter = bounded(full.camera.jitter);
    f.scale =
        glm::vec2(float(width) / float(low_color.width), float(height) / float(low_color.height));
    f.diagonal = std::sqrt(f.scale.x * f.scale.x + f.scale.y * f.scale.y);
    f.width = width;
    f.height = height;
    f.options = &o;
    f.floor3 = o.epsilon * o.epsilon * o.epsilon;
    f.ids = o.id_test && !full.id.empty();
    pass.temporal = has_history_ && !full.motion.empty() && o.history_weight > 0.0f;
    pass.history_ids = o.id_test && !full.id.empty() && history_has_ids_;

    if (pass.temporal) fetch_history(pass);
    if (pass.temporal && o.gradient_steering) smooth_gradient(pass);
    filter(pass, out);
    keep_history(pass);

    if (stats) {
        *stats = {.history_rejected = pass.counters.rejected,
                  .history_used = pass.counters.used,
                  .nonfinite_samples = pass.counters.nonfinite,
                  .unresolved = pass.counters.unresolved,
                  .nonfinite = input_nonfinite};
    }
}

void SpatioTemporalUpsampler::resize(int width, int height) {
    if (history_.width() == width && history_.height() == height) return;
    history_.resize(width, height);
    next_history_.resize(width, height);
    deltas_.resize(width, height);
    next_deltas_.resize(width, height);
    history_depth_.resize(width, height);
    history_id_.resize(width, height);
    reprojected_.resize(width, height);
    gradient_.resize(width, height);
    gradient_tmp_.resize(width, height);
    tap_geometric_.resize(width, height);
    tap_base_.resize(width, height);
    has_history_ = false;
}

// The spatial taps of a pixel whose history has just been fetched (kept for the final pass) and
// its relative temporal gradient; the differences rotate for the next frame.
void SpatioTemporalUpsampler::temporal_gradient(const Pass& pass, int x, int y) {
    const FrameContext& f = pass.f;
    const glm::vec4 h = reprojected_(x, y);
    glm::vec4& d = next_deltas_(x, y);
    float current = 1.0f;
    const Taps taps = compute_taps(f, x, y);
    tap_geometric_(x, y) = taps.geometric;
    tap_base_(x, y) = taps.base;
    if (h.w > 0.0f) {
        const SpatialResult s = combine(f, x, y, taps, options_.gamma_unsteered);
        const float a = luminance(s.color), b = luminance(h);
        const float scale = std::max(std::abs(a), std::abs(b));
        current = s.weight > 0.0f && scale > 0.0f ? std::clamp((a - b) / scale, -1.0f, 1.0f) : 0.0f;
        gradient_(x, y) =
            std::min(1.0f, std::abs(0.4f * current + 0.3f * d.x + 0.2f * d.y + 0.1f * d.z));
    } else {
        gradient_(x, y) = 1.0f;
    }
    d = glm::vec4(current, d.x, d.y, 0.0f);
}

// (A) History at p + motion, disocclusion test, raw temporal gradient.
void SpatioTemporalUpsampler::fetch_history(Pass& pass) {
    const UpsampleOptions& o = options_;
    const GBufferView& full = pass.full;
    const int width = pass.f.width, height = pass.f.height;
    const glm::vec2 full_jitter = pass.f.full_jitter;
    const bool ids = pass.history_ids;
    parallel_for(0, height, [&](int y0, int y1) {
        int64_t rejected = 0;
        for (int y = y0; y < y1; ++y) {
            for (int x = 0; x < width; ++x) {
                const float z = full.depth(x, y);
                const DepthKind kind = depth_kind(z);
                const glm::vec2 m = full.motion(x, y);
                glm::vec4 color(0.0f), delta(0.0f);
                float accepted = 0.0f;
                const float limit = float(kMaxImageSide);
                if (kind != DepthKind::Invalid && std::abs(m.x) < limit && std::abs(m.y) < limit) {
                    float expected = INFINITY;
                    if (kind == DepthKind::Surface) {
                        const glm::vec4 point = pass.camera.unprojector().point(
                            float(x) + 0.5f + full_jitter.x, float(y) + 0.5f + full_jitter.y, z);
                        expected = -(pass.to_previous_view * point).z;
                    }
                    // p + jitter + motion in the previous unjittered image; its pixels saw
                    // their centre + the previous jitter.
                    const float fx = float(x) + m.x + full_jitter.x - history_jitter_.x;
                    const float fy = float(y) + m.y + full_jitter.y - history_jitter_.y;
                    const int x0 = int(std::floor(fx)), y0b = int(std::floor(fy));
                    const float ax = fx - float(x0), ay = fy - float(y0b);
                    const uint32_t id = ids ? full.id(x, y) : 0u;
                    for (int ty = 0; ty < 2; ++ty) {
                        for (int tx = 0; tx < 2; ++tx) {
                            const float w = (tx ? ax : 1.0f - ax) * (ty ? ay : 1.0f - ay);
                            const int px = x0 + tx, py = y0b + ty;
                            if (w <= 0.0f || px < 0 || py < 0 || px >= width || py >= height)
                                continue;
                            if (ids && history_id_(px, py) != id) continue;
                            const float zp = history_depth_(px, py);
                            if (kind == DepthKind::Background) {
                                if (zp != INFINITY) continue;
                            } else {
                                const float tolerance =
                                    o.history_depth_tolerance * (ids ? 4.0f : 1.0f);
                                if (!(std::abs(zp - expected) <= tolerance * expected)) continue;
                            }
                            const glm::vec4 h = history_(px, py);
                            if (!(h.w > 0.0f)) continue;
                            color += w * h;
                            delta += w * deltas_(px, py);
                            accepted += w;
                        }
                    }
                }
                if (accepted > 1e-3f) {
                    reprojected_(x, y) = color / accepted;
                    next_deltas_(x, y) = delta / accepted;  // rotated below, after the spatial one
                } else {
                    reprojected_(x, y) = glm::vec4(0.0f);
                    next_deltas_(x, y) = glm::vec4(1.0f);
                    ++rejected;
                }
                if (o.gradient_steering) temporal_gradient(pass, x, y);
            }
        }
        pass.counters.rejected += rejected;
    });
}

// (B) Box low-pass of the temporal gradient, slightly wider than a low pixel.
void SpatioTemporalUpsampler::smooth_gradient(const Pass& pass) {
    const int width = pass.f.width, height = pass.f.height;
    const int radius = options_.gradient_radius > 0
                           ? options_.gradient_radius
                           : int(std::ceil(std::max(pass.f.scale.x, pass.f.scale.y))) + 1;
    parallel_for(0, height, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            for (int x = 0; x < width; ++x) {
                const int a = std::max(0, x - radius), b = std::min(width - 1, x + radius);
                float sum = 0.0f;
                for (int i = a; i <= b; ++i) sum += gradient_(i, y);
                gradient_tmp_(x, y) = sum / float(b - a + 1);
            }
        }
    });
    parallel_for(0, height, [&](int y0, int y1) {
        for (int y = y0; y < y1; ++y) {
            const int a = std::max(0, y - radius), b = std::min(height - 1, y + radius);
            for (int x = 0; x < width; ++x) {
                float sum = 0.0f;
                for (int i = a; i <= b; ++i) sum += gradient_tmp_(x, i);
                gradient_(x, y) = sum / float(b - a + 1);
            }
        }
    });
}

// (C) Steered spatial filter blended with the history (eq. 7).
void SpatioTemporalUpsampler::filter(Pass& pass, ImageView<glm::vec4> out) {
    const UpsampleOptions& o = options_;
    const FrameContext& f = pass.f;
    const bool temporal = pass.temporal;
    const bool cached_taps = temporal && o.gradient_steering && !o.recompute_taps;
    parallel_for(0, f.height, [&](int y0, int y1) {
        int64_t used = 0, nonfinite = 0, unresolved = 0;
        for (int y = y0; y < y1; ++y) {
            for (int x = 0; x < f.width; ++x) {
                const glm::vec4 history_color = temporal ? reprojected_(x, y) : glm::vec4(0.0f);
                const bool history = history_color.w > 0.0f;
                float fade = 0.0f, gamma_k = o.gamma_unsteered;
                if (history) {
                    if (o.gradient_steering) {
                        const float c =
                            1.0f - std::clamp(o.gradient_gain * gradient_(x, y), 0.0f, 1.0f);
                        fade = std::min(1.0f, o.history_weight * c * c);
                        gamma_k = std::max(o.gamma_min, o.gamma_max * fade);
                    } else {
                        fade = std::min(1.0f, o.history_weight * o.fixed_falloff);
                    }
                } else if (o.gradient_steering) {
                    gamma_k = o.gamma_min;
                }
                const SpatialResult s =
                    combine(f, x, y,
                            cached_taps ? Taps{tap_geometric_(x, y), tap_base_(x, y)}
                                        : compute_taps(f, x, y),
                            gamma_k);
                nonfinite += s.nonfinite;
                glm::vec4 result(s.color.x, s.color.y, s.color.z, 0.0f);
                float weight = s.weight;
                glm::vec4 h = history_color;
                if (history && o.history_clamp >= 0.0f && s.lo.x <= s.hi.x) {
                    const glm::vec3 margin = o.history_clamp * (s.hi - s.lo);
                    const glm::vec3 c = glm::clamp(glm::vec3(h), s.lo - margin, s.hi + margin);
                    h = glm::vec4(c, h.w);
                }
                if (history && fade > 0.0f) {
                    const float hw = fade * h.w;
                    const float total = s.weight + hw;
                    result = (s.weight * s.color + hw * h) / total;
                    weight = std::min(total, o.max_history_weight);
                    ++used;
                } else if (!(s.weight > 0.0f)) {
                    ++unresolved;
                }
                const bool covered = depth_kind(pass.full.depth(x, y)) == DepthKind::Surface;
                out(x, y) = glm::vec4(result.x, result.y, result.z, covered ? 1.0f : 0.0f);
                next_history_(x, y) = glm::vec4(result.x, result.y, result.z, weight);
                if (!temporal || !o.gradient_steering) next_deltas_(x, y) = glm::vec4(0.0f);
            }
        }
        pass.counters.used += used;
        pass.counters.nonfinite += nonfinite;
        pass.counters.unresolved += unresolved;
    });
}

// (D) This frame's result, depth and ids become the history of the next.
void SpatioTemporalUpsampler::keep_history(const Pass& pass) {
    const GBufferView& full = pass.full;
    std::swap(history_, next_history_);
    std::swap(deltas_, next_deltas_);
    for (int y = 0; y < pass.f.height; ++y) {
        std::memcpy(&history_depth_(0, y), full.depth.row(y),
                    sizeof(float) * std::size_t(pass.f.width));
        if (!full.id.empty())
            std::memcpy(&history_id_(0, y), full.id.row(y),
                        sizeof(uint32_t) * std::size_t(pass.f.width));
    }
    history_jitter_ = pass.f.full_jitter;
    history_has_ids_ = !full.id.empty();
    has_history_ = true;
}

}  // namespace reprise::warp
