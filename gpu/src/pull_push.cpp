// warp::PullPush on the GPU as a mip chain: one compute pass per level down (pull), one per level
// back up (push), one into the output; the levels of at most 32x32 pixels pulled and pushed in
// one work group (small_levels), as each dispatch costs a GPU tens of microseconds. Every level
// down to 1x1 is pulled (no read-back to stop early): below the first level without an empty
// pixel every weight is 1 and the push leaves those pixels alone, so the result is the CPU's.
// The arithmetic is pull_push.cpp's, in its order.
#include <algorithm>
#include <cstring>
#include <string>

#include "reprise/warp/fill.hpp"
#include "state.hpp"

namespace reprise::gpu {

namespace {

constexpr int kMaxLevels = 32;  // 2^31 pixels on a side

constexpr const char* kPrelude = R"(
layout(std430, binding = 0) buffer Counts { uint counts[]; };  // holes, then empty per level
uniform bool use_depth;
uniform highp float ratio;  // warp::kBackgroundDepthRatio
uniform int level;          // the level written (pull) or read (push)
uniform ivec2 fine_size, coarse_size;

bool finite3(highp vec3 v) {
    uvec3 e = floatBitsToUint(v) & 0x7f800000u;
    return e.x != 0x7f800000u && e.y != 0x7f800000u && e.z != 0x7f800000u;
}
highp float sane_depth(highp float d) {
    return (floatBitsToUint(d) & 0x7fffffffu) > 0x7f800000u ? uintBitsToFloat(0x7f800000u)
                                                             : max(d, 0.0);
}

// One coarser pixel from up to four children, pull_pixel's arithmetic.
void pull_pixel(highp vec3 p[4], highp float w[4], highp float d[4], int n, out highp vec4 result,
                out highp float depth) {
    highp float dmax = 0.0;
    if (use_depth) {
        bool any = false;
        for (int k = 0; k < 4; ++k)
            if (k < n && w[k] > 0.0) {
                dmax = any ? max(dmax, d[k]) : d[k];
                any = true;
            }
    }
    PRECISE highp vec3 sum = vec3(0.0);
    PRECISE highp float weight = 0.0;
    for (int k = 0; k < 4; ++k)
        if (k < n && w[k] > 0.0 && (!use_depth || d[k] * ratio >= dmax)) {
            sum += p[k];
            weight += w[k];
        }
    result = weight > 1.0 ? vec4(sum / weight, 1.0) : vec4(sum, weight);
    depth = dmax;
}

// The bilinear taps of fine coordinate x on a coarse level of n pixels (1/4 and 3/4).
void taps(int x, int n, out int i0, out int i1, out highp float w0, out highp float w1) {
    int i = x >> 1;
    if ((x & 1) != 0) {
        i0 = i, i1 = min(i + 1, n - 1), w0 = 0.75, w1 = 0.25;
    } else {
        i0 = max(i - 1, 0), i1 = i, w0 = 0.25, w1 = 0.75;
    }
}

// The four taps of fine pixel p on a coarse level of `coarse` pixels and their weights.
void upsample_taps(ivec2 p, ivec2 coarse, out ivec2 t[4], out highp float w[4]) {
    int x0, x1, y0, y1;
    highp float ax, bx, ay, by;
    taps(p.x, coarse.x, x0, x1, ax, bx);
    taps(p.y, coarse.y, y0, y1, ay, by);
    t = ivec2[4](ivec2(x0, y0), ivec2(x1, y0), ivec2(x0, y1), ivec2(x1, y1));
    w = float[4](ax * ay, bx * ay, ax * by, bx * by);
}

// The taps' filled colours and depths upsampled, dropping taps nearer than the farthest.
highp vec3 upsample_of(highp vec4 cs[4], highp float dk[4], highp float w[4],
                       out highp float depth) {
    depth = 0.0;
    if (use_depth) {
        depth = max(max(dk[0], dk[1]), max(dk[2], dk[3]));
        for (int k = 0; k < 4; ++k)
            if (!(dk[k] * ratio >= depth)) w[k] = 0.0;
    }
    if (w[0] > 0.0 && w[1] > 0.0 && w[2] > 0.0 && w[3] > 0.0) {
        PRECISE highp vec4 s = vec4(0.0) + cs[0] * w[0] + cs[1] * w[1] + cs[2] * w[2] + cs[3] * w[3];
        return s.rgb;
    }
    PRECISE highp vec3 acc = vec3(0.0);
    PRECISE highp float sum = 0.0;
    for (int k = 0; k < 4; ++k)
        if (w[k] > 0.0) {
            acc += cs[k].rgb * w[k];
            sum += w[k];
        }
    return acc / sum;
}

// The filled coarse level (textures c and d, coarse_size) upsampled at fine pixel p.
highp vec3 upsample(highp sampler2D c, highp sampler2D d, ivec2 p, out highp float depth) {
    ivec2 t[4];
    highp float w[4], dk[4];
    highp vec4 cs[4];
    upsample_taps(p, coarse_size, t, w);
    for (int k = 0; k < 4; ++k) {
        cs[k] = texelFetch(c, t[k], 0);
        dk[k] = use_depth ? texelFetch(d, t[k], 0).r : 0.0;
    }
    return upsample_of(cs, dk, w, depth);
}
)";

// Level `level` - 1 into level `level`; with FROM_IMAGE the image (level 0) into level 1, where
// holes are valid == 0 or non-finite RGB.
constexpr const char* kPull = R"(
layout(binding = 0) uniform highp sampler2D fine;
#if FROM_IMAGE
layout(binding = 1) uniform highp usampler2D valid;
#endif
layout(binding = 2) uniform highp sampler2D fine_depth;
layout(binding = 0, rgba32f) writeonly uniform highp image2D out_color;
layout(binding = 1, r32f) writeonly uniform highp image2D out_depth;
// Whether coarse pixel q stays empty.
bool pull(ivec2 q) {
    highp vec3 p[4];
    highp float w[4], d[4];
    int n = 0;
    for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
            ivec2 f = 2 * q + ivec2(dx, dy);
            if (f.x >= fine_size.x || f.y >= fine_size.y) continue;
            highp vec4 c = texelFetch(fine, f, 0);
#if FROM_IMAGE
            bool ok = texelFetch(valid, f, 0).r != 0u && finite3(c.rgb);
            p[n] = ok ? c.rgb : vec3(0.0);
            w[n] = ok ? 1.0 : 0.0;
            d[n] = use_depth ? sane_depth(texelFetch(fine_depth, f, 0).r) : 0.0;
#else
            p[n] = c.rgb;
            w[n] = c.a;
            d[n] = use_depth ? texelFetch(fine_depth, f, 0).r : 0.0;
#endif
            ++n;
        }
    highp vec4 result;
    highp float depth;
    pull_pixel(p, w, d, n, result, depth);
    imageStore(out_color, q, result);
    if (use_depth) imageStore(out_depth, q, vec4(depth));
    return result.a < 1.0;
}
void main() {
    ivec2 q = ivec2(gl_GlobalInvocationID.xy);
    bool inside = q.x < coarse_size.x && q.y < coarse_size.y;
    COUNT_IN_GROUP(inside && pull(q), counts[1 + level])
}
)";

