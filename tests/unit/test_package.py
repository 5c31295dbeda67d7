"""The package's metadata: one version, the licence and classifiers, ``py.typed``,
``python -m mirrorlab``, and Dask as an optional extra (tests/batch/test_without_dask.py
runs the command line without it)."""

from __future__ import annotations

import re
import subprocess
import sys
import tomllib
from importlib.metadata import metadata, version
from importlib.resources import files
from pathlib import Path

import pytest

import mirrorlab
from mirrorlab.data import DATA_FOLDERS, data_path

REPO = Path(__file__).resolve().parents[2]


def run_cli(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "mirrorlab", *args],
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=120,
    )


def test_one_version_from_the_metadata():
    assert mirrorlab.__version__ == version("mirrorlab")
    assert re.fullmatch(r"\d+\.\d+\.\d+", mirrorlab.__version__)
    changelog = (REPO / "CHANGELOG.md").read_text()
    assert f"## {mirrorlab.__version__}" in changelog, "the version has no changelog entry"


def test_version_flag_and_python_dash_m(tmp_path):
    done = run_cli("--version", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == f"mirrorlab {mirrorlab.__version__}"
    listed = run_cli("techniques", cwd=tmp_path)
    assert listed.returncode == 0, listed.stderr
    assert listed.stdout.split()[0] == "ortho"


def test_licence_classifiers_and_typed_marker():
    meta = metadata("mirrorlab")
    assert meta["License-Expression"] == "MIT"
    assert "LICENSE" in (meta.get_all("License-File") or [])
    assert "MIT License" in (REPO / "LICENSE").read_text()
    classifiers = meta.get_all("Classifier") or []
    assert "Typing :: Typed" in classifiers
    assert any(c.startswith("Programming Language :: Python :: 3.1") for c in classifiers)
    assert files("mirrorlab").joinpath("py.typed").is_file()


def test_every_package_is_built_and_the_data_folders_sit_at_the_top():
    """pyproject.toml lists the packages: every folder of mirrorlab/ with an __init__.py,
    and the top-level scenes/, models/ and textures/ mapped into mirrorlab.data, which the
    editable install finds where they are (the wheel's side: tests/installed)."""
    setuptools = tomllib.loads((REPO / "pyproject.toml").read_text())["tool"]["setuptools"]
    in_package = {
        ".".join(init.parent.relative_to(REPO).parts)
        for init in (REPO / "mirrorlab").rglob("__init__.py")
    }
    mapped = {f"mirrorlab.data.{folder}": folder for folder in DATA_FOLDERS}
    assert setuptools["package-dir"] == mapped
    assert sorted(setuptools["packages"]) == sorted(in_package | set(mapped))
    for folder in DATA_FOLDERS:
        assert (REPO / folder / "__init__.py").is_file(), folder
        assert not (REPO / "mirrorlab" / "data" / folder).exists(), folder
        assert data_path(folder) == REPO / folder
    assert data_path("models", "base.obj").is_file()
    with pytest.raises(ValueError, match="no shipped folder 'data'"):
        data_path("data")


def test_dask_is_an_extra_not_a_dependency():
    meta = metadata("mirrorlab")
    requires = meta.get_all("Requires-Dist") or []
    plain = [r for r in requires if "extra ==" not in r]
    assert not any(r.startswith(("dask", "distributed")) for r in plain), plain
    assert any(r.startswith("dask[distributed]") and 'extra == "dask"' in r for r in requires), (
        requires
    )
    assert "dask" in (meta.get_all("Provides-Extra") or [])


def test_the_api_takes_everything_after_the_scene_by_keyword():
    """One argument order everywhere: ``render(scene, *, frame=..., size=..., ...)``."""
    import inspect

    from mirrorlab import api

    for function in (
        api.render,
        api.raytrace,
        api.Renderer.render,
        api.Renderer.frames,
        api.Renderer.plan,
    ):
        parameters = list(inspect.signature(function).parameters.values())
        if parameters[0].name == "self":
            parameters = parameters[1:]
        assert parameters[0].name == "scene", function
        kinds = {p.name: p.kind for p in parameters[1:]}
        assert all(
            kind in (inspect.Parameter.KEYWORD_ONLY, inspect.Parameter.VAR_KEYWORD)
            for kind in kinds.values()
        ), (function.__qualname__, kinds)
        assert {"size"} <= set(kinds), function
