"""The value probe on the GPU (mirrorlab/labs/trusted/probe.py): the reference solutions'
GLSL gives the formulas' values (and mirrorlab.envmap's, an implementation of its own) on
every input a seed draws; each GLSL mistake of the issue is named by the variant its
values follow; shaders written against the probe (discards chosen by gl_FragCoord,
constants, a probe told by its coordinates, NaN, early returns) fail; the probe sets all
it reads whatever the context holds; it behaves the same in the simulated macOS core
context; a fuzz of GLSL declarations ends in values or one line; and through the
compiling process, a loop that never ends costs the file, not the checker."""

from __future__ import annotations

import os
import re
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mirrorlab.envmap import cube_map, reflect, sphere_map
from mirrorlab.gl.opengl import GL
from mirrorlab.labs.trusted import glslcheck, probe
from mirrorlab.labs.trusted.judging import glsl_body
from mirrorlab.labs.trusted.session import StudentShaderError
from tests.gl.conftest import module_context
from tests.labs.mutants import solution

gl_context = pytest.fixture(scope="module", name="gl_context")(module_context)
KIT = {"spheremap": "kit_sphere.frag", "cubemap": "kit_cube.frag"}
VARIABLE = {"spheremap": "SPHERE_MAP_GLSL", "cubemap": "CUBE_MAP_GLSL"}


def glsl(lab: str) -> str:
    found = re.search(rf'{VARIABLE[lab]} = """(.*?)"""', solution(lab), re.S)
    assert found is not None
    return found.group(1)


def judged(registry, lab: str, text: str, seed: int = 11) -> dict[str, tuple[bool, str]]:
    """Each function of ``lab`` in ``text``, probed on ``seed``'s inputs: (passed, hint)."""
    functions = probe.lab_functions(lab)
    drawn = probe.draw_all(functions, seed)
    found = probe.evaluate(
        KIT[lab],
        text,
        VARIABLE[lab],
        {n: list(d.values.values()) for n, d in drawn.items()},
        registry,
    )
    verdicts = {}
    for function in functions:
        d = drawn[function.name]
        values = found[function.name].astype(np.float64)
        p = probe.Probed(
            function,
            {k: v.astype(np.float64) for k, v in d.values.items()},
            values,
            values[:, 3] == 1.0,
            d.block.astype(np.int64),
            d.blocks,
        )
        ok = probe.right_rows(p)
        verdicts[function.name] = (
            bool(ok.all()),
            "" if ok.all() else probe.name_mistake(p, ok, glsl_body(text, function.name)),
        )
    return verdicts


@pytest.mark.parametrize("seed", [1, 2**62 + 5])
def test_solutions_give_every_value_of_the_formulas(registry, seed):
    for lab in KIT:
        assert all(passed for passed, _ in judged(registry, lab, glsl(lab), seed).values())
    # against mirrorlab's own implementation, on the probe's own inputs
    functions = probe.lab_functions("spheremap")
    drawn = probe.draw_all(functions, seed)
    found = probe.evaluate(
        KIT["spheremap"],
        glsl("spheremap"),
        "SPHERE_MAP_GLSL",
        {n: list(d.values.values()) for n, d in drawn.items()},
        registry,
    )
    u, n = (drawn["reflect_eye"].values[k].astype(np.float64) for k in "un")
    assert np.abs(found["reflect_eye"][:, :3] - reflect(u, n)).max() < 1e-5
    r = drawn["sphere_map_st"].values["r"].astype(np.float64)
    exact = np.array([drawn["sphere_map_st"].blocks[b][1] for b in drawn["sphere_map_st"].block])
    on = (exact == probe.EXACT) & (np.abs(np.linalg.norm(r, axis=-1) - 1) < 1e-6)
    got = found["sphere_map_st"][on, :2]
    assert np.abs(got - np.stack(sphere_map(r[on]), -1)).max() < probe.TOLERANCE / 10
    functions = probe.lab_functions("cubemap")
    drawn = probe.draw_all(functions, seed)
    found = probe.evaluate(
        KIT["cubemap"],
        glsl("cubemap"),
        "CUBE_MAP_GLSL",
        {n: list(d.values.values()) for n, d in drawn.items()},
        registry,
    )
    r = drawn["cube_face_st"].values["r"].astype(np.float64)
    face, s, t = cube_map(r)
    own = drawn["cube_face_st"].values["face"][:, 0] == face
    assert np.abs(found["cube_face_st"][own, :2] - np.stack([s, t], -1)[own]).max() < 1e-5


