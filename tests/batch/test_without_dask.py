"""Dask is an optional extra: without it, ``--engine dask`` and ``--scheduler`` say in one
line what to install (exit 2, nothing written), and the local process pool still runs."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import pytest

# Run mirrorlab's command line in a Python that cannot import Dask: a finder placed first
# on sys.meta_path refuses dask and distributed, as an install without the extra would.
WITHOUT_DASK = """
import sys

class NoDask:
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in ("dask", "distributed"):
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return None

sys.meta_path.insert(0, NoDask())
from mirrorlab.cli import main
sys.exit(main(sys.argv[1:]))
"""


def run_without_dask(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-c", WITHOUT_DASK, *args],
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=300,
    )


@pytest.mark.parametrize(
    "args, option",
    [
        (
            [
                "render",
                "lab20",
                "--out-dir",
                "frames",
                "--frames",
                "2",
                "--jobs",
                "2",
                "--engine",
                "dask",
            ],
            "--engine dask",
        ),
        (
            [
                "render",
                "lab20",
                "--out-dir",
                "frames",
                "--frames",
                "2",
                "--scheduler",
                "tcp://127.0.0.1:9",
            ],
            "--scheduler",
        ),
        (
            [
                "bench",
                "accuracy",
                "--quick",
                "--out-dir",
                "frames",
                "--jobs",
                "2",
                "--engine",
                "dask",
            ],
            "--engine dask",
        ),
        (
            [
                "lab",
                "grade",
                "lab20",
                "submissions",
                "--scheduler",
                "tcp://127.0.0.1:9",
                "--out-dir",
                "frames",
            ],
            "--scheduler",
        ),
    ],
)
def test_without_dask_the_dask_options_say_what_to_install(tmp_path, args, option):
    done = run_without_dask(*args, cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1, done.stderr
    assert lines[0].endswith(
        f"{option}: needs Dask (dask[distributed]), which is not "
        f"installed; install it with: pip install 'mirrorlab[dask]'"
    )
    assert "Traceback" not in done.stderr
    assert not (tmp_path / "frames").exists()


def test_without_dask_the_pool_still_runs(tmp_path):
    done = run_without_dask(
        "render",
        "lab20",
        "--size",
        "32x32",
        "--out-dir",
        "frames",
        "--frames",
        "2",
        "--jobs",
        "2",
        cwd=tmp_path,
    )
    assert done.returncode == 0, done.stderr
    assert sorted(p.name for p in (tmp_path / "frames").glob("*.png")) == [
        "lab20_0000.png",
        "lab20_0001.png",
    ]
