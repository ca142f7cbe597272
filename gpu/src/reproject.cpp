// warp::reproject as a compute shader: the same per-frame constants (warp::reproject_setup), the
// same arithmetic in the same order (`precise` where the driver offers it, so no fused
// multiply-add), the same outcomes counted per work group and then globally.
#include <chrono>
#include <cstring>
#include <string>

#include "state.hpp"

namespace reprise::gpu {

namespace {

constexpr const char* kReprojectShader = R"(
layout(binding = 0) uniform highp sampler2D depth_map;
layout(binding = 1) uniform highp sampler2D motion_map;
layout(binding = 2) uniform highp usampler2D id_map;
layout(binding = 3) uniform highp sampler2D previous_depth;
layout(binding = 4) uniform highp usampler2D previous_id;
layout(binding = 5) uniform highp sampler2D payload;
layout(binding = 0, rgba32f) writeonly uniform highp image2D out_image;
layout(binding = 1, r32ui) writeonly uniform highp uimage2D hit_image;
layout(std430, binding = 0) buffer Counts { uint counts[8]; };
uniform highp float kx, ky, kw, kz, k1, wz, w1, px0, py0, qx0, qy0, tolerance, id_tolerance;
uniform bool use_ids, background_hits, write_hit;
uniform ivec2 size, previous_size;
uniform int step;

const uint HIT = 0u, OFFSCREEN = 1u, BEHIND = 2u, OCCLUDED = 3u, OTHER_ID = 4u, INVALID = 5u;


uint classify(ivec2 p) {
    highp float z = texelFetch(depth_map, p, 0).r;
    highp vec2 m = texelFetch(motion_map, p, 0).rg;
    if (!finite(m.x) || !finite(m.y)) return INVALID;
    PRECISE highp float z_expected = 0.0;
    bool background = !finite(z);
    if (!background) {
        PRECISE highp float w = wz * z + w1;
        PRECISE highp float row = ky * (float(p.y) + py0) + kw;
        z_expected = w * (kx * (float(p.x) + px0) + row) + (kz * z + k1);
        if (!finite(z_expected)) return INVALID;
        if (z_expected <= 0.0) return BEHIND;
    } else if (!(background_hits && positive_inf(z))) {
        return INVALID;
    }
    PRECISE highp float qx = (float(p.x) + qx0) + m.x;
    PRECISE highp float qy = (float(p.y) + qy0) + m.y;
    if (!(qx >= 0.0 && qy >= 0.0 && qx <= float(previous_size.x) && qy <= float(previous_size.y)))
        return OFFSCREEN;
    PRECISE highp float sx = qx - 0.5, sy = qy - 0.5;
    int ix = int(floor(sx)), iy = int(floor(sy));
    PRECISE highp float fx = sx - float(ix), fy = sy - float(iy);
    int x0 = clamp(ix, 0, previous_size.x - 1), y0 = clamp(iy, 0, previous_size.y - 1);
    int x1 = fx == 0.0 ? x0 : min(ix + 1, previous_size.x - 1);
    int y1 = fy == 0.0 ? y0 : min(iy + 1, previous_size.y - 1);
    ivec2 ta = ivec2(x0, y0), tb = ivec2(x1, y0), tc = ivec2(x0, y1), td = ivec2(x1, y1);

    bool ids_agree = true;
    if (use_ids) {
        uint me = texelFetch(id_map, p, 0).r;
        ids_agree = texelFetch(previous_id, ta, 0).r == me && texelFetch(previous_id, tb, 0).r == me &&
                    texelFetch(previous_id, tc, 0).r == me && texelFetch(previous_id, td, 0).r == me;
    }
    highp float a = texelFetch(previous_depth, ta, 0).r, b = texelFetch(previous_depth, tb, 0).r;
    highp float c = texelFetch(previous_depth, tc, 0).r, d = texelFetch(previous_depth, td, 0).r;
    if (background) {
        if (!(positive_inf(a) && positive_inf(b) && positive_inf(c) && positive_inf(d)))
            return OCCLUDED;
    } else {
        if (!(finite(a) && finite(b) && finite(c) && finite(d))) return OCCLUDED;
        PRECISE highp float top = a + (b - a) * fx, bottom = c + (d - c) * fx;
        PRECISE highp float z_previous = top + (bottom - top) * fy;
        PRECISE highp float allowed = (use_ids && ids_agree ? id_tolerance : tolerance) * z_expected;
        if (!(abs(z_expected - z_previous) <= allowed)) return OCCLUDED;
    }
    if (!ids_agree) return OTHER_ID;
    highp vec4 va = texelFetch(payload, ta, 0), vb = texelFetch(payload, tb, 0);
    highp vec4 vc = texelFetch(payload, tc, 0), vd = texelFetch(payload, td, 0);
    PRECISE highp vec4 top = va + (vb - va) * fx, bottom = vc + (vd - vc) * fx;
    PRECISE highp vec4 v = top + (bottom - top) * fy;
    if (!(finite(v.x) && finite(v.y) && finite(v.z) && finite(v.w))) return INVALID;
    imageStore(out_image, p, v);
    return HIT;
}

// Each invocation's outcome goes to shared memory and eight invocations count them: one global
// atomic per group and outcome, not one per pixel.
shared uint group_outcomes[64];

void main() {
    uint i = gl_LocalInvocationIndex;
    ivec2 p = ivec2(gl_GlobalInvocationID.xy) * step;
    uint outcome = 8u;  // outside the image: not counted
    if (p.x < size.x && p.y < size.y) {
        outcome = classify(p);
        if (write_hit) imageStore(hit_image, p, uvec4(outcome == HIT ? 1u : 0u));
    }
    group_outcomes[i] = outcome;
    barrier();
    if (i < 8u) {
        uint n = 0u;
        for (int k = 0; k < 64; ++k) n += group_outcomes[k] == i ? 1u : 0u;
        if (n != 0u) atomicAdd(counts[i], n);
    }
}
)";

using Clock = std::chrono::steady_clock;

}  // namespace

