"""``mirrorlab lab run``: the window belongs to the trusted process and the student's file
runs in the sandbox, its calls drawn in the window (glfw on Xvfb) as the headless check
draws them; an error in it is one line naming the task and the line; and the file can
reach nothing outside its sandbox."""

from __future__ import annotations

import os
import subprocess
import sys

from mirrorlab.labs import find_lab
from mirrorlab.labs.trusted.gl_process import run_job
from mirrorlab.labs.trusted.sandbox import Limits, sandboxed
from mirrorlab.labs.trusted.variants import default_variant
from mirrorlab.scene.backgrounds import load_picture
from mirrorlab.testing import assert_image_close
from tests import REPO_DIR

SOLUTION = REPO_DIR / "labs" / "solutions" / "lab20_mirror.py"


def lab_run(*args: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYOPENGL_PLATFORM": "glx"}
    return subprocess.run(
        [sys.executable, "-m", "mirrorlab.cli", "lab", "run", *args],
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
    )


def error_lines(done: subprocess.CompletedProcess) -> list[str]:
    """The lines ``lab run`` wrote on stderr, but the one note it writes where there is no
    sandbox (as on macOS and Windows, and in the simulated macOS run), which must then be
    there, once."""
    lines = [text for text in done.stderr.splitlines() if text.strip()]
    notes = [text for text in lines if "note: not sandboxed" in text]
    assert len(notes) == (0 if sandboxed() else 1), done.stderr
    return [text for text in lines if text not in notes]


def test_lab_run_shows_the_solution_as_the_check_sees_it(tmp_path):
    shot = tmp_path / "window.png"
    done = lab_run(
        "lab20", str(SOLUTION), "--size", "256x256", "--max-frames", "3", "--screenshot", str(shot)
    )
    assert done.returncode == 0, done.stderr
    limits = Limits(cpu_seconds=5, seconds=60, unsandboxed=not sandboxed())
    evidence = run_job(
        find_lab("lab20"),
        SOLUTION.read_bytes(),
        "solution.py",
        default_variant("lab20"),
        limits,
        (256, 256),
    )
    assert evidence.status == "ok", evidence.detail
    frame = evidence.arrays["frame"]
    window = load_picture(shot)
    assert window.shape == frame.shape == (256, 256, 3)
    assert_image_close(window, frame, tolerance=8, fraction=0.99, name="lab_run_window")


def test_lab_run_names_the_task_and_line_of_an_error(tmp_path):
    source = SOLUTION.read_text().replace("gluLookAt(MIRROR_X, 0, 0,", "gluLookAt(MIRROR_X, 0,")
    broken = tmp_path / "broken.py"
    broken.write_text(source)
    line = next(
        i for i, text in enumerate(source.splitlines(), 1) if text.strip().startswith("gluLookAt(")
    )
    done = lab_run("lab20", str(broken), "--max-frames", "2")
    assert done.returncode == 1
    lines = error_lines(done)
    assert len(lines) == 1, done.stderr
    assert (
        "in create_mirror() (task 1 (capture_camera): the capture's orthographic "
        f"projection and camera), line {line}"
    ) in lines[0] and "TypeError" in lines[0]


def test_lab_run_keeps_the_file_in_its_sandbox(tmp_path):
    """The student's code runs in the sandbox, not in the window's process: the folders
    around it are not even there for it."""
    target = tmp_path / "written_by_the_lab_file.txt"
    evil = tmp_path / "evil.py"
    evil.write_text(f"open({str(target)!r}, 'w').write('escaped')\n" + SOLUTION.read_text())
    done = lab_run("lab20", str(evil), "--max-frames", "1")
    assert done.returncode == 1
    lines = error_lines(done)
    assert len(lines) == 1 and "while loading the file, line 1" in lines[0], done.stderr
    assert "No such file or directory" in lines[0]
    assert not target.exists()
