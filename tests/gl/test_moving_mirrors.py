"""A planar mirror that slides into view, turns and slides out again
(tests/unit/test_moving_mirrors.py's scene), drawn by the one renderer: each frame as the
ray tracer draws it, and planned frames equal to unplanned ones, whichever order the
frames come in."""

from __future__ import annotations

import numpy as np
import pytest

from mirrorlab.raytrace import trace_scene
from mirrorlab.renderer import SceneRenderer
from mirrorlab.techniques import technique_names
from tests.gl.frames import draw
from tests.imagecheck import save_failure
from tests.unit.test_moving_mirrors import turning

SIZE = (96, 96)


@pytest.mark.parametrize("method", ["reflected", "stencil"])
def test_a_moving_mirror_agrees_with_the_truth_in_every_frame(scene_renderer, method):
    scene = turning(method)
    seen = 0
    for frame in range(scene.frame_count):
        posed = scene.at_frame(frame)
        image = draw(scene_renderer, posed, SIZE)[0]
        truth = trace_scene(posed, SIZE)
        mask = truth.reflective_mask
        worst = np.abs(image.astype(int) - truth.to_uint8().astype(int)).max(axis=-1)
        assert np.mean(worst <= 10) >= 0.99, f"{method} frame {frame}"
        if mask.sum() > 50:
            seen += 1
            share = float(np.mean(worst[mask] <= 10))
            if share < 0.99:
                save_failure(f"moving_{method}_{frame}", rendered=image, traced=truth.to_uint8())
            assert share >= 0.99, f"{method} frame {frame}: {share:.2%}"
    assert seen >= 4  # it was in view, held, turned


@pytest.mark.parametrize("method", technique_names("planar"))
def test_a_moving_mirror_planned_equals_unplanned_in_any_order(scene_renderer, method):
    scene = turning(method)
    unplanned = SceneRenderer(scene_renderer.registry)
    try:
        frames = list(range(scene.frame_count))
        for order in (frames, frames[::-1], [3, 0, 5, 5, 2, 7, 4]):
            for frame in order:
                posed = scene.at_frame(frame)
                planned = draw(scene_renderer, posed, SIZE)[0]
                every = draw(unplanned, posed, SIZE, use_plan=False)[0]
                assert np.array_equal(planned, every), f"{method} frame {frame} of {order}"
    finally:
        unplanned.release()
