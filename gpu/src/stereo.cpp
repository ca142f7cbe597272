// The second eye on the GPU: stereo::StereoSynthesizer. Splat: each pixel's displacement to the
// target camera through its depth (warp/'s displacement_row_reference, same arithmetic), the
// splat; with a history, its warp merged into the holes. Grid: the displacements, the grid's
// cells grown (grid_cells.cpp; on the CPU for skewed projections) and drawn (grid.cpp), the
// history's merged into the holes and stretched pixels, the pixels of stretched triangles left to
// the fill, the border strip continued. Then pull-push over what is left, and
// non-finite colour to 0 on the way into the output.
#include <chrono>
#include <string>

#include "reprise/core/camera_math.hpp"
#include "reprise/warp/silhouettes.hpp"
#include "state.hpp"

namespace reprise::gpu {

namespace {

// Each pixel's displacement to the target camera and its depth there; for the history
// (drop_moving), NaN also where its motion is not its camera's alone (drop_moving in
// stereo/src/synthesize.cpp), counted.
constexpr const char* kDisplacement = R"(
layout(binding = 0) uniform highp sampler2D depth_map;
layout(binding = 1) uniform highp sampler2D motion_map;
layout(binding = 0, rgba32f) writeonly uniform highp image2D displacement;
layout(binding = 1, r32f) writeonly uniform highp image2D target_depth;
uniform highp mat4 M, V, to_previous;
uniform bool drop_moving;
uniform highp float tolerance2;

void displace(ivec2 p) {
    highp float z = texelFetch(depth_map, p, 0).r;
    highp vec4 v = view_point(p, z);
    highp float cw;
    highp vec2 l = seen_at(M, v, cw);
    PRECISE highp float tz = -row(V, 2, v);
    bool ok = nonnegative(z) && cw > 0.0 && finite(l.x) && finite(l.y);
    if (ok && drop_moving) {
        highp vec2 m = texelFetch(motion_map, p, 0).rg;
        highp float before_w;
        highp vec2 before = seen_at(to_previous, v, before_w);
        PRECISE highp vec2 e = before - center(p) - m;
        PRECISE highp float e2 = e.x * e.x + e.y * e.y;
        if (!(finite(m.x) && finite(m.y) && before_w > 0.0 && e2 <= tolerance2)) {
            ok = false;
            atomicAdd(group_counts[0], 1u);
        }
    }
    highp float nan = uintBitsToFloat(0x7fc00000u);
    imageStore(displacement, p, ok ? vec4(l - center(p), 0.0, 0.0) : vec4(nan));
    imageStore(target_depth, p, vec4(ok ? (positive_inf(z) ? uintBitsToFloat(0x7f800000u) : tz) : nan));
}

void main() {
    count_begin();
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x < size.x && p.y < size.y) displace(p);
    count_end();
}
)";

// The history warped to the target where the rendered eye left a hole (or, history_replaces and
// the history's camera nearer, where both see one surface; or, grid eye, where only a stretched
// triangle (2) covered it and the history saw it unstretched): colour into `merged`, depth and
// coverage in place; counts taken pixels and the holes among them.
constexpr const char* kMerge = R"(
layout(binding = 0) uniform highp sampler2D eye;
layout(binding = 1) uniform highp sampler2D history;
layout(binding = 2) uniform highp sampler2D history_depth;
layout(binding = 3) uniform highp usampler2D history_covered;
layout(binding = 0, rgba32f) writeonly uniform highp image2D merged;
layout(binding = 1, r32f) uniform highp image2D depth;
layout(binding = 2, r32ui) uniform highp uimage2D covered;
uniform ivec2 size;
uniform bool closer;
uniform highp float tolerance;

void merge(ivec2 p) {
    highp vec4 c = texelFetch(eye, p, 0);
    uint seen = texelFetch(history_covered, p, 0).r;
    if (seen != 0u) {
        highp float zh = texelFetch(history_depth, p, 0).r, zc = imageLoad(depth, p).r;
        uint mine = imageLoad(covered, p).r;
        bool hole = mine == 0u;
        bool better = hole || (mine == 2u && seen != 2u);
        PRECISE highp float gap = abs(zh - zc), allowed = tolerance * min(zh, zc);
        bool same = zh == zc || gap <= allowed;
        if (better || (closer && same)) {
            c = texelFetch(history, p, 0);
            imageStore(depth, p, vec4(zh));
            imageStore(covered, p, uvec4(1u));
            atomicAdd(group_counts[1], 1u);
            if (hole) atomicAdd(group_counts[2], 1u);
        }
    }
    imageStore(merged, p, c);
}