// The top level normalised (finish_top), or level `level` filled from the filled level above.
constexpr const char* kPush = R"(
layout(binding = 0) uniform highp sampler2D pulled;
layout(binding = 1) uniform highp sampler2D coarse;
layout(binding = 2) uniform highp sampler2D pulled_depth;
layout(binding = 3) uniform highp sampler2D coarse_depth;
layout(binding = 0, rgba32f) writeonly uniform highp image2D out_color;
layout(binding = 1, r32f) writeonly uniform highp image2D out_depth;
uniform bool top;
void main() {
    ivec2 q = ivec2(gl_GlobalInvocationID.xy);
    if (q.x >= fine_size.x || q.y >= fine_size.y) return;
    highp vec4 px = texelFetch(pulled, q, 0);
    highp float d = use_depth ? texelFetch(pulled_depth, q, 0).r : 0.0;
    if (top) {
        if (px.a > 0.0 && px.a < 1.0) px = vec4(px.rgb / px.a, 1.0);
    } else if (px.a < 1.0) {
        highp float ud;
        highp vec3 up = upsample(coarse, coarse_depth, q, ud);
        if (use_depth && px.a == 0.0) d = ud;
        PRECISE highp vec3 filled = px.rgb + (1.0 - px.a) * up;
        px = vec4(filled, 1.0);
    }
    imageStore(out_color, q, px);
    if (use_depth) imageStore(out_depth, q, vec4(d));
}
)";

