"""The source distribution is where a teacher who installed with pip gets the solutions
(docs/labs-teachers.md): built from a clean copy of the checkout with ``python -m
build --sdist``, it holds ``labs/solutions/``, the same files as the repository's, while
the wheel holds none (test_labs.py). It holds the top-level scenes/, models/ and textures/
too, and the wheel built from it carries them as package data in mirrorlab/data/."""

from __future__ import annotations

import shutil
import subprocess
import sys
import tarfile
import zipfile
from pathlib import Path

from mirrorlab.data import DATA_FOLDERS
from tests.installed.conftest import BUILD_LEFTOVERS, REPO


def shipped_files() -> list[str]:
    """The checkout's scenes, meshes and pictures, as paths under the repository's top."""
    return sorted(
        path.relative_to(REPO).as_posix()
        for folder in DATA_FOLDERS
        for path in (REPO / folder).rglob("*")
        if path.is_file() and "__pycache__" not in path.parts
    )


def test_the_source_distribution_carries_the_teachers_solutions_and_the_data(tmp_path: Path):
    source = tmp_path / "source"
    shutil.copytree(REPO, source, ignore=BUILD_LEFTOVERS)
    # the sdist, then the wheel built from that sdist (python -m build's way)
    done = subprocess.run(
        [sys.executable, "-m", "build", "-o", str(tmp_path / "dist"), str(source)],
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
        shipped = shipped_files()
        assert "models/base.obj" in shipped and "textures/sky_cube/px.png" in shipped
        for name in shipped:
            member = archive.extractfile(names[name])
            assert member is not None
            assert member.read() == (REPO / name).read_bytes(), name
    [wheel] = sorted((tmp_path / "dist").glob("mirrorlab-*.whl"))
    with zipfile.ZipFile(wheel) as archive:
        for name in shipped:
            assert archive.read(f"mirrorlab/data/{name}") == (REPO / name).read_bytes(), name
