// warp::shot_change on the GPU: the survey's reprojection (every 4th pixel of every 4th row),
// then each hit's display difference (the CPU's table and arithmetic, rounded to integers) summed
// per work group and into 64 bits, and the CPU's decision on the counts and the sum.
#include <chrono>
#include <string>

#include "state.hpp"

namespace reprise::gpu {

namespace {

constexpr const char* kDifference = R"(
layout(binding = 0) uniform highp sampler2D color;
layout(binding = 1) uniform highp sampler2D reprojected;
layout(binding = 2) uniform highp usampler2D hit;
layout(binding = 3) uniform highp sampler2D display_table;  // TABLE_SIZE + 1 texels in a row
layout(std430, binding = 0) buffer Sum { uint low, high; };
uniform ivec2 count;  // looked-up pixels across and down
shared uint group_sum[64];

highp float display(highp float linear) {
    // NaN and negatives to 0, as on the CPU (NaN tested on bits: a compiler may assume none).
    bool nan = (floatBitsToUint(linear) & 0x7fffffffu) > 0x7f800000u;
    PRECISE highp float c = !nan && linear >= 0.0 ? min(linear, 1.0) * float(TABLE_SIZE) : 0.0;
    int i = min(int(c), TABLE_SIZE - 1);
    PRECISE highp float t = c - float(i);
    highp float v0 = texelFetch(display_table, ivec2(i, 0), 0).r;
    highp float v1 = texelFetch(display_table, ivec2(i + 1, 0), 0).r;
    PRECISE highp float step = v1 - v0;
    PRECISE highp float offset = step * t;
    PRECISE highp float v = v0 + offset;
    return v;
}

uint difference(ivec2 p) {
    highp vec4 a = texelFetch(color, p, 0), b = texelFetch(reprojected, p, 0);
    uint sum = 0u;
    for (int k = 0; k < 3; ++k) {
        PRECISE highp float d = abs(display(a[k]) - display(b[k]));
        PRECISE highp float scaled = d * 1048576.0 + 0.5;
        sum += uint(floor(scaled));
    }
    return sum;
}

void main() {
    ivec2 i = ivec2(gl_GlobalInvocationID.xy), p = 4 * i;
    bool looked = i.x < count.x && i.y < count.y;
    group_sum[gl_LocalInvocationIndex] =
        looked && texelFetch(hit, p, 0).r != 0u ? difference(p) : 0u;
    barrier();
    if (gl_LocalInvocationIndex == 0u) {
        uint n = 0u;  // at most 64 x 3 x 2^20: no overflow
        for (int k = 0; k < 64; ++k) n += group_sum[k];
        uint before = atomicAdd(low, n);
        if (before + n < before) atomicAdd(high, 1u);  // the carry, by whoever wrapped
    }
}
)";

static_assert(warp::kShotChangeStep == 4, "kDifference looks at every 4th pixel");

// The survey and the sum on textures already bound to names; the decision into `result`.
Status shot_change_passes(ContextState& s, const SplatTextures& frame, GLuint frame_id,
                          const SplatTextures& previous, GLuint previous_id,
                          const Camera& frame_camera, const Camera& previous_camera,
                          float cut_misses, float cut_color, warp::ShotChange& result) {
    const int w = frame.width, h = frame.height;
    const bool ids = frame_id && previous_id;
    const warp::ReprojectSetup k = warp::reproject_setup(
        frame_camera, previous_camera, w, h, ids,
        {.depth_tolerance = warp::kShotChangeDepthTolerance, .step = warp::kShotChangeStep});
    s.shot_reprojected.ensure(GL_RGBA32F, w, h);
    s.shot_hit.ensure(GL_R32UI, w, h);
    REPRISE_TRY(reproject_pass(s, frame.depth, frame.motion, ids ? frame_id : 0, previous.depth,
                               ids ? previous_id : 0, previous.color, s.shot_reprojected.name,
                               s.shot_hit.name, w, h, previous.width, previous.height, k,
                               warp::kShotChangeStep, result.counts));
    const int cw = (w + warp::kShotChangeStep - 1) / warp::kShotChangeStep,
              ch = (h + warp::kShotChangeStep - 1) / warp::kShotChangeStep;
    glUseProgram(s.shot_change_program);
    s.bind_inputs({frame.color, s.shot_reprojected.name, s.shot_hit.name, s.display_table.name});
    glUniform2i(glGetUniformLocation(s.shot_change_program, "count"), cw, ch);
    ContextState::reset_counters(s.shot_change_counts, 2);
    dispatch(cw, ch);
    GLuint sum[2] = {};
    s.read_counters(s.shot_change_counts, sum, sizeof sum);
    ContextState::unbind_inputs();
    glUseProgram(0);
    REPRISE_TRY(gl::check_errors("gpu shot change"));
    result.difference = uint64_t(sum[1]) << 32 | sum[0];
    result.cut =
        warp::shot_change_decision(result.counts, result.difference, w, h, cut_misses, cut_color);
    return {};
}

}  // namespace

