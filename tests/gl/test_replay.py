"""A frame planned as the last one was (:class:`mirrorlab.plan.PlanMemo`), into the same
target from the same GL state, is drawn again from the last frame's GL calls: a still
scene's frames, and an animated robot's, whose new pose is sent to the views' buffers
first. On generated sequences of frames (new poses, still frames, a camera that moves,
other techniques, another size, an object added, the robot carried out of a view, a
pose or the camera coming back), every frame is the frame a renderer that never
replays draws, pixel for pixel, planned as the planner plans it, on both draw paths."""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

import mirrorlab
from mirrorlab.draw_path import DrawPath
from mirrorlab.gl.resources import Framebuffer
from mirrorlab.options import apply_options
from mirrorlab.plan import TextureState, plan_frame
from mirrorlab.renderer import SceneRenderer
from mirrorlab.scene.model import Transform
from mirrorlab.techniques import technique_names
from tests.gl.frames import draw
from tests.imagecheck import save_failure
from tests.scenekit import block

SIZES = ((64, 64), (72, 48))
AWAY = ((0.0, 40.0, 0.0), (0.0, 0.0, 4.0))  # the robot carried out of the view, or partly

# A step of a sequence: what changes for the next frame, with what it needs drawn.
STEP = st.one_of(
    *[st.tuples(st.just("pose"), st.tuples(*[st.floats(-120, 120)] * 3))] * 3,
    st.just(("still", None)),
    st.just(("camera", None)),
    st.tuples(st.just("method"), st.sampled_from(technique_names("planar"))),
    st.just(("size", None)),
    st.tuples(st.just("block"), st.tuples(*[st.floats(-3, 3)] * 3)),
    st.tuples(st.just("away"), st.sampled_from(AWAY)),
    st.just(("back", None)),
)


def lab(method: str):
    return apply_options(mirrorlab.load_scene("lab20"), {"method": method})


def step_scene(step: str, value: Any, scene, first):
    """The scene after ``scene`` for a generated ``step`` with its ``value`` (``first``:
    the sequence's first scene, which ``back`` returns to)."""
    if step == "pose":
        return scene.with_angles(value)
    if step == "camera":
        eye = scene.camera.eye
        return replace(scene, camera=replace(scene.camera, eye=(eye[0] + 0.4, *eye[1:])))
    if step == "method":
        return apply_options(scene, {"method": value})
    if step == "block":
        added = block(f"block{len(scene.objects)}", value, 1.0, (0.2, 0.8, 0.3))
        return replace(scene, objects=(*scene.objects, added))
    if step == "away":
        return scene.with_object(scene.robot.name, transform=Transform(position=value))
    if step == "back":
        return first
    return scene  # still, size


class Drawer:
    """Draws a sequence two ways: ``renderer`` into one target for each size (so frames
    replay), ``reference`` into a new target every frame (so none does)."""

    def __init__(self, registry, draw_path: DrawPath) -> None:
        self.renderer = SceneRenderer(registry, draw_path=draw_path)
        self.reference = SceneRenderer(registry, draw_path=draw_path)
        self.targets = {size: Framebuffer(registry, *size) for size in SIZES}
        self.replays = 0
        replay = self.renderer._replay

        def counted(*args):
            done = replay(*args)
            self.replays += done
            return done

        self.renderer._replay = counted  # type: ignore[method-assign]

    def frame(self, scene, size, label: str) -> None:
        expected_plan = self.renderer.plan(scene, size)  # by plan_frame, not the memo
        target = self.targets[size]
        stats = self.renderer.render(scene, target)
        image = target.read()
        expected, _ = draw(self.reference, scene, size)
        if not np.array_equal(image, expected):
            save_failure(f"replay_{label}", replayed=image, expected=expected)
            differing = int((image != expected).any(axis=-1).sum())
            raise AssertionError(
                f"{label}: {differing} pixels differ\n" + "\n".join(stats.plan.describe())
            )
        assert stats.plan.describe() == expected_plan.describe(), label
        assert [p.key for p in stats.plan.passes] == [p.key for p in expected_plan.passes]
        # a replay may draw parts that left a view (clipped away)
        reference = self.reference.last_frame
        assert reference is not None
        assert stats.parts_drawn >= reference.parts_drawn, label
        if stats.parts_drawn == reference.parts_drawn:
            assert stats.draw_calls == reference.draw_calls, label

    def release(self) -> None:
        self.renderer.release()
        self.reference.release()
        for target in self.targets.values():
            target.release()