// The image's holes (counted here: this pass runs also without levels) from filled level 1;
// everything else, and every pixel of an image without a valid one (`top_level` empty), copied.
constexpr const char* kFinal = R"(
layout(binding = 0) uniform highp sampler2D color;
layout(binding = 1) uniform highp usampler2D valid;
layout(binding = 2) uniform highp sampler2D coarse;
layout(binding = 3) uniform highp sampler2D coarse_depth;
layout(binding = 4) uniform highp sampler2D top_level;
layout(binding = 0, rgba32f) writeonly uniform highp image2D out_color;
uniform bool has_levels;
// Whether pixel q is a hole.
bool fill_pixel(ivec2 q) {
    highp vec4 c = texelFetch(color, q, 0);
    bool hole = texelFetch(valid, q, 0).r == 0u || !finite3(c.rgb);
    if (hole && has_levels && texelFetch(top_level, ivec2(0), 0).a > 0.0) {
        highp float ud;
        c = vec4(upsample(coarse, coarse_depth, q, ud), c.a);
    }
    imageStore(out_color, q, c);
    return hole;
}
void main() {
    ivec2 q = ivec2(gl_GlobalInvocationID.xy);
    bool inside = q.x < fine_size.x && q.y < fine_size.y;
    COUNT_IN_GROUP(inside && fill_pixel(q), counts[0])
}
)";

// Levels first..last (each at most kSmallLevel pixels a side) in one work group: pulled from
// level first - 1 (textures of fine_size), each kept in the buffer, then pushed back up in place
// to level first, which is written out with the top level as pulled (the final pass reads it).
constexpr const char* kSmallLevelsPass = R"(
layout(binding = 0) uniform highp sampler2D fine;
layout(binding = 2) uniform highp sampler2D fine_depth;
layout(binding = 0, rgba32f) writeonly uniform highp image2D out_color;
layout(binding = 1, r32f) writeonly uniform highp image2D out_depth;
layout(binding = 2, rgba32f) writeonly uniform highp image2D top_pulled;
struct Pixel {
    highp vec4 color;
    highp float depth;
};
layout(std430, binding = 1) coherent buffer Small { Pixel small[]; };
uniform int first, last;  // at most SMALL_LEVELS levels
const int kInvocations = int(gl_WorkGroupSize.x * gl_WorkGroupSize.y);
ivec2 sizes[SMALL_LEVELS];
int offsets[SMALL_LEVELS];
// Level first + k pulled from the level above it (none past `last`).
void pull_level(int k) {
    int l = first + k;
    if (l > last) return;
    ivec2 fsz = k == 0 ? fine_size : sizes[k - 1];
    int from = k == 0 ? 0 : offsets[k - 1];
    ivec2 sz = sizes[k];
    uint empty = 0u;
    for (int i = int(gl_LocalInvocationIndex); i < sz.x * sz.y; i += kInvocations) {
        ivec2 q = ivec2(i % sz.x, i / sz.x);
        highp vec3 p[4];
        highp float w[4], d[4];
        int n = 0;
        for (int dy = 0; dy < 2; ++dy)
            for (int dx = 0; dx < 2; ++dx) {
                ivec2 f = 2 * q + ivec2(dx, dy);
                if (f.x >= fsz.x || f.y >= fsz.y) continue;
                highp vec4 c;
                highp float z;
                if (l == first) {
                    c = texelFetch(fine, f, 0);
                    z = use_depth ? texelFetch(fine_depth, f, 0).r : 0.0;
                } else {
                    c = small[from + f.y * fsz.x + f.x].color;
                    z = use_depth ? small[from + f.y * fsz.x + f.x].depth : 0.0;
                }
                p[n] = c.rgb;
                w[n] = c.a;
                d[n] = z;
                ++n;
            }
        highp vec4 result;
        highp float depth;
        pull_pixel(p, w, d, n, result, depth);
        small[offsets[k] + i] = Pixel(result, depth);
        if (l == last) imageStore(top_pulled, q, result);
        if (result.a < 1.0) ++empty;
    }
    if (empty != 0u) atomicAdd(counts[1 + l], empty);
}
// Level last - k filled from the filled level below it (none above `first`).
void push_level(int k) {
    int l = last - k;
    if (l < first) return;
    ivec2 sz = sizes[l - first];
    int at = offsets[l - first];
    for (int i = int(gl_LocalInvocationIndex); i < sz.x * sz.y; i += kInvocations) {
        ivec2 q = ivec2(i % sz.x, i / sz.x);
        highp vec4 px = small[at + i].color;
        highp float d = use_depth ? small[at + i].depth : 0.0;
        if (l == last) {
            if (px.a > 0.0 && px.a < 1.0) px = vec4(px.rgb / px.a, 1.0);
        } else if (px.a < 1.0) {
            ivec2 t[4];
            highp float w[4], dk[4];
            highp vec4 cs[4];
            upsample_taps(q, sizes[l + 1 - first], t, w);
            int up = offsets[l + 1 - first], up_width = sizes[l + 1 - first].x;
            for (int k = 0; k < 4; ++k) {
                cs[k] = small[up + t[k].y * up_width + t[k].x].color;
                dk[k] = use_depth ? small[up + t[k].y * up_width + t[k].x].depth : 0.0;
            }
            highp float ud;
            highp vec3 filled = upsample_of(cs, dk, w, ud);
            if (use_depth && px.a == 0.0) d = ud;
            PRECISE highp vec3 mixed = px.rgb + (1.0 - px.a) * filled;
            px = vec4(mixed, 1.0);
        }
        small[at + i] = Pixel(px, d);
        if (l == first) {
            imageStore(out_color, q, px);
            if (use_depth) imageStore(out_depth, q, vec4(d));
        }
    }
}
// barrier() may not sit in control flow: the steps are written out, SMALL_LEVELS of each.
#define STEP(call) call; memoryBarrierBuffer(); barrier();
void main() {
    ivec2 sz = fine_size;
    int at = 0;
    for (int l = first; l <= last; ++l) {
        sz = (sz + 1) / 2;
        sizes[l - first] = sz;
        offsets[l - first] = at;
        at += sz.x * sz.y;
    }
    STEP(pull_level(0)) STEP(pull_level(1)) STEP(pull_level(2))
    STEP(pull_level(3)) STEP(pull_level(4)) STEP(pull_level(5))
    STEP(push_level(0)) STEP(push_level(1)) STEP(push_level(2))
    STEP(push_level(3)) STEP(push_level(4)) STEP(push_level(5))
}
)";

