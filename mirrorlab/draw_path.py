"""The ways the scene drawer (:mod:`mirrorlab.passes.scene_draw`) can draw a view's parts,
by name: imports no OpenGL, so the public API and the command line can check a name
without a context."""

from __future__ import annotations

from typing import Literal

DrawPath = Literal["auto", "packed", "per-draw"]
DRAW_PATHS: tuple[DrawPath, ...] = ("auto", "packed", "per-draw")
"""How a drawer draws a view's parts: ``auto`` picks ``packed`` where the context offers
it, else ``per-draw``."""
