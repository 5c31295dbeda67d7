"""mirrorlab: the CS370 multipass mirror, and environment mapping, measured.

The public API: :func:`load_scene` reads a scene file, :class:`Renderer` keeps one
headless OpenGL context across frames and scenes, and :func:`render` draws one frame.
Importing this package loads neither OpenGL nor glfw; a Renderer does, when made. The
names below are imported on first use, so that a process that needs only a part of
mirrorlab (the labs' checker, the command line's other commands) loads only that part.
"""

from __future__ import annotations

from importlib import import_module
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from mirrorlab.api import Renderer, render
    from mirrorlab.frame import Frame, show
    from mirrorlab.scene.loader import SceneError, load_scene
    from mirrorlab.scene.model import Camera, Scene

_PUBLIC = {
    "Camera": "mirrorlab.scene.model",
    "Frame": "mirrorlab.frame",
    "Renderer": "mirrorlab.api",
    "Scene": "mirrorlab.scene.model",
    "SceneError": "mirrorlab.scene.loader",
    "load_scene": "mirrorlab.scene.loader",
    "render": "mirrorlab.api",
    "show": "mirrorlab.frame",
}
__all__ = ["Camera", "Frame", "Renderer", "Scene", "SceneError", "load_scene", "render", "show"]


def _version() -> str:
    """The installed version, as the package metadata (pyproject.toml) gives it."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("mirrorlab")
    except PackageNotFoundError:  # a source folder on sys.path, never installed
        return "0+unknown"


def __getattr__(name: str) -> Any:
    if name == "__version__":
        value: Any = _version()
    elif name in _PUBLIC:
        value = getattr(import_module(_PUBLIC[name]), name)
    else:
        raise AttributeError(f"module 'mirrorlab' has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted([*globals(), *_PUBLIC, "__version__"])
