"""A viewer looking straight into the mirror from about its near-plane distance: the
frame follows the distance continuously and agrees with the ray tracer on both sides.

The lab's mirror lies in the plane x = -7; the viewer stands on its normal at distance
``d`` from it, looking at it, with the scene's near plane 0.1. For ``d`` below 0.1 the
glass is nearer than the near plane and clipped (the frame behind it shows), for
``d`` of 0.1 and above the glass fills the frame with the reflection. A viewer at
exactly 0.1 once got a black (``reflected``) or flat brown (``stencil``) frame while
0.0001 either side was right: float rounding put the glass on either side of the
near plane. Tolerance: 99% of pixels within 10/255 of the tracer.
"""

from __future__ import annotations

import itertools
from dataclasses import replace

import numpy as np
import pytest

import mirrorlab
from mirrorlab.options import apply_options
from mirrorlab.raytrace import trace_scene
from tests.gl.frames import draw
from tests.imagecheck import save_failure, share_within

SIZE = (40, 40)
NEAR = 0.1
DISTANCES = (
    0.05,
    NEAR - 1e-4,
    NEAR - 1e-7,
    NEAR,
    NEAR + 1e-12,
    NEAR + 1e-9,
    NEAR + 1e-6,
    NEAR + 1e-4,
    NEAR + 1e-3,
    0.12,
    0.2,
)


def viewer_scene(distance: float, method: str):
    scene = mirrorlab.load_scene("lab20")
    camera = replace(
        scene.camera, eye=(-7.0 + distance, 1.0, -2.0), target=(-7.0, 1.0, -2.0), near=NEAR
    )
    return apply_options(replace(scene, camera=camera), {"method": method})


@pytest.fixture(scope="module")
def truths():
    return {d: trace_scene(viewer_scene(d, "stencil"), SIZE) for d in DISTANCES}


@pytest.mark.parametrize("method", ["reflected", "stencil"])
def test_the_frame_agrees_with_the_tracer_across_the_near_plane(scene_renderer, truths, method):
    frames = []
    for distance in DISTANCES:
        image, stats = draw(scene_renderer, viewer_scene(distance, method), SIZE)
        truth = truths[distance]
        share = share_within(image, truth.to_uint8(), np.ones(SIZE[::-1], bool), 10)
        if share < 0.99:
            save_failure(f"near_plane_{method}_{distance!r}", frame=image, truth=truth.to_uint8())
        assert share >= 0.99, (
            f"{method} at distance {distance!r}: only {share:.1%} of "
            f"pixels agree with the tracer (ran {stats.ran})"
        )
        seen = truth.reflective_mask.mean()
        assert (seen > 0.99) == (distance >= NEAR - 1e-7), (
            f"the tracer {'sees' if seen > 0.99 else 'does not see'} the glass at {distance!r}"
        )
        frames.append(image.astype(int))
    # Continuity: from the near plane outwards, each step changes the frame a little.
    on_glass = [f for d, f in zip(DISTANCES, frames, strict=True) if d >= NEAR - 1e-7]
    steps = [np.abs(b - a).mean() for a, b in itertools.pairwise(on_glass)]
    assert max(steps[:-2]) < 1.0, f"the frame jumps between nearby distances: {steps}"
