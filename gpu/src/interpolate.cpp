// The in-between frame on the GPU: warp's interpolate_frame for the splat, the reverse warp or the
// grid (FrucOptions{.warp = Splat, Reverse or Grid}): b warped by 1 - s, a by -s (along their
// true motion when asked), refinement's choices found (refine.cpp), the two blended where both
// see one surface, the border strips continued, pull-push over the other holes, the refined
// colours written over.
#include <chrono>
#include <string>
#include <utility>

#include "reprise/warp/fill.hpp"
#include "reprise/warp/silhouettes.hpp"
#include "reprise/warp/true_motion.hpp"

#include "state.hpp"

namespace reprise::gpu {

namespace {

// warp::blend_row_reference per pixel.
constexpr const char* kBlend = R"(
layout(binding = 0) uniform highp sampler2D color_a;
layout(binding = 1) uniform highp sampler2D depth_a;
layout(binding = 2) uniform highp usampler2D covered_a;
layout(binding = 3) uniform highp sampler2D color_b;
layout(binding = 4) uniform highp sampler2D depth_b;
layout(binding = 5) uniform highp usampler2D covered_b;
layout(binding = 6) uniform highp sampler2D motion_a;
layout(binding = 7) uniform highp sampler2D motion_b;
layout(binding = 0, rgba32f) writeonly uniform highp image2D out_color;
layout(binding = 1, r32f) writeonly uniform highp image2D out_depth;
layout(binding = 2, r32ui) writeonly uniform highp uimage2D out_valid;
layout(binding = 3, rgba32f) writeonly uniform highp image2D out_motion;
layout(std430, binding = 0) buffer Counts { uint counts[]; };
uniform ivec2 size;
uniform highp float s, motion_scale;
uniform bool write_motion;

// Whether pixel p is a hole. blend_row_reference's rule (kSameSurface 0.15): where only one side
// was drawn by a grid triangle stretched over a disocclusion (2), the other side's; the motion
// is b's (0 where nothing landed) unless a alone is taken.
bool blend(ivec2 p) {
    uint mark_a = texelFetch(covered_a, p, 0).r, mark_b = texelFetch(covered_b, p, 0).r;
    bool ca = mark_a != 0u, cb = mark_b != 0u;
    highp float za = texelFetch(depth_a, p, 0).r, zb = texelFetch(depth_b, p, 0).r;
    highp vec4 a = texelFetch(color_a, p, 0), c = texelFetch(color_b, p, 0);
    highp float z = zb;
    bool take_a = false;
    if (ca) {
        PRECISE highp float gap = abs(za - zb), allowed = 0.15 * min(za, zb);
        bool both_background = positive_inf(za) && positive_inf(zb);
        if (cb && (mark_a == 2u) != (mark_b == 2u)) {
            if (mark_b == 2u) {
                c = a;
                z = za;
                take_a = true;
            }
        } else if (cb && (both_background || (!positive_inf(za) && !positive_inf(zb) && gap <= allowed))) {
            PRECISE highp vec4 mixed = (1.0 - s) * a + s * c;
            c = mixed;
            z = min(za, zb);
        } else if (!cb || !(zb < za)) {
            c = a;
            z = za;
            take_a = true;
        }
    }
    imageStore(out_color, p, c);
    imageStore(out_depth, p, vec4(z));
    imageStore(out_valid, p, uvec4(ca || cb ? 1u : 0u));
    if (write_motion) {
        highp vec2 m = take_a ? texelFetch(motion_a, p, 0).rg : texelFetch(motion_b, p, 0).rg;
        imageStore(out_motion, p, vec4(m * motion_scale, 0.0, 0.0));
    }
    return !ca && !cb;
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    bool inside = p.x < size.x && p.y < size.y;
    COUNT_IN_GROUP(inside && blend(p), counts[0])
}
)";

// Each side's true motion (warp's motion_toward): a static pixel's displacement to the in-between
// camera divided by its side's factor, a moving one's motion as it is or, for a, b's motion
// inverted where some pixel of b landed. Without cameras only the latter.
constexpr const char* kTrueMotion = R"(
layout(binding = 0) uniform highp sampler2D depth_map;
layout(binding = 1) uniform highp sampler2D motion_map;
layout(binding = 2) uniform highp sampler2D inverted;
layout(binding = 0, rgba32f) writeonly uniform highp image2D true_motion;
uniform highp float per_factor;
uniform bool cameras, use_inverted;
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= size.x || p.y >= size.y) return;
    highp float z = texelFetch(depth_map, p, 0).r;
    highp vec2 m = texelFetch(motion_map, p, 0).rg, to, result = m;
    if (cameras && still_pixel(p, z, m, to)) {
        PRECISE highp vec2 scaled = to * per_factor;
        result = scaled;
    } else if (use_inverted) {
        highp vec2 i = texelFetch(inverted, p, 0).rg;
        if (finite(i.x) && finite(i.y)) result = i;
    }
    imageStore(true_motion, p, vec4(result, 0.0, 0.0));
}
)";

