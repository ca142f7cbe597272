// warp::splat as compute passes, in the CPU's order. Each landing is appended to its target
// pixel's list (one scatter over the source); then each target pixel sorts its candidates by
// source index and z-tests them one after another as the CPU does (one gather over the target).
// A pixel that more than kSorted candidates reach (only under extreme convergence) takes, among
// those within the depth tolerance of its nearest one, the one landing nearest its centre, ties
// to the first in source order: the CPU's result where they do not chain across the tolerance.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <string>

#include "state.hpp"

namespace reprise::gpu {

namespace {

constexpr const char* kLanding = R"(
#define SORTED 16
layout(binding = 0) uniform highp sampler2D source_color;
layout(binding = 1) uniform highp sampler2D source_depth;
layout(binding = 2) uniform highp sampler2D source_motion;
// Per target pixel the head of its list; per landing its source index and the next landing.
layout(std430, binding = 1) buffer Lists { uint used; uint capacity; uint heads_and_nodes[]; };
uniform ivec2 source_size, target_size;
uniform highp float factor, tol_lo, tol_hi;
uniform int footprint;


struct Landing { ivec2 p0; ivec2 n; highp vec2 o; };

// warp/src/forward_splat.cpp's land(): the pixel-centre frame, kSnap, the footprint.
bool land(ivec2 p, highp vec2 m, out Landing l) {
    PRECISE highp float dx = (float(p.x) + 0.5) + factor * m.x - 0.5;
    PRECISE highp float dy = (float(p.y) + 0.5) + factor * m.y - 0.5;
    if (!(dx > -1.5 && dy > -1.5 && dx < float(target_size.x) + 0.5 &&
          dy < float(target_size.y) + 0.5))
        return false;
    if (footprint == 1) {
        int ix = int(floor(dx + 0.5)), iy = int(floor(dy + 0.5));
        l = Landing(ivec2(ix, iy), ivec2(1), vec2(dx - float(ix), dy - float(iy)));
    } else {
        const highp float snap = 1e-3;
        int ix = int(floor(dx + snap)), iy = int(floor(dy + snap));
        PRECISE highp float ox = dx - float(ix), oy = dy - float(iy);
        l = Landing(ivec2(ix, iy), ivec2(ox > snap ? 2 : 1, oy > snap ? 2 : 1), vec2(ox, oy));
    }
    return true;
}

bool source_lands(ivec2 p, out Landing l) {
    highp float z = texelFetch(source_depth, p, 0).r;
    highp vec2 m = texelFetch(source_motion, p, 0).rg;
    return nonnegative(z) && finite(m.x) && finite(m.y) && land(p, m, l);
}

uint closeness(highp float ox, highp float oy) {
    PRECISE highp float d2 = ox * ox + oy * oy;
    return uint(1 + min(254, int(d2 * 127.0)));
}

int pixels() { return target_size.x * target_size.y; }
int head(ivec2 t) { return t.y * target_size.x + t.x; }
)";

constexpr const char* kScatter = R"(
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= source_size.x || p.y >= source_size.y) return;
    Landing l;
    if (!source_lands(p, l)) return;
    uint index = uint(p.y) * uint(source_size.x) + uint(p.x);
    for (int j = 0; j < l.n.y; ++j)
        for (int i = 0; i < l.n.x; ++i) {
            ivec2 t = l.p0 + ivec2(i, j);
            if (t.x < 0 || t.y < 0 || t.x >= target_size.x || t.y >= target_size.y) continue;
            uint node = atomicAdd(used, 1u);
            if (node >= capacity) return;  // cannot happen: capacity is 4 per source pixel
            uint at = uint(pixels()) + 2u * node;
            heads_and_nodes[at] = index;
            heads_and_nodes[at + 1u] = atomicExchange(heads_and_nodes[head(t)], node);
        }
}
)";

// Per target pixel: the list emptied (CLEAR), or its candidates z-tested and the winner written.
constexpr const char* kGather = R"(
layout(binding = 3, rgba32f) writeonly uniform highp image2D out_color;
layout(binding = 4, r32f) writeonly uniform highp image2D out_depth;
layout(binding = 5, r32ui) writeonly uniform highp uimage2D out_covered;
layout(binding = 6, rgba32f) writeonly uniform highp image2D out_motion;
layout(std430, binding = 0) buffer Counts { uint counts[]; };
uniform bool carry_motion;
const uint NONE = 0xffffffffu;

