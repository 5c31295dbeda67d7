"""A grade is never made from the checker's own failure. Without OpenGL (no EGL, no display:
libEGL.so.1 hidden, as a new user's machine lacks it), ``lab check`` says render's one line
and ``lab grade`` stops before it writes anything; on a full disk every submission is "not
graded" (no score, named, exit 1), never a zero; a checker process killed from outside is
run again, and the file is judged; whose failure a failing checker is follows from a
second run and a control, never from the file (failures.run_attributed)."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from mirrorlab.errors import GLContextError
from mirrorlab.labs import find_lab
from mirrorlab.labs.trusted.evidence import Evidence
from mirrorlab.labs.trusted.failures import control_source, run_attributed
from mirrorlab.labs.trusted.gl_process import CheckerError, MachineError
from mirrorlab.labs.trusted.sandbox import Limits
from mirrorlab.labs.trusted.variants import default_variant
from tests import REPO_DIR
from tests.labs.conftest import SOLUTIONS, mirrorlab_command, read_csv


def without_opengl(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    """``mirrorlab ARGS`` with libEGL.so.1 an empty file (bwrap) and no DISPLAY."""
    bwrap = shutil.which("bwrap")
    assert bwrap, "bubblewrap is needed to hide EGL (./dev setup installs it)"
    hide = [bwrap, "--dev-bind", "/", "/", "--die-with-parent"]
    listed = subprocess.run(["/sbin/ldconfig", "-p"], capture_output=True, text=True).stdout
    for line in listed.splitlines():
        if line.strip().startswith("libEGL.so.1 "):
            hide += ["--ro-bind", "/dev/null", os.path.realpath(line.split("=>")[1].strip())]
    environment = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    return subprocess.run(
        [*hide, sys.executable, "-m", "mirrorlab.cli", *args],
        capture_output=True,
        text=True,
        cwd=cwd,
        env=environment,
        timeout=300,
    )


def test_without_opengl_each_command_says_renders_one_line_and_grades_nobody(tmp_path):
    rendered = without_opengl("render", "--size", "32x32", "--out", "r.png", cwd=tmp_path)
    lines = rendered.stderr.strip().splitlines()
    assert rendered.returncode == 1 and len(lines) == 1, rendered.stderr
    said = lines[0].split(": error: ", 1)[1]
    assert said.startswith("no OpenGL for offscreen rendering: libEGL.so.1 cannot be loaded")
    started = mirrorlab_command("lab", "start", "lab20", str(tmp_path / "mine"))
    assert started.returncode == 0, started.stderr
    checked = without_opengl("lab", "check", "lab20", "mine/starter.py", cwd=tmp_path)
    assert checked.returncode == 1 and checked.stdout == "", checked.stdout + checked.stderr
    assert checked.stderr.strip().splitlines() == [f"mirrorlab lab: error: {said}"]
    # a window needs a display: lab run says the window's one line (the demo's), no more
    ran = without_opengl(
        "lab", "run", "lab20", "mine/starter.py", "--max-frames", "1", cwd=tmp_path
    )
    assert ran.returncode == 1 and len(ran.stderr.strip().splitlines()) == 1, ran.stderr
    assert ran.stderr.startswith("mirrorlab lab: error: no display for a window"), ran.stderr
    submissions = tmp_path / "class"
    submissions.mkdir()
    for name in ("ann", "bob"):
        shutil.copy(SOLUTIONS / "lab20_mirror.py", submissions / f"{name}.py")
    graded = without_opengl(
        "lab", "grade", "lab20", "class", "--out-dir", "grades", "--jobs", "2", cwd=tmp_path
    )
    assert graded.returncode == 2, graded.stdout + graded.stderr
    assert graded.stderr.strip().splitlines() == [
        f"mirrorlab lab: error: grading stopped, nothing written: {said}"
    ]
    assert not (tmp_path / "grades").exists() and graded.stdout == ""
    info = without_opengl("info", cwd=tmp_path)
    assert info.returncode == 1 and info.stderr == "", info.stderr
    assert f"OpenGL      none: {said}" in info.stdout.splitlines()


def test_a_full_disk_grades_nobody_and_books_no_zero(tmp_path):
    """The temporary folder on a file system with one free page (a tmpfs of this test's
    own mount namespace): the checker cannot write a check's files, so each submission is
    not graded, named, its gradebook cells empty; exit 1."""
    unshare = shutil.which("unshare")
    if os.geteuid() != 0 or unshare is None:
        pytest.fail("a file system of the test's own needs root and unshare (CI runs as root)")
    full = tmp_path / "full"
    full.mkdir()
    submissions = tmp_path / "class"
    submissions.mkdir()
    shutil.copy(SOLUTIONS / "lab20_mirror.py", submissions / "ann.py")
    (submissions / "bob.py").write_text("from mirrorlab.labs import kit\nlab = kit.lab20()\n")
    out = tmp_path / "grades"
    script = (
        f"mount -t tmpfs -o size=64k tmpfs {full} && "
        f"head -c {60 << 10} /dev/zero > {full}/fill && "
        f'exec "$@"'
    )
    environment = {**os.environ, "TMPDIR": str(full)}
    environment.pop("MIRRORLAB_SOLUTIONS")  # the shipped reference: nothing made here
    grade = ["lab", "grade", "lab20", str(submissions), "--out-dir", str(out), "--jobs", "1"]
    inside = [unshare, "--mount", "sh", "-c", script, "sh"]
    done = subprocess.run(
        [*inside, sys.executable, "-m", "mirrorlab.cli", *grade],
        capture_output=True,
        text=True,
        env=environment,
        cwd=REPO_DIR,
        timeout=300,
    )
    assert done.returncode == 1, done.stdout + done.stderr
    printed = [line for line in done.stdout.splitlines() if line.startswith("not graded: ")]
    assert [line.split(":")[1].strip() for line in printed] == ["'ann'", "'bob'"], done.stdout
    assert all("No space left on device" in line for line in printed), printed
    assert "0 submissions" in done.stdout and "2 not graded" in done.stdout, done.stdout
    book = read_csv(out / "gradebook.csv")
    assert [(r["student"], r["score"], r["percent"]) for r in book] == [
        ("ann", "", ""),
        ("bob", "", ""),
    ]
    assert all("No space left on device" in r["not_graded"] for r in book)
    assert {r["passed"] for r in read_csv(out / "grades.csv")} == {"not graded"}
    page = (out / "feedback" / "ann.html").read_text()
    assert "Not graded" in page and "0 of 8" not in page


def test_a_checker_killed_from_outside_is_run_again_and_the_file_judged(tmp_path):
    """The checker's OpenGL process SIGKILLed while it runs the honest solution (as an
    out-of-memory killer or a crashed driver would): the check runs it again and passes."""
    check = ["lab", "check", "lab20", str(SOLUTIONS / "lab20_mirror.py")]
    command = subprocess.Popen(
        [sys.executable, "-m", "mirrorlab.cli", *check, "--out", str(tmp_path / "c.png")],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    killed: list[int] = []

    def kill_the_first_checker() -> None:
        while command.poll() is None and not killed:
            for entry in Path("/proc").iterdir():
                try:
                    line = (entry / "cmdline").read_bytes().split(b"\0")
                    parent = int((entry / "stat").read_text().rsplit(")", 1)[1].split()[1])
                except (OSError, ValueError, IndexError):
                    continue
                if parent == command.pid and b"mirrorlab.labs.trusted.gl_process" in line:
                    os.kill(int(entry.name), signal.SIGKILL)
                    killed.append(int(entry.name))
                    return
            time.sleep(0.01)

    watcher = threading.Thread(target=kill_the_first_checker)
    watcher.start()
    stdout, stderr = command.communicate(timeout=600)
    watcher.join()
    assert killed, "the checker's process was never seen"
    assert command.returncode == 0 and "8/8 tasks passed" in stdout, stdout + stderr


# ----------------------------------------------------------------- whose failure: the policy
SPEC = find_lab("lab20")
VARIANT = default_variant("lab20")
LIMITS = Limits()
GOOD = Evidence("lab20", "ok", "")


class Checker:
    """A stand-in for run_job that fails as told, recording each file it was given: the
    policy's decisions, not the GL (those are the tests above)."""

    def __init__(self, *outcomes: object) -> None:
        self.outcomes = list(outcomes)
        self.files: list[tuple[bytes, bool]] = []

    def __call__(self, spec, source, name, variant, limits, size, keep) -> Evidence:
        self.files.append((source, keep))
        outcome = self.outcomes.pop(0)
        if isinstance(outcome, BaseException):
            raise outcome
        assert isinstance(outcome, Evidence)
        return outcome