SOLUTION_REFLECT = "return u - 2.0 * dot(n, u) * n;"
M = "2.0 * sqrt(r.x * r.x + r.y * r.y + (r.z + 1.0) * (r.z + 1.0))"
ST = "vec2(r.x / m + 0.5, r.y / m + 0.5)"
CUBE_ST = "vec2((sc / ma + 1.0) / 2.0, (tc / ma + 1.0) / 2.0)"
MISTAKES = [
    # (lab, function, old, new, a phrase of the hint): the list, each by name
    (
        "spheremap",
        "reflect_eye",
        SOLUTION_REFLECT,
        "return u - 2.0 * dot(n, u) * u;",
        "u where the formula has n",
    ),
    (
        "spheremap",
        "reflect_eye",
        SOLUTION_REFLECT,
        "return u + 2.0 * dot(n, u) * n;",
        "the sign of 2 (n.u) n flipped",
    ),
    ("spheremap", "reflect_eye", SOLUTION_REFLECT, "return u - 4.0 * dot(n, u) * n;", "2 doubled"),
    ("spheremap", "reflect_eye", SOLUTION_REFLECT, "return u - 2.0 * n;", "the factor n.u missing"),
    (
        "spheremap",
        "reflect_eye",
        SOLUTION_REFLECT,
        "return u - 2.0 * dot(n, u) / n;",
        "below the line",
    ),
    (
        "spheremap",
        "reflect_eye",
        SOLUTION_REFLECT,
        "return normalize(u - dot(n, u) * n);",
        "gives NaN or infinity for u = ",
    ),
    (
        "spheremap",
        "reflect_eye",
        SOLUTION_REFLECT,
        "return u - 2.0 * dot(n, u) * n + 0.1 * u.yzx;",
        "a mistake the checker does not know",
    ),
    ("spheremap", "sphere_map_st", M, M.replace("sqrt(", "("), "without its square root"),
    (
        "spheremap",
        "sphere_map_st",
        ST,
        "vec2(0.5 * r.x / m + 0.5, 0.5 * r.y / m + 0.5)",
        "1/2 applied twice",
    ),
    (
        "spheremap",
        "sphere_map_st",
        ST,
        "vec2((r.x / m + 1.0) / 2.0, (r.y / m + 1.0) / 2.0)",
        "1/2 applied twice",
    ),
    (
        "spheremap",
        "sphere_map_st",
        "(r.z + 1.0) * (r.z + 1.0)",
        "r.z + 1.0 * r.z + 1.0",
        "without its parentheses",
    ),
    (
        "spheremap",
        "sphere_map_st",
        "(r.z + 1.0) * (r.z + 1.0)",
        "(r.z * r.z + 1.0)",
        "only rz squared",
    ),
    (
        "spheremap",
        "sphere_map_st",
        ST,
        "vec2(r.x / m + 0.5, r.x / m + 0.5)",
        "rx where the formula has ry",
    ),
    ("spheremap", "sphere_map_st", ST, "vec2(r.x / m + 0.5, 0.5 - r.y / m)", "the sign of"),
    ("spheremap", "sphere_map_st", ST, "vec2(r.x / m, r.y / m)", "the term 1/2 missing"),
    (
        "spheremap",
        "sphere_map_st",
        "r.x * r.x + r.y * r.y + ",
        "r.x * r.x + ",
        "the term ry^2 missing",
    ),
    (
        "spheremap",
        "sphere_map_st",
        "r.x * r.x + r.y * r.y",
        "2.0 * r.x * r.x + r.y * r.y",
        "rx^2 doubled",
    ),
    (
        "spheremap",
        "sphere_map_st",
        ST,
        "normalize(vec2(r.x / m + 0.5, r.y / m + 0.5))",
        "a mistake the checker does not know",
    ),
    (
        "cubemap",
        "cube_face",
        "if (a.x >= a.y && a.x >= a.z)",
        "if (a.x >= a.y && a.y >= a.z)",
        "the comparisons are chained",
    ),
    (
        "cubemap",
        "cube_face",
        "if (a.x >= a.y && a.x >= a.z)",
        "if (a.x >= a.y)",
        "rx is compared with ry only",
    ),
    ("cubemap", "cube_face", "    vec3 a = abs(r);", "    vec3 a = r;", "largest signed"),
    (
        "cubemap",
        "cube_face_st",
        "ma = abs(r.y); }\n    else if (face == 3) { sc = r.x; tc = -r.z; ma = abs(r.y)",
        "ma = abs(r.x); }\n    else if (face == 3) { sc = r.x; tc = -r.z; ma = abs(r.x)",
        "rx where the formula has ry",
    ),
    (
        "cubemap",
        "cube_face_st",
        CUBE_ST,
        "vec2((sc / ma + 1.0) / 4.0, (tc / ma + 1.0) / 4.0)",
        "1/2 applied twice",
    ),
    (
        "cubemap",
        "cube_face_st",
        CUBE_ST,
        "vec2(sc / ma / 2.0 + 1.0, tc / ma / 2.0 + 1.0)",
        "applied to sc / |ma| only",
    ),
    (
        "cubemap",
        "cube_face_st",
        CUBE_ST,
        "vec2((sc / ma + 1.0) / 2.0, (tc / ma - 1.0) / 2.0)",
        "the sign of 1 flipped",
    ),
    (
        "cubemap",
        "cube_face_st",
        CUBE_ST,
        "vec2((1.0 - sc / ma) / 2.0, (tc / ma + 1.0) / 2.0)",
        "the sign of sc",
    ),
]