// Levels of at most kSmallLevel pixels a side are one work group's (kSmallLevelsPass): at most
// kSmallLevels of them (32, 16, 8, 4, 2, 1), as many steps as the shader writes out.
constexpr int kSmallLevel = 32, kSmallLevels = 6;

void set_sizes(GLuint program, int fw, int fh, int cw, int ch) {
    glUniform2i(glGetUniformLocation(program, "fine_size"), fw, fh);
    glUniform2i(glGetUniformLocation(program, "coarse_size"), cw, ch);
}

// The chain's sizes: level s has ceil(w / 2^(s+1)) x ceil(h / 2^(s+1)) pixels, down to 1x1.
int level_count(int w, int h) {
    int n = 0;
    while (w > 1 || h > 1) {
        w = (w + 1) / 2;
        h = (h + 1) / 2;
        ++n;
    }
    return n;
}

void common_uniforms(GLuint program, bool use_depth, int level) {
    glUseProgram(program);
    glUniform1i(glGetUniformLocation(program, "use_depth"), use_depth);
    glUniform1f(glGetUniformLocation(program, "ratio"), warp::kBackgroundDepthRatio);
    glUniform1i(glGetUniformLocation(program, "level"), level);
}

}  // namespace

// The passes over textures the caller or the CPU entry prepared; `out` gets the filled colour.
Status fill_passes(ContextState& s, GLuint color, GLuint valid, GLuint depth, int w, int h,
                   GLuint out, warp::FillStats& stats) {
    const bool use_depth = depth != 0;
    const int levels = level_count(w, h);
    for (auto* chain : {&s.pulled, &s.pulled_depth, &s.filled, &s.filled_depth}) {
        for (std::size_t l = std::size_t(levels); l < chain->size(); ++l)
            glDeleteTextures(1, &(*chain)[l].name);
        chain->resize(std::size_t(levels));
    }
    for (int l = 0, lw = w, lh = h; l < levels; ++l) {
        lw = (lw + 1) / 2;
        lh = (lh + 1) / 2;
        s.pulled[l].ensure(GL_RGBA32F, lw, lh);
        s.filled[l].ensure(GL_RGBA32F, lw, lh);
        if (use_depth) {
            s.pulled_depth[l].ensure(GL_R32F, lw, lh);
            s.filled_depth[l].ensure(GL_R32F, lw, lh);
        }
    }
    ContextState::reset_counters(s.fill_counts, kMaxLevels + 2);
    auto depth_of = [&](std::vector<Texture>& chain, int l) {
        return use_depth ? chain[std::size_t(l)].name : 0u;
    };

    // The first level of at most kSmallLevel pixels a side (never level 0, read from the image):
    // it and those below in one work group.
    int small = 1;
    while (small < levels && (s.pulled[std::size_t(small)].width > kSmallLevel ||
                              s.pulled[std::size_t(small)].height > kSmallLevel))
        ++small;

    // Pull.
    for (int l = 0; l < small && l < levels; ++l) {
        const Texture& target = s.pulled[std::size_t(l)];
        const GLuint program = l == 0 ? s.pull_image_program : s.pull_level_program;
        common_uniforms(program, use_depth, l);
        const int fw = l == 0 ? w : s.pulled[std::size_t(l) - 1].width;
        const int fh = l == 0 ? h : s.pulled[std::size_t(l) - 1].height;
        set_sizes(program, fw, fh, target.width, target.height);
        if (l == 0)
            s.bind_inputs({color, valid, depth});
        else
            s.bind_inputs({s.pulled[std::size_t(l) - 1].name, 0, depth_of(s.pulled_depth, l - 1)});
        glBindImageTexture(0, target.name, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        if (use_depth)
            glBindImageTexture(1, s.pulled_depth[std::size_t(l)].name, 0, GL_FALSE, 0,
                               GL_WRITE_ONLY, GL_R32F);
        dispatch(target.width, target.height);
    }
    if (small < levels) {
        REPRISE_ASSERT(levels - small <= kSmallLevels);
        std::size_t pixels = 0;
        for (int l = small; l < levels; ++l)
            pixels += std::size_t(s.pulled[std::size_t(l)].width) * s.pulled[std::size_t(l)].height;
        const std::size_t bytes = pixels * 8 * sizeof(float);  // std430: vec4, float, padding
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, s.small_levels);
        if (s.small_levels_bytes < bytes) {
            glBufferData(GL_SHADER_STORAGE_BUFFER, GLsizeiptr(bytes), nullptr, GL_DYNAMIC_COPY);
            s.small_levels_bytes = bytes;
        }
        const Texture& fine = s.pulled[std::size_t(small) - 1];
        common_uniforms(s.small_levels_program, use_depth, small);
        set_sizes(s.small_levels_program, fine.width, fine.height, 1, 1);
        glUniform1i(glGetUniformLocation(s.small_levels_program, "first"), small);
        glUniform1i(glGetUniformLocation(s.small_levels_program, "last"), levels - 1);
        s.bind_inputs({fine.name, 0, depth_of(s.pulled_depth, small - 1)});
        glBindImageTexture(0, s.filled[std::size_t(small)].name, 0, GL_FALSE, 0, GL_WRITE_ONLY,
                           GL_RGBA32F);
        if (use_depth)
            glBindImageTexture(1, s.filled_depth[std::size_t(small)].name, 0, GL_FALSE, 0,
                               GL_WRITE_ONLY, GL_R32F);
        glBindImageTexture(2, s.pulled[std::size_t(levels) - 1].name, 0, GL_FALSE, 0, GL_WRITE_ONLY,
                           GL_RGBA32F);
        dispatch(1, 1);  // one work group
    }
    // Push, from the top (or from above the small levels).
    for (int l = std::min(small, levels) - 1; l >= 0; --l) {
        const Texture& target = s.filled[std::size_t(l)];
        const bool top = l == levels - 1;
        common_uniforms(s.push_program, use_depth, l);
        glUniform1i(glGetUniformLocation(s.push_program, "top"), top);
        const Texture& coarse = s.filled[std::size_t(top ? l : l + 1)];
        set_sizes(s.push_program, target.width, target.height, coarse.width, coarse.height);
        s.bind_inputs({s.pulled[std::size_t(l)].name, top ? 0u : coarse.name,
                       depth_of(s.pulled_depth, l), top ? 0u : depth_of(s.filled_depth, l + 1)});
        glBindImageTexture(0, target.name, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        if (use_depth)
            glBindImageTexture(1, s.filled_depth[std::size_t(l)].name, 0, GL_FALSE, 0,
                               GL_WRITE_ONLY, GL_R32F);
        dispatch(target.width, target.height);
    }
    // The image's holes.
    common_uniforms(s.final_program, use_depth, 0);
    glUniform1i(glGetUniformLocation(s.final_program, "has_levels"), levels > 0);
    set_sizes(s.final_program, w, h, levels ? s.filled[0].width : 1,
              levels ? s.filled[0].height : 1);
    s.bind_inputs({color, valid, levels ? s.filled[0].name : 0u,
                   levels ? depth_of(s.filled_depth, 0) : 0u,
                   levels ? s.pulled[std::size_t(levels) - 1].name : 0u});
    glBindImageTexture(0, out, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    dispatch(w, h);
    ContextState::unbind_inputs();
    glUseProgram(0);

    GLuint n[kMaxLevels + 2] = {};
    s.read_counters(s.fill_counts, n, sizeof n);
    REPRISE_TRY(gl::check_errors("gpu pull-push"));
    // The counts as the CPU reports them: levels pulled until one had no empty pixel.
    stats = {.holes = n[0]};
    const std::size_t pixels = std::size_t(w) * std::size_t(h);
    if (stats.holes == 0) return {};
    if (stats.holes == pixels || levels == 0) {
        stats.unfilled = stats.holes;
        return {};
    }
    stats.levels = levels;
    for (int l = 0; l < levels; ++l)
        if (n[1 + l] == 0) {
            stats.levels = l + 1;
            break;
        }
    return {};
}

// warp::continue_border_rows, a row per invocation: up to max_run holes between an image edge
// and the row's outermost valid pixel take its colour and depth and become valid; counted. The
// colour is read through a sampler at the valid pixels and written at the holes only.
constexpr const char* kBorderRows = R"(
layout(binding = 0) uniform highp sampler2D color_in;
layout(binding = 0, rgba32f) writeonly uniform highp image2D color;
layout(binding = 1, r32f) uniform highp image2D depth;
layout(binding = 2, r32ui) uniform highp uimage2D valid;
uniform ivec2 size;
uniform int max_run;
void continue_row(int y) {
    int left = 0;
    while (left < size.x && imageLoad(valid, ivec2(left, y)).r == 0u) ++left;
    if (left == size.x) return;
    int right = size.x - 1;
    while (imageLoad(valid, ivec2(right, y)).r == 0u) --right;
    highp vec4 lc = texelFetch(color_in, ivec2(left, y), 0), rc = texelFetch(color_in, ivec2(right, y), 0);
    highp vec4 lz = imageLoad(depth, ivec2(left, y)), rz = imageLoad(depth, ivec2(right, y));
    int x0 = left - min(left, max_run), x1 = right + 1 + min(size.x - 1 - right, max_run);
    for (int x = x0; x < left; ++x) {
        imageStore(color, ivec2(x, y), lc);
        imageStore(depth, ivec2(x, y), lz);
        imageStore(valid, ivec2(x, y), uvec4(1u));
    }
    for (int x = right + 1; x < x1; ++x) {
        imageStore(color, ivec2(x, y), rc);
        imageStore(depth, ivec2(x, y), rz);
        imageStore(valid, ivec2(x, y), uvec4(1u));
    }
    atomicAdd(group_counts[0], uint(left - x0 + x1 - right - 1));
}
void main() {
    count_begin();
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x == 0 && p.y < size.y) continue_row(p.y);
    count_end();
}
)";

