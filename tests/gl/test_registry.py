"""A technique registered in this file alone is drawn by the renderer: its pass follows the
entry's flags, not its name, so an entry like a shipped one under another name draws
the same frame, pixel for pixel."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import mirrorlab
from mirrorlab.options import apply_options
from mirrorlab.techniques import register, technique, unregister
from tests.gl.frames import draw

SIZE = (96, 96)


@pytest.mark.parametrize(
    ("scene_name", "like"),
    [
        ("lab20", "reflected"),
        ("lab20", "stencil"),
        ("lab20", "ortho"),
        ("chrome_sphere", "sphere"),
        ("chrome_sphere", "sphere-texgen"),
        ("chrome_sphere", "cube"),
        ("chrome_sphere", "latlong"),
        ("chrome_sphere", "normal"),
        ("mirror_and_sphere", "cube-live"),
    ],
)
def test_a_renamed_copy_of_a_technique_draws_the_same_frame(scene_renderer, scene_name, like):
    copy = replace(technique(like), name=f"copy-of-{like}")
    register(copy)
    try:
        scene = mirrorlab.load_scene(scene_name)
        kind = copy.kind
        original = replace(
            scene,
            reflectors=tuple(
                replace(r, technique=like) if r.kind == kind else r for r in scene.reflectors
            ),
        )
        renamed = apply_options(original, {"method": copy.name})
        assert {r.technique for r in renamed.reflectors if r.kind == kind} == {copy.name}
        expected = draw(scene_renderer, original, SIZE)[0]
        image, stats = draw(scene_renderer, renamed, SIZE)
        assert any(d.reflector.technique == copy.name for d in stats.plan.top.draws)
        assert np.array_equal(image, expected)
    finally:
        unregister(copy.name)
