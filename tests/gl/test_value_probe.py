"""The value probe (:mod:`mirrorlab.labs.trusted.probe`): the reference solutions' GLSL,
evaluated on the probe's chosen inputs through a probe main of the checker's own, gives
the numpy references (within the probe's stated tolerance, 1e-3; float32 on the GPU);
each known slip, written in GLSL, is named by its values, and two slips that give the same
numbers on unit vectors are told apart."""

from __future__ import annotations

import re

import numpy as np
import pytest

from mirrorlab.envmap import cube_map, reflect, sphere_map
from mirrorlab.labs import find_lab
from mirrorlab.labs.trusted import probe
from tests.labs.mutants import solution

KIT = {"spheremap": "kit_sphere.frag", "cubemap": "kit_cube.frag"}
VARIABLE = {"spheremap": "SPHERE_MAP_GLSL", "cubemap": "CUBE_MAP_GLSL"}


def glsl(lab: str) -> str:
    found = re.search(rf'{VARIABLE[lab]} = """(.*?)"""', solution(lab), re.S)
    assert found is not None
    return found.group(1)


def run(registry, lab: str, text: str) -> dict[str, np.ndarray]:
    return probe.run_probe(
        KIT[lab], text, find_lab(lab).module("trusted").PROBE_FUNCTIONS, registry
    )


def test_solutions_give_the_numpy_references(registry):
    sphere = run(registry, "spheremap", glsl("spheremap"))
    u, n = probe.INPUTS["reflect_eye"]
    assert np.abs(sphere["reflect_eye"][:, :3] - reflect(u, n)).max() <= 1e-5
    r = probe.SPHERE_R
    unit = r[:16]  # the unit inputs: the solution's formula is envmap.sphere_map there
    assert np.abs(sphere["sphere_map_st"][:16, :2] - np.stack(sphere_map(unit), -1)).max() <= 1e-5
    # on every input: Hoff's formula as written (it takes r to be unit length)
    assert np.abs(sphere["sphere_map_st"][:, :2] - probe._hoff(r)).max() <= 1e-5
    cube = run(registry, "cubemap", glsl("cubemap"))
    _, s, t = cube_map(probe.CUBE_R)
    assert np.abs(cube["cube_face_st"][:, :2] - np.stack([s, t], -1)).max() <= 1e-5
    assert probe.slip("reflect_eye", sphere["reflect_eye"]) == "right"
    assert probe.slip("sphere_map_st", sphere["sphere_map_st"]) == "right"
    assert probe.slip("cube_face_st", cube["cube_face_st"]) == "right"
    assert np.array_equal(cube["cube_face"][:, 0], probe.CUBE_FACE)
    assert probe.slip("cube_face", cube["cube_face"]) == "right"
    assert probe.slip_per_face(cube["cube_face_st"]) == {}


SPHERE_SLIPS = {
    "clamped": ("u - 2.0 * dot(n, u) * n", "u - 2.0 * max(dot(n, u), 0.0) * n"),
    "abs_dot": ("u - 2.0 * dot(n, u) * n", "u - 2.0 * abs(dot(n, u)) * n"),
    "sign": ("u - 2.0 * dot(n, u) * n", "-(u - 2.0 * dot(n, u) * n)"),
    "unnormalised": (
        "    return vec2(r.x / m + 0.5, r.y / m + 0.5);",
        "    vec3 h = r + vec3(0.0, 0.0, 1.0);\n    return h.xy / 2.0 + 0.5;",
    ),
    "no_plus_one": ("(r.z + 1.0) * (r.z + 1.0)", "r.z * r.z"),
    "minus_one": ("(r.z + 1.0) * (r.z + 1.0)", "(r.z - 1.0) * (r.z - 1.0)"),
    "no_half": ("vec2(r.x / m + 0.5, r.y / m + 0.5)", "vec2(r.x / m + 1/2, r.y / m + 1/2)"),
    "swap": ("vec2(r.x / m + 0.5, r.y / m + 0.5)", "vec2(r.y / m + 0.5, r.x / m + 0.5)"),
}


@pytest.mark.parametrize("name", sorted(SPHERE_SLIPS))
def test_sphere_slips_are_named_by_value(registry, name):
    old, new = SPHERE_SLIPS[name]
    text = glsl("spheremap")
    assert old in text
    values = run(registry, "spheremap", text.replace(old, new))
    function = "reflect_eye" if "dot" in old or "u -" in old else "sphere_map_st"
    assert probe.slip(function, values[function]) == name


CUBE = "if (face == 2) { sc = r.x; tc = r.z; ma = abs(r.y); }"


