"""Files that try to get marks without doing lab 20: each forgery's source and a phrase one
of its hints must contain (None: it must simply not pass). Every one must be graded as not
passing, in one line a task and no traceback, by ``lab check`` and by ``lab grade``.

They are what a student could write knowing how the checker works: find a solution
anywhere (the file system, mirrorlab's own objects), rewrite what the checker reads (at
exit, with ``os._exit``, through objects found with ``gc``), patch the runner and the
stand-ins, replay the reference's pictures (read from a cache, or the shipped evidence
embedded in the file) or draw them with mirrorlab's renderer or numpy and upload them,
flood the checker with calls or bytes, speak garbage on the pipe, reach the checker's
own GL objects.
"""

from __future__ import annotations

import base64
import zlib
from pathlib import Path

import numpy as np

from mirrorlab.labs import find_lab
from mirrorlab.labs.content import reference_folder
from mirrorlab.labs.trusted.evidence import Evidence
from tests.labs.mutants import SOLUTIONS, solution

HEADER = """from OpenGL.GL import *  # noqa: F403
from OpenGL.GLU import gluLookAt  # noqa: F401
from mirrorlab.labs import kit

lab = kit.lab20()
WIDTH, HEIGHT = lab.width, lab.height
"""

HONEST_PARTS = solution("lab20").split("lab = kit.lab20()", 1)[1]
"""The solution after its first lines: what a forgery adds its tricks to."""


def _packed(image: np.ndarray) -> str:
    return base64.b64encode(zlib.compress(np.ascontiguousarray(image[::-1]).tobytes())).decode()


def _reference_pictures() -> tuple[str, str]:
    """The shipped reference's final frame and capture, packed to embed in a file (rows
    bottom first, as glTexImage2D takes them)."""
    evidence = Evidence.load(reference_folder(find_lab("lab20")))
    return _packed(evidence.arrays["frame"]), _packed(evidence.arrays["capture"])


PASTE = """

def paste(texture):
    # the whole framebuffer covered by `texture`, through the lab's own texture shader
    glUseProgram(lab.textureShader)
    glUniform1i(lab.texSampler, 3)
    glActiveTexture(GL_TEXTURE3)
    glBindTexture(GL_TEXTURE_2D, texture)
    glActiveTexture(GL_TEXTURE0)
    glMatrixMode(GL_PROJECTION)
    glPushMatrix()
    glLoadIdentity()
    glMatrixMode(GL_MODELVIEW)
    glPushMatrix()
    glLoadIdentity()
    glDisable(GL_DEPTH_TEST)
    glBegin(GL_QUADS)
    for s, t in ((0, 0), (1, 0), (1, 1), (0, 1)):
        glTexCoord2f(s, t)
        glVertex3f(2 * s - 1, 2 * t - 1, 0)
    glEnd()
    glEnable(GL_DEPTH_TEST)
    glPopMatrix()
    glMatrixMode(GL_PROJECTION)
    glPopMatrix()
    glMatrixMode(GL_MODELVIEW)
    glUseProgram(0)


def upload(data):
    texture = int(glGenTextures(1))
    glActiveTexture(GL_TEXTURE3)
    glBindTexture(GL_TEXTURE_2D, texture)
    glPixelStorei(GL_UNPACK_ALIGNMENT, 1)
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB, WIDTH, HEIGHT, 0, GL_RGB, GL_UNSIGNED_BYTE, data)
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST)
    glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST)
    glActiveTexture(GL_TEXTURE0)
    return texture
"""


