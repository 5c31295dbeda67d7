"""Frame planning on the shipped scene files: which captures a frame runs, which it
reuses, how each reflector is drawn, and why. Numpy only: the textures are simulated by
recording each capture that runs, as the renderer does."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from mirrorlab.plan import (
    TINY_PIXELS,
    FramePlan,
    TextureState,
    ViewPlan,
    hidden_reason,
    plan_frame,
    screen_area,
)
from mirrorlab.scene.loader import load_scene, shipped_scene_names
from mirrorlab.scene.model import (
    BoxProxy,
    Camera,
    DistanceSearch,
    Scene,
    SphereProxy,
    Transform,
)
from mirrorlab.views import View, camera_view
from tests.scenekit import curved_reflector, planar_reflector, scene_robot

SIZE = (64, 64)
LAB_CENTER = (-7.0, 1.0, -2.0)
FRONT = Camera(eye=(10.0, 4.0, 3.0), target=LAB_CENTER)
ELSEWHERE = Camera(eye=(9.0, 1.0, -1.0), target=LAB_CENTER)


def run(scene: Scene, state: TextureState, size=SIZE, **options) -> FramePlan:
    """Plan a frame and record what its captures leave in the textures (the renderer's
    part), so that the next frame sees them."""
    plan = plan_frame(scene, size, state, **options)
    for step in plan.ran:
        if step.reflector is not None:
            state.record(step)
    return plan


def captures(plan: FramePlan) -> list:
    return [p for p in plan.passes if p.name in ("capture", "bake")]


def ran_captures(plan: FramePlan) -> list[tuple[str, int]]:
    return [(p.reflector, p.bounce) for p in plan.ran if p.reflector is not None]


def draw_of(view_plan: ViewPlan, name: str):
    (draw,) = [d for d in view_plan.draws if d.reflector.name == name]
    return draw


def with_camera(scene: Scene, camera: Camera) -> Scene:
    return replace(scene, camera=camera)


# --------------------------------------------------------------------------- no capture


def test_a_scene_without_reflectors_is_one_camera_pass():
    scene = load_scene("no_mirror")
    state = TextureState()
    for _ in range(2):
        plan = run(scene, state)
        assert [(p.name, p.runs) for p in plan.passes] == [("camera", True)]
        assert plan.top.draws == ()
    assert state.held == {}


@pytest.mark.parametrize("technique", ["ortho", "reflected", "stencil"])
@pytest.mark.parametrize(
    "camera, mode, words",
    [
        # In front of the glass, looking along +z past its side.
        (Camera(eye=(0.0, 1.0, -2.0), target=(0.0, 1.0, 10.0)), "hidden", "out of view"),
        # Behind the glass (x < -7), looking at the robot: only the back shows.
        (Camera(eye=(-12.0, 2.0, -2.0), target=(0.0, 0.0, 0.0)), "back", "seen from behind"),
        # In the mirror's plane: edge-on.
        (Camera(eye=(-7.0, 2.0, 10.0), target=(-7.0, 1.0, -2.0)), "back", "edge-on"),
        # In front of the glass with the glass behind the viewer.
        (Camera(eye=(0.0, 1.0, 0.0), target=(10.0, 1.0, 0.0)), "hidden", "behind the viewer"),
    ],
)
def test_no_capture_for_a_mirror_out_of_view_facing_away_or_behind(technique, camera, mode, words):
    scene = with_camera(load_scene("lab20"), camera).with_reflector(
        "mirror", technique=technique, ortho=None
    )
    plan = run(scene, TextureState())
    assert captures(plan) == []
    assert [p.name for p in plan.passes] == ["camera"]
    draw = draw_of(plan.top, "mirror")
    assert draw.mode == mode and words in draw.reason
    assert hidden_reason(scene.reflector("mirror"), camera_view(camera, SIZE)) == draw.reason


def test_the_shipped_mirror_behind_the_camera_is_never_captured():
    scene = load_scene("mirror_behind_camera")
    state = TextureState()
    for _ in range(3):
        plan = run(scene, state)
        assert [p.name for p in plan.passes] == ["camera"]
        assert draw_of(plan.top, "mirror").mode == "hidden"
    assert state.held == {}


def test_a_curved_reflector_out_of_view_gets_no_capture():
    scene = load_scene("chrome_sphere").with_reflector("sphere", technique="cube-live")
    away = with_camera(scene, Camera(eye=(0.0, 0.0, 6.0), target=(0.0, 0.0, 20.0)))
    plan = run(away, TextureState())
    assert captures(plan) == []
    assert draw_of(plan.top, "sphere").mode == "hidden"
    assert "out of view" in draw_of(plan.top, "sphere").reason
    assert captures(run(scene, TextureState()))  # seen from the scene's camera: captured


# --------------------------------------------------------------------------- reuse


def test_ortho_capture_is_reused_until_a_joint_moves():
    scene = load_scene("lab20")
    state = TextureState()
    first = run(scene, state)
    assert ran_captures(first) == [("mirror", 1)]
    assert "blank" in captures(first)[0].reason
    again = run(scene, state)
    (skipped,) = captures(again)
    assert not skipped.runs and "nothing it shows changed" in skipped.reason
    assert draw_of(again.top, "mirror").mode == "texture"
    # The orthographic capture does not depend on the viewer.
    assert ran_captures(run(with_camera(scene, ELSEWHERE), state)) == []
    moved = run(scene.with_angles((0.0, 10.0, -20.0)), state)
    (capture,) = captures(moved)
    assert capture.runs and "scene changed" in capture.reason
    # The same size of texture but a frame of another size: the lab's capture follows it.
    resized = run(scene.with_angles((0.0, 10.0, -20.0)), state, size=(80, 64))
    assert ran_captures(resized) == [("mirror", 1)]
    assert "size changed" in captures(resized)[0].reason


def test_robot_wave_captures_in_the_first_frame_and_whenever_a_joint_moves():
    scene = load_scene("robot_wave")
    state = TextureState()
    ran = [bool(ran_captures(run(scene.at_frame(f), state))) for f in range(scene.frame_count)]
    # Frames 0 to 4 hold the pose; from frame 5 the joints move every frame.
    assert [f for f, r in enumerate(ran) if r] == [0, *range(5, scene.frame_count)]


def test_reflected_capture_runs_again_when_the_viewer_moves():
    scene = with_camera(load_scene("lab20"), FRONT).with_reflector(
        "mirror", technique="reflected", ortho=None
    )
    state = TextureState()
    assert ran_captures(run(scene, state)) == [("mirror", 1)]
    (same,) = captures(run(scene, state))
    assert not same.runs
    moved = run(with_camera(scene, ELSEWHERE), state)
    (capture,) = captures(moved)
    assert capture.runs and "viewer moved" in capture.reason
    changed = run(with_camera(scene, ELSEWHERE).with_angles((5.0, 5.0, 5.0)), state)
    assert captures(changed)[0].runs and "scene changed" in captures(changed)[0].reason


def test_live_cube_map_follows_the_objects_not_the_viewer():
    scene = load_scene("chrome_sphere").with_reflector("sphere", technique="cube-live")
    state = TextureState()
    first = run(scene, state)
    (capture,) = captures(first)
    assert capture.runs and capture.reflector == "sphere" and len(capture.views) == 6
    viewer_moved = with_camera(scene, replace(scene.camera, eye=(2.5, 1.0, 6.8)))
    (reused,) = captures(run(viewer_moved, state))
    assert not reused.runs and "nothing it shows changed" in reused.reason
    block = viewer_moved.object("red_block")
    moved = viewer_moved.with_object(
        "red_block", transform=replace(block.transform, position=(2.3, 0.1, 0.9))
    )
    (again,) = captures(run(moved, state))
    assert again.runs and "scene changed" in again.reason


def test_a_live_cube_map_is_not_captured_again_for_a_change_in_how_it_is_read():
    # A proxy's size and a search's steps change the lookup, not what the six faces show;
    # a distance search needs the depths as well, so switching to one captures again.
    room = load_scene("sphere_room")
    state = TextureState()
    assert ran_captures(run(room, state)) == [("sphere", 1)]
    smaller = room.with_reflector("sphere", parallax=BoxProxy((-2.0, -1.0, -2.0), (2.0, 3.0, 2.0)))
    (kept,) = captures(run(smaller, state))
    assert not kept.runs and "nothing it shows changed" in kept.reason
    searched = room.with_reflector("sphere", parallax=DistanceSearch())
    assert ran_captures(run(searched, state)) == [("sphere", 1)]
    finer = room.with_reflector("sphere", parallax=DistanceSearch(steps=16, secant=4))
    assert ran_captures(run(finer, state)) == []
    moved = finer.with_object(
        "floor", transform=replace(finer.object("floor").transform, position=(0.0, -1.9, 0.0))
    )
    assert ran_captures(run(moved, state)) == [("sphere", 1)]


def test_another_reflectors_proxy_is_part_of_what_a_capture_shows():
    # Two live spheres, two bounces: the ball's capture shows the sphere with its own map
    # and lookup, so a change of the sphere's box is a change the ball's capture shows;
    # the sphere's captures show the ball, in which the sphere is plain, and are kept.
    room = load_scene("sphere_room")
    ball = replace(
        curved_reflector(room, "sphere"),
        name="ball",
        parallax=None,
        transform=Transform(position=(-0.7, 0.3, 0.6), scale=(0.35, 0.35, 0.35)),
    )
    scene = replace(room, reflectors=(*room.reflectors, ball), max_bounces=2)
    state = TextureState()
    assert sorted(ran_captures(run(scene, state))) == [
        ("ball", 1),
        ("ball", 2),
        ("sphere", 1),
        ("sphere", 2),
    ]
    resized = scene.with_reflector("sphere", parallax=BoxProxy((-3.0, -2.0, -3.0), (3.0, 3.0, 3.0)))
    assert ran_captures(run(resized, state)) == [("ball", 2)]
    # another kind of correction draws the sphere with another shader: all of it again
    other = scene.with_reflector("sphere", parallax=SphereProxy(3.0))
    assert len(ran_captures(run(other, state))) == 4


def test_a_static_map_is_never_captured_and_a_sphere_map_is_baked_per_view_rotation():
    cube = load_scene("chrome_sphere").with_reflector("sphere", technique="cube")
    plan = run(cube, TextureState())
    assert captures(plan) == [] and draw_of(plan.top, "sphere").mode == "map"
    sphere = load_scene("chrome_sphere")
    state = TextureState()
    assert ran_captures(run(sphere, state)) == [("sphere", 0)]
    assert ran_captures(run(sphere, state)) == []
    turned = with_camera(sphere, replace(sphere.camera, eye=(4.0, 2.0, 6.0)))
    assert ran_captures(run(turned, state)) == [("sphere", 0)]


# --------------------------------------------------------------------------- tiny


def test_the_lossy_small_reflector_rule_is_off_unless_asked_for():
    far = Camera(eye=(300.0, 1.0, -2.0), target=LAB_CENTER, far=1000.0)
    scene = with_camera(load_scene("lab20"), far)
    assert TINY_PIXELS == 0  # by default the plan is lossless
    area = screen_area(scene.reflector("mirror"), camera_view(far, SIZE))
    assert 0.0 < area < 16
    default = run(scene, TextureState())
    assert ran_captures(default) == [("mirror", 1)]
    assert draw_of(default.top, "mirror").mode == "texture"
    lossy = run(scene, TextureState(), tiny_pixels=16)
    assert captures(lossy) == []
    draw = draw_of(lossy.top, "mirror")
    assert draw.mode == "plain"
    assert f"{area:.1f} pixels" in draw.reason and "under 16" in draw.reason
    assert "lossy" in draw.reason
    # Seen large enough, the rule changes nothing.
    assert (
        draw_of(run(load_scene("lab20"), TextureState(), tiny_pixels=16).top, "mirror").mode
        == "texture"
    )


# --------------------------------------------------------------------------- bounces


def test_two_facing_mirrors_two_bounces_deep():
    scene = load_scene("two_mirrors")
    assert scene.max_bounces == 2
    plan = run(scene, TextureState())
    ran = [p for p in plan.ran if p.reflector is not None]
    assert [(p.reflector, p.bounce) for p in ran] == [("east", 1), ("west", 2)]
    east, west = ran
    assert east.for_view == "west seen from camera" and west.for_view == "camera"
    assert draw_of(plan.top, "west").mode == "texture"
    assert draw_of(plan.top, "east").mode == "hidden"  # behind the viewer's right shoulder
    (west_view,) = west.views
    assert west_view.excluded == "west"
    assert draw_of(west_view, "east").mode == "texture"
    assert draw_of(west_view, "east").slot == east.slot
    (east_view,) = east.views
    assert draw_of(east_view, "west").mode in ("plain", "hidden", "back")


def test_no_bounces_means_no_captures_and_plain_reflectors():
    for name in ("lab20", "two_mirrors", "mirror_and_sphere"):
        scene = replace(load_scene(name), max_bounces=0)
        plan = run(scene, TextureState())
        assert [p.name for p in plan.passes] == ["camera"], name
        visible = [d for d in plan.top.draws if d.mode not in ("hidden", "back")]
        assert visible, name
        for draw in visible:
            assert draw.mode == "plain" and "no bounces left" in draw.reason


def test_mirror_and_sphere_see_each_other():
    scene = load_scene("mirror_and_sphere")
    state = TextureState()
    plan = run(scene, state)
    assert draw_of(plan.top, "mirror").mode == "texture"
    assert draw_of(plan.top, "sphere").mode == "texture"
    ran = [p for p in plan.ran if p.reflector is not None]
    top_mirror = [p for p in ran if p.reflector == "mirror" and p.for_view == "camera"]
    top_sphere = [p for p in ran if p.reflector == "sphere" and p.for_view == "camera"]
    assert [p.bounce for p in top_mirror] == [2] and [p.bounce for p in top_sphere] == [2]
    # In the mirror's capture the sphere shows with a capture of its own, one bounce less...
    (mirror_view,) = top_mirror[0].views
    inner = draw_of(mirror_view, "sphere")
    assert inner.mode == "texture"
    (inner_capture,) = [p for p in ran if p.reflector == "sphere" and p.bounce == 1]
    assert inner.slot == inner_capture.slot != draw_of(plan.top, "sphere").slot
    # ...in which the mirror, at bounce 0, is plain.
    assert {draw_of(v, "mirror").mode for v in inner_capture.views} <= {"plain", "hidden", "back"}
    # The sphere's six faces see the mirror where it faces them, with bounce-1 captures.
    face_draws = [draw_of(v, "mirror") for v in top_sphere[0].views]
    assert len(face_draws) == 6 and any(d.mode == "texture" for d in face_draws)
    for draw in face_draws:
        if draw.mode == "texture":
            (made,) = [
                p for p in ran if p.reflector == "mirror" and p.bounce == 1 and p.slot == draw.slot
            ]
            assert made.for_view.startswith("sphere cube")
    # Nothing moves: the next frame runs only the camera pass.
    assert [p.name for p in run(scene, state).ran] == ["camera"]


def test_each_capture_key_gets_its_own_slot_within_a_frame():
    plan = run(load_scene("two_mirrors"), TextureState(), use_plan=False)
    seen: dict[str, dict[int, tuple]] = {}
    for step in plan.ran:
        if step.reflector is not None:
            slots = seen.setdefault(step.reflector, {})
            assert step.slot not in slots or slots[step.slot] == step.key
            slots[step.slot] = step.key


# --------------------------------------------------------------------------- --no-plan


def test_without_the_plan_every_capture_runs_every_frame():
    # From the middle of the room both mirrors show; each mirror's capture sees the other
    # only through its full (unclipped) view, which the planner leaves out.
    scene = with_camera(
        load_scene("two_mirrors"), Camera(eye=(0.0, 3.0, 12.0), target=(0.0, 1.0, -2.0), fovy=70.0)
    )
    planned_state, state = TextureState(), TextureState()
    planned = run(scene, planned_state)
    assert sorted(ran_captures(planned)) == [("east", 2), ("west", 2)]
    assert ran_captures(run(scene, planned_state)) == []
    for _ in range(2):
        plan = run(scene, state, use_plan=False)
        assert plan.skipped == []
        assert sorted(ran_captures(plan)) == [("east", 1), ("east", 2), ("west", 1), ("west", 2)]
        assert all("every pass runs" in p.reason for p in plan.ran if p.reflector)
    # The lab's mirror behind the viewer, and one of a few pixels, are captured too.
    away = with_camera(load_scene("lab20"), Camera(eye=(0.0, 1.0, 0.0), target=(10.0, 1.0, 0.0)))
    assert ran_captures(run(away, TextureState())) == []
    assert ran_captures(run(away, TextureState(), use_plan=False)) == [("mirror", 1)]
    far = with_camera(
        load_scene("lab20"), Camera(eye=(300.0, 1.0, -2.0), target=LAB_CENTER, far=1000.0)
    )
    assert ran_captures(run(far, TextureState(), use_plan=False)) == [("mirror", 1)]


def test_without_the_plan_a_mirror_with_no_capture_camera_is_drawn_plain():
    # two_mirrors' east mirror is behind the viewer: no reflected camera can see through
    # it, so even --no-plan has nothing to capture for it.
    plan = run(load_scene("two_mirrors"), TextureState(), use_plan=False)
    assert ran_captures(plan) == [("east", 1), ("west", 2)]
    east = draw_of(plan.top, "east")
    assert east.mode == "plain" and "no capture camera" in east.reason


# --------------------------------------------------------------------------- invariants


def view_plans(plan: FramePlan):
    """Every view plan of a frame with the reflector it was made for (None: the camera)."""
    pending: list[tuple[ViewPlan, str | None]] = [(plan.top, None)]
    for step in plan.passes:
        pending += [(view, step.reflector) for view in step.views]
    while pending:
        view, owner = pending.pop()
        yield view, owner
        pending += [(d.nested, d.reflector.name) for d in view.draws if d.nested is not None]


SCENE_FILES = [name for name in shipped_scene_names() if name not in ("lab", "cone", "sphere")]


@pytest.mark.parametrize("name", SCENE_FILES)
@pytest.mark.parametrize("use_plan", [True, False])
def test_a_reflector_never_appears_in_its_own_capture(name, use_plan):
    scene = load_scene(name)
    variants = [scene]
    if any(r.kind == "planar" for r in scene.reflectors):
        variants.append(
            replace(
                scene,
                reflectors=tuple(
                    replace(r, technique="stencil", ortho=None) if r.kind == "planar" else r
                    for r in scene.reflectors
                ),
                max_bounces=3,
            )
        )
    for variant in variants:
        plan = run(variant, TextureState(), use_plan=use_plan)
        checked = 0
        for view, owner in view_plans(plan):
            if owner is None:
                assert view.excluded is None
                continue
            assert view.excluded == owner
            assert owner not in {d.reflector.name for d in view.draws}
            checked += 1
        has_capture = any(p.views for p in plan.passes) or any(d.nested for d in plan.top.draws)
        assert checked > 0 or not has_capture


def test_stencil_mirrors_nest_as_deep_as_the_bounces_go():
    scene = load_scene("two_mirrors")
    stencil = replace(
        scene, reflectors=tuple(replace(r, technique="stencil") for r in scene.reflectors)
    )
    plan = run(stencil, TextureState())
    assert captures(plan) == []
    draw = draw_of(plan.top, "west")
    depth = 0
    while draw is not None and draw.mode == "inline":
        depth += 1
        others = [d for d in draw.nested.draws if d.mode == "inline"]
        draw = others[0] if others else None
    assert depth == scene.max_bounces


def test_a_moved_curved_reflector_is_captured_again_from_its_new_centre():
    scene = load_scene("mirror_and_sphere")
    state = TextureState()
    run(scene, state)
    sphere = curved_reflector(scene, "sphere")
    moved = scene.with_reflector(
        "sphere", transform=Transform(position=(-2.0, 2.5, 0.0), scale=sphere.transform.scale)
    )
    plan = run(moved, state)
    assert ("sphere", 2) in ran_captures(plan)
    (capture,) = [p for p in plan.ran if p.reflector == "sphere" and p.bounce == 2]
    assert all(v.view.eye is not None for v in capture.views)
    assert all(v.view.eye is not None and abs(v.view.eye[1] - 2.5) < 1e-9 for v in capture.views)


def test_a_still_camera_has_one_read_only_view_and_a_moved_one_a_new_view():
    """A still camera's view, and what it works out, serve every frame; none of it can be
    changed by a caller, and a camera moved or a target resized makes another view."""
    scene = load_scene("lab20")
    view = camera_view(scene.camera, (64, 48))
    assert camera_view(scene.camera, [64, 48]) is view
    for array in (
        view.view,
        view.projection,
        view.view_projection,
        view.cull_planes,
        view.origin,
        view.relative_view,
        view.relative_view_projection,
        view.forward,
    ):
        with pytest.raises(ValueError, match="read-only"):
            array[0] += 1.0
    moved = replace(scene.camera, eye=(scene.camera.eye[0] + 1e-9, *scene.camera.eye[1:]))
    other = camera_view(moved, (64, 48))
    assert other is not view and other.draw_key != view.draw_key
    assert not np.array_equal(other.view, view.view)
    resized = camera_view(scene.camera, (64, 64))
    assert resized is not view and resized.draw_key != view.draw_key


@pytest.mark.parametrize("method", ["reflected", "stencil"])
def test_a_still_viewers_mirror_views_are_worked_out_once_and_a_moved_mirror_anew(method):
    """The world a still viewer sees in a still mirror is one read-only view across frames
    (a new pose of the robot does not change it); a mirror moved makes another, the one a
    first computation gives."""
    from mirrorlab import views
    from mirrorlab.options import apply_options

    lab = apply_options(load_scene("lab20"), {"method": method})

    def mirror_view(scene: Scene) -> View:
        plan = plan_frame(scene, SIZE, TextureState())
        (draw,) = plan.top.shown
        if method == "stencil":
            assert draw.nested is not None
            return draw.nested.view
        assert draw.source is not None
        return draw.source

    view = mirror_view(lab)
    base, shoulder, elbow = scene_robot(lab).angles
    assert mirror_view(lab.with_angles((base, shoulder + 20.0, elbow))) is view
    with pytest.raises(ValueError, match="read-only"):
        view.cull_test()[0, 0] = 1.0
    mirror = planar_reflector(lab, "mirror")
    moved = lab.with_reflector(
        "mirror",
        corners=tuple(  # a quarter unit off its plane
            tuple(corner) for corner in mirror.corner_array + 0.25 * mirror.normal
        ),
    )
    other = mirror_view(moved)
    assert other is not view and other.draw_key != view.draw_key
    views._reflected_capture_view.cache_clear()
    views._stencil_view.cache_clear()
    fresh = mirror_view(moved)
    assert fresh is not other
    for name in ("view", "projection", "view_projection", "cull_planes", "origin"):
        assert np.array_equal(getattr(fresh, name), getattr(other, name)), name


def test_views_too_magnified_to_round_still_have_keys_of_their_own():
    def magnified(scale: float) -> View:
        return View(
            view=np.eye(4),
            projection=np.diag([scale, scale, -1.0, 1.0]),
            size=(8, 8),
            eye=None,
            label="thin",
        )

    with np.errstate(all="raise"):
        keys = [magnified(scale).key for scale in (1e300, 2e300, 1e300)]
    assert keys[0] != keys[1] and keys[0] == keys[2]


# --------------------------------------------------------------------------- plan memo

MEMO_SCENES = ("lab20", "two_mirrors", "mirror_and_sphere", "chrome_sphere", "no_mirror")
MEMO_STEPS = (
    "pose",
    "pose",
    "pose",
    "still",
    "camera",
    "bounces",
    "method",
    "size",
    "no-plan",
    "cleared",
    "back",
)


def _memo_step(step: str, scene: Scene, first: Scene, data) -> Scene:
    from hypothesis import strategies as st

    from mirrorlab.options import apply_options

    if step == "pose" and scene.robot is not None:
        return scene.with_angles(tuple(data.draw(st.floats(-90, 90)) for _ in range(3)))
    if step == "pose" and scene.objects:
        item = scene.objects[0]
        position = tuple(data.draw(st.floats(-3, 3)) for _ in range(3))
        return scene.with_object(item.name, transform=replace(item.transform, position=position))
    if step == "camera":
        return replace(scene, camera=data.draw(st.sampled_from([FRONT, ELSEWHERE])))
    if step == "bounces":
        return replace(scene, max_bounces=data.draw(st.integers(0, 3)))
    if step == "method" and any(r.kind == "planar" for r in scene.reflectors):
        method = data.draw(st.sampled_from(["ortho", "reflected", "stencil"]))
        return apply_options(scene, {"method": method})
    if step == "back":
        return first
    return scene


def test_the_plan_memo_plans_what_the_planner_plans_on_generated_sequences():
    """:class:`PlanMemo` gives, frame after frame, the plan :func:`plan_frame` makes from
    the same textures (its passes, reasons, keys and draws), whether it planned or put
    the new content into the last plan."""
    from hypothesis import given, settings
    from hypothesis import strategies as st

    from mirrorlab.plan import PlanMemo

    @settings(max_examples=60, deadline=None, derandomize=True)
    @given(
        name=st.sampled_from(MEMO_SCENES),
        steps=st.lists(st.sampled_from(MEMO_STEPS), min_size=3, max_size=12),
        data=st.data(),
    )
    def check(name, steps, data):
        first = load_scene(name)
        memo, state = PlanMemo(), TextureState()
        scene, size, use_plan = first, SIZE, True
        for step in ("first", *steps):
            scene = _memo_step(step, scene, first, data)
            if step == "size":
                size = (48, 80) if size == SIZE else SIZE
            if step == "no-plan":
                use_plan = not use_plan
            if step == "cleared":
                state.clear()
            expected = plan_frame(scene, size, TextureState(dict(state.held)), use_plan)
            plan = memo.plan(scene, size, state, use_plan)
            assert plan.describe() == expected.describe(), step
            assert [p.key for p in plan.passes] == [p.key for p in expected.passes], step
            assert [p.slot for p in plan.passes] == [p.slot for p in expected.passes], step
            for done in plan.ran:
                if done.reflector is not None:
                    state.record(done)

    check()


def test_the_plan_memo_plans_an_animated_robots_frames_once():
    """The lab's robot in a new pose every frame: planned for the blank texture, then for
    a texture holding another pose's capture; every frame after puts its own content
    into that plan (a stencil mirror captures nothing: from the second frame). A mirror
    whose views reach as far as the scene does (``reflected``, ``stencil``) keeps its
    plan while the scene reaches as far; the robot carried far off makes it reach
    further, and the frame is planned anew."""
    from mirrorlab.options import apply_options
    from mirrorlab.plan import PlanMemo

    for method, reused in (
        ("ortho", [False, False, True, True, True, True]),
        ("reflected", [False, False, True, True, True, False]),
        ("stencil", [False, True, True, True, True, False]),
    ):
        scene = apply_options(load_scene("lab20"), {"method": method})
        memo, state = PlanMemo(), TextureState()
        base, lower, upper = scene_robot(scene).angles
        seen = []
        for turn in range(6):
            posed = scene.with_angles((base, lower, upper + turn))
            if turn == 5:
                posed = posed.with_object("robot", transform=Transform(position=(0, 0, 30)))
            expected = plan_frame(posed, SIZE, TextureState(dict(state.held)))
            plan = memo.plan(posed, SIZE, state)
            seen.append(memo.reused)
            assert plan.describe() == expected.describe(), (method, turn)
            for done in plan.ran:
                if done.reflector is not None:
                    state.record(done)
        assert seen == reused, method  # ortho looks at no object's place: reused


@pytest.mark.parametrize(
    "name",
    ["lab20", "two_mirrors", "mirror_and_sphere", "chrome_sphere", "sphere_room", "robot_wave"],
)
@pytest.mark.parametrize("method", [None, "reflected", "stencil"])
def test_the_plan_memo_plans_a_still_scene_once_whatever_its_reflectors(name, method):
    """A scene standing still (the same objects) is planned from the third frame on as the
    frame before was (the first captures, the second reuses the captures; without
    captures, from the second), whether or not its views reach as far as the scene
    does."""
    from mirrorlab.options import apply_options
    from mirrorlab.plan import PlanMemo

    scene = load_scene(name)
    if method is not None and any(r.kind == "planar" for r in scene.reflectors):
        scene = apply_options(scene, {"method": method})
    memo, state = PlanMemo(), TextureState()
    seen = []
    for _ in range(5):
        plan = memo.plan(scene, SIZE, state)
        seen.append(memo.reused)
        for done in plan.ran:
            if done.reflector is not None:
                state.record(done)
    assert not seen[0] and seen[2:] == [True, True, True]
