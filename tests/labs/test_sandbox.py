"""The sandbox's limits without bubblewrap (the fallback where bwrap does not work: a user
id of its own), and the checker's own memory while a submission exhausts its."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from mirrorlab.labs import LABS
from mirrorlab.labs.trusted import sandbox
from mirrorlab.labs.trusted.sandbox import Limits, new_box, run_sandboxed, uid_processes

SYSTEM_PYTHON = "/usr/bin/python3"


@pytest.fixture
def user_mode(monkeypatch):
    """Run as the fallback does: no bubblewrap, a user id of its own. (The fallback needs an
    interpreter other users may run: Debian's own python3, here.)"""
    if os.geteuid() != 0:
        pytest.fail("the user-id fallback is tested as root (./dev test runs as root in CI)")
    assert Path(SYSTEM_PYTHON).is_file(), "Debian's python3 is missing"
    monkeypatch.setattr(sandbox, "sandbox_mode", lambda: "user")


SHORT = Limits(cpu_seconds=3, seconds=60)


def run_python(code: str, tmp_path: Path, limits: Limits = SHORT):
    box = new_box(tmp_path)
    code_and_time = run_sandboxed([SYSTEM_PYTHON, "-c", code], box, limits)
    return (*code_and_time, (box / "stderr.txt").read_text())


def test_user_fallback_cannot_write_outside_its_box(user_mode, tmp_path):
    target = tmp_path / "precious.txt"
    target.write_text("keep me")
    tmp_path.chmod(0o755)
    code, _, stopped, stderr = run_python(
        f"open({str(target)!r}, 'w').write('gone')", tmp_path)
    assert code == 1 and stopped == "" and "PermissionError" in stderr
    assert target.read_text() == "keep me"
    code, _, _, stderr = run_python("open('mine.txt', 'w').write('ok'); print('ok')", tmp_path)
    assert code == 0, stderr


def test_user_fallback_stops_a_fork_bomb_and_leaves_no_process(user_mode, tmp_path):
    code, _, stopped, _ = run_python(
        "import os\nwhile True:\n    try:\n        os.fork()\n    except OSError:\n        pass\n",
        tmp_path)
    assert code is None and stopped == "processes"
    assert uid_processes(sandbox.sandbox_uid()) == []


def test_user_fallback_limits_memory_and_cpu(user_mode, tmp_path):
    code, _, _, stderr = run_python("x = bytearray(8 << 30)", tmp_path,
                                    Limits(cpu_seconds=3, seconds=60, memory_mb=512))
    assert code == 1 and "MemoryError" in stderr
    code, _, stopped, _ = run_python("while True: pass", tmp_path)
    assert code == -24 and stopped == ""  # SIGXCPU at the CPU-time limit


def test_the_checker_stays_small_while_a_submission_exhausts_its_memory(tmp_path):
    hog = tmp_path / "hog.py"
    # untouched zero pages (bytes, not bytearray): the memory limit, never the CPU limit,
    # stops it, however loaded the machine (see classroom.py)
    hog.write_text("hog = []\nwhile True:\n    hog.append(bytes(256 << 20))\n")
    # VmHWM: this process's own peak resident memory (ru_maxrss would also count what the
    # forked pytest process held before exec)
    script = ("import sys\nfrom mirrorlab.cli import main\n"
              "code = main(sys.argv[1:])\n"
              "status = open('/proc/self/status').read()\n"
              "print('peak', status.split('VmHWM:')[1].split()[0])\n"
              "sys.exit(code)\n")
    done = subprocess.run([sys.executable, "-c", script, "lab", "check", "lab20", str(hog),
                           "--out", str(tmp_path / "hog.png"), "--memory", "1024",
                           "--timeout", "5"], capture_output=True, text=True)
    assert done.returncode == 1, done.stderr
    assert "MemoryError" in done.stdout
    peak_kib = int(done.stdout.split("peak ")[1].split()[0])
    assert peak_kib < 400 * 1024, f"the checker itself peaked at {peak_kib} KiB"
    assert LABS["lab20"].tasks  # the lab was judged, each task failed with the error