@pytest.mark.parametrize("lab, function, old, new, phrase", MISTAKES)
def test_each_mistake_is_named_by_the_variant_it_follows(registry, lab, function, old, new, phrase):
    text = glsl(lab)
    assert old in text, old
    verdicts = judged(registry, lab, text.replace(old, new))
    passed, hint = verdicts[function]
    assert not passed and phrase in hint, hint
    assert "\n" not in hint
    # the other function of the lab is untouched, and still passes
    assert all(p for name, (p, _) in verdicts.items() if name != function), verdicts


FORGED = {
    "discard all but a few fragments, chosen by gl_FragCoord": (
        "if (gl_FragCoord.y > 1.0 || gl_FragCoord.x > 8.0) discard;\n",
        "wrote no value",
    ),
    "constants where the probe's points are": (
        "if (gl_FragCoord.y < 16.0) return {constant};\n",
        "same value",
    ),
    "the probe told by its point sprite": (
        "if (gl_PointCoord.x > 0.0 || gl_PrimitiveID > 0) return {constant};\n",
        "",
    ),
    "NaN for every input": ("return {nan};\n", ""),
    "an early return on inputs not of unit length": (
        "if (abs(dot({first}, {first}) - 1.0) > 1e-3) return {constant};\n",
        "",
    ),
}
CONSTANTS = {
    "reflect_eye": ("vec3(0.0, 0.0, 1.0)", "u", "vec3(0.0 / 0.0)"),
    "sphere_map_st": ("vec2(0.5)", "r", "vec2(0.0 / 0.0)"),
    "cube_face": ("0", "r", "int(0.0 / 0.0)"),
    "cube_face_st": ("vec2(0.5)", "r", "vec2(0.0 / 0.0)"),
}
FIRST_LINES = {
    "reflect_eye": "vec3 reflect_eye(vec3 u, vec3 n) {\n",
    "sphere_map_st": "vec2 sphere_map_st(vec3 r) {\n",
    "cube_face": "int cube_face(vec3 r) {\n",
    "cube_face_st": "vec2 cube_face_st(vec3 r, int face) {\n",
}


@pytest.mark.parametrize("forgery", sorted(FORGED))
@pytest.mark.parametrize("lab", sorted(KIT))
def test_shaders_written_against_the_probe_fail(registry, lab, forgery):
    """Each function with a line put first that fakes its values where it thinks the
    probe looks; it must fail (an early return on inputs off the domain only changes
    values that are never judged: that one may pass, but must not pass by faking)."""
    template, phrase = FORGED[forgery]
    text = glsl(lab)
    for function in (f.name for f in probe.lab_functions(lab)):
        constant, first, nan = CONSTANTS[function]
        line = FIRST_LINES[function]
        assert line in text
        faked = template.format(constant=constant, first=first, nan=nan)
        text = text.replace(line, line + "    " + faked)
    verdicts = judged(registry, lab, text, seed=3)
    if forgery == "an early return on inputs not of unit length":
        # r of other lengths are diagnostic for the sphere map; the cube's domain has them
        assert verdicts.get("cube_face_st", (False, ""))[0] is False or lab == "spheremap"
        return
    for name, (passed, hint) in verdicts.items():
        assert not passed, (name, forgery)
        assert phrase in hint, (name, hint)


