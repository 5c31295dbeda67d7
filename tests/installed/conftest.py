"""mirrorlab as a user gets it: the wheel built from this checkout, installed (not
editable, without extras) into a fresh virtual environment two folders deep in a
temporary folder, and run from an empty folder, with nothing of the checkout on the path.

The session fixture :func:`installed` builds and installs once; each test asks for an
:func:`empty_folder` of its own to work in. To add a step (a lab started and checked, a
new command), write a test that takes both and runs ``installed.run(...)`` or
``installed.python(...)`` there.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
import tempfile
import zipfile
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
HIDDEN = (
    "PYTHONPATH",
    "PYTHONHOME",
    "VIRTUAL_ENV",
    "PYOPENGL_PLATFORM",
    "EGL_PLATFORM",
    "MIRRORLAB_FAILURES",
    "MIRRORLAB_SOLUTIONS",
    "MIRRORLAB_CACHE",
    "PYTEST_ADDOPTS",
    "PYTEST_CURRENT_TEST",
)
"""Variables of this test process that a user's shell would not have."""


@dataclass(frozen=True)
class Installed:
    """The installed mirrorlab: ``venv`` (its folder), ``wheel`` (the file installed) and
    ``root`` (the temporary folder holding both, removed after the session)."""

    root: Path
    venv: Path
    wheel: Path

    @property
    def bin(self) -> Path:
        return self.venv / "bin"

    def env(self) -> dict[str, str]:
        env = {k: v for k, v in os.environ.items() if k not in HIDDEN}
        env["PATH"] = f"{self.bin}{os.pathsep}{env.get('PATH', '')}"
        return env

    def run(
        self, *args: str, cwd: Path, timeout: float = 300, **extra_env: str
    ) -> subprocess.CompletedProcess:
        """A program of the venv (``"mirrorlab", "render"``, ``"python", "-c", ...``) run in
        ``cwd`` as a user's shell would run it."""
        program = str(self.bin / args[0])
        return subprocess.run(
            [program, *args[1:]],
            cwd=cwd,
            capture_output=True,
            text=True,
            timeout=timeout,
            env={**self.env(), **extra_env},
        )

    def python(self, code: str, cwd: Path, timeout: float = 300) -> subprocess.CompletedProcess:
        return self.run("python", "-c", code, cwd=cwd, timeout=timeout)


def _check(done: subprocess.CompletedProcess, what: str) -> None:
    if done.returncode != 0:
        raise RuntimeError(
            f"{what} failed (exit {done.returncode}):\n{done.stdout[-3000:]}\n{done.stderr[-3000:]}"
        )


BUILD_LEFTOVERS = shutil.ignore_patterns(
    ".git",
    ".venv*",
    "build",
    "dist",
    "site",
    "out",
    "*.egg-info",
    "__pycache__",
    ".*_cache",
    ".hypothesis",
    "_failures",
)


def build_wheel(out_dir: Path) -> Path:
    """``pip wheel`` (no dependencies) of a copy of the checkout without its build
    leftovers, the way a release is built from a clean tree: a stale ``build/`` folder
    could otherwise put files in the wheel that the checkout no longer has."""
    source = out_dir.parent / "source"
    shutil.copytree(REPO, source, ignore=BUILD_LEFTOVERS)
    done = subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "wheel",
            "--no-deps",
            "-q",
            "--disable-pip-version-check",
            "-w",
            str(out_dir),
            str(source),
        ],
        capture_output=True,
        text=True,
        timeout=600,
    )
    _check(done, "building the wheel")
    wheels = sorted(out_dir.glob("mirrorlab-*.whl"))
    assert len(wheels) == 1, wheels
    return wheels[0]


@pytest.fixture(scope="session")
def installed() -> Iterator[Installed]:
    """Build the wheel, make a venv at ``TMP/mirrorlab-installed-*/home/venv`` and install
    the wheel and pytest into it (dependencies from the package index, as for a user)."""
    root = Path(tempfile.mkdtemp(prefix="mirrorlab-installed-"))
    try:
        wheel = build_wheel(root / "dist")
        venv = root / "home" / "venv"
        _check(
            subprocess.run(
                [sys.executable, "-m", "venv", str(venv)],
                capture_output=True,
                text=True,
                timeout=300,
            ),
            "making the venv",
        )
        done = subprocess.run(
            [
                str(venv / "bin" / "python"),
                "-m",
                "pip",
                "install",
                "-q",
                "--disable-pip-version-check",
                str(wheel),
                "pytest",
            ],
            capture_output=True,
            text=True,
            timeout=1200,
            cwd=root,
        )
        _check(done, "installing the wheel")
        yield Installed(root=root, venv=venv, wheel=wheel)
    finally:
        shutil.rmtree(root, ignore_errors=True)


@pytest.fixture
def empty_folder(installed: Installed, request: pytest.FixtureRequest) -> Path:
    """A new empty folder beside the venv (``TMP/mirrorlab-installed-*/home/NAME``)."""
    folder = installed.venv.parent / request.node.name.replace("[", "-").strip("]")
    folder.mkdir()
    return folder


@pytest.fixture(scope="session")
def wheel_names(installed: Installed) -> list[str]:
    with zipfile.ZipFile(installed.wheel) as archive:
        return archive.namelist()


@pytest.fixture(scope="session")
def pyrender_python() -> Path:
    """The Python of pyrender's environment (the clone's ``.venv-pyrender``, made once by
    ``bench/speed.py``'s own function, as ``./dev bench speed`` makes it)."""
    import importlib.util

    spec = importlib.util.spec_from_file_location("bench_speed", REPO / "bench" / "speed.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.pyrender_python()
