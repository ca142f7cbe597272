// Spatio-temporal upsampling on the GPU: warp/src/upsample.cpp's passes and arithmetic as compute
// shaders. (A) the history at p + motion with its disocclusion test, the 2x2 taps and the raw
// temporal gradient; (B) the gradient's box low-pass, a row pass and a column pass; (C) the
// steered spatial filter blended with the history. The history (colour and weight, the last
// three gradients, depth and ids) stays in textures, swapped with this frame's each call.
#include "reprise/gpu/upsampler.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>
#include <utility>

#include "state.hpp"

namespace reprise::gpu {

namespace {

// What every pass reads: the low colour and the guides, the frame's constants, equations 2 and 3.
constexpr const char* kCommon = R"(
layout(binding = 0) uniform highp sampler2D low;
layout(binding = 1) uniform highp sampler2D depth_map;
layout(binding = 2) uniform highp sampler2D normal_map;
layout(binding = 3) uniform highp usampler2D id_map;
uniform ivec2 size, low_size;
uniform highp vec2 jitter, full_jitter, scale;
uniform highp float diagonal, epsilon, floor3, depth_sigma, normal_sigma;
uniform bool has_normals, ids, separable;

const int SURFACE = 0, BACKGROUND = 1, INVALID = 2;
int depth_kind(highp float z) {
    if (positive_inf(z)) return BACKGROUND;
    return finite(z) && z > 0.0 ? SURFACE : INVALID;
}

highp float fast_log2(highp float x) {
    uint bits = floatBitsToUint(x);
    highp float exponent = float(int((bits >> 23) & 0xffu) - 127);
    highp float m = uintBitsToFloat((bits & 0x007fffffu) | 0x3f800000u);
    PRECISE highp float t = (m - 1.0) / (m + 1.0);
    PRECISE highp float t2 = t * t;
    PRECISE highp float r =
        exponent + t * (2.8853900818 + t2 * (0.9617966939 + t2 * (0.5770780164 + t2 * 0.4121985232)));
    return r;
}
highp float fast_exp2(highp float e) {
    if (e < -126.0) return 0.0;
    highp float whole = floor(e);
    PRECISE highp float frac = e - whole;
    PRECISE highp float p =
        1.0 + frac * (0.6931471806 +
                      frac * (0.2402265070 +
                              frac * (0.0555041087 + frac * (0.0096181291 + frac * 0.0013333558))));
    PRECISE highp float r = p * uintBitsToFloat(uint(int(whole) + 127) << 23);
    return r;
}
highp float fast_pow(highp float base, highp float gamma) {
    PRECISE highp float e = gamma * fast_log2(base);
    return fast_exp2(e);
}
highp float falloff_of_base(highp float base, highp float gamma) {
    PRECISE highp float cube = base * base * base;
    if (gamma == 3.0) return cube;
    if (gamma == 1.0) return base;
    if (gamma <= 0.0) return 1.0;
    return fast_pow(base, gamma);
}
highp float steered_power(highp float base, highp float gamma) {
    if (!(gamma > 0.0)) return 1.0;
    if (gamma > 8.0) return fast_pow(base, gamma);
    int whole = int(gamma);
    PRECISE highp float lower = 1.0;
    for (int i = 0; i < whole; ++i) lower *= base;
    PRECISE highp float frac = gamma - float(whole);
    PRECISE highp float r = frac > 0.0 ? lower * ((1.0 - frac) + frac * base) : lower;
    return r;
}
highp float falloff(highp float ratio, highp float gamma) {
    PRECISE highp float base = max(epsilon, 1.0 - ratio);
    return falloff_of_base(base, gamma);
}

struct Guide {
    highp float depth;
    int kind;
    highp vec3 normal;
    uint id;
};
Guide guide_at(ivec2 p) {
    highp float z = texelFetch(depth_map, p, 0).r;
    return Guide(z, depth_kind(z), has_normals ? texelFetch(normal_map, p, 0).rgb : vec3(0.0),
                 ids ? texelFetch(id_map, p, 0).r : 0u);
}

// Geometric part of w_s (eq. 2) between full pixels i and j, and the id test.
highp float geometric_weight(Guide i, Guide j) {
    highp float w = 1.0;
    if (i.kind == SURFACE && j.kind == SURFACE) {
        PRECISE highp float dz = (i.depth - j.depth) / (depth_sigma * i.depth);
        PRECISE highp float r = dz * dz;
        w = falloff(r, 3.0);
    } else if (!(i.kind == BACKGROUND && j.kind == BACKGROUND)) {
        return floor3;
    }
    if (has_normals) {
        PRECISE highp float d =
            i.normal.x * j.normal.x + i.normal.y * j.normal.y + i.normal.z * j.normal.z;
        PRECISE highp float failed = floor3 * w;
        if (!finite(d)) return failed;
        bool zero_i = i.normal == vec3(0.0), zero_j = j.normal == vec3(0.0);
        if (zero_i != zero_j) {
            w = failed;
        } else if (!zero_i) {
            PRECISE highp float a = max(0.0, 1.0 - d);
            PRECISE highp float r = a * a / (normal_sigma * normal_sigma);
            PRECISE highp float v = w * falloff(r, 3.0);
            w = v;
        }
    }
    PRECISE highp float other = w * floor3;
    return ids && i.id != j.id ? other : w;
}

ivec2 tap_origin(ivec2 p) {
    PRECISE highp vec2 q =
        (vec2(float(p.x) + 0.5, float(p.y) + 0.5) + full_jitter - jitter) / scale - 0.5;
    return ivec2(floor(q));
}

// The 2x2 nearest low samples of full pixel p: geometric weights and the image-space base.
void compute_taps(ivec2 p, out highp vec4 geometric, out highp vec4 base) {
    ivec2 o = tap_origin(p);
    Guide here = guide_at(p);
    PRECISE highp float px = float(p.x) + 0.5 + full_jitter.x;
    PRECISE highp float py = float(p.y) + 0.5 + full_jitter.y;
    for (int dv = 0; dv < 2; ++dv) {
        int v = clamp(o.y + dv, 0, low_size.y - 1);
        PRECISE highp float sy = (float(v) + 0.5) * scale.y + jitter.y;
        int gy = clamp(int(floor(sy - full_jitter.y)), 0, size.y - 1);
        for (int du = 0; du < 2; ++du) {
            int u = clamp(o.x + du, 0, low_size.x - 1);
            PRECISE highp float sx = (float(u) + 0.5) * scale.x + jitter.x;
            int gx = clamp(int(floor(sx - full_jitter.x)), 0, size.x - 1);
            PRECISE highp float dx = sx - px, dy = sy - py;
            PRECISE highp float tent =
                max(epsilon, 1.0 - abs(dx) / scale.x) * max(epsilon, 1.0 - abs(dy) / scale.y);
            PRECISE highp float radial = max(epsilon, 1.0 - sqrt(dx * dx + dy * dy) / diagonal);
            base[dv * 2 + du] = separable ? tent : radial;
            geometric[dv * 2 + du] = geometric_weight(here, guide_at(ivec2(gx, gy)));
        }
    }
}

struct Spatial {
    highp vec4 color;
    highp float weight;
    uint nonfinite;
    highp vec3 lo, hi;
};

// Eq. 6 over the 2x2 nearest low samples with image-space fall-off gamma_k.
Spatial combine(ivec2 p, highp vec4 geometric, highp vec4 base, highp float gamma_k) {
    ivec2 o = tap_origin(p);
    highp float inf = uintBitsToFloat(0x7f800000u);
    Spatial r = Spatial(vec4(0.0), 0.0, 0u, vec3(inf), vec3(-inf));
    PRECISE highp vec4 sum = vec4(0.0);
    PRECISE highp float weight = 0.0;
    for (int dv = 0; dv < 2; ++dv) {
        int v = clamp(o.y + dv, 0, low_size.y - 1);
        for (int du = 0; du < 2; ++du) {
            int u = clamp(o.x + du, 0, low_size.x - 1);
            highp vec4 c = texelFetch(low, ivec2(u, v), 0);
            if (!(finite(c.x) && finite(c.y) && finite(c.z))) {
                ++r.nonfinite;
                continue;
            }
            highp float g = geometric[dv * 2 + du];
            PRECISE highp float w = g * steered_power(base[dv * 2 + du], gamma_k);
            sum = sum + w * vec4(c.xyz, 0.0);
            weight = weight + w;
            if (g > floor3) {
                r.lo = min(r.lo, c.xyz);
                r.hi = max(r.hi, c.xyz);
            }
        }
    }
    r.weight = weight;
    if (weight > 0.0) {
        PRECISE highp vec4 normalized = sum / weight;
        r.color = normalized;
    }
    return r;
}

highp float luminance(highp vec4 c) {
    PRECISE highp float y = 0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z;
    return y;
}

)";

// (A) The history at p + motion (bilinear, taps rejected by depth and id), the taps, the raw
// temporal gradient and the rotated differences.
constexpr const char* kFetchHistory = R"(
layout(binding = 4) uniform highp sampler2D motion_map;
layout(binding = 5) uniform highp sampler2D history;
layout(binding = 6) uniform highp sampler2D deltas;
layout(binding = 7) uniform highp sampler2D history_depth;
layout(binding = 8) uniform highp usampler2D history_id;
layout(binding = 0, rgba32f) writeonly uniform highp image2D reprojected;
layout(binding = 1, rgba32f) writeonly uniform highp image2D next_deltas;
layout(binding = 2, r32f) writeonly uniform highp image2D gradient;
layout(binding = 3, rgba32f) writeonly uniform highp image2D tap_geometric;
layout(binding = 4, rgba32f) writeonly uniform highp image2D tap_base;
uniform highp mat4 P, to_previous_view;
uniform highp vec2 history_jitter;
uniform highp float depth_tolerance, gamma_unsteered, limit;
uniform bool history_ids, steering;

// Unprojector::point for an axis-aligned projection, at pixel position c.
highp vec4 point_at(highp vec2 c, highp float z) {
    PRECISE highp float nx = 2.0 * c.x / float(size.x) - 1.0;
    PRECISE highp float ny = 1.0 - 2.0 * c.y / float(size.y);
    highp float zv = -z;
    PRECISE highp float wc = P[2][3] * zv + P[3][3];
    PRECISE highp float vx = (nx * wc - P[2][0] * zv - P[3][0]) / P[0][0];
    PRECISE highp float vy = (ny * wc - P[2][1] * zv - P[3][1]) / P[1][1];
    return vec4(vx, vy, zv, 1.0);
}

void fetch(ivec2 p) {
    highp float z = texelFetch(depth_map, p, 0).r;
    int kind = depth_kind(z);
    highp vec2 m = texelFetch(motion_map, p, 0).rg;
    PRECISE highp vec4 color = vec4(0.0), delta = vec4(0.0);
    PRECISE highp float accepted = 0.0;
    if (kind != INVALID && abs(m.x) < limit && abs(m.y) < limit) {
        highp float expected = uintBitsToFloat(0x7f800000u);
        if (kind == SURFACE) {
            highp vec4 v = point_at(vec2(float(p.x) + 0.5 + full_jitter.x,
                                         float(p.y) + 0.5 + full_jitter.y), z);
            highp mat4 M = to_previous_view;
            PRECISE highp float e = (M[0][2] * v.x + M[1][2] * v.y) + (M[2][2] * v.z + M[3][2] * v.w);
            expected = -e;
        }
        PRECISE highp float fx = float(p.x) + m.x + full_jitter.x - history_jitter.x;
        PRECISE highp float fy = float(p.y) + m.y + full_jitter.y - history_jitter.y;
        int x0 = int(floor(fx)), y0 = int(floor(fy));
        PRECISE highp float ax = fx - float(x0), ay = fy - float(y0);
        uint id = history_ids ? texelFetch(id_map, p, 0).r : 0u;
        for (int ty = 0; ty < 2; ++ty) {
            for (int tx = 0; tx < 2; ++tx) {
                PRECISE highp float w = (tx != 0 ? ax : 1.0 - ax) * (ty != 0 ? ay : 1.0 - ay);
                ivec2 q = ivec2(x0 + tx, y0 + ty);
                if (w <= 0.0 || q.x < 0 || q.y < 0 || q.x >= size.x || q.y >= size.y) continue;
                if (history_ids && texelFetch(history_id, q, 0).r != id) continue;
                highp float zp = texelFetch(history_depth, q, 0).r;
                if (kind == BACKGROUND) {
                    if (!positive_inf(zp)) continue;
                } else {
                    PRECISE highp float gap = abs(zp - expected);
                    PRECISE highp float allowed = depth_tolerance * expected;
                    if (!(gap <= allowed)) continue;
                }
                highp vec4 h = texelFetch(history, q, 0);
                if (!(h.w > 0.0)) continue;
                color = color + w * h;
                delta = delta + w * texelFetch(deltas, q, 0);
                accepted = accepted + w;
            }
        }
    }
    highp vec4 h = vec4(0.0), d = vec4(1.0);
    if (accepted > 1e-3) {
        PRECISE highp vec4 hc = color / accepted, dd = delta / accepted;
        h = hc;
        d = dd;
    } else {
        atomicAdd(group_counts[0], 1u);
    }
    imageStore(reprojected, p, h);
    if (!steering) {
        imageStore(next_deltas, p, d);
        return;
    }
    highp vec4 geometric, base;
    compute_taps(p, geometric, base);
    imageStore(tap_geometric, p, geometric);
    imageStore(tap_base, p, base);
    highp float current = 1.0, g = 1.0;
    if (h.w > 0.0) {
        Spatial s = combine(p, geometric, base, gamma_unsteered);
        highp float a = luminance(s.color), b = luminance(h);
        highp float range = max(abs(a), abs(b));
        PRECISE highp float relative = (a - b) / range;
        current = s.weight > 0.0 && range > 0.0 ? clamp(relative, -1.0, 1.0) : 0.0;
        PRECISE highp float mixed = 0.4 * current + 0.3 * d.x + 0.2 * d.y + 0.1 * d.z;
        g = min(1.0, abs(mixed));
    }
    imageStore(gradient, p, vec4(g));
    imageStore(next_deltas, p, vec4(current, d.x, d.y, 0.0));
}

void main() {
    count_begin();
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x < size.x && p.y < size.y) fetch(p);
    count_end();
}
)";

