// Motion refinement of the in-between frame (warp::MotionRefiner) with the GPU's sides: the survey
// per tile, the grey crops, the evaluation of the flow and the choice per pixel on the GPU; the
// tiles' counts come back to plan the boxes, and each box's optical flow (OpenCV's DIS) runs on
// the CPU between its grey crops, which come back, and goes up again.
#include <chrono>
#include <cstdint>
#include <string>
#include <utility>

#include "state.hpp"

namespace reprise::gpu {

namespace {

// refine.cpp's display value, difference measures and surface test.
constexpr const char* kMeasures = R"(
highp float display(highp float linear) {
    // NaN -> 0, as the CPU's comparison does; +inf -> 1.
    highp float c = (floatBitsToUint(linear) & 0x7fffffffu) > 0x7f800000u ? 0.0 : clamp(linear, 0.0, 1.0);
    PRECISE highp float d = 1.138 * sqrt(c) - 0.138 * c;
    return d;
}
highp vec3 display_difference(highp vec4 a, highp vec4 b) {
    return abs(vec3(display(a.r), display(a.g), display(a.b)) -
               vec3(display(b.r), display(b.g), display(b.b)));
}
highp float mean_difference(highp vec4 a, highp vec4 b) {
    highp vec3 d = display_difference(a, b);
    PRECISE highp float m = (d.r + d.g + d.b) * (1.0 / 3.0);
    return m;
}
bool infinite(highp float v) { return (floatBitsToUint(v) & 0x7fffffffu) == 0x7f800000u; }
bool same_surface(highp float za, highp float zb) {
    if (infinite(za) && infinite(zb)) return true;
    PRECISE highp float gap = abs(za - zb), allowed = 0.02 * min(za, zb);
    return gap <= allowed;
}
)";

// Per tile (one invocation each): the pixels surveyed (both sides cover one surface) and those
// whose sides disagree, at (2 tx, ty) and (2 tx + 1, ty) of `counts`.
constexpr const char* kSurvey = R"(
layout(binding = 0) uniform highp sampler2D color_a;
layout(binding = 1) uniform highp sampler2D depth_a;
layout(binding = 2) uniform highp usampler2D covered_a;
layout(binding = 3) uniform highp sampler2D color_b;
layout(binding = 4) uniform highp sampler2D depth_b;
layout(binding = 5) uniform highp usampler2D covered_b;
layout(binding = 0, r32ui) writeonly uniform highp uimage2D counts;
uniform ivec2 size, tiles;
uniform int tile;
uniform highp float threshold;
void main() {
    ivec2 t = ivec2(gl_GlobalInvocationID.xy);
    if (t.x >= tiles.x || t.y >= tiles.y) return;
    uint surveyed = 0u, disagreeing = 0u;
    int x0 = t.x * tile;
    x0 += 1 - (x0 & 1);  // the survey's columns are the odd ones
    int x1 = min(size.x, (t.x + 1) * tile), y1 = min(size.y, (t.y + 1) * tile);
    for (int y = t.y * tile + 1; y < y1; y += 2)
        for (int x = x0; x < x1; x += 2) {
            ivec2 p = ivec2(x, y);
            if (texelFetch(covered_a, p, 0).r == 0u || texelFetch(covered_b, p, 0).r == 0u) continue;
            if (!same_surface(texelFetch(depth_a, p, 0).r, texelFetch(depth_b, p, 0).r)) continue;
            ++surveyed;
            highp vec3 d = display_difference(texelFetch(color_a, p, 0), texelFetch(color_b, p, 0));
            if (max(max(d.r, d.g), d.b) > threshold) ++disagreeing;
        }
    imageStore(counts, ivec2(2 * t.x, t.y), uvec4(surveyed));
    imageStore(counts, ivec2(2 * t.x + 1, t.y), uvec4(disagreeing));
}
)";

