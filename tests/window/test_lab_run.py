"""``mirrorlab lab run``: the window belongs to the trusted process and the student's file
runs in the sandbox, its calls drawn in the window (glfw on Xvfb) as the headless check
draws them; an error in it is one line naming the task and the line; and the file can
reach nothing outside its sandbox."""

from __future__ import annotations

import os
import subprocess
import sys
import threading

from mirrorlab.labs import find_lab
from mirrorlab.labs.trusted.gl_process import run_job
from mirrorlab.labs.trusted.sandbox import Limits, sandboxed
from mirrorlab.labs.trusted.variants import default_variant
from mirrorlab.scene.backgrounds import load_picture
from mirrorlab.testing import assert_image_close
from tests import REPO_DIR
from tests.window.xwindow import GIVE_UP_S, find_window, press, screenshot, wait_for

SOLUTION = REPO_DIR / "labs" / "solutions" / "lab20_mirror.py"


def lab_run(*args: str, cwd=None) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYOPENGL_PLATFORM": "glx"}
    return subprocess.run(
        [sys.executable, "-m", "mirrorlab.cli", "lab", "run", *args],
        capture_output=True,
        text=True,
        env=env,
        timeout=300,
        cwd=cwd,
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


class LabRun:
    """``mirrorlab lab run ARGS`` in a process of its own, its stderr read as it comes."""

    def __init__(self, *args: str, cwd=None) -> None:
        env = {**os.environ, "PYOPENGL_PLATFORM": "glx"}
        self.process = subprocess.Popen(
            [sys.executable, "-m", "mirrorlab.cli", "lab", "run", *args],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            env=env,
            cwd=cwd,
        )
        self.errors: list[str] = []
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self) -> None:
        assert self.process.stderr is not None
        for line in self.process.stderr:
            self.errors.append(line)

    def __enter__(self) -> LabRun:
        return self

    def __exit__(self, *exc: object) -> None:
        if self.process.poll() is None:
            self.process.kill()
        self.process.communicate()

    def finish(self) -> int:
        code = self.process.wait(timeout=GIVE_UP_S)
        self.reader.join(GIVE_UP_S)
        return code


def test_lab_run_without_a_file_runs_the_folders_starter(tmp_path):
    """As ``lab check`` does: the ``starter.py`` of the folder it runs in, here a finished
    one; and a folder without one is refused in one line."""
    (tmp_path / "starter.py").write_text(SOLUTION.read_text())
    shot = tmp_path / "window.png"
    done = lab_run(
        "lab20", "--size", "128x128", "--max-frames", "2", "--screenshot", str(shot), cwd=tmp_path
    )
    assert done.returncode == 0, done.stderr
    limits = Limits(cpu_seconds=5, seconds=60, unsandboxed=not sandboxed())
    evidence = run_job(
        find_lab("lab20"),
        SOLUTION.read_bytes(),
        "solution.py",
        default_variant("lab20"),
        limits,
        (128, 128),
    )
    assert_image_close(
        load_picture(shot),
        evidence.arrays["frame"],
        tolerance=8,
        fraction=0.99,
        name="lab_run_starter",
    )
    empty = tmp_path / "empty"
    empty.mkdir()
    refused = lab_run("lab20", "--max-frames", "1", cwd=empty)
    assert refused.returncode == 2 and "holds no starter.py" in refused.stderr, refused.stderr
    assert len(refused.stderr.strip().splitlines()) == 1


def test_a_tap_of_esc_closes_a_window_whose_frames_are_slow(xdisplay, tmp_path):
    """Esc is a key callback, not a look once a frame: a tap while a frame takes half a
    second (pressed and released before the frame ends) still closes the window."""
    slow = tmp_path / "slow.py"
    slow.write_text(
        "import time\n"
        + SOLUTION.read_text().replace(
            "def display():\n", "def display():\n    time.sleep(0.5)\n", 1
        )
    )
    with LabRun("lab20", str(slow), "--size", "128x128", cwd=tmp_path) as run:
        window = find_window(xdisplay, "mirrorlab lab lab20 - slow.py")
        wait_for(lambda: screenshot(xdisplay, window).any(), "the first frame")
        press(xdisplay, window, "Escape")
        assert run.finish() == 0, "".join(run.errors)


def test_lab_run_watch_runs_each_save_in_the_same_window(xdisplay, tmp_path):
    mine = tmp_path / "mine.py"
    mine.write_text(SOLUTION.read_text())
    with LabRun("lab20", "mine.py", "--watch", "--size", "128x128", cwd=tmp_path) as run:
        window = find_window(xdisplay, "mirrorlab lab lab20 - mine.py")
        first = wait_for(
            lambda: (lambda image: image if image.any() else None)(screenshot(xdisplay, window)),
            "the first frame",
        )
        assert tuple(first[0, 0]) != (255, 0, 0)
        staging = tmp_path / ".mine.py.swp"  # saved as vim saves: a new file renamed
        staging.write_text(
            SOLUTION.read_text().replace(
                "    create_mirror()\n    glClear(",
                "    create_mirror()\n    glClearColor(1, 0, 0, 1)\n    glClear(",
                1,
            )
        )
        os.replace(staging, mine)
        wait_for(
            lambda: tuple(screenshot(xdisplay, window)[0, 0]) == (255, 0, 0),
            "the saved file's frame in the same window",
        )
        press(xdisplay, window, "Escape")
        assert run.finish() == 0, "".join(run.errors)
    assert any("mine.py saved: running it again" in line for line in run.errors), run.errors
