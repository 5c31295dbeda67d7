"""Every shipped scene's frames are what they were, pixel for pixel: each sequence of
:mod:`tests.gl.golden_frames` (every scene file as a still, turning and moving sequence,
every frame of the animated one, and every technique on the scenes made for them) is
drawn by a fresh renderer and compared with its golden PNG exactly (tolerance 0), and
drawn again into one target, so that its frames are replayed, to the same PNG. On a
failure the actual, expected and difference (x4) images are written to tests/_failures/
and the message names the frames and the pixels that differ."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image

from mirrorlab.gl.resources import Framebuffer
from mirrorlab.renderer import SceneRenderer
from mirrorlab.testing import difference_image
from tests.gl.golden_frames import SIZE, draw_sequence, sequences
from tests.imagecheck import save_failure

SEQUENCES = list(sequences())


@pytest.mark.parametrize("sequence", SEQUENCES, ids=[s.name for s in SEQUENCES])
def test_shipped_scene_frames_equal_their_golden_frames(scene_renderer, sequence):
    """The context's own draw path (on llvmpipe's OpenGL 4.5: one multi-draw a pass)."""
    assert_golden(draw_sequence(scene_renderer, sequence), sequence)


@pytest.mark.parametrize("sequence", SEQUENCES, ids=[s.name for s in SEQUENCES])
def test_the_per_draw_path_draws_the_same_frames(registry, sequence):
    """The draw path a context without multi-draw gets (macOS's OpenGL 4.1), forced: an
    instanced draw call for each run of parts of one mesh, the same frames."""
    renderer = SceneRenderer(registry, draw_path="per-draw")
    try:
        assert renderer.drawer.draw_path == "per-draw"
        assert_golden(draw_sequence(renderer, sequence), sequence, "per_draw_")
    finally:
        renderer.release()


@pytest.mark.parametrize("sequence", SEQUENCES, ids=[s.name for s in SEQUENCES])
def test_frames_drawn_again_into_one_target_are_replayed_as_the_golden_frames(
    scene_renderer, registry, sequence
):
    """Into one target, as a program drawing a scene would: each frame of a still
    sequence drawn four times over (the fourth time the third's calls are made again),
    and an animated scene's frames one after another (from the fourth frame planned as
    the one before, its calls made again with the robot's new pose sent first). The
    frames are the golden frames, and frames were replayed."""
    replays = []
    replay = scene_renderer._replay

    def counted_replay(*args):
        replays.append(replay(*args))
        return replays[-1]

    scene_renderer._replay = counted_replay
    target = Framebuffer(registry, *SIZE)
    try:
        animated = sequence.frames[0][0].animation is not None
        frames = []
        for scene, frame in sequence.frames:
            for _ in range(1 if animated else 4):
                scene_renderer.render(scene.at_frame(frame), target)
            frames.append(target.read())
        assert_golden(np.concatenate(frames, axis=1), sequence, "replayed_")
        assert any(replays)
    finally:
        target.release()


def test_the_draw_path_follows_the_contexts_multi_draw(scene_renderer):
    """llvmpipe's OpenGL 4.5 has multi-draw (4.3): the packed path is chosen; a 4.1 context
    (the simulated macOS run) gets the per-draw path."""
    from mirrorlab.gl.context import has_multi_draw

    expected = "packed" if has_multi_draw() else "per-draw"
    assert scene_renderer.drawer.draw_path == expected


def assert_golden(actual: np.ndarray, sequence, prefix: str = "") -> None:
    expected = np.asarray(Image.open(sequence.path).convert("RGB"))
    assert actual.shape == expected.shape, (actual.shape, expected.shape)
    if np.array_equal(actual, expected):
        return
    width = SIZE[0]
    differing = (actual != expected).any(axis=-1)
    per_frame = [
        int(differing[:, i * width : (i + 1) * width].sum()) for i in range(len(sequence.frames))
    ]
    folder = save_failure(
        f"golden_{prefix}{sequence.name}",
        actual=actual,
        expected=expected,
        diff=difference_image(actual, expected),
    )
    raise AssertionError(
        f"{sequence.name}: pixels differing in each frame {per_frame} "
        f"(of {SIZE[0] * SIZE[1]}); images in {folder}"
    )