Status create_shot_change_program(ContextState& s) {
    REPRISE_TRY(gl::link_compute((std::string(kComputeHeader) + "#define TABLE_SIZE " +
                                  std::to_string(warp::kDisplayTableSize) + "\n" + kDifference)
                                     .c_str(),
                                 "shot change", s.shot_change_program));
    s.shot_change_counts = s.make_counters(2 * sizeof(GLuint));
    s.display_table.ensure(GL_R32F, warp::kDisplayTableSize + 1, 1);
    s.upload(s.display_table, warp::display_table(), warp::kDisplayTableSize + 1);
    return {};
}

Status Context::shot_change(const GBufferView& frame, const GBufferView& previous, float cut_misses,
                            float cut_color, warp::ShotChange& result) {
    timings_ = {};
    result = {};
    const int w = frame.width(), h = frame.height();
    const int pw = previous.width(), ph = previous.height();
    if (frame.depth.empty() || frame.motion.empty() || previous.depth.empty() || w <= 0 || h <= 0 ||
        pw <= 0 || ph <= 0)
        return {};  // as on the CPU: never a cut
    REPRISE_ASSERT(frame.depth.width == w && frame.depth.height == h && frame.motion.width == w &&
                   frame.motion.height == h);
    REPRISE_ASSERT(previous.depth.width == pw && previous.depth.height == ph);
    const bool ids = !frame.id.empty() && !previous.id.empty();
    REPRISE_ASSERT(!ids || (frame.id.width == w && frame.id.height == h &&
                            previous.id.width == pw && previous.id.height == ph));
    ContextState& s = *state_;
    REPRISE_TRY(s.gl->acquire());
    auto t = std::chrono::steady_clock::now();
    s.made_valid = false;  // color and depth no longer hold an extrapolation
    s.upload_frame(frame, s.color, s.depth, s.motion);
    s.payload.ensure(GL_RGBA32F, pw, ph);
    s.previous_depth.ensure(GL_R32F, pw, ph);
    s.upload(s.payload, previous.color.data, previous.color.stride);
    s.upload(s.previous_depth, previous.depth.data, previous.depth.stride);
    if (ids) {
        s.id.ensure(GL_R32UI, w, h);
        s.previous_id.ensure(GL_R32UI, pw, ph);
        s.upload(s.id, frame.id.data, frame.id.stride);
        s.upload(s.previous_id, previous.id.data, previous.id.stride);
    }
    timings_.upload_ms = finish_ms(t);
    REPRISE_TRY(shot_change_passes(
        s, {s.color.name, s.depth.name, s.motion.name, w, h}, ids ? s.id.name : 0,
        {s.payload.name, s.previous_depth.name, 0, pw, ph}, ids ? s.previous_id.name : 0,
        frame.camera, previous.camera, cut_misses, cut_color, result));
    timings_.compute_ms = finish_ms(t);
    return {};
}

Status Context::shot_change(const GBufferTextures& frame, unsigned frame_color,
                            const GBufferTextures& previous, unsigned previous_color,
                            float cut_misses, float cut_color, warp::ShotChange& result) {
    timings_ = {};
    result = {};
    ContextState& s = *state_;
    REPRISE_TRY(s.gl->acquire());
    const int w = frame.width, h = frame.height, pw = previous.width, ph = previous.height;
    if (w <= 0 || h <= 0 || pw <= 0 || ph <= 0)
        return Status::error("gpu shot change: texture sizes " + std::to_string(w) + "x" +
                             std::to_string(h) + " and " + std::to_string(pw) + "x" +
                             std::to_string(ph) + " must be positive");
    REPRISE_TRY(check_texture(frame.depth, GL_R32F, w, h, "frame depth"));
    REPRISE_TRY(check_texture(frame.motion, GL_RG32F, w, h, "frame motion"));
    REPRISE_TRY(check_texture(frame_color, GL_RGBA32F, w, h, "frame colour"));
    REPRISE_TRY(check_texture(previous.depth, GL_R32F, pw, ph, "previous depth"));
    REPRISE_TRY(check_texture(previous_color, GL_RGBA32F, pw, ph, "previous colour"));
    const bool ids = frame.id && previous.id;
    if (ids) {
        REPRISE_TRY(check_texture(frame.id, GL_R32UI, w, h, "frame id"));
        REPRISE_TRY(check_texture(previous.id, GL_R32UI, pw, ph, "previous id"));
    }
    auto t = std::chrono::steady_clock::now();
    REPRISE_TRY(shot_change_passes(s, {frame_color, frame.depth, frame.motion, w, h},
                                   ids ? frame.id : 0, {previous_color, previous.depth, 0, pw, ph},
                                   ids ? previous.id : 0, frame.camera, previous.camera, cut_misses,
                                   cut_color, result));
    timings_.compute_ms = finish_ms(t);
    return {};
}

}  // namespace reprise::gpu
