"""The student's GLSL is compiled alone: a shader object of its own (its own preprocessor,
so no macro of it reaches the kit's code), linked to the kit's main through fixed
prototypes; a declaration outside the functions (a uniform, such as the kit's check mode,
an output, a block) is refused, and compile errors still name the student's line."""

from __future__ import annotations

import re

import numpy as np
import pytest

from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import FloatFramebuffer
from mirrorlab.labs.trusted.session import StudentShaderError, open_session
from mirrorlab.labs.trusted.variants import default_variant
from tests.gl.conftest import module_context
from tests.labs.mutants import solution

SIZE = (48, 48)


gl_context = pytest.fixture(scope="module", name="gl_context")(module_context)
LABS = {
    "cubemap": ("CUBE_MAP_GLSL", "draw_sphere", 2, "int cube_face(vec3 r) {"),
    "spheremap": ("SPHERE_MAP_GLSL", "draw_cone_shader", 2, "vec3 reflect_eye(vec3 u, vec3 n) {"),
}
"""lab -> its GLSL variable, the kit's draw, a check mode that shows only the kit's own
numbers (the cube's r, the cone's u), and the first line of a student function."""
MACROS = (
    "#define normalize(v) vec3(0.0, 0.0, 1.0)\n#define texture(s, d) vec4(0.5)\n#define mode 0\n"
)
"""What a student's text once did to the kit's code it was pasted into."""


def glsl(lab: str) -> str:
    variable = LABS[lab][0]
    found = re.search(rf'{variable} = """(.*?)"""', solution(lab), re.S)
    assert found is not None
    return found.group(1)


def values(registry, lab: str, text: str) -> np.ndarray:
    """The kit's check mode drawn around ``text``: ``(h, w, 3)`` float32."""
    session = open_session(lab, SIZE, default_variant(lab))
    target = FloatFramebuffer(registry, *SIZE)
    target.bind()
    GL.glViewport(0, 0, *SIZE)
    session.set_viewer()
    GL.glClearColor(0.0, 0.0, 0.0, 0.0)
    GL.glClear(GL.GL_COLOR_BUFFER_BIT | GL.GL_DEPTH_BUFFER_BIT)
    _, draw, mode, _ = LABS[lab]
    getattr(session, draw)(text, 0, mode)
    return target.read()


@pytest.mark.parametrize("lab", sorted(LABS))
def test_a_students_macros_never_reach_the_kits_code(registry, lab):
    honest = values(registry, lab, glsl(lab))
    assert np.ptp(honest) > 0.5  # the kit's own directions, varying over the picture
    forged = values(registry, lab, MACROS + glsl(lab))
    assert np.array_equal(forged, honest)


@pytest.mark.parametrize("lab", sorted(LABS))
def test_declarations_outside_the_functions_are_refused_with_their_line(registry, lab):
    """A uniform, a sampler, an output or a block of the student's own is refused before
    the driver sees it, whether the functions read it or not."""
    first = LABS[lab][3]
    text = "uniform int mode;\n" + glsl(lab).replace(
        first, first + "\n    if (mode == 1) { return " + ("0; }" if lab == "cubemap" else "u; }")
    )
    with pytest.raises(StudentShaderError, match=r"line 1 is refused: 'uniform' outside"):
        values(registry, lab, text)
    # hidden behind a macro (tests/unit/test_glsl_source.py has every other form)
    with pytest.raises(StudentShaderError, match="line 2 is refused: 'uniform' outside"):
        values(registry, lab, "#define U uniform\nU sampler2D hidden;\n" + glsl(lab))


@pytest.mark.parametrize("lab", sorted(LABS))
def test_a_compile_error_names_the_students_line_and_a_missing_function_its_name(registry, lab):
    variable = LABS[lab][0]
    text = glsl(lab)
    broken = text + "\n    oops\n"
    with pytest.raises(StudentShaderError) as caught:
        values(registry, lab, broken)
    assert caught.value.variable == variable
    assert caught.value.line == text.count("\n") + 2  # "oops", counted from 1
    with pytest.raises(StudentShaderError, match=r"unresolved|undefined"):
        values(registry, lab, "float unrelated(float x) { return x; }\n")


def test_gl_built_in_state_is_not_a_uniform_of_the_kit(registry):
    """Compatibility GLSL may read GL's own state (the same for the kit's every draw)."""
    from mirrorlab.labs.trusted.session import compile_program

    text = (
        "vec3 reflect_eye(vec3 u, vec3 n) {\n"
        "    return (gl_ModelViewMatrix * vec4(u - 2.0 * dot(n, u) * n, 0.0)).xyz;\n}\n"
        "vec2 sphere_map_st(vec3 r) { return r.xy; }\n"
    )
    open_session("spheremap", SIZE, default_variant("spheremap"))
    program = compile_program("kit_sphere.vert", "kit_sphere.frag", text, "SPHERE_MAP_GLSL")
    assert program > 0
    GL.glDeleteProgram(program)
