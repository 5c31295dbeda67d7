"""Every number of lights a scene may have (0 to 4) is lit as the ray tracer lights it.

The lit shader is built once per light count (``LIGHT_COUNT`` in lighting.glsl), so each
count is its own program: the robot of the lab scene, without its mirror, is drawn with
0, 1, 2, 3 and 4 lights of different directions and colours by one renderer, in an order
that goes back and forth between counts, on both draw paths, and compared with the
tracer. Tolerance: 99% of the pixels inside the robot's silhouette within 10/255 (its
edge is rasterised differently). A count the renderer got wrong (a light left out or
counted twice) moves most of them by far more; each count's frame must also differ from
the last one's.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import mirrorlab
from mirrorlab.raytrace import trace_scene
from mirrorlab.renderer import SceneRenderer
from mirrorlab.scene.model import Light
from tests.gl.frames import draw
from tests.imagecheck import save_failure, share_within

SIZE = (64, 64)
# lights on the camera's side, of different colours: each one shows on most lit pixels
LIGHTS = (
    Light((0.45, 0.8, 0.4), 0.25),
    Light((0.9, 0.1, 0.3), 0.25, (1.0, 0.6, 0.3)),
    Light((0.2, 0.3, 0.95), 0.25, (0.3, 0.5, 1.0)),
    Light((0.6, -0.2, 0.7), 0.25, (0.6, 1.0, 0.6)),
)
ORDER = (1, 4, 0, 2, 3, 1, 0)


def lit_scene(count: int):
    lab = mirrorlab.load_scene("lab20")
    return replace(lab, reflectors=(), lights=LIGHTS[:count])


@pytest.fixture(scope="module")
def truths():
    return {count: trace_scene(lit_scene(count), SIZE).to_uint8() for count in set(ORDER)}


def inside_the_robot(truth: np.ndarray) -> np.ndarray:
    """``(h, w)`` bool: pixels whose 3 x 3 neighbourhood the tracer shows all robot (not
    background): where the lighting is judged, away from the silhouette's edge."""
    background = truth[0, 0]
    robot = np.any(truth != background, axis=-1)
    inner = robot.copy()
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            inner &= np.roll(robot, (dy, dx), axis=(0, 1))
    return inner


@pytest.mark.parametrize("draw_path", ["packed", "per-draw"])
def test_every_light_count_is_lit_as_the_tracer_lights_it(registry, truths, draw_path):
    renderer = SceneRenderer(registry, draw_path=draw_path)
    try:
        previous = None
        for count in ORDER:
            image, _ = draw(renderer, lit_scene(count), SIZE)
            mask = inside_the_robot(truths[count])
            assert mask.sum() > 200  # the robot fills much of the frame
            share = share_within(image, truths[count], mask, 10)
            if share < 0.99:
                save_failure(f"lights_{draw_path}_{count}", frame=image, truth=truths[count])
            assert share >= 0.99, (
                f"{count} lights ({draw_path}): only {share:.1%} of "
                f"the robot's pixels within 10/255 of the tracer"
            )
            if previous is not None:
                assert not np.array_equal(image, previous), f"{count} lights: frame unchanged"
            previous = image
    finally:
        renderer.release()


def test_lights_changed_at_the_same_count_are_the_ones_drawn(registry):
    """One program draws every scene of a light count: a change of the lights' directions,
    colours or the ambient light (the program kept) shows in the next frame, as a fresh
    renderer draws it."""
    lab = lit_scene(2)
    scenes = [lab, replace(lab, lights=LIGHTS[2:4]), replace(lab, ambient=lab.ambient + 0.2), lab]
    renderer = SceneRenderer(registry)
    try:
        images = [draw(renderer, scene, SIZE)[0] for scene in scenes]
    finally:
        renderer.release()
    for scene, image in zip(scenes, images, strict=True):
        fresh = SceneRenderer(registry)
        try:
            assert np.array_equal(image, draw(fresh, scene, SIZE)[0])
        finally:
            fresh.release()
    assert not np.array_equal(images[0], images[1])
    assert not np.array_equal(images[0], images[2])
    assert np.array_equal(images[0], images[3])