def attribute(checker: Checker) -> Evidence:
    return run_attributed(SPEC, b"# file", "f.py", VARIANT, LIMITS, (64, 64), True, checker)


def test_whose_failure_a_second_run_and_a_control_decide():
    died = CheckerError("the checker's OpenGL process died (signal 9)")
    # a run that works is the verdict, at once
    checker = Checker(GOOD)
    assert attribute(checker) is GOOD and len(checker.files) == 1
    # a failure once, then a verdict: never the file's (the second run is in a new process)
    checker = Checker(died, GOOD)
    assert attribute(checker) is GOOD and [keep for _, keep in checker.files] == [True, False]
    # twice, while the untouched starter runs: the file's calls make the checker fail
    checker = Checker(died, died, Evidence("lab20", "ok", ""))
    judged = attribute(checker)
    assert judged.status == "crashed" and "twice" in judged.detail, judged.detail
    assert checker.files[2][0] == control_source(SPEC, VARIANT)
    # twice, and the starter fails too: the checker fails here, whatever the file
    checker = Checker(died, died, died)
    with pytest.raises(CheckerError, match="the checker itself fails"):
        attribute(checker)
    # the machine's own failures are never retried, never judged
    for failure in (MachineError("disk full"), GLContextError("no OpenGL")):
        checker = Checker(failure)
        with pytest.raises(type(failure)):
            attribute(checker)
        assert len(checker.files) == 1
