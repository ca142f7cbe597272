// The in-between frame on the GPU: warp's interpolate_frame for the splat without refinement and
// without true motion (FrucOptions{.warp = Splat, .true_motion = false, .refine = off}): b
// splatted by 1 - s, a by -s, the two blended where both see one surface, pull-push over what
// neither covers.
#include <chrono>
#include <string>

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

// Whether pixel p is a hole. blend_row_reference's rule (kSameSurface 0.15); the splat marks no
// pixel kCoveredStretched, so its rule for stretched sides never applies here. The motion is b's
// (0 where nothing landed) unless a alone is taken.
bool blend(ivec2 p) {
    bool ca = texelFetch(covered_a, p, 0).r != 0u, cb = texelFetch(covered_b, p, 0).r != 0u;
    highp float za = texelFetch(depth_a, p, 0).r, zb = texelFetch(depth_b, p, 0).r;
    highp vec4 a = texelFetch(color_a, p, 0), c = texelFetch(color_b, p, 0);
    highp float z = zb;
    bool take_a = false;
    if (ca) {
        PRECISE highp float gap = abs(za - zb), allowed = 0.15 * min(za, zb);
        bool both_background = positive_inf(za) && positive_inf(zb);
        if (cb && (both_background || (!positive_inf(za) && !positive_inf(zb) && gap <= allowed))) {
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
    if (p.x < size.x && p.y < size.y) imageStore(to, p, texelFetch(from, p, 0) * scale);
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
    REPRISE_TRY(
        gl::link_compute((std::string(kComputeHeader) + kBlend).c_str(), "blend", s.blend_program));
    REPRISE_TRY(
        gl::link_compute((std::string(kComputeHeader) + kCopy).c_str(), "copy", s.copy_program));
    s.blend_counts = s.make_counters(sizeof(GLuint));
    return {};
}

// a and b (w x h, on the GPU) made into the frame at s: colour and depth into out_color /
// out_depth.
Status interpolate_passes(ContextState& s, const SplatTextures& a, const SplatTextures& b,
                          float s_between, int w, int h, const warp::SplatOptions& options,
                          GLuint out_color, GLuint out_depth, GLuint out_motion, float motion_scale,
                          InterpolateStats& stats) {
    Interpolation& k = s.interpolation;
    k.side_a_color.ensure(GL_RGBA32F, w, h);
    k.side_a_depth.ensure(GL_R32F, w, h);
    k.side_a_covered.ensure(GL_R32UI, w, h);
    k.side_b_color.ensure(GL_RGBA32F, w, h);
    k.side_b_depth.ensure(GL_R32F, w, h);
    k.side_b_covered.ensure(GL_R32UI, w, h);
    k.blended.ensure(GL_RGBA32F, w, h);
    k.valid.ensure(GL_R32UI, w, h);
    const bool motion = out_motion != 0;
    k.side_a_motion.ensure(GL_RGBA32F, motion ? w : 1, motion ? h : 1);
    k.side_b_motion.ensure(GL_RGBA32F, motion ? w : 1, motion ? h : 1);
    REPRISE_TRY(splat_passes(s, b, 1.0f - s_between, options, w, h, k.side_b_color.name,
                             k.side_b_depth.name, k.side_b_covered.name,
                             motion ? k.side_b_motion.name : 0, stats.covered_b));
    REPRISE_TRY(splat_passes(s, a, -s_between, options, w, h, k.side_a_color.name,
                             k.side_a_depth.name, k.side_a_covered.name,
                             motion ? k.side_a_motion.name : 0, stats.covered_a));

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
    // No holes, no fill: the blend as it is (the fill's last pass writes every pixel).
    if (holes)
        REPRISE_TRY(
            fill_passes(s, k.blended.name, k.valid.name, out_depth, w, h, out_color, stats.fill));
    else
        copy_scaled(s, k.blended.name, out_color, w, h, 1.0f);
    return gl::check_errors("gpu interpolate");
}

Status Context::interpolate(const GBufferView& given_a, const GBufferView& given_b, float s_between,
                            Frame& out, InterpolateStats& stats, const warp::SplatOptions& options,
                            float motion_scale) {
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
    Texture* textures[6] = {&k.a_color, &k.a_depth, &k.a_motion,
                            &k.b_color, &k.b_depth, &k.b_motion};
    const GBufferView* frames[2] = {&a, &b};
    for (int f = 0; f < 2; ++f) {
        textures[3 * f]->ensure(GL_RGBA32F, w, h);
        textures[3 * f + 1]->ensure(GL_R32F, w, h);
        textures[3 * f + 2]->ensure(GL_RG32F, w, h);
    }
    s.color.ensure(GL_RGBA32F, w, h);
    s.depth.ensure(GL_R32F, w, h);
    k.made_motion.ensure(GL_RGBA32F, w, h);
    for (int f = 0; f < 2; ++f) {
        s.upload(*textures[3 * f], frames[f]->color.data, frames[f]->color.stride);
        s.upload(*textures[3 * f + 1], frames[f]->depth.data, frames[f]->depth.stride);
        s.upload(*textures[3 * f + 2], frames[f]->motion.data, frames[f]->motion.stride);
    }
    timings_.upload_ms = finish_ms(t);
    REPRISE_TRY(interpolate_passes(s, {k.a_color.name, k.a_depth.name, k.a_motion.name, w, h},
                                   {k.b_color.name, k.b_depth.name, k.b_motion.name, w, h},
                                   s_between, w, h, options, s.color.name, s.depth.name,
                                   k.made_motion.name, motion_scale, stats));
    timings_.compute_ms = finish_ms(t);
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
                            const warp::SplatOptions& options, unsigned out_motion,
                            float motion_scale) {
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
    REPRISE_TRY(interpolate_passes(s, {a_color, a.depth, a.motion, w, h},
                                   {b_color, b.depth, b.motion, w, h}, s_between, w, h, options,
                                   out_color, out_depth, out_motion, motion_scale, stats));
    timings_.compute_ms = finish_ms(t);
    return {};
}

}  // namespace reprise::gpu
