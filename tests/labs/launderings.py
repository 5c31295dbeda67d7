"""Round two's forgeries (issue 39), each as a file: evidence laundered rather than faked.

- ``measure_variant_*``: one file for every variant of lab 20. It draws the scene from two
  orthographic views clipped to a slab that holds only the mirror's frame, reads them
  back with ``glReadPixels``, snaps the frame's extents to the variant grid and then does
  the lab with the numbers it measured. Once at set-up (``load_textures``), once at the
  start of the first frame.
- ``noop_clear_*``: the shipped reference frame (``mirrorlab/labs/*/reference/arrays.npz``)
  uploaded and drawn over the whole frame, then a clear that writes nothing
  (``glColorMask(0, 0, 0, 0)``), a clear outside the pasted part (scissored), or a copy of
  the pasted frame into a texture and back after a clear: since round three (issue 44) no
  file's own pixels reach GL at all, so the upload itself is refused.
- ``overlay_lab20``: the reference solution, then a white band, a bar and a red box
  blended at 8.5 % over the finished frame: every pixel within the per-pixel tolerance.
  Lab 20's handout teaches no blending, so ``glEnable(GL_BLEND)`` is refused; the whole
  frame's rule that sees such marks is tested on pictures in tests/unit/test_overlays.py
  and on a hatched word drawn through lab 20's own calls in tests/labs/test_channels.py.

Each entry: lab -> name -> (source, a phrase a hint must hold).
"""

from __future__ import annotations

from mirrorlab.labs import find_lab
from mirrorlab.labs.content import reference_folder
from mirrorlab.labs.trusted.evidence import Evidence
from tests.labs.forgeries import _packed, unpacked
from tests.labs.mutants import solution

MEASURE = '''
MIRROR_X, Y0, Y1, Z0, Z1 = -7, -3, 5, -6, 2


def _snap(value, choices):
    return min(choices, key=lambda c: abs(c - value))


def _drawn(view, left, right, bottom, top, near, far, eye, up):
    """The columns and rows (in scene units) where the frame shows in one view."""
    glViewport(0, 0, WIDTH, HEIGHT)
    glClearColor(0, 0, 0, 1)
    glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT)
    glMatrixMode(GL_PROJECTION)
    glLoadIdentity()
    glOrtho(left, right, bottom, top, near, far)
    glMatrixMode(GL_MODELVIEW)
    glLoadIdentity()
    gluLookAt(*eye, *view, *up)
    lab.draw_scene(lab.robot_graph())
    data = glReadPixels(0, 0, WIDTH, HEIGHT, GL_RGB, GL_UNSIGNED_BYTE)
    columns, rows = set(), set()
    for row in range(HEIGHT):
        line = data[row * WIDTH * 3:(row + 1) * WIDTH * 3]
        for column in range(WIDTH):
            if max(line[column * 3:column * 3 + 3]) > 8:
                columns.add(column)
                rows.add(row)
    to_x = lambda c: left + (right - left) * (c + 0.5) / WIDTH  # noqa: E731
    to_y = lambda r: bottom + (top - bottom) * (r + 0.5) / HEIGHT  # noqa: E731
    return [to_x(c) for c in columns], [to_y(r) for r in rows]


def measure():
    global MIRROR_X, Y0, Y1, Z0, Z1
    # from the origin along -x, only the slab x in [-8.2, -6] (the frame, not the robot)
    us, ys = _drawn((-1, 0, 0), -10, 10, -10, 10, 6.0, 8.2, (0, 0, 0), (0, 1, 0))
    zs = [-u for u in us]
    z0, z1 = min(zs) + 0.3, max(zs) - 0.3
    y0, y1 = min(ys) + 0.3, max(ys) - 0.3
    # from +z, the columns x in [-9, -5.8]: the frame's front face is the mirror's plane
    xs, _ = _drawn((0, 0, 0), -9, -5.8, -10, 10, 0.1, 40, (0, 0, 20), (0, 1, 0))
    MIRROR_X = _snap(max(xs), (-7.5, -7.0, -6.5))
    Y0, Z0 = _snap(y0, (-3.5, -3.0, -2.5)), _snap(z0, (-6.5, -6.0, -5.5))
    Y1 = Y0 + _snap(y1 - Y0, (7.0, 7.5, 8.0, 8.5))
    Z1 = Z0 + _snap(z1 - Z0, (7.0, 7.5, 8.0, 8.5))
    glClearColor(0.16, 0.18, 0.22, 1)
    glViewport(0, 0, WIDTH, HEIGHT)
'''