def test_the_probe_sets_all_it_reads_whatever_the_context_holds(registry):
    """State a student's calls (or the checker's own drawing) could leave: another
    program, framebuffer, viewport, scissor, blending, masks, a sampler on unit 0, a
    bound VAO and buffer. The probe's values are the same as in a clean context."""
    clean = judged(registry, "cubemap", glsl("cubemap"))
    program = GL.glCreateProgram()
    GL.glUseProgram(0)
    GL.glEnable(GL.GL_SCISSOR_TEST)
    GL.glScissor(0, 0, 1, 1)
    GL.glEnable(GL.GL_BLEND)
    GL.glBlendFunc(GL.GL_ZERO, GL.GL_ZERO)
    GL.glColorMask(0, 0, 0, 0)
    GL.glViewport(0, 0, 1, 1)
    GL.glEnable(GL.GL_DEPTH_TEST)
    GL.glDepthFunc(GL.GL_NEVER)
    GL.glEnable(GL.GL_CULL_FACE)
    GL.glCullFace(GL.GL_FRONT_AND_BACK)
    texture = int(GL.glGenTextures(1))
    GL.glBindTexture(GL.GL_TEXTURE_CUBE_MAP, texture)
    vao = int(GL.glGenVertexArrays(1))
    GL.glBindVertexArray(vao)
    try:
        assert judged(registry, "cubemap", glsl("cubemap")) == clean
    finally:
        GL.glDisable(GL.GL_SCISSOR_TEST)
        GL.glDisable(GL.GL_BLEND)
        GL.glColorMask(1, 1, 1, 1)
        GL.glDisable(GL.GL_DEPTH_TEST)
        GL.glDepthFunc(GL.GL_LESS)
        GL.glDisable(GL.GL_CULL_FACE)
        GL.glBindVertexArray(0)
        GL.glDeleteVertexArrays(1, [vao])
        GL.glDeleteTextures(1, [texture])
        GL.glDeleteProgram(program)


