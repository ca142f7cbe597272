#pragma once
// What a gpu::Context owns: the GL context, programs, and textures sized once per frame size.
#include <algorithm>
#include <chrono>
#include <initializer_list>
#include <memory>
#include <string>
#include <vector>

#include <glm/vec4.hpp>

#include "reprise/core/camera_math.hpp"
#include "reprise/core/nonfinite.hpp"
#include "reprise/gl/context.hpp"
#include "reprise/gl/program.hpp"
#include "reprise/gpu/context.hpp"
#include "reprise/warp/grid_warp.hpp"
#include "reprise/warp/refine.hpp"

namespace reprise::gpu {

// A texture reallocated only when its format or size changes.
struct Texture {
    GLuint name = 0;
    GLenum format = 0;
    int width = 0;
    int height = 0;
    void ensure(GLenum new_format, int w, int h);
    // At least w x h: grown (to the larger of each side) only when it is smaller.
    void ensure_at_least(GLenum new_format, int w, int h) {
        ensure(new_format, format == new_format ? std::max(width, w) : w,
               format == new_format ? std::max(height, h) : h);
    }
};

// An error naming `what` unless texture `name` is a 2D texture of `format` and w x h.
Status check_texture(unsigned name, GLenum format, int w, int h, const char* what);

// The first lines of every shader here (compute and the grid's draw): GLSL ES 3.10 and PRECISE
// (GL_EXT_gpu_shader5's or GL_OES_gpu_shader5's `precise` where offered) on what must not be
// fused into multiply-adds, so that the GPU repeats the CPU reference's arithmetic.
inline constexpr const char* kShaderPrelude = R"(#version 310 es
#if defined(GL_EXT_gpu_shader5)
#extension GL_EXT_gpu_shader5 : enable
#define PRECISE precise
#elif defined(GL_OES_gpu_shader5)
#extension GL_OES_gpu_shader5 : enable
#define PRECISE precise
#else
#define PRECISE
#endif
)";
// Then, in compute shaders, 8x8 work groups and the helpers below.
inline const std::string kComputeHeader = std::string(kShaderPrelude) + R"(
layout(local_size_x = 8, local_size_y = 8) in;
// Tested by bits: a shader compiler may assume that no float is NaN or infinite.
bool finite(highp float v) { return (floatBitsToUint(v) & 0x7f800000u) != 0x7f800000u; }
bool positive_inf(highp float v) { return floatBitsToUint(v) == 0x7f800000u; }
// z >= 0 (+inf included): NaN fails, and -0 counts as 0.
bool nonnegative(highp float z) {
    uint b = floatBitsToUint(z);
    return b <= 0x7f800000u || b == 0x80000000u;
}
// COUNT_IN_GROUP(condition, counter) as the whole body of main(): counts where `condition` holds
// in the work group (each invocation's flag in shared memory, added up by the first), then adds
// the group's count to `counter` with one atomic. barrier() may not sit in control flow, so every
// invocation evaluates `condition`, whose side effects are the pass.
shared uint group_flags[64];
#define COUNT_IN_GROUP(condition, counter) \
    group_flags[gl_LocalInvocationIndex] = (condition) ? 1u : 0u; \
    barrier(); \
    if (gl_LocalInvocationIndex == 0u) { \
        uint n = 0u; \
        for (int k = 0; k < 64; ++k) n += group_flags[k]; \
        if (n != 0u) atomicAdd(counter, n); \
    }
)";

// Warp's bicubic_fetch (Catmull-Rom, taps clamped to the border) of `source_color` (a sampler the
// shader declares, `source_size` its size) at position p in pixels.
inline constexpr const char* kBicubicFetch = R"(
int floor_small(highp float v) {
    int i = int(v);
    return i - (v < float(i) ? 1 : 0);
}
void weights(highp float t, out highp vec4 w) {
    PRECISE highp float t2 = t * t, t3 = t2 * t;
    PRECISE highp float w0 = 0.5 * (-t3 + 2.0 * t2 - t);
    PRECISE highp float w1 = 0.5 * (3.0 * t3 - 5.0 * t2 + 2.0);
    PRECISE highp float w2 = 0.5 * (-3.0 * t3 + 4.0 * t2 + t);
    PRECISE highp float w3 = 0.5 * (t3 - t2);
    w = vec4(w0, w1, w2, w3);
}
highp vec4 bicubic(highp vec2 p) {
    PRECISE highp float sx = p.x - 0.5, sy = p.y - 0.5;
    int ix = floor_small(sx), iy = floor_small(sy);
    PRECISE highp float tx = sx - float(ix), ty = sy - float(iy);
    highp vec4 wx, wy;
    weights(tx, wx);
    weights(ty, wy);
    PRECISE highp vec4 sum = vec4(0.0);
    for (int j = 0; j < 4; ++j) {
        int y = clamp(iy - 1 + j, 0, source_size.y - 1);
        PRECISE highp vec4 line = vec4(0.0);
        for (int i = 0; i < 4; ++i)
            line = line + wx[i] * texelFetch(source_color, ivec2(clamp(ix - 1 + i, 0, source_size.x - 1), y), 0);
        sum = sum + wy[j] * line;
    }
    return sum;
}
)";