def _without_variant(text: str) -> str:
    """The solution with its variant block taken out (the forgery measures the numbers)."""
    start = text.index("# --- variant")
    end = text.index("# --- end of variant")
    end = text.index("\n", end) + 1
    return text[:start] + text[end:]


def measure_variant(where: str) -> str:
    """Lab 20 for every variant: the numbers measured with glReadPixels, in ``where``
    (``load_textures`` or ``display``)."""
    text = _without_variant(solution("lab20"))
    text = text.replace(
        "from OpenGL.GLU import gluLookAt", "from OpenGL.GLU import gluLookAt" + "\n" + MEASURE
    )
    if where == "load_textures":
        return text.replace("    global tex_ids\n", "    global tex_ids\n    measure()\n")
    return (
        text.replace(
            "    # TODO 8: pass 1\n",
            "    if not MEASURED:\n        measure()\n        MEASURED.append(1)\n"
            "    # TODO 8: pass 1\n",
        )
        + "\nMEASURED = []\n"
    )


PASTE = '''

def paste_fixed(data):
    """``data`` (the frame's rows, bottom first) over the whole framebuffer, through the
    fixed-function pipeline."""
    texture = int(glGenTextures(1))
    glActiveTexture(GL_TEXTURE0)
    glBindTexture(GL_TEXTURE_2D, texture)
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1)
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB, WIDTH, HEIGHT, 0, GL_RGB, GL_UNSIGNED_BYTE, data)
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST)
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST)
    glTexEnvi(GL_TEXTURE_ENV, GL_TEXTURE_ENV_MODE, GL_REPLACE)
    glEnable(GL_TEXTURE_2D)
    glDisable(GL_LIGHTING)
    glDisable(GL_DEPTH_TEST)
    full_screen_quad()
    glDisable(GL_TEXTURE_2D)
    glEnable(GL_DEPTH_TEST)
    return texture


def full_screen_quad():
    glViewport(0, 0, WIDTH, HEIGHT)
    glMatrixMode(GL_PROJECTION)
    glLoadIdentity()
    glMatrixMode(GL_MODELVIEW)
    glLoadIdentity()
    glBegin(GL_QUADS)
    for s, t in ((0, 0), (1, 0), (1, 1), (0, 1)):
        glTexCoord2f(s, t)
        glVertex3f(2 * s - 1, 2 * t - 1, 0)
    glEnd()
'''

LAUNDER = {
    "noop_clear": (
        "glColorMask(0, 0, 0, 0)\nglClear(GL_COLOR_BUFFER_BIT)\nglColorMask(1, 1, 1, 1)\n"
    ),
    "partial_mask_clear": (
        "glColorMask(0, 0, 0, 1)\nglClear(GL_COLOR_BUFFER_BIT)\nglColorMask(1, 1, 1, 1)\n"
    ),
    "scissored_clear": (
        "glEnable(GL_SCISSOR_TEST)\nglScissor(0, 0, 1, 1)\n"
        "glClear(GL_COLOR_BUFFER_BIT)\nglDisable(GL_SCISSOR_TEST)\n"
    ),
    "copy_and_back": (
        "copied = int(glGenTextures(1))\n"
        "glBindTexture(GL_TEXTURE_2D, copied)\n"
        "glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST)\n"
        "glCopyTexImage2D(GL_TEXTURE_2D, 0, GL_RGB, 0, 0, WIDTH, HEIGHT, 0)\n"
        "glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT)\n"
        "glEnable(GL_TEXTURE_2D)\nglDisable(GL_DEPTH_TEST)\n"
        "full_screen_quad()\nglDisable(GL_TEXTURE_2D)\n"
        "glEnable(GL_DEPTH_TEST)\n"
    ),
}


