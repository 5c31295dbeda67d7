// Parallax-corrected cube-map lookups, pulled in with #include "parallax.glsl" (after
// common.glsl). A cube map captured at capture_center takes everything it saw as
// infinitely far away; these follow the reflected ray r from the surface point origin to
// where the surroundings are, and return the unit direction from capture_center to that
// point. Where there is no such point (origin outside the proxy, behind what the capture
// saw, or at the centre) they return r: the plain lookup. mirrorlab.parallax is the
// numpy reference, with the same thresholds.
const float PARALLEL = 1e-20;   // a ray component this small never reaches its faces
const float AT_CENTER = 1e-6;   // world units: a surface point at the capture centre
const float NO_EXIT = 3.0e38;
const int REFINE_STEPS = 4;    // a distance search's smaller steps within a crossing step

uniform vec3 capture_center;    // world

// Box proxy: the axis-aligned box proxy_min..proxy_max (world), e.g. a room.
uniform vec3 proxy_min;
uniform vec3 proxy_max;

vec3 box_lookup(vec3 origin, vec3 r) {
    bool inside = all(greaterThanEqual(origin, proxy_min))
                  && all(lessThanEqual(origin, proxy_max)) && all(lessThan(proxy_min, proxy_max));
    if (!inside) {
        return r;
    }
    // Distance to the far face along each axis; a ray parallel to a pair of faces never
    // meets them (no division by zero).
    bvec3 moving = greaterThan(abs(r), vec3(PARALLEL));
    vec3 ahead = mix(proxy_min - origin, proxy_max - origin, greaterThan(r, vec3(0.0)));
    vec3 steps = mix(vec3(NO_EXIT), ahead / mix(vec3(1.0), r, moving), moving);
    steps = max(steps, 0.0);
    float leave = min(steps.x, min(steps.y, steps.z));
    return safe_normalize(origin + leave * r - capture_center, r);
}

// Sphere proxy: a sphere of proxy_radius around capture_center.
uniform float proxy_radius;

vec3 sphere_lookup(vec3 origin, vec3 r) {
    vec3 offset = origin - capture_center;
    float q = dot(offset, offset) - proxy_radius * proxy_radius;  // <= 0 inside
    if (!(proxy_radius > 0.0) || q > 0.0) {
        return r;
    }
    float b = dot(offset, r);
    float root = sqrt(max(b * b - q, 0.0));
    // -b + root, written so that neither form subtracts nearly equal numbers
    float leave = b > 0.0 ? -q / (b + root) : root - b;
    return safe_normalize(offset + max(leave, 0.0) * r, r);
}

// Distance search: distance_map holds each texel's depth as the capture's faces saw it
// (90-degree perspective, clip distances capture_depth_range); the ray is searched for
// the point whose distance from the centre meets the stored one. The stored distances
// are a height field seen from the centre: what lies behind a surface is hidden, and a
// ray that passes behind an object (without meeting it) crosses its stored surface too.
// Such a crossing is told from a hit by the depth mismatch left after the secant steps
// (more than thickness, relative): the search goes on past it. Without secant steps
// every crossing is a hit. Where the search accepts no crossing it falls back to the
// plain lookup where the surroundings close the centre in (enclosed), and to the
// background (looked up in background_map, not in the capture, where an object may
// hide it from the centre) where they do not.
uniform samplerCube distance_map;
uniform vec2 capture_depth_range;  // near, far
uniform int search_steps;          // linear steps, at least 1
uniform int secant_steps;          // regula-falsi steps at each crossing
uniform float thickness;           // largest relative depth mismatch of a hit
uniform bool enclosed;             // the surroundings close the capture centre in

// 1 / distance to the captured surface along the unit direction w (0: the background).
float inverse_distance(vec3 w) {
    float depth = textureLod(distance_map, w, 0.0).r;
    if (depth >= 1.0) {
        return 0.0;
    }
    float n = capture_depth_range.x;
    float f = capture_depth_range.y;
    float major = max(abs(w.x), max(abs(w.y), abs(w.z)));
    return major * (f + n - (2.0 * depth - 1.0) * (f - n)) / (2.0 * f * n);
}

