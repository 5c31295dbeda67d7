"""Lab tests: students' files run only in the sandbox, through the checker, the command
line or grading; this process never loads OpenGL. The reference runs are cached in a
folder of this session's own."""

from __future__ import annotations

import csv
import os
import shutil
import socket
import subprocess
import sys
import tempfile
from pathlib import Path

import pytest

from mirrorlab.labs.sandbox import Limits

LIMITS = Limits(cpu_seconds=3, seconds=90.0)
"""An endless loop ends after 3 s of CPU; honest runs use under one."""


@pytest.fixture(scope="session", autouse=True)
def lab_cache(tmp_path_factory):
    folder = tmp_path_factory.mktemp("lab-cache")
    old = os.environ.get("MIRRORLAB_CACHE")
    os.environ["MIRRORLAB_CACHE"] = str(folder)
    yield folder
    if old is None:
        os.environ.pop("MIRRORLAB_CACHE", None)
    else:
        os.environ["MIRRORLAB_CACHE"] = old


def mirrorlab_command(*args: str, cwd: Path | None = None) -> subprocess.CompletedProcess:
    """``mirrorlab ARGS`` as a process of its own."""
    return subprocess.run([sys.executable, "-m", "mirrorlab.cli", *args], capture_output=True,
                          text=True, cwd=cwd, env=dict(os.environ))


@pytest.fixture(scope="session")
def canaries():
    """Two files outside every submission's folder, which anyone may write: only the
    sandbox keeps them whole. In /var/tmp, which sandboxed runs see (their /tmp is their
    own)."""
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
