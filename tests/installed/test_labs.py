"""The labs from the installed wheel, as a student gets them: no solutions anywhere, the
venv two folders deep under a temporary folder closed to other users (mode 0700, as
``mkdtemp`` makes it), run from an empty folder. ``lab start`` writes the handout and the
starter from the package; ``lab check`` judges them against the packaged reference
evidence, inside the sandbox."""

from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import numpy as np

from mirrorlab.labs import find_lab, labs
from mirrorlab.labs.content import reference_folder
from mirrorlab.scene.backgrounds import load_picture
from mirrorlab.testing import assert_image_close
from tests import REPO_DIR
from tests.installed.conftest import Installed
from tests.labs.warm_checks import Watch, save_by_rename


def test_the_wheel_carries_each_labs_handout_starter_and_reference(wheel_names: list[str]):
    for spec in labs():
        for name in ("handout.md", "starter.py", "reference/evidence.json", "reference/arrays.npz"):
            assert f"mirrorlab/labs/{spec.folder}/{name}" in wheel_names
    assert "mirrorlab/labs/student/runner.py" in wheel_names
    assert not [n for n in wheel_names if n.startswith(("labs/", "tests/"))]


def test_lab_start_and_check_from_the_installed_wheel(installed: Installed, empty_folder: Path):
    assert installed.root.stat().st_mode & 0o077 == 0  # a closed folder above the venv
    cache = empty_folder / "cache"
    where = installed.python(
        "import mirrorlab.labs.student as s, mirrorlab.labs.lab20_mirror as c;"
        " print(s.__file__); print(c.__file__)",
        cwd=empty_folder,
    )
    assert all(line.startswith(str(installed.venv)) for line in where.stdout.split()), where

    started = installed.run("mirrorlab", "lab", "start", "lab20", "mine", cwd=empty_folder)
    assert started.returncode == 0, started.stderr
    assert sorted(p.name for p in (empty_folder / "mine").iterdir()) == ["README.md", "starter.py"]
    checked = installed.run(
        "mirrorlab",
        "lab",
        "check",
        "lab20",
        "mine/starter.py",
        cwd=empty_folder,
        MIRRORLAB_CACHE=str(cache),
    )
    assert checked.returncode == 1, checked.stdout + checked.stderr
    assert "0/8 tasks passed" in checked.stdout and checked.stderr == ""
    assert (empty_folder / "out" / "lab20_check.png").is_file()

    shutil.copy(
        REPO_DIR / "labs" / "solutions" / "lab20_mirror.py", empty_folder / "mine" / "done.py"
    )
    checked = installed.run(
        "mirrorlab",
        "lab",
        "check",
        "lab20",
        "mine/done.py",
        cwd=empty_folder,
        MIRRORLAB_CACHE=str(cache),
    )
    assert checked.returncode == 0, checked.stdout + checked.stderr
    assert "8/8 tasks passed" in checked.stdout
    # judged against the packaged reference (the cache holds the lab's meshes and pictures
    # as arrays, and no reference)
    assert not (cache / "lab-references").exists()


def test_lab_check_watch_and_lab_run_in_a_lab_folder_from_the_installed_wheel(
    installed: Installed, empty_folder: Path
):
    """In the folder ``lab start`` made, without naming the file: ``lab check --watch``
    answers a save and ends on Ctrl-C; ``lab run`` shows that folder's starter.py (not the
    package's), in a window under Xvfb."""
    assert (
        installed.run("mirrorlab", "lab", "start", "lab20", "mine", cwd=empty_folder).returncode
        == 0
    )
    folder = empty_folder / "mine"
    env = {**installed.env(), "MIRRORLAB_CACHE": str(empty_folder / "cache")}
    watch = Watch(folder, name="", command=(str(installed.bin / "mirrorlab"),), env=env)
    with watch:
        assert "0/8 tasks passed" in watch.report()
        save_by_rename(
            folder / "starter.py", (REPO_DIR / "labs" / "solutions" / "lab20_mirror.py").read_text()
        )
        assert "8/8 tasks passed" in watch.report()
        code, out, errors = watch.interrupt()
    assert code == 0 and "stopped watching" in out and "Traceback" not in errors, (out, errors)
    if shutil.which("xvfb-run") is None:
        return
    shot = empty_folder / "window.png"
    shown = subprocess.run(
        [
            "xvfb-run",
            "-a",
            str(installed.bin / "mirrorlab"),
            "lab",
            "run",
            "lab20",
            "--size",
            "256x256",
            "--max-frames",
            "2",
            "--screenshot",
            str(shot),
        ],
        cwd=folder,
        env=env,
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert shown.returncode == 0, shown.stderr
    with np.load(reference_folder(find_lab("lab20")) / "arrays.npz") as reference:
        frame = reference["frame"]
    assert_image_close(load_picture(shot), frame, tolerance=8, fraction=0.99, name="wheel_lab_run")


def test_info_a_headed_starter_and_a_canvas_gradebook_from_the_installed_wheel(
    installed: Installed, empty_folder: Path
):
    """``mirrorlab info`` names the OpenGL and the sandbox; a starter moved away from its
    folder is judged by its first line (no note); a class graded from a CSV list writes
    Canvas's layout with the list's names and ids. All from the wheel, no solutions."""
    info = installed.run("mirrorlab", "info", cwd=empty_folder)
    assert info.returncode == 0, info.stdout + info.stderr
    lines = dict(line.split(None, 1) for line in info.stdout.splitlines() if " " in line)
    assert lines["mirrorlab"].strip() and "profile" in lines["profile"], info.stdout
    assert lines["draw"].startswith("path ") and lines["sandbox"].strip(), info.stdout
    started = installed.run("mirrorlab", "lab", "start", "lab20", "mine", cwd=empty_folder)
    assert started.returncode == 0, started.stderr
    assert (empty_folder / "mine" / "starter.py").read_text().startswith("# mirrorlab variant: ")
    submissions = empty_folder / "class"
    submissions.mkdir()
    shutil.copy(empty_folder / "mine" / "starter.py", submissions / "s1001.py")
    (empty_folder / "class.csv").write_text("id,name,email\ns1001,Ada Lovelace,ada@uni.edu\n")
    graded = installed.run(
        "mirrorlab",
        "lab",
        "grade",
        "lab20",
        "class",
        "--students",
        "class.csv",
        "--format",
        "canvas",
        "--out-dir",
        "grades",
        cwd=empty_folder,
    )
    assert graded.returncode == 0, graded.stdout + graded.stderr
    assert (empty_folder / "grades" / "gradebook.csv").read_text().splitlines() == [
        "Student,ID,SIS User ID,SIS Login ID,Section,Lab 20: the multipass mirror",
        "Points Possible,,,,,8",
        "Ada Lovelace,,s1001,ada@uni.edu,,0",
    ]