void main() {
    count_begin();
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x < size.x && p.y < size.y) merge(p);
    count_end();
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

// The grid eye's valid mask in place: a pixel only a stretched triangle covered (2) is a hole
// where pull-push refills it, as StereoSynthesizer's.
constexpr const char* kGridValid = R"(
layout(binding = 0, r32ui) uniform highp uimage2D covered;
uniform ivec2 size;
uniform bool refill;
void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    if (p.x >= size.x || p.y >= size.y) return;
    uint c = imageLoad(covered, p).r;
    imageStore(covered, p, uvec4(c == 2u && refill ? 0u : min(c, 1u)));
}
)";

void run(GLuint program, int w, int h) {
    glUniform2i(glGetUniformLocation(program, "size"), w, h);
    dispatch(w, h);
}

Status check_options(const stereo::StereoOptions& o) {
    if (o.fill != stereo::StereoFill::PullPush && o.fill != stereo::StereoFill::None)
        return Status::error(
            "gpu stereo eye: Andreev's and the patch fill are not on the GPU yet (PullPush and "
            "None are)");
    return {};
}

}  // namespace

Status create_stereo_programs(ContextState& s) {
    const std::string header = kComputeHeader;
    REPRISE_TRY(gl::link_compute((header + kGroupCounts + kViewPoint + kDisplacement).c_str(),
                                 "stereo displacement", s.displacement_program));
    REPRISE_TRY(gl::link_compute((header + kGroupCounts + kMerge).c_str(), "stereo merge",
                                 s.merge_program));
    REPRISE_TRY(gl::link_compute((header + kGridValid).c_str(), "stereo grid valid",
                                 s.grid.eye_valid_program));
    s.eye_counts = s.make_counters(4 * sizeof(GLuint));
    return gl::link_compute((header + kFinish).c_str(), "stereo finish", s.finish_program);
}

// The history's textures and camera (motion 0: none).
struct EyeHistory {
    GLuint color = 0, depth = 0, motion = 0;
    Camera camera;
};

