#pragma once
// GLSL ES 3.00 shaders of the G-buffer pass. Vertices arrive posed in world space (current and
// previous instant); the fragment shader writes colour, (depth, motion, id) and the normal.

namespace reprise::server::shaders {

inline constexpr const char* kVertex = R"(#version 300 es
uniform mat4 u_view_projection;           // jittered, for rasterisation
uniform mat4 u_unjittered_view_projection;
uniform mat4 u_view;
uniform mat4 u_previous_view_projection;  // unjittered
layout(location = 0) in vec3 a_position;
layout(location = 1) in vec3 a_previous_position;
layout(location = 2) in vec3 a_normal;
layout(location = 3) in vec2 a_uv;
out vec4 v_clip;
out vec4 v_previous_clip;
out vec3 v_world;
out vec3 v_normal;
out vec2 v_uv;
out float v_depth;
void main() {
    vec4 world = vec4(a_position, 1.0);
    gl_Position = u_view_projection * world;
    v_clip = u_unjittered_view_projection * world;
    v_previous_clip = u_previous_view_projection * vec4(a_previous_position, 1.0);
    v_world = a_position;
    v_normal = a_normal;
    v_uv = a_uv;
    v_depth = -(u_view * world).z;
}
)";

inline constexpr const char* kFragment = R"(#version 300 es
precision highp float;
uniform vec2 u_size;
uniform vec3 u_eye;
uniform vec3 u_light_direction;
uniform vec3 u_light_color;
uniform vec3 u_ambient;
uniform vec4 u_base_color;
uniform bool u_textured;
uniform bool u_lit;
uniform float u_specular;
uniform float u_shininess;
uniform float u_mirror;
uniform float u_id;
uniform sampler2D u_texture;
uniform float u_lod_bias;
in vec4 v_clip;
in vec4 v_previous_clip;
in vec3 v_world;
in vec3 v_normal;
in vec2 v_uv;
in float v_depth;
layout(location = 0) out vec4 o_color;
layout(location = 1) out vec4 o_depth_motion_id;
layout(location = 2) out vec4 o_normal;
vec2 to_pixels(vec4 clip) {  // y down, origin at the top-left corner
    vec2 ndc = clip.xy / clip.w;
    return vec2((ndc.x * 0.5 + 0.5) * u_size.x, (0.5 - ndc.y * 0.5) * u_size.y);
}
// What a mirror reflects: a sky with soft-edged coloured panels around the horizon over a
// far checkered ground, so that a reflection has features to follow.
vec3 environment(vec3 d) {
    vec3 sky = mix(vec3(0.6, 0.72, 0.9), vec3(0.15, 0.3, 0.75), clamp(d.y, 0.0, 1.0));
    float azimuth = atan(d.z, d.x);
    float column = smoothstep(-0.4, 0.4, sin(10.0 * azimuth));
    float band = smoothstep(0.0, 0.1, d.y) * (1.0 - smoothstep(0.5, 0.6, d.y));
    vec3 panel = mix(vec3(0.95, 0.35, 0.1), vec3(0.1, 0.6, 0.3), 0.5 + 0.5 * sin(3.0 * azimuth));
    sky = mix(sky, panel, band * column);
    vec2 g = d.xz / max(-d.y, 0.05);
    float checker = smoothstep(-0.3, 0.3, sin(3.0 * g.x) * sin(3.0 * g.y));
    vec3 ground = mix(vec3(0.08, 0.07, 0.06), vec3(0.7, 0.66, 0.55), checker);
    ground = mix(vec3(0.35, 0.32, 0.28), ground, smoothstep(-0.05, -0.3, d.y));
    return mix(ground, sky, smoothstep(-0.02, 0.02, d.y));
}
void main() {
    vec3 n = dot(v_normal, v_normal) > 0.0 ? normalize(gl_FrontFacing ? v_normal : -v_normal)
                                           : vec3(0.0, 0.0, 1.0);
    vec4 base = u_base_color;
    // llvmpipe takes another filtering path for an explicit bias, even 0: full-resolution renders
    // keep the plain lookup.
    if (u_textured) base *= u_lod_bias != 0.0 ? texture(u_texture, v_uv, u_lod_bias) : texture(u_texture, v_uv);
    vec3 color = base.rgb;
    if (u_lit) {
        vec3 l = -normalize(u_light_direction);
        vec3 v = normalize(u_eye - v_world);
        float diffuse = max(dot(n, l), 0.0);
        float highlight = diffuse > 0.0 ? pow(max(dot(n, normalize(l + v)), 0.0), u_shininess) : 0.0;
        color = base.rgb * (u_ambient + u_light_color * diffuse) + u_light_color * u_specular * highlight;
        if (u_mirror > 0.0) color = mix(color, environment(reflect(-v, n)), u_mirror);
    }
    // Both ends through the same arithmetic, so that nothing moving gives exactly 0.
    // Pixel p samples the unjittered image at p + jitter, which is where `here` lies.
    vec2 motion = vec2(1e30);  // no previous position: behind the previous camera
    if (v_previous_clip.w > 0.0) motion = to_pixels(v_previous_clip) - to_pixels(v_clip);
    o_color = vec4(color, 1.0);
    o_depth_motion_id = vec4(v_depth, motion, u_id);
    o_normal = vec4(n, 0.0);
}
)";

}  // namespace reprise::server::shaders
