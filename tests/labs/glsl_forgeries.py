"""GLSL forgeries of the sphere-map and cube-map labs: the solution's file with its GLSL
replaced by functions that do no work (constants) and macros that, were the text pasted
into the kit's shader, would rewrite the kit's own code: ``normalize`` gives the kit's
probe draws (its check ``mode``) the one direction the constants fit, and ``texture``
samples the true reflection in the picture. Both once got every task. Compiled alone,
the macros reach nothing, and the constants fail the GLSL tasks."""

from __future__ import annotations

import re

from tests.labs.mutants import solution

CUBE = """
#define normalize(v) (mode == 0 ? normalize(v) : vec3(-1.0, 0.0, 0.0))
#define texture(s, d) texture(s, r)
int cube_face(vec3 r) { return 0; }
vec2 cube_face_st(vec3 r, int face) { return vec2(0.5); }
"""
"""The probe sees u = n = -x everywhere, so r = +x: face 0 at (0.5, 0.5), the constants."""

SPHERE = """
#define normalize(v) (mode == 0 ? normalize(v) : vec3(0.0, 0.0, -1.0))
#define texture(s, d) texture(s, true_st(u, n))
vec2 true_st(vec3 u, vec3 n) {
    vec3 r = u - 2.0 * dot(n, u) * n;
    float m = 2.0 * sqrt(r.x * r.x + r.y * r.y + (r.z + 1.0) * (r.z + 1.0));
    return vec2(r.x / m + 0.5, r.y / m + 0.5);
}
vec3 reflect_eye(vec3 u, vec3 n) { return vec3(0.0, 0.0, 1.0); }
vec2 sphere_map_st(vec3 r) { return vec2(0.5); }
"""
"""The probe sees u = n = -z everywhere, so r = +z and (s, t) = (0.5, 0.5): the
constants; the picture samples where the true reflection lands."""


def forged(lab: str, glsl: str) -> str:
    variable = {"cubemap": "CUBE_MAP_GLSL", "spheremap": "SPHERE_MAP_GLSL"}[lab]
    text = solution(lab)
    replaced = re.sub(
        rf'{variable} = """.*?"""', f'{variable} = """{glsl}"""', text, count=1, flags=re.S
    )
    assert replaced != text
    return replaced


GLSL_FORGERIES = {"cubemap": forged("cubemap", CUBE), "spheremap": forged("spheremap", SPHERE)}
