// Extrapolation on the GPU: warp's extrapolate_to_camera for the splat and the grid (its cells
// grown by grid_cells.cpp and drawn by grid.cpp; for a skewed projection on CPU images, the
// displacement and cells are made on the CPU). The static-layer test
// (warp's static_layer_row_reference: a pixel is static when the camera alone explains its
// motion) gives each pixel its displacement, to where the target camera sees it or `periods`
// along its own motion; one splat carries colour, depth and that displacement; pull-push fills
// what nothing covers; the carried displacement becomes backward motion per period.
#include <chrono>
#include <cmath>
#include <string>
#include <utility>

#include "reprise/warp/extrapolate.hpp"
#include "reprise/warp/fill.hpp"
#include "reprise/warp/silhouettes.hpp"

#include "state.hpp"

namespace reprise::gpu {

namespace {

constexpr const char* kStaticLayer = R"(
layout(binding = 0) uniform highp sampler2D depth_map;
layout(binding = 1) uniform highp sampler2D motion_map;
layout(binding = 0, rgba32f) writeonly uniform highp image2D displacement;
layout(std430, binding = 0) buffer Counts { uint counts[]; };
uniform highp float periods;

// Whether pixel p moves on its own; its displacement written either way.
bool moving(ivec2 p) {
    highp float z = texelFetch(depth_map, p, 0).r;
    highp vec2 m = texelFetch(motion_map, p, 0).rg;
    highp vec2 later;
    bool still = still_pixel(p, z, m, later);
    PRECISE highp vec2 along = -periods * m;
    imageStore(displacement, p, vec4(still ? later : along, 0.0, 0.0));
    return !still;
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    bool inside = p.x < size.x && p.y < size.y;
    COUNT_IN_GROUP(inside && moving(p), counts[0])
}
)";

Status check_options(const warp::FrucOptions& o) {
    const bool grid = o.warp == warp::WarpMethod::Grid;
    if (!grid && o.warp != warp::WarpMethod::Splat && o.warp != warp::WarpMethod::Reverse)
        return Status::error(
            "gpu extrapolate: the GPU warps with warp grid, splat or reverse only (docs/gpu.md)");
    if (o.fill != warp::FillMethod::PullPush && o.fill != warp::FillMethod::None)
        return Status::error("gpu extrapolate: the GPU fills with pullpush or none only");
    if (!grid && o.splat.footprint != 1 && o.splat.footprint != 2)
        return Status::error("gpu extrapolate: splat footprint " +
                             std::to_string(o.splat.footprint) + ": expected 1 or 2");
    return {};
}

Status check_periods(float periods) {
    if (!(periods >= 0.0f) || !std::isfinite(periods))
        return Status::error("gpu extrapolate: periods must be finite and >= 0");
    return {};
}

}  // namespace

Status create_extrapolate_programs(ContextState& s) {
    s.extrapolate_counts = s.make_counters(sizeof(GLuint));
    return gl::link_compute(
        (std::string(kComputeHeader) + kViewPoint + kStillTest + kStaticLayer).c_str(),
        "static layer", s.static_layer_program);
}

// After the warp into s.eye_color, out_depth, s.hit (covered) and s.splat_motion (the
// displacement carried): the border strips continued, pull-push over the other holes into
// out_color, the motion per period.
Status fill_and_scale(ContextState& s, int w, int h, const warp::FrucOptions& options,
                      GLuint out_color, GLuint out_depth, GLuint out_motion, float to_backward,
                      ExtrapolateStats& stats) {
    stats.holes = std::size_t(w) * std::size_t(h) - stats.covered;
    if (stats.holes && options.fill == warp::FillMethod::PullPush && options.border_run > 0) {
        stats.border =
            border_rows_pass(s, s.eye_color.name, out_depth, s.hit.name, w, h, options.border_run);
        stats.holes -= std::min(stats.holes, stats.border);
    }
    if (stats.holes && options.fill == warp::FillMethod::PullPush)
        REPRISE_TRY(
            fill_passes(s, s.eye_color.name, s.hit.name, out_depth, w, h, out_color, stats.fill));
    else
        copy_scaled(s, s.eye_color.name, out_color, w, h, 1.0f);
    if (out_motion) copy_scaled(s, s.splat_motion.name, out_motion, w, h, to_backward);
    return gl::check_errors("gpu extrapolate");
}