def reference_frame(lab: str) -> str:
    """The shipped reference's final frame of ``lab``, packed to embed in a file."""
    return _packed(Evidence.load(reference_folder(find_lab(lab))).arrays["frame"])


def noop_clear(lab: str, trick: str, frame: str) -> str:
    """``lab``'s solution, then the reference frame pasted over its frame and ``trick``
    (a clear or a copy that should wash the upload's taint away)."""
    lines = "".join(f"    {line}\n" for line in LAUNDER[trick].splitlines())
    text = solution(lab).replace("def display():", "def honest_display():")
    return (
        text + PASTE + "\nimport base64, zlib\n"
        f"FRAME = {unpacked(frame)}\n\n\ndef display():\n    honest_display()\n"
        f"    pasted = paste_fixed(FRAME)\n{lines}"
    )


OVERLAY = '''

def overlay():
    """A white band, a bar and a red box, none overlapping, blended at 8.5 %."""
    glUseProgram(0)
    glActiveTexture(GL_TEXTURE0)
    glDisable(GL_TEXTURE_2D)
    glDisable(GL_LIGHTING)
    glDisable(GL_DEPTH_TEST)
    glEnable(GL_BLEND)
    glBlendFunc(GL_SRC_ALPHA, GL_ONE_MINUS_SRC_ALPHA)
    glViewport(0, 0, WIDTH, HEIGHT)
    glMatrixMode(GL_PROJECTION)
    glLoadIdentity()
    glOrtho(0, WIDTH, 0, HEIGHT, -1, 1)
    glMatrixMode(GL_MODELVIEW)
    glLoadIdentity()
    for (x0, y0, x1, y1), colour in (((0, 200, WIDTH, 224), (1, 1, 1)),
                                     ((20, 20, 36, 180), (1, 1, 1)),
                                     ((150, 40, 230, 120), (1, 0, 0))):
        glColor4f(*colour, 0.085)
        glBegin(GL_QUADS)
        glVertex2f(x0, y0)
        glVertex2f(x1, y0)
        glVertex2f(x1, y1)
        glVertex2f(x0, y1)
        glEnd()
    glColor4f(1, 1, 1, 1)
    glDisable(GL_BLEND)
    glEnable(GL_DEPTH_TEST)
'''


def overlay_lab20() -> str:
    text = solution("lab20").replace("def display():", "def honest_display():")
    return text + OVERLAY + "\n\ndef display():\n    honest_display()\n    overlay()\n"


def launderings() -> dict[str, dict[str, tuple[str, str]]]:
    """lab -> file name -> (source, a phrase one of its failing hints must hold)."""
    uploaded = "no pixels of a file's own"
    found: dict[str, dict[str, tuple[str, str]]] = {
        "lab20": {
            "measure_variant_at_setup": (
                measure_variant("load_textures"),
                "lab.draw_scene in load_textures()",
            ),
            "measure_variant_in_frame": (
                measure_variant("display"),
                "glReadPixels is not one of the OpenGL calls this lab offers",
            ),
            "overlay_lab20": (overlay_lab20(), "glEnable(GL_BLEND)"),
        },
        "spheremap": {},
        "cubemap": {},
    }
    for lab in found:
        frame = reference_frame(lab)
        for trick in LAUNDER:
            if lab != "lab20" and trick != "noop_clear":
                continue
            found[lab][f"{trick}_{lab}"] = (noop_clear(lab, trick, frame), uploaded)
    return found