ivec2 source_pixel(uint index) {
    return ivec2(int(index % uint(source_size.x)), int(index / uint(source_size.x)));
}
// Source `index`'s depth and closeness to target pixel t (it landed there).
void candidate(uint index, ivec2 t, out highp float z, out uint q) {
    ivec2 p = source_pixel(index);
    z = texelFetch(source_depth, p, 0).r;
    Landing l;
    source_lands(p, l);
    ivec2 k = t - l.p0;
    q = closeness(l.o.x - float(k.x), l.o.y - float(k.y));
}
uint next(uint node) { return heads_and_nodes[uint(pixels()) + 2u * node + 1u]; }
uint source_of(uint node) { return heads_and_nodes[uint(pixels()) + 2u * node]; }

// The CPU's order: sorted by source index, each z-tested against the one stored.
uint in_order(ivec2 t, uint first, out bool too_many) {
    uint sorted[SORTED];
    int n = 0;
    too_many = false;
    for (uint node = first; node != NONE; node = next(node)) {
        if (n == SORTED) { too_many = true; return NONE; }
        uint index = source_of(node);
        int k = n++;
        for (; k > 0 && sorted[k - 1] > index; --k) sorted[k] = sorted[k - 1];
        sorted[k] = index;
    }
    uint winner = NONE, stored_q = 0u;
    highp float stored_z = 0.0;
    for (int k = 0; k < n; ++k) {
        highp float z;
        uint q;
        candidate(sorted[k], t, z, q);
        PRECISE highp float lo = stored_z * tol_lo, hi = stored_z * tol_hi;
        if (winner == NONE || z < lo || (z <= hi && q < stored_q)) {
            winner = sorted[k];
            stored_z = z;
            stored_q = q;
        }
    }
    return winner;
}

// Over kSorted candidates: nearest depth, then closest landing within the tolerance, then first.
uint by_rule(ivec2 t, uint first) {
    highp float nearest = uintBitsToFloat(0x7f800000u);
    for (uint node = first; node != NONE; node = next(node))
        nearest = min(nearest, texelFetch(source_depth, source_pixel(source_of(node)), 0).r);
    PRECISE highp float bound = nearest * tol_hi;
    uint best_q = 256u, winner = NONE;
    for (uint node = first; node != NONE; node = next(node)) {
        highp float z;
        uint q, index = source_of(node);
        candidate(index, t, z, q);
        if (z <= bound && (q < best_q || (q == best_q && index < winner))) {
            best_q = q;
            winner = index;
        }
    }
    return winner;
}

bool gather(ivec2 t) {
#if CLEAR
    heads_and_nodes[head(t)] = NONE;
    return false;
#else
    uint first = heads_and_nodes[head(t)];
    bool too_many = false;
    uint index = first == NONE ? NONE : in_order(t, first, too_many);
    if (too_many) {
        index = by_rule(t, first);
        atomicAdd(counts[1], 1u);
    }
    bool covered = index != NONE;
    ivec2 s = source_pixel(covered ? index : 0u);
    imageStore(out_color, t, covered ? texelFetch(source_color, s, 0) : vec4(0.0));
    imageStore(out_depth, t, vec4(covered ? texelFetch(source_depth, s, 0).r
                                          : uintBitsToFloat(0x7f800000u)));
    imageStore(out_covered, t, uvec4(covered ? 1u : 0u));
    if (carry_motion)
        imageStore(out_motion, t, covered ? vec4(texelFetch(source_motion, s, 0).rg, 0.0, 0.0)
                                          : vec4(0.0));
    return covered;
#endif
}

void main() {
    ivec2 t = ivec2(gl_GlobalInvocationID.xy);
    bool inside = t.x < target_size.x && t.y < target_size.y;
    COUNT_IN_GROUP(inside && gather(t), counts[0])
}
)";

