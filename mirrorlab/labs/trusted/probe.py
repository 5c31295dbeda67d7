"""The value probe: each GLSL function a lab asks for, evaluated on inputs the checker
chooses, so that a hint names the slip the values show.

The student's GLSL is compiled alone, as the fragment shader object the kit links it as
(:func:`.session.compile_program`), and linked here to a probe ``main`` of the checker's own
that declares the same prototypes (those after the kit file's ``// STUDENT CODE`` line)
and nothing else of the kit. One input per pixel: the inputs are two ``(n, 1)`` RGBA32F
textures read with ``texelFetch``, the results one RGBA32F pixel each. ``#version 330
core`` with no compatibility built-in, so it runs on a 4.1 core context too.

The inputs (:data:`INPUTS`) are chosen to tell the usual slips apart: both signs of
``n.u`` (a clamped dot product is right on one side only), reflection vectors of length
other than 1 (a halfway vector left unnormalised gives the same numbers as a missing
``+ 1`` on unit vectors only), directions on every cube face, each face's major axis
well ahead of the others, none near a singularity. :func:`slip` names which of a
function's known formulas (:data:`FORMULAS`) the values follow. The GL part
(:func:`run_probe`) imports OpenGL lazily; the rest is numpy only, for the judges.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from mirrorlab.envmap import cube_map, reflect, sphere_map

TOLERANCE = 1e-3
"""Largest difference between the GPU's float32 values and a formula's float64 ones on
the probe's inputs (measured: below 1e-6 on Mesa llvmpipe)."""


def _directions(rng: np.random.Generator, count: int) -> np.ndarray:
    v = rng.normal(size=(count, 3))
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def _reflect_inputs() -> tuple[np.ndarray, np.ndarray]:
    """(u, n) ``(32, 3)`` each, unit vectors; n.u < 0 on the first half (the cone's side),
    > 0 on the second, |n.u| >= 0.2 everywhere."""
    rng = np.random.default_rng(39)
    us: list[np.ndarray] = []
    ns: list[np.ndarray] = []
    while len(us) < 32:
        u, n = _directions(rng, 2)
        d = float(u @ n)
        if abs(d) < 0.2:
            continue
        want_negative = len(us) < 16
        if (d < 0) != want_negative:
            n = -n
        us.append(u)
        ns.append(n)
    return np.array(us), np.array(ns)


def _sphere_inputs() -> np.ndarray:
    """r ``(48, 3)``: 16 unit directions away from (0, 0, -1) with |r.x|, |r.y| >= 0.1 and
    r.x != r.y, then the same scaled by 0.5 and 2.5."""
    rng = np.random.default_rng(40)
    rs: list[np.ndarray] = []
    while len(rs) < 16:
        r = _directions(rng, 1)[0]
        if r[2] < -0.7 or min(abs(r[0]), abs(r[1])) < 0.1 or abs(r[0] - r[1]) < 0.1:
            continue
        rs.append(r)
    unit = np.array(rs)
    return np.concatenate([unit, 0.5 * unit, 2.5 * unit])


def _cube_inputs() -> tuple[np.ndarray, np.ndarray]:
    """(r ``(48, 3)``, its face ``(48,)``): 8 directions on each face, the major axis at
    least 1.3 times either other component, the minor ones >= 0.1 apart in size and from 0,
    lengths from 0.5 to 3."""
    rng = np.random.default_rng(41)
    rs: list[np.ndarray] = []
    for face in range(6):
        axis, sign = face // 2, (1.0 if face % 2 == 0 else -1.0)
        found = 0
        while found < 8:
            v = rng.uniform(-0.75, 0.75, size=3)
            v[axis] = sign
            others = [v[i] for i in range(3) if i != axis]
            if min(abs(o) for o in others) < 0.1 or abs(abs(others[0]) - abs(others[1])) < 0.1:
                continue
            rs.append(v * rng.uniform(0.5, 3.0))
            found += 1
    r = np.array(rs)
    return r, cube_map(r)[0]


REFLECT_U, REFLECT_N = _reflect_inputs()
SPHERE_R = _sphere_inputs()
CUBE_R, CUBE_FACE = _cube_inputs()

