// The second eye on the GPU: stereo::StereoSynthesizer with StereoWarp::Splat, without history.
// Each pixel's displacement to the target camera through its depth (warp/'s
// displacement_row_reference, same arithmetic), the splat, pull-push over its holes, and
// non-finite colour to 0 on the way into the output.
#include <chrono>
#include <string>

#include "reprise/core/camera_math.hpp"
#include "reprise/warp/silhouettes.hpp"
#include "state.hpp"

namespace reprise::gpu {

namespace {

constexpr const char* kDisplacement = R"(
layout(binding = 0) uniform highp sampler2D depth_map;
layout(binding = 0, rgba32f) writeonly uniform highp image2D displacement;
layout(binding = 1, r32f) writeonly uniform highp image2D target_depth;
uniform highp mat4 M, V;

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= size.x || p.y >= size.y) return;
    highp float z = texelFetch(depth_map, p, 0).r;
    highp vec4 v = view_point(p, z);
    highp float cw;
    highp vec2 l = seen_at(M, v, cw);
    PRECISE highp float tz = -row(V, 2, v);
    bool ok = nonnegative(z) && cw > 0.0 && finite(l.x) && finite(l.y);
    highp float nan = uintBitsToFloat(0x7fc00000u);
    imageStore(displacement, p, ok ? vec4(l - center(p), 0.0, 0.0) : vec4(nan));
    imageStore(target_depth, p, vec4(ok ? (positive_inf(z) ? uintBitsToFloat(0x7f800000u) : tz) : nan));
}
)";

// The filled colour into the output, a pixel with a non-finite channel as 0 (as the CPU does).
constexpr const char* kFinish = R"(
layout(binding = 0) uniform highp sampler2D filled;
layout(binding = 0, rgba32f) writeonly uniform highp image2D out_color;
uniform ivec2 size;
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= size.x || p.y >= size.y) return;
    highp vec4 c = texelFetch(filled, p, 0);
    imageStore(out_color, p, finite(c.x) && finite(c.y) && finite(c.z) && finite(c.w) ? c : vec4(0.0));
}
)";

void run(GLuint program, int w, int h) {
    glUniform2i(glGetUniformLocation(program, "size"), w, h);
    dispatch(w, h);
}

Status check_options(const stereo::StereoOptions& o) {
    if (o.warp != stereo::StereoWarp::Splat)
        return Status::error(
            "gpu stereo eye: the grid warp is not on the GPU yet (StereoWarp::Splat is)");
    if (o.fill == stereo::StereoFill::Andreev)
        return Status::error(
            "gpu stereo eye: Andreev's fill is not on the GPU yet (PullPush and None are)");
    return {};
}

}  // namespace

Status create_stereo_programs(ContextState& s) {
    const std::string header = kComputeHeader;
    REPRISE_TRY(gl::link_compute((header + kViewPoint + kDisplacement).c_str(),
                                 "stereo displacement", s.displacement_program));
    return gl::link_compute((header + kFinish).c_str(), "stereo finish", s.finish_program);
}

