"""Where mirrorlab finds its assets (models/, textures/) and shaders."""

from __future__ import annotations

from pathlib import Path

PACKAGE_DIR = Path(__file__).resolve().parent
REPO_DIR = PACKAGE_DIR.parent


def asset_path(folder: str, name: str) -> Path:
    """Path of ``<repo>/<folder>/<name>``; FileNotFoundError with the full path if missing.

    The assets live beside the package in the source checkout, so mirrorlab
    is installed editable (``pip install -e .``) from that checkout.
    """
    path = REPO_DIR / folder / name
    if not path.is_file():
        raise FileNotFoundError(
            f"asset {path} is missing; mirrorlab expects its source checkout "
            f"(install with 'pip install -e .', or re-make assets with tools/make_assets.py)"
        )
    return path


def shader_source(name: str) -> str:
    """Text of the package shader file ``mirrorlab/shaders/<name>``."""
    path = PACKAGE_DIR / "shaders" / name
    if not path.is_file():
        raise FileNotFoundError(f"shader file {path} is missing from the package")
    return path.read_text()
