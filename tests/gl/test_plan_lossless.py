"""The plan is lossless: on generated scenes, a planned frame equals the frame drawn with
every pass (``--no-plan``: no pass skipped, no object culled, nothing scissored), pixel
for pixel. The scenes hold reflectors of every technique, placed across the edges and
corners of the view (reaching behind the eye, long and thin, tiny and huge), small and
sub-pixel objects, turned, near the edges too, cameras rolled and tilted with lenses
from 3 to 178 degrees, one to three bounces, and a second frame in which a mirror moves
and turns and the camera shifts, then the first frame again (whose captures the
planner may reuse). And a mirror flush with a wall, where the draws' order decides the
depth ties (which generated scenes hardly ever hold), on both draw paths.

The planner keeps its textures from one generated scene to the next, as a renderer
does; the unplanned renderer draws every pass of every frame. Examples are generated
from a fixed seed (``derandomize``), so a run is reproducible; ``MIRRORLAB_PLAN_EXAMPLES``
asks for more of them (the suite runs 30)."""

from __future__ import annotations

import os
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mirrorlab import techniques as registry
from mirrorlab.renderer import SceneRenderer
from mirrorlab.scene.model import (
    Background,
    BoxProxy,
    DistanceSearch,
    MeshObject,
    OrthoCapture,
    PlanarReflector,
    RobotObject,
    Scene,
    SceneObject,
    SphereProxy,
    Transform,
)
from mirrorlab.techniques import technique_names
from tests.gl.frames import draw
from tests.imagecheck import save_failure
from tests.scenekit import PANEL_MESH, ball, block, looking, mirror

EXAMPLES = int(os.environ.get("MIRRORLAB_PLAN_EXAMPLES", "30"))
SIZES = [(64, 64), (80, 48), (48, 72)]


def unit_vector(draw) -> np.ndarray:
    while True:
        v = np.array([draw(st.floats(-1, 1)) for _ in range(3)])
        if np.linalg.norm(v) > 0.2:
            return v / np.linalg.norm(v)


@st.composite
def cameras(draw):
    eye = np.array([draw(st.floats(-10, 10)), draw(st.floats(-4, 8)), draw(st.floats(-10, 10))])
    forward = unit_vector(draw)
    side = np.cross(forward, (0.0, 1.0, 0.0))
    if np.linalg.norm(side) < 0.1:
        side = np.array([1.0, 0.0, 0.0])
    side /= np.linalg.norm(side)
    roll = np.radians(draw(st.floats(-180, 180)))
    up = np.cos(roll) * np.cross(side, forward) + np.sin(roll) * side
    fovy = draw(st.sampled_from([3.0, 20.0, 45.0, 90.0, 150.0, 178.0]))
    near = draw(st.sampled_from([0.05, 0.5]))
    far = draw(st.sampled_from([15.0, 60.0, 300.0]))
    return looking(eye, eye + forward, up, fovy=fovy, near=near, far=far)


def near_the_edge(draw, camera, aspect: float) -> np.ndarray:
    """A world point the camera sees near (or past) an edge or corner of its view."""
    x, y = draw(st.floats(-1.4, 1.4)), draw(st.floats(-1.4, 1.4))
    if draw(st.booleans()):  # on an edge
        if draw(st.booleans()):
            x = draw(st.sampled_from([-1.0, 1.0]))
        else:
            y = draw(st.sampled_from([-1.0, 1.0]))
    depth = draw(st.floats(0.3, 25.0))
    view, projection = camera.view(), camera.projection(aspect)
    tangent_y = 1.0 / projection[1, 1]
    tangent_x = 1.0 / projection[0, 0]
    eye_point = np.array([x * tangent_x * depth, y * tangent_y * depth, -depth, 1.0])
    return (np.linalg.inv(view) @ eye_point)[:3]


@st.composite
def reflectors(draw, camera, aspect, index: int):
    center = near_the_edge(draw, camera, aspect)
    name = f"r{index}"
    if draw(st.booleans()):
        normal = unit_vector(draw)
        if draw(st.booleans()):  # mostly facing the camera, so that it shows
            normal = np.asarray(camera.eye) - center
            normal = normal / np.linalg.norm(normal) + 0.6 * unit_vector(draw)
        up = unit_vector(draw)
        if np.linalg.norm(np.cross(normal, up)) < 0.2:
            up = np.cross(normal, (0.3, 0.9, 0.2))
        width = draw(st.sampled_from([0.05, 0.6, 3.0, 12.0, 40.0]))
        height = draw(st.sampled_from([0.05, 0.6, 3.0, 12.0, 40.0]))
        technique = draw(st.sampled_from(technique_names("planar")))
        size = draw(st.sampled_from([None, 32]))
        return mirror(
            name, center, normal, width, height, technique, up=tuple(up), texture_size=size
        )
    technique = draw(st.sampled_from(technique_names("curved")))
    radius = draw(st.sampled_from([0.05, 0.4, 1.5, 6.0]))
    made = ball(name, center, radius, technique, map_size=draw(st.sampled_from([16, 32])))
    if registry.technique(technique).parallax:
        parallax = draw(st.sampled_from([None, "box", "sphere", "distance"]))
        if parallax == "box":
            made = replace(made, parallax=BoxProxy(tuple(center - 8.0), tuple(center + 8.0)))
        elif parallax == "sphere":
            made = replace(made, parallax=SphereProxy(6.0))
        elif parallax == "distance":
            made = replace(made, parallax=DistanceSearch(steps=4, secant=1))
    return made