Status reproject_pass(ContextState& s, GLuint depth, GLuint motion, GLuint id,
                      GLuint previous_depth, GLuint previous_id, GLuint payload, GLuint out,
                      GLuint hit, int width, int height, int previous_width, int previous_height,
                      const warp::ReprojectSetup& k, int step, warp::ReprojectCounts& counts) {
    const GLuint program = s.reproject_program;
    glUseProgram(program);
    s.bind_inputs({depth, motion, id, previous_depth, previous_id, payload});
    glBindImageTexture(0, out, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_RGBA32F);
    if (hit) glBindImageTexture(1, hit, 0, GL_FALSE, 0, GL_WRITE_ONLY, GL_R32UI);
    auto set = [&](const char* name, float v) {
        glUniform1f(glGetUniformLocation(program, name), v);
    };
    set("kx", k.kx), set("ky", k.ky), set("kw", k.kw), set("kz", k.kz), set("k1", k.k1);
    set("wz", k.wz), set("w1", k.w1), set("px0", k.px0), set("py0", k.py0);
    set("qx0", k.qx0), set("qy0", k.qy0), set("tolerance", k.tolerance);
    set("id_tolerance", k.id_tolerance);
    glUniform1i(glGetUniformLocation(program, "use_ids"), k.use_ids);
    glUniform1i(glGetUniformLocation(program, "background_hits"), k.background);
    glUniform1i(glGetUniformLocation(program, "write_hit"), hit != 0);
    glUniform2i(glGetUniformLocation(program, "size"), width, height);
    glUniform2i(glGetUniformLocation(program, "previous_size"), previous_width, previous_height);
    glUniform1i(glGetUniformLocation(program, "step"), step);

    ContextState::reset_counters(s.counts_buffer, 8);
    dispatch((width + step - 1) / step, (height + step - 1) / step);  // the looked-up pixels
    GLuint n[8] = {};
    s.read_counters(s.counts_buffer, n, sizeof n);
    ContextState::unbind_inputs();
    glUseProgram(0);
    REPRISE_TRY(gl::check_errors("gpu reproject"));
    counts = {.hits = n[0],
              .offscreen = n[1],
              .behind = n[2],
              .occluded = n[3],
              .other_id = n[4],
              .invalid = n[5]};
    return {};
}

Status create_programs(ContextState& state) {
    return gl::link_compute((std::string(kComputeHeader) + kReprojectShader).c_str(),
                            "reprojection", state.reproject_program);
}