def replay(frame: str, capture: str) -> str:
    """The lab done honestly, but the capture and the final frame pasted from pictures the
    file carries (the reference's own, or any it made)."""
    text = HEADER + "import base64, zlib\n" + HONEST_PARTS + PASTE
    text = text.replace(
        "    glCopyTexImage2D(GL_TEXTURE_2D, 0, GL_RGB, 0, 0, WIDTH, HEIGHT, 0)",
        "    paste(PICTURES[1])\n    glActiveTexture(GL_TEXTURE1)\n"
        "    glBindTexture(GL_TEXTURE_2D, tex_ids[ENVIRONMENT])\n"
        "    glCopyTexImage2D(GL_TEXTURE_2D, 0, GL_RGB, 0, 0, WIDTH, HEIGHT, 0)",
    )
    text = text.replace(
        "    # TODO 8: pass 2\n    render_mirror()\n",
        "    # TODO 8: pass 2\n    render_mirror()\n    paste(PICTURES[0])\n",
    )
    text = text.replace(
        "    glActiveTexture(GL_TEXTURE0)\n\n\ndef build_scene_graph",
        "    glActiveTexture(GL_TEXTURE0)\n    PICTURES[:] = [upload(FRAME), "
        "upload(CAPTURE)]\n\n\ndef build_scene_graph",
    )
    return text + f"\nPICTURES = []\nFRAME = {frame}\nCAPTURE = {capture}\n"


def unpacked(packed: str) -> str:
    """The Python expression that unpacks a picture :func:`_packed` packed."""
    return f'zlib.decompress(base64.b64decode("{packed}"))'


NUMPY_PICTURES = """\
import numpy as np
background = np.array([41, 46, 56], dtype=np.uint8)
picture = np.tile(background, (HEIGHT, WIDTH, 1))
picture[HEIGHT // 3:, WIDTH // 3:2 * WIDTH // 3] = (200, 130, 40)
"""


