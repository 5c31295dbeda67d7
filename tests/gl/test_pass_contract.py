"""The pass contract (:mod:`mirrorlab.techniques`, :class:`mirrorlab.passes.base.ReflectorPass`):

- the replay rule, for every registered technique the renderer draws: the arrays a
  recorded frame's calls hold do not change while later frames are drawn, replayed or
  not, and a replayed frame is the frame a renderer that never replays draws;
- a technique with a capture camera and a draw order of its own, registered in this file
  alone, gets the frames its entry defines: its camera from where the entry says, its
  draw before or after the objects as the entry says (pixels worked out here in numpy).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import mirrorlab
from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import Framebuffer
from mirrorlab.options import apply_options
from mirrorlab.passes.planar import CapturingMirror
from mirrorlab.plan import CaptureCameras
from mirrorlab.renderer import SceneRenderer
from mirrorlab.scene.model import (
    Background,
    Camera,
    CurvedReflector,
    MeshObject,
    PlanarReflector,
    Scene,
    Transform,
)
from mirrorlab.techniques import Technique, register, technique_names, techniques, unregister
from mirrorlab.views import camera_view
from tests.gl.frames import draw
from tests.scenekit import PANEL_MESH

SIZE = (64, 64)
DRAWN = tuple(t.name for t in techniques() if t.kind != "frame")
"""Every registered technique the renderer draws (a frame technique draws no GL)."""


def scene_for(name: str) -> Scene:
    """Two reflectors drawn by ``name`` (so, in every frame, what its pass hands GL changes
    between the two: two mirrors seeing each other, or two small-mapped spheres), with
    objects around them."""
    if name in technique_names("planar"):
        scene = apply_options(mirrorlab.load_scene("two_mirrors"), {"method": name})
        camera = replace(scene.camera, eye=(0.0, 6.0, 16.0), target=(0.0, 1.0, -2.0), fovy=60.0)
        return replace(scene, camera=camera)  # sees both mirrors
    scene = apply_options(mirrorlab.load_scene("chrome_sphere"), {"method": name})
    (sphere,) = scene.reflectors
    assert isinstance(sphere, CurvedReflector)
    sphere = replace(sphere, map_size=32)
    small = replace(
        sphere,
        name="small sphere",
        transform=replace(sphere.transform, position=(-1.2, 1.6, 1.5), scale=(0.4,) * 3),
    )
    return replace(scene, reflectors=(sphere, small))


@pytest.mark.parametrize("name", DRAWN)
def test_a_recorded_frames_arrays_stay_as_they_were_and_its_replays_are_fresh_frames(
    registry, name
):
    first = scene_for(name)
    assert [r.technique for r in first.reflectors] == [name, name]
    x, y, z = first.camera.eye
    moved = replace(first, camera=replace(first.camera, eye=(x - 0.2, y + 0.2, z - 0.4)))
    renderer = SceneRenderer(registry)
    reference = SceneRenderer(registry)  # draws into a new target every frame: never replays
    target = Framebuffer(registry, *SIZE)
    try:
        recorded = None
        for _ in range(4):  # planned anew, reused, then recorded
            stats = renderer.render(first, target)
            recorded = renderer.recorded_frame
            if recorded is not None:
                break
        assert recorded is not None, "a still scene's third or fourth frame is recorded"
        assert [d.own for d in stats.plan.top.draws] == [True, True]
        arrays = recorded.arrays()
        assert arrays, "the recorded calls hand GL arrays (the two reflectors' matrices)"
        held = [array.copy() for array in arrays]
        # replayed, drawn anew (the viewer moved), planned anew, recorded, replayed, ...
        frames = [first, first, *[moved] * 5, *[first] * 5]
        replayed = 0
        for index, scene in enumerate(frames):
            kept = renderer.recorded_frame
            renderer.render(scene, target)
            replayed += kept is not None and renderer.recorded_frame is kept
            image = target.read()
            expected, _ = draw(reference, scene, SIZE)
            assert np.array_equal(image, expected), f"frame {index} of {name}"
            changed = [
                i
                for i, (a, b) in enumerate(zip(arrays, held, strict=True))
                if not np.array_equal(a, b)
            ]
            assert not changed, f"frame {index}: the recorded arrays {changed} changed"
        assert replayed >= 3, f"{name}: {replayed} frames replayed"
    finally:
        renderer.release()
        reference.release()
        target.release()


# --------------------------------------------------------------- a technique of the test's

CAPTURE_EYE = (40.0, 0.0, 10.0)
CAPTURE_TARGET = (40.0, 0.0, 0.0)
CAPTURE_SIZE = (16, 16)
BACKGROUND = (0.0, 0.0, 0.4)
WALL = (0.0, 0.8, 0.0)
BLOCKER = (0.8, 0.0, 0.0)
GLASS = ((-2.0, -2.0, 0.0), (2.0, -2.0, 0.0), (2.0, 2.0, 0.0), (-2.0, 2.0, 0.0))
BLOCKER_CENTER, BLOCKER_SIDE = (1.5, 0.0, 3.0), 2.0


def fixed_point_camera(reflector, view, footprint, scissor, context):
    """The test technique's capture camera: a perspective camera at a fixed point, looking
    at a fixed target, whatever the viewer does (its texture depends on nothing else)."""
    camera = Camera(eye=CAPTURE_EYE, target=CAPTURE_TARGET, fovy=45.0, near=0.5, far=50.0)
    capture = camera_view(camera, CAPTURE_SIZE, f"{reflector.name}'s fixed point")
    return CaptureCameras((capture,), (None,), ("fixed point", CAPTURE_SIZE))


class PictureOnTop(CapturingMirror):
    """The test technique's pass: the capture on the quad's own texture coordinates,
    drawn with no depth test (as a picture glued on the glass), so where it lands among
    the objects is its draw order's doing alone."""

    def draw_own(self, draw, view, renderer, target, stencil_level):
        GL.glDisable(GL.GL_DEPTH_TEST)
        try:
            return self.draw_textured(view, self.captures.texture(draw.slot), None)
        finally:
            GL.glEnable(GL.GL_DEPTH_TEST)