Status Context::reproject(const GBufferView& current, const GBufferView& previous,
                          warp::ConstPayload previous_payload, warp::Payload out,
                          ImageView<uint8_t> hit, const warp::ReprojectOptions& options,
                          warp::ReprojectCounts& counts) {
    timings_ = {};
    const int w = current.depth.width, h = current.depth.height;
    const int pw = previous.depth.width, ph = previous.depth.height;
    if (previous_payload.channels != 4 || out.channels != 4)
        return Status::error("gpu reproject: the payload has " +
                             std::to_string(previous_payload.channels) +
                             " channels; the GPU path takes RGBA (4)");
    if (previous_payload.stride % 4 || out.stride % 4)
        return Status::error("gpu reproject: payload rows must be whole RGBA pixels apart");
    REPRISE_ASSERT(current.motion.width == w && current.motion.height == h);
    REPRISE_ASSERT(previous_payload.width == pw && previous_payload.height == ph);
    REPRISE_ASSERT(out.width == w && out.height == h);
    REPRISE_ASSERT(hit.empty() || (hit.width == w && hit.height == h));
    if (w <= 0 || h <= 0 || pw <= 0 || ph <= 0) {
        counts = {};
        return {};
    }
    ContextState& s = *state_;
    REPRISE_TRY(s.gl->acquire());
    const bool ids = !current.id.empty() && !previous.id.empty();
    const warp::ReprojectSetup k =
        warp::reproject_setup(current.camera, previous.camera, w, h, ids, options);

    Clock::time_point t = Clock::now();
    s.made_valid = false;  // color and depth no longer hold an extrapolation
    s.depth.ensure(GL_R32F, w, h);
    s.motion.ensure(GL_RG32F, w, h);
    s.out.ensure(GL_RGBA32F, w, h);
    s.hit.ensure(GL_R32UI, w, h);
    s.previous_depth.ensure(GL_R32F, pw, ph);
    s.payload.ensure(GL_RGBA32F, pw, ph);
    s.upload(s.depth, current.depth.data, current.depth.stride);
    s.upload(s.motion, current.motion.data, current.motion.stride);
    s.upload(s.out, out.data, out.stride / 4);
    s.upload(s.previous_depth, previous.depth.data, previous.depth.stride);
    s.upload(s.payload, previous_payload.data, previous_payload.stride / 4);
    if (ids) {
        s.id.ensure(GL_R32UI, w, h);
        s.previous_id.ensure(GL_R32UI, pw, ph);
        s.upload(s.id, current.id.data, current.id.stride);
        s.upload(s.previous_id, previous.id.data, previous.id.stride);
    }
    timings_.upload_ms = finish_ms(t);

    const int step = std::max(1, options.step);
    REPRISE_TRY(reproject_pass(s, s.depth.name, s.motion.name, ids ? s.id.name : 0,
                               s.previous_depth.name, ids ? s.previous_id.name : 0, s.payload.name,
                               s.out.name, s.hit.name, w, h, pw, ph, k, step, counts));
    timings_.compute_ms = finish_ms(t);

    s.download(s.out, out.data, out.stride / 4);
    if (!hit.empty()) {
        s.download(s.hit, nullptr, 0);
        for (int y = 0; y < h; y += step)
            for (int x = 0; x < w; x += step)
                hit(x, y) = uint8_t(s.hit_readback[std::size_t(y) * w + x].x);
    }
    REPRISE_TRY(gl::check_errors("gpu reproject download"));
    timings_.download_ms = finish_ms(t);
    return {};
}

Status Context::reproject(const GBufferTextures& current, const GBufferTextures& previous,
                          unsigned payload, unsigned out, unsigned hit,
                          const warp::ReprojectOptions& options, warp::ReprojectCounts& counts) {
    ContextState& s = *state_;
    REPRISE_TRY(s.gl->acquire());
    const int w = current.width, h = current.height, pw = previous.width, ph = previous.height;
    if (w <= 0 || h <= 0 || pw <= 0 || ph <= 0)
        return Status::error("gpu reproject: texture sizes " + std::to_string(w) + "x" +
                             std::to_string(h) + " and " + std::to_string(pw) + "x" +
                             std::to_string(ph) + " must be positive");
    REPRISE_TRY(check_texture(current.depth, GL_R32F, w, h, "current depth"));
    REPRISE_TRY(check_texture(current.motion, GL_RG32F, w, h, "current motion"));
    REPRISE_TRY(check_texture(previous.depth, GL_R32F, pw, ph, "previous depth"));
    REPRISE_TRY(check_texture(payload, GL_RGBA32F, pw, ph, "previous payload"));
    REPRISE_TRY(check_texture(out, GL_RGBA32F, w, h, "output"));
    if (hit) REPRISE_TRY(check_texture(hit, GL_R32UI, w, h, "hit"));
    const bool ids = current.id && previous.id;
    if (ids) {
        REPRISE_TRY(check_texture(current.id, GL_R32UI, w, h, "current id"));
        REPRISE_TRY(check_texture(previous.id, GL_R32UI, pw, ph, "previous id"));
    }
    if (payload == out) return Status::error("gpu reproject: the output is the payload texture");
    const warp::ReprojectSetup k =
        warp::reproject_setup(current.camera, previous.camera, w, h, ids, options);
    timings_ = {};
    Clock::time_point t = Clock::now();
    REPRISE_TRY(reproject_pass(s, current.depth, current.motion, ids ? current.id : 0,
                               previous.depth, ids ? previous.id : 0, payload, out, hit, w, h, pw,
                               ph, k, std::max(1, options.step), counts));
    timings_.compute_ms = finish_ms(t);
    timings_.download_ms = 0.0;
    return {};
}

}  // namespace reprise::gpu