// A pixel's view-space point through its depth and where a camera sees it, in warp/'s
// arithmetic (reproject_setup's Unprojector for an axis-aligned projection P, transform_row's
// sums): the stereo eye's displacement and extrapolation's static-layer test. Background (+inf)
// is the direction (background_zv, background_w).
inline constexpr const char* kViewPoint = R"(
uniform highp mat4 P;
uniform highp float background_zv, background_w;
uniform ivec2 size;

highp float row(highp mat4 m, int r, highp vec4 v) {
    PRECISE highp float t = (m[0][r] * v.x + m[1][r] * v.y) + (m[2][r] * v.z + m[3][r] * v.w);
    return t;
}
highp vec2 center(ivec2 p) { return vec2(float(p.x) + 0.5, float(p.y) + 0.5); }
highp vec4 view_point(ivec2 p, highp float z) {
    highp vec2 c = center(p);
    PRECISE highp float ny = 1.0 - 2.0 * c.y / float(size.y);
    PRECISE highp float nx = 2.0 * c.x / float(size.x) - 1.0;
    bool background = positive_inf(z);
    highp float zv = background ? background_zv : -z;
    highp float w = background ? background_w : 1.0;
    PRECISE highp float wc = P[2][3] * zv + P[3][3] * w;
    PRECISE highp float vx = (nx * wc - P[2][0] * zv - P[3][0] * w) / P[0][0];
    PRECISE highp float vy = (ny * wc - P[2][1] * zv - P[3][1] * w) / P[1][1];
    return vec4(vx, vy, zv, w);
}
// The pixel position where clip matrix M sees view point v; `cw` its clip w (> 0: in front).
highp vec2 seen_at(highp mat4 M, highp vec4 v, out highp float cw) {
    cw = row(M, 3, v);
    PRECISE highp float x = (row(M, 0, v) / cw * 0.5 + 0.5) * float(size.x);
    PRECISE highp float y = (0.5 - 0.5 * row(M, 1, v) / cw) * float(size.y);
    return vec2(x, y);
}
)";

// Several counts per work group: count_begin() first and count_end() last in main() (both
// reached by every invocation), atomicAdd(group_counts[k], n) between them; each group adds its
// counts to the global `counts` once.
inline constexpr const char* kGroupCounts = R"(
layout(std430, binding = 0) buffer Counts { uint counts[]; };
shared uint group_counts[4];
void count_begin() {
    if (gl_LocalInvocationIndex == 0u)
        group_counts[0] = group_counts[1] = group_counts[2] = group_counts[3] = 0u;
    barrier();
}
void count_end() {
    barrier();
    if (gl_LocalInvocationIndex == 0u)
        for (int k = 0; k < 4; ++k)
            if (group_counts[k] != 0u) atomicAdd(counts[k], group_counts[k]);
}
)";

// warp's static-layer test (static_layer_row_reference) after kViewPoint: pixel p (depth z,
// motion m) is static when its camera alone explains its motion within sqrt(tolerance2) px;
// `to` gets its displacement to the target camera either way.
inline constexpr const char* kStillTest = R"(
uniform highp mat4 to_previous, to_target;
uniform highp float tolerance2;
bool still_pixel(ivec2 p, highp float z, highp vec2 m, out highp vec2 to) {
    highp vec4 v = view_point(p, z);
    highp float before_w, later_w;
    highp vec2 before = seen_at(to_previous, v, before_w), later = seen_at(to_target, v, later_w);
    highp vec2 c = center(p);
    PRECISE highp vec2 e = before - c - m;
    PRECISE highp float e2 = e.x * e.x + e.y * e.y;
    PRECISE highp vec2 d = later - c;
    to = d;
    bool nan_depth = (floatBitsToUint(z) & 0x7fffffffu) > 0x7f800000u;
    return !nan_depth && finite(m.x) && finite(m.y) && before_w > 0.0 && later_w > 0.0 &&
           e2 <= tolerance2;
}
)";

