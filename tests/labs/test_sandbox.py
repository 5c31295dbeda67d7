"""The sandbox from anywhere: a clone and its venv two folders deep under the temporary
folder, an interpreter under a closed home (pyenv's, under /root, here); a sandbox that
cannot start is one line and exit 2; no temporary folder is left after a run and none is
world-writable while it exists. Then its limits without bubblewrap (the fallback where
bwrap does not work: a user id of its own), and the checker's own memory while a
submission exhausts its."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from mirrorlab.labs import find_lab
from mirrorlab.labs.trusted import sandbox
from mirrorlab.labs.trusted.sandbox import Limits, new_box, run_sandboxed, uid_processes
from tests import REPO_DIR
from tests.labs.conftest import mirrorlab_command

SYSTEM_PYTHON = "/usr/bin/python3"


@pytest.fixture
def user_mode(monkeypatch):
    """Run as the fallback does: no bubblewrap, a user id of its own. (The fallback needs an
    interpreter other users may run: Debian's own python3, here.)"""
    if os.geteuid() != 0:
        pytest.fail("the user-id fallback is tested as root (./dev test runs as root in CI)")
    assert Path(SYSTEM_PYTHON).is_file(), "Debian's python3 is missing"
    monkeypatch.setattr(sandbox, "sandbox_mode", lambda: "user")


SHORT = Limits(cpu_seconds=3, seconds=60, unsandboxed=True)
"""The fallback is no sandbox: a run there must say it may go without one."""


def test_a_clone_and_its_venv_two_folders_deep_check_a_lab(tmp_path):
    """A fresh clone at TMP/x/y/clone with its own venv (the interpreter stays pyenv's under
    /root, closed to other users): the sandbox's student side, interpreter and numpy are
    all reached, and the solution passes from the clone's own folder."""
    clone = tmp_path / "x" / "y" / "clone"
    clone.mkdir(parents=True)
    for folder in ("mirrorlab", "labs", "scenes", "models", "textures"):
        shutil.copytree(
            REPO_DIR / folder, clone / folder, ignore=shutil.ignore_patterns("__pycache__")
        )
    for name in ("pyproject.toml", "README.md", "LICENSE"):
        shutil.copy(REPO_DIR / name, clone / name)
    venv = clone / ".venv"
    subprocess.run([sandbox.interpreter(), "-m", "venv", "--without-pip", str(venv)], check=True)
    site = next(venv.glob("lib/python3*/site-packages"))
    # the dependencies of this venv (no second download; pip too), and the clone installed
    # in place, as ./dev installs a checkout (its data folders are mapped into the package)
    (site / "dependencies.pth").write_text(f"{Path(np.__file__).parent.parent}\n")
    subprocess.run(
        [
            str(venv / "bin" / "python"),
            "-m",
            "pip",
            "install",
            "-q",
            "--no-deps",
            "--disable-pip-version-check",
            "-e",
            str(clone),
        ],
        check=True,
        capture_output=True,
    )
    for parent in (tmp_path / "x", tmp_path / "x" / "y", clone):
        parent.chmod(0o700)
    cache = tmp_path / "cache"
    done = subprocess.run(
        [
            str(venv / "bin" / "python"),
            "-m",
            "mirrorlab.cli",
            "lab",
            "check",
            "lab20",
            "labs/solutions/lab20_mirror.py",
            "--solutions",
            "labs/solutions",
            "--out",
            str(tmp_path / "c.png"),
            "--timeout",
            "10",
        ],
        cwd=clone,
        capture_output=True,
        text=True,
        env={**os.environ, "MIRRORLAB_CACHE": str(cache)},
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert "8/8 tasks passed" in done.stdout
    found = subprocess.run(
        [
            str(venv / "bin" / "python"),
            "-c",
            "import mirrorlab.labs.trusted.sandbox as s; print(s.__file__)",
        ],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        check=True,
    )
    assert found.stdout.strip().startswith(str(clone))
    # what the sandbox built from this clone shows: nothing of the clone's path (its
    # site-packages and package folder, hidden, lie in the sandbox's own fresh /tmp)
    probe = subprocess.run(
        [str(venv / "bin" / "python"), "-c", LIST_SANDBOX, str(tmp_path)],
        cwd=tmp_path,
        capture_output=True,
        text=True,
    )
    assert probe.returncode == 0, probe.stderr
    assert str(clone) not in probe.stdout and "/x/y" not in probe.stdout, probe.stdout


LIST_SANDBOX = r"""
import shutil, sys
from pathlib import Path
from mirrorlab.labs.trusted.sandbox import Limits, Sandboxed, interpreter, new_box
box = new_box(Path(sys.argv[1]) / "boxes")
walk = ("import os\nfor r, d, f in os.walk('/'):\n"
        "    d[:] = [x for x in d if os.path.join(r, x) not in ('/proc', '/dev', '/usr')]\n"
        "    print(*[os.path.join(r, n) for n in d + f], sep='\\n')\n")
run = Sandboxed([str(interpreter()), "-I", "-S", "-c", walk], box,
                Limits(cpu_seconds=20, seconds=60))
code = run.wait()[0]
print((box / "stdout.txt").read_text())
shutil.rmtree(box)
sys.exit(code)
"""


def test_a_folder_hidden_from_the_sandbox_is_made_only_where_the_host_shows_through(tmp_path):
    """Hiding a folder mounts an empty one over it where a folder bound from the host would
    show it; within the sandbox's own fresh /tmp it shows nothing already, and a folder
    made there would give away the host's path."""
    assert str(tmp_path).startswith("/tmp/")
    site = tmp_path / "deep" / "site-packages"
    site.mkdir(parents=True)
    root = sandbox._Root()
    root.bound.append(Path("/tmp"))
    root.fresh.append(Path("/tmp"))
    root.hide(site)
    assert root.arguments == []
    root.bind(tmp_path / "deep")  # as an interpreter installed under the temporary folder
    root.hide(site)
    assert root.arguments[-2:] == ["--tmpfs", str(site)]


def test_a_sandbox_that_cannot_start_is_one_line_and_exit_2(tmp_path):
    """A bubblewrap that passes the probe but cannot build the sandbox (as when a kernel
    refuses its mounts): one line naming the sandbox, exit 2, no traceback."""
    if sandbox.sandbox_mode() != "bwrap":
        pytest.fail("bubblewrap is needed (./dev setup installs it)")
    fake = tmp_path / "bin"
    fake.mkdir()
    (fake / "bwrap").write_text(
        "#!/bin/sh\n"
        "for last; do :; done\n"
        'if [ "$last" = true ]; then exit 0; fi\n'
        'echo "bwrap: Creating new namespace failed: Operation not '
        'permitted" >&2\nexit 1\n'
    )
    (fake / "bwrap").chmod(0o755)
    start = tmp_path / "lab"
    done = mirrorlab_command("lab", "start", "lab20", str(start))
    assert done.returncode == 0, done.stderr
    done = mirrorlab_command(
        "lab",
        "check",
        "lab20",
        str(start / "starter.py"),
        "--out",
        str(tmp_path / "c.png"),
        env={"PATH": f"{fake}:{os.environ['PATH']}"},
    )
    lines = done.stderr.strip().splitlines()
    assert done.returncode == 2 and len(lines) == 1, done.stderr
    assert "the sandbox could not start" in lines[0] and "Operation not permitted" in lines[0]
    assert not (tmp_path / "c.png").exists()


def test_no_temporary_folder_is_left_or_world_writable(tmp_path, lab_environment):
    """While a check and a grading run, every folder they make in the temporary folder is
    closed to other users; after them, none is left (a crash and a loop among them)."""
    scratch = tmp_path / "tmp"
    scratch.mkdir()
    scratch.chmod(0o1777)
    folder = tmp_path / "class"
    folder.mkdir()
    (folder / "crash.py").write_text("import ctypes\nctypes.string_at(0)\n")
    (folder / "loop.py").write_text("while True:\n    pass\n")
    (folder / "ok.py").write_text((REPO_DIR / "labs/solutions/lab20_mirror.py").read_text())
    seen: dict[str, int] = {}
    stop = threading.Event()

    def watch() -> None:
        while not stop.is_set():
            for entry in list(scratch.iterdir()):
                try:
                    seen[entry.name] = max(seen.get(entry.name, 0), entry.stat().st_mode)
                except OSError:
                    continue
            time.sleep(0.01)

    watcher = threading.Thread(target=watch)
    watcher.start()
    try:
        env = {"TMPDIR": str(scratch)}
        check = mirrorlab_command(
            "lab",
            "check",
            "lab20",
            str(folder / "ok.py"),
            "--out",
            str(tmp_path / "c.png"),
            env=env,
        )
        grade = mirrorlab_command(
            "lab",
            "grade",
            "lab20",
            str(folder),
            "--jobs",
            "2",
            "--timeout",
            "2",
            "--out-dir",
            str(tmp_path / "g"),
            env=env,
        )
    finally:
        stop.set()
        watcher.join()
    assert check.returncode == 0 and grade.returncode == 0, check.stderr + grade.stderr
    made = {name for name in seen if name.startswith("mirrorlab-")}
    assert any(name.startswith("mirrorlab-box-") for name in made), seen
    assert [name for name in made if seen[name] & 0o002] == []
    assert sorted(p.name for p in scratch.iterdir()) == []


def run_python(code: str, tmp_path: Path, limits: Limits = SHORT):
    box = new_box(tmp_path)
    code_and_time = run_sandboxed([SYSTEM_PYTHON, "-c", code], box, limits)
    return (*code_and_time, (box / "stderr.txt").read_text())


def test_user_fallback_cannot_write_outside_its_box(user_mode, tmp_path):
    target = tmp_path / "precious.txt"
    target.write_text("keep me")
    tmp_path.chmod(0o755)
    code, _, stopped, stderr = run_python(f"open({str(target)!r}, 'w').write('gone')", tmp_path)
    assert code == 1 and stopped == "" and "PermissionError" in stderr
    assert target.read_text() == "keep me"
    code, _, _, stderr = run_python("open('mine.txt', 'w').write('ok'); print('ok')", tmp_path)
    assert code == 0, stderr


def test_user_fallback_stops_a_fork_bomb_and_leaves_no_process(user_mode, tmp_path):
    code, _, stopped, _ = run_python(
        "import os\nwhile True:\n    try:\n        os.fork()\n    except OSError:\n        pass\n",
        tmp_path,
    )
    assert code is None and stopped == "processes"
    assert uid_processes(sandbox.sandbox_uid()) == []


def test_user_fallback_limits_memory_and_cpu(user_mode, tmp_path):
    code, _, _, stderr = run_python(
        "x = bytearray(8 << 30)",
        tmp_path,
        Limits(cpu_seconds=3, seconds=60, memory_mb=512, unsandboxed=True),
    )
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
    script = (
        "import sys\nfrom mirrorlab.cli import main\n"
        "code = main(sys.argv[1:])\n"
        "status = open('/proc/self/status').read()\n"
        "print('peak', status.split('VmHWM:')[1].split()[0])\n"
        "sys.exit(code)\n"
    )
    done = subprocess.run(
        [
            sys.executable,
            "-c",
            script,
            "lab",
            "check",
            "lab20",
            str(hog),
            "--out",
            str(tmp_path / "hog.png"),
            "--memory",
            "1024",
            "--timeout",
            "5",
        ],
        capture_output=True,
        text=True,
    )
    assert done.returncode == 1, done.stderr
    assert "MemoryError" in done.stdout
    peak_kib = int(done.stdout.split("peak ")[1].split()[0])
    assert peak_kib < 400 * 1024, f"the checker itself peaked at {peak_kib} KiB"
    assert find_lab("lab20").tasks  # the lab was judged, each task failed with the error