// The reverse warp's refetch (warp's refetch_row_reference): at each covered target pixel q the
// splat's carried motion gives a first source position, the source's own motion bilinear there
// the final one, where colour is fetched as a Catmull-Rom bicubic (written where finite).
constexpr const char* kRefetch = R"(
layout(binding = 0) uniform highp sampler2D source_color;
layout(binding = 1) uniform highp sampler2D source_motion;
layout(binding = 2) uniform highp sampler2D carried;
layout(binding = 3) uniform highp usampler2D covered;
layout(binding = 0, rgba32f) writeonly uniform highp image2D out_color;
uniform ivec2 source_size, target_size;
uniform highp float factor;
)";
constexpr const char* kRefetchMain = R"(
void main() {
    ivec2 t = ivec2(gl_GlobalInvocationID.xy);
    if (t.x >= target_size.x || t.y >= target_size.y) return;
    if (texelFetch(covered, t, 0).r == 0u) return;
    highp vec2 q = vec2(float(t.x) + 0.5, float(t.y) + 0.5);
    PRECISE highp vec2 p = q - factor * texelFetch(carried, t, 0).rg;
    highp float w = float(source_size.x), h = float(source_size.y);
    if (!(p.x >= 0.0 && p.y >= 0.0 && p.x <= w && p.y <= h)) return;
    PRECISE highp float sx = p.x - 0.5, sy = p.y - 0.5;
    int ix = floor_small(sx), iy = floor_small(sy);
    PRECISE highp float fx = sx - float(ix), fy = sy - float(iy);
    int x0 = clamp(ix, 0, source_size.x - 1), x1 = clamp(ix + 1, 0, source_size.x - 1);
    int y0 = clamp(iy, 0, source_size.y - 1), y1 = clamp(iy + 1, 0, source_size.y - 1);
    highp vec2 a = texelFetch(source_motion, ivec2(x0, y0), 0).rg;
    highp vec2 b = texelFetch(source_motion, ivec2(x1, y0), 0).rg;
    highp vec2 c = texelFetch(source_motion, ivec2(x0, y1), 0).rg;
    highp vec2 d = texelFetch(source_motion, ivec2(x1, y1), 0).rg;
    PRECISE highp vec2 top = a + (b - a) * fx, bottom = c + (d - c) * fx;
    PRECISE highp vec2 m = top + (bottom - top) * fy;
    if (!finite(m.x) || !finite(m.y)) return;
    PRECISE highp vec2 r = q - factor * m;
    if (!(r.x >= 0.0 && r.y >= 0.0 && r.x <= w && r.y <= h)) return;
    highp vec4 color = bicubic(r);
    PRECISE highp float total = color.r + color.g + color.b + color.a;
    if (finite(total)) imageStore(out_color, t, color);
}
)";

}  // namespace

