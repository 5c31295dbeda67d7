"""GLSL forgeries of the sphere-map and cube-map labs: the solution's file with its GLSL
replaced.

- Round one: functions that do no work (constants) and macros that, were the text pasted
  into the kit's shader, would rewrite the kit's own code (``normalize`` giving the kit's
  check draws the one direction the constants fit, ``texture`` sampling the true
  reflection). Compiled alone, the macros reach nothing.
- Issue 44's forged pass 4: GLSL that computes nothing, discards every fragment but 64
  chosen by ``gl_FragCoord`` and returns hard-coded values there. The probe judges every
  input it draws, and a discard is a wrong value.
- Forged pass 5: a ``samplerCube`` hidden in a uniform array of structs named ``ml_...``
  (the checker's namespace) doing the face selection by the GPU's own cube lookup, and a
  second, unused uniform that broke the probe's link so that it never ran. Both names
  are refused before the driver sees them; a probe that cannot run is never a pass.

Each once got every task."""

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


TABLE = "".join(f"    vec4({0.05 * i:.2f}, {0.5 - 0.01 * i:.2f}, 0.7, 0.5),\n" for i in range(64))
HARD_CODED = f"""
const vec4 VALUES[64] = vec4[64](
{TABLE.rstrip().rstrip(",")}
);
int chosen() {{
    ivec2 at = ivec2(gl_FragCoord.xy) - ivec2(100, 120);
    if (at.x < 0 || at.y < 0 || at.x >= 8 || at.y >= 8) discard;
    return at.y * 8 + at.x;
}}
"""
"""Forged pass 4's machinery: 64 fragments of the cone, the rest discarded, a value each."""

SPHERE_64 = (
    HARD_CODED
    + """
vec3 reflect_eye(vec3 u, vec3 n) { return VALUES[chosen()].xyz; }
vec2 sphere_map_st(vec3 r) { return VALUES[chosen()].zw; }
"""
)
CUBE_64 = (
    HARD_CODED
    + """
int cube_face(vec3 r) { return int(VALUES[chosen()].x * 5.0); }
vec2 cube_face_st(vec3 r, int face) { return VALUES[chosen()].yz; }
"""
)
CUBE_SAMPLER = """
struct Faces { samplerCube faces; };
uniform Faces ml_ModelViewMatrixInverse[2];
uniform float mirrorlab_probe_call;
int cube_face(vec3 r) {
    return int(texture(ml_ModelViewMatrixInverse[0].faces, r).r * 5.0 + 0.5);
}
vec2 cube_face_st(vec3 r, int face) {
    return texture(ml_ModelViewMatrixInverse[1].faces, r).gb;
}
"""
"""Forged pass 5: the GPU's own cube lookup picks the face (its picture would carry the
face number), in the checker's namespace; the float beside it clashed with the probe's
old ``int`` of that name, so the probe never linked."""


def forged(lab: str, glsl: str) -> str:
    variable = {"cubemap": "CUBE_MAP_GLSL", "spheremap": "SPHERE_MAP_GLSL"}[lab]
    text = solution(lab)
    replaced = re.sub(
        rf'{variable} = """.*?"""', f'{variable} = """{glsl}"""', text, count=1, flags=re.S
    )
    assert replaced != text
    return replaced


GLSL_FORGERIES = {
    "cubemap": forged("cubemap", CUBE),
    "spheremap": forged("spheremap", SPHERE),
    "cubemap_64_fragments": forged("cubemap", CUBE_64),
    "spheremap_64_fragments": forged("spheremap", SPHERE_64),
    "cubemap_sampler_in_ml_structs": forged("cubemap", CUBE_SAMPLER),
}
"""Each forgery by name (its lab first): the GLSL tasks must fail, with the phrase of
:data:`PHRASES` in task 1's hint."""
PHRASES = {
    "cubemap": "the same value",
    "spheremap": "the same value",
    "cubemap_64_fragments": "wrote no value for",
    "spheremap_64_fragments": "wrote no value for",
    "cubemap_sampler_in_ml_structs": "names beginning with ml_ are the checker's own",
}
