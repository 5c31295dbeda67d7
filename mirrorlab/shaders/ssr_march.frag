#version 330
// Screen-space reflections: the reflected ray of each visible reflector fragment
// marched through the view's own depth buffer (frame_depth, copied after the view's
// objects and the reflector's probe were drawn), as mirrorlab.screen_space.march does
// it in numpy: the ray clipped to the view's volume in clip space, then followed along
// its screen line pixel by pixel (McGuire and Mara, JCGT 2014), its eye-space depth
// carried perspective-correctly; a sample behind the surface there by more than the
// thickness ends it as a miss, one that meets the surface is narrowed by halvings.
// Writes the hit's colour (location 0) and what happened (location 1: weight, reason,
// hit pixel x, y). The reflector's own pixels have alpha 0 in frame_color.
#include "common.glsl"
in vec3 world_position;
in vec3 world_normal;
in vec3 eye_position;
in vec3 eye_normal;
in vec2 vertex_sphere_st;

uniform sampler2D frame_color;
uniform sampler2D frame_depth;
uniform sampler2D pyramid;  // the frame's nearest depths, level k over 2^k pixels a side
uniform int top_level;      // its last level used (0: the plain DDA)
uniform mat4 projection;
uniform vec4 depth_row_z;   // rows 2 and 3 of the inverse projection: window depth to eye z
uniform vec4 depth_row_w;
uniform vec2 viewport;      // the view's size in pixels
uniform vec4 screen;        // the drawn rectangle: x0, y0, x1, y1 (pixels)
uniform bool orthographic;
uniform float stride;
uniform int steps;
uniform float thickness;
uniform float max_distance; // 0: until the ray leaves the view
uniform int refine;
uniform float edge_fade;
uniform float end_fade;
// 0: march; 1: the ray's eye-space origin, 2: its direction (for checks), into location 1
uniform int output_mode;

layout(location = 0) out vec4 hit_color;
layout(location = 1) out vec4 hit_info;

const int HIT = 1, SCREEN = 2, DISTANCE = 3, STEPS = 4, BEHIND = 5, THICKNESS = 6, OWN = 7;
const float FAR_AWAY = 1e30;
const float DEPTH_SLACK = 1.0 / 1048576.0;  // a stored 24-bit depth against the fragment's

float k0, k1, qz0, qz1;
vec2 s0, span;

float ray_depth(float s) {
    return -(qz0 + s * (qz1 - qz0)) / max(k0 + s * (k1 - k0), 1e-30);
}

ivec2 pixel_at(float s) {
    vec2 p = floor(s0 + s * span);
    return ivec2(clamp(p, screen.xy, screen.zw - 1.0));
}

// The eye distance of the surface at pixel p; empty where nothing was drawn (infinite).
float surface_depth(ivec2 p, out bool empty, out bool mine) {
    float z = texelFetch(frame_depth, p, 0).r;
    mine = texelFetch(frame_color, p, 0).a < 0.5;
    empty = z >= 1.0;
    vec4 ndc = vec4((vec2(p) + 0.5) * 2.0 / viewport - 1.0, 2.0 * z - 1.0, 1.0);
    float w = dot(depth_row_w, ndc);
    float distance = -dot(depth_row_z, ndc) / (abs(w) < 1e-30 ? (w < 0.0 ? -1e-30 : 1e-30) : w);
    return empty ? FAR_AWAY : distance;
}

// The surface's eye distance at a window position: the inverse depths of the four pixel
// centres around it interpolated bilinearly (exact on a plane), over those that show a
// surface (not nothing, not the reflector's own); FAR_AWAY where none does.
float surface_between(vec2 point) {
    vec2 corner = floor(point - 0.5);
    vec2 fraction = point - 0.5 - corner;
    float inverse = 0.0;
    float weights = 0.0;
    for (int k = 0; k < 4; ++k) {
        vec2 offset = vec2(float(k & 1), float(k >> 1));
        ivec2 p = ivec2(clamp(corner + offset, screen.xy, screen.zw - 1.0));
        bool empty, mine;
        float distance = surface_depth(p, empty, mine);
        vec2 share = mix(1.0 - fraction, fraction, offset);
        bool solid = !empty && !mine;
        inverse += solid ? share.x * share.y / distance : 0.0;
        weights += solid ? share.x * share.y : 0.0;
    }
    inverse /= max(weights, 1e-30);
    return inverse > 1e-30 ? 1.0 / inverse : FAR_AWAY;
}

// How far along a ray a clip-space bound value + t * rate >= 0 holds (FAR_AWAY: always;
// a rate nearer 0 than -1e-30 never ends it, and no division overflows).
float leave(float value, float rate) {
    return rate < -1e-30 ? min(max(value, 0.0) / -rate, FAR_AWAY) : FAR_AWAY;
}

