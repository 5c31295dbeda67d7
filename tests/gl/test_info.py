"""``mirrorlab info`` and ``render --stats`` name the OpenGL mirrorlab chose: the backend the
chooser picks here, its version and profile as the context reports them, and the draw
path; in the simulated macOS run, a hidden window's 4.1 core, forward-compatible context
drawn per draw, and no sandbox. (Without OpenGL at all: tests/labs/test_not_graded.py.)"""

from __future__ import annotations

import json
import subprocess
import sys

import mirrorlab
from mirrorlab.gl.context import choose
from mirrorlab.labs.trusted.sandbox import sandbox_mode

LABELS = (
    "mirrorlab",
    "system",
    "python",
    "packages",
    "chosen",
    "OpenGL",
    "profile",
    "renderer",
    "backend",
    "draw path",
    "EGL",
    "display",
    "sandbox",
    "bubblewrap",
    "scratch",
    "labs",
    "environment",
)


def mirrorlab_says(*args: str, cwd) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "mirrorlab.cli", *args],
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=300,
    )


def test_info_names_the_opengl_chosen_and_the_sandbox(tmp_path):
    done = mirrorlab_says("info", "--json", cwd=tmp_path)
    assert done.returncode == 0 and done.stderr == "", done.stdout + done.stderr
    found = json.loads(done.stdout)
    chosen = choose("offscreen", new_process=True)
    opengl = found["opengl"]
    assert found["mirrorlab"] == mirrorlab.__version__
    assert (opengl["backend"], opengl["platform"]) == (chosen.backend, chosen.platform)
    version = tuple(int(n) for n in opengl["version"].split(" ")[0].split(".")[:2])
    if chosen.core:  # asked for 4.1 core, forward-compatible (macOS, MIRRORLAB_GL_CORE=1)
        assert opengl["profile"] == "core profile, forward-compatible", opengl
    else:  # Mesa gives its compatibility profile when none is asked for
        assert opengl["profile"] == "compatibility profile", opengl
    assert opengl["draw_path"] == ("packed" if version >= (4, 3) else "per-draw"), opengl
    mode = sandbox_mode()
    assert found["sandbox"].startswith("bubblewrap" if mode == "bwrap" else "none ("), found
    assert found["scratch"].startswith("tmpfs" if mode == "bwrap" else "watched"), found
    text = mirrorlab_says("info", cwd=tmp_path)
    assert text.returncode == 0, text.stderr
    shown = [line[:12].strip() for line in text.stdout.splitlines()]
    assert shown == list(LABELS), text.stdout


def test_render_stats_names_the_backend_and_profile(tmp_path):
    done = mirrorlab_says(
        "render", "--size", "32x32", "--out", str(tmp_path / "f.png"), "--stats", cwd=tmp_path
    )
    assert done.returncode == 0, done.stderr
    said = [line for line in done.stdout.splitlines() if line.startswith("OpenGL: ")]
    chosen = choose("offscreen", new_process=True)
    profile = "core profile, forward-compatible" if chosen.core else "compatibility profile"
    assert len(said) == 1, done.stdout
    assert said[0].startswith(f"OpenGL: backend {chosen.backend} (PyOpenGL {chosen.platform}), ")
    assert f", {profile}, " in said[0] and "; draw path " in said[0], said[0]