// The displacement of `depth` (w x h, seen from `from`) to `target` into `displacement` and
// `target_depth`; with `motion`, pixels whose motion `from`'s camera does not explain within
// `moving_tolerance` px left out (NaN) and returned.
std::size_t displace(ContextState& s, GLuint depth, GLuint motion, int w, int h, const Camera& from,
                     const Camera& target, float moving_tolerance, GLuint displacement,
                     GLuint target_depth) {
    const StaticReprojection to_target(from, target.view, target.projection, w, h);
    const StaticReprojection to_previous = camera_only_motion(from, w, h);
    const GLuint program = s.displacement_program;
    glUseProgram(program);
    s.bind_inputs({depth, motion});
    glBindImageTexture(0, displacement, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glBindImageTexture(1, target_depth, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
    ContextState::reset_counters(s.eye_counts, 4);
    set_view_point(program, to_target.unprojector(), w, h);
    glUniformMatrix4fv(glGetUniformLocation(program, "M"), 1, GL_FALSE, &to_target.to_clip()[0][0]);
    glUniformMatrix4fv(glGetUniformLocation(program, "V"), 1, GL_FALSE, &to_target.to_view()[0][0]);
    glUniformMatrix4fv(glGetUniformLocation(program, "to_previous"), 1, GL_FALSE,
                       &to_previous.to_clip()[0][0]);
    const bool drop = motion != 0 && moving_tolerance < INFINITY;
    glUniform1i(glGetUniformLocation(program, "drop_moving"), drop);
    glUniform1f(glGetUniformLocation(program, "tolerance2"), moving_tolerance * moving_tolerance);
    dispatch(w, h);
    GLuint moving = 0;
    if (drop) s.read_counters(s.eye_counts, &moving, sizeof moving);
    return moving;
}

// The history's warp (s.history_warped, its depth and coverage) merged into the eye's
// (s.eye_color, `out_depth`, s.hit): colour into s.merged.
Status merge_history(ContextState& s, int w, int h, const stereo::StereoOptions& o,
                     const Camera& from, const Camera& target, const Camera& history_camera,
                     GLuint out_depth, stereo::StereoStats& stats,
                     std::size_t& history_holes_filled) {
    auto distance = [](const Camera& a, const Camera& b) {
        return glm::length(glm::vec3(glm::inverse(a.view)[3]) - glm::vec3(glm::inverse(b.view)[3]));
    };
    glUseProgram(s.merge_program);
    s.bind_inputs({s.eye_color.name, s.history_warped.name, s.history_warped_depth.name,
                   s.history_covered.name});
    glBindImageTexture(0, s.merged.name, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glBindImageTexture(1, out_depth, 0, GL_FALSE, 0, GL_READ_WRITE, GL_R32F);
    glBindImageTexture(2, s.hit.name, 0, GL_FALSE, 0, GL_READ_WRITE, GL_R32UI);
    ContextState::reset_counters(s.eye_counts, 4);
    glUniform1i(glGetUniformLocation(s.merge_program, "closer"),
                o.history_replaces && distance(history_camera, target) < distance(from, target));
    glUniform1f(glGetUniformLocation(s.merge_program, "tolerance"), o.history_depth_tolerance);
    run(s.merge_program, w, h);
    GLuint taken[3] = {0, 0, 0};
    s.read_counters(s.eye_counts, taken, sizeof taken);
    stats.from_history = taken[1];
    history_holes_filled = taken[2];
    return gl::check_errors("gpu stereo eye merge");
}

// Pull-push over the holes of `warped` (valid mask s.hit), non-finite colour to 0, into
// `out_color`.
Status fill_and_finish(ContextState& s, GLuint warped, int w, int h, const stereo::StereoOptions& o,
                       GLuint out_color, GLuint out_depth, stereo::StereoStats& stats,
                       std::size_t history_holes_filled) {
    warp::FillStats filled;
    if (o.fill == stereo::StereoFill::PullPush)
        REPRISE_TRY(fill_passes(s, warped, s.hit.name, out_depth, w, h, s.out.name, filled));
    else
        filled.holes = filled.unfilled = stats.holes - history_holes_filled;
    stats.filled = filled.holes - filled.unfilled;
    stats.unfilled = filled.unfilled;

    glUseProgram(s.finish_program);
    s.bind_inputs({stats.filled ? s.out.name : warped});
    glBindImageTexture(0, out_color, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    run(s.finish_program, w, h);
    ContextState::unbind_inputs();
    glUseProgram(0);
    return gl::check_errors("gpu stereo eye");
}

// The grid eye's warp of `color` (w x h) by `cells` (and the history's by `history_cells`):
// colour into `warped` (s.eye_color, or s.merged with a history), depth into `out_depth`, the
// valid mask into s.hit, the border strip continued.
Status grid_eye_passes(ContextState& s, GLuint color, int w, int h, const stereo::StereoOptions& o,
                       const Camera& from, const Camera& target, const EyeHistory* history,
                       const GridCells& cells, const GridCells& history_cells, GLuint out_depth,
                       stereo::StereoStats& stats, GLuint& warped,
                       std::size_t& history_holes_filled) {
    warp::GridStats grid;
    REPRISE_TRY(grid_passes(s, color, w, h, cells, o.grid.bicubic,
                            {s.eye_color.name, out_depth, s.hit.name, 0, w, h}, grid,
                            stats.stretched));
    stats.cells = grid.cells;
    stats.covered = grid.covered;
    stats.holes = std::size_t(w) * std::size_t(h) - grid.covered;
    warped = s.eye_color.name;
    if (history) {
        warp::GridStats seen;
        std::size_t unused = 0;
        REPRISE_TRY(grid_passes(
            s, history->color, w, h, history_cells, o.grid.bicubic,
            {s.history_warped.name, s.history_warped_depth.name, s.history_covered.name, 0, w, h},
            seen, unused));
        stats.cells += seen.cells;
        REPRISE_TRY(merge_history(s, w, h, o, from, target, history->camera, out_depth, stats,
                                  history_holes_filled));
        warped = s.merged.name;
    }
    glUseProgram(s.grid.eye_valid_program);
    glBindImageTexture(0, s.hit.name, 0, GL_FALSE, 0, GL_READ_WRITE, GL_R32UI);
    glUniform1i(glGetUniformLocation(s.grid.eye_valid_program, "refill"),
                o.fill == stereo::StereoFill::PullPush);
    run(s.grid.eye_valid_program, w, h);
    if (o.fill == stereo::StereoFill::None) return {};
    stats.border = border_rows_pass(s, warped, out_depth, s.hit.name, w, h, w);
    return {};
}

// Whether the GPU makes the eye's displacement (for axis-aligned projections only).
bool displaced_on_gpu(const Camera& from, const Camera* history, int w, int h) {
    return Unprojector(from.projection, w, h).axis_aligned() &&
           (!history || Unprojector(history->projection, w, h).axis_aligned());
}

// Colour `color` and depth `depth` (w x h) seen from `target` into out_color / out_depth; with
// `history`, its warp fills the rendered eye's holes first. Silhouettes are widened here
// (o.widen_silhouettes) and the grid's cells grown on the GPU, or, `cpu_cells`, both were done on
// the CPU into s.grid (skewed projections).
Status eye_passes(ContextState& s, GLuint color, GLuint depth, int w, int h, const Camera& from,
                  const Camera& target, const stereo::StereoOptions& o, GLuint out_color,
                  GLuint out_depth, stereo::StereoStats& stats, const EyeHistory* given_history,
                  bool cpu_cells = false) {
    const bool grid = o.warp == stereo::StereoWarp::Grid;
    if (!(grid && cpu_cells) &&
        !displaced_on_gpu(from, given_history ? &given_history->camera : nullptr, w, h))
        return Status::error(
            "gpu stereo eye: the rendered or the history camera's projection is skewed (the grid "
            "takes it on CPU images)");
    EyeHistory widened_history;
    const EyeHistory* history = given_history;
    if (o.widen_silhouettes && !(grid && cpu_cells)) {
        widen_pass(s, depth, 0, w, h, s.eye_wide_depth, nullptr, Widening::Uncounted);
        depth = s.eye_wide_depth.name;
        if (history) {
            widened_history = *history;
            widen_pass(s, history->depth, history->motion, w, h, s.history_wide_depth,
                       &s.history_wide_motion, Widening::Uncounted);
            widened_history.depth = s.history_wide_depth.name;
            if (history->motion) widened_history.motion = s.history_wide_motion.name;
            history = &widened_history;
        }
    }
    s.displacement.ensure(GL_RGBA32F, w, h);
    s.target_depth.ensure(GL_R32F, w, h);
    s.eye_color.ensure(GL_RGBA32F, w, h);
    s.hit.ensure(GL_R32UI, w, h);
    s.out.ensure(GL_RGBA32F, w, h);
    if (history) {
        s.history_displacement.ensure(GL_RGBA32F, w, h);
        s.history_target_depth.ensure(GL_R32F, w, h);
        s.history_warped.ensure(GL_RGBA32F, w, h);
        s.history_warped_depth.ensure(GL_R32F, w, h);
        s.history_covered.ensure(GL_R32UI, w, h);
        s.merged.ensure(GL_RGBA32F, w, h);
    }

    const std::size_t n = std::size_t(w) * std::size_t(h);
    GLuint warped = s.eye_color.name;
    std::size_t history_holes_filled = 0;
    if (grid) {
        GridCells cells{&s.grid.cells_cpu}, history_cells{&s.grid.history_cells};
        if (!cpu_cells) {
            cells = {nullptr, 0, 0};
            history_cells = {nullptr, 0, 1};
            displace(s, depth, 0, w, h, from, target, INFINITY, s.displacement.name,
                     s.target_depth.name);
            REPRISE_TRY(grow_cells(s, s.target_depth.name, s.displacement.name, w, h, o.grid, 1.0f,
                                   0, cells.grown));
            if (history) {
                stats.history_moving =
                    displace(s, history->depth, history->motion, w, h, history->camera, target,
                             o.history_moving_tolerance, s.history_displacement.name,
                             s.history_target_depth.name);
                REPRISE_TRY(grow_cells(s, s.history_target_depth.name, s.history_displacement.name,
                                       w, h, o.grid, 1.0f, 1, history_cells.grown));
            }
        }
        REPRISE_TRY(grid_eye_passes(s, color, w, h, o, from, target, history, cells, history_cells,
                                    out_depth, stats, warped, history_holes_filled));
        return fill_and_finish(s, warped, w, h, o, out_color, out_depth, stats,
                               history_holes_filled);
    }
    displace(s, depth, 0, w, h, from, target, INFINITY, s.displacement.name, s.target_depth.name);
    std::size_t covered = 0;
    REPRISE_TRY(splat_passes(s, {color, s.target_depth.name, s.displacement.name, w, h}, 1.0f,
                             o.splat, w, h, s.eye_color.name, out_depth, s.hit.name, 0, covered));
    stats.covered = covered;
    stats.holes = n - covered;
    if (history) {
        stats.history_moving = displace(s, history->depth, history->motion, w, h, history->camera,
                                        target, o.history_moving_tolerance,
                                        s.history_displacement.name, s.history_target_depth.name);
        std::size_t seen = 0;
        REPRISE_TRY(splat_passes(
            s, {history->color, s.history_target_depth.name, s.history_displacement.name, w, h},
            1.0f, o.splat, w, h, s.history_warped.name, s.history_warped_depth.name,
            s.history_covered.name, 0, seen));
        REPRISE_TRY(merge_history(s, w, h, o, from, target, history->camera, out_depth, stats,
                                  history_holes_filled));
        warped = s.merged.name;
    }
    return fill_and_finish(s, warped, w, h, o, out_color, out_depth, stats, history_holes_filled);
}

Status Context::stereo_eye(const GBufferView& given, const Camera& target, Frame& out,
                           stereo::StereoStats& stats, const stereo::StereoOptions& options,
                           const GBufferView* given_history) {
    timings_ = {};
    stats = {};
    REPRISE_TRY(check_options(options));
    const int w = given.width(), h = given.height();
    REPRISE_ASSERT(given.depth.width == w && given.depth.height == h);
    ContextState& s = *state_;
    // NaN and infinities (but background depth) repaired first, as on the CPU.
    GBufferView rendered = s.eye_repair.clean(given, stats.nonfinite);
    GBufferView history;
    const bool with_history = given_history && given_history->width() == w &&
                              given_history->height() == h && given_history->depth.width == w &&
                              given_history->depth.height == h;
    if (given_history) {
        NonfiniteCounts found;
        history = s.eye_history_repair.clean(*given_history, found);
        stats.nonfinite += found;
    }
    out.motion.clear();
    out.normal.clear();
    out.id.clear();
    out.camera = target;
    auto same_camera = [&](const Camera& c) {
        return c.view == target.view && c.projection == target.projection;
    };
    // The same viewpoint: nothing to warp.
    const std::size_t n = std::size_t(w) * std::size_t(h);
    const GBufferView* exact =
        same_camera(rendered.camera)                                               ? &rendered
        : with_history && same_camera(history.camera) && rendered.motion_is_zero() ? &history
                                                                                   : nullptr;
    if (exact) {
        out.color.assign(exact->color);
        out.depth.assign(exact->depth);
        (exact == &rendered ? stats.covered : stats.from_history) = n;
        return {};
    }
    if (w <= 0 || h <= 0) return {};
    REPRISE_TRY(s.gl->acquire());
    auto t = std::chrono::steady_clock::now();
    // The grid's displacement and cells on the CPU where the GPU's displacement cannot be made
    // (and, below, where more cells grow than a storage buffer holds), from silhouettes widened
    // on the CPU, as StereoSynthesizer widens them (elsewhere the GPU widens them).
    GridRaster& g = s.grid;
    auto grow_on_cpu = [&] {
        if (options.widen_silhouettes) {
            rendered = warp::widen_silhouettes(rendered, s.wide_depth, s.wide_motion);
            if (with_history)
                history =
                    warp::widen_silhouettes(history, s.wide_history_depth, s.wide_history_motion);
        }
        g.displacement.resize(w, h);
        g.target_depth.resize(w, h);
        stereo::stereo_displacement(rendered, target, g.displacement.view(), g.target_depth.view());
        const GBufferView moved{.color = rendered.color,
                                .depth = g.target_depth.view(),
                                .motion = g.displacement.view(),
                                .camera = rendered.camera};
        g.warper.cells(moved, 1.0f, options.grid, g.cells_cpu);
        if (with_history) {  // its moving pixels left out, as StereoSynthesizer does
            g.history_displacement.resize(w, h);
            g.history_target_depth.resize(w, h);
            stereo::stereo_displacement(history, target, g.history_displacement.view(),
                                        g.history_target_depth.view());
            stats.history_moving = stereo::drop_moving(history, options.history_moving_tolerance,
                                                       g.history_displacement.view());
            const GBufferView history_moved{.color = history.color,
                                            .depth = g.history_target_depth.view(),
                                            .motion = g.history_displacement.view(),
                                            .camera = history.camera};
            g.warper.cells(history_moved, 1.0f, options.grid, g.history_cells);
        }
    };
    const bool cpu_cells =
        options.warp == stereo::StereoWarp::Grid &&
        !displaced_on_gpu(rendered.camera, with_history ? &history.camera : nullptr, w, h);
    if (cpu_cells) grow_on_cpu();
    timings_.cpu_ms = ms_since(t);
    s.payload.ensure(GL_RGBA32F, w, h);
    s.previous_depth.ensure(GL_R32F, w, h);
    s.upload(s.payload, rendered.color.data, rendered.color.stride);
    if (!cpu_cells) s.upload(s.previous_depth, rendered.depth.data, rendered.depth.stride);
    EyeHistory textures;
    if (with_history) {
        const bool motion = history.motion.width == w && history.motion.height == h;
        s.history_color.ensure(GL_RGBA32F, w, h);
        s.history_depth.ensure(GL_R32F, w, h);
        s.history_motion.ensure(GL_RG32F, motion ? w : 1, motion ? h : 1);
        s.upload(s.history_color, history.color.data, history.color.stride);
        if (!cpu_cells) {  // else the history's cells were grown on the CPU
            s.upload(s.history_depth, history.depth.data, history.depth.stride);
            if (motion) s.upload(s.history_motion, history.motion.data, history.motion.stride);
        }
        textures = {s.history_color.name, s.history_depth.name, motion ? s.history_motion.name : 0u,
                    history.camera};
    }
    s.made_valid = false;  // color and depth no longer hold an extrapolation
    s.color.ensure(GL_RGBA32F, w, h);
    s.depth.ensure(GL_R32F, w, h);
    timings_.upload_ms = finish_ms(t);
    Status made = eye_passes(s, s.payload.name, s.previous_depth.name, w, h, rendered.camera,
                             target, options, s.color.name, s.depth.name, stats,
                             with_history ? &textures : nullptr, cpu_cells);
    if (!made.ok() && !cpu_cells && g.overflowed) {
        auto cpu = std::chrono::steady_clock::now();
        grow_on_cpu();
        timings_.cpu_ms += ms_since(cpu);
        made = eye_passes(s, s.payload.name, s.previous_depth.name, w, h, rendered.camera, target,
                          options, s.color.name, s.depth.name, stats,
                          with_history ? &textures : nullptr, true);
    }
    REPRISE_TRY(made);
    timings_.compute_ms = finish_ms(t);
    s.download_made(out);
    REPRISE_TRY(gl::check_errors("gpu stereo eye download"));
    timings_.download_ms = finish_ms(t);
    return {};
}

Status Context::stereo_eye(const GBufferTextures& rendered, unsigned color, const Camera& target,
                           unsigned out_color, unsigned out_depth, stereo::StereoStats& stats,
                           const stereo::StereoOptions& options, const GBufferTextures* history,
                           unsigned history_color) {
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
    EyeHistory textures;
    if (history) {
        if (history->width != w || history->height != h)
            return Status::error("gpu stereo eye: the history is " +
                                 std::to_string(history->width) + "x" +
                                 std::to_string(history->height) + ", the rendered eye " +
                                 std::to_string(w) + "x" + std::to_string(h));
        REPRISE_TRY(check_texture(history->depth, GL_R32F, w, h, "history depth"));
        REPRISE_TRY(check_texture(history_color, GL_RGBA32F, w, h, "history colour"));
        if (history->motion != 0)
            REPRISE_TRY(check_texture(history->motion, GL_RG32F, w, h, "history motion"));
        textures = {history_color, history->depth, history->motion, history->camera};
    }
    if (out_color == color || (history && out_color == history_color))
        return Status::error("gpu stereo eye: the output is the rendered or the history colour");
    if (out_depth == rendered.depth || (history && out_depth == history->depth))
        return Status::error(
            "gpu stereo eye: the output depth is the rendered or the history depth");
    auto t = std::chrono::steady_clock::now();
    REPRISE_TRY(eye_passes(s, color, rendered.depth, w, h, rendered.camera, target, options,
                           out_color, out_depth, stats, history ? &textures : nullptr));
    timings_.compute_ms = finish_ms(t);
    return {};
}

}  // namespace reprise::gpu