def fixed_point_technique(name: str, after: bool) -> Technique:
    return Technique(
        name,
        "planar",
        "a test's: the scene from a fixed point, glued on the glass",
        texture="fixed",
        pass_class=f"{__name__}:PictureOnTop",
        capture_camera=f"{__name__}:fixed_point_camera",
        draws_after_objects=after,
    )


def panel(name: str, center, side: float, color) -> MeshObject:
    """A square of ``side`` facing +z (unlit look: the scene has ambient 1, no lights)."""
    return MeshObject(
        name=name,
        mesh=PANEL_MESH,
        color=color,
        transform=Transform(position=center, scale=(side, side, side)),
    )


def fixed_point_scene(technique: str, eye=(0.0, 0.0, 10.0)) -> Scene:
    """A square mirror at z = 0 facing the viewer, a red square in front of its right part,
    and, far to the side where the viewer never looks, a green wall that fills the fixed
    point's view. Lit by ambient 1 alone: every surface shows its colour as it is."""
    return Scene(
        name="fixed point",
        camera=Camera(eye=eye, target=(0.0, 0.0, 0.0), fovy=45.0, near=0.5, far=60.0),
        background=Background(color=BACKGROUND),
        ambient=1.0,
        lights=(),
        objects=(
            panel("wall", (40.0, 0.0, 0.0), 30.0, WALL),
            panel("blocker", BLOCKER_CENTER, BLOCKER_SIDE, BLOCKER),
        ),
        reflectors=(PlanarReflector("glass", GLASS, technique=technique, texture_size=16),),
        max_bounces=1,
    )


def inside(points: np.ndarray, size: tuple[int, int], margin: float) -> np.ndarray:
    """``(h, w)`` bool, row 0 at the top: pixel centres at least ``margin`` pixels inside
    the convex polygon of window points ``points`` ``(k, 2)`` (counter-clockwise; a
    negative margin: within that distance outside it too)."""
    width, height = size
    x, y = np.meshgrid(np.arange(width) + 0.5, np.arange(height)[::-1] + 0.5)
    result = np.ones((height, width), dtype=bool)
    for a, b in zip(points, np.roll(points, -1, axis=0), strict=True):
        edge = b - a
        distance = (edge[0] * (y - a[1]) - edge[1] * (x - a[0])) / np.linalg.norm(edge)
        result &= distance >= margin
    return result