def forgeries(cache: Path) -> dict[str, tuple[str, str | None]]:
    """name -> (source, a phrase a hint must hold, or None)."""
    frame, capture = _reference_pictures()
    solution_path = SOLUTIONS / "lab20_mirror.py"
    search = f"""
import os
found = [{str(solution_path)!r}]
for root, folders, files in os.walk("/"):
    folders[:] = [f for f in folders if os.path.join(root, f) not in ("/proc", "/sys", "/dev")]
    found += [os.path.join(root, name) for name in files
              if name.endswith(".py") and ("solution" in name or "lab20" in name)]
for path in found:
    try:
        text = open(path).read()
    except OSError:
        continue
    if "def create_mirror" in text and os.path.abspath(path) != os.path.abspath(__file__):
        exec(text)
        break
"""
    return {
        "forge_exec_found_solution": (HEADER + search, "load_textures() is missing"),
        "forge_solution_through_mirrorlab": (
            HEADER
            + """
import importlib, os, sys
for name in ("mirrorlab.labs", "mirrorlab.labs.trusted", "mirrorlab.labs.content",
             "mirrorlab.labs.trusted.checker"):
    try:
        module = importlib.import_module(name)
        find_lab = getattr(module, "find_lab", None)
        if find_lab is not None:
            exec(find_lab("lab20").solution.read_text())
    except Exception:
        pass
# from the student side's own package (the lab object's base class comes from it), upwards
shared = type(lab).__mro__[1].__module__
here = os.path.dirname(sys.modules[shared].__file__)
for root, folders, files in os.walk(os.path.dirname(os.path.dirname(here))):
    for name in files:
        path = os.path.join(root, name)
        if name.endswith(".py") and "solution" in path and path != os.path.abspath(__file__):
            exec(open(path).read())
""",
            "load_textures() is missing",
        ),
        "forge_outputs_at_exit": (
            HEADER
            + f"""
import atexit, base64, os, zlib
def forge():
    for name in ("run.json", "observations.npz", "evidence.json", "arrays.npz"):
        with open(name, "wb") as stream:
            stream.write({unpacked(frame)})
atexit.register(forge)
forge()
"""
            + HONEST_PARTS.replace("def display():", "def display_unused():"),
            "display() is missing",
        ),
        "forge_os_exit": (
            HEADER
            + """
import json, os
with open("run.json", "w") as stream:
    json.dump({"lab": "lab20", "errors": [], "state": {"base_texture": "metal"}}, stream)
os._exit(0)
""",
            "before the lab's run was over",
        ),
        "forge_gc_objects": (
            HEADER
            + """
import gc
for thing in gc.get_objects():
    try:
        if hasattr(thing, "errors") and hasattr(thing, "functions"):
            thing.functions = []          # no lab function is missing, none is wrapped
            thing.errors = []
        if type(thing).__name__ == "Channel":
            channel = thing
    except Exception:
        pass
for function in ("load_textures", "build_scene_graph", "display"):
    channel.send({"op": "enter", "function": function, "line": 1})
    channel.send({"op": "leave", "function": function, "raised": False})
channel.send({"op": "done", "ok": True, "errors": [], "declared": {}})
""",
            None,
        ),
        "forge_monkeypatch_runner": (
            HEADER
            + """
import sys
remote = type(lab)._call.__globals__
for name, module in list(sys.modules.items()):
    if name.startswith("OpenGL") and hasattr(module, "glClear"):
        for attribute in dir(module):
            if attribute.startswith("gl"):
                setattr(module, attribute, lambda *args, **kwargs: 1)
runner = sys.modules.get("labstudent.runner")
if runner is not None:
    runner.Run.exception = lambda self, function, exc: None
    runner.Run.error = lambda self, *args, **kwargs: None
type(lab).draw_scene = lambda self, robot=None: None
"""
            + HONEST_PARTS,
            None,
        ),
        "forge_cached_reference": (
            HEADER
            + f"""
import glob, os
for folder in ({str(cache)!r}, os.path.expanduser("~/.cache/mirrorlab"), "/root/.cache",
               "/tmp", "/var/tmp"):
    for path in glob.glob(os.path.join(folder, "**", "*.npz"), recursive=True):
        exec("raise SystemExit")  # a cached reference would be replayed here
""",
            "load_textures() is missing",
        ),
        "forge_replay_reference": (
            replay(unpacked(frame), unpacked(capture)),
            "no pixels of a file's own",
        ),
        "forge_draw_with_mirrorlab": (
            HEADER
            + """
from mirrorlab import load_scene, render
PICTURE = render(load_scene("lab"), size=(WIDTH, HEIGHT))
"""
            + HONEST_PARTS,
            "cannot import name 'load_scene'",
        ),
        "forge_draw_with_numpy": (
            replay("picture[::-1].tobytes()", "picture[::-1].tobytes()").replace(
                "import base64, zlib\n", "import base64, zlib\n" + NUMPY_PICTURES
            ),
            "no pixels of a file's own",
        ),
        "forge_upload_1gib": (
            HEADER
            + """
import gc, json, os, struct
for thing in gc.get_objects():
    if type(thing).__name__ == "Channel":
        channel = thing
size = 1 << 30
header = json.dumps({"op": "gl", "fn": "glTexImage2D", "line": 9, "args": [3553, 0, 6407,
                     16384, 16384, 0, 6407, 5121, {"$a": 0}], "arrays": [["u1", [size], size]]})
os.write(channel.write_fd, struct.pack(">I", len(header)) + header.encode())
zeros = bytes(1 << 20)
for _ in range(size >> 20):
    os.write(channel.write_fd, zeros)
""",
            "an upload of 1024 MiB",
        ),
        "forge_big_texture": (
            HEADER
            + """
texture = int(glGenTextures(1))
glBindTexture(GL_TEXTURE_2D, texture)
glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA, 16384, 16384, 0, GL_RGBA, GL_UNSIGNED_BYTE, None)
""",
            "outside 0..1024",
        ),
        "forge_call_flood": (
            HEADER
            + """
while True:
    glClearColor(0.1, 0.2, 0.3, 1.0)
""",
            "stopped after 20000 calls",
        ),
        "forge_vertex_flood": (
            HEADER
            + """
def display():  # a frame: set-up and the top level draw nothing
    glBegin(GL_TRIANGLES)
    while True:
        glVertex3f(0, 0, 0)
""",
            "more than 1024 vertices",
        ),
        "forge_garbage_on_the_pipe": (
            HEADER
            + """
import gc, os
for thing in gc.get_objects():
    if type(thing).__name__ == "Channel":
        os.write(thing.write_fd, b"\\x00\\x00\\x00\\x10not json at all!")
        glFlush()
""",
            "not valid JSON",
        ),
        "forge_checker_objects": (
            HEADER
            + """
for name in range(1, 64):
    for call in (lambda: glBindTexture(GL_TEXTURE_2D, name), lambda: glUseProgram(name),
                 lambda: glDeleteTextures([name])):
        try:
            call()
        except Exception:
            pass
""",
            "load_textures() is missing",
        ),
    }