// Sets kStillTest's uniforms of `program` (in use) for `frame` seen by (view, projection), and
// kViewPoint's; an error where the frame's projection is skewed.
Status set_still_test(GLuint program, const Camera& frame, const glm::mat4& view,
                      const glm::mat4& projection, int w, int h, float tolerance);

// Sets kViewPoint's uniforms of `program` (in use) for `unproject` over w x h.
void set_view_point(GLuint program, const Unprojector& unproject, int w, int h);

// A splat's source on the GPU: colour GL_RGBA32F, depth GL_R32F, motion (RG of any float format).
struct SplatTextures {
    GLuint color = 0, depth = 0, motion = 0;
    int width = 0, height = 0;
};

// warp::reproject over the looked-up pixels (every step-th of every step-th row) of `width` x
// `height`: binds the inputs, runs the shader, returns the counts.
Status reproject_pass(ContextState& s, GLuint depth, GLuint motion, GLuint id,
                      GLuint previous_depth, GLuint previous_id, GLuint payload, GLuint out,
                      GLuint hit, int width, int height, int previous_width, int previous_height,
                      const warp::ReprojectSetup& k, int step, warp::ReprojectCounts& counts);

// warp::continue_border_rows on textures: `color` (GL_RGBA32F), `depth` (GL_R32F) and `valid`
// (GL_R32UI), w x h, changed in place; returns how many pixels it made valid.
std::size_t border_rows_pass(ContextState& s, GLuint color, GLuint depth, GLuint valid, int w,
                             int h, int max_run);

// What widen_pass does: widen and count (the count read back: a synchronisation), widen alone
// (returns 0), or copy the depth and motion as they are (returns 0).
enum class Widening { Counted, Uncounted, Copy };
// warp::widen_silhouettes on textures: `depth` (GL_R32F) and `motion` (RG of a float texture; 0:
// none) of w x h into `wide_depth` (GL_R32F) and, with motion, `wide_motion` (GL_RGBA32F, the
// motion in RG); returns how many pixels took a neighbour's surface.
std::size_t widen_pass(ContextState& s, GLuint depth, GLuint motion, int w, int h,
                       GLuint wide_depth, GLuint wide_motion, Widening how = Widening::Counted);
// The same into scratch textures, sized here.
std::size_t widen_pass(ContextState& s, GLuint depth, GLuint motion, int w, int h,
                       Texture& wide_depth, Texture* wide_motion, Widening how = Widening::Counted);

// The passes of each path over textures, shared by its CPU-image and texture entry points.
Status fill_passes(ContextState& s, GLuint color, GLuint valid, GLuint depth, int w, int h,
                   GLuint out, warp::FillStats& stats);
// Whether and how the in-between frame's sides follow their true motion (warp's
// interpolate_frame decides it from the cameras and a CPU survey of linearity).
struct TrueMotion {
    bool follow = false;
    bool cameras = false;  // through the cameras, `at` the in-between one; else a along b inverted
    Camera a_camera, b_camera, at;
};
Status interpolate_passes(ContextState& s, const SplatTextures& a, const SplatTextures& b,
                          float s_between, int w, int h, const InterpolateOptions& options,
                          GLuint out_color, GLuint out_depth, GLuint out_motion,
                          InterpolateStats& stats, const TrueMotion& plan, double& cpu_ms);
// `out_motion` (GL_RGBA32F, motion in RG; 0: none) gets the motion each winner carried.
Status splat_passes(ContextState& s, const SplatTextures& in, float factor,
                    const warp::SplatOptions& options, int tw, int th, GLuint out_color,
                    GLuint out_depth, GLuint out_covered, GLuint out_motion, std::size_t& covered);

Status extrapolate_passes(ContextState& s, const SplatTextures& frame, const Camera& camera,
                          const glm::mat4& view, const glm::mat4& projection, float periods,
                          float motion_scale, const warp::FrucOptions& options, GLuint out_color,
                          GLuint out_depth, GLuint out_motion, ExtrapolateStats& stats);