// (B) One axis of the gradient's box low-pass.
constexpr const char* kBox = R"(
layout(binding = 0) uniform highp sampler2D from;
layout(binding = 0, r32f) writeonly uniform highp image2D to;
uniform ivec2 size, axis;
uniform int radius;
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= size.x || p.y >= size.y) return;
    int at = axis.x != 0 ? p.x : p.y, n = axis.x != 0 ? size.x : size.y;
    int a = max(0, at - radius), b = min(n - 1, at + radius);
    PRECISE highp float sum = 0.0;
    for (int i = a; i <= b; ++i) sum = sum + texelFetch(from, axis.x != 0 ? ivec2(i, p.y) : ivec2(p.x, i), 0).r;
    PRECISE highp float mean = sum / float(b - a + 1);
    imageStore(to, p, vec4(mean));
}
)";

// (C) The steered spatial filter blended with the history (eq. 7).
constexpr const char* kFilter = R"(
layout(binding = 4) uniform highp sampler2D reprojected;
layout(binding = 5) uniform highp sampler2D gradient;
layout(binding = 6) uniform highp sampler2D tap_geometric;
layout(binding = 7) uniform highp sampler2D tap_base;
layout(binding = 0, rgba32f) writeonly uniform highp image2D out_color;
layout(binding = 1, rgba32f) writeonly uniform highp image2D next_history;
layout(binding = 2, rgba32f) writeonly uniform highp image2D next_deltas;
uniform bool temporal, steering, cached_taps;
uniform highp float history_weight, fixed_falloff, max_history_weight, gamma_max, gamma_min,
    gamma_unsteered, gradient_gain, history_clamp;

