"""``mirrorlab lab run``: a student's lab file in a real window (glfw on Xvfb) draws what the
headless check draws, and an error in it is one line naming the task and the line."""

from __future__ import annotations

import os
import subprocess
import sys

import numpy as np

from mirrorlab.labs import LABS
from mirrorlab.scene.backgrounds import load_picture
from mirrorlab.testing import assert_image_close


def run(*args: str, platform: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYOPENGL_PLATFORM": platform}
    return subprocess.run([sys.executable, *args], capture_output=True, text=True, env=env,
                          timeout=300)


def test_lab_run_shows_the_solution_as_the_check_sees_it(tmp_path):
    solution = str(LABS["lab20"].solution)
    shot = tmp_path / "window.png"
    done = run("-m", "mirrorlab.cli", "lab", "run", "lab20", solution, "--size", "256x256",
               "--max-frames", "3", "--screenshot", str(shot), platform="glx")
    assert done.returncode == 0, done.stderr
    headless = run("-m", "mirrorlab.labs.harness", "lab20", solution, str(tmp_path / "check"),
                   "--size", "256x256", platform="egl")
    assert headless.returncode == 0, headless.stderr
    with np.load(tmp_path / "check" / "observations.npz") as observed:
        frame = observed["frame"]
    window = load_picture(shot)
    assert window.shape == frame.shape == (256, 256, 3)
    assert_image_close(window, frame, tolerance=8, fraction=0.99, name="lab_run_window")


def test_lab_run_names_the_task_and_line_of_an_error(tmp_path):
    source = LABS["lab20"].solution.read_text().replace("gluLookAt(-7, 0, 0,", "gluLookAt(-7, 0,")
    broken = tmp_path / "broken.py"
    broken.write_text(source)
    line = next(i for i, text in enumerate(source.splitlines(), 1)
                if text.strip().startswith("gluLookAt("))
    done = run("-m", "mirrorlab.cli", "lab", "run", "lab20", str(broken), "--max-frames", "2",
               platform="glx")
    assert done.returncode == 1
    lines = [text for text in done.stderr.splitlines() if text.strip()]
    assert len(lines) == 1, done.stderr
    assert f"in create_mirror() (task 1: the capture's orthographic projection and camera), " \
           f"line {line}" in lines[0] and "TypeError" in lines[0]
