#pragma once
// GLSL ES 3.00 shaders of the heavy shading mode and its screen-space reuse cache, and of the
// key light's shadow map. The heavy pass uses the G-buffer vertex shader (gbuffer_shaders.hpp).
//
// Cache layout (ping-pong between frames, GL rows bottom-up like the framebuffer):
//   term (RGBA16F, read filtered): procedural albedo (rgb), key-light visibility (a)
//   meta (RGBA32F): depth key (depth_key below) of the unjittered image, object id, age in
//         frames (0 = shaded this frame), temporal gradient of the display colour per frame
//         (-1: unknown, the pixel was shaded on a miss). The CPU reads each pixel's status from it.

namespace reprise::server::shaders {

// Also the heavy pass's depth pre-pass (u_light_matrix = the camera's view-projection), so that
// each pixel runs the heavy shader once: gl_Position is invariant in both programs.
inline constexpr const char* kShadowVertex = R"(#version 300 es
invariant gl_Position;
uniform mat4 u_light_matrix;
layout(location = 0) in vec3 a_position;
void main() { gl_Position = u_light_matrix * vec4(a_position, 1.0); }
)";

inline constexpr const char* kShadowFragment = R"(#version 300 es
precision mediump float;
void main() {}
)";

// Compiled three times: REUSE 0 (full shading, no cache code); REUSE 1 with PASS 1 (the hit
// pass: reuse or discard) and PASS 2 (the miss pass: full shading where the hit pass discarded).
inline constexpr const char* kHeavyFragment = R"(
precision highp float;
precision highp int;
precision highp sampler2DShadow;
uniform vec2 u_size;
uniform vec3 u_eye;
uniform vec3 u_light_direction;
uniform vec3 u_light_color;
uniform vec3 u_ambient;
uniform vec4 u_base_color;
uniform bool u_textured;
uniform float u_specular;
uniform float u_shininess;
uniform float u_id;
uniform sampler2D u_texture;
uniform sampler2DShadow u_shadow_map;
uniform mat4 u_light_matrix;
uniform float u_shadow_texel;
uniform int u_pcf_radius;
uniform int u_octaves;
uniform int u_point_count;
uniform vec3 u_point_position[16];
uniform vec3 u_point_color[16];
uniform int u_reuse;  // 0 off, 1 cache, 2 adaptive
uniform bool u_cache_valid;
uniform highp sampler2D u_cache_term;
uniform highp sampler2D u_cache_meta;
uniform int u_frame;
uniform int u_refresh;  // 0 tiled, 1 random 2x2, 2 random 8x8, 3 interleaved
uniform int u_period;
uniform ivec2 u_tiles;
uniform int u_interleave_step;
uniform float u_threshold;
uniform int u_filter_radius;
uniform float u_epsilon;
uniform bool u_orthographic;
uniform float u_smoothing;
in vec4 v_clip;
in vec4 v_previous_clip;
in vec3 v_world;
in vec3 v_normal;
in vec2 v_uv;
in float v_depth;
layout(location = 0) out vec4 o_color;
layout(location = 1) out vec4 o_depth_motion_id;
layout(location = 2) out vec4 o_normal;
#if REUSE
layout(location = 3) out vec4 o_cache_term;
layout(location = 4) out vec4 o_cache_meta;
#endif

