"""Parallax-corrected live cube maps on llvmpipe: each shader path (box proxy, sphere proxy,
distance search; ``shaders/parallax.glsl``) against its numpy reference
(:mod:`mirrorlab.parallax`) on the rays of random views, the hard cases through a float
framebuffer, the box proxy in a room against the ray tracer, and what the plan and the
renderer keep when only a proxy's sizes change.

The rays are read back from the reflector itself: the cube shader writes, instead of the
colour, each fragment's lookup direction (``OUTPUT_COORDINATES``; alpha 0 where a distance
search leaves for the background), the reflected ray's world origin
(``OUTPUT_RAY_ORIGIN``) or its direction (``OUTPUT_RAY_DIRECTION``), into a 32-bit float
target. The numpy reference gets the same origins and directions (and, for the distance
search, the depth cube read back from the pass) and must give the same directions.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from mirrorlab import load_scene, math3d, parallax
from mirrorlab.accuracy import erode
from mirrorlab.bounds import encloses
from mirrorlab.gl.resources import FloatFramebuffer
from mirrorlab.options import apply_options
from mirrorlab.passes.cube_live import capture_depth_range
from mirrorlab.passes.envmap import (
    OUTPUT_COLOR,
    OUTPUT_COORDINATES,
    OUTPUT_RAY_DIRECTION,
    OUTPUT_RAY_ORIGIN,
)
from mirrorlab.raytrace import trace_scene
from mirrorlab.scene.model import (
    BoxProxy,
    Camera,
    CurvedReflector,
    DistanceSearch,
    Scene,
    SphereProxy,
    Transform,
)
from mirrorlab.views import View
from tests.gl.envmap_frames import assert_close_to_truth, region_error, render
from tests.imagecheck import save_failure
from tests.scenekit import curved_reflector, mesh_object

SIZE = 96
ROOM_SIZE = 128
MAP = 64
PANEL = mesh_object(load_scene("sphere_room"), "floor").mesh


def sphere_scene(correction: str, map_size: int = MAP) -> Scene:
    """The chrome sphere among its objects as a live cube map with ``correction``."""
    return apply_options(
        load_scene("chrome_sphere"),
        {"method": "cube-live", "map_size": map_size, "parallax": correction},
    )


def read_rays(
    renderer, scene: Scene, view: View | None = None, name: str = "sphere"
) -> dict[int, np.ndarray]:
    """Every output of one view of ``scene``, ``(h, w, 4)`` float32 each, by mode."""
    target = FloatFramebuffer(renderer.registry, SIZE, SIZE)
    curved = None
    outputs = {}
    try:
        for mode in (OUTPUT_COLOR, OUTPUT_COORDINATES, OUTPUT_RAY_ORIGIN, OUTPUT_RAY_DIRECTION):
            if curved is not None:
                curved.output_mode = mode
            renderer.render(scene, target, view=view)
            curved = renderer.pass_for(name)
            outputs[mode] = target.read_rgba()
    finally:
        if curved is not None:
            curved.output_mode = OUTPUT_COLOR
        target.release()
    return outputs


def reflector_pixels(outputs: dict[int, np.ndarray]) -> np.ndarray:
    """Where the reflector was drawn: its ray direction is a unit vector there (the sky
    and the objects write colours, which are not)."""
    direction = outputs[OUTPUT_RAY_DIRECTION][..., :3]
    return np.abs(np.linalg.norm(direction, axis=-1) - 1.0) < 1e-4


def reference(renderer, scene: Scene, outputs, pixels, name: str = "sphere"):
    """(lookup directions, background flags) of the numpy reference on the rays read back."""
    reflector = scene.reflector(name)
    assert isinstance(reflector, CurvedReflector)
    origin = outputs[OUTPUT_RAY_ORIGIN][pixels][:, :3].astype(np.float64)
    direction = outputs[OUTPUT_RAY_DIRECTION][pixels][:, :3].astype(np.float64)
    center = reflector.center()
    correction = reflector.parallax
    none = np.zeros(len(origin), bool)
    if isinstance(correction, BoxProxy):
        return parallax.box_lookup(origin, direction, center, correction.min, correction.max), none
    if isinstance(correction, SphereProxy):
        return parallax.sphere_lookup(origin, direction, center, correction.radius), none
    assert isinstance(correction, DistanceSearch)
    live = renderer.pass_for(name)
    drawn = renderer.last_frame.plan.top.draws[0]
    faces = np.stack([live.depth(drawn.slot).read_face(face) for face in range(6)])
    near, far = capture_depth_range(drawn.source)
    return parallax.distance_lookup(
        origin,
        direction,
        center,
        parallax.depth_capture(faces, near, far),
        correction.steps,
        correction.secant,
        correction.thickness,
        encloses(scene, center, name),
    )


def random_camera(rng: np.random.Generator) -> Camera:
    """Somewhere 3 to 8 units from the sphere and 5 to 50 degrees above it (from lower,
    the pedestal hides it), looking near it."""
    azimuth = rng.uniform(0.0, 2.0 * np.pi)
    elevation = np.radians(rng.uniform(5.0, 50.0))
    direction = np.array(
        [
            np.cos(elevation) * np.cos(azimuth),
            np.sin(elevation),
            np.cos(elevation) * np.sin(azimuth),
        ]
    )
    eye = direction * rng.uniform(3.0, 8.0)
    target = rng.uniform(-0.3, 0.3, size=3)
    return Camera(eye=tuple(eye), target=tuple(target), fovy=float(rng.uniform(25.0, 45.0)))


def random_correction(kind: str, rng: np.random.Generator) -> str:
    if kind == "box":  # around the sphere's centre, from just outside it to the objects
        low = -rng.uniform(0.5, 3.0, size=3)
        high = rng.uniform(0.5, 3.0, size=3)
        return "box:" + ",".join(f"{v:.3f}" for v in (*low, *high))
    if kind == "sphere":
        return f"sphere:{rng.uniform(0.6, 4.0):.3f}"
    return f"distance:{rng.integers(2, 12)}+{rng.integers(0, 4)}"


@pytest.mark.parametrize("kind", ["box", "sphere", "distance"])
def test_each_correction_matches_its_numpy_reference_on_the_rays_of_random_views(
    scene_renderer, kind
):
    # Box and sphere are arithmetic, float32 against float64: over 16 random views, 99 %
    # of the rays within 1.2e-7 of the reference, the worst 7e-5 (an origin next to a face,
    # where the exit distance is ill-conditioned); allowed: 99.9 % within 1e-6, all within
    # 1e-3. The distance search branches on signs and on which texel a direction falls
    # in, and float32 rounding may take another branch for a ray now and then: measured
    # within 2.4e-6 everywhere, allowed 1e-4 on 99 % of the rays.
    rng = np.random.default_rng({"box": 11, "sphere": 12, "distance": 13}[kind])
    rays = 0
    for _ in range(2):
        scene = replace(sphere_scene(random_correction(kind, rng)), camera=random_camera(rng))
        outputs = read_rays(scene_renderer, scene)
        pixels = reflector_pixels(outputs)
        assert pixels.sum() > 200
        look = outputs[OUTPUT_COORDINATES][pixels]
        assert np.isfinite(look).all()
        expected, background = reference(scene_renderer, scene, outputs, pixels)
        error = np.linalg.norm(look[:, :3] - expected, axis=-1)
        same_map = (look[:, 3] < 0.5) == background
        if kind == "distance":
            assert np.mean((error < 1e-4) & same_map) >= 0.99, (
                np.percentile(error, 99),
                same_map.mean(),
            )
        else:
            assert np.mean(error < 1e-6) >= 0.999 and error.max() < 1e-3, error.max()
            assert same_map.all()
        colour = outputs[OUTPUT_COLOR][..., :3]
        assert np.isfinite(colour).all() and colour.min() >= 0.0 and colour.max() <= 1.0
        rays += int(pixels.sum())
    assert rays > 1000


# ------------------------------------------------------------------- hard cases


def plain_where_the_proxy_says_nothing(outputs, pixels):
    """Every lookup is the unit reflected ray itself (the plain lookup, in the capture)."""
    look = outputs[OUTPUT_COORDINATES][pixels]
    direction = outputs[OUTPUT_RAY_DIRECTION][pixels]
    assert np.isfinite(look).all()
    assert np.allclose(look[:, :3], direction[:, :3], atol=1e-6)
    assert np.all(look[:, 3] == 1.0)


@pytest.mark.parametrize("correction", ["box:-0.5,-0.5,-0.5,0.5,0.5,0.5", "sphere:0.5"])
def test_rays_that_start_outside_the_proxy_get_the_plain_lookup(scene_renderer, correction):
    # A proxy smaller than the sphere holds its centre but none of its surface.
    outputs = read_rays(scene_renderer, sphere_scene(correction))
    pixels = reflector_pixels(outputs)
    assert pixels.sum() > 500
    plain_where_the_proxy_says_nothing(outputs, pixels)
    colour = outputs[OUTPUT_COLOR][..., :3]
    assert np.isfinite(colour).all() and colour.min() >= 0.0 and colour.max() <= 1.0


def panel_scene(correction: str) -> tuple[Scene, View]:
    """A flat square reflector facing +z in a box room (chrome_sphere's sky and objects),
    and an orthographic view straight down -z onto it: every reflected ray is exactly
    (0, 0, 1), parallel to four faces of a box proxy; at the panel's centre the ray starts
    at the capture centre."""
    scene = sphere_scene(correction)
    panel = replace(
        curved_reflector(scene, "sphere"),
        mesh=PANEL,
        transform=Transform(position=(0.0, 0.2, 0.0), scale=(1.6, 1.6, 1.0)),
    )
    scene = replace(scene, reflectors=(panel,))
    view = math3d.look_at((0.0, 0.2, 5.0), (0.0, 0.2, 0.0), (0.0, 1.0, 0.0))
    projection = math3d.ortho(-1.0, 1.0, -1.0, 1.0, 0.5, 20.0)
    return scene, View(
        view=view, projection=projection, size=(SIZE, SIZE), eye=None, label="straight down -z"
    )


@pytest.mark.parametrize(
    "correction", ["box:-3,-1,-3,3,3,3", "sphere:3", "distance:8+2", "distance:3+0"]
)
def test_rays_parallel_to_the_box_faces_and_from_the_centre_stay_finite(scene_renderer, correction):
    scene, view = panel_scene(correction)
    outputs = read_rays(scene_renderer, scene, view)
    pixels = reflector_pixels(outputs)
    assert pixels.mean() > 0.5  # the panel fills most of the view
    direction = outputs[OUTPUT_RAY_DIRECTION][pixels][:, :3]
    assert np.all(direction == (0.0, 0.0, 1.0))  # exactly: x and y are zero
    look = outputs[OUTPUT_COORDINATES][pixels]
    assert np.isfinite(look).all()
    assert np.allclose(np.linalg.norm(look[:, :3], axis=-1), 1.0, atol=1e-5)
    expected, background = reference(scene_renderer, scene, outputs, pixels)
    error = np.linalg.norm(look[:, :3] - expected, axis=-1)
    assert np.mean((error < 1e-4) & ((look[:, 3] < 0.5) == background)) >= 0.99
    colour = outputs[OUTPUT_COLOR][..., :3]
    assert np.isfinite(colour).all() and colour.min() >= 0.0 and colour.max() <= 1.0


def test_a_distance_search_that_meets_nothing_looks_up_the_background(scene_renderer):
    # The sphere in the sky alone: every reflected ray leaves the world. It must find no
    # surface and take the background map, never the capture (which holds the same sky).
    scene = replace(sphere_scene("distance"), objects=())
    outputs = read_rays(scene_renderer, scene)
    pixels = reflector_pixels(outputs)
    look = outputs[OUTPUT_COORDINATES][pixels]
    assert pixels.sum() > 500 and np.all(look[:, 3] == 0.0)
    assert np.allclose(look[:, :3], outputs[OUTPUT_RAY_DIRECTION][pixels][:, :3], atol=1e-6)


# ------------------------------------------------------------------- the room


def test_box_proxy_in_a_room_matches_the_ray_tracer(scene_renderer):
    # The walls are all there is, and the box proxy is the room: the lookup is exact up
    # to filtering. Measured at 128 x 128: 0.46 % of the sphere's pixels off by more than
    # 10/255 (box proxy and distance search alike; where two walls meet), the plain live
    # cube map 29.6 %, the sphere proxy 17.5 %.
    room = load_scene("sphere_room")
    assert isinstance(curved_reflector(room, "sphere").parallax, BoxProxy)
    truth = trace_scene(room, (ROOM_SIZE, ROOM_SIZE), supersample=4)
    expected, mask = truth.to_uint8(), erode(truth.reflective_mask, 1)
    assert mask.sum() > 5000
    box, _ = render(scene_renderer, room, ROOM_SIZE)
    mean, _ = assert_close_to_truth("room_box", box, expected, mask, 1.0, 0.01)
    searched, _ = render(scene_renderer, apply_options(room, {"parallax": "distance"}), ROOM_SIZE)
    assert_close_to_truth("room_distance", searched, expected, mask, 1.0, 0.01)
    plain, _ = render(scene_renderer, apply_options(room, {"parallax": "none"}), ROOM_SIZE)
    plain_mean, plain_share = region_error(plain, expected, mask)
    assert plain_share > 0.2 and plain_mean > 5 * mean, (plain_mean, plain_share)


def cluttered_room() -> Scene:
    """sphere_room with a crate and an orange ball standing near the sphere: their
    silhouettes against the walls behind them, and walls they hide from the centre."""
    from mirrorlab.data import data_path
    from mirrorlab.scene.model import MeshObject
    from tests.scenekit import block

    room = load_scene("sphere_room")
    ball = MeshObject(
        "ball",
        data_path("models") / "joint.obj",
        Transform(position=(-1.2, 1.5, -1.2), scale=(1.2, 1.2, 1.2)),
        color=(0.95, 0.5, 0.1),
    )
    return replace(
        room, objects=(*room.objects, block("crate", (1.9, 0.2, 0.2), 1.2, (0.9, 0.9, 0.9)), ball)
    )


def near_ball_sky() -> Scene:
    """chrome_sphere with a teal ball close beside the sphere (under the open sky)."""
    from mirrorlab.data import data_path
    from mirrorlab.scene.model import MeshObject

    sky = load_scene("chrome_sphere")
    ball = MeshObject(
        "near_ball",
        data_path("models") / "joint.obj",
        Transform(position=(1.25, 0.2, -0.3), scale=(0.9, 0.9, 0.9)),
        color=(0.2, 0.8, 0.9),
    )
    return replace(sky, objects=(*sky.objects, ball))


def test_the_distance_search_in_a_closed_room_matches_its_numpy_reference(scene_renderer):
    # The room closes the centre in: where the search accepts no crossing it falls back
    # to the plain lookup (not the background, which a closed room never shows).
    rng = np.random.default_rng(21)
    base = apply_options(cluttered_room(), {"parallax": "distance", "map_size": MAP})
    assert encloses(base, curved_reflector(base, "sphere").center(), "sphere")
    for _ in range(2):
        eye = np.array([rng.uniform(-1.5, 2.5), rng.uniform(0.0, 2.5), rng.uniform(1.5, 3.2)])
        scene = replace(
            base,
            camera=Camera(eye=tuple(eye), target=(0.5, 1.0, -0.8), fovy=40.0, near=0.1, far=40.0),
        )
        outputs = read_rays(scene_renderer, scene)
        pixels = reflector_pixels(outputs)
        assert pixels.sum() > 200
        look = outputs[OUTPUT_COORDINATES][pixels]
        expected, background = reference(scene_renderer, scene, outputs, pixels)
        error = np.linalg.norm(look[:, :3] - expected, axis=-1)
        same_map = (look[:, 3] < 0.5) == background
        assert not background.any()
        assert np.mean((error < 1e-4) & same_map) >= 0.99, (
            np.percentile(error, 99),
            same_map.mean(),
        )


def test_the_distance_search_leaves_no_cracks_in_a_closed_room(scene_renderer):
    """Where an object's silhouette meets the wall behind it, or the object hides that
    wall from the centre, the search used to find no surface and look up the room's
    black background (263 such pixels at 160 x 160, MAE 3.17); now each step that ends
    behind the stored surface is searched again in smaller steps, and a ray still
    without a surface takes the plain lookup: none black, MAE 2.96."""
    scene = apply_options(cluttered_room(), {"parallax": "distance"})
    truth = trace_scene(scene, (160, 160), supersample=4)
    expected, mask = truth.to_uint8(), erode(truth.reflective_mask, 1)
    image, _ = render(scene_renderer, scene, 160)
    cracks = mask & (image.max(axis=-1) < 25) & (expected.max(axis=-1) > 40)
    if cracks.any():
        save_failure(
            "distance_cracks",
            rendered=image,
            traced=expected,
            cracks=(cracks[..., None] * 255).repeat(3, axis=-1).astype(np.uint8),
        )
    assert not cracks.any(), int(cracks.sum())
    mean, _ = region_error(image, expected, mask)
    assert mean < 3.1, mean


def test_the_distance_search_keeps_a_near_ball_whole_under_the_sky(scene_renderer):
    """A ball close to the sphere: rays grazing its silhouette used to be taken for
    passing behind it and shown the sky around its reflection (MAE 6.32 at 160 x 160);
    the smaller steps find where they meet it: MAE 5.46. Rays that find nothing under an
    open sky still leave for the background (the plain lookup would show a ghost of
    whatever stands in their direction from the centre: MAE 12.3)."""
    scene = apply_options(near_ball_sky(), {"method": "cube-live", "parallax": "distance"})
    assert not encloses(scene, curved_reflector(scene, "sphere").center(), "sphere")
    truth = trace_scene(scene, (160, 160), supersample=4)
    expected, mask = truth.to_uint8(), erode(truth.reflective_mask, 1)
    image, _ = render(scene_renderer, scene, 160)
    mean, _ = region_error(image, expected, mask)
    assert mean < 5.9, mean


# ------------------------------------------------------------------- plan and renderer


def test_changing_a_proxys_size_reuses_the_capture_and_changes_the_picture(scene_renderer):
    room = load_scene("sphere_room")
    first, stats = render(scene_renderer, room, SIZE)
    assert "capture:sphere" in stats.ran
    smaller = room.with_reflector("sphere", parallax=BoxProxy((-2.0, -1.0, -2.0), (2.0, 3.0, 2.0)))
    second, stats = render(scene_renderer, smaller, SIZE)
    assert "capture:sphere" in stats.skipped and "capture:sphere" not in stats.ran
    assert np.abs(first.astype(int) - second.astype(int)).max() > 40
    # a distance search needs the depths too: captured again
    _, stats = render(scene_renderer, apply_options(room, {"parallax": "distance"}), SIZE)
    assert "capture:sphere" in stats.ran
    _, stats = render(scene_renderer, apply_options(room, {"parallax": "distance:16"}), SIZE)
    assert "capture:sphere" in stats.skipped


def test_a_distance_search_releases_its_depth_and_background_cubes(gl_context):
    from mirrorlab.renderer import SceneRenderer

    before = len(gl_context.resources)
    renderer = SceneRenderer(gl_context.resources)
    try:
        render(renderer, sphere_scene("distance", 32), 32)
        made = len(gl_context.resources) - before
    finally:
        renderer.release()
    assert len(gl_context.resources) == before
    plain = SceneRenderer(gl_context.resources)
    try:
        render(plain, sphere_scene("none", 32), 32)
        assert made == len(gl_context.resources) - before + 2  # depth cube + background
    finally:
        plain.release()
