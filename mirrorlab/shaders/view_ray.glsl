// The world direction from the eye through a fragment, pulled in with
// #include "view_ray.glsl": from the eye for a perspective view, along the view for an
// orthographic one.
uniform vec3 eye_world;      // the viewer's position, world units (perspective)
uniform bool orthographic;
uniform vec3 view_direction; // world, unit (orthographic)

vec3 view_ray(vec3 world_position) {
    return orthographic ? view_direction
                        : safe_normalize(world_position - eye_world, vec3(0.0));
}
