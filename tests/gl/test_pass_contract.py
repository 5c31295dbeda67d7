"""The pass contract (:mod:`mirrorlab.techniques`, :class:`mirrorlab.passes.base.ReflectorPass`):

- the replay rule, for every registered technique the renderer draws: the arrays a
  recorded frame's calls hold do not change while later frames are drawn, replayed or
  not, and a replayed frame is the frame a renderer that never replays draws;
- a technique with a capture camera and a draw order of its own, registered in this file
  alone, gets the frames its entry defines: its camera from where the entry says, its
  draw before or after the objects as the entry says (pixels worked out here in numpy);
- a technique of the ``screen`` kind (the view's own frame), registered here alone: it
  must draw after the objects; no pass is planned for its texture; the copy is made at
  the draw, holds what the view drew, and is one of the recorded calls, so a replayed
  frame reads what that frame drew.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

import mirrorlab
from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import Framebuffer
from mirrorlab.options import apply_options
from mirrorlab.passes.base import set_view_uniforms
from mirrorlab.passes.planar import CapturingMirror, PlanarPass
from mirrorlab.passes.view_frame import ViewFrame
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
from mirrorlab.views import camera_view, projective_lookup
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


# --------------------------------------------- the view's own frame (the screen kind)

SHIFT = 6
"""Pixels to the left the test's screen technique reads the view's own frame from."""
SQUARE_CORNERS = ((-1, -1), (1, -1), (1, 1), (-1, 1))


class ShiftedFrame(PlanarPass):
    """The test's ``screen`` technique: the glass shows the view's own frame as it was
    when the glass was drawn (after the objects), read :data:`SHIFT` pixels to the left:
    a copy through :class:`mirrorlab.passes.view_frame.ViewFrame`, sampled on the quad
    through the view's own projective lookup, moved."""

    def __init__(self, shared, reflector, background=None) -> None:
        super().__init__(shared, reflector, background)
        self.frames = ViewFrame(shared.registry)

    def update(self, step, reflector, renderer, frame_target):
        raise AssertionError("a screen technique has no planned texture")

    def release(self) -> None:
        self.frames.release()
        super().release()

    def draw_own(self, draw, view, renderer, target, stencil_level):
        frame = self.frames.copy(view.size, None)
        program = self.mirror_program(view)
        program.use()
        set_view_uniforms(program, view)
        program.set_mat4("model", self.quad_model(view))
        program.set_vec3("backing_color", self.reflector.backing)
        program.set_int("projective", True)
        shift = np.eye(4)
        shift[0, 3] = -SHIFT / view.size[0]
        program.set_mat4("texture_matrix", shift @ projective_lookup(view, view))
        frame.bind(0, 1)
        self.quad.draw()
        return 1


def screen_technique(name: str) -> Technique:
    return Technique(
        name,
        "planar",
        "a test's: the view's own frame, shifted, on the glass",
        texture="screen",
        pass_class=f"{__name__}:ShiftedFrame",
        draws_after_objects=True,
    )


def test_a_screen_technique_must_draw_after_the_objects():
    entry = replace(screen_technique("early-screen"), draws_after_objects=False)
    with pytest.raises(ValueError, match="must draw after the view's objects"):
        register(entry)
    assert "early-screen" not in technique_names()


def test_the_views_own_frame_is_copied_at_the_draw_never_planned_and_replayed_fresh(registry):
    """The screen kind: the planner plans no pass for it (mode ``screen``, no capture, no
    slot held), the copy holds the view as the objects left it (the glass shows what lay
    under it, shifted), a moved object is in the next copy, and a replayed frame, whose
    recorded calls hold the copy, is the frame a renderer that never replays draws."""
    name = "shifted-frame"
    register(screen_technique(name))
    renderer = SceneRenderer(registry)
    reference = SceneRenderer(registry)
    target = Framebuffer(registry, *SIZE)
    try:
        scene = fixed_point_scene(name)
        stats = renderer.render(scene, target)
        (glass,) = stats.plan.top.draws
        assert glass.mode == "screen" and glass.own and glass.fallback is None
        assert [p.name for p in stats.plan.passes] == ["camera"]
        assert renderer.state.held == {}
        image = target.read()
        bare, _ = draw(reference, replace(scene, reflectors=()), SIZE)
        window = window_points(scene, GLASS)
        cx, cy, cz = BLOCKER_CENTER
        half = BLOCKER_SIDE / 2
        blocker = window_points(
            scene, [(cx + dx * half, cy + dy * half, cz) for dx, dy in SQUARE_CORNERS]
        )
        # the glass, where the blocker (in front of it) leaves it showing
        sure = inside(window, SIZE, 1.5) & ~inside(blocker, SIZE, -1.5)
        shifted = np.roll(bare, SHIFT, axis=1)  # what lies SHIFT pixels to the left
        sure[:, :SHIFT] = False
        assert sure.sum() > 200
        differing = (image != shifted).any(axis=-1) & sure
        assert not differing.any(), f"{int(differing.sum())} glass pixels differ"
        outside = ~inside(window, SIZE, -1.5)
        assert np.array_equal(image[outside], bare[outside])
        # the blocker moves every frame: the plan stays, the frame is replayed, and the
        # copy in the replayed calls reads what this frame drew
        replayed = 0
        for step in range(6):
            x = BLOCKER_CENTER[0] - 0.3 * step
            moved = scene.with_object(
                "blocker",
                transform=Transform(
                    position=(x, BLOCKER_CENTER[1], BLOCKER_CENTER[2]), scale=(BLOCKER_SIDE,) * 3
                ),
            )
            kept = renderer.recorded_frame
            renderer.render(moved, target)
            replayed += kept is not None and renderer.recorded_frame is kept
            expected, _ = draw(reference, moved, SIZE)
            assert np.array_equal(target.read(), expected), f"frame {step}"
        assert replayed >= 3
        recorded = renderer.recorded_frame
        assert recorded is not None
        names = [getattr(call[0], "__name__", "") for call in recorded.calls]
        assert names.count("glCopyTexSubImage2D") == 2  # the colour and the depth
    finally:
        unregister(name)
        renderer.release()
        reference.release()
        target.release()