// The point of the ray at parameter t (0: origin, 1: infinitely far) is seen from the
// centre along look = (1 - t) offset + t size r, at the distance |look| / (1 - t). Returns
// H = s (1 - t) / |look| - s w (> 0 while the point is in front of the captured surface)
// and, in mismatch, |point| w - 1 (the point's depth behind the surface, relative).
float in_front(vec3 offset, float size, vec3 r, float t, out float mismatch) {
    vec3 look = (1.0 - t) * offset + (t * size) * r;
    float len = max(length(look), AT_CENTER * size);
    vec3 w = length(look) > AT_CENTER * size ? look / length(look) : r;
    float inverse = inverse_distance(w);
    mismatch = t < 1.0 ? len * inverse / (1.0 - t) - 1.0 : (inverse > 0.0 ? NO_EXIT : 0.0);
    return size * (1.0 - t) / len - size * inverse;
}

// Where H, positive at low and not at high, is zero if it is linear between them;
// written from high, so that H(high) = 0 gives high exactly.
float secant(float low, float h_low, float high, float h_high) {
    return high + (high - low) * h_high / (h_low - h_high);  // h_low > 0 >= h_high
}

// The lookup direction, and in background whether it is to be looked up in the
// background rather than the capture.
vec3 distance_lookup(vec3 origin, vec3 r, out bool background) {
    background = false;
    vec3 offset = origin - capture_center;
    float size = length(offset);
    if (!(size > AT_CENTER)) {
        return r;  // at the centre the plain lookup is exact
    }
    float mismatch;
    float h_before = in_front(offset, size, r, 0.0, mismatch);
    if (!(h_before > 0.0)) {
        return r;  // the origin is behind what the capture saw
    }
    float t_before = 0.0;
    for (int k = 1; k <= search_steps; ++k) {
        float t_after = float(k) / float(search_steps);
        float h_after = in_front(offset, size, r, t_after, mismatch);
        if (h_after <= 0.0) {
            // A step that ends behind the stored surface may hide more than one
            // crossing: the ray passing behind an object, coming out past its silhouette
            // and meeting the wall behind it, all within one step. Such a step is
            // looked at again in REFINE_STEPS smaller ones, and each crossing found there
            // (in front, then behind) is narrowed and judged in turn, the first accepted
            // taken.
            float sub_before = t_before;
            float sh_before = h_before;
            for (int j = 1; j <= REFINE_STEPS; ++j) {
                float sub_after = j == REFINE_STEPS ? t_after
                    : mix(t_before, t_after, float(j) / float(REFINE_STEPS));
                float sh_after = j == REFINE_STEPS ? h_after
                    : in_front(offset, size, r, sub_after, mismatch);
                if (sh_before > 0.0 && sh_after <= 0.0) {
                    float low = sub_before;
                    float h_low = sh_before;
                    float high = sub_after;
                    float h_high = sh_after;
                    for (int i = 0; i < secant_steps; ++i) {
                        float t = secant(low, h_low, high, h_high);
                        float h = in_front(offset, size, r, t, mismatch);
                        if (h <= 0.0) {
                            high = t;
                            h_high = h;
                        } else {
                            low = t;
                            h_low = h;
                        }
                    }
                    // A hit short of infinity (t = 1 exactly where the ray meets nothing
                    // but the background there). Without secant steps there is no
                    // refined point to judge: every such crossing is a hit (the
                    // height-field assumption).
                    float t = secant(low, h_low, high, h_high);
                    if (t < 1.0 && (secant_steps == 0 || abs(mismatch) <= thickness)) {
                        return safe_normalize((1.0 - t) * offset + (t * size) * r, r);
                    }
                }
                sub_before = sub_after;
                sh_before = sh_after;
            }
        }
        t_before = t_after;
        h_before = h_after;
    }
    // No crossing the search could accept: the ray passed behind what the capture saw
    // (or met what it could not see). Closed in (a room), it meets a surface hidden from
    // the centre: the plain lookup, in the capture, shows the surroundings that way
    // (the background map where the capture saw nothing either). Under an open sky it
    // most likely leaves for the background, which the plain lookup would show behind
    // a ghost of whatever stands along r seen from the centre.
    background = !enclosed || inverse_distance(r) == 0.0;
    return r;
}