void filter_pixel(ivec2 p) {
    highp vec4 history_color = temporal ? texelFetch(reprojected, p, 0) : vec4(0.0);
    bool history = history_color.w > 0.0;
    highp float fade = 0.0, gamma_k = gamma_unsteered;
    if (history) {
        if (steering) {
            PRECISE highp float c = 1.0 - clamp(gradient_gain * texelFetch(gradient, p, 0).r, 0.0, 1.0);
            PRECISE highp float f = history_weight * c * c;
            fade = min(1.0, f);
            PRECISE highp float g = gamma_max * fade;
            gamma_k = max(gamma_min, g);
        } else {
            PRECISE highp float f = history_weight * fixed_falloff;
            fade = min(1.0, f);
        }
    } else if (steering) {
        gamma_k = gamma_min;
    }
    highp vec4 geometric, base;
    if (cached_taps) {
        geometric = texelFetch(tap_geometric, p, 0);
        base = texelFetch(tap_base, p, 0);
    } else {
        compute_taps(p, geometric, base);
    }
    Spatial s = combine(p, geometric, base, gamma_k);
    if (s.nonfinite != 0u) atomicAdd(group_counts[1], s.nonfinite);
    highp vec4 result = vec4(s.color.xyz, 0.0);
    highp float weight = s.weight;
    highp vec4 h = history_color;
    if (history && history_clamp >= 0.0 && s.lo.x <= s.hi.x) {
        PRECISE highp vec3 margin = history_clamp * (s.hi - s.lo);
        PRECISE highp vec3 lo = s.lo - margin, hi = s.hi + margin;
        h = vec4(clamp(h.xyz, lo, hi), h.w);
    }
    if (history && fade > 0.0) {
        PRECISE highp float hw = fade * h.w;
        PRECISE highp float total = s.weight + hw;
        PRECISE highp vec4 blended = (s.weight * s.color + hw * h) / total;
        result = blended;
        weight = min(total, max_history_weight);
        atomicAdd(group_counts[0], 1u);
    } else if (!(s.weight > 0.0)) {
        atomicAdd(group_counts[2], 1u);
    }
    bool covered = depth_kind(texelFetch(depth_map, p, 0).r) == SURFACE;
    imageStore(out_color, p, vec4(result.xyz, covered ? 1.0 : 0.0));
    imageStore(next_history, p, vec4(result.xyz, weight));
    if (!temporal || !steering) imageStore(next_deltas, p, vec4(0.0));
}