float smooth_ramp(float x) {
    return smoothstep(0.0, 1.0, x);
}

void main() {
    ivec2 here = ivec2(gl_FragCoord.xy);
    // Only the fragments the view shows: the probe's draw left their depth and marked
    // them with alpha 0; anything nearer won the depth test there.
    if (texelFetch(frame_color, here, 0).a >= 0.5
            || gl_FragCoord.z > texelFetch(frame_depth, here, 0).r + DEPTH_SLACK) {
        discard;
    }
    vec3 origin = eye_position;
    vec3 incoming = orthographic ? vec3(0.0, 0.0, -1.0) : safe_normalize(origin, vec3(0.0));
    vec3 n = safe_normalize(eye_normal, vec3(0.0));
    n = dot(n, incoming) > 0.0 ? -n : n;  // reflect about the side the ray comes from
    vec3 r = safe_normalize(incoming - 2.0 * dot(n, incoming) * n, vec3(1.0, 0.0, 0.0));
    hit_color = vec4(0.0);
    if (output_mode == 1) {
        hit_info = vec4(origin, 1.0);
        return;
    }
    if (output_mode == 2) {
        hit_info = vec4(r, 1.0);
        return;
    }

    // the part of the ray within the drawn rectangle and between the near and far planes
    vec4 h0 = projection * vec4(origin, 1.0);
    vec4 hd = projection * vec4(r, 0.0);
    vec2 low = 2.0 * screen.xy / viewport - 1.0;
    vec2 high = 2.0 * screen.zw / viewport - 1.0;
    float end = leave(h0.x - low.x * h0.w, hd.x - low.x * hd.w);
    end = min(end, leave(high.x * h0.w - h0.x, high.x * hd.w - hd.x));
    end = min(end, leave(h0.y - low.y * h0.w, hd.y - low.y * hd.w));
    end = min(end, leave(high.y * h0.w - h0.y, high.y * hd.w - hd.y));
    end = min(end, leave(h0.z + h0.w, hd.z + hd.w));
    end = min(end, leave(h0.w - h0.z, hd.w - hd.z));
    float limit = max_distance > 0.0 ? max_distance : FAR_AWAY;
    int end_reason = end <= limit ? SCREEN : DISTANCE;
    end = min(end, limit);

    vec3 far_end = origin + r * end;
    vec4 h1 = projection * vec4(far_end, 1.0);
    k0 = 1.0 / max(h0.w, 1e-30);
    k1 = 1.0 / max(h1.w, 1e-30);
    s0 = (h0.xy * k0 + 1.0) * 0.5 * viewport;
    vec2 s1 = (h1.xy * k1 + 1.0) * 0.5 * viewport;
    span = s1 - s0;
    qz0 = origin.z * k0;
    qz1 = far_end.z * k1;
    // the ray's window depth, which changes linearly along its screen line (both it and
    // the screen position are ratios over the same w): a sample it is in front of there
    // is passed over without a look at eye depths
    float wz0 = h0.z * k0 * 0.5 + 0.5;
    float dwz = h1.z * k1 * 0.5 + 0.5 - wz0;
    float pixels_along = max(abs(span.x), abs(span.y));
    float step_size = stride / max(pixels_along, 1e-30);

    int reason = 0;
    float hit_s = 0.0;
    int taken = 0;
    if (pixels_along < 0.5) {
        // along the line of sight: towards the eye it leaves the view, away from it it
        // runs behind its own surface
        reason = ray_depth(1.0) < ray_depth(0.0) ? SCREEN : OWN;
    } else {
        float previous_s = 0.0;
        float pixel_step = 1.0 / max(pixels_along, 1e-30);
        float half_step = 0.5 * step_size;
        int last_sample = min(steps, int(floor(1.0 / step_size)));  // the last within the ray
        // The samples are the DDA's, one by one at level 0; above it, the nearest-depth
        // pyramid passes over every sample of a block at once where the ray stays in front
        // of the block's nearest depth (each would pass alone): the same samples decided,
        // the same way, fewer of them looked at.
        int level = 0;
        int i = 1;
        for (int guard = 0; guard < 3 * steps + 64 && i <= steps; ++guard) {
            float s = float(i) * step_size;
            if (s > 1.0) {
                reason = end_reason;
                break;
            }
            ivec2 p = pixel_at(s);
            if (level > 0) {
                // the level's size, as GL sizes a mipmap (llvmpipe's textureSize takes one
                // lane's level for all, so it is not asked)
                ivec2 size = max(ivec2(viewport) >> level, ivec2(1));
                ivec2 block = min(p >> level, size - 1);
                // a block's pixels; the last of a row or column reaches the view's end
                vec2 low_corner = vec2(block << level);
                vec2 high_corner = vec2(
                    block.x == size.x - 1 ? int(viewport.x) : (block.x + 1) << level,
                    block.y == size.y - 1 ? int(viewport.y) : (block.y + 1) << level);
                vec2 out_x = vec2(
                    span.x > 0.0 ? (high_corner.x - s0.x) / span.x
                                 : (span.x < 0.0 ? (low_corner.x - s0.x) / span.x : FAR_AWAY),
                    span.y > 0.0 ? (high_corner.y - s0.y) / span.y
                                 : (span.y < 0.0 ? (low_corner.y - s0.y) / span.y : FAR_AWAY));
                float exit_s = min(out_x.x, out_x.y);
                // the samples short of the block's edge (by a thousandth of a step)
                int inside = min(int(floor(min(exit_s, 2.0) / step_size - 1e-3)), last_sample);
                if (inside >= i) {
                    float nearest = texelFetch(pyramid, block, level).r;
                    float skipped_end = min(float(inside) * step_size + half_step, 1.0);
                    float farthest = max(wz0 + max(s - half_step, 0.0) * dwz, wz0 + skipped_end * dwz);
                    if (nearest >= 1.0 || farthest < nearest) {
                        taken = inside;
                        previous_s = float(inside) * step_size;
                        i = inside + 1;
                        level = min(level + 1, top_level);
                        continue;
                    }
                }
                level -= 1;
                continue;
            }
            taken = i;
            float start_s = max(s - half_step, 0.0), end_s = min(s + half_step, 1.0);
            float stored = texelFetch(frame_depth, p, 0).r;
            if (stored >= 1.0 || max(wz0 + start_s * dwz, wz0 + end_s * dwz) < stored) {
                previous_s = s;  // nothing drawn there, or the ray in front of it
                i += 1;
                level = min(1, top_level);
                continue;
            }
            float a = ray_depth(start_s);
            float b = ray_depth(end_s);
            float near = min(a, b), far = max(a, b);
            bool empty, mine;
            float seen = surface_depth(p, empty, mine);
            float thick = thickness * seen;
            bool reaches = !empty && far >= seen;
            bool behind_all = reaches && near > seen;  // the whole step behind the surface
            bool within = near <= seen + thick;
            bool continues = false;
            if (behind_all) {
                // the surface under the last sample and the pixel before it along the
                // line, carried on to this one (a plane's inverse depth is linear across
                // the screen): where the surface here continues it, the ray went through
                // that one surface between the two samples
                bool e1, m1, e2, m2;
                float last = surface_depth(pixel_at(previous_s), e1, m1);
                float before = surface_depth(pixel_at(max(previous_s - pixel_step, 0.0)), e2, m2);
                float predicted = 1.0 / last + (1.0 / last - 1.0 / before) * (s - previous_s) / pixel_step;
                float expected = !e1 && !e2 && predicted > 1e-30 ? 1.0 / predicted : FAR_AWAY;
                continues = abs(seen - expected) <= thick;
                if (mine ? !within : !(continues && within)) {
                    reason = mine ? OWN : (continues ? THICKNESS : BEHIND);
                    break;
                }
            }
            if (reaches && !mine) {
                reason = HIT;
                float low_s = previous_s;
                float high_s = min(s + half_step, 1.0);
                for (int j = 0; j < refine; ++j) {
                    float middle = 0.5 * (low_s + high_s);
                    bool crossed = ray_depth(middle) >= surface_between(s0 + middle * span);
                    high_s = crossed ? middle : high_s;
                    low_s = crossed ? low_s : middle;
                }
                hit_s = refine > 0 ? 0.5 * (low_s + high_s) : high_s;
                break;
            }
            previous_s = s;
            i += 1;
        }
        if (reason == 0) {
            reason = STEPS;
        }
    }
    if (reason != HIT) {
        hit_info = vec4(0.0, float(reason), 0.0, 0.0);
        return;
    }
    // where the ray crosses the surface, kept within the drawn pixels' centres; its
    // colour is read there bilinearly
    vec2 centre = clamp(s0 + hit_s * span, screen.xy + 0.5, screen.zw - 0.5);
    float edge = min(min(centre.x - screen.x, screen.z - centre.x),
                     min(centre.y - screen.y, screen.w - centre.y));
    float fade_width = edge_fade * min(viewport.x, viewport.y);
    float weight = fade_width > 0.0 ? smooth_ramp(edge / fade_width) : 1.0;
    weight *= smooth_ramp(float(steps - taken + 1) / (end_fade * float(steps)));
    if (max_distance > 0.0) {
        weight *= smooth_ramp((1.0 - hit_s * end / max_distance) / end_fade);
    }
    hit_color = vec4(texture(frame_color, centre / viewport).rgb, 1.0);
    hit_info = vec4(weight, float(HIT), centre);
}
