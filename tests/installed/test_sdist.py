"""The source distribution is where a teacher who installed with pip gets the solutions
(docs/labs-teachers.md): built from a clean copy of the checkout with ``python -m
build --sdist``, it holds ``labs/solutions/``, the same files as the repository's, while
the wheel holds none (test_labs.py)."""

from __future__ import annotations

import shutil
import subprocess
import sys
import tarfile
from pathlib import Path

from tests.installed.conftest import BUILD_LEFTOVERS, REPO


def test_the_source_distribution_carries_the_teachers_solutions(tmp_path: Path):
    source = tmp_path / "source"
    shutil.copytree(REPO, source, ignore=BUILD_LEFTOVERS)
    done = subprocess.run(
        [sys.executable, "-m", "build", "--sdist", "-o", str(tmp_path / "dist"), str(source)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    [sdist] = sorted((tmp_path / "dist").glob("mirrorlab-*.tar.gz"))
    with tarfile.open(sdist) as archive:
        names = {name.split("/", 1)[1]: name for name in archive.getnames() if "/" in name}
        solutions = sorted(p.name for p in (REPO / "labs" / "solutions").glob("*.py"))
        assert len(solutions) == 3
        for name in solutions:
            member = archive.extractfile(names[f"labs/solutions/{name}"])
            assert member is not None
            assert member.read() == (REPO / "labs" / "solutions" / name).read_bytes(), name
        assert "labs/README.md" in names
        assert not [n for n in names if "__pycache__" in n]