void main() {
    count_begin();
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x < size.x && p.y < size.y) filter_pixel(p);
    count_end();
}
)";

// (D) This frame's depth and ids become the next one's history.
constexpr const char* kKeepGuides = R"(
layout(binding = 0) uniform highp sampler2D depth_map;
layout(binding = 1) uniform highp usampler2D id_map;
layout(binding = 0, r32f) writeonly uniform highp image2D kept_depth;
layout(binding = 1, r32ui) writeonly uniform highp uimage2D kept_id;
uniform ivec2 size;
uniform bool ids;
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= size.x || p.y >= size.y) return;
    imageStore(kept_depth, p, vec4(texelFetch(depth_map, p, 0).r));
    if (ids) imageStore(kept_id, p, uvec4(texelFetch(id_map, p, 0).r));
}
)";

void uniform_float(GLuint program, const char* name, float v) {
    glUniform1f(glGetUniformLocation(program, name), v);
}
void uniform_int(GLuint program, const char* name, int v) {
    glUniform1i(glGetUniformLocation(program, name), v);
}
void uniform_vec2(GLuint program, const char* name, glm::vec2 v) {
    glUniform2f(glGetUniformLocation(program, name), v.x, v.y);
}

}  // namespace

struct Upsampler::State {
    Context* context = nullptr;
    warp::UpsampleOptions options;
    GLuint fetch_program = 0, box_program = 0, filter_program = 0, keep_program = 0, counts = 0;
    // Inputs, and the history double-buffered: this frame's guides become the next one's history.
    Texture low, depth, normal, id, motion, history_depth, history_id;
    Texture history, next_history, deltas, next_deltas;
    Texture reprojected, gradient, gradient_tmp, tap_geometric, tap_base, out;
    glm::vec2 history_jitter{0.0f};
    bool history_has_ids = false, has_history = false;
    NonfiniteRepair guide_repair;
    Timings timings, total;
    std::size_t frames = 0;
    bool keep = false;                    // keep_output
    ImageView<const glm::vec4> kept_for;  // the `out` the last call kept its result for
    GBufferView guides;                   // the depth and motion the last call uploaded