// A box's crop: grey of a and of b (MotionRefiner::grey) and b's motion (non-finite: 0).
constexpr const char* kCrop = R"(
layout(binding = 0) uniform highp sampler2D color_a;
layout(binding = 1) uniform highp sampler2D color_b;
layout(binding = 2) uniform highp sampler2D motion_b;
layout(binding = 0, rgba32f) writeonly uniform highp image2D crop;
uniform ivec2 origin, box_size;
highp float grey(highp vec4 c) {
    PRECISE highp float luma = 0.2126 * c.r + 0.7152 * c.g + 0.0722 * c.b;
    PRECISE highp float v = display(luma) * 255.0 + 0.5;
    return float(uint(v));
}
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= box_size.x || p.y >= box_size.y) return;
    ivec2 q = origin + p;
    highp vec2 m = texelFetch(motion_b, q, 0).rg;
    if (!finite(m.x) || !finite(m.y)) m = vec2(0.0);
    imageStore(crop, p, vec4(grey(texelFetch(color_a, q, 0)), grey(texelFetch(color_b, q, 0)), m));
}
)";

// Over a box: the rendered motion's error (-1 where the sides are not one surface) and the
// flow's, and the flow's colour (refine.cpp's evaluate and along).
constexpr const char* kEvaluate = R"(
layout(binding = 0) uniform highp sampler2D color_a;
layout(binding = 1) uniform highp sampler2D color_b;
layout(binding = 2) uniform highp sampler2D side_color_a;
layout(binding = 3) uniform highp sampler2D side_depth_a;
layout(binding = 4) uniform highp usampler2D side_covered_a;
layout(binding = 5) uniform highp sampler2D side_color_b;
layout(binding = 6) uniform highp sampler2D side_depth_b;
layout(binding = 7) uniform highp usampler2D side_covered_b;
layout(binding = 8) uniform highp sampler2D flow;
layout(binding = 0, rgba32f) writeonly uniform highp image2D errors;
layout(binding = 1, rgba32f) writeonly uniform highp image2D flow_color;
uniform ivec2 origin, box_size, size;
uniform highp float s;
// warp's bilinear_taps and bilinear_fetch; false outside the image rectangle.
bool bilinear(highp sampler2D image, highp vec2 p, out highp vec4 c) {
    c = vec4(0.0);
    if (!(p.x >= 0.0 && p.y >= 0.0 && p.x <= float(size.x) && p.y <= float(size.y))) return false;
    PRECISE highp float sx = p.x - 0.5, sy = p.y - 0.5;
    int ix = int(floor(sx)), iy = int(floor(sy));
    PRECISE highp float fx = sx - float(ix), fy = sy - float(iy);
    int x0 = clamp(ix, 0, size.x - 1), x1 = clamp(ix + 1, 0, size.x - 1);
    int y0 = clamp(iy, 0, size.y - 1), y1 = clamp(iy + 1, 0, size.y - 1);
    highp vec4 a = texelFetch(image, ivec2(x0, y0), 0), b = texelFetch(image, ivec2(x1, y0), 0);
    highp vec4 d = texelFetch(image, ivec2(x0, y1), 0), e = texelFetch(image, ivec2(x1, y1), 0);
    PRECISE highp vec4 top = a + (b - a) * fx, bottom = d + (e - d) * fx;
    PRECISE highp vec4 mixed = top + (bottom - top) * fy;
    c = mixed;
    return true;
}
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= box_size.x || p.y >= box_size.y) return;
    ivec2 q = origin + p;
    highp float rendered = -1.0;
    if (texelFetch(side_covered_a, q, 0).r != 0u && texelFetch(side_covered_b, q, 0).r != 0u &&
        same_surface(texelFetch(side_depth_a, q, 0).r, texelFetch(side_depth_b, q, 0).r)) {
        rendered = mean_difference(texelFetch(side_color_a, q, 0), texelFetch(side_color_b, q, 0));
        if (!finite(rendered)) rendered = -1.0;
    }
    highp vec2 a_to_b = -texelFetch(flow, p, 0).rg;
    highp vec2 centre = vec2(q) + 0.5;
    PRECISE highp vec2 pa = centre - s * a_to_b, pb = centre + (1.0 - s) * a_to_b;
    highp vec4 ca, cb, mixed = vec4(0.0);
    highp float flowed = uintBitsToFloat(0x7f800000u);
    if (bilinear(color_a, pa, ca) && bilinear(color_b, pb, cb)) {
        highp float e = mean_difference(ca, cb);
        if (finite(e)) {
            flowed = e;
            PRECISE highp vec4 blend = (1.0 - s) * ca + s * cb;
            mixed = blend;
        }
    }
    imageStore(errors, p, vec4(rendered, flowed, 0.0, 0.0));
    imageStore(flow_color, p, mixed);
}
)";