uint hash3(uvec3 v) {
    uint h = v.x * 0x8da6b343u ^ v.y * 0xd8163841u ^ v.z * 0xcb1ab31fu;
    h ^= h >> 16; h *= 0x7feb352du; h ^= h >> 15; h *= 0x846ca68bu; h ^= h >> 16;
    return h;
}
float lattice(ivec2 p, uint seed) {
    return float(hash3(uvec3(uvec2(p), seed)) & 0xffffu) * (1.0 / 65535.0);
}
float value_noise(vec2 p, uint seed) {
    vec2 f = floor(p);
    vec2 t = p - f;
    t = t * t * (3.0 - 2.0 * t);
    ivec2 i = ivec2(f);
    float a = lattice(i, seed), b = lattice(i + ivec2(1, 0), seed);
    float c = lattice(i + ivec2(0, 1), seed), d = lattice(i + ivec2(1, 1), seed);
    return mix(mix(a, b, t.x), mix(c, d, t.x), t.y);
}
float fbm(vec2 p, int octaves, uint seed) {
    float sum = 0.0, amplitude = 0.5, norm = 0.0;
    for (int k = 0; k < octaves; ++k) {
        sum += amplitude * value_noise(p, seed + uint(k));
        norm += amplitude;
        amplitude *= 0.5;
        p = mat2(1.6, 1.2, -1.2, 1.6) * p + vec2(17.3, 5.1);
    }
    return sum / max(norm, 1e-6);
}
// Marbled, domain-warped noise over the surface's texture coordinates.
vec3 procedural_albedo() {
    vec3 base = u_base_color.rgb;
    if (u_textured) base *= texture(u_texture, v_uv).rgb;
    uint seed = uint(u_id) * 131u;
    vec2 p = v_uv * 1.5;
    vec2 warp = vec2(fbm(p, u_octaves, seed), fbm(p + vec2(5.2, 1.3), u_octaves, seed + 40u));
    float n = fbm(p + 1.5 * warp, u_octaves, seed + 80u);
    float veins = smoothstep(0.35, 0.65, n);
    return base * mix(vec3(0.7, 0.68, 0.64), vec3(1.15, 1.1, 1.0), veins);
}
vec3 shadow_coord(vec3 n) {
    vec4 s = u_light_matrix * vec4(v_world + n * 0.02, 1.0);
    return s.xyz / s.w * 0.5 + 0.5;
}
// Wide percentage-closer filtering: (2r+1)^2 bilinear depth comparisons.
float visibility_pcf(vec3 n) {
    vec3 s = shadow_coord(n);
    float sum = 0.0;
    int r = u_pcf_radius;
    for (int y = -r; y <= r; ++y)
        for (int x = -r; x <= r; ++x)
            sum += texture(u_shadow_map, vec3(s.xy + 1.5 * u_shadow_texel * vec2(x, y), s.z - 0.0015));
    float taps = float((2 * r + 1) * (2 * r + 1));
    return sum / taps;
}
// Four taps drawn per pixel and frame from the PCF grid (amortized supersampling, Nehab §6):
// an unbiased estimate of visibility_pcf that exponential smoothing averages over frames.
float visibility_jittered(vec3 n) {
    vec3 s = shadow_coord(n);
    float z = s.z - 0.0015;
    uint side = uint(2 * u_pcf_radius + 1);
    float sum = 0.0;
    for (int k = 0; k < 4; ++k) {
        uint h = hash3(uvec3(uvec2(gl_FragCoord.xy), uint(u_frame * 4 + k)));
        vec2 tap = vec2(float(h % side), float((h >> 16) % side)) - float(u_pcf_radius);
        sum += texture(u_shadow_map, vec3(s.xy + 1.5 * u_shadow_texel * tap, z));
    }
    return 0.25 * sum;
}
// The cheap, view-dependent rest, split so that a colour costs a few operations per term:
// colour = albedo * (ambient_and_points + key * visibility) + specular + key_specular * visibility.
struct Lights {
    vec3 diffuse;       // ambient + point lights' diffuse irradiance
    vec3 key;           // key light's irradiance when unshadowed
    vec3 specular;      // point lights' highlights
    vec3 key_specular;  // key light's highlight when unshadowed
};
// Schlick's rational stand-in for pow(x, shininess): one division instead of exp2 and log2.
float lobe(float x) {
    return x / (u_shininess - u_shininess * x + x);
}
Lights gather_lights(vec3 n) {
    Lights L;
    vec3 v = normalize(u_eye - v_world);
    vec3 l = -normalize(u_light_direction);
    float diffuse = max(dot(n, l), 0.0);
    float highlight = diffuse > 0.0 ? lobe(max(dot(n, normalize(l + v)), 0.0)) : 0.0;
    L.diffuse = u_ambient;
    L.key = u_light_color * diffuse;
    L.specular = vec3(0.0);
    L.key_specular = u_light_color * u_specular * highlight;
    for (int i = 0; i < u_point_count; ++i) {
        vec3 d = u_point_position[i] - v_world;
        float d2 = max(dot(d, d), 1e-4);
        vec3 li = d * inversesqrt(d2);
        float ndl = max(dot(n, li), 0.0);
        float spec = ndl > 0.0 ? lobe(max(dot(n, normalize(li + v)), 0.0)) : 0.0;
        L.diffuse += u_point_color[i] / d2 * ndl;
        L.specular += u_point_color[i] / d2 * u_specular * spec;
    }
    return L;
}
vec3 shade(Lights L, vec4 term) {
    return term.rgb * (L.diffuse + L.key * term.a) + L.specular + L.key_specular * term.a;
}
// sRGB encoding within about 1 % (for the change estimate only).
vec3 approximate_display(vec3 linear) {
    vec3 c = clamp(linear, 0.0, 1.0);
    return 1.138 * sqrt(c) - 0.138 * c;
}
vec2 to_pixels(vec4 clip) {  // y down, origin at the top-left corner
    vec2 ndc = clip.xy / clip.w;
    return vec2((ndc.x * 0.5 + 0.5) * u_size.x, (0.5 - ndc.y * 0.5) * u_size.y);
}
// What the cache stores as depth: window depth is affine in screen space but crowds against 1
// in floats; 1/w is affine too, keeps full precision, and a step of a 24-bit Z-buffer is a
// constant step in it (2^-24 (1/near - 1/far)).
float depth_key(vec4 clip) {
    return u_orthographic ? clip.z / clip.w * 0.5 + 0.5 : 1.0 / clip.w;
}
// Reverse reprojection into the previous frame's cache: bilinear depth within epsilon, the same
// object id on every texel that carries bilinear weight.
bool lookup(out vec4 term, out float age, out float gradient) {
    term = vec4(0.0); age = 0.0; gradient = 0.0;
    if (!u_cache_valid || v_previous_clip.w <= 0.0) return false;
    vec3 ndc = v_previous_clip.xyz / v_previous_clip.w;
    vec2 p = (ndc.xy * 0.5 + 0.5) * u_size - 0.5;  // texel space, GL rows
    if (any(lessThan(p, vec2(-0.5))) || any(greaterThan(p, u_size - 0.5))) return false;
    ivec2 last = ivec2(u_size) - 1;
    vec2 f = floor(p);
    vec2 t = p - f;
    ivec2 i0 = clamp(ivec2(f), ivec2(0), last), i1 = clamp(ivec2(f) + 1, ivec2(0), last);
    vec4 m00 = texelFetch(u_cache_meta, i0, 0), m10 = texelFetch(u_cache_meta, ivec2(i1.x, i0.y), 0);
    vec4 m01 = texelFetch(u_cache_meta, ivec2(i0.x, i1.y), 0), m11 = texelFetch(u_cache_meta, i1, 0);
    // Texels that carry bilinear weight must show this object; their oldest entry counts.
    vec4 weight = vec4((1.0 - t.x) * (1.0 - t.y), t.x * (1.0 - t.y), (1.0 - t.x) * t.y, t.x * t.y);
    bvec4 counted = greaterThan(weight, vec4(1.0 / 256.0));
    bvec4 same = equal(vec4(m00.y, m10.y, m01.y, m11.y), vec4(u_id));
    if (any(bvec4(counted.x && !same.x, counted.y && !same.y, counted.z && !same.z, counted.w && !same.w)))
        return false;
    float z = dot(weight, vec4(m00.x, m10.x, m01.x, m11.x));
    if (abs(z - depth_key(v_previous_clip)) > u_epsilon) return false;
    term = texture(u_cache_term, (p + 0.5) / u_size);  // half floats, filtered: bilinear
    vec4 ages = mix(vec4(0.0), vec4(m00.z, m10.z, m01.z, m11.z), vec4(counted));
    vec4 gradients = mix(vec4(-2.0), vec4(m00.w, m10.w, m01.w, m11.w), vec4(counted));
    age = max(max(ages.x, ages.y), max(ages.z, ages.w));
    gradient = max(max(gradients.x, gradients.y), max(gradients.z, gradients.w));
    if (min(min(gradients.x, gradients.y), min(gradients.z, gradients.w)) == -1.0) gradient = -1.0;
    if (u_reuse == 2 && gradient >= 0.0) {  // spatial maximum filter of the gradients
        ivec2 c = clamp(ivec2(floor(p + 0.5)), ivec2(0), last);
        int r = u_filter_radius;
        for (int y = -r; y <= r; ++y)
            for (int x = -r; x <= r; ++x)
                gradient = max(gradient, texelFetch(u_cache_meta, clamp(c + ivec2(x, y), ivec2(0), last), 0).w);
    }
    return true;
}
int refresh_phase() {
    ivec2 px = ivec2(gl_FragCoord.xy);
    if (u_refresh == 0) {
        ivec2 tile = min(px * u_tiles / ivec2(u_size), u_tiles - 1);
        return tile.x + tile.y * u_tiles.x;
    }
    if (u_refresh == 1) return int(hash3(uvec3(uvec2(px / 2), 17u)) % uint(u_period));
    if (u_refresh == 2) return int(hash3(uvec3(uvec2(px / 8), 29u)) % uint(u_period));
    return (px.x + px.y * u_interleave_step) % u_period;
}
void main() {
    vec3 n = dot(v_normal, v_normal) > 0.0 ? normalize(gl_FrontFacing ? v_normal : -v_normal)
                                           : vec3(0.0, 0.0, 1.0);
#if REUSE
    vec4 cached;
    float age, gradient;
    bool hit = lookup(cached, age, gradient);
    bool reshade = !hit;
    if (hit) {
        if (u_reuse == 1) {
            reshade = age + 1.0 >= float(u_period) || (u_frame + refresh_phase()) % u_period == 0;
        } else {
            // The period caps each deadline, staggered per 8x8 block so that caps do not align.
            float cap = float(u_period - int(hash3(uvec3(uvec2(ivec2(gl_FragCoord.xy) / 8), 31u)) %
                                             uint(max(u_period / 2, 1))));
            reshade = age + 1.0 >= cap || gradient < 0.0 || gradient * (age + 1.0) > u_threshold;
        }
    }
    vec4 term = cached;
    float new_gradient = gradient;
#if PASS == 1
    // The hit pass: what reshades is left to the miss pass (stencil 0 there), so that llvmpipe
    // never runs the expensive term for blocks without a reshaded pixel.
    if (reshade) discard;
    Lights L = gather_lights(n);
    if (u_smoothing > 0.0) term.a = mix(term.a, visibility_jittered(n), u_smoothing);
#else
    reshade = true;  // the miss pass sees only pixels the hit pass discarded
    Lights L = gather_lights(n);
    term = vec4(procedural_albedo(), visibility_pcf(n));
    vec3 change = abs(approximate_display(shade(L, term)) - approximate_display(shade(L, cached)));
    new_gradient = hit ? max(change.r, max(change.g, change.b)) / (age + 1.0) : -1.0;
#endif
#else
    Lights L = gather_lights(n);
    vec4 term = vec4(procedural_albedo(), visibility_pcf(n));
#endif
    vec3 color = shade(L, term);

    vec2 motion = vec2(1e30);
    if (v_previous_clip.w > 0.0) motion = to_pixels(v_previous_clip) - to_pixels(v_clip);
    o_color = vec4(color, 1.0);
    o_depth_motion_id = vec4(v_depth, motion, u_id);
    o_normal = vec4(n, 0.0);
#if REUSE
    float new_age = reshade ? 0.0 : age + 1.0;
    o_cache_term = term;
    o_cache_meta = vec4(depth_key(v_clip), u_id, new_age, new_gradient);
#endif
}
)";

}  // namespace reprise::server::shaders
