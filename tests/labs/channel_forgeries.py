"""Round three's files against the channels from a file's numbers to the frame (issue 44),
each with a phrase one of its failing hints must hold (None: every task must pass).

- Forged passes 1 to 3, as a student who read the checker would write them after this
  round: each *catches* the refusal of every call that carries the picture, so that the
  run goes on; what is left must fail a task. 1: the reference frame uploaded and drawn as
  one-pixel lines in viewports 0 pixels wide; 2: the frame hidden in a level that
  GL_GENERATE_MIPMAP makes, level 0 uploaded again empty, the hidden level drawn as the
  base; 3: the kit's texgen cone zoomed over the frame with the reference on unit 4,
  GL_REPLACE and eye-linear planes mapping the window.
- Forged pass 7: "HACKED" 24 levels brighter than the background on even pixel columns
  only, painted through what lab 20 offers (a texture of one colour from a clear and a
  copy, thin quads through the lab's texture shader): the whole frame's rule at every
  scale must see it.
- The crashes: the modelview stack left full (the kit's draw once pushed onto it), and
  the capture copied as GL_DEPTH_COMPONENT (an honest slip: judged, the format named).
- Leftover state (issue 44 item 8): a seeded fuzz corpus of files that leave the stacks,
  units, levels, bindings, switches and the program in any state at the end of the
  set-up and of the frame, each judged task by task in one line.
"""

from __future__ import annotations

import random
from dataclasses import dataclass

from tests.labs.classroom import starter_text
from tests.labs.launderings import reference_frame
from tests.labs.mutants import solution

TRY = "\n".join(
    [
        "",
        "",
        "def attempt(call, *args):",
        '    """A refused call caught, so the run goes on without it."""',
        "    try:",
        "        return call(*args)",
        "    except Exception:",
        "        return None",
        "",
        "",
        "import base64, zlib",
        "import numpy as np",
        "",
    ]
)


def _frame_lines(lab: str) -> str:
    return f"FRAME = zlib.decompress(base64.b64decode({reference_frame(lab)!r}))\n"


LINES = '''

def paste_as_lines():
    """Forged pass 1: the frame on a texture, drawn one column at a time as a line in a
    viewport 0 pixels wide (taint once covered only the empty viewport)."""
    picture = int(glGenTextures(1))
    glActiveTexture(GL_TEXTURE0)
    glBindTexture(GL_TEXTURE_2D, picture)
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1)
    attempt(glTexImage2D, GL_TEXTURE_2D, 0, GL_RGB, WIDTH, HEIGHT, 0, GL_RGB,
            GL_UNSIGNED_BYTE, FRAME)
    for pname in (GL_TEXTURE_MIN_FILTER, GL_TEXTURE_MAG_FILTER):
        glTexParameteri(GL_TEXTURE_2D, pname, GL_NEAREST)
    attempt(glTexEnvi, GL_TEXTURE_ENV, GL_TEXTURE_ENV_MODE, GL_REPLACE)
    attempt(glEnable, GL_TEXTURE_2D)
    glDisable(GL_DEPTH_TEST)
    glMatrixMode(GL_PROJECTION)
    glLoadIdentity()
    glMatrixMode(GL_MODELVIEW)
    glLoadIdentity()
    for column in range(WIDTH):
        glViewport(column, 0, 0, HEIGHT)
        if attempt(glBegin, GL_LINES) is None and column == 0:
            pass
        s = (column + 0.5) / WIDTH
        attempt(glTexCoord2f, s, 0.0)
        attempt(glVertex2f, -1.0, -1.0)
        attempt(glTexCoord2f, s, 1.0)
        attempt(glVertex2f, -1.0, 1.0)
        attempt(glEnd)
    glViewport(0, 0, WIDTH, HEIGHT)
    attempt(glDisable, GL_TEXTURE_2D)
    glEnable(GL_DEPTH_TEST)
'''

HIDDEN_LEVEL = '''

def paste_from_a_hidden_level():
    """Forged pass 2: the frame in level 1 of a texture GL_GENERATE_MIPMAP fills, level 0
    made again empty, level 1 drawn as the base by the kit's shader cone, zoomed."""
    picture = int(glGenTextures(1))
    glActiveTexture(GL_TEXTURE0)
    glBindTexture(GL_TEXTURE_2D, picture)
    glTexParameteri(GL_TEXTURE_2D, GL_GENERATE_MIPMAP, 1)
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1)
    frame = np.frombuffer(FRAME, np.uint8).reshape(HEIGHT, WIDTH, 3)
    doubled = np.ascontiguousarray(frame.repeat(2, axis=0).repeat(2, axis=1))
    attempt(glTexImage2D, GL_TEXTURE_2D, 0, GL_RGB, 2 * WIDTH, 2 * HEIGHT, 0, GL_RGB,
            GL_UNSIGNED_BYTE, doubled)
    glTexParameteri(GL_TEXTURE_2D, GL_GENERATE_MIPMAP, 0)
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB, 2 * WIDTH, 2 * HEIGHT, 0, GL_RGB, GL_UNSIGNED_BYTE,
                 None)
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_BASE_LEVEL, 1)
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST)
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST)
    return picture
'''

