#version 330
// Blinn-Newell latitude-longitude map: theta = angle from +z, phi = atan2(ry, rx),
// s = phi / 2 pi wrapped into [0, 1), t = theta / pi (mirrorlab.envmap.latlong_map).
// s jumps from 1 to 0 where phi crosses 0; the screen-space derivative of s is taken
// from phi's analytic gradient instead, which has no jump, so the mipmap level stays
// right along the seam (an implicit-derivative lookup would smear the coarsest level
// over a line of pixels there).
//
// Near the poles (reflections along +z or -z) a row of the map is a small circle of
// directions stretched over the map's whole width: a pixel's footprint spans many
// texels along s but few along t, and an isotropic filter would take its level from the
// long side and blur a blob of the coarsest levels there. So the level is chosen from
// the footprint on the sphere of directions (along s a texel spans sin(theta) of what it
// spans at the equator), as a cube map's is, and up to MAX_TAPS lookups at that level
// are spread along the footprint's long side and averaged: a small anisotropic filter.
#include "common.glsl"
#include "view_ray.glsl"
in vec3 world_position;
in vec3 world_normal;

uniform sampler2D latlong_texture;
uniform int output_mode;  // 0: colour; 1: the lookup coordinates (s, t, 0)
uniform bool seam_safe = true;  // false: let the hardware difference s (a test's control)

out vec4 frag_color;

const float PI = 3.14159265358979;
const int MAX_TAPS = 8;

// d phi for a change dw of the direction w: (x dy - y dx) / (x^2 + y^2), with the
// denominator held away from 0 at the poles (where phi is undefined anyway).
float phi_change(vec3 w, vec3 dw) {
    return (w.x * dw.y - w.y * dw.x) / max(dot(w.xy, w.xy), 1e-6);
}

// The map's colour over a pixel's footprint (uv steps grad_x, grad_y per pixel) at a
// direction rho = sin(theta) from the poles.
vec3 footprint_lookup(vec2 st, vec2 grad_x, vec2 grad_y, float rho) {
    vec2 size = vec2(textureSize(latlong_texture, 0));
    vec2 step_x = grad_x * size;  // texels of level 0 per pixel
    vec2 step_y = grad_y * size;
    // on the sphere: an s-texel at latitude theta is sin(theta) of an equator texel
    vec2 sphere_x = vec2(step_x.x * rho, step_x.y);
    vec2 sphere_y = vec2(step_y.x * rho, step_y.y);
    float level = log2(max(max(length(sphere_x), length(sphere_y)), 1e-8));
    float scale = exp2(max(level, 0.0));
    vec2 major = dot(step_x, step_x) >= dot(step_y, step_y) ? grad_x : grad_y;
    major.x = clamp(major.x, -1.0, 1.0);  // at most once around
    float span = length(major * size) / scale;  // texels of that level the long side spans
    int taps = int(clamp(floor(span + 0.5), 1.0, float(MAX_TAPS)));
    vec3 sum = vec3(0.0);
    for (int k = 0; k < taps; ++k) {
        float along = (float(k) + 0.5) / float(taps) - 0.5;
        sum += textureLod(latlong_texture, st + along * major, level).rgb;
    }
    return sum / float(taps);
}

void main() {
    vec3 u = view_ray(world_position);
    vec3 n = safe_normalize(world_normal, vec3(0.0));
    vec3 w = safe_normalize(u - 2.0 * dot(n, u) * n, vec3(0.0, 0.0, 1.0));
    float rho = length(w.xy);
    float theta = atan(rho, w.z);  // as accurate as acos(rz) can't be near the poles
    float s = 0.0;
    if (rho > 0.0) {
        s = atan(w.y, w.x) / (2.0 * PI);
        s = s < 0.0 ? s + 1.0 : s;
        s = s >= 1.0 ? 0.0 : s;
    }
    float t = clamp(theta / PI, 0.0, 1.0);
    vec3 dwdx = dFdx(w);
    vec3 dwdy = dFdy(w);
    vec2 grad_x = vec2(phi_change(w, dwdx) / (2.0 * PI), dFdx(t));
    vec2 grad_y = vec2(phi_change(w, dwdy) / (2.0 * PI), dFdy(t));
    if (output_mode == 1) {
        frag_color = vec4(s, t, 0.0, 1.0);
    } else if (seam_safe) {
        frag_color = vec4(footprint_lookup(vec2(s, t), grad_x, grad_y, rho), 1.0);
    } else {
        frag_color = vec4(texture(latlong_texture, vec2(s, t)).rgb, 1.0);
    }
}