// `from` times `scale` into `to` (GL_RGBA32F), w x h.
void copy_scaled(ContextState& s, GLuint from, GLuint to, int w, int h, float scale);

// The reverse warp's refetch after a footprint-2 splat of `source` by `factor` that carried its
// motion into `carried` and marked `covered`: the refetched colour into `out_color` (tw x th).
Status refetch_pass(ContextState& s, const SplatTextures& source, float factor, GLuint carried,
                    GLuint covered, int tw, int th, GLuint out_color);

// The bound program over w x h in 8x8 groups, its writes visible to whatever comes next.
void dispatch(int w, int h);

// glFinish, then the milliseconds since `since`, which moves to now.
double finish_ms(std::chrono::steady_clock::time_point& since);
// The milliseconds since `since` (CPU work), which moves to now.
double ms_since(std::chrono::steady_clock::time_point& since);

// The grid warp's GL objects (made on first use: the cells are read in a vertex shader, which
// GL ES 3.1 does not promise) and the CPU's side for skewed projections and for more cells than
// a storage buffer holds: the cells and the displacements.
struct GridRaster {
    GLuint program = 0, finish_program = 0, eye_valid_program = 0;
    GLuint cells_program = 0, offsets_program = 0;  // growing the cells (grid_cells.cpp)
    GLuint framebuffer = 0, depth_buffer = 0, cells = 0, counts = 0, offsets = 0, vertex_array = 0;
    GLuint grown[2] = {0, 0};  // cells grown on the GPU: the eye's or the frame's, the history's
    int depth_width = 0, depth_height = 0;
    std::size_t cells_bytes = 0, offsets_bytes = 0, grown_bytes[2] = {0, 0};
    bool overflowed = false;  // the last grow_cells had more cells than a storage buffer holds
    warp::GridWarper warper;
    std::vector<warp::GridCell> cells_cpu, history_cells;
    Image<glm::vec2> displacement, history_displacement;
    Image<float> target_depth, history_target_depth;
};
void destroy_grid(GridRaster& grid);

// Where grid_passes draws: colour GL_RGBA32F, depth GL_R32F, covered GL_R32UI (1, or 2 where a
// stretched triangle won), motion GL_RGBA32F (RG; 0: none), all width x height.
struct GridOutput {
    GLuint color = 0, depth = 0, covered = 0, motion = 0;
    int width = 0, height = 0;
};
// The cells to draw: `cpu` (warp::GridWarper::cells, uploaded in batches), else the `grown`
// cells grow_cells left in s.grid.grown[slot].
struct GridCells {
    const std::vector<warp::GridCell>* cpu = nullptr;
    std::size_t grown = 0;
    int slot = 0;
};
// `cells` drawn over source colour `source_color` (sw x sh) into `out` as
// warp::GridWarper::warp draws them; stats' cells, covered and nonfinite set, `stretched` the
// covered pixels marked 2.
Status grid_passes(ContextState& s, GLuint source_color, int sw, int sh, const GridCells& cells,
                   bool bicubic, const GridOutput& out, warp::GridStats& stats,
                   std::size_t& stretched);
// warp::GridWarper::cells on the GPU: the cells of a source whose depth (GL_R32F) and motion (RG
// of a float texture) are w x h, warped by `factor`, into s.grid.grown[slot] in the CPU's order;
// `count` gets how many. An error where they exceed one storage buffer.
Status grow_cells(ContextState& s, GLuint depth, GLuint motion, int w, int h,
                  const warp::GridOptions& options, float factor, int slot, std::size_t& count);

// The in-between frame's inputs (a, b) and intermediates.
struct Interpolation {
    Texture a_color, a_depth, a_motion, b_color, b_depth, b_motion;
    Texture side_a_color, side_a_depth, side_a_covered, side_a_motion, side_b_color, side_b_depth,
        side_b_covered, side_b_motion, blended, valid, made_motion, true_a, true_b, inverted,
        survey;
    // a's and b's silhouettes widened (widen_pass), and whether they hold the uploaded inputs'.
    Texture a_wide_depth, a_wide_motion, b_wide_depth, b_wide_motion;
    bool widened[2] = {false, false};
    NonfiniteRepair repair_a, repair_b;  // each keeps its repaired copy until the next call
    Image<glm::vec4> survey_samples;     // the linearity survey's samples, read back
    uint64_t key[2] = {0, 0};            // the frame keys a's and b's textures hold (0: none)
    Texture* all[25] = {
        &a_color,      &a_depth,      &a_motion,       &b_color,        &b_depth,
        &b_motion,     &side_a_color, &side_a_depth,   &side_a_covered, &side_a_motion,
        &side_b_color, &side_b_depth, &side_b_covered, &side_b_motion,  &blended,
        &valid,        &made_motion,  &true_a,         &true_b,         &inverted,
        &survey,       &a_wide_depth, &a_wide_motion,  &b_wide_depth,   &b_wide_motion};
};

