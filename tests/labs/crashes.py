"""Legal files that used to break the checker (an internal error, or 0/8 "grading failed"
in ``lab grade``): each is the teacher's solution with a few lines changed or added. The
honest ones must be judged like the solution (every task passes); the others must be
judged, or stopped in one line, with a phrase the output must contain.

They are the issue's examples of each class: a call form the executor lacked, a number
out of range (through the OpenGL stand-ins, a kit call, or sent straight down the pipe),
thousands of legal calls that swell the evidence, a GLSL preprocessor bomb, and a frame
left inside glBegin.
"""

from __future__ import annotations

from dataclasses import dataclass

from tests.labs.mutants import solution


@dataclass(frozen=True)
class Crash:
    lab: str
    name: str
    edits: tuple[tuple[str, str], ...]
    phrase: str | None
    """A phrase the check's output must contain; None: every task must pass."""

    def source(self) -> str:
        text = solution(self.lab)
        for old, new in self.edits:
            if old not in text:
                raise AssertionError(f"crash {self.name}: {old!r} is not in the solution")
            text = text.replace(old, new, 1)
        return text


CHANNEL = """
import gc, json, os, struct
for thing in gc.get_objects():
    if type(thing).__name__ == "Channel":
        channel = thing
"""

BLANK = (
    "    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB, WIDTH, HEIGHT, 0, GL_RGB, GL_UNSIGNED_BYTE, None)\n"
)
DISPLAY = "def display():\n"

CRASHES = (
    # honest: a form of an allowed call the executor lacked
    Crash(
        "lab20",
        "honest_tex_sub_image",
        (
            (
                BLANK,
                BLANK
                + (
                    "    glPixelStorei(GL_UNPACK_ALIGNMENT, 1)\n"
                    "    glTexSubImage2D(GL_TEXTURE_2D, 0, 0, 0, 1, 1, GL_RGB, GL_UNSIGNED_BYTE, "
                    "bytes(3))\n"
                ),
            ),
        ),
        None,
    ),
    Crash(
        "lab20",
        "honest_integer_vertices",
        (
            ("glVertex3f(MIRROR_X, Y0, Z0)", "glVertex3i(MIRROR_X, Y0, Z0)"),
            ("glVertex3f(MIRROR_X, Y1, Z0)", "glVertex3s(MIRROR_X, Y1, Z0)"),
            ("glVertex3f(MIRROR_X, Y1, Z1)", "glVertex3iv([MIRROR_X, Y1, Z1])"),
            ("glTexCoord2f(0, 0)", "glTexCoord2i(0, 0)"),
        ),
        None,
    ),
    # numbers out of range
    Crash(
        "lab20",
        "huge_float_argument",
        (("    lab.set_viewer()\n", "    lab.set_viewer()\n    glTranslatef(10 ** 400, 0, 0)\n"),),
        "out of range",
    ),
    Crash(
        "lab20",
        "huge_float_sent_down_the_pipe",
        (
            (
                DISPLAY,
                CHANNEL
                + """

def send(header):
    channel.send(header)
    return channel.receive()[0]


"""
                + DISPLAY
                + """    reply = send({"op": "gl", "fn": "glTranslatef", "args": [10 ** 400, 0, 0],
                  "line": 1})
    assert not reply["ok"], reply
    reply = send({"op": "kit", "fn": "set_viewer", "args": [10 ** 400], "line": 1})
    assert not reply["ok"], reply
    raise ValueError(reply["message"])
""",
            ),
        ),
        "out of range",
    ),
    Crash(
        "spheremap",
        "huge_aspect_through_the_kit",
        ((DISPLAY, DISPLAY + "    lab.set_viewer(10 ** 400)\n"),),
        "out of range",
    ),
    # evidence that grows with the calls
    Crash(
        "lab20",
        "four_thousand_legal_calls",
        (
            (
                DISPLAY,
                DISPLAY
                + """    for _ in range(1300):
        glMultMatrixf([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1])
        glBegin(GL_TRIANGLES)
        glEnd()
""",
            ),
        ),
        None,
    ),
    Crash(
        "lab20",
        "twenty_thousand_legal_calls",
        (
            (
                DISPLAY,
                DISPLAY
                + """    for _ in range(3300):
        glMultMatrixf([1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1])
        glBegin(GL_TRIANGLES)
        glEnd()
""",
            ),
        ),
        "MiB of evidence",
    ),
    # a GLSL preprocessor bomb: 28 macros, each twice the one before
    Crash(
        "cubemap",
        "glsl_preprocessor_bomb",
        (
            (
                'CUBE_MAP_GLSL = """\n',
                'CUBE_MAP_GLSL = """\n#define A0 1.0\n'
                + "".join(f"#define A{i} (A{i - 1} + A{i - 1})\n" for i in range(1, 29))
                + "float bomb() { return A28; }\n",
            ),
        ),
        "could not be compiled within the limits",
    ),
    # the checker's own names and bindings in the student's GLSL (issue 44): each once
    # "the checker's OpenGL process failed"; now refused in one line before any driver
    # sees it, and every task judged
    Crash(
        "spheremap",
        "uniform_float_ml_modelview",
        (
            (
                'SPHERE_MAP_GLSL = """\n',
                'SPHERE_MAP_GLSL = """\nuniform float ml_ModelViewMatrix;\n',
            ),
            (
                "return u - 2.0 * dot(n, u) * n;",
                "return (u - 2.0 * dot(n, u) * n) * ml_ModelViewMatrix;",
            ),
        ),
        "names beginning with ml_ are the checker's own",
    ),
    Crash(
        "cubemap",
        "sampler_clashing_with_the_probe",
        (
            (
                'CUBE_MAP_GLSL = """\n',
                'CUBE_MAP_GLSL = """\nuniform samplerCube faces;\n',
            ),
            ("    vec3 a = abs(r);", "    vec3 a = abs(r) + texture(faces, r).rgb * 0.0;"),
        ),
        "'uniform' outside a function",
    ),
    # a frame left inside glBegin
    Crash(
        "lab20",
        "display_ends_inside_glbegin",
        (("    render_mirror()\n", "    render_mirror()\n    glBegin(GL_TRIANGLES)\n"),),
        "returned inside glBegin",
    ),
)
