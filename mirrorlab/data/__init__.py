"""The files mirrorlab ships: scenes (``scenes/*.toml``), meshes (``models/*.obj``) and
pictures (``textures/``), package data found through :mod:`importlib.resources`, the same
way from a wheel, an editable install and a checkout. A scene file's own paths stay
relative to that file (``../models/base.obj``)."""

from __future__ import annotations

from functools import lru_cache
from importlib.resources import files
from pathlib import Path


@lru_cache(maxsize=256)
def data_path(*parts: str) -> Path:
    """The shipped file or folder ``mirrorlab/data/<parts...>`` as a path on disk, e.g.
    ``data_path("models", "base.obj")``. It need not exist (callers check); RuntimeError
    when mirrorlab runs from a zip archive, which it does not support. (Remembered: a
    scene graph asks for its meshes whenever it is posed.)"""
    root = files(__name__)
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


__all__ = ["data_path", "model_file", "scenes_dir", "texture_file"]
