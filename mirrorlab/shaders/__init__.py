"""The GLSL sources (``*.vert``, ``*.frag``, ``*.glsl``), package data read with
:mod:`importlib.resources`."""

from __future__ import annotations

from importlib.resources import files


def shader_source(name: str) -> str:
    """Text of the package shader file ``mirrorlab/shaders/<name>``; FileNotFoundError
    naming it when the package lacks it."""
    resource = files(__name__).joinpath(name)
    if not resource.is_file():
        raise FileNotFoundError(f"shader file {name} is missing from the mirrorlab package")
    return resource.read_text()
