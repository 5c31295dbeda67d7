"""Cost that follows sight, on llvmpipe: objects and mirrors out of view cost a frame no
draw and no recorded data; a pass is one multi-draw whose commands hold consecutive
parts of one mesh as instances; a still frame replays what it recorded (nothing uploaded
again), a moving one records anew; the draw path without multi-draw gives the same
frames (its goldens: tests/gl/test_shipped_goldens.py)."""

from __future__ import annotations

import itertools
import os
import subprocess
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import mirrorlab
from mirrorlab.bounds import scene_index
from mirrorlab.data import data_path
from mirrorlab.gl.resources import Buffer
from mirrorlab.options import apply_options
from mirrorlab.passes import scene_draw
from mirrorlab.passes.scene_draw import indirect_commands, texture_runs
from mirrorlab.plan import FramePlan
from mirrorlab.renderer import SceneRenderer
from mirrorlab.scene.model import MeshObject, Transform
from mirrorlab.techniques import technique, technique_names, techniques
from tests.gl.frames import draw
from tests.scenekit import mirror, scene_robot, vec3

SIZE = (96, 96)
BOX = data_path("models") / "hand.obj"


def lab_reflected():
    return apply_options(mirrorlab.load_scene("lab20"), {"method": "reflected"})


def behind_the_camera(scene, count: int, kind: str):
    """``scene`` with ``count`` boxes or mirrors 6 units behind its camera, facing it."""
    camera = scene.camera
    eye, target = np.asarray(camera.eye), np.asarray(camera.target)
    back = (eye - target) / np.linalg.norm(eye - target)
    points = [eye + 6.0 * back + (i % 10 - 4.5, i // 10 - 2.0, 0.0) for i in range(count)]
    if kind == "boxes":
        boxes = tuple(
            MeshObject(
                name=f"box{i}",
                mesh=BOX,
                color=(0.8, 0.3, 0.2),
                transform=Transform(position=vec3(p), scale=(0.3, 0.3, 0.3)),
            )
            for i, p in enumerate(points)
        )
        return replace(scene, objects=scene.objects + boxes)
    mirrors = tuple(mirror(f"m{i}", p, -back, 0.5, 0.5, "reflected") for i, p in enumerate(points))
    return replace(scene, reflectors=scene.reflectors + mirrors)


@pytest.mark.parametrize("kind", ["boxes", "mirrors"])
def test_things_behind_the_camera_cost_no_draw_and_leave_the_frame_as_it_was(scene_renderer, kind):
    base = lab_reflected()
    crowded = behind_the_camera(base, 60, kind)
    image, stats = draw(scene_renderer, base, SIZE)
    crowded_image, crowded_stats = draw(scene_renderer, crowded, SIZE)
    assert np.array_equal(image, crowded_image)
    assert crowded_stats.ran == stats.ran == ["capture:mirror", "camera"]
    assert crowded_stats.draw_calls == stats.draw_calls
    assert crowded_stats.parts_drawn == stats.parts_drawn
    # nothing of them is planned one by one: every extra mirror is hidden by the arrays
    assert len(crowded_stats.plan.top.shown) == len(stats.plan.top.shown)


def test_a_still_frame_replays_and_a_moving_one_records_anew(scene_renderer, monkeypatch):
    uploads = []
    original = Buffer.upload

    def counted_upload(self, target, data):
        uploads.append(len(data))
        return original(self, target, data)

    monkeypatch.setattr(Buffer, "upload", counted_upload)
    scene = lab_reflected()
    first, _ = draw(scene_renderer, scene, SIZE)
    assert uploads, "the first frame records its views"
    uploads.clear()
    again, stats = draw(scene_renderer, scene, SIZE)
    assert uploads == [] and stats.ran == ["camera"]  # replayed: nothing sent again
    assert np.array_equal(first, again)
    eye = scene.camera.eye
    moved = replace(scene, camera=replace(scene.camera, eye=(eye[0] + 0.01, *eye[1:])))
    _, stats = draw(scene_renderer, moved, SIZE)
    assert uploads and stats.ran == ["capture:mirror", "camera"]


def test_a_new_pose_keeps_the_layout_of_its_parts_and_draws_as_a_fresh_renderer(
    scene_renderer, registry, monkeypatch
):
    """A view's layout (its steps and indirect commands) is kept by the visible parts:
    a new pose of the same visible parts makes none, a different set of parts its own,
    and every frame is a fresh renderer's, pixel for pixel."""
    made = []
    original = scene_draw.indirect_commands

    def counted_indirect_commands(table, visible):
        made.append(len(visible))
        return original(table, visible)

    monkeypatch.setattr(scene_draw, "indirect_commands", counted_indirect_commands)
    scene = lab_reflected()
    base, shoulder, elbow = scene_robot(scene).angles
    frames = [
        (elbow, 45.0),
        (elbow + 3.0, 45.0),
        (elbow + 3.0, 12.0),
        (elbow + 3.5, 12.0),
        (elbow, 45.0),
        (elbow + 6.0, 20.0),
    ]
    made_per_frame, drawn = [], []
    for turn, fovy in frames:
        posed = replace(
            scene.with_angles((base, shoulder, turn)), camera=replace(scene.camera, fovy=fovy)
        )
        made.clear()
        image, stats = draw(scene_renderer, posed, SIZE)
        made_per_frame.append(len(made))
        drawn.append(stats.parts_drawn)
        fresh = SceneRenderer(registry)
        try:
            fresh_image, _ = draw(fresh, posed, SIZE)
        finally:
            fresh.release()
        assert np.array_equal(image, fresh_image), (turn, fovy)
    assert drawn[2] < drawn[0]  # the narrow view culls parts: a layout of its own
    # frames 1 and 3 are new poses of the parts the frame before saw: no layout is made
    assert made_per_frame[0] > 0 and made_per_frame[1] == 0 and made_per_frame[3] == 0
    assert made_per_frame[2] > 0 and made_per_frame[5] > 0


def planned_views(plan: FramePlan) -> list[str]:
    """The labels of the views a frame of ``plan`` draws objects in: its captures'
    cameras (a probe's too), the camera's view, and the worlds seen in stencil mirrors
    within any of them."""
    pending = [view for step in plan.ran if step.name != "camera" for view in step.views]
    pending.append(plan.top)
    labels = []
    while pending:
        view_plan = pending.pop()
        labels.append(view_plan.view.label)
        pending += [shown.nested for shown in view_plan.shown if shown.nested is not None]
    return labels


@pytest.mark.parametrize("method", technique_names("planar"))
def test_a_frames_views_are_recorded_before_its_first_draw(scene_renderer, monkeypatch, method):
    """Every view a frame draws objects in (a capture's camera, a probe's, the camera's
    view, the world in a stencil mirror: each its plan names) has its draw recorded
    before the first multi-draw, and the drawing uploads nothing more."""
    events = []
    record = scene_draw.SceneDrawer._record
    draw_recorded = scene_draw.SceneDrawer._draw_recorded

    def noted_record(self, index, view, *rest):
        events.append(("record", view.label))
        return record(self, index, view, *rest)

    def noted_draw_recorded(self, scene, view, *a):
        events.append(("draw", view.label))
        return draw_recorded(self, scene, view, *a)

    monkeypatch.setattr(scene_draw.SceneDrawer, "_record", noted_record)
    monkeypatch.setattr(scene_draw.SceneDrawer, "_draw_recorded", noted_draw_recorded)
    upload = Buffer.upload

    def noted_upload(self, target, data):
        events.append(("upload", ""))
        return upload(self, target, data)

    monkeypatch.setattr(Buffer, "upload", noted_upload)
    scene = apply_options(mirrorlab.load_scene("lab20"), {"method": method})
    base, shoulder, elbow = scene_robot(scene).angles
    _, stats = draw(scene_renderer, scene.with_angles((base, shoulder, elbow + 7.0)), SIZE)
    drawn = [label for kind, label in events if kind == "draw"]
    assert sorted(drawn) == sorted(planned_views(stats.plan)), events
    # the world in the mirror is drawn in a view of its own (where it is not the screen's)
    assert len(drawn) > 1 or technique(method).texture == "screen", events
    first_draw = events.index(("draw", drawn[0]))
    prepared = {label for kind, label in events[:first_draw] if kind == "record"}
    assert prepared == set(drawn), events
    assert ("upload", "") not in events[first_draw:], events  # drawing finds them recorded


@pytest.mark.parametrize(
    "scene_name, method",
    [*(("lab20", name) for name in technique_names("planar")), ("mirror_and_sphere", None)],
)
def test_a_view_draws_its_reflectors_before_the_objects_and_stencil_mirrors_after(
    scene_renderer, monkeypatch, scene_name, method
):
    """In the camera's view, a reflector drawn on its own (a textured mirror, a mapped
    sphere) comes before the objects, so what it hides fails the depth test unshaded; a
    stencil mirror comes after them, as it marks only the pixels they leave showing: each
    technique where its registry entry says (``draws_after_objects``). The renderer's
    draws are noted, by every registered technique's pass: not those a pass makes within
    its own (``ssr`` draws its probe's after the objects, as its own draw)."""
    events = []
    inside: list[object] = []  # the pass draws being made
    owners: set[Any] = {entry.load() for entry in techniques() if entry.pass_class}
    for owner in owners:

        def noted_pass_draw(self, step, view, *rest, _o=owner.draw):
            if not inside:
                events.append((step.reflector.technique, view.label))
            inside.append(step)
            try:
                return _o(self, step, view, *rest)
            finally:
                inside.pop()

        monkeypatch.setattr(owner, "draw", noted_pass_draw)
    objects = scene_draw.SceneDrawer.draw

    def noted_objects(self, scene, view, *a, **k):
        events.append(("objects", view.label))
        return objects(self, scene, view, *a, **k)

    monkeypatch.setattr(scene_draw.SceneDrawer, "draw", noted_objects)
    scene = mirrorlab.load_scene(scene_name)
    if method is not None:
        scene = apply_options(scene, {"method": method})
    draw(scene_renderer, scene, SIZE)
    camera = [what for what, label in events if label == "camera"]
    assert camera.count("objects") == 1, events
    before, after = camera[: camera.index("objects")], camera[camera.index("objects") + 1 :]
    assert before or after, events  # the view shows a reflector
    assert not any(technique(name).draws_after_objects for name in before), events
    assert all(technique(name).draws_after_objects for name in after), events
    if method is not None:
        assert bool(after) == technique(method).draws_after_objects, events


def test_a_thousand_boxes_of_one_mesh_are_one_command(scene_renderer, registry):
    scene = lab_reflected()
    camera = scene.camera
    eye, target = np.asarray(camera.eye), np.asarray(camera.target)
    forward = (target - eye) / np.linalg.norm(target - eye)
    side = np.cross(forward, (0.0, 1.0, 0.0))
    side /= np.linalg.norm(side)
    up = np.cross(side, forward)
    spots = [
        target + 3.0 * forward + ((i % 40) / 4 - 5.0) * side + ((i // 40) / 4 - 3) * up
        for i in range(1000)
    ]
    boxes = tuple(
        MeshObject(
            name=f"box{i}",
            mesh=BOX,
            color=(0.8, 0.3, 0.2),
            transform=Transform(position=vec3(p), scale=(0.1, 0.1, 0.1)),
        )
        for i, p in enumerate(spots)
    )
    crowded = replace(scene, objects=scene.objects + boxes, reflectors=())
    image, stats = draw(scene_renderer, crowded, SIZE)
    # one pass, one multi-draw; the boxes half a pixel across between pixel centres culled
    assert stats.draw_calls == 1 and 100 < stats.parts_drawn < 1000
    per_draw = SceneRenderer(registry, draw_path="per-draw")
    try:
        each, each_stats = draw(per_draw, crowded, SIZE)
    finally:
        per_draw.release()
    assert np.array_equal(image, each)
    # the lab's seven parts (each of its own mesh) a draw each, the boxes one instanced
    # draw (no base instance: the parts' attributes point at the first box's data)
    assert each_stats.draw_calls == 8 and each_stats.parts_drawn == stats.parts_drawn


@settings(max_examples=200, deadline=None)
@given(ids=st.lists(st.integers(-1, 3), max_size=40))
def test_texture_runs_cover_every_part_in_order_with_one_texture_each(ids):
    ids = np.array(ids, dtype=np.int64)
    runs = texture_runs(ids)
    assert sum(count for _, _, count in runs) == len(ids)
    position = 0
    for texture, first, count in runs:
        assert first == position and count > 0
        worn = {int(i) for i in ids[first : first + count] if i >= 0}
        assert worn == ({texture} if texture >= 0 else set())
        position += count
    assert all(a[0] != b[0] for a, b in itertools.pairwise(runs))


def test_indirect_commands_draw_consecutive_parts_of_a_mesh_as_instances(scene_renderer):
    scene = lab_reflected()
    draw(scene_renderer, scene, SIZE)  # the drawer makes the scene's part table
    table = scene_renderer.drawer._table(scene_index(scene))
    visible = np.arange(len(table.textures))
    commands, runs = indirect_commands(table, visible)
    assert commands[:, 1].sum() == len(visible)  # every part an instance of one command
    assert list(commands[:, 4]) == list(np.cumsum(commands[:, 1]) - commands[:, 1])
    assert sum(count for _, _, count in runs) == len(commands)


@settings(max_examples=200, deadline=None)
@given(
    parts=st.lists(st.tuples(st.integers(-1, 2), st.integers(0, 3)), min_size=1, max_size=80),
    seed=st.integers(0, 99),
)
def test_few_and_many_parts_make_the_same_commands(parts, seed):
    """Commands made one part at a time (a few parts) and by arrays (many) agree."""
    from mirrorlab.passes import scene_draw
    from mirrorlab.passes.scene_draw import PartTable

    rng = np.random.default_rng(seed)
    count = len(parts)
    ranges = np.array([(10 * m, 3 + m, 100 * m) for _, m in parts], dtype=np.int64)
    table = PartTable(
        np.zeros((count, 2, 4, 4)),
        tuple(Path(f"t{t}") if t >= 0 else None for t, _ in parts),
        np.array([t for t, _ in parts], dtype=np.int64),
        (Path("t0"), Path("t1"), Path("t2")),
        ranges,
        np.array([m for _, m in parts], dtype=np.int64),
    )
    visible = np.sort(rng.choice(count, size=int(rng.integers(1, count + 1)), replace=False))
    few = scene_draw._few_indirect_commands(table, visible)
    original = scene_draw.FEW_PARTS
    scene_draw.FEW_PARTS = -1
    try:
        many = indirect_commands(table, visible)
    finally:
        scene_draw.FEW_PARTS = original
    assert np.array_equal(few[0], many[0]) and few[1] == many[1]


def test_a_still_frame_is_replayed_into_the_same_target_from_the_same_state(
    scene_renderer, registry, monkeypatch
):
    from mirrorlab.gl.opengl import GL
    from mirrorlab.gl.resources import Framebuffer
    from mirrorlab.passes.base import gl_state

    target = Framebuffer(registry, *SIZE)
    worked = []
    original = SceneRenderer._run

    def counted_run(self, *a, **k):
        worked.append(1)
        return original(self, *a, **k)

    monkeypatch.setattr(SceneRenderer, "_run", counted_run)
    scene = mirrorlab.load_scene("lab20")
    images = []
    for _ in range(5):
        scene_renderer.render(scene, target)
        images.append(target.read())
    # frame 1 captures; frame 2 draws the camera pass alone (a new plan: the textures
    # changed); frame 3 plans what frame 2 did and is recorded; 4 and 5 replay it
    assert len(worked) == 3 and all(np.array_equal(images[0], i) for i in images[1:])
    assert scene_renderer.last_frame.ran == ["camera"]
    # a caller's GL state that differs is no still frame: worked out, and left as it was
    GL.glEnable(GL.GL_BLEND)
    scene_renderer.render(scene, target)
    assert len(worked) == 4 and gl_state()["GL_BLEND"] is True
    assert np.array_equal(target.read(), images[0])
    GL.glDisable(GL.GL_BLEND)
    # what a caller may change in a pass is drawn again, not replayed
    scene_renderer.render(scene, target)
    scene_renderer.render(scene, target)
    count = len(worked)
    scene_renderer.pass_for("mirror")
    scene_renderer.render(scene, target)
    assert len(worked) == count + 1
    # another target of the same size is no replay either
    other = Framebuffer(registry, *SIZE)
    scene_renderer.render(scene, other)
    assert len(worked) == count + 2 and np.array_equal(other.read(), images[0])


def test_what_a_renderer_holds_in_gl_does_not_grow_with_the_views_it_has_drawn(
    scene_renderer, registry
):
    """A resized window or a moving camera makes a new view every frame: the buffers of
    views no longer drawn are freed or kept (a few pairs) for the next views recorded, so
    the live GL objects after forty such frames are those after the second of them (the
    first frame's buffers are the spares the later frames fill)."""
    from mirrorlab.gl.resources import Framebuffer
    from mirrorlab.passes.scene_draw import SPARE_BUFFERS

    scene = lab_reflected()
    counts = []
    for step in range(40):
        size = (64 + 7 * step, 48 + 5 * step) if step % 2 else SIZE
        moved = replace(
            scene,
            camera=replace(
                scene.camera, eye=(scene.camera.eye[0] + 0.01 * step, *scene.camera.eye[1:])
            ),
        )
        target = Framebuffer(registry, *size)
        scene_renderer.render(moved, target)
        target.release()
        counts.append(len(registry))
    assert counts[2:] == [counts[1]] * 38, counts
    assert 0 <= counts[1] - counts[0] <= 2 * SPARE_BUFFERS, counts


def test_a_reflected_capture_copies_its_glass_and_leaves_the_texture_as_a_whole_copy(monkeypatch):
    """A moving viewer's reflected capture clears and copies only the rectangle holding its
    glass and the last frame's (outside it, the texture holds background from before):
    frame and texture are those of a fresh renderer, which clears and copies the whole
    target, every frame, at every size."""
    from mirrorlab.gl.resources import Texture2D

    regions = []
    original = Texture2D.copy_from_framebuffer

    def spy(self, width, height, source, region=None):
        regions.append(region)
        return original(self, width, height, source, region)

    monkeypatch.setattr(Texture2D, "copy_from_framebuffer", spy)
    scene = lab_reflected()
    eye = np.asarray(scene.camera.eye, dtype=float)
    with mirrorlab.Renderer(SIZE) as moving:
        # the glass grows, moves across the frame and back (its rectangles at 96x96 go
        # from x 26-80 to x 42-81: the last one's left part must be background again),
        # then the frame changes size twice (a texture of a new size is copied whole)
        for step, (offset, size) in enumerate(
            [
                ((0, 0, 0), SIZE),
                ((0, 0, -4), SIZE),
                ((0, 3, -8), SIZE),
                ((0, -2, 3), SIZE),
                ((0, 0, 6), SIZE),
                ((0, 0, 0), SIZE),
                ((0, 0, -4), (80, 72)),
                ((0, 0, 0), SIZE),
            ]
        ):
            moved = replace(scene, camera=replace(scene.camera, eye=tuple(eye + offset)))
            frame = moving.render(moved, size=size)
            texture = moving.read_texture("mirror")
            with mirrorlab.Renderer(size) as fresh:
                assert np.array_equal(fresh.render(moved), frame), step
                assert np.array_equal(fresh.read_texture("mirror"), texture), step
    partial = [r for r in regions if r is not None]
    assert len(partial) >= 5, regions
    assert all(w * h < SIZE[0] * SIZE[1] for _, _, w, h in partial), partial


_DRAW_IN_A_CHILD = """
import hashlib, sys
import mirrorlab
path = sys.argv[1]
try:
    with mirrorlab.Renderer((48, 48), draw_path=path) as renderer:
        frame = renderer.render("lab20", method="reflected")
        print(renderer._renderer.drawer.draw_path, hashlib.sha256(frame.tobytes()).hexdigest())
except ValueError as exc:
    print("ValueError", exc)
"""


def draw_in_a_child(path: str, version: str | None) -> str:
    """What a fresh process prints drawing the lab scene by ``path`` in a context whose
    OpenGL Mesa reports as ``version`` (its own when None): the path taken and the
    frame's digest, or the ValueError."""
    env = {k: v for k, v in os.environ.items() if k != "MESA_GL_VERSION_OVERRIDE"}
    if version is not None:
        env["MESA_GL_VERSION_OVERRIDE"] = version
    result = subprocess.run(
        [sys.executable, "-c", _DRAW_IN_A_CHILD, path],
        capture_output=True,
        text=True,
        timeout=120,
        env=env,
    )
    assert result.returncode == 0, result.stderr
    return result.stdout.strip()


def test_a_context_under_opengl_4_3_draws_the_same_frame_a_part_at_a_time():
    """OpenGL 4.2 has base instances but not multi-draw indirect: ``auto`` takes the
    per-draw path there, and its frame is the packed path's; ``packed`` forced there
    says what it needs and what the context has."""
    packed = draw_in_a_child("auto", None)
    older = draw_in_a_child("auto", "4.2")
    assert packed.split()[0] == "packed" and older.split()[0] == "per-draw"
    assert packed.split()[1] == older.split()[1]
    assert draw_in_a_child("packed", "4.2") == (
        "ValueError draw_path 'packed' needs OpenGL 4.3; this context has 4.2"
    )