INPUTS: dict[str, tuple[np.ndarray, np.ndarray]] = {
    "reflect_eye": (REFLECT_U, REFLECT_N),
    "sphere_map_st": (SPHERE_R, np.zeros_like(SPHERE_R)),
    "cube_face": (CUBE_R, np.zeros_like(CUBE_R)),
    "cube_face_st": (CUBE_R, np.stack([CUBE_FACE, CUBE_FACE, CUBE_FACE], -1).astype(float)),
}
"""Per function, its two inputs ``(n, 3)`` (a and b of the probe's main)."""

CALLS = {
    "reflect_eye": "vec4(reflect_eye(a.xyz, b.xyz), 1.0)",
    "sphere_map_st": "vec4(sphere_map_st(a.xyz), 0.0, 1.0)",
    "cube_face": "vec4(float(cube_face(a.xyz)), 0.0, 0.0, 1.0)",
    "cube_face_st": "vec4(cube_face_st(a.xyz, int(b.x + 0.5)), 0.0, 1.0)",
}
"""How the probe's main calls each function (a, b: the inputs as vec4)."""


# ------------------------------------------------------------------ formulas and slips
def _hoff(r: np.ndarray, plus: float = 1.0, two: float = 2.0, half: float = 0.5) -> np.ndarray:
    m = two * np.sqrt(r[:, 0] ** 2 + r[:, 1] ** 2 + (r[:, 2] + plus) ** 2)
    return np.stack([r[:, 0] / m + half, r[:, 1] / m + half], -1)


def _unit(r: np.ndarray) -> np.ndarray:
    return r / np.linalg.norm(r, axis=-1, keepdims=True)


def sphere_formulas(r: np.ndarray) -> dict[str, np.ndarray]:
    """Hoff's (s, t) ``(n, 2)`` of ``r`` ``(n, 3)`` as written (``right``, right for any
    length of r only after normalising: ``normalised``), and each slip of it."""
    h = r + np.array([0.0, 0.0, 1.0])
    return {
        "right": _hoff(r),
        "normalised": np.stack(sphere_map(r), -1),
        "swap": _hoff(r)[:, ::-1],
        "flip_t": _hoff(r) * [1, -1] + [0, 1],
        "flip_s": _hoff(r) * [-1, 1] + [1, 0],
        "no_plus_one": _hoff(r, plus=0.0),
        "unnormalised": h[:, :2] / 2 + 0.5,
        "minus_one": _hoff(r, plus=-1.0),
        "no_two": _hoff(r, two=1.0),
        "no_half": _hoff(r, half=0.0),
    }


def reflect_formulas(u: np.ndarray, n: np.ndarray) -> dict[str, np.ndarray]:
    """u - 2 (n.u) n ``(n, 3)`` (``right``) and each slip of it."""
    d = (u * n).sum(-1, keepdims=True)
    right = reflect(u, n)
    return {
        "right": right,
        "sign": -right,
        "no_two": u - d * n,
        "plus": u + 2 * d * n,
        "unreflected": u,
        "normal": n,
        "clamped": u - 2 * np.maximum(d, 0.0) * n,
        "abs_dot": u - 2 * np.abs(d) * n,
    }


def cube_formulas(r: np.ndarray, face: np.ndarray) -> dict[str, np.ndarray]:
    """The OpenGL table's (s, t) ``(n, 2)`` of ``r`` ``(n, 3)`` on ``face`` ``(n,)``
    (``right``) and each slip of it."""
    _, s, t = cube_map(r)
    right = np.stack([s, t], -1)
    axis = face // 2
    signed = np.take_along_axis(r, axis[:, None], -1)
    major = np.abs(signed)
    sc_tc = (2 * right - 1) * major
    return {
        "right": right,
        "swap": right[:, ::-1],
        "flip_s": right * [-1, 1] + [1, 0],
        "flip_t": right * [1, -1] + [0, 1],
        "undivided": (sc_tc + 1) / 2,
        "length": (sc_tc / np.linalg.norm(r, axis=-1, keepdims=True) + 1) / 2,
        "no_shift": sc_tc / major,
        "no_scale": sc_tc / major + 1,
        "signed_major": (sc_tc / signed + 1) / 2,
        "zero": np.zeros_like(right),
    }