// The pixels of the box's tiles (those whose label is box + 1): the flow's colour where its
// error over the 3x3 around (within the box) beats the rendered motion's by the margin; each
// pixel's choice into `mask`, the winners counted.
constexpr const char* kDecide = R"(
layout(binding = 0) uniform highp sampler2D errors;
layout(binding = 1) uniform highp sampler2D flow_color;
layout(binding = 2) uniform highp usampler2D labels;
layout(binding = 0, rgba32f) writeonly uniform highp image2D refined;
layout(binding = 1, r32ui) writeonly uniform highp uimage2D mask;
layout(std430, binding = 0) buffer Counts { uint counts[]; };
uniform ivec2 origin, box_size;
uniform int tile, box;
uniform highp float margin;
bool decide(ivec2 p) {
    if (p.x >= box_size.x || p.y >= box_size.y) return false;
    ivec2 q = origin + p;
    if (texelFetch(labels, q / tile, 0).r != uint(box + 1)) return false;
    bool won = false;
    if (texelFetch(errors, p, 0).r >= 0.0) {
        PRECISE highp float rendered = 0.0, flowed = 0.0;
        int count = 0;
        for (int v = max(0, p.y - 1); v <= min(box_size.y - 1, p.y + 1); ++v)
            for (int u = max(0, p.x - 1); u <= min(box_size.x - 1, p.x + 1); ++u) {
                highp vec2 e = texelFetch(errors, ivec2(u, v), 0).rg;
                if (!(e.r >= 0.0)) continue;
                rendered += e.r;
                flowed += e.g;
                ++count;
            }
        PRECISE highp float mean_flowed = flowed / float(count) + margin;
        PRECISE highp float mean_rendered = rendered / float(count);
        won = mean_flowed < mean_rendered;
    }
    imageStore(mask, q, uvec4(won ? 1u : 0u));
    if (won) imageStore(refined, q, texelFetch(flow_color, p, 0));
    return won;
}
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    COUNT_IN_GROUP(decide(p), counts[0])
}
)";

// The chosen colours over the made frame.
constexpr const char* kApply = R"(
layout(binding = 0) uniform highp sampler2D refined;
layout(binding = 1) uniform highp usampler2D mask;
layout(binding = 2) uniform highp usampler2D labels;
layout(binding = 0, rgba32f) writeonly uniform highp image2D out_color;
uniform ivec2 size;
uniform int tile;
void main() {
    ivec2 q = ivec2(gl_GlobalInvocationID.xy);
    if (q.x >= size.x || q.y >= size.y) return;
    if (texelFetch(labels, q / tile, 0).r == 0u || texelFetch(mask, q, 0).r == 0u) return;
    imageStore(out_color, q, texelFetch(refined, q, 0));
}
)";

void set_box(GLuint program, const warp::RefineBox& box) {
    glUniform2i(glGetUniformLocation(program, "origin"), box.x0, box.y0);
    glUniform2i(glGetUniformLocation(program, "box_size"), box.width(), box.height());
}