    void count_frame() {
        total.upload_ms += timings.upload_ms;
        total.compute_ms += timings.compute_ms;
        total.download_ms += timings.download_ms;
        ++frames;
    }
};

Upsampler::Upsampler() : state_(std::make_unique<State>()) {}

Upsampler::~Upsampler() {
    State& u = *state_;
    if (!u.context) return;
    u.context->make_current();
    for (Texture* t :
         {&u.low, &u.depth, &u.normal, &u.id, &u.motion, &u.history_depth, &u.history_id,
          &u.history, &u.next_history, &u.deltas, &u.next_deltas, &u.reprojected, &u.gradient,
          &u.gradient_tmp, &u.tap_geometric, &u.tap_base, &u.out})
        glDeleteTextures(1, &t->name);
    for (GLuint program : {u.fetch_program, u.box_program, u.filter_program, u.keep_program})
        glDeleteProgram(program);
    glDeleteBuffers(1, &u.counts);
}

Status Upsampler::create(Context& context, const warp::UpsampleOptions& options,
                         std::unique_ptr<Upsampler>& upsampler) {
    const warp::UpsampleOptions& o = options;
    if (!(o.depth_sigma > 0.0f && o.normal_sigma > 0.0f && o.epsilon > 0.0f && o.epsilon < 1.0f))
        return Status::error(
            "gpu upsample: depth_sigma and normal_sigma must be > 0, epsilon in (0, 1)");
    std::unique_ptr<Upsampler> made(new Upsampler());
    State& u = *made->state_;
    ContextState& s = *context.state_;
    REPRISE_TRY(s.gl->acquire());
    u.context = &context;
    u.options = options;
    const std::string common = std::string(kComputeHeader) + kGroupCounts + kCommon;
    REPRISE_TRY(
        gl::link_compute((common + kFetchHistory).c_str(), "upsample history", u.fetch_program));
    REPRISE_TRY(gl::link_compute((std::string(kComputeHeader) + kBox).c_str(), "upsample box",
                                 u.box_program));
    REPRISE_TRY(gl::link_compute((common + kFilter).c_str(), "upsample filter", u.filter_program));
    REPRISE_TRY(gl::link_compute((std::string(kComputeHeader) + kKeepGuides).c_str(),
                                 "upsample history guides", u.keep_program));
    u.counts = s.make_counters(4 * sizeof(GLuint));
    upsampler = std::move(made);
    return {};
}

void Upsampler::reset() {
    state_->has_history = false;
    state_->kept_for = {};
    state_->guides = {};
}

void Upsampler::keep_output(bool keep) {
    if (keep == state_->keep) return;
    state_->keep = keep;
    state_->kept_for = {};
}

const Context& Upsampler::context() const { return *state_->context; }

bool Upsampler::output_kept() const { return !state_->kept_for.empty(); }

unsigned Upsampler::kept_for(ImageView<const glm::vec4> out) const {
    const ImageView<const glm::vec4>& k = state_->kept_for;
    const bool same = !k.empty() && k.data == out.data && k.width == out.width &&
                      k.height == out.height && k.stride == out.stride;
    return same ? state_->out.name : 0u;
}

FrameOnGpu Upsampler::on_gpu(const GBufferView& frame) const {
    const State& u = *state_;
    auto same = [](const auto& a, const auto& b) {
        return !a.empty() && a.data == b.data && a.width == b.width && a.height == b.height &&
               a.stride == b.stride;
    };
    FrameOnGpu held{.color = kept_for(frame.color)};
    if (same(u.guides.depth, frame.depth) && same(u.guides.motion, frame.motion)) {
        held.depth = u.depth.name;
        held.motion = u.motion.name;
    }
    return held;
}

