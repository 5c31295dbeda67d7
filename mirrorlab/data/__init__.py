"""The files mirrorlab ships: scenes (``scenes/*.toml``), meshes (``models/*.obj``) and
pictures (``textures/``). In a checkout they are the repository's top-level folders
``scenes/``, ``models/`` and ``textures/``; pyproject.toml maps them into this package as
``mirrorlab.data.scenes``, ``mirrorlab.data.models`` and ``mirrorlab.data.textures``, so
a wheel holds them in ``mirrorlab/data/`` and an editable install finds them where they
are. Either way they are found through :mod:`importlib.resources` and sit side by side,
so a scene file's own paths stay relative to that file (``../models/base.obj``)."""

from __future__ import annotations

from functools import lru_cache
from importlib.resources import files
from pathlib import Path

DATA_FOLDERS = ("scenes", "models", "textures")
"""The shipped folders, each the package ``mirrorlab.data.<folder>``."""


@lru_cache(maxsize=256)
def data_path(folder: str, *parts: str) -> Path:
    """The shipped file or folder ``<folder>/<parts...>`` (``folder`` one of
    :data:`DATA_FOLDERS`) as a path on disk, e.g. ``data_path("models", "base.obj")``. It
    need not exist (callers check); ValueError for another folder; RuntimeError when
    mirrorlab runs from a zip archive, which it does not support. (Remembered: a scene
    graph asks for its meshes whenever it is posed.)"""
    if folder not in DATA_FOLDERS:
        raise ValueError(f"no shipped folder {folder!r}; expected one of {DATA_FOLDERS}")
    root = files(f"{__name__}.{folder}")
    if not isinstance(root, Path):
        raise RuntimeError(
            f"mirrorlab's data is not on the file system ({root}); install "
            f"mirrorlab as a wheel or from a source folder, not as a zip"
        )
    return root.joinpath(*parts)


def scenes_dir() -> Path:
    """The folder of the shipped scene files."""
    return data_path("scenes")


def model_file(name: str) -> Path:
    """The shipped mesh ``models/<name>.obj``."""
    return data_path("models", f"{name}.obj")


def texture_file(name: str) -> Path:
    """The shipped picture ``textures/<name>.png``."""
    return data_path("textures", f"{name}.png")


__all__ = ["DATA_FOLDERS", "data_path", "model_file", "scenes_dir", "texture_file"]
