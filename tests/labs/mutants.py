"""Mutants of the teachers' solutions (labs/solutions/), one per common mistake: each is the
solution with a few lines changed, the tasks it must fail and a phrase the hint of each
must contain (every other task must pass). The issue's hint problems are here by name
(``wrong_corner``, ``copy_offset``, ``depth_not_cleared``, ...); the ``EQUIVALENT`` ones
are forms the handouts allow, which must pass every task. ``write_mutants`` writes them as
files (the checker never sees where they came from)."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

from mirrorlab.labs import find_lab
from tests import REPO_DIR

SOLUTIONS = REPO_DIR / "labs" / "solutions"


def solution(lab: str) -> str:
    """The teacher's solution of ``lab`` (the lab's own numbers), where its registry entry
    says it is."""
    return find_lab(lab).solution.read_text()


@dataclass(frozen=True)
class Mutant:
    lab: str
    name: str
    edits: tuple[tuple[str, str], ...]
    fails: dict[str, str] = field(default_factory=dict)
    """task id -> a phrase its hint must contain; every other task must pass."""
    cause: str = ""
    """A phrase naming the mistake, which the hint of the first failing task (in the
    handout's order) must contain; '' when that task's phrase in ``fails`` names it."""

    def expected_cause(self) -> tuple[str, str]:
        """(the first task expected to fail, the phrase naming the cause in its hint)."""
        first = next(t.id for t in find_lab(self.lab).tasks if t.id in self.fails)
        return first, self.cause or self.fails[first]

    def source(self) -> str:
        text = solution(self.lab)
        for old, new in self.edits:
            if old not in text:
                raise AssertionError(f"mutant {self.name}: {old!r} is not in the solution")
            text = text.replace(old, new)
        return text


QUAD = """    glTexCoord2f(0, 0)
    glVertex3f(MIRROR_X, Y0, Z0)
    glTexCoord2f(0, 1)
    glVertex3f(MIRROR_X, Y1, Z0)
    glTexCoord2f(1, 1)
    glVertex3f(MIRROR_X, Y1, Z1)
    glTexCoord2f(1, 0)
    glVertex3f(MIRROR_X, Y0, Z1)
"""
CORNERS = ("MIRROR_X, Y0, Z0", "MIRROR_X, Y1, Z0", "MIRROR_X, Y1, Z1", "MIRROR_X, Y0, Z1")


def quad(
    texcoords, corners=CORNERS, vertex: str = "glVertex3f({})", texcoord: str = "glTexCoord2f{}"
) -> str:
    """The mirror quad's lines with ``texcoords`` at ``corners``."""
    return "".join(
        f"    {texcoord.format(tuple(st))}\n    {vertex.format(corner)}\n"
        for st, corner in zip(texcoords, corners, strict=True)
    )


RIGHT = ((0, 0), (0, 1), (1, 1), (1, 0))
CLEAR = "    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT)\n"

LAB20 = (
    Mutant(
        "lab20",
        "wrong_extents",
        (("glOrtho(Z0, Z1, Y0, Y1, 0, 15)", "glOrtho(-4, 4, -4, 4, 0, 15)"),),
        {
            "capture_camera": "left, right, bottom, top = -4, 4, -4, 4",
            "capture_scene": "left, right, bottom, top = -4, 4, -4, 4",
        },
    ),
    Mutant(
        "lab20",
        "camera_wrong_side",
        (
            (
                "gluLookAt(MIRROR_X, 0, 0, 0, 0, 0, 0, 1, 0)",
                "gluLookAt(-MIRROR_X, 0, 0, 0, 0, 0, 0, 1, 0)",
            ),
        ),
        {"capture_camera": "eyeX = 7 (the solution's: -7)", "capture_scene": "eyeX = 7"},
    ),
    Mutant(
        "lab20",
        "no_projection_mode",
        (
            (
                "    glMatrixMode(GL_PROJECTION)\n    glLoadIdentity()\n    glOrtho",
                "    glLoadIdentity()\n    glOrtho",
            ),
        ),
        {
            "capture_camera": "applied to the modelview matrix",
            "capture_scene": "applied to the modelview matrix",
        },
    ),
    Mutant(
        "lab20",
        "no_load_identity",
        (
            (
                "    glMatrixMode(GL_PROJECTION)\n    glLoadIdentity()\n",
                "    glMatrixMode(GL_PROJECTION)\n",
            ),
        ),
        {
            "capture_camera": "needs glLoadIdentity on the projection matrix",
            "capture_scene": "needs glLoadIdentity on the projection matrix",
        },
    ),
    Mutant(
        "lab20",
        "texcoords_flipped",
        ((QUAD, quad(((1, 0), (1, 1), (0, 1), (0, 0)))),),
        {"mirror_quad": "flipped left-right"},
    ),
    Mutant(
        "lab20",
        "texcoords_upside_down",
        ((QUAD, quad(((0, 1), (0, 0), (1, 0), (1, 1)))),),
        {"mirror_quad": "upside down"},
    ),
    Mutant(
        "lab20",
        "texcoords_rotated",
        ((QUAD, quad(((0, 1), (1, 1), (1, 0), (0, 0)))),),
        {"mirror_quad": "rotated by 90 degrees"},
    ),
    Mutant(
        "lab20",
        "wrong_corner",
        (("glVertex3f(MIRROR_X, Y1, Z1)", "glVertex3f(MIRROR_X, Y1, Z1 - 1)"),),
        {"mirror_quad": "gives the vertex (-7, 5, 1); the solution's nearest is (-7, 5, 2)"},
    ),
    Mutant(
        "lab20",
        "quad_moved",
        ((QUAD, QUAD.replace("MIRROR_X,", "-5,")),),
        {"mirror_quad": "lies in the plane x = -5"},
    ),
    Mutant(
        "lab20",
        "mirror_in_capture",
        (
            (
                "    lab.draw_scene(robot)\n    # TODO 3",
                "    lab.draw_scene(robot)\n    render_mirror()\n    # TODO 3",
            ),
        ),
        {
            "capture_scene": "render_mirror() is called inside create_mirror()",
        },
    ),
    Mutant(
        "lab20",
        "environment_not_bound",
        (
            (
                "    glActiveTexture(GL_TEXTURE1)\n"
                "    glBindTexture(GL_TEXTURE_2D, tex_ids[ENVIRONMENT])\n    glCopyTexImage2D",
                "    glCopyTexImage2D",
            ),
        ),
        {"capture_copy": "filled tex_ids[METAL]", "capture_scene": "filled tex_ids[METAL]"},
    ),
    Mutant(
        "lab20",
        "half_copy",
        (("0, 0, WIDTH, HEIGHT, 0)", "0, 0, WIDTH // 2, HEIGHT // 2, 0)"),),
        {"capture_copy": "width, height = 128, 128 (the solution's: 256, 256)"},
    ),
    Mutant(
        "lab20",
        "copy_offset",
        (("GL_RGB, 0, 0, WIDTH, HEIGHT, 0)", "GL_RGB, 64, 64, WIDTH, HEIGHT, 0)"),),
        {"capture_copy": "x, y = 64, 64 (the solution's: 0, 0)"},
    ),
    Mutant(
        "lab20",
        "environment_mipmaps",
        (("GL_TEXTURE_MIN_FILTER, GL_LINEAR)", "GL_TEXTURE_MIN_FILTER, GL_LINEAR_MIPMAP_LINEAR)"),),
        {"environment_texture": "GL_LINEAR_MIPMAP_LINEAR"},
    ),
    Mutant(
        "lab20",
        "environment_repeat",
        (("GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE", "GL_TEXTURE_WRAP_S, GL_REPEAT"),),
        {"environment_texture": "repeat"},
    ),
    Mutant(
        "lab20",
        "base_not_textured",
        (('    robot["base"].texture = tex_ids[METAL]\n', ""),),
        {
            "base_texture": 'robot["base"].texture is no texture',
            "capture_scene": "base wears no texture",
        },
    ),
    Mutant(
        "lab20",
        "sampler_not_set",
        (("    glUniform1i(lab.texSampler, 1)\n", ""),),
        {"mirror_texture": "makes no glUniform1i(lab.texSampler, 1)"},
    ),
    Mutant(
        "lab20",
        "passes_wrong_order",
        (
            ("    create_mirror()\n", ""),
            (
                "    lab.draw_scene(robot)\n    # TODO 8: pass 2\n",
                "    lab.draw_scene(robot)\n    create_mirror()\n    # TODO 8: pass 2\n",
            ),
        ),
        {"passes": "wrong order", "mirror_quad": "task 8 (passes)"},
    ),
    Mutant(
        "lab20",
        "capture_after_clear",
        (
            (CLEAR + "    # TODO 1", "    # TODO 1"),
            ("    create_mirror()\n" + CLEAR, CLEAR + "    create_mirror()\n"),
        ),
        {"passes": "create_mirror() at line 97 (create_mirror()) comes after glClear"},
    ),
)

VIEWER_PASS = "    lab.set_viewer()\n    lab.draw_scene(robot)"

LAB20_MORE = (
    # graded by test_check.py, beside the other labs' mutants
    Mutant(
        "lab20",
        "frame_cleared_white",
        (
            (
                "    create_mirror()\n" + CLEAR,
                "    create_mirror()\n    glClearColor(1, 1, 1, 1)\n" + CLEAR,
            ),
        ),
        {
            "passes": "glClearColor at line 98 (glClearColor(1, 1, 1, 1)) in display()",
            "capture_scene": "the capture is cleared to (1, 1, 1)",
        },
    ),
    Mutant(
        "lab20",
        "viewport_quarter",
        ((VIEWER_PASS, "    glViewport(0, 0, 128, 128)\n" + VIEWER_PASS),),
        {
            "passes": "glViewport at line 99 (glViewport(0, 0, 128, 128)) in display()",
            "capture_scene": "the capture is drawn in the viewport (0, 0, 128, 128)",
        },
    ),
    Mutant(
        "lab20",
        "viewer_by_hand",
        (
            (
                VIEWER_PASS,
                "    glMatrixMode(GL_PROJECTION)\n    glLoadIdentity()\n"
                "    gluPerspective(60, 1, 0.1, 100)\n    glMatrixMode(GL_MODELVIEW)\n"
                "    glLoadIdentity()\n    gluLookAt(12, 5, 9, -3.5, 1, -2, 0, 1, 0)\n"
                "    lab.draw_scene(robot)",
            ),
            (
                "from OpenGL.GLU import gluLookAt",
                "from OpenGL.GLU import gluLookAt, gluPerspective",
            ),
        ),
        {"passes": "field of view 60 degrees (the solution's: 45)"},
    ),
    Mutant(
        "lab20",
        "texcoords_in_world_units",
        ((QUAD, quad(((0, 0), (0, 8), (8, 8), (8, 0)))),),
        {"mirror_quad": "should be (0, 1): s = (z + 6) / 8, t = (y + 3) / 8"},
    ),
    Mutant(
        "lab20",
        "near_cuts_the_robot",
        (("glOrtho(Z0, Z1, Y0, Y1, 0, 15)", "glOrtho(Z0, Z1, Y0, Y1, 5, 15)"),),
        {
            "capture_camera": "the near and far planes 5, 15",
            "capture_scene": "judged once task 1 (capture_camera)",
        },
    ),
    Mutant(
        "lab20",
        "capture_upside_down",
        (
            (
                "gluLookAt(MIRROR_X, 0, 0, 0, 0, 0, 0, 1, 0)",
                "gluLookAt(MIRROR_X, 0, 0, 0, 0, 0, 0, -1, 0)",
            ),
        ),
        {"capture_camera": "upY = -1 (the solution's: 1)", "capture_scene": "upY = -1"},
    ),
)

ROUND_TWO_LAB20 = (
    # issue 39's slips: GL errors named by the precondition broken, then "not judged"
    Mutant(
        "lab20",
        "uniform_before_program",
        (
            (
                "    glUseProgram(lab.textureShader)\n    glUniform1i(lab.texSampler, 1)\n",
                "    glUniform1i(lab.texSampler, 1)\n    glUseProgram(lab.textureShader)\n",
            ),
        ),
        {
            "mirror_texture": "call glUseProgram(program) before setting its uniforms",
            "mirror_quad": "call glUseProgram(program) before setting its uniforms",
            "passes": "not judged: the frame stopped at render_mirror()",
        },
        cause="glUseProgram(program) before setting its uniforms",
    ),
    Mutant(
        "lab20",
        "sampler_enum",
        (("glUniform1i(lab.texSampler, 1)", "glUniform1i(lab.texSampler, GL_TEXTURE1)"),),
        {
            "mirror_texture": "the enum GL_TEXTURE1; a sampler takes the unit's number",
            "mirror_quad": "the enum GL_TEXTURE1",
            "passes": "not judged: the frame stopped at render_mirror()",
        },
        cause="a sampler takes the unit's number",
    ),
)

EQUIVALENT = (
    # the lab text's own calls: GL_CLAMP works in the compatibility profile
    Mutant("lab20", "legacy_gl_clamp", (("GL_CLAMP_TO_EDGE", "GL_CLAMP"),)),
    Mutant("lab20", "triangle_fan", (("glBegin(GL_QUADS)", "glBegin(GL_TRIANGLE_FAN)"),)),
    Mutant(
        "lab20",
        "two_triangles",
        (
            ("glBegin(GL_QUADS)", "glBegin(GL_TRIANGLES)"),
            (
                QUAD,
                quad(
                    (*RIGHT[:3], RIGHT[0], RIGHT[2], RIGHT[3]),
                    (*CORNERS[:3], CORNERS[0], CORNERS[2], CORNERS[3]),
                ),
            ),
        ),
    ),
    Mutant("lab20", "other_winding", ((QUAD, quad(RIGHT[::-1], CORNERS[::-1])),)),
    Mutant(
        "lab20",
        "vector_calls",
        ((QUAD, quad(RIGHT, vertex="glVertex3fv(({},))", texcoord="glTexCoord2fv({})")),),
    ),
    Mutant(
        "lab20",
        "look_at_along_x",
        (
            (
                "gluLookAt(MIRROR_X, 0, 0, 0, 0, 0, 0, 1, 0)",
                "gluLookAt(MIRROR_X, 0, 0, 1, 0, 0, 0, 1, 0)",
            ),
        ),
    ),
    Mutant(
        "lab20",
        "farther_far_plane",
        (("glOrtho(Z0, Z1, Y0, Y1, 0, 15)", "glOrtho(Z0, Z1, Y0, Y1, 0, 25)"),),
    ),
)

SPHEREMAP = (
    Mutant(
        "spheremap",
        "reflect_sign",
        (("return u - 2.0 * dot(n, u) * n;", "return 2.0 * dot(n, u) * n - u;"),),
        {"reflection": "wrong way", "side_by_side": "the shader's cone's half is judged once task"},
    ),
    Mutant(
        "spheremap",
        "reflect_no_two",
        (("return u - 2.0 * dot(n, u) * n;", "return u - dot(n, u) * n;"),),
        {"reflection": "factor 2", "side_by_side": "the shader's cone's half is judged once task"},
    ),
    Mutant(
        "spheremap",
        "st_no_plus_one",
        (("(r.z + 1.0) * (r.z + 1.0)", "r.z * r.z"),),
        {
            "sphere_coordinates": "the term 1 missing",
            "side_by_side": "the shader's cone's half is judged once task",
        },
    ),
    Mutant(
        "spheremap",
        "st_swapped",
        (("vec2(r.x / m + 0.5, r.y / m + 0.5)", "vec2(r.y / m + 0.5, r.x / m + 0.5)"),),
        {
            "sphere_coordinates": "swapped",
            "side_by_side": "the shader's cone's half is judged once task",
        },
    ),
    Mutant(
        "spheremap",
        "texgen_object_linear",
        (
            (
                "glTexGeni(GL_T, GL_TEXTURE_GEN_MODE, GL_SPHERE_MAP)",
                "glTexGeni(GL_T, GL_TEXTURE_GEN_MODE, GL_OBJECT_LINEAR)",
            ),
        ),
        {
            "texgen_setup": "GL_OBJECT_LINEAR",
            "side_by_side": "judged once task 3 (texgen_setup)",
        },
    ),
    Mutant(
        "spheremap",
        "texgen_left_on",
        (("    glDisable(GL_TEXTURE_GEN_S)\n    glDisable(GL_TEXTURE_GEN_T)\n", ""),),
        {"texgen_draw": "makes no glDisable(GL_TEXTURE_GEN_S)"},
    ),
    Mutant(
        "spheremap",
        "texgen_only_s",
        (("    glEnable(GL_TEXTURE_GEN_T)\n", ""),),
        {
            "texgen_draw": "makes no glEnable(GL_TEXTURE_GEN_T)",
            "side_by_side": "judged once task 4 (texgen_draw)",
        },
    ),
    Mutant(
        "spheremap",
        "cone_aspect_of_the_window",
        (
            (
                "    glViewport(0, 0, half, HEIGHT)\n    lab.set_viewer(half / HEIGHT)",
                "    glViewport(0, 0, half, HEIGHT)\n    lab.set_viewer()",
            ),
        ),
        {"side_by_side": "aspect 1.00 (the solution's: 0.50)"},
    ),
    Mutant(
        "spheremap",
        "texgen_reflection_map",
        (
            (
                "glTexGeni(GL_S, GL_TEXTURE_GEN_MODE, GL_SPHERE_MAP)",
                "glTexGeni(GL_S, GL_TEXTURE_GEN_MODE, GL_REFLECTION_MAP)",
            ),
        ),
        {
            "texgen_setup": "param = GL_REFLECTION_MAP (the solution's: GL_SPHERE_MAP)",
            "side_by_side": "judged once task 3 (texgen_setup)",
        },
    ),
    Mutant(
        "spheremap",
        "texgen_unit_1",
        (
            (
                'texgen on for it alone."""\n    glActiveTexture(GL_TEXTURE0 + UNIT)',
                'texgen on for it alone."""\n    glActiveTexture(GL_TEXTURE1)',
            ),
        ),
        {
            "texgen_draw": "(GL_TEXTURE1 was active, by glActiveTexture at line 52",
            "side_by_side": "judged once task 4 (texgen_draw)",
        },
    ),
)

ROUND_TWO_SPHEREMAP = (
    Mutant(
        "spheremap",
        "st_halfway_unnormalised",
        (
            (
                "    float m = 2.0 * sqrt(r.x * r.x + r.y * r.y + (r.z + 1.0) * (r.z + 1.0));\n"
                "    return vec2(r.x / m + 0.5, r.y / m + 0.5);",
                "    vec3 h = vec3(r.x, r.y, r.z + 1.0);\n"
                "    return vec2(h.x / 2.0 + 0.5, h.y / 2.0 + 0.5);",
            ),
        ),
        {
            "sphere_coordinates": "h not normalised",
            "side_by_side": "the shader's cone's half is judged once task",
        },
    ),
    Mutant(
        "spheremap",
        "st_halfway_vector_unnormalised",
        (
            (
                "    float m = 2.0 * sqrt(r.x * r.x + r.y * r.y + (r.z + 1.0) * (r.z + 1.0));\n"
                "    return vec2(r.x / m + 0.5, r.y / m + 0.5);",
                "    vec3 h = r + vec3(0.0, 0.0, 1.0);\n    return h.xy / 2.0 + 0.5;",
            ),
        ),
        {
            "sphere_coordinates": "h not normalised",
            "side_by_side": "the shader's cone's half is judged once task",
        },
    ),
    Mutant(
        "spheremap",
        "st_integer_half",
        (("vec2(r.x / m + 0.5, r.y / m + 0.5)", "vec2(r.x / m + 1/2, r.y / m + 1/2)"),),
        {
            "sphere_coordinates": "integer division",
            "side_by_side": "the shader's cone's half is judged once task",
        },
    ),
    Mutant(
        "spheremap",
        "reflect_clamped_dot",
        (("return u - 2.0 * dot(n, u) * n;", "return u - 2.0 * max(dot(n, u), 0.0) * n;"),),
        {
            "reflection": "n.u clamped to 0 or more",
            "side_by_side": "the shader's cone's half is judged once task",
        },
    ),
    Mutant(
        "spheremap",
        "glsl_syntax_error",
        (("return u - 2.0 * dot(n, u) * n;", "return u - 2.0 * dot(n, u) * n"),),
        {
            "reflection": "GLSL in SPHERE_MAP_GLSL line",
            "sphere_coordinates": "GLSL in SPHERE_MAP_GLSL line",
            "texgen_setup": "judged once task 4 (texgen_draw)",
            "texgen_draw": "not judged: the frame stopped at display()",
            "side_by_side": "not judged: display() stopped at line",
        },
    ),
)

FACE_LOOP = "FACE_SIZE, FACE_SIZE, 0\n        )\n        glActiveTexture(GL_TEXTURE0)\n"

CUBEMAP = (
    Mutant(
        "cubemap",
        "face_signed_max",
        (("    vec3 a = abs(r);", "    vec3 a = r;"),),
        {"face_selection": "largest signed"},
    ),
    Mutant(
        "cubemap",
        "st_swapped",
        (
            (
                "return vec2((sc / ma + 1.0) / 2.0, (tc / ma + 1.0) / 2.0);",
                "return vec2((tc / ma + 1.0) / 2.0, (sc / ma + 1.0) / 2.0);",
            ),
        ),
        {"face_coordinates": "swapped"},
    ),
    Mutant(
        "cubemap",
        "st_not_divided",
        (
            (
                "return vec2((sc / ma + 1.0) / 2.0, (tc / ma + 1.0) / 2.0);",
                "return vec2((sc + 1.0) / 2.0, (tc + 1.0) / 2.0);",
            ),
        ),
        {"face_coordinates": "the division by |ma| missing"},
    ),
    Mutant(
        "cubemap",
        "up_wrong",
        (
            ("((1, 0, 0), (0, -1, 0))", "((1, 0, 0), (0, 1, 0))"),
            ("((-1, 0, 0), (0, -1, 0))", "((-1, 0, 0), (0, 1, 0))"),
            ("((0, 0, 1), (0, -1, 0))", "((0, 0, 1), (0, 1, 0))"),
            ("((0, 0, -1), (0, -1, 0))", "((0, 0, -1), (0, 1, 0))"),
        ),
        {
            "capture_cameras": "the camera's up is (0, 1, 0); the solution's is (0, -1, 0)",
            "capture_copy": "judged once task 3 (capture_cameras)",
        },
    ),
    Mutant(
        "cubemap",
        "fov_60",
        (("gluPerspective(90, 1, 0.05, 50)", "gluPerspective(60, 1, 0.05, 50)"),),
        {
            "capture_cameras": "field of view 60 degrees",
            "capture_copy": "judged once task 3 (capture_cameras)",
        },
    ),
    Mutant(
        "cubemap",
        "faces_swapped_y",
        (
            ("((0, 1, 0), (0, 0, 1)),  # POSITIVE_Y", "((0, -1, 0), (0, 0, -1)),  # Y-"),
            ("((0, -1, 0), (0, 0, -1)),  # NEGATIVE_Y", "((0, 1, 0), (0, 0, 1)),  # Y+"),
        ),
        {
            "capture_cameras": "in the wrong order: the 3rd is the solution's 4th",
            "capture_copy": "judged once task 3 (capture_cameras)",
        },
    ),
    Mutant(
        "cubemap",
        "capture_after_camera",
        (
            ("    capture_cube()\n    glClear", "    glClear"),
            (
                "    lab.draw_scene()\n    lab.draw_sphere",
                "    lab.draw_scene()\n    capture_cube()\n    lab.draw_sphere",
            ),
        ),
        {"live_frame": "wrong order"},
    ),
    Mutant(
        "cubemap",
        "depth_not_cleared",
        (
            (
                "        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT)\n        glMatrixMode",
                "        glClear(GL_COLOR_BUFFER_BIT)\n        glMatrixMode",
            ),
        ),
        {"capture_copy": "mask = GL_COLOR_BUFFER_BIT (the solution's: GL_DEPTH_BUFFER_BIT"},
    ),
    Mutant(
        "cubemap",
        "viewport_in_loop",
        ((FACE_LOOP, FACE_LOOP + "        glViewport(0, 0, WIDTH, HEIGHT)\n"),),
        {
            "capture_cameras": "glViewport at line 104 (glViewport(0, 0, WIDTH, HEIGHT))",
            "capture_copy": "judged once task 3 (capture_cameras)",
        },
    ),
    Mutant(
        "cubemap",
        "cleared_black",
        (("    cx, cy, cz = CENTER\n", "    cx, cy, cz = CENTER\n    glClearColor(0, 0, 0, 1)\n"),),
        {
            "capture_copy": "glClearColor at line 88 (glClearColor(0, 0, 0, 1))",
            "live_frame": "glClearColor at line 88 (glClearColor(0, 0, 0, 1))",
        },
    ),
    Mutant(
        "cubemap",
        "no_projection_mode",
        (
            (
                "    glMatrixMode(GL_PROJECTION)\n    glLoadIdentity()\n    gluPerspective",
                "    glLoadIdentity()\n    gluPerspective",
            ),
        ),
        {
            "capture_cameras": "was applied to the modelview matrix",
            "capture_copy": "judged once task 3 (capture_cameras)",
        },
    ),
    Mutant(
        "cubemap",
        "near_3",
        (("gluPerspective(90, 1, 0.05, 50)", "gluPerspective(90, 1, 3, 50)"),),
        {"capture_cameras": "the near plane 3", "capture_copy": "task 3 (capture_cameras)"},
    ),
    Mutant(
        "cubemap",
        "mipmaps_before_faces",
        (
            (
                "    glTexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_MIN_FILTER, GL_LINEAR)\n",
                "    glTexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_MIN_FILTER, "
                "GL_LINEAR_MIPMAP_LINEAR)\n    glGenerateMipmap(GL_TEXTURE_CUBE_MAP)\n",
            ),
        ),
        {"live_frame": "mipmaps made before this frame's pictures"},
    ),
)

ROUND_TWO_CUBEMAP = (
    Mutant(
        "cubemap",
        "st_swapped_on_one_face",
        (
            (
                "else if (face == 2) { sc = r.x; tc = r.z; ma = abs(r.y); }",
                "else if (face == 2) { sc = r.z; tc = r.x; ma = abs(r.y); }",
            ),
        ),
        {"face_coordinates": "on the +Y face (face 2): sc and tc swapped"},
    ),
    Mutant(
        "cubemap",
        "st_integer_half",
        (
            (
                "return vec2((sc / ma + 1.0) / 2.0, (tc / ma + 1.0) / 2.0);",
                "return vec2(1/2 * (sc / ma + 1.0), 1/2 * (tc / ma + 1.0));",
            ),
        ),
        {"face_coordinates": "integer division"},
    ),
)

PROBED_SLIPS = (
    # slips the value probe names (mirrorlab/labs/trusted/probe.py): each gives, on the
    # cone's or the sphere's own inputs, the numbers of another slip or of none listed
    Mutant(
        "spheremap",
        "reflect_abs_dot",
        (("return u - 2.0 * dot(n, u) * n;", "return u - 2.0 * abs(dot(n, u)) * n;"),),
        {"reflection": "abs(n.u)", "side_by_side": "the shader's cone's half is judged once task"},
        cause="abs(n.u): the sign of n.u matters",
    ),
    Mutant(
        "spheremap",
        "reflect_clamped_dot_clamp",
        (("return u - 2.0 * dot(n, u) * n;", "return u - 2.0 * clamp(dot(n, u), 0.0, 1.0) * n;"),),
        {
            "reflection": "n.u clamped to 0 or more",
            "side_by_side": "the shader's cone's half is judged once task",
        },
        cause="n.u clamped to 0 or more (clamp or max)",
    ),
    Mutant(
        "spheremap",
        "st_minus_one",
        (("(r.z + 1.0) * (r.z + 1.0)", "(r.z - 1.0) * (r.z - 1.0)"),),
        {
            "sphere_coordinates": "the sign of rz flipped",
            "side_by_side": "the shader's cone's half is judged once task",
        },
        cause="m = 2 sqrt(rx^2 + ry^2 + (-rz + 1)^2)",
    ),
    Mutant(
        "spheremap",
        "st_halfway_unnormalised_named_h",
        (
            (
                "    float m = 2.0 * sqrt(r.x * r.x + r.y * r.y + (r.z + 1.0) * (r.z + 1.0));\n"
                "    return vec2(r.x / m + 0.5, r.y / m + 0.5);",
                "    vec3 h = r;\n    h.z += 1.0;\n    return 0.5 * h.xy + vec2(0.5);",
            ),
        ),
        {
            "sphere_coordinates": "h not normalised",
            "side_by_side": "the shader's cone's half is judged once task",
        },
        cause="h not normalised",
    ),
    Mutant(
        "cubemap",
        "face_opposite_sign",
        (
            ("return r.x >= 0.0 ? 0 : 1;", "return r.x >= 0.0 ? 1 : 0;"),
            ("return r.y >= 0.0 ? 2 : 3;", "return r.y >= 0.0 ? 3 : 2;"),
            ("return r.z >= 0.0 ? 4 : 5;", "return r.z >= 0.0 ? 5 : 4;"),
        ),
        {"face_selection": "the opposite sign"},
        cause="the right axis but the opposite sign",
    ),
    Mutant(
        "cubemap",
        "st_signed_major",
        (
            (
                "    if (face == 0) { sc = -r.z; tc = -r.y; ma = abs(r.x); }\n"
                "    else if (face == 1) { sc = r.z; tc = -r.y; ma = abs(r.x); }\n"
                "    else if (face == 2) { sc = r.x; tc = r.z; ma = abs(r.y); }\n"
                "    else if (face == 3) { sc = r.x; tc = -r.z; ma = abs(r.y); }\n"
                "    else if (face == 4) { sc = r.x; tc = -r.y; ma = abs(r.z); }\n"
                "    else { sc = -r.x; tc = -r.y; ma = abs(r.z); }",
                "    if (face == 0) { sc = -r.z; tc = -r.y; ma = r.x; }\n"
                "    else if (face == 1) { sc = r.z; tc = -r.y; ma = r.x; }\n"
                "    else if (face == 2) { sc = r.x; tc = r.z; ma = r.y; }\n"
                "    else if (face == 3) { sc = r.x; tc = -r.z; ma = r.y; }\n"
                "    else if (face == 4) { sc = r.x; tc = -r.y; ma = r.z; }\n"
                "    else { sc = -r.x; tc = -r.y; ma = r.z; }",
            ),
        ),
        {"face_coordinates": "abs() missing around ma"},
        cause="abs() missing around ma",
    ),
    Mutant(
        "cubemap",
        "st_signed_major_on_one_face",
        (
            (
                "else if (face == 1) { sc = r.z; tc = -r.y; ma = abs(r.x); }",
                "else if (face == 1) { sc = r.z; tc = -r.y; ma = r.x; }",
            ),
        ),
        {"face_coordinates": "on the -X face (face 1), ma: abs() missing around rx"},
        cause="on the -X face (face 1), ma: abs() missing around rx",
    ),
    Mutant(
        "cubemap",
        "st_divided_by_length",
        (
            (
                "return vec2((sc / ma + 1.0) / 2.0, (tc / ma + 1.0) / 2.0);",
                "return vec2((sc / length(r) + 1.0) / 2.0, (tc / length(r) + 1.0) / 2.0);",
            ),
        ),
        {"face_coordinates": "divided by the length of r where the formula divides by |ma|"},
        cause="divided by the length of r",
    ),
)

REFLECT = "return u - 2.0 * dot(n, u) * n;"
HALF_ST = "vec2(r.x / m + 0.5, r.y / m + 0.5)"
M_LINE = "float m = 2.0 * sqrt(r.x * r.x + r.y * r.y + (r.z + 1.0) * (r.z + 1.0));"
CUBE_ST = "return vec2((sc / ma + 1.0) / 2.0, (tc / ma + 1.0) / 2.0);"
CUBE_TABLE = (
    "    if (face == 0) { sc = -r.z; tc = -r.y; ma = abs(r.x); }\n"
    "    else if (face == 1) { sc = r.z; tc = -r.y; ma = abs(r.x); }\n"
    "    else if (face == 2) { sc = r.x; tc = r.z; ma = abs(r.y); }\n"
    "    else if (face == 3) { sc = r.x; tc = -r.z; ma = abs(r.y); }\n"
    "    else if (face == 4) { sc = r.x; tc = -r.y; ma = abs(r.z); }\n"
    "    else { sc = -r.x; tc = -r.y; ma = abs(r.z); }"
)

PROBED_VARIANTS = (
    # issue 45's GLSL slips, each named by the variant of the formula its values follow
    # (mirrorlab/labs/trusted/formulas.py), not by a rule written for it
    Mutant(
        "spheremap",
        "reflect_scales_u",
        ((REFLECT, "return u - 2.0 * dot(n, u) * u;"),),
        {
            "reflection": "u where the formula has n",
            "side_by_side": "the shader's cone's half is judged once task",
        },
        cause="r = u - 2 (n.u) u",
    ),
    Mutant(
        "spheremap",
        "reflect_dot_squared",
        ((REFLECT, "return u - 2.0 * dot(n, u) * dot(n, u) * n;"),),
        {
            "reflection": "n.u squared",
            "side_by_side": "the shader's cone's half is judged once task",
        },
    ),
    Mutant(
        "spheremap",
        "st_m_without_square_root",
        ((M_LINE, M_LINE.replace("2.0 * sqrt(", "2.0 * (")),),
        {
            "sphere_coordinates": "without its square root",
            "side_by_side": "the shader's cone's half is judged once task",
        },
    ),
    Mutant(
        "spheremap",
        "st_half_applied_twice",
        ((HALF_ST, "vec2(0.5 * r.x / m + 0.5, 0.5 * r.y / m + 0.5)"),),
        {
            "sphere_coordinates": "1/2 applied twice",
            "side_by_side": "the shader's cone's half is judged once task",
        },
    ),
    Mutant(
        "spheremap",
        "st_square_without_parentheses",
        (("(r.z + 1.0) * (r.z + 1.0)", "r.z + 1.0 * r.z + 1.0"),),
        {
            "sphere_coordinates": "without its parentheses",
            "side_by_side": "the shader's cone's half is judged once task",
        },
    ),
    Mutant(
        "spheremap",
        "st_a_mistake_nobody_listed",
        ((HALF_ST, "vec2(r.x * r.y + 0.5, r.y / m + 0.5)"),),
        {
            "sphere_coordinates": "a mistake the checker does not know",
            "side_by_side": "the shader's cone's half is judged once task",
        },
    ),
    Mutant(
        "cubemap",
        "face_comparisons_chained",
        (("if (a.x >= a.y && a.x >= a.z)", "if (a.x >= a.y && a.y >= a.z)"),),
        {"face_selection": "the comparisons are chained"},
    ),
    Mutant(
        "cubemap",
        "face_numbered_by_sign",
        (
            ("return r.x >= 0.0 ? 0 : 1;", "return r.x >= 0.0 ? 0 : 3;"),
            ("return r.y >= 0.0 ? 2 : 3;", "return r.y >= 0.0 ? 1 : 4;"),
            ("return r.z >= 0.0 ? 4 : 5;", "return r.z >= 0.0 ? 2 : 5;"),
        ),
        {"face_selection": "numbered +X, +Y, +Z, -X, -Y, -Z"},
    ),
    Mutant(
        "cubemap",
        "st_ma_rx_on_every_face",
        ((CUBE_TABLE, CUBE_TABLE.replace("abs(r.y)", "abs(r.x)").replace("abs(r.z)", "abs(r.x)")),),
        {"face_coordinates": "every face takes ma of the +X face"},
    ),
    Mutant(
        "cubemap",
        "st_half_applied_twice",
        ((CUBE_ST, "return vec2((sc / ma + 1.0) / 2.0 / 2.0, (tc / ma + 1.0) / 2.0 / 2.0);"),),
        {"face_coordinates": "1/2 applied twice"},
    ),
    Mutant(
        "cubemap",
        "st_component_swapped_on_one_face",
        (("if (face == 0) { sc = -r.z;", "if (face == 0) { sc = -r.x;"),),
        {"face_coordinates": "on the +X face (face 0), sc: rx where the formula has rz"},
    ),
)

GLSL_EQUIVALENT = (
    # right forms the handout allows, which the probe must pass on every input it draws
    Mutant("spheremap", "reflect_builtin", ((REFLECT, "return reflect(u, n);"),)),
    Mutant(
        "spheremap",
        "st_unit_length_identity",
        ((M_LINE, "float m = 2.0 * sqrt(2.0 * (r.z + 1.0));"),),
    ),
    Mutant(
        "spheremap",
        "st_normalised_halfway",
        (
            (
                M_LINE + "\n    return " + HALF_ST + ";",
                "vec3 h = normalize(r + vec3(0.0, 0.0, 1.0));\n    return h.xy * 0.5 + 0.5;",
            ),
        ),
    ),
    Mutant(
        "cubemap",
        "face_strict_comparisons",
        (
            ("if (a.x >= a.y && a.x >= a.z)", "if (a.x > a.y && a.x > a.z)"),
            ("if (a.y >= a.z)", "if (a.y > a.z)"),
        ),
    ),
)

CUBE_EQUIVALENT = (
    Mutant(
        "cubemap",
        "mipmaps_after_faces",
        (
            (
                "    glTexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_MIN_FILTER, GL_LINEAR)\n",
                "    glTexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_MIN_FILTER, "
                "GL_LINEAR_MIPMAP_LINEAR)\n",
            ),
            (
                "    glViewport(0, 0, WIDTH, HEIGHT)\n\n\ndef display",
                "    glActiveTexture(GL_TEXTURE1)\n    glBindTexture(GL_TEXTURE_CUBE_MAP, "
                "cube_texture)\n    glGenerateMipmap(GL_TEXTURE_CUBE_MAP)\n"
                "    glActiveTexture(GL_TEXTURE0)\n    glViewport(0, 0, WIDTH, HEIGHT)\n\n\n"
                "def display",
            ),
        ),
    ),
    Mutant(
        "cubemap",
        "other_near_far",
        (("gluPerspective(90, 1, 0.05, 50)", "gluPerspective(90, 1, 0.2, 100)"),),
    ),
)

MUTANTS = (*LAB20, *SPHEREMAP, *CUBEMAP)
ROUND_TWO = (*ROUND_TWO_LAB20, *ROUND_TWO_SPHEREMAP, *ROUND_TWO_CUBEMAP)
EVERY_MUTANT = (*MUTANTS, *LAB20_MORE, *ROUND_TWO, *PROBED_SLIPS, *PROBED_VARIANTS)
"""Every mistake of the suite; each one's first failing task names its cause."""


def write_mutants(folder: Path, mutants=MUTANTS) -> dict[str, Mutant]:
    """Write each mutant as ``folder/<lab>_<name>.py``; returns file stem -> mutant."""
    folder.mkdir(parents=True, exist_ok=True)
    written = {}
    for mutant in mutants:
        stem = f"{mutant.lab}_{mutant.name}"
        (folder / f"{stem}.py").write_text(mutant.source())
        written[stem] = mutant
    return written


def problems(expected_fails: dict[str, str], verdicts: dict[str, tuple[bool, str]]) -> list[str]:
    """What differs between a mutant's expected failures and the ``verdicts`` (task id ->
    (passed, hint)) the checker gave; empty when they agree."""
    found = []
    for task, (passed, hint) in verdicts.items():
        if task in expected_fails:
            if passed:
                found.append(f"{task} passed, expected to fail with {expected_fails[task]!r}")
            elif expected_fails[task] not in hint:
                found.append(f"{task} hint {hint!r} lacks {expected_fails[task]!r}")
        elif not passed:
            found.append(f"{task} failed unexpectedly: {hint}")
    return found


def texcoords_after_vertices() -> str:
    """The mirror quad with each glTexCoord2f after its glVertex3f."""
    lines = QUAD.splitlines(keepends=True)
    return "".join(lines[i + 1] + lines[i] for i in range(0, len(lines), 2))


ENVIRONMENT_PARAMETERS = (
    "    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_LINEAR)\n"
    "    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_LINEAR)\n"
    "    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_S, GL_CLAMP_TO_EDGE)\n"
    "    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE)\n"
)
BIND_ENVIRONMENT = (
    "    glActiveTexture(GL_TEXTURE1)\n    glBindTexture(GL_TEXTURE_2D, tex_ids[ENVIRONMENT])\n"
)
LAB20_COPY = (
    BIND_ENVIRONMENT + "    glCopyTexImage2D(GL_TEXTURE_2D, 0, GL_RGB, 0, 0, WIDTH, HEIGHT, 0)\n"
)
TEXGEN_ON = "    glEnable(GL_TEXTURE_GEN_S)\n    glEnable(GL_TEXTURE_GEN_T)\n"
CUBE_COPY = (
    "        glActiveTexture(GL_TEXTURE1)\n"
    "        glBindTexture(GL_TEXTURE_CUBE_MAP, cube_texture)\n"
    "        glCopyTexImage2D(\n"
    "            GL_TEXTURE_CUBE_MAP_POSITIVE_X + face, 0, GL_RGB, 0, 0, FACE_SIZE, FACE_SIZE, 0\n"
    "        )\n"
    "        glActiveTexture(GL_TEXTURE0)\n"
)

TRACE_SLIPS = (
    # issue 45's mistakes by pattern, each a slip a student makes following the handout;
    # the hint must come from the call trace (the call, its line, why it took no effect)
    Mutant(
        "lab20",
        "texcoord_after_vertex",
        ((QUAD, texcoords_after_vertices()),),
        {"mirror_quad": "a vertex takes the texture coordinates set before it"},
    ),
    Mutant(
        "lab20",
        "parameters_on_metal",
        (
            (
                BIND_ENVIRONMENT + "    glTexImage2D",
                ENVIRONMENT_PARAMETERS + BIND_ENVIRONMENT + "    glTexImage2D",
            ),
            (
                "    # TODO 4: filters and wrapping of ENVIRONMENT (no mipmaps)\n"
                + ENVIRONMENT_PARAMETERS,
                "",
            ),
        ),
        {"environment_texture": "set the parameters of tex_ids[METAL]"},
    ),
    Mutant(
        "lab20",
        "copy_before_draw",
        (
            (
                "    lab.draw_scene(robot)\n    # TODO 3: copy the framebuffer into ENVIRONMENT\n"
                + LAB20_COPY,
                "    # TODO 3: copy the framebuffer into ENVIRONMENT\n"
                + LAB20_COPY
                + "    lab.draw_scene(robot)\n",
            ),
        ),
        {
            "capture_scene": "a copy takes only what was drawn before it",
            "capture_copy": "a copy takes only what was drawn before it",
        },
    ),
    Mutant(
        "lab20",
        "luminance_copy",
        (
            (
                "GL_TEXTURE_2D, 0, GL_RGB, 0, 0, WIDTH, HEIGHT, 0)",
                "GL_TEXTURE_2D, 0, GL_LUMINANCE, 0, 0, WIDTH, HEIGHT, 0)",
            ),
        ),
        {"capture_copy": "internalformat = GL_LUMINANCE (the solution's: GL_RGB)"},
    ),
    Mutant(
        "lab20",
        "render_mirror_never_called",
        (("    # TODO 8: pass 2\n    render_mirror()\n", "    # TODO 8: pass 2\n"),),
        {
            "mirror_texture": "render_mirror() is never called",
            "mirror_quad": "render_mirror() is never called",
            "passes": "render_mirror() is never called",
        },
    ),
    Mutant(
        "lab20",
        "sampler_on_unit_0",
        (("glUniform1i(lab.texSampler, 1)", "glUniform1i(lab.texSampler, 0)"),),
        {"mirror_texture": "v0 = 0 (the solution's: 1)"},
    ),
    Mutant(
        "lab20",
        "no_texture_shader",
        (("    glUseProgram(lab.textureShader)\n    glUniform1i(lab.texSampler, 1)\n", ""),),
        {"mirror_texture": "makes no glUseProgram(lab.textureShader)"},
    ),
    Mutant(
        "lab20",
        "look_at_off_axis",
        (
            (
                "gluLookAt(MIRROR_X, 0, 0, 0, 0, 0, 0, 1, 0)",
                "gluLookAt(MIRROR_X, 0, 0, 0, 0, 5, 0, 1, 0)",
            ),
        ),
        {"capture_camera": "centerZ = 5 (the solution's: 0)", "capture_scene": "centerZ = 5"},
    ),
    Mutant(
        "lab20",
        "ortho_top_and_bottom_swapped",
        (("glOrtho(Z0, Z1, Y0, Y1, 0, 15)", "glOrtho(Z0, Z1, Y1, Y0, 0, 15)"),),
        {
            "capture_camera": "bottom, top = 5, -3 (the solution's: -3, 5)",
            "capture_scene": "bottom, top = 5, -3",
        },
    ),
    Mutant(
        "lab20",
        "look_at_on_the_projection",
        (("    glMatrixMode(GL_MODELVIEW)\n    glLoadIdentity()\n    gluLookAt", "    gluLookAt"),),
        {
            "capture_camera": (
                "gluLookAt at line 60 (gluLookAt(MIRROR_X, 0, 0, 0, 0, 0, 0, 1, 0)) "
                "was applied to the projection matrix"
            ),
            "capture_scene": "was applied to the projection matrix",
        },
    ),
    Mutant(
        "lab20",
        "viewer_before_capture",
        (
            (
                "    create_mirror()\n" + CLEAR + "    lab.set_viewer()\n",
                "    lab.set_viewer()\n    create_mirror()\n" + CLEAR,
            ),
        ),
        {
            "mirror_quad": "judged once task 8 (passes)",
            "passes": "lab.set_viewer at line 97 (lab.set_viewer()) comes before create_mirror()",
        },
    ),
    Mutant(
        "lab20",
        "filter_by_number",
        (("GL_TEXTURE_MAG_FILTER, GL_LINEAR)", "GL_TEXTURE_MAG_FILTER, 0x2600)"),),
        {"environment_texture": "param = GL_NEAREST (the solution's: GL_LINEAR)"},
    ),
    Mutant(
        "lab20",
        "quad_as_a_line_loop",
        (("glBegin(GL_QUADS)", "glBegin(GL_LINE_LOOP)"),),
        {  # lines are a channel lab 20 leaves closed: refused, named by the mode
            "mirror_texture": "glBegin with GL_LINE_LOOP",
            "mirror_quad": "glBegin with GL_LINE_LOOP",
            "passes": "not judged",
        },
    ),
    # the sphere-map lab
    Mutant(
        "spheremap",
        "texgen_enabled_in_setup",
        (
            (
                "    glTexGeni(GL_T, GL_TEXTURE_GEN_MODE, GL_SPHERE_MAP)\n",
                "    glTexGeni(GL_T, GL_TEXTURE_GEN_MODE, GL_SPHERE_MAP)\n" + TEXGEN_ON,
            ),
            (
                "    glBindTexture(GL_TEXTURE_2D, launch)\n" + TEXGEN_ON,
                "    glBindTexture(GL_TEXTURE_2D, launch)\n",
            ),
        ),
        {
            "texgen_draw": "runs once, in setup_texgen() before the first frame",
            "side_by_side": "judged once task 4 (texgen_draw)",
        },
    ),
    Mutant(
        "spheremap",
        "texgen_function_never_called",
        (
            (
                '    if SHADER_SIDE == "left":\n        draw_cone_texgen()',
                '    if SHADER_SIDE == "left":\n        lab.draw_cone_fixed_function()',
            ),
            (
                "    else:\n        draw_cone_texgen()",
                "    else:\n        lab.draw_cone_fixed_function()",
            ),
        ),
        {
            "texgen_draw": "draw_cone_texgen() is never called",
            "side_by_side": "draw_cone_texgen() is never called",
        },
    ),
    Mutant(
        "spheremap",
        "texgen_set_up_on_unit_1",
        (
            (
                'texgen makes s and t by the sphere-map formula, for the variant\'s unit."""\n'
                "    glActiveTexture(GL_TEXTURE0 + UNIT)",
                'texgen makes s and t by the sphere-map formula, for the variant\'s unit."""\n'
                "    glActiveTexture(GL_TEXTURE1)",
            ),
        ),
        {
            "texgen_setup": "acted on texture unit 1",
            "side_by_side": "judged once task 3 (texgen_setup)",
        },
    ),
    Mutant(
        "spheremap",
        "launch_not_bound",
        (("    glBindTexture(GL_TEXTURE_2D, launch)\n", ""),),
        {"texgen_draw": "makes no glBindTexture(GL_TEXTURE_2D, launch)"},
    ),
    Mutant(
        "spheremap",
        "texgen_s_twice",
        (
            (
                "glTexGeni(GL_T, GL_TEXTURE_GEN_MODE, GL_SPHERE_MAP)",
                "glTexGeni(GL_S, GL_TEXTURE_GEN_MODE, GL_SPHERE_MAP)",
            ),
        ),
        {
            "texgen_setup": "coord = GL_S (the solution's: GL_T)",
            "side_by_side": "judged once task 3 (texgen_setup)",
        },
    ),
    Mutant(
        "spheremap",
        "texgen_coordinate_as_capability",
        (
            (
                "glTexGeni(GL_S, GL_TEXTURE_GEN_MODE, GL_SPHERE_MAP)",
                "glTexGeni(GL_TEXTURE_GEN_S, GL_TEXTURE_GEN_MODE, GL_SPHERE_MAP)",
            ),
        ),
        {
            "texgen_setup": (
                "GL_TEXTURE_GEN_S is a capability (glEnable's); glTexGeni takes GL_S, "
                "GL_T, GL_R or GL_Q"
            ),
            "side_by_side": "judged once task 3 (texgen_setup)",
        },
    ),
    Mutant(
        "spheremap",
        "enable_a_coordinate",
        (("    glEnable(GL_TEXTURE_GEN_T)\n", "    glEnable(GL_T)\n"),),
        {
            "texgen_setup": "judged once task 4 (texgen_draw)",
            "texgen_draw": "GL_T is a texture coordinate (glTexGen's); glEnable takes",
            "side_by_side": "not judged",
        },
    ),
    Mutant(
        "spheremap",
        "cones_swapped",
        (
            (
                '    if SHADER_SIDE == "left":\n'
                "        lab.draw_cone_shader(SPHERE_MAP_GLSL, launch)\n"
                "    else:\n"
                "        draw_cone_texgen()",
                '    if SHADER_SIDE == "left":\n'
                "        draw_cone_texgen()\n"
                "    else:\n"
                "        lab.draw_cone_shader(SPHERE_MAP_GLSL, launch)",
            ),
            (
                '    if SHADER_SIDE == "left":\n'
                "        draw_cone_texgen()\n"
                "    else:\n"
                "        lab.draw_cone_shader(SPHERE_MAP_GLSL, launch)\n"
                "    glViewport(0, 0, WIDTH, HEIGHT)",
                '    if SHADER_SIDE == "left":\n'
                "        lab.draw_cone_shader(SPHERE_MAP_GLSL, launch)\n"
                "    else:\n"
                "        draw_cone_texgen()\n"
                "    glViewport(0, 0, WIDTH, HEIGHT)",
            ),
        ),
        {"side_by_side": "where the solution draws lab.draw_cone_shader"},
    ),
    Mutant(
        "spheremap",
        "right_viewport_forgotten",
        (("    glViewport(half, 0, WIDTH - half, HEIGHT)\n", ""),),
        {"side_by_side": "makes no glViewport(128, 0, 128, 256)"},
    ),
    Mutant(
        "spheremap",
        "texgen_off_before_the_cone",
        (
            (
                "    lab.draw_cone_fixed_function()\n    glDisable(GL_TEXTURE_GEN_S)\n    "
                "glDisable(GL_TEXTURE_GEN_T)\n",
                "    glDisable(GL_TEXTURE_GEN_S)\n    glDisable(GL_TEXTURE_GEN_T)\n    "
                "lab.draw_cone_fixed_function()\n",
            ),
        ),
        {
            "texgen_draw": (
                "lab.draw_cone_fixed_function at line 58 "
                "(lab.draw_cone_fixed_function()) comes after glDisable"
            ),
            "side_by_side": "judged once task 4 (texgen_draw)",
        },
    ),
    Mutant(
        "spheremap",
        "texgen_t_normal_map",
        (
            (
                "glTexGeni(GL_T, GL_TEXTURE_GEN_MODE, GL_SPHERE_MAP)",
                "glTexGeni(GL_T, GL_TEXTURE_GEN_MODE, GL_NORMAL_MAP)",
            ),
        ),
        {
            "texgen_setup": "param = GL_NORMAL_MAP (the solution's: GL_SPHERE_MAP)",
            "side_by_side": "judged once task 3 (texgen_setup)",
        },
    ),
    Mutant(
        "spheremap",
        "right_backdrop_forgotten",
        (
            (
                "    lab.set_viewer((WIDTH - half) / HEIGHT)\n    lab.draw_backdrop()\n",
                "    lab.set_viewer((WIDTH - half) / HEIGHT)\n",
            ),
        ),
        {"side_by_side": "needs one more lab.draw_backdrop"},
    ),
    # the cube-map lab
    Mutant(
        "cubemap",
        "copies_before_each_face",
        (("        lab.draw_scene()\n" + CUBE_COPY, CUBE_COPY + "        lab.draw_scene()\n"),),
        {"capture_copy": "a copy takes only what was drawn before it"},
    ),
    Mutant(
        "cubemap",
        "face_target_off_by_one",
        (
            (
                "GL_TEXTURE_CUBE_MAP_POSITIVE_X + face, 0, GL_RGB, 0, 0",
                "GL_TEXTURE_CUBE_MAP_POSITIVE_X + face + 1, 0, GL_RGB, 0, 0",
            ),
        ),
        {
            "capture_copy": "GL_TEXTURE_CUBE_MAP_NEGATIVE_Z + 1 is past the last face",
            "capture_cameras": "GL_TEXTURE_CUBE_MAP_NEGATIVE_Z + 1 is past the last face",
            "live_frame": "not judged",
        },
    ),
    Mutant(
        "cubemap",
        "every_face_into_negative_x",
        (
            (
                "GL_TEXTURE_CUBE_MAP_POSITIVE_X + face, 0, GL_RGB, 0, 0",
                "GL_TEXTURE_CUBE_MAP_NEGATIVE_X, 0, GL_RGB, 0, 0",
            ),
        ),
        {
            "capture_copy": (
                "target = GL_TEXTURE_CUBE_MAP_NEGATIVE_X (the solution's: "
                "GL_TEXTURE_CUBE_MAP_POSITIVE_X)"
            )
        },
    ),
    Mutant(
        "cubemap",
        "capture_after_the_sphere",
        (
            ("    capture_cube()\n    glClear", "    glClear"),
            (
                "    lab.draw_sphere(CUBE_MAP_GLSL, cube_texture)",
                "    lab.draw_sphere(CUBE_MAP_GLSL, cube_texture)\n    capture_cube()",
            ),
        ),
        {"live_frame": "in the wrong order"},
    ),
    Mutant(
        "cubemap",
        "faces_of_aspect_2",
        (("gluPerspective(90, 1, 0.05, 50)", "gluPerspective(90, 2, 0.05, 50)"),),
        {
            "capture_cameras": "aspect = 2 (the solution's: 1)",
            "capture_copy": "judged once task 3 (capture_cameras)",
        },
    ),
    Mutant(
        "cubemap",
        "far_plane_5",
        (("gluPerspective(90, 1, 0.05, 50)", "gluPerspective(90, 1, 0.05, 5)"),),
        {
            "capture_cameras": "the far plane 5 stops short",
            "capture_copy": "judged once task 3 (capture_cameras)",
        },
    ),
    Mutant(
        "cubemap",
        "luminance_faces",
        (
            (
                "GL_TEXTURE_CUBE_MAP_POSITIVE_X + face, 0, GL_RGB, 0, 0",
                "GL_TEXTURE_CUBE_MAP_POSITIVE_X + face, 0, GL_LUMINANCE, 0, 0",
            ),
        ),
        {"capture_copy": "internalformat = GL_LUMINANCE (the solution's: GL_RGB)"},
    ),
    Mutant(
        "cubemap",
        "copy_into_level_1",
        (
            (
                "GL_TEXTURE_CUBE_MAP_POSITIVE_X + face, 0, GL_RGB, 0, 0",
                "GL_TEXTURE_CUBE_MAP_POSITIVE_X + face, 1, GL_RGB, 0, 0",
            ),
        ),
        {"capture_copy": "level = 1 (the solution's: 0)"},
    ),
    Mutant(
        "cubemap",
        "face_viewport_forgotten",
        (("    glViewport(0, 0, FACE_SIZE, FACE_SIZE)\n", ""),),
        {
            "capture_cameras": "makes no glViewport(0, 0, 128, 128)",
            "capture_copy": "judged once task 3 (capture_cameras)",
        },
    ),
    Mutant(
        "cubemap",
        "cleared_once_for_six_faces",
        (
            (
                "    gluPerspective(90, 1, 0.05, 50)\n",
                "    gluPerspective(90, 1, 0.05, 50)\n    glClear(GL_COLOR_BUFFER_BIT | "
                "GL_DEPTH_BUFFER_BIT)\n",
            ),
            (
                "        glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT)\n        glMatrixMode",
                "        glMatrixMode",
            ),
        ),
        {"capture_copy": "glClear"},
    ),
    Mutant(
        "cubemap",
        "identity_outside_the_loop",
        (
            (
                "    for face, ((dx, dy, dz), (ux, uy, uz)) in enumerate(FACE_VIEWS):\n",
                "    glMatrixMode(GL_MODELVIEW)\n    glLoadIdentity()\n    for face, ((dx, dy, "
                "dz), (ux, uy, uz)) in enumerate(FACE_VIEWS):\n",
            ),
            (
                "        glMatrixMode(GL_MODELVIEW)\n        glLoadIdentity()\n        gluLookAt",
                "        gluLookAt",
            ),
        ),
        {
            "capture_cameras": "needs glLoadIdentity",
            "capture_copy": "judged once task 3 (capture_cameras)",
        },
    ),
    Mutant(
        "cubemap",
        "mipmap_filter_without_mipmaps",
        (
            (
                "glTexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_MIN_FILTER, GL_LINEAR)",
                "glTexParameteri(GL_TEXTURE_CUBE_MAP, GL_TEXTURE_MIN_FILTER, "
                "GL_LINEAR_MIPMAP_LINEAR)",
            ),
        ),
        {"live_frame": "wants mipmaps it does not have"},
    ),
    Mutant(
        "cubemap",
        "background_colour_forgotten",
        (("    glClearColor(*lab.BACKGROUND, 1.0)\n", ""),),
        {
            "capture_copy": "the 1st face is cleared to (0, 0, 0)",
            "live_frame": "makes no glClearColor(0.55, 0.7, 0.9, 1)",
        },
    ),
    # degenerate input, named by the argument that makes it so (issue 45, item 3)
    Mutant(
        "lab20",
        "look_at_itself",
        (
            (
                "gluLookAt(MIRROR_X, 0, 0, 0, 0, 0, 0, 1, 0)",
                "gluLookAt(MIRROR_X, 0, 0, MIRROR_X, 0, 0, 0, 1, 0)",
            ),
        ),
        {
            "capture_camera": "eye and center are both (-7, 0, 0): the camera has no direction",
            "capture_scene": "eye and center are both (-7, 0, 0)",
        },
    ),
    Mutant(
        "lab20",
        "ortho_without_width",
        (("glOrtho(Z0, Z1, Y0, Y1, 0, 15)", "glOrtho(Z0, Z0, Y0, Y1, 0, 15)"),),
        {
            "capture_camera": "left = right = -6: the box has no width",
            "capture_scene": "left = right = -6",
            "capture_copy": "left = right = -6",
            "base_texture": "stopped at create_mirror()",
            "mirror_texture": "stopped at create_mirror()",
            "mirror_quad": "stopped at create_mirror()",
            "passes": "stopped at create_mirror()",
        },
    ),
    Mutant(
        "cubemap",
        "far_plane_nan",
        (("gluPerspective(90, 1, 0.05, 50)", 'gluPerspective(90, 1, 0.05, float("nan"))'),),
        {
            "capture_cameras": "gluPerspective() argument 4 (zFar) is nan (not a number)",
            "capture_copy": "argument 4 (zFar) is nan",
            "live_frame": "not judged",
        },
    ),
    Mutant(
        "lab20",
        "copy_into_the_existing_image",
        (
            (
                "glCopyTexImage2D(GL_TEXTURE_2D, 0, GL_RGB, 0, 0, WIDTH, HEIGHT, 0)",
                "glCopyTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, 0, 0, WIDTH, HEIGHT)",
            ),
        ),
        {  # partial copies are a channel lab 20 leaves closed (main's channels): refused
            "capture_camera": "glCopyTexSubImage2D is not one of the OpenGL calls",
            "capture_scene": "glCopyTexSubImage2D is not one of the OpenGL calls",
            "capture_copy": "glCopyTexSubImage2D is not one of the OpenGL calls",
            "mirror_texture": "not judged",
            "mirror_quad": "not judged",
            "passes": "not judged",
        },
    ),
)

TRACE_EQUIVALENT = (
    # other forms the handouts allow: each passes every task
    Mutant(
        "lab20",
        "rgba_copy",
        (("0, GL_RGB, 0, 0, WIDTH, HEIGHT, 0)", "0, GL_RGBA, 0, 0, WIDTH, HEIGHT, 0)"),),
    ),
    Mutant(
        "spheremap",
        "builtin_reflect",
        (("return u - 2.0 * dot(n, u) * n;", "return reflect(u, n);"),),
    ),
    Mutant("cubemap", "rgba_faces", (("face, 0, GL_RGB, 0, 0", "face, 0, GL_RGBA, 0, 0"),)),
)

HELD_OUT = (
    # written after the hints' module was done, graded before anything was fixed for them
    # (the report of issue 45 says how many it named then); each names its cause now
    Mutant(
        "lab20",
        "sampler_on_unit_2",
        (("glUniform1i(lab.texSampler, 1)", "glUniform1i(lab.texSampler, 2)"),),
        {"mirror_texture": "v0 = 2 (the solution's: 1)"},
    ),
    Mutant(
        "lab20",
        "quad_ends_swapped",
        (
            (
                QUAD,
                quad(
                    RIGHT,
                    (
                        "MIRROR_X, Y0, Z1",
                        "MIRROR_X, Y1, Z1",
                        "MIRROR_X, Y1, Z0",
                        "MIRROR_X, Y0, Z0",
                    ),
                ),
            ),
        ),
        {"mirror_quad": "flipped left-right"},
    ),
    Mutant(
        "lab20",
        "ortho_depth_behind",
        (("glOrtho(Z0, Z1, Y0, Y1, 0, 15)", "glOrtho(Z0, Z1, Y0, Y1, -15, 0)"),),
        {"capture_camera": "near and far planes -15, 0", "capture_scene": "judged once task 1"},
    ),
    Mutant(
        "lab20",
        "frame_not_cleared",
        (("    create_mirror()\n" + CLEAR, "    create_mirror()\n"),),
        {"passes": "glClear"},
    ),
    Mutant(
        "lab20",
        "mirror_wears_metal",
        (
            (
                "    glActiveTexture(GL_TEXTURE1)\n    glBindTexture(GL_TEXTURE_2D, "
                "tex_ids[ENVIRONMENT])\n    glActiveTexture(GL_TEXTURE0)\n    # TODO 7",
                "    glActiveTexture(GL_TEXTURE1)\n    glBindTexture(GL_TEXTURE_2D, "
                "tex_ids[METAL])\n    glActiveTexture(GL_TEXTURE0)\n    # TODO 7",
            ),
        ),
        {"mirror_texture": "tex_ids[METAL]"},
    ),
    Mutant(
        "lab20",
        "up_along_the_view",
        (
            (
                "gluLookAt(MIRROR_X, 0, 0, 0, 0, 0, 0, 1, 0)",
                "gluLookAt(MIRROR_X, 0, 0, 0, 0, 0, 1, 0, 0)",
            ),
        ),
        {
            "capture_camera": "is parallel to the view direction",
            "capture_scene": "is parallel to the view direction",
        },
    ),
    Mutant(
        "lab20",
        "wrap_t_repeats",
        (("GL_TEXTURE_WRAP_T, GL_CLAMP_TO_EDGE", "GL_TEXTURE_WRAP_T, GL_REPEAT"),),
        {"environment_texture": "GL_REPEAT"},
    ),
    Mutant(
        "lab20",
        "program_off_inside_begin",
        (("    glEnd()\n    glUseProgram(0)\n", "    glUseProgram(0)\n    glEnd()\n"),),
        {
            "mirror_texture": "between glBegin and glEnd",
            "mirror_quad": "between glBegin and glEnd",
            "passes": "makes no glEnd()",
        },
    ),
    Mutant(
        "lab20",
        "capture_in_perspective",
        (("glOrtho(Z0, Z1, Y0, Y1, 0, 15)", "glFrustum(Z0, Z1, Y0, Y1, 1, 15)"),),
        {"capture_camera": "set by glFrustum at line 59", "capture_scene": "makes no glOrtho"},
    ),
    Mutant(
        "lab20",
        "base_wears_environment",
        (
            (
                'robot["base"].texture = tex_ids[METAL]',
                'robot["base"].texture = tex_ids[ENVIRONMENT]',
            ),
        ),
        {"base_texture": "tex_ids[ENVIRONMENT]", "capture_scene": "tex_ids[ENVIRONMENT]"},
    ),
    Mutant(
        "lab20",
        "quad_lifted",
        (("    glBegin(GL_QUADS)\n", "    glTranslatef(0, 1, 0)\n    glBegin(GL_QUADS)\n"),),
        {"mirror_quad": "glTranslatef"},
    ),
    # the sphere-map lab
    Mutant(
        "spheremap",
        "texgen_for_r",
        (
            (
                "glTexGeni(GL_T, GL_TEXTURE_GEN_MODE, GL_SPHERE_MAP)",
                "glTexGeni(GL_R, GL_TEXTURE_GEN_MODE, GL_SPHERE_MAP)",
            ),
        ),
        {"texgen_setup": "GL_R", "side_by_side": "judged once task 3"},
    ),
    Mutant(
        "spheremap",
        "enable_gen_r",
        (("    glEnable(GL_TEXTURE_GEN_T)\n", "    glEnable(GL_TEXTURE_GEN_R)\n"),),
        {  # r is a channel this lab leaves closed: refused, and the frame stops there
            "texgen_setup": "judged once task 4",
            "texgen_draw": "glEnable with GL_TEXTURE_GEN_R",
            "side_by_side": "not judged",
        },
    ),
    Mutant(
        "spheremap",
        "t_left_on",
        (("    glDisable(GL_TEXTURE_GEN_T)\n", ""),),
        {"texgen_draw": "glDisable(GL_TEXTURE_GEN_T)"},
    ),
    Mutant(
        "spheremap",
        "left_aspect_of_the_window",
        (
            (
                "    glViewport(0, 0, half, HEIGHT)\n    lab.set_viewer(half / HEIGHT)",
                "    glViewport(0, 0, half, HEIGHT)\n    lab.set_viewer(WIDTH / HEIGHT)",
            ),
        ),
        {"side_by_side": "aspect 1.00"},
    ),
    Mutant(
        "spheremap",
        "texgen_cone_both_sides",
        (
            (
                '    if SHADER_SIDE == "left":\n'
                "        lab.draw_cone_shader(SPHERE_MAP_GLSL, launch)",
                '    if SHADER_SIDE == "left":\n        draw_cone_texgen()',
            ),
        ),
        {"side_by_side": "lab.draw_cone_shader"},
    ),
    Mutant(
        "spheremap",
        "s_eye_linear",
        (
            (
                "glTexGeni(GL_S, GL_TEXTURE_GEN_MODE, GL_SPHERE_MAP)",
                "glTexGeni(GL_S, GL_TEXTURE_GEN_MODE, GL_EYE_LINEAR)",
            ),
        ),
        {"texgen_setup": "GL_EYE_LINEAR", "side_by_side": "judged once task 3"},
    ),
    Mutant(
        "spheremap",
        "left_viewport_whole_window",
        (("    glViewport(0, 0, half, HEIGHT)\n", "    glViewport(0, 0, WIDTH, HEIGHT)\n"),),
        {"side_by_side": "viewport"},
    ),
    Mutant(
        "spheremap",
        "texgen_on_unit_3_everywhere",
        (("glActiveTexture(GL_TEXTURE0 + UNIT)", "glActiveTexture(GL_TEXTURE3)"),),
        {"texgen_setup": "unit 3", "texgen_draw": "unit 3", "side_by_side": "judged once task 3"},
    ),
    Mutant(
        "spheremap",
        "left_backdrop_forgotten",
        (
            (
                "    lab.set_viewer(half / HEIGHT)\n    lab.draw_backdrop()\n",
                "    lab.set_viewer(half / HEIGHT)\n",
            ),
        ),
        {"side_by_side": "lab.draw_backdrop"},
    ),
    # the cube-map lab
    Mutant(
        "cubemap",
        "near_plane_zero",
        (("gluPerspective(90, 1, 0.05, 50)", "gluPerspective(90, 1, 0, 50)"),),
        {"capture_copy": "zNear = 0: the near plane must lie in front of the eye"},
    ),
    Mutant(
        "cubemap",
        "fov_45",
        (("gluPerspective(90, 1, 0.05, 50)", "gluPerspective(45, 1, 0.05, 50)"),),
        {"capture_cameras": "field of view 45", "capture_copy": "judged once task 3"},
    ),
    Mutant(
        "cubemap",
        "cameras_beside_the_centre",
        (("gluLookAt(cx, cy, cz, cx + dx", "gluLookAt(cx + 1, cy, cz, cx + dx"),),
        {
            "capture_cameras": "eye and center are both (1, 0, 0)",
            "capture_copy": "judged once task 3",
        },
    ),
    Mutant(
        "cubemap",
        "half_a_face_copied",
        (("0, 0, FACE_SIZE, FACE_SIZE, 0\n", "0, 0, FACE_SIZE // 2, FACE_SIZE // 2, 0\n"),),
        {"capture_copy": "width, height = 64, 64"},
    ),
    Mutant(
        "cubemap",
        "face_copied_from_the_middle",
        (("GL_RGB, 0, 0, FACE_SIZE, FACE_SIZE, 0\n", "GL_RGB, 64, 64, FACE_SIZE, FACE_SIZE, 0\n"),),
        {"capture_copy": "x, y = 64, 64"},
    ),
    Mutant(
        "cubemap",
        "sphere_in_its_own_capture",
        (
            (
                "        lab.draw_scene()\n        glActiveTexture(GL_TEXTURE1)",
                "        lab.draw_scene()\n        lab.draw_sphere(CUBE_MAP_GLSL, "
                "cube_texture)\n        glActiveTexture(GL_TEXTURE1)",
            ),
        ),
        {"capture_copy": "lab.draw_sphere"},
    ),
    Mutant(
        "cubemap",
        "cube_bound_as_2d",
        (
            (
                "        glBindTexture(GL_TEXTURE_CUBE_MAP, cube_texture)\n",
                "        glBindTexture(GL_TEXTURE_2D, cube_texture)\n",
            ),
        ),
        {
            "capture_cameras": "another target",
            "capture_copy": "another target",
            "live_frame": "not judged",
        },
    ),
    Mutant(
        "cubemap",
        "up_along_y_faces",
        (("((0, 1, 0), (0, 0, 1)),  # POSITIVE_Y", "((0, 1, 0), (0, -1, 0)),  # POSITIVE_Y"),),
        {"capture_cameras": "parallel to the view direction", "capture_copy": "judged once task 3"},
    ),
    Mutant(
        "cubemap",
        "look_at_on_the_projection",
        (
            (
                "        glMatrixMode(GL_MODELVIEW)\n        glLoadIdentity()\n        gluLookAt",
                "        glLoadIdentity()\n        gluLookAt",
            ),
        ),
        {
            "capture_cameras": "applied to the projection matrix",
            "capture_copy": "judged once task 3",
        },
    ),
    Mutant(
        "cubemap",
        "viewport_not_restored",
        (("    glViewport(0, 0, WIDTH, HEIGHT)\n\n\ndef display", "\n\ndef display"),),
        {"live_frame": "glViewport"},
    ),
)