Status refetch_pass(ContextState& s, const SplatTextures& source, float factor, GLuint carried,
                    GLuint covered, int tw, int th, GLuint out_color) {
    glUseProgram(s.refetch_program);
    s.bind_inputs({source.color, source.motion, carried, covered});
    glBindImageTexture(0, out_color, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glUniform2i(glGetUniformLocation(s.refetch_program, "source_size"), source.width,
                source.height);
    glUniform2i(glGetUniformLocation(s.refetch_program, "target_size"), tw, th);
    glUniform1f(glGetUniformLocation(s.refetch_program, "factor"), factor);
    dispatch(tw, th);
    ContextState::unbind_inputs();
    glUseProgram(0);
    return gl::check_errors("gpu refetch");
}

Status create_splat_programs(ContextState& s) {
    REPRISE_TRY(gl::link_compute((kComputeHeader + kRefetch + kBicubicFetch + kRefetchMain).c_str(),
                                 "refetch", s.refetch_program));
    const std::string landing = std::string(kComputeHeader) + kLanding;
    REPRISE_TRY(
        gl::link_compute((landing + kScatter).c_str(), "splat scatter", s.splat_scatter_program));
    REPRISE_TRY(gl::link_compute((landing + "#define CLEAR 1\n" + kGather).c_str(), "splat clear",
                                 s.splat_clear_program));
    REPRISE_TRY(gl::link_compute((landing + "#define CLEAR 0\n" + kGather).c_str(), "splat gather",
                                 s.splat_gather_program));
    s.splat_counts = s.make_counters(2 * sizeof(GLuint));
    return {};
}

Status splat_passes(ContextState& s, const SplatTextures& in, float factor,
                    const warp::SplatOptions& options, int tw, int th, GLuint out_color,
                    GLuint out_depth, GLuint out_covered, GLuint out_motion, std::size_t& covered) {
    const bool carry_motion = out_motion != 0;
    // Two counters, a head per target pixel, two words per landing (at most 4 per source pixel).
    const std::size_t capacity = 4 * std::size_t(in.width) * std::size_t(in.height);
    const std::size_t list_bytes =
        sizeof(GLuint) * (2 + std::size_t(tw) * std::size_t(th) + 2 * capacity);
    if (s.splat_list_bytes != list_bytes) {
        if (s.splat_lists) glDeleteBuffers(1, &s.splat_lists);
        s.splat_lists = s.make_counters(list_bytes);
        s.splat_list_bytes = list_bytes;
    }
    const GLuint header[2] = {0, GLuint(capacity)};
    glBindBuffer(GL_SHADER_STORAGE_BUFFER, s.splat_lists);
    glBufferSubData(GL_SHADER_STORAGE_BUFFER, 0, sizeof header, header);
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, s.splat_lists);
    ContextState::reset_counters(s.splat_counts, 2);
    s.bind_inputs({in.color, in.depth, in.motion});
    glBindImageTexture(3, out_color, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glBindImageTexture(4, out_depth, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
    glBindImageTexture(5, out_covered, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32UI);
    glBindImageTexture(6, out_motion, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    const float tol = std::clamp(options.depth_tolerance, 0.0f, 0.5f);
    auto pass = [&](GLuint program, int w, int h) {
        glUseProgram(program);
        glUniform2i(glGetUniformLocation(program, "source_size"), in.width, in.height);
        glUniform2i(glGetUniformLocation(program, "target_size"), tw, th);
        glUniform1f(glGetUniformLocation(program, "factor"), factor);
        glUniform1f(glGetUniformLocation(program, "tol_lo"), 1.0f - tol);
        glUniform1f(glGetUniformLocation(program, "tol_hi"), 1.0f + tol);
        glUniform1i(glGetUniformLocation(program, "footprint"), options.footprint);
        glUniform1i(glGetUniformLocation(program, "carry_motion"), carry_motion);
        dispatch(w, h);
    };
    pass(s.splat_clear_program, tw, th);
    pass(s.splat_scatter_program, in.width, in.height);
    pass(s.splat_gather_program, tw, th);
    ContextState::unbind_inputs();
    glUseProgram(0);
    GLuint n[2] = {};
    s.read_counters(s.splat_counts, n, sizeof n);
    covered = n[0];
    s.splat_by_rule = n[1];
    return gl::check_errors("gpu splat");
}

Status Context::splat(const GBufferView& source, float factor, const warp::WarpTarget& target,
                      const warp::SplatOptions& options, std::size_t& covered) {
    timings_ = {};
    covered = 0;
    const int sw = source.width(), sh = source.height();
    const int tw = target.color.width, th = target.color.height;
    REPRISE_ASSERT(source.depth.width == sw && source.motion.width == sw);
    REPRISE_ASSERT(target.depth.width == tw && target.covered.width == tw);
    if (options.footprint != 1 && options.footprint != 2)
        return Status::error("gpu splat: footprint " + std::to_string(options.footprint) +
                             ": expected 1 or 2");
    if (!std::isfinite(factor)) return Status::error("gpu splat: the factor is not finite");
    if (sw <= 0 || sh <= 0 || tw <= 0 || th <= 0) return {};
    ContextState& s = *state_;
    REPRISE_TRY(s.gl->acquire());
    auto t = std::chrono::steady_clock::now();
    s.upload_frame(source, s.payload, s.previous_depth, s.motion);
    timings_.upload_ms = finish_ms(t);
    s.out.ensure(GL_RGBA32F, tw, th);
    s.made_valid = false;  // color and depth no longer hold an extrapolation
    s.depth.ensure(GL_R32F, tw, th);
    s.hit.ensure(GL_R32UI, tw, th);
    const bool carry_motion = !target.motion.empty();
    if (carry_motion) s.splat_motion.ensure(GL_RGBA32F, tw, th);
    REPRISE_TRY(splat_passes(s, {s.payload.name, s.previous_depth.name, s.motion.name, sw, sh},
                             factor, options, tw, th, s.out.name, s.depth.name, s.hit.name,
                             carry_motion ? s.splat_motion.name : 0, covered));
    timings_.compute_ms = finish_ms(t);
    s.download(s.out, target.color.data, target.color.stride);
    s.download_channels(s.depth, target.depth.data, 1, target.depth.stride);
    s.download(s.hit, nullptr, 0);
    for (int y = 0; y < th; ++y)
        for (int x = 0; x < tw; ++x)
            target.covered(x, y) = uint8_t(s.hit_readback[std::size_t(y) * tw + x].x);
    if (carry_motion)
        s.download_channels(s.splat_motion, &target.motion.data->x, 2, target.motion.stride);
    REPRISE_TRY(gl::check_errors("gpu splat download"));
    timings_.download_ms = finish_ms(t);
    return {};
}

}  // namespace reprise::gpu