// Colour `color` and depth `depth` (w x h) seen from `target` into out_color / out_depth.
Status eye_passes(ContextState& s, GLuint color, GLuint depth, int w, int h, const Camera& from,
                  const Camera& target, const stereo::StereoOptions& o, GLuint out_color,
                  GLuint out_depth, stereo::StereoStats& stats) {
    const StaticReprojection to_target(from, target.view, target.projection, w, h);
    const Unprojector& unproject = to_target.unprojector();
    if (!unproject.axis_aligned())
        return Status::error("gpu stereo eye: the rendered camera's projection is skewed");
    s.displacement.ensure(GL_RGBA32F, w, h);
    s.target_depth.ensure(GL_R32F, w, h);
    s.eye_color.ensure(GL_RGBA32F, w, h);
    s.hit.ensure(GL_R32UI, w, h);
    s.out.ensure(GL_RGBA32F, w, h);

    const GLuint program = s.displacement_program;
    glUseProgram(program);
    s.bind_inputs({depth});
    glBindImageTexture(0, s.displacement.name, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glBindImageTexture(1, s.target_depth.name, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
    set_view_point(program, unproject, w, h);
    glUniformMatrix4fv(glGetUniformLocation(program, "M"), 1, GL_FALSE, &to_target.to_clip()[0][0]);
    glUniformMatrix4fv(glGetUniformLocation(program, "V"), 1, GL_FALSE, &to_target.to_view()[0][0]);
    dispatch(w, h);

    std::size_t covered = 0;
    REPRISE_TRY(splat_passes(s, {color, s.target_depth.name, s.displacement.name, w, h}, 1.0f,
                             o.splat, w, h, s.eye_color.name, out_depth, s.hit.name, 0, covered));
    const std::size_t n = std::size_t(w) * std::size_t(h);
    stats.covered = covered;
    stats.holes = n - covered;
    warp::FillStats filled;
    if (o.fill == stereo::StereoFill::PullPush)
        REPRISE_TRY(
            fill_passes(s, s.eye_color.name, s.hit.name, out_depth, w, h, s.out.name, filled));
    else
        filled.holes = filled.unfilled = stats.holes;
    stats.filled = filled.holes - filled.unfilled;
    stats.unfilled = filled.unfilled;

    glUseProgram(s.finish_program);
    s.bind_inputs({stats.filled ? s.out.name : s.eye_color.name});
    glBindImageTexture(0, out_color, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    run(s.finish_program, w, h);
    ContextState::unbind_inputs();
    glUseProgram(0);
    return gl::check_errors("gpu stereo eye");
}

Status Context::stereo_eye(const GBufferView& given, const Camera& target, Frame& out,
                           stereo::StereoStats& stats, const stereo::StereoOptions& options) {
    timings_ = {};
    stats = {};
    REPRISE_TRY(check_options(options));
    const int w = given.width(), h = given.height();
    REPRISE_ASSERT(given.depth.width == w && given.depth.height == h);
    ContextState& s = *state_;
    // NaN and infinities (but background depth) repaired first, as on the CPU.
    GBufferView rendered = s.eye_repair.clean(given, stats.nonfinite);
    out.motion.clear();
    out.normal.clear();
    out.id.clear();
    out.camera = target;
    if (rendered.camera.view == target.view && rendered.camera.projection == target.projection) {
        out.color.assign(rendered.color);
        out.depth.assign(rendered.depth);
        stats.covered = std::size_t(w) * std::size_t(h);
        return {};
    }
    if (w <= 0 || h <= 0) return {};
    REPRISE_TRY(s.gl->acquire());
    auto t = std::chrono::steady_clock::now();
    // The silhouettes widened on the CPU, as StereoSynthesizer does (counted as upload time).
    if (options.widen_silhouettes)
        rendered = warp::widen_silhouettes(rendered, s.wide_depth, s.wide_motion);
    s.payload.ensure(GL_RGBA32F, w, h);
    s.previous_depth.ensure(GL_R32F, w, h);
    s.upload(s.payload, rendered.color.data, rendered.color.stride);
    s.upload(s.previous_depth, rendered.depth.data, rendered.depth.stride);
    s.color.ensure(GL_RGBA32F, w, h);
    s.depth.ensure(GL_R32F, w, h);
    timings_.upload_ms = finish_ms(t);
    REPRISE_TRY(eye_passes(s, s.payload.name, s.previous_depth.name, w, h, rendered.camera, target,
                           options, s.color.name, s.depth.name, stats));
    timings_.compute_ms = finish_ms(t);
    s.download_made(out);
    REPRISE_TRY(gl::check_errors("gpu stereo eye download"));
    timings_.download_ms = finish_ms(t);
    return {};
}

Status Context::stereo_eye(const GBufferTextures& rendered, unsigned color, const Camera& target,
                           unsigned out_color, unsigned out_depth, stereo::StereoStats& stats,
                           const stereo::StereoOptions& options) {
    timings_ = {};
    stats = {};
    REPRISE_TRY(check_options(options));
    ContextState& s = *state_;
    REPRISE_TRY(s.gl->acquire());
    const int w = rendered.width, h = rendered.height;
    if (w <= 0 || h <= 0)
        return Status::error("gpu stereo eye: texture size " + std::to_string(w) + "x" +
                             std::to_string(h) + " must be positive");
    REPRISE_TRY(check_texture(rendered.depth, GL_R32F, w, h, "rendered depth"));
    REPRISE_TRY(check_texture(color, GL_RGBA32F, w, h, "rendered colour"));
    REPRISE_TRY(check_texture(out_color, GL_RGBA32F, w, h, "eye colour"));
    REPRISE_TRY(check_texture(out_depth, GL_R32F, w, h, "eye depth"));
    if (out_color == color)
        return Status::error("gpu stereo eye: the output is the rendered colour");
    auto t = std::chrono::steady_clock::now();
    REPRISE_TRY(eye_passes(s, color, rendered.depth, w, h, rendered.camera, target, options,
                           out_color, out_depth, stats));
    timings_.compute_ms = finish_ms(t);
    return {};
}

}  // namespace reprise::gpu
