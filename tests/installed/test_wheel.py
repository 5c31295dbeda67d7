"""The wheel, installed into a fresh venv and run from an empty folder: what it holds, the
version it reports, every shipped scene, a short batch, the plan as JSON, the Python API
examples of the documentation, and a user's pytest file using the plugin."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
from PIL import Image

from tests.installed.conftest import REPO, Installed

SHIPPED_SCENES = sorted(p.stem for p in (REPO / "scenes").glob("*.toml"))
GOLDEN_LAB = REPO / "tests" / "gl" / "golden" / "lab_default_128.png"


def ok(done) -> str:
    assert done.returncode == 0, f"exit {done.returncode}\n{done.stdout}\n{done.stderr}"
    return done.stdout


def test_the_wheel_has_the_licence_the_type_marker_and_the_data_and_no_solutions(
    installed: Installed, wheel_names: list[str]
):
    names = set(wheel_names)
    dist_info = next(n.split("/")[0] for n in names if n.endswith(".dist-info/METADATA"))
    assert f"{dist_info}/licenses/LICENSE" in names
    assert "mirrorlab/py.typed" in names
    for scene in SHIPPED_SCENES:
        assert f"mirrorlab/data/scenes/{scene}.toml" in names
    for folder in ("mirrorlab/data/models/", "mirrorlab/data/textures/", "mirrorlab/shaders/"):
        assert any(n.startswith(folder) for n in names), folder
    assert not [n for n in names if "solution" in n.lower()], "lab solutions in the wheel"
    assert not [n for n in names if n.startswith(("tests/", "labs/", "docs/", "bench/"))]
    import zipfile

    with zipfile.ZipFile(installed.wheel) as archive:
        metadata = archive.read(f"{dist_info}/METADATA").decode()
    assert "License-Expression: MIT" in metadata


def test_it_runs_from_the_venv_not_the_checkout(installed: Installed, empty_folder: Path):
    where = ok(
        installed.python(
            "import mirrorlab, mirrorlab.data as d\n"
            "print(mirrorlab.__file__); print(d.scenes_dir())",
            cwd=empty_folder,
        )
    ).split()
    for path in where:
        assert Path(path).is_relative_to(installed.venv), path
        assert not Path(path).is_relative_to(REPO), path


def test_one_version_everywhere(installed: Installed, empty_folder: Path):
    from importlib.metadata import version

    flag = ok(installed.run("mirrorlab", "--version", cwd=empty_folder)).strip()
    module = ok(installed.run("python", "-m", "mirrorlab", "--version", cwd=empty_folder))
    attribute = ok(
        installed.python("import mirrorlab; print(mirrorlab.__version__)", cwd=empty_folder)
    ).strip()
    assert flag == module.strip() == f"mirrorlab {attribute}"
    assert attribute == version("mirrorlab")  # the checkout's own metadata: one version


def test_the_default_render_is_the_golden_frame(installed: Installed, empty_folder: Path):
    from mirrorlab.testing import assert_image_close

    out = ok(installed.run("mirrorlab", "render", "--size", "128x128", cwd=empty_folder))
    assert "out/lab20.png" in out
    image = np.asarray(Image.open(empty_folder / "out" / "lab20.png"))
    assert_image_close(
        image,
        GOLDEN_LAB,
        tolerance=8,
        fraction=0.995,
        max_mean=0.5,
        name="installed_default_render",
    )


def test_every_shipped_scene_renders(installed: Installed, empty_folder: Path):
    listed = ok(
        installed.python(
            "from mirrorlab.data import scenes_dir\n"
            "print(' '.join(sorted(p.stem for p in scenes_dir().glob('*.toml'))))",
            cwd=empty_folder,
        )
    ).split()
    assert listed == SHIPPED_SCENES
    for name in SHIPPED_SCENES:
        ok(
            installed.run(
                "mirrorlab",
                "render",
                name,
                "--size",
                "64x48",
                "--out",
                f"{name}.png",
                cwd=empty_folder,
            )
        )
        image = np.asarray(Image.open(empty_folder / f"{name}.png"))
        assert image.shape == (48, 64, 3), name
        assert image.std() > 8, f"{name} rendered a blank frame"


def test_a_short_batch_on_two_processes(installed: Installed, empty_folder: Path):
    out = ok(
        installed.run(
            "mirrorlab",
            "render",
            "robot_wave",
            "--frames",
            "3",
            "--size",
            "64x64",
            "--out-dir",
            "frames",
            "--jobs",
            "2",
            cwd=empty_folder,
        )
    )
    assert "wrote 3 frames of robot_wave" in out
    assert sorted(p.name for p in (empty_folder / "frames").glob("*.png")) == [
        f"robot_wave_{f:04d}.png" for f in range(3)
    ]


def test_without_the_dask_extra_dask_options_say_what_to_install(
    installed: Installed, empty_folder: Path
):
    done = installed.run(
        "mirrorlab",
        "render",
        "robot_wave",
        "--frames",
        "3",
        "--out-dir",
        "frames",
        "--jobs",
        "2",
        "--engine",
        "dask",
        cwd=empty_folder,
    )
    assert done.returncode == 2
    assert done.stderr.strip().splitlines() == [
        "mirrorlab render: error: --engine dask: needs Dask (dask[distributed]), which is "
        "not installed; install it with: pip install 'mirrorlab[dask]'"
    ]
    assert not (empty_folder / "frames").exists()


def test_the_speed_benchmark_with_pyrender_beside_it(
    installed: Installed, empty_folder: Path, pyrender_python: Path
):
    """The benchmark's pyrender worker ships in the wheel and runs in pyrender's own
    environment; the scale scenes come from the package."""
    out = ok(
        installed.run(
            "mirrorlab",
            "bench",
            "speed",
            "--quick",
            "--parts",
            "scale",
            "--scale-modes",
            "still",
            "--pyrender",
            str(pyrender_python),
            "--out-dir",
            "speed",
            cwd=empty_folder,
        )
    )
    assert "| 12 objects unseen |" in out and "pyrender flat / its base" in out
    assert (empty_folder / "speed" / "scale.csv").is_file()
    assert not (empty_folder / "speed" / "speed.csv").exists()  # no sweep asked for


def test_plan_as_json(installed: Installed, empty_folder: Path):
    plans = json.loads(
        ok(installed.run("mirrorlab", "plan", "lab20", "--frames", "2", "--json", cwd=empty_folder))
    )
    text = json.dumps(plans)
    assert "capture" in text and "camera" in text
    assert not any(empty_folder.iterdir()), "plan wrote files"


def python_blocks(page: Path) -> list[str]:
    return re.findall(r"```python\n(.*?)```", page.read_text(), flags=re.S)


MY_ROOM = """
name = "my_room"
[camera]
eye = [12.0, 5.0, 9.0]
target = [-3.5, 1.0, -2.0]
[[objects]]
type = "robot"
[[reflectors]]
name = "mirror"
technique = "reflected"
corners = [[-7, -3, -6], [-7, 5, -6], [-7, 5, 2], [-7, -3, 2]]
"""


def test_the_documented_python_api_examples_run(installed: Installed, empty_folder: Path):
    """The Python code blocks of docs/api.md, docs/getting-started.md and the README,
    exactly as they are shown, run in one interpreter in an empty folder (with the user's
    my_room.toml the example names)."""
    (empty_folder / "my_room.toml").write_text(MY_ROOM)
    blocks = python_blocks(REPO / "docs" / "api.md")
    blocks += python_blocks(REPO / "docs" / "getting-started.md")
    blocks += python_blocks(REPO / "README.md")
    assert len(blocks) >= 4
    script = "\n".join(blocks) + "\nprint('examples done')\n"
    out = ok(installed.python(script, cwd=empty_folder, timeout=600))
    assert out.strip().endswith("examples done")
    for name in ("sphere.png", "frame.png", "mirrors.png"):
        assert np.asarray(Image.open(empty_folder / name)).std() > 8, name


USER_TEST = """
from mirrorlab.testing import assert_image_close