Status extrapolate_passes(ContextState& s, const SplatTextures& frame, const Camera& camera,
                          const glm::mat4& view, const glm::mat4& projection, float periods,
                          float motion_scale, const warp::FrucOptions& options, GLuint out_color,
                          GLuint out_depth, GLuint out_motion, ExtrapolateStats& stats) {
    const int w = frame.width, h = frame.height;
    const std::size_t pixels = std::size_t(w) * std::size_t(h);
    s.displacement.ensure(GL_RGBA32F, w, h);
    s.eye_color.ensure(GL_RGBA32F, w, h);
    s.hit.ensure(GL_R32UI, w, h);
    SplatTextures along = frame;
    float factor = 1.0f, to_backward = periods > 1e-6f ? -motion_scale / periods : 0.0f;
    if (has_projection(camera)) {
        const GLuint program = s.static_layer_program;
        glUseProgram(program);
        REPRISE_TRY(
            set_still_test(program, camera, view, projection, w, h, options.static_tolerance));
        s.bind_inputs({frame.depth, frame.motion});
        glBindImageTexture(0, s.displacement.name, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
        ContextState::reset_counters(s.extrapolate_counts, 1);
        glUniform1f(glGetUniformLocation(program, "periods"), periods);
        dispatch(w, h);
        ContextState::unbind_inputs();
        glUseProgram(0);
        GLuint moving = 0;
        s.read_counters(s.extrapolate_counts, &moving, sizeof moving);
        stats.moving = moving;
        along.motion = s.displacement.name;
    } else {
        // Without a camera nothing tells static from moving: every pixel follows its motion.
        stats.moving = pixels;
        factor = -periods;
        to_backward = motion_scale;
    }
    if (options.warp == warp::WarpMethod::Grid) {  // its cells grown here, carrying the motion
        if (out_motion) s.splat_motion.ensure(GL_RGBA32F, w, h);
        std::size_t grown = 0, stretched = 0;
        REPRISE_TRY(grow_cells(s, frame.depth, along.motion, w, h, options.grid, factor, 0, grown));
        warp::GridStats grid;
        REPRISE_TRY(grid_passes(
            s, frame.color, w, h, {nullptr, grown, 0}, options.grid.bicubic,
            {s.eye_color.name, out_depth, s.hit.name, out_motion ? s.splat_motion.name : 0u, w, h},
            grid, stretched));
        stats.covered = grid.covered;
        stats.grid_cells = grid.cells;
        return fill_and_scale(s, w, h, options, out_color, out_depth, out_motion, to_backward,
                              stats);
    }
    // The reverse warp: a footprint-2 splat, each covered pixel's colour then refetched.
    const bool reverse = options.warp == warp::WarpMethod::Reverse;
    const bool carry = out_motion || reverse;
    if (carry) s.splat_motion.ensure(GL_RGBA32F, w, h);
    REPRISE_TRY(splat_passes(
        s, along, factor, reverse ? warp::SplatOptions{.footprint = 2} : options.splat, w, h,
        s.eye_color.name, out_depth, s.hit.name, carry ? s.splat_motion.name : 0, stats.covered));
    if (reverse)
        REPRISE_TRY(refetch_pass(s, along, factor, s.splat_motion.name, s.hit.name, w, h,
                                 s.eye_color.name));
    return fill_and_scale(s, w, h, options, out_color, out_depth, out_motion, to_backward, stats);
}

// The grid's extrapolation of `frame` (CPU images, repaired; its colour uploaded as
// s.source_color) for a skewed projection: the displacement and the cells on the CPU, drawn by
// the GPU.
Status grid_extrapolation(ContextState& s, const GBufferView& frame, const glm::mat4& view,
                          const glm::mat4& projection, float periods, float motion_scale,
                          const warp::FrucOptions& options, GLuint out_color, GLuint out_depth,
                          GLuint out_motion, ExtrapolateStats& stats, double& cpu_ms) {
    auto start = std::chrono::steady_clock::now();
    const int w = frame.width(), h = frame.height();
    GridRaster& g = s.grid;
    GBufferView along = frame;
    float factor = 1.0f, to_backward = periods > 1e-6f ? -motion_scale / periods : 0.0f;
    if (has_projection(frame.camera)) {
        g.target_depth.resize(w, h);
        g.displacement.resize(w, h);
        stats.moving = warp::extrapolation_displacement(
            frame, view, projection, periods, options.static_tolerance, g.target_depth.view(),
            g.displacement.view());
        along.motion = std::as_const(g.displacement).view();
    } else {
        // Without a camera nothing tells static from moving: every pixel follows its motion.
        stats.moving = std::size_t(w) * std::size_t(h);
        factor = -periods;
        to_backward = motion_scale;
    }
    g.warper.cells(along, factor, options.grid, g.cells_cpu);
    cpu_ms = ms_since(start);
    s.eye_color.ensure(GL_RGBA32F, w, h);
    s.hit.ensure(GL_R32UI, w, h);
    s.splat_motion.ensure(GL_RGBA32F, w, h);
    warp::GridStats grid;
    std::size_t stretched = 0;  // kept as covered, as the CPU's extrapolation keeps them
    REPRISE_TRY(grid_passes(s, s.source_color.name, w, h, {&g.cells_cpu}, options.grid.bicubic,
                            {s.eye_color.name, out_depth, s.hit.name, s.splat_motion.name, w, h},
                            grid, stretched));
    stats.covered = grid.covered;
    stats.grid_cells = grid.cells;
    return fill_and_scale(s, w, h, options, out_color, out_depth, out_motion, to_backward, stats);
}

Status Context::extrapolate(const GBufferView& given, const glm::mat4& view,
                            const glm::mat4& projection, float periods, Frame& out,
                            ExtrapolateStats& stats, const warp::FrucOptions& options,
                            float motion_scale, uint64_t frame_key, const FrameOnGpu& on_gpu) {
    REPRISE_TRY(extrapolate_on_gpu(given, view, projection, periods, stats, options, motion_scale,
                                   frame_key, on_gpu));
    out.normal.clear();
    out.id.clear();
    const int w = given.width(), h = given.height();
    if (w <= 0 || h <= 0) return {};
    ContextState& s = *state_;
    auto t = std::chrono::steady_clock::now();
    s.download_made(out);
    out.motion.resize(w, h);
    s.download_channels(s.made_motion, &out.motion.data()->x, 2, w);
    const Status downloaded = gl::check_errors("gpu extrapolate download");
    if (!downloaded.ok()) {
        s.made_valid = false;
        return downloaded;
    }
    timings_.download_ms = finish_ms(t);
    return {};
}

Status Context::extrapolate_on_gpu(const GBufferView& given, const glm::mat4& view,
                                   const glm::mat4& projection, float periods,
                                   ExtrapolateStats& stats, const warp::FrucOptions& options,
                                   float motion_scale, uint64_t frame_key,
                                   const FrameOnGpu& on_gpu) {
    ContextState& s = *state_;
    s.made_valid = false;
    timings_ = {};
    stats = {};
    REPRISE_TRY(check_options(options));
    REPRISE_TRY(check_periods(periods));
    const int w = given.width(), h = given.height();
    if (given.depth.width != w || given.depth.height != h || given.motion.width != w ||
        given.motion.height != h)
        return Status::error("gpu extrapolate: the frame needs depth and motion of its size");
    if (w <= 0 || h <= 0) return {};
    REPRISE_TRY(s.gl->acquire());
    const bool color_on_gpu = on_gpu.color != 0;
    const bool geometry_on_gpu = on_gpu.depth != 0 || on_gpu.motion != 0;
    if (color_on_gpu) REPRISE_TRY(check_texture(on_gpu.color, GL_RGBA32F, w, h, "frame colour"));
    if (geometry_on_gpu) {
        REPRISE_TRY(check_texture(on_gpu.depth, GL_R32F, w, h, "frame depth"));
        REPRISE_TRY(check_texture(on_gpu.motion, GL_RG32F, w, h, "frame motion"));
    }
    auto t = std::chrono::steady_clock::now();
    // The colour from a texture: only the depth and motion are repaired (and uploaded).
    GBufferView geometry = given;
    if (color_on_gpu) geometry.color = {};
    // The same frame as the last call's: its repaired pixels are uploaded already (its depth and
    // motion only if they were not handed over then, or are handed over again now).
    const bool kept = frame_key != 0 && frame_key == s.extrapolate_key &&
                      s.source_color.width == w && s.source_color.height == h &&
                      (geometry_on_gpu || s.source_geometry_uploaded);
    // A skewed projection: no static-layer test on the GPU; the grid's displacement and cells
    // are made on the CPU instead.
    const bool grid = options.warp == warp::WarpMethod::Grid;
    const bool cpu_grid = grid && has_projection(given.camera) &&
                          !Unprojector(given.camera.projection, w, h).axis_aligned();
    GBufferView frame;  // repaired; the CPU grid's cells are grown from it
    if (kept) {
        stats.nonfinite = s.extrapolate_nonfinite;
        stats.upload_kept = true;
        NonfiniteCounts again;
        if (grid) frame = s.extrapolate_repair.clean(geometry, again);
    } else {
        s.source_wide = SourceWide::Nothing;
        frame = s.extrapolate_repair.clean(geometry, stats.nonfinite);
        s.source_color.ensure(GL_RGBA32F, w, h);
        s.source_depth.ensure(GL_R32F, w, h);
        s.source_motion.ensure(GL_RG32F, w, h);
        if (color_on_gpu)
            copy_scaled(s, on_gpu.color, s.source_color.name, w, h, 1.0f);
        else
            s.upload(s.source_color, frame.color.data, frame.color.stride);
        if (!geometry_on_gpu) {
            s.upload(s.source_depth, frame.depth.data, frame.depth.stride);
            s.upload(s.source_motion, frame.motion.data, frame.motion.stride);
        }
        s.source_geometry_uploaded = !geometry_on_gpu;
        s.extrapolate_key = frame_key;
        s.extrapolate_nonfinite = stats.nonfinite;
    }
    if (color_on_gpu) frame.color = given.color;  // sizes the CPU grid's cells
    s.color.ensure(GL_RGBA32F, w, h);
    s.depth.ensure(GL_R32F, w, h);
    s.made_motion.ensure(GL_RGBA32F, w, h);
    timings_.upload_ms = finish_ms(t);
    // The depth and motion warped: the silhouettes widened on the GPU once per upload (the CPU
    // grid widens its own), or the textures handed over copied (they may change before the
    // frame key does).
    const bool widen = options.widen_silhouettes && !cpu_grid;
    const SourceWide wanted = widen             ? SourceWide::Widened
                              : geometry_on_gpu ? SourceWide::Copied
                                                : SourceWide::Nothing;
    if (wanted != SourceWide::Nothing && s.source_wide != wanted) {
        const std::size_t changed = widen_pass(
            s, geometry_on_gpu ? on_gpu.depth : s.source_depth.name,
            geometry_on_gpu ? on_gpu.motion : s.source_motion.name, w, h, s.source_wide_depth,
            &s.source_wide_motion, widen ? Widening::Counted : Widening::Copy);
        if (!kept) stats.silhouette_pixels = changed;
        s.source_wide = wanted;
    }
    const bool from_wide = wanted != SourceWide::Nothing;
    Status made;
    if (!cpu_grid)
        made = extrapolate_passes(
            s,
            {s.source_color.name, from_wide ? s.source_wide_depth.name : s.source_depth.name,
             from_wide ? s.source_wide_motion.name : s.source_motion.name, w, h},
            given.camera, view, projection, periods, motion_scale, options, s.color.name,
            s.depth.name, s.made_motion.name, stats);
    // A skewed projection, or more cells than a storage buffer holds: the CPU grows them.
    if (cpu_grid || (!made.ok() && grid && s.grid.overflowed)) {
        if (options.widen_silhouettes) {
            auto cpu = std::chrono::steady_clock::now();
            std::size_t changed = 0;
            frame = warp::widen_silhouettes(frame, s.wide_depth, s.wide_motion, &changed);
            if (!kept) stats.silhouette_pixels = changed;
            timings_.cpu_ms += ms_since(cpu);
        }
        double grid_ms = 0.0;
        made = grid_extrapolation(s, frame, view, projection, periods, motion_scale, options,
                                  s.color.name, s.depth.name, s.made_motion.name, stats, grid_ms);
        timings_.cpu_ms += grid_ms;
    }
    REPRISE_TRY(made);
    timings_.compute_ms = finish_ms(t) - timings_.cpu_ms;
    s.made_valid = true;
    return {};
}

MadeTextures Context::made() const {
    const ContextState& s = *state_;
    if (!s.made_valid) return {};
    return {s.color.name, s.depth.name, s.made_motion.name, s.color.width, s.color.height};
}

Status Context::extrapolate(const GBufferTextures& frame, unsigned color, const glm::mat4& view,
                            const glm::mat4& projection, float periods, unsigned out_color,
                            unsigned out_depth, unsigned out_motion, ExtrapolateStats& stats,
                            const warp::FrucOptions& options, float motion_scale) {
    timings_ = {};
    stats = {};
    REPRISE_TRY(check_options(options));
    REPRISE_TRY(check_periods(periods));
    ContextState& s = *state_;
    REPRISE_TRY(s.gl->acquire());
    const int w = frame.width, h = frame.height;
    if (w <= 0 || h <= 0)
        return Status::error("gpu extrapolate: texture size " + std::to_string(w) + "x" +
                             std::to_string(h) + " must be positive");
    REPRISE_TRY(check_texture(frame.depth, GL_R32F, w, h, "frame depth"));
    REPRISE_TRY(check_texture(frame.motion, GL_RG32F, w, h, "frame motion"));
    REPRISE_TRY(check_texture(color, GL_RGBA32F, w, h, "frame colour"));
    REPRISE_TRY(check_texture(out_color, GL_RGBA32F, w, h, "output colour"));
    REPRISE_TRY(check_texture(out_depth, GL_R32F, w, h, "output depth"));
    if (out_motion) REPRISE_TRY(check_texture(out_motion, GL_RGBA32F, w, h, "output motion"));
    if (out_color == color || out_depth == frame.depth)
        return Status::error("gpu extrapolate: an output is an input (colour or depth)");
    auto t = std::chrono::steady_clock::now();
    SplatTextures source{color, frame.depth, frame.motion, w, h};
    if (options.widen_silhouettes) {
        s.source_wide = SourceWide::Nothing;  // no longer the CPU-image entry's source
        stats.silhouette_pixels = widen_pass(s, frame.depth, frame.motion, w, h,
                                             s.source_wide_depth, &s.source_wide_motion);
        source.depth = s.source_wide_depth.name;
        source.motion = s.source_wide_motion.name;
    }
    REPRISE_TRY(extrapolate_passes(s, source, frame.camera, view, projection, periods, motion_scale,
                                   options, out_color, out_depth, out_motion, stats));
    timings_.compute_ms = finish_ms(t);
    return {};
}

}  // namespace reprise::gpu
