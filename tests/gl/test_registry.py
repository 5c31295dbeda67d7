"""A technique registered in this file alone is drawn by the renderer: its pass follows the
entry's flags, not its name, so an entry like a shipped one under another name draws
the same frame, pixel for pixel."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import mirrorlab
from mirrorlab.options import apply_options
from mirrorlab.techniques import (
    Technique,
    register,
    technique,
    technique_names,
    techniques,
    unregister,
)
from tests.gl.frames import draw

SIZE = (96, 96)


def scene_for(entry: Technique) -> str:
    """A shipped scene with a reflector of ``entry``'s kind: the lab's mirror for a planar
    technique, and for a curved one the sphere beside a mirror (a live map captures the
    mirror too)."""
    return "lab20" if entry.kind == "planar" else "mirror_and_sphere"


def copy_cases() -> list[tuple[str, str]]:
    """Every technique a reflector may take (from the registry), on its :func:`scene_for`."""
    return [(scene_for(entry), entry.name) for entry in techniques() if entry.kind != "frame"]


@pytest.mark.parametrize(("scene_name", "like"), copy_cases())
def test_a_renamed_copy_of_a_technique_draws_the_same_frame(scene_renderer, scene_name, like):
    copy = replace(technique(like), name=f"copy-of-{like}")
    register(copy)
    try:
        scene = mirrorlab.load_scene(scene_name)

        def takes(reflector) -> bool:  # a reflector of a kind the technique serves
            return copy.name in technique_names(reflector.kind)

        original = replace(
            scene,
            reflectors=tuple(
                replace(r, technique=like) if takes(r) else r for r in scene.reflectors
            ),
        )
        renamed = apply_options(original, {"method": copy.name})
        assert {r.technique for r in renamed.reflectors if takes(r)} == {copy.name}
        expected = draw(scene_renderer, original, SIZE)[0]
        image, stats = draw(scene_renderer, renamed, SIZE)
        assert any(d.reflector.technique == copy.name for d in stats.plan.top.draws)
        assert np.array_equal(image, expected)
    finally:
        unregister(copy.name)
