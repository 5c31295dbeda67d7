"""The labs from a wheel, as a student installs them: ``pip wheel --no-deps`` of this
checkout, installed into a fresh venv two folders deep under the temporary folder, run
from an empty folder with no solutions anywhere: ``lab start`` writes the handout and the
starter from the package, and ``lab check`` judges them against the packaged reference
evidence. The wheel carries the handouts, starters and references, and no solution."""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import zipfile

from mirrorlab.labs import LABS
from mirrorlab.labs.trusted.sandbox import interpreter
from tests import REPO_DIR


def run(command: list, cwd=None, env=None) -> subprocess.CompletedProcess:
    return subprocess.run([str(c) for c in command], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=600)


def test_lab_start_and_check_from_an_installed_wheel(tmp_path):
    dist = tmp_path / "dist"
    built = run([sys.executable, "-m", "pip", "wheel", "--no-deps", "-q", "-w", dist, REPO_DIR])
    assert built.returncode == 0, built.stderr[-2000:]
    (wheel,) = dist.glob("mirrorlab-*.whl")
    names = zipfile.ZipFile(wheel).namelist()
    for spec in LABS.values():
        for name in ("handout.md", "starter.py", "reference/evidence.json",
                     "reference/arrays.npz"):
            assert f"mirrorlab/labs/content/{spec.folder}/{name}" in names
    assert "mirrorlab/labs/student/runner.py" in names
    assert not [n for n in names if "solution" in n and not n.endswith("release.py")], names
    assert not [n for n in names if n.startswith(("labs/", "tests/"))]

    venv = tmp_path / "x" / "y" / "venv"
    made = run([interpreter(), "-m", "venv", venv])
    assert made.returncode == 0, made.stderr
    installed = run([venv / "bin" / "python", "-m", "pip", "install", "-q", wheel])
    assert installed.returncode == 0, installed.stderr[-2000:]

    empty = tmp_path / "empty"
    empty.mkdir()
    env = {key: value for key, value in os.environ.items()
           if key not in ("MIRRORLAB_SOLUTIONS", "PYTHONPATH", "VIRTUAL_ENV")}
    env["MIRRORLAB_CACHE"] = str(tmp_path / "cache")
    mirrorlab = venv / "bin" / "mirrorlab"
    where = run([venv / "bin" / "python", "-c",
                 "import mirrorlab.labs.student as s, mirrorlab.labs.content as c; "
                 "print(s.__file__); print(c.__file__)"], cwd=empty, env=env)
    assert all(line.startswith(str(venv)) for line in where.stdout.split()), where.stdout

    started = run([mirrorlab, "lab", "start", "lab20", "mine"], cwd=empty, env=env)
    assert started.returncode == 0, started.stderr
    assert sorted(p.name for p in (empty / "mine").iterdir()) == ["README.md", "starter.py"]
    checked = run([mirrorlab, "lab", "check", "lab20", "mine/starter.py"], cwd=empty, env=env)
    assert checked.returncode == 1, checked.stdout + checked.stderr
    assert "0/8 tasks passed" in checked.stdout and checked.stderr == ""
    assert (empty / "out" / "lab20_check.png").is_file()
    shutil.copy(REPO_DIR / "labs" / "solutions" / "lab20_mirror.py", empty / "mine" / "done.py")
    checked = run([mirrorlab, "lab", "check", "lab20", "mine/done.py"], cwd=empty, env=env)
    assert checked.returncode == 0, checked.stdout + checked.stderr
    assert "8/8 tasks passed" in checked.stdout
    assert not (tmp_path / "cache").exists()  # judged against the packaged reference
