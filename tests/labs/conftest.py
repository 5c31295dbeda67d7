"""Lab tests: students' files run only in the sandbox, through the checker, the command
line or grading. References are made from the teachers' solutions (labs/solutions, as on
a teacher's machine: $MIRRORLAB_SOLUTIONS) and cached in a folder of this session's own;
the tests of the shipped references and of the wheel run without them. Every temporary
folder the labs make goes into a folder of the session's own (TMPDIR), which must be left
empty of them."""

from __future__ import annotations

import csv
import os
import shutil
import socket
import subprocess
import sys
import tempfile
from collections.abc import Mapping
from pathlib import Path

import pytest

from mirrorlab.labs.trusted.sandbox import Limits
from tests import REPO_DIR

LIMITS = Limits(
    cpu_seconds=3, seconds=90.0, unsandboxed=os.environ.get("MIRRORLAB_SANDBOX") == "none"
)
"""An endless loop ends after 3 s of CPU; honest runs use under one. Where the run has no
sandbox on purpose (MIRRORLAB_SANDBOX=none: the simulated macOS run), the tests grade
as a teacher who gave ``--unsandboxed``."""
SOLUTIONS = REPO_DIR / "labs" / "solutions"
LEFTOVER_PREFIXES = (
    "mirrorlab-box-",
    "mirrorlab-submission-",
    "mirrorlab-home-",
    "mirrorlab-check-",
    "mirrorlab-solution-",
    "mirrorlab-release-",
)


def leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir() if p.name.startswith(LEFTOVER_PREFIXES))


@pytest.fixture(scope="session", autouse=True)
def lab_environment(tmp_path_factory):
    cache = tmp_path_factory.mktemp("lab-cache")
    scratch = Path(tempfile.mkdtemp(prefix="lab-tmp-"))
    saved = {
        key: os.environ.get(key) for key in ("MIRRORLAB_CACHE", "MIRRORLAB_SOLUTIONS", "TMPDIR")
    }
    saved_tempdir = tempfile.tempdir
    os.environ.update(
        MIRRORLAB_CACHE=str(cache), MIRRORLAB_SOLUTIONS=str(SOLUTIONS), TMPDIR=str(scratch)
    )
    tempfile.tempdir = str(scratch)
    yield scratch
    tempfile.tempdir = saved_tempdir
    for key, value in saved.items():
        if value is None:
            os.environ.pop(key, None)
        else:
            os.environ[key] = value
    left = leftovers(scratch)
    shutil.rmtree(scratch, ignore_errors=True)
    assert left == [], f"the lab tests left these temporary folders: {left}"


def mirrorlab_command(
    *args: str, cwd: Path | None = None, env: Mapping[str, str | None] | None = None
) -> subprocess.CompletedProcess:
    """``mirrorlab ARGS`` as a process of its own (``env``: changes, None removes)."""
    environment = dict(os.environ)
    for key, value in (env or {}).items():
        if value is None:
            environment.pop(key, None)
        else:
            environment[key] = value
    return subprocess.run(
        [sys.executable, "-m", "mirrorlab.cli", *args],
        capture_output=True,
        text=True,
        cwd=cwd,
        env=environment,
    )


@pytest.fixture(scope="session")
def canaries():
    """Two files outside every submission's folder, which anyone may write: only the
    sandbox keeps them whole. In /var/tmp (outside the session's own TMPDIR)."""
    folder = Path(tempfile.mkdtemp(prefix="mirrorlab-canary-", dir="/var/tmp"))
    folder.chmod(0o777)
    for name in ("delete_me.txt", "overwrite_me.txt"):
        (folder / name).write_text("canary\n")
        (folder / name).chmod(0o666)
    yield folder
    shutil.rmtree(folder, ignore_errors=True)


@pytest.fixture(scope="session")
def listening_port():
    """A port this machine listens on during the session (loopback)."""
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen()
        yield server.getsockname()[1]


@pytest.fixture(scope="session")
def classroom(tmp_path_factory, canaries, listening_port):
    """The generated lab 20 class: (folder, student -> expected verdicts)."""
    from tests.labs.classroom import make_class

    folder = tmp_path_factory.mktemp("class") / "submissions"
    folder.mkdir()
    return folder, make_class(folder, canaries, listening_port)


def read_csv(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as stream:
        return list(csv.DictReader(stream))
