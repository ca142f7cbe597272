// warp::widen_silhouettes on the GPU: a pixel with a 4-neighbour nearer than kSilhouetteKeep of
// its depth takes the nearest such neighbour's depth and motion (ties to the first of left,
// right, up, down), counted per work group.
#include <chrono>
#include <string>

#include "reprise/warp/silhouettes.hpp"

#include "state.hpp"

namespace reprise::gpu {

namespace {

constexpr const char* kWiden = R"(
layout(binding = 0) uniform highp sampler2D depth_map;
layout(binding = 1) uniform highp sampler2D motion_map;
layout(binding = 0, r32f) writeonly uniform highp image2D wide_depth;
layout(binding = 1, rgba32f) writeonly uniform highp image2D wide_motion;
layout(std430, binding = 0) buffer Counts { uint counts[]; };
uniform ivec2 size;
uniform highp float keep;
uniform bool moves, widen;  // widen false: a plain copy

// z > 0, +inf included: NaN, zeros and negatives neither take nor give.
bool positive(highp float z) {
    uint b = floatBitsToUint(z);
    return b != 0u && b <= 0x7f800000u;
}

bool widened(ivec2 p) {
    highp float z = texelFetch(depth_map, p, 0).r;
    PRECISE highp float nearest = z * keep;
    ivec2 from = p;
    if (widen && positive(z)) {
        const ivec2 around[4] = ivec2[4](ivec2(-1, 0), ivec2(1, 0), ivec2(0, -1), ivec2(0, 1));
        for (int k = 0; k < 4; ++k) {
            ivec2 q = p + around[k];
            if (q.x < 0 || q.y < 0 || q.x >= size.x || q.y >= size.y) continue;
            highp float c = texelFetch(depth_map, q, 0).r;
            if (positive(c) && c < nearest) {
                nearest = c;
                from = q;
            }
        }
    }
    bool took = from != p;
    imageStore(wide_depth, p, vec4(took ? nearest : z, 0.0, 0.0, 0.0));
    if (moves) imageStore(wide_motion, p, vec4(texelFetch(motion_map, from, 0).rg, 0.0, 0.0));
    return took;
}

void main() {
    ivec2 p = ivec2(gl_GlobalInvocationID.xy);
    bool inside = p.x < size.x && p.y < size.y;
    COUNT_IN_GROUP(inside && widened(p), counts[0])
}
)";

}  // namespace

Status create_silhouette_program(ContextState& s) {
    s.widen_counts = s.make_counters(sizeof(GLuint));
    return gl::link_compute((kComputeHeader + kWiden).c_str(), "widened silhouettes",
                            s.widen_program);
}

std::size_t widen_pass(ContextState& s, GLuint depth, GLuint motion, int w, int h,
                       GLuint wide_depth, GLuint wide_motion, Widening how) {
    const GLuint program = s.widen_program;
    glUseProgram(program);
    s.bind_inputs({depth, motion});
    glBindImageTexture(0, wide_depth, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32F);
    if (motion) glBindImageTexture(1, wide_motion, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    glUniform2i(glGetUniformLocation(program, "size"), w, h);
    glUniform1f(glGetUniformLocation(program, "keep"), warp::kSilhouetteKeep);
    glUniform1i(glGetUniformLocation(program, "moves"), motion ? 1 : 0);
    glUniform1i(glGetUniformLocation(program, "widen"), how != Widening::Copy ? 1 : 0);
    ContextState::reset_counters(s.widen_counts, 1);
    dispatch(w, h);
    ContextState::unbind_inputs();
    glUseProgram(0);
    GLuint changed = 0;
    if (how == Widening::Counted) s.read_counters(s.widen_counts, &changed, sizeof changed);
    return changed;
}

std::size_t widen_pass(ContextState& s, GLuint depth, GLuint motion, int w, int h,
                       Texture& wide_depth, Texture* wide_motion, Widening how) {
    REPRISE_ASSERT(!motion || wide_motion);
    wide_depth.ensure(GL_R32F, w, h);
    if (motion) wide_motion->ensure(GL_RGBA32F, w, h);
    return widen_pass(s, depth, motion, w, h, wide_depth.name, motion ? wide_motion->name : 0u,
                      how);
}

Status Context::widen_silhouettes(const GBufferTextures& frame, unsigned out_depth,
                                  unsigned out_motion, std::size_t& changed) {
    changed = 0;
    timings_ = {};
    ContextState& s = *state_;
    REPRISE_TRY(s.gl->acquire());
    const int w = frame.width, h = frame.height;
    if (w <= 0 || h <= 0)
        return Status::error("gpu widen silhouettes: texture size " + std::to_string(w) + "x" +
                             std::to_string(h) + " must be positive");
    REPRISE_TRY(check_texture(frame.depth, GL_R32F, w, h, "depth"));
    REPRISE_TRY(check_texture(out_depth, GL_R32F, w, h, "output depth"));
    if (frame.motion) {
        REPRISE_TRY(check_texture(frame.motion, GL_RG32F, w, h, "motion"));
        REPRISE_TRY(check_texture(out_motion, GL_RGBA32F, w, h, "output motion"));
    }
    if (out_depth == frame.depth)
        return Status::error("gpu widen silhouettes: the output depth is the input depth");
    auto t = std::chrono::steady_clock::now();
    changed = widen_pass(s, frame.depth, frame.motion, w, h, out_depth, out_motion);
    REPRISE_TRY(gl::check_errors("gpu widen silhouettes"));
    timings_.compute_ms = finish_ms(t);
    return {};
}

}  // namespace reprise::gpu