def test_my_mirror(renderer):
    image = renderer.render("lab20", size=(64, 48), method="{method}")
    assert_image_close(image, "expected/my_mirror.png", tolerance=4, fraction=0.99)
"""


def test_a_users_pytest_file_with_the_plugin(installed: Installed, empty_folder: Path):
    test_file = empty_folder / "test_mine.py"
    test_file.write_text(USER_TEST.format(method="ortho"))

    def pytest(*args: str):
        return installed.run(
            "python",
            "-m",
            "pytest",
            "-q",
            "-p",
            "no:cacheprovider",
            "test_mine.py",
            *args,
            cwd=empty_folder,
        )

    first = pytest()
    assert first.returncode == 1 and "run pytest --mirrorlab-update" in first.stdout
    assert "expected/my_mirror.png (new)" in ok(pytest("--mirrorlab-update"))
    assert "1 passed" in ok(pytest())
    test_file.write_text(USER_TEST.format(method="stencil"))
    changed = pytest()
    assert changed.returncode == 1 and "Traceback" not in changed.stdout
    for key in ("actual", "expected", "diff"):
        assert f"mirrorlab-failures/test_my_mirror_{key}.png" in changed.stdout
        assert (empty_folder / "mirrorlab-failures" / f"test_my_mirror_{key}.png").is_file()
