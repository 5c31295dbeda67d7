"""Labs where there is no bubblewrap (macOS, Windows, a Linux without it): bubblewrap is
hidden by bubblewrap itself (an empty file over it). ``lab check`` runs a student's own
file in a process of its own over the same pipe and says so once; ``lab grade`` refuses
other people's code (exit 2, one line) unless ``--unsandboxed`` takes the risk, and its
report says so. With ``resource`` and ``fcntl`` unimportable too, as on Windows, a check
still runs to its verdicts."""

from __future__ import annotations

import ast
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

from tests import REPO_DIR
from tests.labs.conftest import SOLUTIONS

HIDE_MODULES = '''
import os, sys
class _Hidden:
    """resource and fcntl unimportable, as on Windows; each refusal noted in a log."""
    def find_spec(self, name, path=None, target=None):
        if name in ("resource", "fcntl"):
            with open(os.environ["HIDDEN_LOG"], "a") as log:
                log.write(f"{os.getpid()} {name}\\n")
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return None
sys.meta_path.insert(0, _Hidden())
with open(os.environ["HIDDEN_LOG"], "a") as log:
    log.write(f"{os.getpid()} started\\n")
'''


def without_bubblewrap(
    *args: str, as_user: bool = False, env: dict[str, str] | None = None
) -> subprocess.CompletedProcess:
    """``mirrorlab ARGS`` where bubblewrap is an empty file; ``as_user``: as a user who is
    not root (uid 1000 in a user namespace of its own), as a student is."""
    bwrap = shutil.which("bwrap")
    if bwrap is None:
        pytest.fail("bubblewrap is needed to hide itself (./dev setup installs it)")
    command = [bwrap, "--dev-bind", "/", "/", "--ro-bind", "/dev/null", bwrap, "--die-with-parent"]
    home = Path(tempfile.mkdtemp(prefix="mirrorlab-home-"))
    if as_user:
        # Mesa's shader cache goes under $HOME: a home of this run's own
        command += [
            "--unshare-user",
            "--uid",
            "1000",
            "--gid",
            "1000",
            "--setenv",
            "HOME",
            str(home),
            "--setenv",
            "XDG_CACHE_HOME",
            str(home),
        ]
    environment = {**os.environ, **(env or {})}
    environment.pop("MIRRORLAB_SANDBOX", None)
    try:
        return subprocess.run(
            [*command, sys.executable, "-m", "mirrorlab.cli", *args],
            capture_output=True,
            text=True,
            cwd=REPO_DIR,
            env=environment,
            timeout=600,
        )
    finally:
        shutil.rmtree(home, ignore_errors=True)


def note_lines(stderr: str) -> list[str]:
    return [line for line in stderr.splitlines() if "not sandboxed" in line]


def test_a_check_without_bubblewrap_passes_and_says_once_it_is_not_sandboxed(tmp_path):
    """As a student (not root), and as root (a user id of its own for the file, which must
    reach its box: a temporary folder others may enter, as /tmp is)."""
    scratch = Path(tempfile.mkdtemp(prefix="mirrorlab-scratch-", dir="/var/tmp"))
    scratch.chmod(0o755)
    try:
        for as_user, how in ((True, "as you"), (False, "as a user id of its own")):
            done = without_bubblewrap(
                "lab",
                "check",
                "lab20",
                str(SOLUTIONS / "lab20_mirror.py"),
                "--out",
                str(tmp_path / "c.png"),
                as_user=as_user,
                env={"TMPDIR": str(scratch)},
            )
            check_note(done, how, tmp_path / "c.png")
        assert list(scratch.iterdir()) == []
    finally:
        shutil.rmtree(scratch, ignore_errors=True)


def check_note(done: subprocess.CompletedProcess, how: str, picture: Path) -> None:
    assert done.returncode == 0, done.stderr
    assert "8/8 tasks passed" in done.stdout
    # the teacher's solution names no variant: the line under its name says what it is
    # judged against
    assert done.stdout.splitlines()[1] == (
        "  note: lab20_mirror.py names no variant (no variant.json beside it, no variant "
        "line at its top): judged against the lab's own numbers; a released starter is "
        "checked in its own folder"
    ), done.stdout
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, done.stderr
    assert lines[0].startswith(
        "mirrorlab lab check: note: not sandboxed (no sandbox: bubblewrap is not installed)"
    ), lines[0]
    assert how in lines[0], lines[0]
    assert picture.is_file()
    picture.unlink()