TEXGEN_UNIT_4 = '''

def paste_through_texgen_unit_4():
    """Forged pass 3: the kit's texgen cone, zoomed to fill the frame, textured from the
    frame on unit 4 (GL_REPLACE, eye-linear planes mapping the window) while the
    variant's unit has texgen on."""
    picture = int(glGenTextures(1))
    glActiveTexture(GL_TEXTURE4)
    glBindTexture(GL_TEXTURE_2D, picture)
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1)
    attempt(glTexImage2D, GL_TEXTURE_2D, 0, GL_RGB, WIDTH, HEIGHT, 0, GL_RGB,
            GL_UNSIGNED_BYTE, FRAME)
    for pname in (GL_TEXTURE_MIN_FILTER, GL_TEXTURE_MAG_FILTER):
        glTexParameteri(GL_TEXTURE_2D, pname, GL_NEAREST)
    attempt(glTexEnvi, GL_TEXTURE_ENV, GL_TEXTURE_ENV_MODE, GL_REPLACE)
    attempt(glEnable, GL_TEXTURE_2D)
    for coord, cap, plane in ((GL_S, GL_TEXTURE_GEN_S, (0.5, 0, 0, 0.5)),
                              (GL_T, GL_TEXTURE_GEN_T, (0, 0.5, 0, 0.5))):
        attempt(glTexGeni, coord, GL_TEXTURE_GEN_MODE, GL_EYE_LINEAR)
        attempt(glTexGenfv, coord, GL_EYE_PLANE, plane)
        attempt(glEnable, cap)
    glActiveTexture(GL_TEXTURE0 + UNIT)
    glBindTexture(GL_TEXTURE_2D, launch)
    glTexGeni(GL_S, GL_TEXTURE_GEN_MODE, GL_SPHERE_MAP)
    glTexGeni(GL_T, GL_TEXTURE_GEN_MODE, GL_SPHERE_MAP)
    glEnable(GL_TEXTURE_GEN_S)
    glEnable(GL_TEXTURE_GEN_T)
    glActiveTexture(GL_TEXTURE0)
    glViewport(0, 0, WIDTH, HEIGHT)
    glMatrixMode(GL_PROJECTION)
    glLoadIdentity()
    glOrtho(-0.05, 0.05, 0.95, 1.05, -10, 10)  # the cone's tip fills the frame
    glMatrixMode(GL_MODELVIEW)
    glLoadIdentity()
    lab.draw_cone_fixed_function()
'''

FONT = {
    "H": ("101", "101", "111", "101", "101"),
    "A": ("010", "101", "111", "101", "101"),
    "C": ("011", "100", "100", "100", "011"),
    "K": ("101", "110", "100", "110", "101"),
    "E": ("111", "100", "110", "100", "111"),
    "D": ("110", "101", "101", "101", "110"),
}

HATCHED = '''

FONT = {font!r}
paint = 0


def make_paint():
    """A texture of one colour, the background 24 levels brighter: a clear and a copy."""
    global paint
    if not paint:
        paint = int(glGenTextures(1))
    glClearColor(65 / 255, 70 / 255, 80 / 255, 1.0)
    glClear(GL_COLOR_BUFFER_BIT)
    glActiveTexture(GL_TEXTURE3)
    glBindTexture(GL_TEXTURE_2D, paint)
    glCopyTexImage2D(GL_TEXTURE_2D, 0, GL_RGB, 0, 0, 8, 8, 0)
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST)
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST)
    glActiveTexture(GL_TEXTURE0)
    glClearColor(0.16, 0.18, 0.22, 1.0)


def hatched_word(word, left, top, scale):
    """``word`` over the background, its strokes on even pixel columns only."""
    glUseProgram(lab.textureShader)
    glUniform1i(lab.texSampler, 3)
    glDisable(GL_DEPTH_TEST)
    glViewport(0, 0, WIDTH, HEIGHT)
    glMatrixMode(GL_PROJECTION)
    glLoadIdentity()
    glOrtho(0, WIDTH, HEIGHT, 0, -1, 1)
    glMatrixMode(GL_MODELVIEW)
    glLoadIdentity()
    glBegin(GL_QUADS)
    for index, letter in enumerate(word):
        for column in range(3):
            for row, line in enumerate(FONT[letter]):
                if line[column] != "1":
                    continue
                x0 = left + (4 * index + column) * scale
                y0 = top + row * scale
                for x in range(x0 + x0 % 2, x0 + scale, 2):
                    for px, py in ((x, y0), (x + 1, y0), (x + 1, y0 + scale), (x, y0 + scale)):
                        glTexCoord2f(0.5, 0.5)
                        glVertex2f(px, py)
    glEnd()
    glEnable(GL_DEPTH_TEST)
    glUseProgram(0)
'''