// The pixels warp's linearity survey looks at, (4 + 8 i, 4 + 8 j), gathered as (depth, motion).
constexpr const char* kSurvey = R"(
layout(binding = 0) uniform highp sampler2D depth_map;
layout(binding = 1) uniform highp sampler2D motion_map;
layout(binding = 0, rgba32f) writeonly uniform highp image2D samples;
uniform ivec2 count;
void main() {
    ivec2 i = ivec2(gl_GlobalInvocationID.xy);
    if (i.x >= count.x || i.y >= count.y) return;
    ivec2 p = 4 + 8 * i;
    imageStore(samples, i, vec4(texelFetch(depth_map, p, 0).r, texelFetch(motion_map, p, 0).rg,
                                0.0));
}
)";

// b's moving pixels splatted to where they were (warp's invert_motion), nearest first, ties to
// the first in raster order: STAGE 0 empties the per-pixel (depth key, source index) pairs, 1 keeps
// the nearest depth, 2 the first index at it, 3 writes the motion found (NaN where none).
constexpr const char* kInvert = R"(
layout(binding = 0) uniform highp sampler2D depth_map;
layout(binding = 1) uniform highp sampler2D motion_map;
layout(binding = 0, rgba32f) writeonly uniform highp image2D inverted;
layout(std430, binding = 1) buffer Nearest { uint nearest[]; };  // key, index per pixel
uniform bool cameras;
const uint NONE = 0xffffffffu;

// Depths in the order of their values as unsigned keys (-0 as +0).
uint key_of(highp float z) {
    uint b = floatBitsToUint(z);
    if (b == 0x80000000u) b = 0u;
    return (b & 0x80000000u) != 0u ? ~b : b | 0x80000000u;
}
bool lands(ivec2 p, out ivec2 t0, out highp float z) {
    z = texelFetch(depth_map, p, 0).r;
    highp vec2 m = texelFetch(motion_map, p, 0).rg, to;
    if (cameras && still_pixel(p, z, m, to)) return false;
    if (!finite(z) || !finite(m.x) || !finite(m.y)) return false;
    PRECISE highp vec2 q = (center(p) + m) - 0.5;
    if (!(q.x > -1.0 && q.y > -1.0 && q.x < float(size.x) && q.y < float(size.y))) return false;
    t0 = ivec2(floor(q));
    return true;
}
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= size.x || p.y >= size.y) return;
    uint at = uint(p.y * size.x + p.x);
#if STAGE == 0
    nearest[2u * at] = NONE;
    nearest[2u * at + 1u] = NONE;
#elif STAGE == 3
    uint index = nearest[2u * at + 1u];
    highp vec2 m = vec2(uintBitsToFloat(0x7fc00000u));
    if (index != NONE) m = texelFetch(motion_map, ivec2(int(index % uint(size.x)), int(index / uint(size.x))), 0).rg;
    imageStore(inverted, p, vec4(m, 0.0, 0.0));
