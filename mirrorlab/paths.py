"""Where mirrorlab finds its shipped files: the source checkout (models/, textures/,
scenes/, beside the package; mirrorlab is installed editable from it) and its shaders."""

from __future__ import annotations

from pathlib import Path

PACKAGE_DIR = Path(__file__).resolve().parent
REPO_DIR = PACKAGE_DIR.parent


def shader_source(name: str) -> str:
    """Text of the package shader file ``mirrorlab/shaders/<name>``."""
    path = PACKAGE_DIR / "shaders" / name
    if not path.is_file():
        raise FileNotFoundError(f"shader file {path} is missing from the package")
    return path.read_text()