@dataclass(frozen=True)
class Forged:
    lab: str
    name: str
    source: str
    expect: str
    """``fail``: a task fails, a hint holding ``phrase``; ``pass``: every task passes;
    ``judged``: every task judged, in one line each."""
    phrase: str = ""


def forged_lines() -> str:
    text = starter_text("spheremap")
    return (
        text
        + TRY
        + _frame_lines("spheremap")
        + LINES
        + "\n\n_display = display\n\n\ndef display():\n    _display()\n    paste_as_lines()\n"
    )


def forged_hidden_level() -> str:
    text = starter_text("spheremap")
    return (
        text
        + TRY
        + _frame_lines("spheremap")
        + HIDDEN_LEVEL
        + "\n\nhidden = 0\n_display = display\n\n\ndef display():\n    global hidden\n"
        "    _display()\n    hidden = hidden or paste_from_a_hidden_level()\n"
        "    glViewport(0, 0, WIDTH, HEIGHT)\n    glMatrixMode(GL_PROJECTION)\n"
        "    glLoadIdentity()\n    glOrtho(-0.05, 0.05, 0.95, 1.05, -10, 10)\n"
        "    glMatrixMode(GL_MODELVIEW)\n    glLoadIdentity()\n"
        "    lab.draw_cone_shader(SPHERE_MAP_GLSL, hidden)\n"
    )


def forged_texgen_unit_4() -> str:
    text = solution("spheremap")  # its numbers and its launch texture; its tasks undone
    text = text.replace("def display():", "def honest_display():")
    return (
        text
        + TRY
        + _frame_lines("spheremap")
        + TEXGEN_UNIT_4
        + "\n\ndef display():\n    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT)\n"
        "    paste_through_texgen_unit_4()\n"
    )


def forged_hatched_word() -> str:
    text = solution("lab20").replace("def display():", "def honest_display():")
    return (
        text
        + HATCHED.format(font=FONT)
        + "\n\ndef display():\n    make_paint()\n    honest_display()\n"
        "    hatched_word('HACKED', 40, 14, 6)\n"
    )


def crash_stack_full() -> str:
    """The modelview stack left full at the end of the set-up (32 deep, Mesa's limit)."""
    return solution("lab20").replace(
        '    robot["base"].texture = tex_ids[METAL]\n',
        '    robot["base"].texture = tex_ids[METAL]\n'
        "    glMatrixMode(GL_MODELVIEW)\n    for _ in range(31):\n        glPushMatrix()\n",
    )


def crash_depth_copy(lab: str) -> str:
    """The capture copied as GL_DEPTH_COMPONENT: an honest slip."""
    text = solution(lab)
    old = (
        "glCopyTexImage2D(GL_TEXTURE_2D, 0, GL_RGB, 0, 0, WIDTH, HEIGHT, 0)"
        if lab == "lab20"
        else "GL_TEXTURE_CUBE_MAP_POSITIVE_X + face, 0, GL_RGB, 0, 0"
    )
    new = old.replace("GL_RGB", "GL_DEPTH_COMPONENT")
    assert old in text
    return text.replace(old, new)


# ---------------------------------------------------------------- leftover state (fuzz)
PLACES = {
    "lab20": ('    robot["base"].texture = tex_ids[METAL]\n', "    render_mirror()\n"),
    "spheremap": ("    glActiveTexture(GL_TEXTURE0)\n", None),
    "cubemap": ("    glActiveTexture(GL_TEXTURE0)\n", None),
}
"""Where a lab's leftover state goes: after the first line given, the last of a set-up
function, and after the second, the last of the frame (``None``: at the end of the
solution, whose last function is ``display()``)."""