def face_formulas(r: np.ndarray) -> dict[str, np.ndarray]:
    """The face ``(n, 1)`` of ``r`` ``(n, 3)``: the axis of largest magnitude and its sign
    (``right``), and each slip of it."""
    right = cube_map(r)[0].astype(np.float64)
    axis = np.argmax(r, axis=-1)
    signed = 2 * axis + (np.take_along_axis(r, axis[:, None], -1)[:, 0] < 0)
    return {
        "right": right[:, None],
        "signed": signed[:, None].astype(np.float64),
        "opposite": (right.astype(np.int64) ^ 1)[:, None].astype(np.float64),
    }


FORMULAS: dict[str, Callable[[], dict[str, np.ndarray]]] = {
    "cube_face": lambda: face_formulas(CUBE_R),
    "reflect_eye": lambda: reflect_formulas(REFLECT_U, REFLECT_N),
    "sphere_map_st": lambda: sphere_formulas(SPHERE_R),
    "cube_face_st": lambda: cube_formulas(CUBE_R, CUBE_FACE),
}
"""Per function, its right formula and its known slips on the probe's inputs."""

RIGHT = {
    "reflect_eye": ("right",),
    "sphere_map_st": ("right", "normalised"),
    "cube_face": ("right",),
    "cube_face_st": ("right",),
}
"""The formulas that are the function, not a slip of it."""


def _matches(values: np.ndarray, predicted: np.ndarray) -> bool:
    width = predicted.shape[-1]
    return bool(np.all(np.abs(values[:, :width] - predicted) <= TOLERANCE))


def slip(function: str, values: np.ndarray | None) -> str:
    """The formula of :data:`FORMULAS` that ``values`` ``(n, 4)`` (the probe's results for
    ``function``) follow on every input: 'right' for the function itself, a slip's name,
    or '' when they follow none (or are missing or not finite)."""
    if values is None or not np.all(np.isfinite(values)):
        return ""
    for name, predicted in FORMULAS[function]().items():
        if _matches(values, predicted):
            return "right" if name in RIGHT[function] else name
    return ""


def slip_per_face(values: np.ndarray | None) -> dict[int, str]:
    """cube_face_st's slip on each face's inputs, for faces where it is not right:
    ``{face: name or ''}``; {} when the values are missing or not finite."""
    if values is None or not np.all(np.isfinite(values)):
        return {}
    formulas = FORMULAS["cube_face_st"]()
    wrong = {}
    for face in range(6):
        on = CUBE_FACE == face
        found = next(
            (name for name, predicted in formulas.items() if _matches(values[on], predicted[on])),
            "",
        )
        if found != "right":
            wrong[face] = found
    return wrong


# ------------------------------------------------------------------ the GL part
PROBE_VERTEX = """#version 330 core
void main() {
    gl_Position = vec4(float((gl_VertexID & 1) * 4 - 1), float((gl_VertexID & 2) * 2 - 1),
                       0.0, 1.0);
}
"""


def probe_fragment(version: str, prototypes: str, calls: list[str]) -> str:
    """The probe's main: ``calls[i]`` when ``mirrorlab_probe_call`` is i."""
    branches = "\n".join(
        f"    {'else ' if i else ''}if (mirrorlab_probe_call == {i}) mirrorlab_probe_out = {call};"
        for i, call in enumerate(calls)
    )
    return (
        f"{version}\n{prototypes}"
        "uniform sampler2D mirrorlab_probe_a;\nuniform sampler2D mirrorlab_probe_b;\n"
        "uniform int mirrorlab_probe_call;\n"
        "layout(location = 0) out vec4 mirrorlab_probe_out;\n"
        "void main() {\n    ivec2 at = ivec2(gl_FragCoord.xy);\n"
        "    vec4 a = texelFetch(mirrorlab_probe_a, at, 0);\n"
        "    vec4 b = texelFetch(mirrorlab_probe_b, at, 0);\n"
        f"    mirrorlab_probe_out = vec4(0.0);\n{branches}\n}}\n"
    )