@pytest.mark.parametrize(
    "old,new,whole,faces",
    [
        (
            "(sc / ma + 1.0) / 2.0, (tc / ma + 1.0) / 2.0",
            "(tc / ma + 1.0) / 2.0, (sc / ma + 1.0) / 2.0",
            "swap",
            {},
        ),
        (
            "return vec2((sc / ma + 1.0) / 2.0, (tc / ma + 1.0) / 2.0);",
            "return vec2(1/2 * (sc / ma + 1.0), 1/2 * (tc / ma + 1.0));",
            "zero",
            {},
        ),
        (
            "ma = abs(r.x); }\n    else if (face == 2)",
            "ma = r.x; }\n    else if (face == 2)",
            "",
            {1: "signed_major"},
        ),
        (CUBE, "if (face == 2) { sc = r.z; tc = r.x; ma = abs(r.y); }", "", {2: "swap"}),
        (
            "(sc / ma + 1.0) / 2.0, (tc / ma + 1.0) / 2.0",
            "(sc / length(r) + 1.0) / 2.0, (tc / length(r) + 1.0) / 2.0",
            "length",
            {},
        ),
    ],
)
def test_cube_slips_are_named_by_value_per_face(registry, old, new, whole, faces):
    text = glsl("cubemap")
    assert old in text
    values = run(registry, "cubemap", text.replace(old, new))["cube_face_st"]
    assert probe.slip("cube_face_st", values) == (whole or "")
    if not whole:
        assert probe.slip_per_face(values) == faces


def test_the_probe_runs_on_a_core_context():
    """The probe's own shaders use no compatibility built-in: in macOS's 4.1 core context
    (Mesa's overrides, as tests/labs/test_core_profile.py) the solutions' functions give
    the right formulas and a slip is still named."""
    import os
    import subprocess
    import sys

    from tests import MACOS_CONTEXT

    script = (
        "import re, sys\n"
        "from mirrorlab.gl.context import offscreen_context\n"
        "from mirrorlab.gl.opengl import GL\n"
        "from mirrorlab.labs import find_lab\n"
        "from mirrorlab.labs.trusted import probe\n"
        "from tests.labs.mutants import solution\n"
        "with offscreen_context() as context:\n"
        "    print('profile', int(GL.glGetIntegerv(GL.GL_CONTEXT_PROFILE_MASK)))\n"
        "    for lab, variable, kit in (('spheremap', 'SPHERE_MAP_GLSL', 'kit_sphere.frag'),\n"
        "                               ('cubemap', 'CUBE_MAP_GLSL', 'kit_cube.frag')):\n"
        '        text = re.search(variable + \' = """(.*?)"""\', solution(lab), re.S)[1]\n'
        "        for name, old, new in (('right', 'XX', 'XX'),\n"
        "                               ('swap', '(sc / ma + 1.0) / 2.0, (tc / ma + 1.0) / 2.0',\n"
        "                                '(tc / ma + 1.0) / 2.0, (sc / ma + 1.0) / 2.0'),\n"
        "                               ('clamped', '2.0 * dot(n, u)',\n"
        "                                '2.0 * max(dot(n, u), 0.0)')):\n"
        "            if old not in text and old != 'XX':\n"
        "                continue\n"
        "            values = probe.run_probe(kit, text.replace(old, new),\n"
        "                                     find_lab(lab).module('trusted').PROBE_FUNCTIONS,\n"
        "                                     context.resources)\n"
        "            print(lab, name, *(probe.slip(f, v) for f, v in values.items()))\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", script],
        capture_output=True,
        text=True,
        env={**os.environ, **MACOS_CONTEXT},
        timeout=300,
    )
    assert done.returncode == 0, done.stderr[-2000:]
    lines = done.stdout.splitlines()
    assert lines[0] == "profile 1"  # GL_CONTEXT_CORE_PROFILE_BIT
    assert lines[1:] == [
        "spheremap right right right",
        "spheremap clamped clamped right",
        "cubemap right right right",
        "cubemap swap right swap",
    ]


@pytest.mark.parametrize(
    "old,new,name",
    [
        ("    vec3 a = abs(r);", "    vec3 a = r;", "signed"),
        ("return r.x >= 0.0 ? 0 : 1;", "return r.x >= 0.0 ? 1 : 0;", ""),
    ],
)
def test_face_slips_are_named_by_value(registry, old, new, name):
    text = glsl("cubemap")
    assert old in text
    values = run(registry, "cubemap", text.replace(old, new))["cube_face"]
    assert probe.slip("cube_face", values) == name
    for right, wrong in (
        (" ? 0 : 1;", " ? 1 : 0;"),
        (" ? 2 : 3;", " ? 3 : 2;"),
        (" ? 4 : 5;", " ? 5 : 4;"),
    ):
        assert right in text
        text = text.replace(right, wrong)
    values = run(registry, "cubemap", text)["cube_face"]
    assert probe.slip("cube_face", values) == "opposite"