// One box's grey crops down, its flow up (CPU time into cpu_ms).
void box_flow(ContextState& s, const SplatTextures& a, const SplatTextures& b,
              const warp::RefineBox& box, double& cpu_ms) {
    Refinement& r = s.refinement;
    const int bw = box.width(), bh = box.height();
    r.crop.ensure_at_least(GL_RGBA32F, bw, bh);
    glUseProgram(s.refine_programs[1]);
    s.bind_inputs({a.color, b.color, b.motion});
    glBindImageTexture(0, r.crop.name, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    set_box(s.refine_programs[1], box);
    dispatch(bw, bh);
    r.crop_pixels.resize(bw, bh);
    s.download(r.crop, r.crop_pixels.data(), r.crop_pixels.view().stride, bw, bh);
    auto t = std::chrono::steady_clock::now();
    r.grey_a.resize(bw, bh), r.grey_b.resize(bw, bh), r.seed.resize(bw, bh);
    for (int y = 0; y < bh; ++y)
        for (int x = 0; x < bw; ++x) {
            const glm::vec4 c = r.crop_pixels(x, y);
            r.grey_a(x, y) = uint8_t(c.r), r.grey_b(x, y) = uint8_t(c.g);
            r.seed(x, y) = glm::vec2(c.b, c.a);
        }
    r.refiner.flow(std::as_const(r.grey_b).view(), std::as_const(r.grey_a).view(),
                   std::as_const(r.seed).view(), r.flow_field);
    cpu_ms += ms_since(t);
    r.flow.ensure_at_least(GL_RG32F, bw, bh);
    s.upload(r.flow, r.flow_field.data(), r.flow_field.view().stride, bw, bh);
}

}  // namespace