def run_probe(
    kit_fragment: str, glsl: str, functions: tuple[str, ...], registry
) -> dict[str, np.ndarray]:
    """Each of ``functions`` of the student's ``glsl`` evaluated on its :data:`INPUTS`:
    ``{function: (n, 4) float32}``. ``kit_fragment`` is the kit's fragment shader file that
    the student's GLSL is linked to (its prototypes are the interface). Raises LabSetupError
    (StudentShaderError) when the GLSL does not compile or link with the probe. Leaves the
    framebuffer and the viewport as the
    checker found them, but for the program (0) and the active unit (0)."""
    from mirrorlab.gl.opengl import GL
    from mirrorlab.gl.resources import FloatFramebuffer, expand_includes
    from mirrorlab.labs.trusted import legacy, session

    kit_source = expand_includes(kit_fragment)
    version, interface = session.student_interface(kit_source)
    version = version or "#version 330 core"
    prototypes = "".join(f"{r} {n}({p});\n" for r, n, p in interface)
    shaders = [session.student_shader(GL.GL_FRAGMENT_SHADER, kit_source, glsl, "probe")]
    framebuffer = int(GL.glGetIntegerv(GL.GL_FRAMEBUFFER_BINDING))
    viewport = [int(v) for v in GL.glGetIntegerv(GL.GL_VIEWPORT)]
    textures: list[int] = []
    program = 0
    vao = 0
    target = None
    try:
        shaders.append(
            session._compiled(
                GL.GL_VERTEX_SHADER, PROBE_VERTEX, "the probe's vertex shader", "probe"
            )
        )
        shaders.append(
            session._compiled(
                GL.GL_FRAGMENT_SHADER,
                probe_fragment(version, prototypes, [CALLS[f] for f in functions]),
                "the probe's main",
                "probe",
            )
        )
        program = session._linked(shaders, "probe", "probe")
        count = max(INPUTS[f][0].shape[0] for f in functions)
        target = FloatFramebuffer(registry, count, 1)
        target.bind()
        GL.glViewport(0, 0, count, 1)
        for cap in (
            GL.GL_SCISSOR_TEST,
            GL.GL_BLEND,
            GL.GL_DEPTH_TEST,
            GL.GL_CULL_FACE,
            GL.GL_STENCIL_TEST,
            GL.GL_RASTERIZER_DISCARD,
        ):
            GL.glDisable(cap)
        GL.glColorMask(1, 1, 1, 1)
        GL.glUseProgram(program)
        legacy.load_matrix_uniforms(program)
        vao = int(GL.glGenVertexArrays(1))
        GL.glBindVertexArray(vao)
        textures = [int(t) for t in np.atleast_1d(GL.glGenTextures(2))]
        for unit, name in enumerate(("mirrorlab_probe_a", "mirrorlab_probe_b")):
            GL.glUniform1i(GL.glGetUniformLocation(program, name), unit)
        results = {}
        for index, function in enumerate(functions):
            for unit, array in enumerate(INPUTS[function]):
                rgba = np.zeros((1, count, 4), dtype=np.float32)
                rgba[0, : array.shape[0], :3] = array
                GL.glActiveTexture(GL.GL_TEXTURE0 + unit)
                GL.glBindTexture(GL.GL_TEXTURE_2D, textures[unit])
                GL.glPixelStorei(GL.GL_UNPACK_ALIGNMENT, 4)
                GL.glTexImage2D(
                    GL.GL_TEXTURE_2D, 0, GL.GL_RGBA32F, count, 1, 0, GL.GL_RGBA, GL.GL_FLOAT, rgba
                )
                GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MIN_FILTER, GL.GL_NEAREST)
                GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAG_FILTER, GL.GL_NEAREST)
            GL.glUniform1i(GL.glGetUniformLocation(program, "mirrorlab_probe_call"), index)
            GL.glClearColor(0.0, 0.0, 0.0, 0.0)
            GL.glClear(GL.GL_COLOR_BUFFER_BIT)
            GL.glDrawArrays(GL.GL_TRIANGLES, 0, 3)
            values = target.read_rgba()[0, : INPUTS[function][0].shape[0]]
            results[function] = values.astype(np.float32)
        return results
    finally:
        GL.glUseProgram(0)
        GL.glBindVertexArray(0)
        for unit in (1, 0):
            GL.glActiveTexture(GL.GL_TEXTURE0 + unit)
            GL.glBindTexture(GL.GL_TEXTURE_2D, 0)
        if textures:
            GL.glDeleteTextures(len(textures), textures)
        if vao:
            GL.glDeleteVertexArrays(1, [vao])
        if target is not None:
            target.release()
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, framebuffer)
        GL.glViewport(*viewport)
        if program:
            GL.glDeleteProgram(program)
        for shader in shaders:
            GL.glDeleteShader(shader)
