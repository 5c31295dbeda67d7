#version 330
// The paraboloid map, looked up per fragment by the direction of the reflected view ray
// (paraboloid.glsl), corrected for parallax as a live cube map's is where PARALLAX (a #define,
// 0 when not given) says so (direction_map.glsl).
#ifndef PARALLAX
#define PARALLAX 0
#endif
#include "common.glsl"
#include "view_ray.glsl"
#include "parallax.glsl"
#include "paraboloid.glsl"
#include "direction_map.glsl"