Status refine_passes(ContextState& s, const SplatTextures& a, const SplatTextures& b,
                     float s_between, int w, int h, const warp::RefineOptions& options,
                     InterpolateStats& stats, double& cpu_ms, bool& refined) {
    refined = false;
    Refinement& r = s.refinement;
    const warp::RefineTiles tiles = warp::RefineTiles::of(w, h, options);
    Interpolation& k = s.interpolation;
    r.counts.ensure(GL_R32UI, 2 * tiles.x, tiles.y);
    glUseProgram(s.refine_programs[0]);
    s.bind_inputs({k.side_a_color.name, k.side_a_depth.name, k.side_a_covered.name,
                   k.side_b_color.name, k.side_b_depth.name, k.side_b_covered.name});
    glBindImageTexture(0, r.counts.name, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32UI);
    glUniform2i(glGetUniformLocation(s.refine_programs[0], "size"), w, h);
    glUniform2i(glGetUniformLocation(s.refine_programs[0], "tiles"), tiles.x, tiles.y);
    glUniform1i(glGetUniformLocation(s.refine_programs[0], "tile"), tiles.size);
    glUniform1f(glGetUniformLocation(s.refine_programs[0], "threshold"), options.threshold);
    dispatch(tiles.x, tiles.y);
    s.download(r.counts, nullptr, 0);  // into hit_readback
    auto t = std::chrono::steady_clock::now();
    r.surveyed.resize(tiles.count());
    r.disagreeing.resize(tiles.count());
    for (std::size_t i = 0; i < tiles.count(); ++i) {
        r.surveyed[i] = int(s.hit_readback[2 * i].r);
        r.disagreeing[i] = int(s.hit_readback[2 * i + 1].r);
    }
    warp::FrucCounters counters;
    const std::vector<warp::RefineBox>& boxes =
        r.refiner.plan(w, h, r.surveyed, r.disagreeing, options, counters);
    stats.refine_skipped = counters.refine_skipped != 0;
    stats.refine_tiles = counters.refine_tiles;
    stats.refine_tiles_left_out = counters.refine_tiles_left_out;
    stats.flow_pixels = counters.flow_pixels;
    if (boxes.empty()) {
        cpu_ms += ms_since(t);
        return gl::check_errors("gpu refine survey");
    }
    const std::span<const int> label = r.refiner.tile_boxes();
    r.label_codes.resize(tiles.count());
    for (std::size_t i = 0; i < tiles.count(); ++i) r.label_codes[i] = uint32_t(label[i] + 1);
    cpu_ms += ms_since(t);
    r.labels.ensure(GL_R32UI, tiles.x, tiles.y);
    s.upload(r.labels, r.label_codes.data(), tiles.x);
    r.refined.ensure(GL_RGBA32F, w, h);
    r.mask.ensure(GL_R32UI, w, h);
    ContextState::reset_counters(r.won, 1);
    for (std::size_t i = 0; i < boxes.size(); ++i) {
        const warp::RefineBox& box = boxes[i];
        if (box.area() == 0) continue;
        box_flow(s, a, b, box, cpu_ms);
        r.errors.ensure_at_least(GL_RGBA32F, box.width(), box.height());
        r.flow_color.ensure_at_least(GL_RGBA32F, box.width(), box.height());
        GLuint program = s.refine_programs[2];
        glUseProgram(program);
        s.bind_inputs({a.color, b.color, k.side_a_color.name, k.side_a_depth.name,
                       k.side_a_covered.name, k.side_b_color.name, k.side_b_depth.name,
                       k.side_b_covered.name, r.flow.name});
        glBindImageTexture(0, r.errors.name, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        glBindImageTexture(1, r.flow_color.name, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        set_box(program, box);
        glUniform2i(glGetUniformLocation(program, "size"), w, h);
        glUniform1f(glGetUniformLocation(program, "s"), s_between);
        dispatch(box.width(), box.height());
        program = s.refine_programs[3];
        glUseProgram(program);
        s.bind_inputs({r.errors.name, r.flow_color.name, r.labels.name});
        glBindImageTexture(0, r.refined.name, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        glBindImageTexture(1, r.mask.name, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32UI);
        glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 0, r.won);
        set_box(program, box);
        glUniform1i(glGetUniformLocation(program, "tile"), tiles.size);
        glUniform1i(glGetUniformLocation(program, "box"), int(i));
        glUniform1f(glGetUniformLocation(program, "margin"), warp::kRefineWinMargin);
        dispatch(box.width(), box.height());
    }
    ContextState::unbind_inputs();
    glUseProgram(0);
    GLuint won = 0;
    s.read_counters(r.won, &won, sizeof won);
    stats.refined_pixels = won;
    refined = won > 0;
    return gl::check_errors("gpu refine");
}

void refine_apply(ContextState& s, int w, int h, const warp::RefineOptions& options,
                  GLuint out_color) {
    Refinement& r = s.refinement;
    const GLuint program = s.refine_programs[4];
    glUseProgram(program);
    s.bind_inputs({r.refined.name, r.mask.name, r.labels.name});
    glBindImageTexture(0, out_color, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glUniform2i(glGetUniformLocation(program, "size"), w, h);
    glUniform1i(glGetUniformLocation(program, "tile"), warp::RefineTiles::of(w, h, options).size);
    dispatch(w, h);
    ContextState::unbind_inputs();
    glUseProgram(0);
}

Status create_refine_programs(ContextState& s) {
    const std::string header = kComputeHeader + kMeasures;
    const char* names[5] = {"refine survey", "refine crop", "refine evaluate", "refine decide",
                            "refine apply"};
    const char* bodies[5] = {kSurvey, kCrop, kEvaluate, kDecide, kApply};
    for (int i = 0; i < 5; ++i)
        REPRISE_TRY(gl::link_compute((header + bodies[i]).c_str(), names[i], s.refine_programs[i]));
    s.refinement.won = s.make_counters(sizeof(GLuint));
    return {};
}

}  // namespace reprise::gpu