def leftover(rng: random.Random, lab: str) -> list[str]:
    """Lines that leave some state (every call wrapped, as a file that does not care)."""
    lines = []
    for _ in range(rng.randint(3, 9)):
        kind = rng.choice(
            ["stack", "unit", "bind", "switch", "program", "store", "masks", "level", "begin"]
        )
        if kind == "stack":
            mode = rng.choice(["GL_MODELVIEW", "GL_PROJECTION", "GL_TEXTURE"])
            count = rng.choice([1, 5, 31, 40])
            lines.append(f"glMatrixMode({mode})")
            lines.append(f"for _ in range({count}):\n        attempt(glPushMatrix)")
        elif kind == "unit":
            lines.append(f"glActiveTexture(GL_TEXTURE{rng.randint(0, 7)})")
        elif kind == "bind":
            target = rng.choice(["GL_TEXTURE_2D", "GL_TEXTURE_CUBE_MAP"])
            lines.append("leftover_texture = int(glGenTextures(1))")
            lines.append(f"attempt(glBindTexture, {target}, leftover_texture)")
        elif kind == "switch":
            cap = rng.choice(
                [
                    "GL_TEXTURE_2D",
                    "GL_TEXTURE_CUBE_MAP",
                    "GL_TEXTURE_GEN_S",
                    "GL_TEXTURE_GEN_Q",
                    "GL_CULL_FACE",
                    "GL_BLEND",
                    "GL_SCISSOR_TEST",
                    "GL_LIGHTING",
                    "GL_DEPTH_TEST",
                ]
            )
            lines.append(f"attempt({rng.choice(['glEnable', 'glDisable'])}, {cap})")
        elif kind == "program":
            program = "lab.textureShader" if lab == "lab20" else "0"
            lines.append(f"attempt(glUseProgram, {program})")
        elif kind == "store":
            lines.append(
                f"glPixelStorei({rng.choice(['GL_PACK_ALIGNMENT', 'GL_UNPACK_ALIGNMENT'])}, "
                f"{rng.choice([1, 2, 8])})"
            )
        elif kind == "masks":
            lines.append(f"glColorMask({rng.randint(0, 1)}, 1, {rng.randint(0, 1)}, 1)")
            lines.append(f"glDepthMask({rng.randint(0, 1)})")
            lines.append(f"glDepthFunc({rng.choice(['GL_GREATER', 'GL_ALWAYS', 'GL_LEQUAL'])})")
        elif kind == "level":
            internal = rng.choice(
                ["GL_RGBA", "GL_DEPTH_COMPONENT", "GL_LUMINANCE", "GL_RGB16F", "GL_ALPHA", "3"]
            )
            fmt = "GL_DEPTH_COMPONENT" if "DEPTH" in internal else "GL_RGBA"
            lines.append("leftover_texture = int(glGenTextures(1))")
            lines.append("glBindTexture(GL_TEXTURE_2D, leftover_texture)")
            lines.append(
                f"attempt(glTexImage2D, GL_TEXTURE_2D, {rng.randint(0, 4)}, {internal}, "
                f"16, 16, 0, {fmt}, GL_UNSIGNED_BYTE, None)"
            )
        else:
            lines.append("attempt(glBegin, GL_TRIANGLES)")
    return lines


def leftover_file(lab: str, seed: int) -> str:
    """``lab``'s solution leaving the state of seed ``seed`` at the end of a set-up
    function and of each frame."""
    rng = random.Random(seed)
    text = solution(lab)
    setup_place, frame_place = PLACES[lab]
    assert setup_place in text, (lab, setup_place)
    body = "".join(f"    {line}\n" for line in leftover(rng, lab))
    text = text.replace(setup_place, setup_place + body, 1)
    end = "".join(f"    {line}\n" for line in leftover(rng, lab))
    if frame_place is None:
        text = text.rstrip("\n") + "\n" + end
    else:
        text = text.replace(frame_place, frame_place + end, 1)
    return text + TRY


def channel_forgeries() -> list[Forged]:
    found = [
        Forged("spheremap", "forged_lines_in_empty_viewports", forged_lines(), "fail"),
        Forged("spheremap", "forged_hidden_mip_level", forged_hidden_level(), "fail"),
        Forged("spheremap", "forged_texgen_unit_4", forged_texgen_unit_4(), "fail"),
        Forged("lab20", "forged_hatched_word", forged_hatched_word(), "fail", "faint mark"),
        Forged("lab20", "crash_modelview_stack_full", crash_stack_full(), "pass"),
        Forged(
            "lab20", "crash_depth_copy", crash_depth_copy("lab20"), "fail", "GL_DEPTH_COMPONENT"
        ),
        Forged(
            "cubemap",
            "crash_depth_copy_cube",
            crash_depth_copy("cubemap"),
            "fail",
            "GL_DEPTH_COMPONENT",
        ),
    ]
    for lab in ("lab20", "spheremap", "cubemap"):
        for seed in range(1):
            found.append(Forged(lab, f"leftover_{lab}_{seed}", leftover_file(lab, seed), "judged"))
    return found
