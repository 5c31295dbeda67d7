"""mirrorlab: the CS370 multipass mirror, and environment mapping, measured.

The public API: :func:`load_scene` reads a scene file, :class:`Renderer` keeps one
headless OpenGL context across frames and scenes, and :func:`render` draws one frame.
Importing this package loads neither OpenGL nor glfw; a Renderer does, when made.
"""

from __future__ import annotations

from importlib.metadata import PackageNotFoundError, version

from mirrorlab.api import Renderer, render
from mirrorlab.frame import Frame, show
from mirrorlab.scene.loader import SceneError, load_scene
from mirrorlab.scene.model import Camera, Scene

__all__ = ["Camera", "Frame", "Renderer", "Scene", "SceneError", "load_scene", "render", "show"]
try:
    __version__ = version("mirrorlab")
    """The installed version, as the package metadata (pyproject.toml) gives it."""
except PackageNotFoundError:  # a source folder on sys.path, never installed
    __version__ = "0+unknown"