// Motion refinement: the tiles' counts and boxes (warp::MotionRefiner plans them and runs the
// flow), each box's crop, flow, errors and flow colour, and the chosen colours over the frame.
struct Refinement {
    warp::MotionRefiner refiner;
    Texture counts, labels, crop, flow, errors, flow_color, refined, mask;
    Texture* all[8] = {&counts, &labels, &crop, &flow, &errors, &flow_color, &refined, &mask};
    GLuint won = 0;  // the winners' counter
    std::vector<int> surveyed, disagreeing;
    std::vector<uint32_t> label_codes;  // per tile: its box + 1, 0 where none
    Image<glm::vec4> crop_pixels;
    Image<uint8_t> grey_a, grey_b;
    Image<glm::vec2> seed, flow_field;
};

// After the in-between frame's sides are warped (Interpolation's side textures) and before
// the blend: where they disagree, the flow's colour per pixel found (into Refinement::refined);
// `refined` says whether any pixel took it. The flow's CPU time goes to `cpu_ms`.
Status refine_passes(ContextState& s, const SplatTextures& a, const SplatTextures& b,
                     float s_between, int w, int h, const warp::RefineOptions& options,
                     InterpolateStats& stats, double& cpu_ms, bool& refined);
// ... written over the made frame's colour.
void refine_apply(ContextState& s, int w, int h, const warp::RefineOptions& options,
                  GLuint out_color);

// What the extrapolation's source_wide_* textures hold of the frame its source textures hold.
enum class SourceWide { Nothing, Copied, Widened };

struct ContextState {
    std::unique_ptr<gl::Context> gl;
    GLuint reproject_program = 0;
    GLuint nearest_sampler = 0;  // bound over the inputs: an application's filter settings
                                 // (linear on integer or float textures) would make them incomplete
    GLuint counts_buffer = 0;    // per-outcome counters of the last dispatch
    GLuint read_framebuffer = 0;  // downloads: the texture read is attached here
    Texture depth, motion, id, previous_depth, previous_id, payload, out, hit;
    // Pull-push: the image's colour and valid mask, the pulled levels and the filled ones.
    GLuint pull_image_program = 0, pull_level_program = 0, push_program = 0, final_program = 0;
    GLuint fill_counts = 0;  // holes, then the empty pixels of each level
    GLuint small_levels_program = 0, small_levels = 0;  // the levels of one work group, a buffer
    std::size_t small_levels_bytes = 0;
    GLuint border_program = 0, border_counts = 0;  // border_rows_pass
    GLuint widen_program = 0, widen_counts = 0;    // widen_pass
    Texture color, valid;
    std::vector<Texture> pulled, pulled_depth, filled, filled_depth;
    std::vector<glm::uvec4> hit_readback;   // integer downloads come as RGBA
    std::vector<glm::vec4> float_readback;  // so do float ones of fewer channels
    // Splat: the lists of landings per target pixel, the motion carried, and how many pixels of
    // the last splat had more candidates than the shader sorts (taken by the rule instead).
    GLuint splat_scatter_program = 0, splat_clear_program = 0, splat_gather_program = 0,
           refetch_program = 0;
    GLuint splat_counts = 0, splat_lists = 0;
    std::size_t splat_list_bytes = 0, splat_by_rule = 0;
    Texture splat_motion;
    // Stereo eye: displacement (RG) and the depth seen from the target.
    GLuint displacement_program = 0, finish_program = 0;
    NonfiniteRepair eye_repair;
    Image<float> wide_depth;  // the rendered eye's depth with its silhouettes widened
    Image<glm::vec2> wide_motion;
    // Interpolation: the blend of the two splatted sides, a plain copy, and the hole count.
    GLuint blend_program = 0, copy_program = 0, blend_counts = 0;
    // True motion: each side's, and b's moving pixels inverted (stages of kInvert).
    GLuint true_motion_program = 0, invert_programs[4] = {0, 0, 0, 0}, invert_buffer = 0;
    GLuint survey_program = 0;  // gathers the pixels warp's linearity survey looks at
    // The shot-change test: each hit's display difference summed (64 bits as two words), the
    // display table, the survey's reprojected colour and hits.
    GLuint shot_change_program = 0, shot_change_counts = 0;
    Texture display_table, shot_reprojected, shot_hit;
    std::size_t invert_bytes = 0;
    Interpolation interpolation;
    GLuint refine_programs[5] = {0, 0, 0, 0, 0};  // survey, crop, evaluate, decide, apply
    Refinement refinement;
    GridRaster grid;
    Texture displacement, target_depth, eye_color;
    // The eye's history: its displacement and depth, warped colour, depth and coverage, the merge.
    GLuint merge_program = 0, eye_counts = 0;
    Texture history_color, history_depth, history_motion, history_displacement,
        history_target_depth, history_warped, history_warped_depth, history_covered, merged;
    // The eye's and its history's silhouettes widened (widen_pass).
    Texture eye_wide_depth, history_wide_depth, history_wide_motion;
    NonfiniteRepair eye_history_repair;
    Image<float> wide_history_depth;
    Image<glm::vec2> wide_history_motion;
    // Extrapolation: the static-layer test (its moving pixels counted), the input frame's
    // textures and the made frame's motion.
    GLuint static_layer_program = 0, extrapolate_counts = 0;
    NonfiniteRepair extrapolate_repair;
    Texture source_color, source_depth, source_motion, made_motion;
    Texture source_wide_depth, source_wide_motion;  // the source's silhouettes widened
    uint64_t extrapolate_key = 0;  // the frame key of what the source textures hold (0: none)
    SourceWide source_wide = SourceWide::Nothing;  // what source_wide_* hold
    bool source_geometry_uploaded = false;  // source_depth and _motion hold the frame (not handed)
    bool made_valid = false;  // color, depth and made_motion hold the last extrapolation
    NonfiniteCounts extrapolate_nonfinite;  // ... and what its repair found