def test_the_probe_and_the_compat_rewriting_behave_the_same_in_a_core_context(registry):
    """In macOS's 4.1 core context (Mesa's overrides): the same verdicts and hints as
    here, for the solutions, a slip of each lab, GLSL naming gl_ModelViewMatrix (the
    identity in the probe, both ways) and a refused reserved name."""
    from tests import MACOS_CONTEXT

    script = (
        "import sys\n"
        "from mirrorlab.gl.context import offscreen_context\n"
        "from mirrorlab.gl.opengl import GL\n"
        "from tests.gl.test_value_probe import CASES, verdict_lines\n"
        "with offscreen_context() as context:\n"
        "    print('profile', int(GL.glGetIntegerv(GL.GL_CONTEXT_PROFILE_MASK)))\n"
        "    print('\\n'.join(verdict_lines(context.resources)))\n"
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
    assert lines[1:] == verdict_lines(registry)
    assert sum(" True " in line for line in lines) >= 5
    assert any("refused" in line and "ml_ModelViewMatrix" in line for line in lines)


CASES = [
    ("spheremap", "", ""),
    ("spheremap", "(r.z + 1.0) * (r.z + 1.0)", "r.z + 1.0 * r.z + 1.0"),
    (
        "spheremap",
        SOLUTION_REFLECT,
        "return (gl_ModelViewMatrix * vec4(u - 2.0 * dot(n, u) * n, 0.0)).xyz;",
    ),
    ("spheremap", SOLUTION_REFLECT, "float ml_ModelViewMatrix = 1.0;\n" + SOLUTION_REFLECT),
    ("cubemap", "", ""),
    ("cubemap", "if (a.x >= a.y && a.x >= a.z)", "if (a.x >= a.y && a.y >= a.z)"),
]


def verdict_lines(registry) -> list[str]:
    """One line per case and function: its verdict and hint (the seed fixed)."""
    lines = []
    for lab, old, new in CASES:
        text = glsl(lab).replace(old, new) if old else glsl(lab)
        try:
            verdicts = judged(registry, lab, text, seed=8)
        except StudentShaderError as exc:
            lines.append(f"{lab} refused {exc}")
            continue
        lines += [f"{lab} {name} {passed} {hint}" for name, (passed, hint) in verdicts.items()]
    return lines


# ------------------------------------------------------------------ the declaration fuzz
DECLARED = st.sampled_from(
    [
        "",
        "const float HALF = 0.5;",
        "struct Pair { float a; vec3 b; };",
        "struct S { samplerCube c; };\nuniform S ml_ModelViewMatrix[2];",
        "uniform float ml_ModelViewMatrix;",
        "uniform samplerCube cube;",
        "uniform sampler2D ml_probe_a;",
        "layout(location = 0) out vec4 ml_out;",
        "out vec4 colour;",
        "flat in int ml_call;",
        "uniform Block { vec4 v; } block;",
        "#define CAT(a, b) a ## b\nuniform float CAT(ml, _TextureMatrix)[8];",
        "#define U uniform\nU mat4 ml_ProjectionMatrix;",
        "float ml_/**/ModelViewMatrix;",
        "vec4 ml_in0;",
        "precision highp float;",
        "void main() {}",
        "int counter;",
        "#define normalize(v) vec3(0.0)",
        "vec3 reflect_eye(vec3 u, vec3 n);",
    ]
)
BODIES = st.sampled_from(
    [
        "    return u - 2.0 * dot(n, u) * n;",
        "    if (gl_FragCoord.x < 2.0) discard;\n    return u;",
        "    return (gl_ModelViewMatrix * vec4(u, 0.0)).xyz;",
        "    return u / 0.0;",
        "    return vec3(counter);",
        "    return texture(cube, u).rgb;",
        "    return u - 2.0 * dot(n, u) * n + ml_out.xyz;",
        "    return vec3(HALF);",
        "    for (int i = 0; i < 4; i++) { u = reflect(u, n); }\n    return u;",
        "    return u -;",
    ]
)


@settings(max_examples=40, suppress_health_check=[HealthCheck.function_scoped_fixture])
@given(declared=st.lists(DECLARED, max_size=3), body=BODIES)
def test_fuzzed_declarations_end_in_values_or_one_line(registry, declared, body):
    """Any declarations, with a body that may read them: the probe gives values (judged
    as any others) or the student's error in one line; never another exception, and no
    GL error left behind."""
    text = (
        "\n".join(declared)
        + "\nvec3 reflect_eye(vec3 u, vec3 n) {\n"
        + body
        + "\n}\nvec2 sphere_map_st(vec3 r) { return r.xy; }\n"
    )
    try:
        verdicts = judged(registry, "spheremap", text, seed=5)
    except StudentShaderError as exc:
        assert "\n" not in str(exc) and len(str(exc)) < 500
    else:
        for passed, hint in verdicts.values():
            assert passed or (hint and "\n" not in hint)
    assert GL.glGetError() == GL.GL_NO_ERROR


SLOW = (
    "#define S1 s = sin(s + u.y);\n#define S4 S1 S1 S1 S1\n#define S16 S4 S4 S4 S4\n"
    "vec3 slow(vec3 u) {\n    float s = u.x;\n"
    "    for (int i = 0; i < 65535; i++) { S16 S16 S16 S16 S16 S16 S16 S16 }\n"
    "    return u + s * 1e-30;\n}\n"
)
"""Functions that take minutes on the probe's inputs (llvmpipe ends any loop after 65,535
turns, so a loop that never ends is one that runs long)."""


def test_through_the_compiling_process_a_function_that_never_finishes_costs_the_file(
    monkeypatch,
):
    """Compiled and probed in a process of its own: the same text is asked once (its
    inputs kept), another text gets inputs of its own, and functions that do not finish
    on the probe's inputs are the file's error at the limit, not the checker's."""
    monkeypatch.setattr(glslcheck, "CPU_SECONDS", 1)
    monkeypatch.delenv(probe.SEED_VARIABLE, raising=False)
    text = glsl("spheremap")
    first = glslcheck.precompile("kit_sphere.vert", "kit_sphere.frag", text, "G", "spheremap")
    again = glslcheck.precompile("kit_sphere.vert", "kit_sphere.frag", text, "G", "spheremap")
    assert again is first and set(first.values) == {"reflect_eye", "sphere_map_st"}
    other = glslcheck.precompile(
        "kit_sphere.vert", "kit_sphere.frag", text + "\n", "G", "spheremap"
    )
    assert other.seed != first.seed
    endless = SLOW + text.replace(SOLUTION_REFLECT, "u = slow(u);\n    " + SOLUTION_REFLECT)
    with pytest.raises(StudentShaderError, match="did not finish on the checker's inputs"):
        glslcheck.precompile("kit_sphere.vert", "kit_sphere.frag", endless, "G", "spheremap")