def test_a_check_runs_where_resource_and_fcntl_cannot_be_imported(tmp_path):
    """As on Windows: no ``resource``, no ``fcntl``, no bubblewrap, not root. The reference
    solution passes and the starter fails with hints. The modules are hidden in the
    command and in the checker's GL process; the student's runner starts isolated (``-I``,
    no PYTHONPATH), and its package imports neither."""
    for module in (REPO_DIR / "mirrorlab" / "labs" / "student").glob("*.py"):
        imported = {
            alias.name
            for node in ast.walk(ast.parse(module.read_text()))
            if isinstance(node, ast.Import)
            for alias in node.names
        }
        imported |= {
            node.module
            for node in ast.walk(ast.parse(module.read_text()))
            if isinstance(node, ast.ImportFrom) and node.module
        }
        assert not imported & {"resource", "fcntl"}, module
    site = tmp_path / "site"
    site.mkdir()
    (site / "sitecustomize.py").write_text(HIDE_MODULES)
    log = tmp_path / "hidden.log"
    env = {"PYTHONPATH": str(site), "HIDDEN_LOG": str(log)}
    done = without_bubblewrap(
        "lab",
        "check",
        "spheremap",
        str(SOLUTIONS / "lab_spheremap.py"),
        "--out",
        str(tmp_path / "s.png"),
        as_user=True,
        env=env,
    )
    assert done.returncode == 0, done.stderr
    assert "tasks passed" in done.stdout and "FAIL" not in done.stdout, done.stdout
    assert len(note_lines(done.stderr)) == 1, done.stderr
    starter = tmp_path / "lab"
    made = without_bubblewrap("lab", "start", "lab20", str(starter), as_user=True, env=env)
    assert made.returncode == 0, made.stderr
    failed = without_bubblewrap(
        "lab",
        "check",
        "lab20",
        str(starter / "starter.py"),
        "--out",
        str(tmp_path / "f.png"),
        as_user=True,
        env=env,
    )
    assert failed.returncode == 1, failed.stderr
    assert "0/8 tasks passed" in failed.stdout and "hint:" in failed.stdout, failed.stdout
    # the hiding was in force in the command and in the checker's own GL process, and the
    # code that would have used the modules asked for them and went on without them
    entries = [line.split() for line in log.read_text().splitlines()]
    started = {pid for pid, what in entries if what == "started"}
    refused = {pid for pid, what in entries if what == "resource"}
    assert len(started) >= 2 and refused, entries


def test_grading_without_bubblewrap_stops_in_one_line_and_writes_nothing(tmp_path):
    folder = tmp_path / "class"
    folder.mkdir()
    shutil.copy(SOLUTIONS / "lab20_mirror.py", folder / "ann.py")
    out = tmp_path / "grades"
    for as_user in (False, True):
        done = without_bubblewrap(
            "lab", "grade", "lab20", str(folder), "--out-dir", str(out), as_user=as_user
        )
        lines = done.stderr.strip().splitlines()
        assert done.returncode == 2 and len(lines) == 1, done.stderr
        assert lines[0].startswith(
            "mirrorlab lab: error: no sandbox: bubblewrap is not "
            "installed; install it (Debian/Ubuntu: apt-get install "
            "bubblewrap"
        ), lines[0]
        assert "--unsandboxed" in lines[0]
        assert done.stdout == ""
        assert not out.exists()
        assert sorted(p.name for p in tmp_path.iterdir()) == ["class"]


def test_grading_unsandboxed_grades_and_says_so(tmp_path):
    folder = tmp_path / "class"
    folder.mkdir()
    shutil.copy(SOLUTIONS / "lab20_mirror.py", folder / "ann.py")
    (folder / "bob.py").write_text("x = 1\n")
    out = tmp_path / "grades"
    done = without_bubblewrap(
        "lab", "grade", "lab20", str(folder), "--out-dir", str(out), "--unsandboxed", as_user=True
    )
    assert done.returncode == 0, done.stderr
    warnings = note_lines(done.stderr)
    assert warnings == [
        "mirrorlab lab grade: warning: not sandboxed (--unsandboxed): every "
        "submission runs as you, in a process of its own"
    ], done.stderr
    assert "NOT sandboxed" in done.stdout
    rows = (out / "gradebook.csv").read_text().splitlines()
    assert rows[1].startswith("ann,8,8,") and rows[2].startswith("bob,0,8,"), rows
    report = (out / "report.html").read_text()
    assert "NOT sandboxed (--unsandboxed: each submission ran as you" in report