std::size_t border_rows_pass(ContextState& s, GLuint color, GLuint depth, GLuint valid, int w,
                             int h, int max_run) {
    glUseProgram(s.border_program);
    s.bind_inputs({color});
    glBindImageTexture(0, color, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glBindImageTexture(1, depth, 0, GL_FALSE, 0, GL_READ_WRITE, GL_R32F);
    glBindImageTexture(2, valid, 0, GL_FALSE, 0, GL_READ_WRITE, GL_R32UI);
    ContextState::reset_counters(s.border_counts, 4);
    glUniform2i(glGetUniformLocation(s.border_program, "size"), w, h);
    glUniform1i(glGetUniformLocation(s.border_program, "max_run"), std::max(max_run, 0));
    dispatch(1, h);
    ContextState::unbind_inputs();
    glUseProgram(0);
    GLuint border = 0;
    s.read_counters(s.border_counts, &border, sizeof border);
    return border;
}

Status create_fill_programs(ContextState& s) {
    const std::string prelude = std::string(kComputeHeader) + kPrelude;
    REPRISE_TRY(gl::link_compute(
        (std::string(kComputeHeader) + "#define FROM_IMAGE 1\n" + kPrelude + kPull).c_str(),
        "pull (image)", s.pull_image_program));
    REPRISE_TRY(gl::link_compute(
        (std::string(kComputeHeader) + "#define FROM_IMAGE 0\n" + kPrelude + kPull).c_str(), "pull",
        s.pull_level_program));
    REPRISE_TRY(gl::link_compute((prelude + kPush).c_str(), "push", s.push_program));
    REPRISE_TRY(gl::link_compute((prelude + kFinal).c_str(), "fill", s.final_program));
    s.fill_counts = s.make_counters((kMaxLevels + 2) * sizeof(GLuint));
    REPRISE_TRY(gl::link_compute((std::string(kComputeHeader) + "#define SMALL_LEVELS " +
                                  std::to_string(kSmallLevels) + "\n" + kPrelude + kSmallLevelsPass)
                                     .c_str(),
                                 "pull-push small levels", s.small_levels_program));
    glGenBuffers(1, &s.small_levels);
    REPRISE_TRY(gl::link_compute((std::string(kComputeHeader) + kGroupCounts + kBorderRows).c_str(),
                                 "border rows", s.border_program));
    s.border_counts = s.make_counters(4 * sizeof(GLuint));
    return {};
}

Status Context::fill(ImageView<glm::vec4> color, ImageView<const uint8_t> valid,
                     ImageView<const float> depth, warp::FillStats& stats) {
    REPRISE_ASSERT(valid.width == color.width && valid.height == color.height);
    REPRISE_ASSERT(depth.empty() || (depth.width == color.width && depth.height == color.height));
    stats = {};
    timings_ = {};
    const int w = color.width, h = color.height;
    if (color.empty()) return {};
    ContextState& s = *state_;
    REPRISE_TRY(s.gl->acquire());
    using Clock = std::chrono::steady_clock;
    Clock::time_point t = Clock::now();
    s.made_valid = false;  // color and depth no longer hold an extrapolation
    s.color.ensure(GL_RGBA32F, w, h);
    s.valid.ensure(GL_R8UI, w, h);
    s.out.ensure(GL_RGBA32F, w, h);
    s.upload(s.color, color.data, color.stride);
    s.upload(s.valid, valid.data, valid.stride);
    if (!depth.empty()) {
        s.depth.ensure(GL_R32F, w, h);
        s.upload(s.depth, depth.data, depth.stride);
    }
    timings_.upload_ms = finish_ms(t);
    REPRISE_TRY(fill_passes(s, s.color.name, s.valid.name, depth.empty() ? 0u : s.depth.name, w, h,
                            s.out.name, stats));
    timings_.compute_ms = finish_ms(t);
    if (stats.holes > stats.unfilled) s.download(s.out, color.data, color.stride);
    REPRISE_TRY(gl::check_errors("gpu pull-push download"));
    timings_.download_ms = finish_ms(t);
    return {};
}

Status Context::fill(unsigned color, unsigned valid, unsigned depth, int width, int height,
                     unsigned out, warp::FillStats& stats) {
    stats = {};
    ContextState& s = *state_;
    REPRISE_TRY(s.gl->acquire());
    if (width <= 0 || height <= 0)
        return Status::error("gpu pull-push: size " + std::to_string(width) + "x" +
                             std::to_string(height) + " must be positive");
    REPRISE_TRY(check_texture(color, GL_RGBA32F, width, height, "colour"));
    REPRISE_TRY(check_texture(valid, GL_R8UI, width, height, "valid"));
    if (depth) REPRISE_TRY(check_texture(depth, GL_R32F, width, height, "depth"));
    REPRISE_TRY(check_texture(out, GL_RGBA32F, width, height, "output"));
    if (out == color) return Status::error("gpu pull-push: the output is the colour texture");
    using Clock = std::chrono::steady_clock;
    Clock::time_point t = Clock::now();
    timings_ = {};
    REPRISE_TRY(fill_passes(s, color, valid, depth, width, height, out, stats));
    timings_.compute_ms = finish_ms(t);
    return {};
}

}  // namespace reprise::gpu