#else
    ivec2 t0;
    highp float z;
    if (!lands(p, t0, z)) return;
    uint key = key_of(z);
    for (int ty = max(t0.y, 0); ty <= min(t0.y + 1, size.y - 1); ++ty)
        for (int tx = max(t0.x, 0); tx <= min(t0.x + 1, size.x - 1); ++tx) {
            uint t = uint(ty * size.x + tx);
#if STAGE == 1
            atomicMin(nearest[2u * t], key);
#else
            if (nearest[2u * t] == key) atomicMin(nearest[2u * t + 1u], at);
#endif
        }
#endif
}
)";

}  // namespace

// `from` times `scale` into `to` (GL_RGBA32F), w x h: a made frame's colour as it is, or the
// motion it carried scaled per output period.
constexpr const char* kCopy = R"(
layout(binding = 0) uniform highp sampler2D from;
layout(binding = 0, rgba32f) writeonly uniform highp image2D to;
uniform ivec2 size;
uniform highp float scale;
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= size.x || p.y >= size.y) return;
    highp vec4 v = texelFetch(from, p, 0);  // scale 1: a plain copy (no denormal flushed)
    imageStore(to, p, scale == 1.0 ? v : v * scale);
}
)";

void copy_scaled(ContextState& s, GLuint from, GLuint to, int w, int h, float scale) {
    glUseProgram(s.copy_program);
    s.bind_inputs({from});
    glBindImageTexture(0, to, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glUniform2i(glGetUniformLocation(s.copy_program, "size"), w, h);
    glUniform1f(glGetUniformLocation(s.copy_program, "scale"), scale);
    dispatch(w, h);
    ContextState::unbind_inputs();
    glUseProgram(0);
}

Status create_interpolate_programs(ContextState& s) {
    const std::string still = std::string(kComputeHeader) + kViewPoint + kStillTest;
    REPRISE_TRY(
        gl::link_compute((still + kTrueMotion).c_str(), "true motion", s.true_motion_program));
    for (int stage = 0; stage < 4; ++stage)
        REPRISE_TRY(gl::link_compute(
            (still + "#define STAGE " + std::to_string(stage) + "\n" + kInvert).c_str(),
            "invert motion", s.invert_programs[stage]));
    REPRISE_TRY(gl::link_compute((std::string(kComputeHeader) + kSurvey).c_str(), "survey",
                                 s.survey_program));
    REPRISE_TRY(
        gl::link_compute((std::string(kComputeHeader) + kBlend).c_str(), "blend", s.blend_program));
    REPRISE_TRY(
        gl::link_compute((std::string(kComputeHeader) + kCopy).c_str(), "copy", s.copy_program));
    s.blend_counts = s.make_counters(sizeof(GLuint));
    return {};
}

// a and b (w x h, on the GPU) made into the frame at s: colour and depth into out_color /
// out_depth.
// b's moving pixels inverted into k.inverted, then each side's true motion (a's from b's inverted
// motion where it has one) into k.true_a and k.true_b: `at` the in-between camera, or null
// without cameras (a follows b's inverted motion, b its own).
void true_motion_passes(ContextState& s, const SplatTextures& a, const SplatTextures& b,
                        const Camera& a_camera, const Camera& b_camera, const Camera* at,
                        float s_between, int w, int h, float tolerance) {
    Interpolation& k = s.interpolation;
    k.inverted.ensure(GL_RGBA32F, w, h);
    k.true_a.ensure(GL_RGBA32F, w, h);
    k.true_b.ensure(GL_RGBA32F, w, h);
    const std::size_t bytes = 2 * sizeof(GLuint) * std::size_t(w) * std::size_t(h);
    if (s.invert_bytes != bytes) {
        if (s.invert_buffer) glDeleteBuffers(1, &s.invert_buffer);
        s.invert_buffer = s.make_counters(bytes);
        s.invert_bytes = bytes;
    }
    glBindBufferBase(GL_SHADER_STORAGE_BUFFER, 1, s.invert_buffer);
    for (GLuint program : s.invert_programs) {
        glUseProgram(program);
        if (at)
            (void)set_still_test(program, b_camera, b_camera.view, b_camera.projection, w, h,
                                 tolerance);
        else
            glUniform2i(glGetUniformLocation(program, "size"), w, h);
        glUniform1i(glGetUniformLocation(program, "cameras"), at != nullptr);
        s.bind_inputs({b.depth, b.motion});
        glBindImageTexture(0, k.inverted.name, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        dispatch(w, h);
    }
    const GLuint program = s.true_motion_program;
    glUseProgram(program);
    glBindImageTexture(0, k.true_a.name, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    // a toward the in-between instant -s periods on; without cameras, b's motion inverted.
    if (at)
        (void)set_still_test(program, a_camera, at->view, at->projection, w, h, tolerance);
    else
        glUniform2i(glGetUniformLocation(program, "size"), w, h);
    glUniform1i(glGetUniformLocation(program, "cameras"), at != nullptr);
    glUniform1i(glGetUniformLocation(program, "use_inverted"), 1);
    glUniform1f(glGetUniformLocation(program, "per_factor"), 1.0f / -s_between);
    s.bind_inputs({a.depth, a.motion, k.inverted.name});
    dispatch(w, h);
    if (at) {  // b toward it 1 - s periods back, along its own motion where it moves
        glBindImageTexture(0, k.true_b.name, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        (void)set_still_test(program, b_camera, at->view, at->projection, w, h, tolerance);
        glUniform1i(glGetUniformLocation(program, "use_inverted"), 0);
        glUniform1f(glGetUniformLocation(program, "per_factor"), 1.0f / (1.0f - s_between));
        s.bind_inputs({b.depth, b.motion, 0});
        dispatch(w, h);
    }
    ContextState::unbind_inputs();
    glUseProgram(0);
}

Status interpolate_passes(ContextState& s, const SplatTextures& given_a,
                          const SplatTextures& given_b, float s_between, int w, int h,
                          const InterpolateOptions& options, GLuint out_color, GLuint out_depth,
                          GLuint out_motion, InterpolateStats& stats, const TrueMotion& plan,
                          double& cpu_ms) {
    Interpolation& k = s.interpolation;
    SplatTextures a = given_a, b = given_b;
    if (plan.follow) {
        true_motion_passes(s, a, b, plan.a_camera, plan.b_camera, plan.cameras ? &plan.at : nullptr,
                           s_between, w, h, options.static_tolerance);
        a.motion = k.true_a.name;
        if (plan.cameras) b.motion = k.true_b.name;
    }
    k.side_a_color.ensure(GL_RGBA32F, w, h);
    k.side_a_depth.ensure(GL_R32F, w, h);
    k.side_a_covered.ensure(GL_R32UI, w, h);
    k.side_b_color.ensure(GL_RGBA32F, w, h);
    k.side_b_depth.ensure(GL_R32F, w, h);
    k.side_b_covered.ensure(GL_R32UI, w, h);
    k.blended.ensure(GL_RGBA32F, w, h);
    k.valid.ensure(GL_R32UI, w, h);
    const bool motion = out_motion != 0;
    const bool carry = motion || options.reverse;  // the refetch reads the carried motion
    const float motion_scale = options.motion_scale;
    k.side_a_motion.ensure(GL_RGBA32F, carry ? w : 1, carry ? h : 1);
    k.side_b_motion.ensure(GL_RGBA32F, carry ? w : 1, carry ? h : 1);
    if (options.grid) {  // each side's cells grown (slots 1 and 0) and drawn
        struct Side {
            const SplatTextures& in;
            float factor;
            int slot;
            Texture &color, &depth, &covered, &motion;
            std::size_t& count;
        };
        for (const Side& side : {Side{b, 1.0f - s_between, 1, k.side_b_color, k.side_b_depth,
                                      k.side_b_covered, k.side_b_motion, stats.covered_b},
                                 Side{a, -s_between, 0, k.side_a_color, k.side_a_depth,
                                      k.side_a_covered, k.side_a_motion, stats.covered_a}}) {
            std::size_t grown = 0, stretched = 0;
            REPRISE_TRY(grow_cells(s, side.in.depth, side.in.motion, w, h, options.grid_options,
                                   side.factor, side.slot, grown));
            warp::GridStats drawn;
            REPRISE_TRY(grid_passes(s, side.in.color, w, h, {nullptr, grown, side.slot},
                                    options.grid_options.bicubic,
                                    {side.color.name, side.depth.name, side.covered.name,
                                     carry ? side.motion.name : 0u, w, h},
                                    drawn, stretched));
            side.count = drawn.covered;
            stats.grid_cells += drawn.cells;
        }
    } else {
        // The reverse warp: a footprint-2 splat, each covered pixel's colour then refetched.
        const warp::SplatOptions splat =
            options.reverse ? warp::SplatOptions{.footprint = 2} : options.splat;
        REPRISE_TRY(splat_passes(s, b, 1.0f - s_between, splat, w, h, k.side_b_color.name,
                                 k.side_b_depth.name, k.side_b_covered.name,
                                 carry ? k.side_b_motion.name : 0, stats.covered_b));
        REPRISE_TRY(splat_passes(s, a, -s_between, splat, w, h, k.side_a_color.name,
                                 k.side_a_depth.name, k.side_a_covered.name,
                                 carry ? k.side_a_motion.name : 0, stats.covered_a));
    }
    if (options.reverse && !options.grid) {
        REPRISE_TRY(refetch_pass(s, b, 1.0f - s_between, k.side_b_motion.name,
                                 k.side_b_covered.name, w, h, k.side_b_color.name));
        REPRISE_TRY(refetch_pass(s, a, -s_between, k.side_a_motion.name, k.side_a_covered.name, w,
                                 h, k.side_a_color.name));
    }

    bool refined = false;
    if (options.refine.enabled) {
        auto refine_start = std::chrono::steady_clock::now();
        REPRISE_TRY(refine_passes(s, given_a, given_b, s_between, w, h, options.refine, stats,
                                  cpu_ms, refined));
        stats.refine_ms = finish_ms(refine_start);
    }

    glUseProgram(s.blend_program);
    s.bind_inputs({k.side_a_color.name, k.side_a_depth.name, k.side_a_covered.name,
                   k.side_b_color.name, k.side_b_depth.name, k.side_b_covered.name,
                   k.side_a_motion.name, k.side_b_motion.name});
    glBindImageTexture(0, k.blended.name, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glBindImageTexture(1, out_depth, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
    glBindImageTexture(2, k.valid.name, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32UI);
    glBindImageTexture(3, out_motion, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    ContextState::reset_counters(s.blend_counts, 1);
    glUniform2i(glGetUniformLocation(s.blend_program, "size"), w, h);
    glUniform1f(glGetUniformLocation(s.blend_program, "s"), s_between);
    glUniform1f(glGetUniformLocation(s.blend_program, "motion_scale"), motion_scale);
    glUniform1i(glGetUniformLocation(s.blend_program, "write_motion"), motion);
    dispatch(w, h);
    ContextState::unbind_inputs();
    glUseProgram(0);
    GLuint holes = 0;
    s.read_counters(s.blend_counts, &holes, sizeof holes);
    stats.holes = holes;
    stats.fill = {};
    if (holes && options.border_run > 0) {
        stats.border =
            border_rows_pass(s, k.blended.name, out_depth, k.valid.name, w, h, options.border_run);
        stats.holes -= std::min(stats.holes, stats.border);
    }
    // No holes, no fill: the blend as it is (the fill's last pass writes every pixel).
    if (stats.holes)
        REPRISE_TRY(
            fill_passes(s, k.blended.name, k.valid.name, out_depth, w, h, out_color, stats.fill));
    else
        copy_scaled(s, k.blended.name, out_color, w, h, 1.0f);
    if (refined) refine_apply(s, w, h, options.refine, out_color);
    return gl::check_errors("gpu interpolate");
}

namespace {

// warp::motion_is_linear of a frame on the GPU: its sampled pixels gathered and read back.
bool motion_is_linear(ContextState& s, const SplatTextures& f, const Camera& camera,
                      const Camera& to, float factor, float tolerance) {
    const int cw = warp::linear_survey_samples(f.width), ch = warp::linear_survey_samples(f.height);
    Interpolation& k = s.interpolation;
    k.survey_samples.resize(cw, ch);
    if (cw > 0 && ch > 0) {
        k.survey.ensure(GL_RGBA32F, cw, ch);
        glUseProgram(s.survey_program);
        s.bind_inputs({f.depth, f.motion});
        glBindImageTexture(0, k.survey.name, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        glUniform2i(glGetUniformLocation(s.survey_program, "count"), cw, ch);
        dispatch(cw, ch);
        ContextState::unbind_inputs();
        glUseProgram(0);
        s.download(k.survey, k.survey_samples.data(), cw);
    }
    return warp::motion_is_linear(camera, f.width, f.height, std::as_const(k.survey_samples).view(),
                                  to, factor, tolerance);
}

// The samples warp's linearity survey looks at, of `f` with its silhouettes widened.
void widened_samples(const GBufferView& f, Image<glm::vec4>& samples) {
    constexpr int kStep = warp::kLinearSurveyStep;
    samples.resize(warp::linear_survey_samples(f.width()), warp::linear_survey_samples(f.height()));
    for (int j = 0; j < samples.height(); ++j)
        for (int i = 0; i < samples.width(); ++i) {
            float z = 0.0f;
            glm::vec2 m{0.0f};
            warp::widened_pixel(f, kStep / 2 + kStep * i, kStep / 2 + kStep * j, z, m);
            samples(i, j) = {z, m.x, m.y, 0.0f};
        }
}

// warp's interpolate_frame's choice (both sides warpable): through the cameras unless the survey
// finds the motion linear (`linear(side, factor)`, side 0 a, 1 b); without b's camera, a along
// b's motion inverted.
template <class Linear>
Status plan_true_motion(const Camera& a, const Camera& b, float s_between, int w, int h,
                        const Linear& linear, TrueMotion& plan, InterpolateStats& stats) {
    plan = {.a_camera = a, .b_camera = b};
    const bool cameras = has_projection(a) && has_projection(b);
    if (cameras) {
        plan.at = warp::camera_between(a, b, s_between);
        stats.linear_motion = linear(1, 1.0f - s_between) && linear(0, -s_between);
        plan.follow = plan.cameras = !stats.linear_motion;
        auto skewed = [&](const Camera& c) {
            return !Unprojector(c.projection, w, h).axis_aligned();
        };
        if (plan.cameras && (skewed(a) || skewed(b)))
            return Status::error("gpu interpolate: a frame's projection is skewed");
    } else {
        plan.follow = !has_projection(b);
    }
    stats.true_motion = plan.follow;
    return {};
}

}  // namespace

Status Context::interpolate(const GBufferView& given_a, const GBufferView& given_b, float s_between,
                            Frame& out, InterpolateStats& stats, const InterpolateOptions& options,
                            uint64_t a_key, uint64_t b_key) {
    timings_ = {};
    stats = {};
    ContextState& s = *state_;
    Interpolation& k = s.interpolation;
    // NaN and infinities (but background depth) repaired first, as the CPU converter does.
    const GBufferView a = k.repair_a.clean(given_a, stats.nonfinite);
    NonfiniteCounts found_in_b;
    const GBufferView b = k.repair_b.clean(given_b, found_in_b);
    stats.nonfinite += found_in_b;
    const int w = b.width(), h = b.height();
    if (a.width() != w || a.height() != h)
        return Status::error("gpu interpolate: the frames are " + std::to_string(a.width()) + "x" +
                             std::to_string(a.height()) + " and " + std::to_string(w) + "x" +
                             std::to_string(h));
    if (!(s_between >= 0.0f && s_between <= 1.0f))
        return Status::error("gpu interpolate: s must lie in [0, 1]");
    out.normal.clear();
    out.id.clear();
    out.camera = b.camera;
    if (w <= 0 || h <= 0) return {};
    REPRISE_TRY(s.gl->acquire());
    auto t = std::chrono::steady_clock::now();
    // The last pair's b as this pair's a: its textures change sides instead of uploading again.
    if (a_key != 0 && a_key == k.key[1] && a_key != k.key[0] && b_key != k.key[1]) {
        std::swap(k.a_color, k.b_color);
        std::swap(k.a_depth, k.b_depth);
        std::swap(k.a_motion, k.b_motion);
        std::swap(k.a_wide_depth, k.b_wide_depth);
        std::swap(k.a_wide_motion, k.b_wide_motion);
        std::swap(k.widened[0], k.widened[1]);
        std::swap(k.key[0], k.key[1]);
    }
    Texture* textures[6] = {&k.a_color, &k.a_depth, &k.a_motion,
                            &k.b_color, &k.b_depth, &k.b_motion};
    Texture* wide[4] = {&k.a_wide_depth, &k.a_wide_motion, &k.b_wide_depth, &k.b_wide_motion};
    const GBufferView* frames[2] = {&a, &b};
    const uint64_t keys[2] = {a_key, b_key};
    for (int f = 0; f < 2; ++f) {
        const bool kept = keys[f] != 0 && keys[f] == k.key[f] && textures[3 * f]->width == w &&
                          textures[3 * f]->height == h;
        stats.uploads_kept += kept;
        if (kept) continue;
        s.upload_frame(*frames[f], *textures[3 * f], *textures[3 * f + 1], *textures[3 * f + 2]);
        k.key[f] = keys[f];
        k.widened[f] = false;
    }
    s.made_valid = false;  // color and depth no longer hold an extrapolation
    s.color.ensure(GL_RGBA32F, w, h);
    s.depth.ensure(GL_R32F, w, h);
    k.made_motion.ensure(GL_RGBA32F, w, h);
    timings_.upload_ms = finish_ms(t);
    SplatTextures sides[2];
    for (int f = 0; f < 2; ++f) {
        // Widened once per upload, kept with it.
        if (options.widen_silhouettes && !k.widened[f]) {
            (f ? stats.silhouette_b : stats.silhouette_a) =
                widen_pass(s, textures[3 * f + 1]->name, textures[3 * f + 2]->name, w, h,
                           *wide[2 * f], wide[2 * f + 1]);
            k.widened[f] = true;
        }
        const bool widened = options.widen_silhouettes;
        sides[f] = {textures[3 * f]->name, (widened ? wide[2 * f] : textures[3 * f + 1])->name,
                    (widened ? wide[2 * f + 1] : textures[3 * f + 2])->name, w, h};
    }
    // The linearity survey on what is warped, on the CPU (no read-back): where the silhouettes
    // are widened, each sampled pixel widened as the GPU widened it.
    TrueMotion plan;
    if (options.true_motion)
        REPRISE_TRY(plan_true_motion(
            a.camera, b.camera, s_between, w, h,
            [&](int side, float factor) {
                const GBufferView& f = side ? b : a;
                if (!options.widen_silhouettes)
                    return warp::motion_is_linear(f, plan.at, factor, options.static_tolerance);
                widened_samples(f, k.survey_samples);
                return warp::motion_is_linear(f.camera, w, h,
                                              std::as_const(k.survey_samples).view(), plan.at,
                                              factor, options.static_tolerance);
            },
            plan, stats));
    REPRISE_TRY(interpolate_passes(s, sides[0], sides[1], s_between, w, h, options, s.color.name,
                                   s.depth.name, k.made_motion.name, stats, plan, timings_.cpu_ms));
    timings_.compute_ms = finish_ms(t) - timings_.cpu_ms;
    s.download_made(out);
    out.motion.resize(w, h);
    s.download_channels(k.made_motion, &out.motion.data()->x, 2, w);
    REPRISE_TRY(gl::check_errors("gpu interpolate download"));
    timings_.download_ms = finish_ms(t);
    return {};
}

Status Context::interpolate(const GBufferTextures& a, unsigned a_color, const GBufferTextures& b,
                            unsigned b_color, float s_between, unsigned out_color,
                            unsigned out_depth, InterpolateStats& stats,
                            const InterpolateOptions& options, unsigned out_motion) {
    timings_ = {};
    stats = {};
    ContextState& s = *state_;
    REPRISE_TRY(s.gl->acquire());
    const int w = b.width, h = b.height;
    if (w <= 0 || h <= 0 || a.width != w || a.height != h)
        return Status::error("gpu interpolate: texture sizes " + std::to_string(a.width) + "x" +
                             std::to_string(a.height) + " and " + std::to_string(w) + "x" +
                             std::to_string(h) + " must be equal and positive");
    if (!(s_between >= 0.0f && s_between <= 1.0f))
        return Status::error("gpu interpolate: s must lie in [0, 1]");
    REPRISE_TRY(check_texture(a.depth, GL_R32F, w, h, "a depth"));
    REPRISE_TRY(check_texture(a.motion, GL_RG32F, w, h, "a motion"));
    REPRISE_TRY(check_texture(a_color, GL_RGBA32F, w, h, "a colour"));
    REPRISE_TRY(check_texture(b.depth, GL_R32F, w, h, "b depth"));
    REPRISE_TRY(check_texture(b.motion, GL_RG32F, w, h, "b motion"));
    REPRISE_TRY(check_texture(b_color, GL_RGBA32F, w, h, "b colour"));
    REPRISE_TRY(check_texture(out_color, GL_RGBA32F, w, h, "output colour"));
    REPRISE_TRY(check_texture(out_depth, GL_R32F, w, h, "output depth"));
    if (out_motion) REPRISE_TRY(check_texture(out_motion, GL_RGBA32F, w, h, "output motion"));
    if (out_color == a_color || out_color == b_color)
        return Status::error("gpu interpolate: the output is an input colour");
    auto t = std::chrono::steady_clock::now();
    SplatTextures sides[2] = {{a_color, a.depth, a.motion, w, h},
                              {b_color, b.depth, b.motion, w, h}};
    if (options.widen_silhouettes) {
        Interpolation& k = s.interpolation;
        Texture* wide[4] = {&k.a_wide_depth, &k.a_wide_motion, &k.b_wide_depth, &k.b_wide_motion};
        for (int f = 0; f < 2; ++f) {
            (f ? stats.silhouette_b : stats.silhouette_a) =
                widen_pass(s, sides[f].depth, sides[f].motion, w, h, *wide[2 * f], wide[2 * f + 1]);
            k.widened[f] = false;  // no longer the CPU-image entry's uploads widened
            sides[f].depth = wide[2 * f]->name;
            sides[f].motion = wide[2 * f + 1]->name;
        }
    }
    TrueMotion plan;
    if (options.true_motion)
        REPRISE_TRY(plan_true_motion(
            a.camera, b.camera, s_between, w, h,
            [&](int side, float factor) {
                return motion_is_linear(s, sides[side], side ? b.camera : a.camera, plan.at, factor,
                                        options.static_tolerance);
            },
            plan, stats));
    REPRISE_TRY(interpolate_passes(s, sides[0], sides[1], s_between, w, h, options, out_color,
                                   out_depth, out_motion, stats, plan, timings_.cpu_ms));
    timings_.compute_ms = finish_ms(t) - timings_.cpu_ms;
    return {};
}

}  // namespace reprise::gpu