    // Counters live in GPU memory (a buffer hinted for reading may be placed in the host's, where
    // every shader atomic crosses the bus: reprojection took 39-90 ms at 1920x1080 on an H200,
    // 0.32 ms with them in GPU memory) and are copied into this one to be read.
    GLuint readback_buffer = 0;
    GLuint unpack_buffer = 0;  // uploads go through it: the GPU lays the texels out, not the CPU
    std::size_t unpack_bytes = 0;  // its size: the largest upload so far (kept until destroyed)

    // Binds `textures` to units 0, 1, ... for texelFetch through the nearest sampler (0: none).
    static constexpr unsigned kInputUnits = 16;  // GL ES 3.1's least for compute shaders
    void bind_inputs(std::initializer_list<GLuint> textures) const;
    // Units 0..15 without a sampler again (the application's own filtering applies).
    static void unbind_inputs();
    // Zeroes the first `count` counters of `buffer` and binds it as storage buffer 0.
    static void reset_counters(GLuint buffer, std::size_t count);
    // A counters buffer in GPU memory of `bytes`.
    GLuint make_counters(std::size_t bytes);
    // The first `bytes` of counters buffer `buffer` (the shaders that wrote it finished).
    void read_counters(GLuint buffer, void* counts, std::size_t bytes);
    // Uploads the texture's rows, `stride` pixels apart, into `texture` (already sized), or into
    // its top-left width x height.
    void upload(const Texture& texture, const void* data, std::ptrdiff_t stride, int width = 0,
                int height = 0);
    // A frame's colour, depth and motion into `color` (RGBA32F), `depth` (R32F) and `motion`
    // (RG32F), sized to the frame.
    void upload_frame(const GBufferView& frame, Texture& color, Texture& depth, Texture& motion);
    // Reads `texture` (GL_RGBA32F into floats, GL_R32UI into hit_readback) through the
    // framebuffer, or its top-left width x height; `stride` in pixels for float targets.
    void download(const Texture& texture, void* data, std::ptrdiff_t stride, int width = 0,
                  int height = 0);
    // The first `channels` of each pixel of a float texture into floats, `stride` pixels apart.
    void download_channels(const Texture& texture, float* data, int channels,
                           std::ptrdiff_t stride);
    // A made frame's colour and depth (the `color` and `depth` textures) into `made`, sized.
    void download_made(Frame& made);
};

}  // namespace reprise::gpu