@settings(
    max_examples=25,
    deadline=None,
    derandomize=True,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(
    method=st.sampled_from(technique_names("planar")),
    draw_path=st.sampled_from(["packed", "packed", "per-draw"]),
    steps=st.lists(STEP, min_size=4, max_size=10),
)
# A frame recorded where a program's view uniforms held the camera's from the frame
# before (a stencil mirror's world drew nothing there) left their setting out; its
# replay started from the mirrored view's that it set last.
@example(
    method="ortho",
    draw_path="packed",
    steps=[
        ("pose", (0.0, 0.0, 0.0)),
        ("away", AWAY[0]),
        ("method", "stencil"),
        ("block", (0.0, 0.0, 0.0)),
        ("away", AWAY[0]),
    ],
)
# A technique whose probe captures as the one before did (a fixed camera): its pass is
# made anew, so its texture is blank, whatever the one before left.
@example(method="ortho", draw_path="packed", steps=[("still", None)] * 3 + [("method", "ssr")])
def test_replayed_frames_are_the_frames_of_a_renderer_that_never_replays(
    registry, method, draw_path, steps
):
    first = lab(method)
    drawer = Drawer(registry, draw_path)
    try:
        scene, size = first, SIZES[0]
        drawer.frame(scene, size, "first")
        for index, (step, value) in enumerate(steps):
            scene = step_scene(step, value, scene, first)
            if step == "size":
                size = SIZES[1] if size == SIZES[0] else SIZES[0]
            drawer.frame(scene, size, f"{index}-{step}")
    finally:
        drawer.release()


def test_an_animated_robots_frames_replay_from_the_fourth_on(registry):
    """A new pose every frame: the first frame captures into a blank texture, the second
    plans anew (its texture holds a capture), the third plans as the second did (and is
    recorded), and every one after is the third's calls with its own pose sent first."""
    drawer = Drawer(registry, "packed")
    try:
        scene = lab("ortho")
        base, lower, upper = scene.robot.angles
        for turn in range(8):
            drawer.frame(
                scene.with_angles((base, lower, upper + 2.0 * turn)), SIZES[0], f"pose {turn}"
            )
        assert drawer.replays == 5
        # two poses in turn replay too
        for turn in range(4):
            drawer.frame(
                scene.with_angles((base, lower, upper + 2.0 * (turn % 2))),
                SIZES[0],
                f"in turn {turn}",
            )
        assert drawer.replays == 9
        # standing still: the camera pass alone, planned anew, then recorded, then replayed
        for _ in range(3):
            drawer.frame(scene.with_angles((base, lower, upper + 2.0)), SIZES[0], "still")
        assert drawer.replays == 10
    finally:
        drawer.release()


@pytest.mark.parametrize("change", ["left", "entered", "many", "per-draw"])
def test_a_pose_is_replayed_only_where_the_calls_draw_every_part_that_may_show(registry, change):
    """A new pose whose moved parts the views drew is replayed, even where a part left a
    view (drawn, clipped away: the same pixels); one in which a part that a view did not
    draw may now show (the robot coming back into the capture's box), or in which more
    than a few parts moved and a view sees other parts of them (what is unseen stays
    undrawn), is drawn anew. Either draw path reads the parts' matrices from a buffer
    the new pose is sent into, so the per-draw path replays a pose as the packed one
    does."""
    from mirrorlab.passes.scene_draw import FEW_PARTS

    drawer = Drawer(registry, "per-draw" if change == "per-draw" else "packed")
    try:
        scene = lab("ortho")
        if change == "entered":  # half out of the capture's box to begin with
            scene = scene.with_object("robot", transform=Transform(position=(0.0, 0.0, 4.0)))
        if change == "many":  # more boxes than a few, moving together
            boxes = tuple(
                block(f"box{i}", (-3.0 + 0.2 * i, 1.0, 0.0), 0.6, (0.9, 0.6, 0.2))
                for i in range(FEW_PARTS + 8)
            )
            scene = replace(scene, objects=(*scene.objects, *boxes))
        base, lower, upper = scene.robot.angles
        for turn in range(4):
            if change == "many":
                scene = replace(
                    scene,
                    objects=(
                        *scene.objects[:2],
                        *(
                            replace(
                                box,
                                transform=replace(
                                    box.transform,
                                    position=(box.transform.position[0], 1.0 + 0.01 * turn, 0.0),
                                ),
                            )
                            for box in scene.objects[2:]
                        ),
                    ),
                )
            else:
                scene = scene.with_angles((base, lower, upper + turn))
            drawer.frame(scene, SIZES[0], "pose")
        replays = drawer.replays
        assert replays == 1  # on the per-draw path too: the matrices are in a buffer
        if change == "left":  # half out of the capture's box now: still replayed
            scene = scene.with_object("robot", transform=Transform(position=(0.0, 0.0, 4.0)))
            drawer.frame(scene, SIZES[0], "half out of view")
            assert drawer.replays == replays + 1
            assert drawer.renderer.last_frame is not None
            assert drawer.reference.last_frame is not None
            assert drawer.renderer.last_frame.parts_drawn > (
                drawer.reference.last_frame.parts_drawn
            )
            replays += 1
        elif change == "entered":  # back in full view: drawn anew
            scene = scene.with_object("robot", transform=Transform())
            drawer.frame(scene, SIZES[0], "back in view")
            assert drawer.replays == replays
        elif change == "many":  # one box out of the camera's view: drawn anew
            scene = replace(
                scene,
                objects=(
                    *scene.objects[:2],
                    *(
                        replace(
                            box,
                            transform=replace(
                                box.transform,
                                position=(
                                    box.transform.position[0] - (60.0 if i == 0 else 0.0),
                                    1.0,
                                    0.0,
                                ),
                            ),
                        )
                        for i, box in enumerate(scene.objects[2:])
                    ),
                ),
            )
            drawer.frame(scene, SIZES[0], "a box out of view")
            assert drawer.replays == replays
        for _ in range(3):
            drawer.frame(scene, SIZES[0], "still")
        assert drawer.replays == replays + 1
    finally:
        drawer.release()


def _call(name: str, *args):
    def function(*_: object) -> None:
        return None

    function.__name__ = name
    return (function, args, {})


def _names(calls) -> list[str]:
    return [f"{function.__name__}{args}" for function, args, _ in calls]


def test_a_replay_leaves_out_the_settings_an_earlier_call_of_it_made_already():
    """Within a recorded frame, a call that sets a piece of state to the value an earlier
    one set is left out, and only then: what each binding depends on is followed (the
    active texture unit, a framebuffer target that is both draw and read, the generic
    binding a glBindBufferBase sets too), what nothing earlier set is kept, and a call
    whose effect is not followed forgets everything."""
    from mirrorlab.gl.calls import without_repeats
    from mirrorlab.gl.opengl import GL

    T2D, SSBO = GL.GL_TEXTURE_2D, GL.GL_SHADER_STORAGE_BUFFER
    calls = [
        _call("glEnable", GL.GL_DEPTH_TEST),
        _call("glEnable", GL.GL_DEPTH_TEST),
        _call("glDisable", GL.GL_DEPTH_TEST),
        _call("glViewport", 0, 0, 8, 8),
        _call("glViewport", 0, 0, 8, 8),
        _call("glViewport", 0, 0, 8, 9),
        _call("glBindTexture", T2D, 3),  # the unit is not known: kept
        _call("glBindTexture", T2D, 3),  # nor here
        _call("glActiveTexture", GL.GL_TEXTURE0),
        _call("glBindTexture", T2D, 3),
        _call("glBindTexture", T2D, 3),  # left out
        _call("glActiveTexture", GL.GL_TEXTURE1),
        _call("glBindTexture", T2D, 3),  # kept
        _call("glBindFramebuffer", GL.GL_FRAMEBUFFER, 5),
        _call("glBindFramebuffer", GL.GL_DRAW_FRAMEBUFFER, 5),  # left out
        _call("glBindFramebuffer", GL.GL_READ_FRAMEBUFFER, 6),
        _call("glBindFramebuffer", GL.GL_FRAMEBUFFER, 5),  # read was 6: kept
        _call("glBindBufferBase", SSBO, 0, 7),
        _call("glBindBuffer", SSBO, 7),  # left out
        _call("glBindBuffer", GL.GL_ELEMENT_ARRAY_BUFFER, 2),
        _call("glBindBuffer", GL.GL_ELEMENT_ARRAY_BUFFER, 2),  # the vertex array's: kept
        _call("glClear", GL.GL_COLOR_BUFFER_BIT),
        _call("glDepthMask", True),
        _call("glDepthMask", 1),  # the same value given another way: left out
        _call("glDeleteTextures", 1, [3]),  # not followed: everything is forgotten
        _call("glViewport", 0, 0, 8, 9),
        _call("glActiveTexture", GL.GL_TEXTURE1),
    ]
    expected = _names(calls)
    for index in (23, 18, 14, 10, 4, 1):  # the repeats
        del expected[index]
    assert _names(without_repeats(calls)) == expected


def test_an_error_in_a_replayed_frame_is_raised_naming_it_and_the_next_frame_plans_anew(registry):
    """The replayed calls skip PyOpenGL's check after each call: an error they make is
    raised by the frame's own check, naming the replayed frame, and the renderer forgets
    what it held (the next frame is drawn anew, and right)."""
    from mirrorlab.errors import GLPassError
    from mirrorlab.gl.calls import for_replay
    from mirrorlab.gl.opengl import GL

    drawer = Drawer(registry, "packed")
    try:
        scene = lab("ortho")
        base, lower, upper = scene.robot.angles
        for turn in range(4):
            drawer.frame(scene.with_angles((base, lower, upper + turn)), SIZES[0], "pose")
        assert drawer.replays == 1
        recorded = drawer.renderer._recorded
        assert recorded is not None
        recorded.calls.extend(for_replay([(GL.glEnable, (0x7FFF,), {})]))
        with pytest.raises(GLPassError, match="frame \\(replayed\\)"):
            drawer.renderer.render(
                scene.with_angles((base, lower, upper + 9.0)), drawer.targets[SIZES[0]]
            )
        assert GL.glGetError() == GL.GL_NO_ERROR
        assert drawer.renderer.state.held == {}
        drawer.frame(scene.with_angles((base, lower, upper + 10.0)), SIZES[0], "after")
        assert drawer.replays == 1
    finally:
        drawer.release()


def test_a_replay_takes_the_state_it_starts_from_as_known_but_the_framebuffers():
    """Where the GL state a frame started from is known (:func:`known_state` of the state
    the renderer read), a setting to that value is left out from the first; not for the
    framebuffer bindings, which reading the last frame back changed."""
    from mirrorlab.gl.calls import known_state, without_repeats
    from mirrorlab.gl.opengl import GL
    from mirrorlab.passes.base import gl_state

    found: dict[str, Any] = gl_state()
    calls = [
        _call("glEnable" if found["GL_DEPTH_TEST"] else "glDisable", GL.GL_DEPTH_TEST),
        _call("glViewport", *found["GL_VIEWPORT"]),
        _call("glColorMask", *found["GL_COLOR_WRITEMASK"]),
        _call(
            "glStencilFunc",
            found["GL_STENCIL_FUNC"],
            found["GL_STENCIL_REF"],
            found["GL_STENCIL_VALUE_MASK"],
        ),
        _call("glBindFramebuffer", GL.GL_FRAMEBUFFER, found["GL_DRAW_FRAMEBUFFER_BINDING"]),
        _call("glClearColor", *found["GL_COLOR_CLEAR_VALUE"]),
        _call("glViewport", 0, 0, 1, 1),
    ]
    assert _names(without_repeats(calls, known_state(found))) == _names(calls[4:])
    assert _names(without_repeats(calls)) == _names(calls)


def test_a_frame_read_back_top_row_first_by_gl_is_the_one_flipped_after(registry):
    """Where the context has ``GL_MESA_pack_invert`` (llvmpipe does), GL writes a frame's
    rows top row first straight into the array returned; without it they are read as GL
    keeps them and flipped. Both give the same array, and a texture read afterwards
    (glGetTexImage also follows the switch) still comes the right way up."""
    from mirrorlab.gl.resources import Texture2D

    assert "GL_MESA_pack_invert" in registry.extensions()
    renderer = SceneRenderer(registry)
    target = Framebuffer(registry, *SIZES[1])
    picture = np.arange(4 * 6 * 3, dtype=np.uint8).reshape(4, 6, 3)
    texture = Texture2D.from_image(registry, picture)
    try:
        renderer.render(lab("ortho"), target)
        top_first = target.read()
        assert target.top_first is True
        target.top_first = False
        flipped = target.read()
        assert np.array_equal(top_first, flipped) and top_first.flags.c_contiguous
        assert not np.array_equal(flipped, flipped[::-1])  # so the order shows
        target.top_first = True
        target.read()
        assert np.array_equal(texture.read(), picture)
    finally:
        renderer.release()
        target.release()
        texture.release()


@pytest.mark.parametrize("method", technique_names("planar"))
def test_a_still_scene_replays_whatever_its_mirror(registry, method):
    """A scene standing still replays from its fourth frame on (captured, reused, planned
    as the frame before and recorded; a mirror that captures nothing, as a stencil mirror,
    from its third), also where its views reach as far as the scene does."""
    drawer = Drawer(registry, "packed")
    try:
        scene = lab(method)
        captures = any(p.name == "capture" for p in plan_frame(scene, SIZES[0], TextureState()).ran)
        for _ in range(5):
            drawer.frame(scene, SIZES[0], "still")
        assert drawer.replays == (2 if captures else 3)
    finally:
        drawer.release()