@st.composite
def scenes(draw):
    size = draw(st.sampled_from(SIZES))
    camera = draw(cameras())
    aspect = size[0] / size[1]
    count = draw(st.integers(1, 3))
    made = [draw(reflectors(camera, aspect, i)) for i in range(count)]
    # live maps (six captures each) cost the most bounces: two or more, at most two deep
    live = sum(
        1 for r in made if r.kind == "curved" and registry.technique(r.technique).texture == "fixed"
    )
    bounces = draw(st.integers(0, 3 if live < 2 else 2))
    robot = RobotObject(
        angles=(draw(st.floats(-90, 90)), 30.0, -60.0),
        transform=Transform(position=tuple(near_the_edge(draw, camera, aspect))),
    )
    objects: tuple[SceneObject, ...] = (
        robot,
        block("block", near_the_edge(draw, camera, aspect), 2.0, (0.2, 0.8, 0.3)),
    )
    for i in range(draw(st.integers(0, 6))):  # small things near the edges, some specks
        side = draw(st.sampled_from([0.003, 0.03, 0.3]))
        turn = tuple(draw(st.floats(-180, 180)) for _ in range(3))
        speck = block(f"speck{i}", near_the_edge(draw, camera, aspect), side, (0.9, 0.7, 0.2))
        objects += (replace(speck, transform=replace(speck.transform, rotation=turn)),)
    background = draw(st.sampled_from([Background(), Background(kind="sky")]))
    return size, Scene(
        name="generated",
        camera=camera,
        background=background,
        objects=objects,
        reflectors=tuple(made),
        max_bounces=bounces,
    )


def moved(scene: Scene) -> Scene:
    """The next frame: the first planar mirror turned and moved, the camera shifted."""
    reflectors = list(scene.reflectors)
    for i, reflector in enumerate(reflectors):
        if isinstance(reflector, PlanarReflector):
            reflectors[i] = reflector.moved(
                tuple(np.add(reflector.center, (0.4, -0.3, 0.5))), (5.0, 20.0, -10.0)
            )
            break
    camera = scene.camera
    eye = tuple(np.add(camera.eye, (0.3, 0.1, -0.2)))
    return replace(scene, reflectors=tuple(reflectors), camera=replace(camera, eye=eye))


@settings(
    max_examples=EXAMPLES,
    deadline=None,
    derandomize=True,
    suppress_health_check=[
        HealthCheck.function_scoped_fixture,
        HealthCheck.too_slow,
        HealthCheck.data_too_large,
        HealthCheck.large_base_example,
    ],
)
@given(generated=scenes())
def test_planned_frames_equal_unplanned_frames_on_generated_scenes(scene_renderer, generated):
    size, scene = generated
    unplanned = SceneRenderer(scene_renderer.registry)
    try:
        for index, frame in enumerate((scene, moved(scene), scene)):
            planned_image = draw(scene_renderer, frame, size)[0]
            every_image = draw(unplanned, frame, size, use_plan=False)[0]
            if not np.array_equal(planned_image, every_image):
                save_failure(
                    f"plan_lossless_{index}", planned=planned_image, every_pass=every_image
                )
                differing = int((planned_image != every_image).any(axis=-1).sum())
                plan = scene_renderer.last_frame.plan
                raise AssertionError(
                    f"frame {index}: {differing} pixels differ\n"
                    + "\n".join(plan.describe())
                    + f"\n{frame}"
                )
    finally:
        unplanned.release()


@pytest.mark.parametrize("method", technique_names("planar"))
def test_a_mirror_flush_with_a_wall_comes_out_the_same_planned_or_not_on_either_path(
    scene_renderer, method
):
    """A mirror hung flat on a wall (the two in one plane: their depths tie wherever
    rounding lets them) is drawn in one order whatever the plan skips, culls or scissors,
    and on either draw path: the frames are the same, pixel for pixel, moving or still."""
    wall = MeshObject(
        name="wall",
        mesh=PANEL_MESH,
        color=(0.7, 0.6, 0.5),
        transform=Transform(scale=(8.0, 6.0, 1.0)),
    )
    glass = mirror("glass", (0.0, 0.0, 0.0), (0.0, 0.0, 1.0), 3.0, 2.0, method)
    if registry.technique(method).own_camera:  # ortho: the capture camera it needs
        glass = replace(
            glass,
            ortho=OrthoCapture(
                eye=(0.0, 0.0, 0.0),
                target=(0.0, 0.0, 1.0),
                up=(0.0, 1.0, 0.0),
                extents=(-1.5, 1.5, -1.0, 1.0, 0.0, 20.0),
            ),
        )
    scene = Scene(
        name="flush",
        camera=looking((1.5, 0.8, 6.0), (0.0, 0.0, 0.0)),
        objects=(wall, block("block", (0.6, -0.2, 2.0), 0.8, (0.2, 0.8, 0.3))),
        reflectors=(glass,),
        max_bounces=1,
    )
    turned = replace(scene, camera=looking((-1.0, 0.5, 5.0), (0.0, 0.0, 0.0)))
    unplanned = SceneRenderer(scene_renderer.registry)
    per_draw = SceneRenderer(scene_renderer.registry, draw_path="per-draw")
    try:
        for index, frame in enumerate((scene, turned, scene)):
            planned_image = draw(scene_renderer, frame, (96, 80))[0]
            for name, other, options in (
                ("every_pass", unplanned, {"use_plan": False}),
                ("per_draw", per_draw, {}),
            ):
                image = draw(other, frame, (96, 80), **options)[0]
                if not np.array_equal(planned_image, image):
                    save_failure(
                        f"flush_{method}_{name}_{index}", planned=planned_image, other=image
                    )
                    differing = int((planned_image != image).any(axis=-1).sum())
                    raise AssertionError(f"frame {index}, {name}: {differing} pixels differ")
    finally:
        unplanned.release()
        per_draw.release()
