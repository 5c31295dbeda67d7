"""The labs' shipped meshes and pictures as the checker draws them, kept as arrays in the
user's cache (``$MIRRORLAB_CACHE`` or ``~/.cache/mirrorlab``, as the references are), so
that a checker process reads them with numpy alone: reading the mesh files through
trimesh and the pictures through Pillow, imports included, was about a third of a cold
check's time in the checker's process.

An entry is named by a digest of everything that makes it (the shipped file's bytes, the
code that reads it and that code's libraries' versions), so a changed file, mirrorlab or
library makes a new entry; an entry that cannot be read is made again. The sandbox sees
none of it.
"""

from __future__ import annotations

import hashlib
import os
from collections.abc import Callable
from functools import lru_cache
from importlib.metadata import PackageNotFoundError, version
from pathlib import Path

import numpy as np

FOLDER = "lab-assets"


def cache_folder() -> Path:
    """Where the entries live: ``lab-assets/`` in the checker's cache folder."""
    base = os.environ.get("MIRRORLAB_CACHE") or str(Path.home() / ".cache" / "mirrorlab")
    return Path(base) / FOLDER


@lru_cache(maxsize=4)
def _versions(packages: tuple[str, ...]) -> str:
    found = []
    for package in packages:
        try:
            found.append(f"{package}={version(package)}")
        except PackageNotFoundError:
            found.append(f"{package}=?")
    return ",".join(found)


def cached_arrays(
    kind: str,
    name: str,
    sources: list[Path],
    packages: tuple[str, ...],
    make: Callable[[], dict[str, np.ndarray]],
) -> dict[str, np.ndarray]:
    """The arrays ``make()`` gives, from the cache when an entry made from the same
    ``sources`` (files: the shipped file and the code that reads it) with the same
    ``packages``' versions is there, else made and stored (a temporary file, then a
    rename: two processes may store the same entry at once). A cache that cannot be
    written costs only the time."""
    digest = hashlib.sha256(_versions(packages).encode())
    for source in sources:
        digest.update(source.read_bytes())
    path = cache_folder() / f"{kind}-{name}-{digest.hexdigest()[:24]}.npz"
    try:
        with np.load(path, allow_pickle=False) as stored:
            return {key: stored[key] for key in stored.files}
    except (OSError, ValueError, EOFError):
        pass
    arrays = make()
    staging = path.with_name(f"{path.name}.{os.getpid()}.tmp")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        with open(staging, "wb") as stream:
            np.savez(stream, allow_pickle=False, **arrays)
        os.replace(staging, path)
    except OSError:
        staging.unlink(missing_ok=True)
    return arrays
