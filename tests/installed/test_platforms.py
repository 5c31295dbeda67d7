"""mirrorlab installs everywhere students are: for CPython 3.11, 3.12 and 3.13, its
dependencies and the extras users install (plot, dask) resolve to stable wheels, with no
compiler and no pre-release, on Linux x86_64 and aarch64 (manylinux 2.28: glibc 2.28 and
later), macOS arm64 and x86_64, and Windows amd64, each with its own environment markers.

uv resolves for each platform from PyPI (``uv pip compile --python-platform P
--python-version V --only-binary :all: --prerelease disallow``); a dependency without a
wheel there fails the resolution, and so the test. A package that resolves to an older
version on one platform than on the others (its newest has no wheel there) fails it too:
the version the others need may not work with it (as PyOpenGL 3.1.10 ignores, with a
warning, an older PyOpenGL-accelerate). The platforms resolve side by side: each call
mostly waits on the network.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
PLATFORMS = {
    "Linux x86_64": "x86_64-manylinux_2_28",
    "Linux aarch64": "aarch64-manylinux_2_28",
    "macOS arm64": "aarch64-apple-darwin",
    "macOS x86_64": "x86_64-apple-darwin",
    "Windows amd64": "x86_64-pc-windows-msvc",
}
"""Each desktop, as uv names its platform."""
EXTRAS = ("plot", "dask")
"""The extras users install (test and docs are the developers')."""
ACCELERATED = {"Linux x86_64", "Windows amd64"}
"""Where PyOpenGL-accelerate has wheels of the version PyOpenGL needs."""
EMBREE = {"Linux x86_64", "macOS x86_64", "Windows amd64"}
"""Where embreex (Intel's Embree) has wheels; elsewhere trimesh casts rays with rtree."""


def uv() -> str:
    found = Path(sys.executable).parent / "uv"
    if found.is_file():
        return str(found)
    which = shutil.which("uv")
    if which is None:
        pytest.fail("uv is missing: it comes with the test extra (pip install -e '.[test]')")
    return which


def resolve(platform: str, python: str) -> subprocess.CompletedProcess:
    command = [
        uv(),
        "pip",
        "compile",
        str(REPO / "pyproject.toml"),
        *[f"--extra={extra}" for extra in EXTRAS],
        "--python-platform",
        platform,
        "--python-version",
        python,
        "--python",
        sys.executable,
        "--no-python-downloads",
        "--only-binary",
        ":all:",
        "--prerelease",
        "disallow",
        "--no-header",
        "--no-annotate",
        "--quiet",
    ]
    env = {
        k: v
        for k, v in os.environ.items()
        if not k.startswith(("UV_INDEX", "UV_EXTRA_INDEX", "UV_FIND_LINKS", "PIP_"))
    }
    return subprocess.run(command, capture_output=True, text=True, timeout=300, env=env, cwd=REPO)


def pins(output: str) -> dict[str, str]:
    found = {}
    for line in output.splitlines():
        line = line.split("#")[0].strip()
        if line:
            name, _, version = line.partition("==")
            assert version, f"not a pinned requirement: {line!r}"
            found[name.lower()] = version.split(";")[0].strip()
    return found


@pytest.mark.parametrize("python", ["3.11", "3.12", "3.13"])
def test_the_dependencies_resolve_to_stable_wheels_on_every_desktop(python: str):
    with ThreadPoolExecutor(max_workers=len(PLATFORMS)) as pool:
        done = dict(
            zip(PLATFORMS, pool.map(lambda p: resolve(p, python), PLATFORMS.values()), strict=True)
        )
    failed = {
        name: result.stderr.strip() for name, result in done.items() if result.returncode != 0
    }
    assert not failed, "\n\n".join(
        f"{name} (CPython {python}): {error}" for name, error in failed.items()
    )
    resolved = {name: pins(result.stdout) for name, result in done.items()}
    for name, found in resolved.items():
        assert "pyopengl" in found and "glfw" in found and "numpy" in found, (name, found)
        assert ("pyopengl-accelerate" in found) == (name in ACCELERATED), (name, found)
        assert ("embreex" in found) == (name in EMBREE), (name, found)
        assert ("rtree" in found) == (name not in EMBREE), (name, found)
    # one version of each package everywhere it is installed: an older one on a platform
    # means its newest has no wheel there
    versions: dict[str, dict[str, str]] = {}
    for name, found in resolved.items():
        for package, version in found.items():
            versions.setdefault(package, {})[name] = version
    apart = {package: where for package, where in versions.items() if len(set(where.values())) > 1}
    assert not apart, f"CPython {python}: versions differ between platforms: {apart}"