Status Upsampler::download_kept(ImageView<glm::vec4> out) {
    State& u = *state_;
    if (!kept_for(out)) return Status::error("gpu upsample: nothing kept for this image");
    ContextState& s = *u.context->state_;
    REPRISE_TRY(s.gl->acquire());
    auto t = std::chrono::steady_clock::now();
    s.download(u.out, out.data, out.stride);
    u.kept_for = {};
    REPRISE_TRY(gl::check_errors("gpu upsample download"));
    u.total.download_ms += finish_ms(t);  // the frame's download, made late
    return {};
}

const Timings& Upsampler::timings() const { return state_->timings; }
const Timings& Upsampler::total() const { return state_->total; }
std::size_t Upsampler::frames() const { return state_->frames; }

// The frame's inputs on the GPU (motion, id and normal 0 where absent).
struct UpsampleInputs {
    GLuint low = 0;
    int low_width = 0, low_height = 0;
    GLuint depth = 0, motion = 0, id = 0, normal = 0;
    int width = 0, height = 0;
    Camera camera;
    glm::vec2 jitter{0.0f};
};

// The three passes and the history kept, `out` written; counts into stats.
Status upsample_passes(Upsampler::State& u, ContextState& s, const UpsampleInputs& in, GLuint out,
                       warp::UpsampleStats& stats) {
    const warp::UpsampleOptions& o = u.options;
    const int width = in.width, height = in.height;
    if (!(u.history.width == width && u.history.height == height)) u.has_history = false;
    for (Texture* texture : {&u.history, &u.next_history, &u.deltas, &u.next_deltas, &u.reprojected,
                             &u.tap_geometric, &u.tap_base})
        texture->ensure(GL_RGBA32F, width, height);
    for (Texture* texture : {&u.history_depth, &u.gradient, &u.gradient_tmp})
        texture->ensure(GL_R32F, width, height);
    u.history_id.ensure(GL_R32UI, width, height);
    auto bounded = [](glm::vec2 v) {
        const float limit = float(kMaxImageSide);
        if (!std::isfinite(v.x) || !std::isfinite(v.y)) return glm::vec2(0.0f);
        return glm::clamp(v, glm::vec2(-limit), glm::vec2(limit));
    };
    const glm::vec2 jitter = bounded(in.jitter), full_jitter = bounded(in.camera.jitter);
    const glm::vec2 scale(float(width) / float(in.low_width), float(height) / float(in.low_height));
    const bool ids = o.id_test && in.id != 0;
    const bool temporal = u.has_history && in.motion != 0 && o.history_weight > 0.0f;
    u.has_history = false;  // until this frame's passes all succeeded
    const bool history_ids = ids && u.history_has_ids;
    const StaticReprojection camera(in.camera, in.camera.prev_view, in.camera.prev_projection,
                                    width, height);
    if (temporal && !camera.unprojector().axis_aligned())
        return Status::error("gpu upsample: the full camera's projection is skewed");
    // The frame's constants of kCommon, set on `program` (in use).
    auto set_common = [&](GLuint program) {
        glUniform2i(glGetUniformLocation(program, "size"), width, height);
        glUniform2i(glGetUniformLocation(program, "low_size"), in.low_width, in.low_height);
        uniform_vec2(program, "jitter", jitter);
        uniform_vec2(program, "full_jitter", full_jitter);
        uniform_vec2(program, "scale", scale);
        uniform_float(program, "diagonal", std::sqrt(scale.x * scale.x + scale.y * scale.y));
        uniform_float(program, "epsilon", o.epsilon);
        uniform_float(program, "floor3", o.epsilon * o.epsilon * o.epsilon);
        uniform_float(program, "depth_sigma", o.depth_sigma);
        uniform_float(program, "normal_sigma", o.normal_sigma);
        uniform_int(program, "has_normals", in.normal != 0);
        uniform_int(program, "ids", ids);
        uniform_int(program, "separable", o.separable_filter);
        uniform_float(program, "gamma_unsteered", o.gamma_unsteered);
    };
    GLuint counts[3] = {0, 0, 0};
    ContextState::reset_counters(u.counts, 4);
    if (temporal) {  // (A)
        const GLuint program = u.fetch_program;
        glUseProgram(program);
        s.bind_inputs({in.low, in.depth, in.normal, in.id, in.motion, u.history.name, u.deltas.name,
                       u.history_depth.name, u.history_id.name});
        glBindImageTexture(0, u.reprojected.name, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        glBindImageTexture(1, u.next_deltas.name, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        glBindImageTexture(2, u.gradient.name, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
        glBindImageTexture(3, u.tap_geometric.name, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        glBindImageTexture(4, u.tap_base.name, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        set_common(program);
        glUniformMatrix4fv(glGetUniformLocation(program, "P"), 1, GL_FALSE,
                           &camera.unprojector().projection()[0][0]);
        glUniformMatrix4fv(glGetUniformLocation(program, "to_previous_view"), 1, GL_FALSE,
                           &camera.to_view()[0][0]);
        uniform_vec2(program, "history_jitter", u.history_jitter);
        uniform_float(program, "depth_tolerance",
                      o.history_depth_tolerance * (history_ids ? 4.0f : 1.0f));
        uniform_float(program, "limit", float(kMaxImageSide));
        uniform_int(program, "history_ids", history_ids);
        uniform_int(program, "steering", o.gradient_steering);
        dispatch(width, height);
        s.read_counters(u.counts, counts, sizeof counts);
        ContextState::reset_counters(u.counts, 4);
    }
    if (temporal && o.gradient_steering) {  // (B)
        const int radius = o.gradient_radius > 0 ? o.gradient_radius
                                                 : int(std::ceil(std::max(scale.x, scale.y))) + 1;
        glUseProgram(u.box_program);
        glUniform2i(glGetUniformLocation(u.box_program, "size"), width, height);
        uniform_int(u.box_program, "radius", radius);
        for (int axis = 0; axis < 2; ++axis) {
            const GLuint from = axis == 0 ? u.gradient.name : u.gradient_tmp.name;
            const GLuint to = axis == 0 ? u.gradient_tmp.name : u.gradient.name;
            s.bind_inputs({from});
            glBindImageTexture(0, to, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
            glUniform2i(glGetUniformLocation(u.box_program, "axis"), axis == 0, axis == 1);
            dispatch(width, height);
        }
    }
    {  // (C)
        const GLuint program = u.filter_program;
        glUseProgram(program);
        s.bind_inputs({in.low, in.depth, in.normal, in.id, u.reprojected.name, u.gradient.name,
                       u.tap_geometric.name, u.tap_base.name});
        glBindImageTexture(0, out, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        glBindImageTexture(1, u.next_history.name, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        glBindImageTexture(2, u.next_deltas.name, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        set_common(program);
        uniform_int(program, "temporal", temporal);
        uniform_int(program, "steering", o.gradient_steering);
        uniform_int(program, "cached_taps", temporal && o.gradient_steering && !o.recompute_taps);
        uniform_float(program, "history_weight", o.history_weight);
        uniform_float(program, "fixed_falloff", o.fixed_falloff);
        uniform_float(program, "max_history_weight", o.max_history_weight);
        uniform_float(program, "gamma_max", o.gamma_max);
        uniform_float(program, "gamma_min", o.gamma_min);
        uniform_float(program, "gradient_gain", o.gradient_gain);
        uniform_float(program, "history_clamp", o.history_clamp);
        dispatch(width, height);
    }
    ContextState::unbind_inputs();
    glUseProgram(0);
    GLuint filtered[3] = {0, 0, 0};  // used, non-finite samples, unresolved
    s.read_counters(u.counts, filtered, sizeof filtered);
    {  // (D) the history of the next frame: this one's result (swapped below), depth and ids
        glUseProgram(u.keep_program);
        s.bind_inputs({in.depth, in.id});
        glBindImageTexture(0, u.history_depth.name, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
        glBindImageTexture(1, u.history_id.name, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32UI);
        glUniform2i(glGetUniformLocation(u.keep_program, "size"), width, height);
        uniform_int(u.keep_program, "ids", in.id != 0);
        dispatch(width, height);
        ContextState::unbind_inputs();
        glUseProgram(0);
    }
    REPRISE_TRY(gl::check_errors("gpu upsample"));
    std::swap(u.history, u.next_history);
    std::swap(u.deltas, u.next_deltas);
    u.history_jitter = full_jitter;
    u.history_has_ids = in.id != 0;
    u.has_history = true;
    stats.history_rejected = counts[0];
    stats.history_used = filtered[0];
    stats.nonfinite_samples = filtered[1];
    stats.unresolved = filtered[2];
    return {};
}

Status Upsampler::upsample(ImageView<const glm::vec4> low_color, glm::vec2 jitter_px,
                           const GBufferView& given, ImageView<glm::vec4> out,
                           warp::UpsampleStats* stats) {
    State& u = *state_;
    ContextState& s = *u.context->state_;
    u.timings = {};
    u.kept_for = {};
    u.guides = {};
    GBufferView guides = given;
    guides.color = {};
    NonfiniteCounts input_nonfinite;
    const GBufferView full = u.guide_repair.clean(guides, input_nonfinite);
    input_nonfinite.color = count_nonfinite({.color = low_color}).color;
    input_nonfinite.frames = input_nonfinite.total() > 0;
    const int width = full.depth.width, height = full.depth.height;
    auto sized = [&](int w, int h) { return w == width && h == height; };
    if (full.depth.empty() || low_color.empty())
        return Status::error("gpu upsample: needs the low colour and the full depth");
    if (!sized(out.width, out.height))
        return Status::error("gpu upsample: the output is not the full size");
    if (low_color.width > width || low_color.height > height)
        return Status::error("gpu upsample: the low colour is larger than the full image");
    if ((!full.normal.empty() && !sized(full.normal.width, full.normal.height)) ||
        (!full.id.empty() && !sized(full.id.width, full.id.height)) ||
        (!full.motion.empty() && !sized(full.motion.width, full.motion.height)))
        return Status::error("gpu upsample: a guide's size differs from the depth's");
    REPRISE_TRY(s.gl->acquire());
    auto t = std::chrono::steady_clock::now();
    u.low.ensure(GL_RGBA32F, low_color.width, low_color.height);
    u.depth.ensure(GL_R32F, width, height);
    u.out.ensure(GL_RGBA32F, width, height);
    if (!full.id.empty()) u.id.ensure(GL_R32UI, width, height);
    if (!full.motion.empty()) u.motion.ensure(GL_RG32F, width, height);
    if (!full.normal.empty()) u.normal.ensure(GL_RGB32F, width, height);
    s.upload(u.low, low_color.data, low_color.stride);
    s.upload(u.depth, full.depth.data, full.depth.stride);
    if (!full.id.empty()) s.upload(u.id, full.id.data, full.id.stride);
    if (!full.motion.empty()) s.upload(u.motion, full.motion.data, full.motion.stride);
    if (!full.normal.empty()) s.upload(u.normal, full.normal.data, full.normal.stride);
    u.timings.upload_ms = finish_ms(t);
    warp::UpsampleStats counted;
    REPRISE_TRY(upsample_passes(u, s,
                                {.low = u.low.name,
                                 .low_width = low_color.width,
                                 .low_height = low_color.height,
                                 .depth = u.depth.name,
                                 .motion = full.motion.empty() ? 0u : u.motion.name,
                                 .id = full.id.empty() ? 0u : u.id.name,
                                 .normal = full.normal.empty() ? 0u : u.normal.name,
                                 .width = width,
                                 .height = height,
                                 .camera = full.camera,
                                 .jitter = jitter_px},
                                u.out.name, counted));
    u.timings.compute_ms = finish_ms(t);
    if (!given.motion.empty()) u.guides = {.depth = given.depth, .motion = given.motion};
    if (u.keep) {
        u.kept_for = out;
    } else {
        s.download(u.out, out.data, out.stride);
        REPRISE_TRY(gl::check_errors("gpu upsample download"));
        u.timings.download_ms = finish_ms(t);
    }
    u.count_frame();
    counted.nonfinite = input_nonfinite;
    if (stats) *stats = counted;
    return {};
}

Status Upsampler::upsample(unsigned low_color, int low_width, int low_height, glm::vec2 jitter_px,
                           const GBufferTextures& full, unsigned normal, unsigned out,
                           warp::UpsampleStats* stats) {
    State& u = *state_;
    ContextState& s = *u.context->state_;
    u.timings = {};
    u.kept_for = {};
    u.guides = {};
    REPRISE_TRY(s.gl->acquire());
    const int w = full.width, h = full.height;
    if (w <= 0 || h <= 0 || low_width <= 0 || low_height <= 0 || low_width > w || low_height > h)
        return Status::error("gpu upsample: sizes " + std::to_string(low_width) + "x" +
                             std::to_string(low_height) + " (low) and " + std::to_string(w) + "x" +
                             std::to_string(h) + " (full) must be positive, the low one no larger");
    REPRISE_TRY(check_texture(low_color, GL_RGBA32F, low_width, low_height, "low colour"));
    REPRISE_TRY(check_texture(full.depth, GL_R32F, w, h, "full depth"));
    if (full.motion) REPRISE_TRY(check_texture(full.motion, GL_RG32F, w, h, "full motion"));
    if (full.id) REPRISE_TRY(check_texture(full.id, GL_R32UI, w, h, "full ids"));
    if (normal) REPRISE_TRY(check_texture(normal, GL_RGB32F, w, h, "full normals"));
    REPRISE_TRY(check_texture(out, GL_RGBA32F, w, h, "output colour"));
    if (out == low_color) return Status::error("gpu upsample: the output is the low colour");
    auto t = std::chrono::steady_clock::now();
    warp::UpsampleStats counted;
    REPRISE_TRY(upsample_passes(u, s,
                                {.low = low_color,
                                 .low_width = low_width,
                                 .low_height = low_height,
                                 .depth = full.depth,
                                 .motion = full.motion,
                                 .id = full.id,
                                 .normal = normal,
                                 .width = w,
                                 .height = h,
                                 .camera = full.camera,
                                 .jitter = jitter_px},
                                out, counted));
    u.timings.compute_ms = finish_ms(t);
    u.count_frame();
    if (stats) *stats = counted;
    return {};
}

}  // namespace reprise::gpu