def window_points(scene: Scene, corners) -> np.ndarray:
    """``corners`` ``(k, 3)`` projected into ``scene``'s camera at :data:`SIZE`, in window
    pixels ``(k, 2)``."""
    view = camera_view(scene.camera, SIZE)
    homogeneous = np.hstack([np.asarray(corners, dtype=float), np.ones((len(corners), 1))])
    clip = homogeneous @ view.view_projection.T
    ndc = clip[:, :2] / clip[:, 3:4]
    return (ndc + 1.0) / 2.0 * np.asarray(SIZE, dtype=float)


def expected_frame(scene: Scene, after: bool) -> tuple[np.ndarray, np.ndarray]:
    """The frame worked out in numpy: background, the glass showing the green wall (all
    the fixed point sees), the red square in front of it; where the two overlap, the
    glass when it draws after the objects, the square when before. Also where the
    pixels are sure (a pixel off every edge by at least one pixel)."""

    def colour(rgb):
        return np.round(np.asarray(rgb) * 255).astype(np.uint8)

    cx, cy, cz = BLOCKER_CENTER
    half = BLOCKER_SIDE / 2
    square = [(cx - half, cy - half, cz), (cx + half, cy - half, cz)]
    square += [(cx + half, cy + half, cz), (cx - half, cy + half, cz)]
    glass_points, square_points = window_points(scene, GLASS), window_points(scene, square)
    glass, square_mask = inside(glass_points, SIZE, 0.0), inside(square_points, SIZE, 0.0)
    sure = (inside(glass_points, SIZE, 1.0) | ~inside(glass_points, SIZE, -1.0)) & (
        inside(square_points, SIZE, 1.0) | ~inside(square_points, SIZE, -1.0)
    )
    image = np.empty((*SIZE[::-1], 3), dtype=np.uint8)
    image[:] = colour(BACKGROUND)
    first, second = (
        ((square_mask, BLOCKER), (glass, WALL))
        if after
        else ((glass, WALL), (square_mask, BLOCKER))
    )
    image[first[0]] = colour(first[1])
    image[second[0]] = colour(second[1])
    return image, sure


@pytest.mark.parametrize("after", [False, True], ids=["before the objects", "after them"])
def test_a_technique_registered_here_gets_its_own_capture_camera_and_draw_order(
    scene_renderer, after
):
    name = f"fixed-point-{'after' if after else 'before'}"
    register(fixed_point_technique(name, after))
    try:
        scene = fixed_point_scene(name)
        image, stats = draw(scene_renderer, scene, SIZE)
        (capture,) = [p for p in stats.plan.ran if p.name == "capture"]
        (camera,) = [plan.view for plan in capture.views]
        assert np.allclose(camera.eye, CAPTURE_EYE) and camera.size == CAPTURE_SIZE
        assert capture.key[2] == ("fixed point", CAPTURE_SIZE)
        (glass,) = stats.plan.top.draws
        assert glass.mode == "texture" and glass.own

        expected, sure = expected_frame(scene, after)
        assert sure.sum() > 0.8 * sure.size
        differing = (image != expected).any(axis=-1) & sure
        assert not differing.any(), f"{int(differing.sum())} sure pixels differ"
        overlap = (expected == np.round(np.asarray(WALL if after else BLOCKER) * 255)).all(-1)
        assert (overlap & sure).sum() > 20  # the order shows: the overlap is large enough

        # the viewer moves: the fixed point's capture is kept, the frame follows the viewer
        moved = fixed_point_scene(name, eye=(-1.0, 0.5, 9.0))
        image, stats = draw(scene_renderer, moved, SIZE)
        assert [p.name for p in stats.plan.ran] == ["camera"]
        assert [p.reason for p in stats.plan.skipped] == [
            "nothing it shows changed since it was captured"
        ]
        expected, sure = expected_frame(moved, after)
        differing = (image != expected).any(axis=-1) & sure
        assert not differing.any(), f"{int(differing.sum())} sure pixels differ after a move"
    finally:
        unregister(name)


def test_a_technique_that_shows_the_scene_needs_a_capture_camera():
    entry = replace(fixed_point_technique("no-camera", False), capture_camera="")
    with pytest.raises(ValueError, match="needs a capture_camera"):
        register(entry)
    assert "no-camera" not in technique_names()
