"""The public API and the command line, end to end on llvmpipe, and a golden frame; the
Renderer that keeps its context across frames and scenes; and the ``mirrorlab.testing``
pytest plugin (its ``renderer`` fixture and ``assert_image_close``)."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from PIL import Image

import mirrorlab
from mirrorlab.testing import assert_image_close
from tests.imagecheck import assert_images_close

GOLDEN = Path(__file__).parent / "golden"
GOLDEN_LAB = GOLDEN / "lab_default_128.png"


def test_render_api_returns_an_rgb_frame_of_the_asked_size():
    image = mirrorlab.render(size=(96, 64))
    assert image.shape == (64, 96, 3) and image.dtype == np.uint8
    assert image.std() > 10  # not a blank frame


def test_frames_show_as_pictures_in_a_notebook():
    """What the API returns is a Frame: IPython's display formatter (a notebook's) finds
    the frame's own pixels as a PNG in it, for a one-shot render, a kept renderer's frame,
    its capture texture and the ray tracer's truth."""
    import io

    from IPython.core.formatters import DisplayFormatter

    with mirrorlab.Renderer(size=(48, 40)) as renderer:
        images = [
            mirrorlab.render(size=(48, 40)),
            renderer.render("lab20"),
            renderer.read_texture("mirror"),
            mirrorlab.render(size=(24, 20), method="raytrace"),
        ]
    for image in images:
        assert isinstance(image, mirrorlab.Frame)
        data, _ = DisplayFormatter().format(image)
        shown = np.asarray(Image.open(io.BytesIO(data["image/png"])))
        assert np.array_equal(shown, image)


def test_render_api_refuses_bad_sizes_and_cameras():
    with pytest.raises(ValueError, match="size"):
        mirrorlab.render(size=(0, 10))
    with pytest.raises(ValueError, match="differ"):
        mirrorlab.render(camera=(1, 2, 3), target=(1, 2, 3))


def test_default_frame_matches_the_golden_image():
    """Regression guard against the reviewed frame tests/gl/golden/lab_default_128.png
    (re-made by tools/make_golden.py). Tolerance: 99.5% of pixels within 8/255 on every
    channel and mean difference under 0.5/255, room for another Mesa's rounding but
    not for a moved part or a flipped reflection."""
    expected = np.asarray(Image.open(GOLDEN_LAB).convert("RGB"))
    actual = mirrorlab.render(size=(128, 128))
    assert_images_close(
        "golden_lab_default_128",
        actual,
        expected,
        channel_tolerance=8,
        min_fraction_within=0.995,
        max_mean_abs=0.5,
    )


# --------------------------------------------------------------------------- Renderer

# Scenes in an order that makes one renderer switch techniques, reflectors and
# backgrounds, and come back to a scene it drew before.
SEQUENCE: list[tuple[str, int, dict[str, Any]]] = [
    ("lab20", 0, {}),
    ("chrome_sphere", 0, {}),
    ("lab20", 0, {"method": "stencil"}),
    ("two_mirrors", 0, {}),
    ("spheremap_cone", 0, {}),
    ("mirror_and_sphere", 0, {}),
    ("robot_wave", 6, {}),
    ("chrome_sphere", 0, {"method": "cube-live", "map_size": 64}),
    ("no_mirror", 0, {}),
    ("lab20", 0, {}),
]


def test_one_renderer_draws_many_scenes_as_one_shot_renders_do():
    """One Renderer keeps one context (and its GL side) across frames and scenes, and
    every frame is what a fresh one-shot ``mirrorlab.render`` of it gives."""
    size = (96, 80)
    with mirrorlab.Renderer(size=size) as renderer:
        gl_side = renderer.scene_renderer
        kept = []
        for name, frame, options in SEQUENCE:
            kept.append(renderer.render(name, frame=frame, **options))
            assert renderer.scene_renderer is gl_side, "the renderer changed its GL side"
    for (name, frame, options), image in zip(SEQUENCE, kept, strict=True):
        fresh = mirrorlab.render(name, size=size, frame=frame, **options)
        assert image.shape == (80, 96, 3)
        label = f"kept_renderer_{name}_{'_'.join(map(str, options.values())) or 'default'}"
        if not np.array_equal(image, fresh):
            assert_image_close(image, fresh, tolerance=0, name=label)


def test_renderer_frees_its_gl_objects_on_exit_and_opens_again():
    with mirrorlab.Renderer(size=(64, 64)) as renderer:
        renderer.render("mirror_and_sphere")
        registry = renderer.scene_renderer.registry
        assert len(registry) > 0
    assert len(registry) == 0, f"{len(registry)} GL objects left after close"
    renderer.close()  # closing twice is harmless
    image = renderer.render("lab20")  # and it opens again on use
    try:
        assert image.shape == (64, 64, 3)
        assert renderer.scene_renderer.registry is not registry
    finally:
        renderer.close()


def test_the_renderer_draws_the_same_frames_by_either_draw_path():
    """``draw_path="per-draw"`` (what a context without multi-draw gets, macOS's 4.1) and
    the packed path llvmpipe offers give the same frames; a wrong name is refused."""
    from mirrorlab.gl.context import has_multi_draw

    frames = {}
    for path in ("auto", "per-draw"):
        with mirrorlab.Renderer(size=(96, 80), draw_path=path) as renderer:
            frames[path] = [
                renderer.render(name, frame=frame, **options) for name, frame, options in SEQUENCE
            ]
            multi_draw = has_multi_draw()  # not on 4.1 (the simulated macOS run)
            assert renderer.scene_renderer.drawer.draw_path == (
                "packed" if path == "auto" and multi_draw else "per-draw"
            )
    for packed, each in zip(frames["auto"], frames["per-draw"], strict=True):
        assert_image_close(each, packed, tolerance=0, name="draw_path_per_draw")
    with pytest.raises(ValueError, match="draw_path: expected one of auto, packed, per-draw"):
        mirrorlab.Renderer(draw_path="instanced")  # type: ignore[arg-type]


# --------------------------------------------------------------------------- testing plugin


def test_two_renderers_in_turn_each_draw_in_their_own_context():
    """Each frame makes its renderer's context current (when another one is), so two
    renderers used in turn on one thread draw what each draws alone."""
    scenes: list[tuple[str, dict[str, Any]]] = [
        ("lab20", {}),
        ("mirror_and_sphere", {}),
        ("lab20", {"method": "stencil"}),
    ]
    sizes = ((48, 40), (40, 56))  # GL names alike in both contexts: the sizes tell them apart
    expected = {}
    for size in sizes:
        with mirrorlab.Renderer(size=size) as alone:
            expected[size] = [alone.render(name, **options) for name, options in scenes]
    with mirrorlab.Renderer(size=sizes[0]) as first, mirrorlab.Renderer(size=sizes[1]) as second:
        for _ in range(2):
            for number, (name, options) in enumerate(scenes):
                for renderer in (first, second):
                    assert_image_close(
                        renderer.render(name, **options),
                        expected[renderer.size][number],
                        tolerance=0,
                        name=f"two_renderers_{name}",
                    )
        first.close()  # its objects and context go; the other's stay
        assert_image_close(
            second.render("lab20"),
            expected[sizes[1]][0],
            tolerance=0,
            name="two_renderers_after_close",
        )


def test_the_renderer_reads_its_own_contexts_gl_state_once(monkeypatch):
    """A Renderer's context is its own: the GL state is read at the first frame only,
    and every frame leaves that state (a frame drawn anew puts back even a caller's
    change made in it before the frame); the frames are those of a fresh renderer."""
    import mirrorlab.renderer
    from mirrorlab.gl.opengl import GL
    from mirrorlab.passes.base import gl_state

    lab = mirrorlab.load_scene("lab20")
    poses = [lab, lab.with_angles((10.0, 20.0, 30.0)), lab, lab, lab]
    with mirrorlab.Renderer(size=(64, 48)) as fresh:
        expected = [fresh.render(posed) for posed in poses]
    reads = []

    def counted_gl_state():
        reads.append(1)
        return gl_state()

    monkeypatch.setattr(mirrorlab.renderer, "gl_state", counted_gl_state)
    with mirrorlab.Renderer(size=(64, 48)) as renderer:
        home = None
        for number, posed in enumerate(poses):
            if number == 3:
                GL.glEnable(GL.GL_BLEND)  # the caller's, in the renderer's context
                GL.glViewport(0, 0, 3, 3)
            image = renderer.render(posed)
            home = home or gl_state()
            assert gl_state() == home, f"frame {number} left another state"
            assert_image_close(image, expected[number], tolerance=0, name=f"own_context_{number}")
        assert renderer.last_stats is not None
        assert renderer.last_stats.ran == ["camera"]  # still frames at the end
    assert len(reads) == 1


def test_the_plugin_renderer_fixture_draws_the_golden_frame(renderer):
    """A user's test as the mirrorlab.testing docstring shows it: the session's
    ``renderer`` fixture, compared with a PNG file by ``assert_image_close``."""
    assert isinstance(renderer, mirrorlab.Renderer)
    image = renderer.render("lab20", size=(128, 128))
    assert_image_close(image, GOLDEN_LAB, tolerance=8, fraction=0.995, max_mean=0.5)
    assert renderer.last_stats is not None and renderer.last_stats.ran[-1] == "camera"


def test_assert_image_close_writes_actual_expected_and_diff_on_failure(tmp_path, monkeypatch):
    folder = tmp_path / "failures"
    monkeypatch.setenv("MIRRORLAB_FAILURES", str(folder))
    expected = np.zeros((8, 10, 3), np.uint8)
    actual = expected.copy()
    actual[2:4, 3:6] = (200, 10, 30)
    assert_image_close(actual, actual.copy(), tolerance=0)  # equal images pass
    assert not folder.exists(), "a passing comparison wrote images"
    with pytest.raises(AssertionError) as failure:
        assert_image_close(actual, expected, tolerance=2, name="probe")
    message = str(failure.value)
    assert str(folder) in message and "probe" in message
    written = sorted(p.name for p in folder.iterdir())
    assert written == ["probe_actual.png", "probe_diff.png", "probe_expected.png"]
    assert np.array_equal(np.asarray(Image.open(folder / "probe_actual.png")), actual)
    assert np.array_equal(np.asarray(Image.open(folder / "probe_expected.png")), expected)
    diff = np.asarray(Image.open(folder / "probe_diff.png"))
    assert diff.shape == actual.shape
    assert (diff.max(axis=-1) > 0).sum() == 6  # the 2 x 3 changed pixels, nothing else
    # Without a name, the images are named after the running test.
    with pytest.raises(AssertionError, match=str(folder)):
        assert_image_close(actual, expected, tolerance=2, fraction=0.99)
    named = "test_assert_image_close_writes_actual_expected_and_diff_on_failure"
    assert (folder / f"{named}_diff.png").exists()


# --------------------------------------------------------------------------- command line


def run_cli(*args, cwd):
    return subprocess.run(
        [sys.executable, "-m", "mirrorlab.cli", *args],
        cwd=cwd,
        capture_output=True,
        text=True,
        timeout=120,
    )


def test_cli_render_writes_frame_and_environment(tmp_path):
    (tmp_path / "o").mkdir()
    result = run_cli(
        "render",
        "--out",
        "o/frame.png",
        "--size",
        "80x60",
        "--save-env",
        "o/env.png",
        "--angles",
        "0,10,-20",
        "--camera",
        "10,4,8",
        "--target",
        "-3.5,1,-2",
        cwd=tmp_path,
    )
    assert result.returncode == 0, result.stderr
    frame = np.asarray(Image.open(tmp_path / "o/frame.png"))
    env = np.asarray(Image.open(tmp_path / "o/env.png"))
    assert frame.shape == (60, 80, 3) and env.shape == (60, 80, 3)
    assert sorted(p.name for p in (tmp_path / "o").iterdir()) == ["env.png", "frame.png"]


def test_cli_bad_input_leaves_existing_output_untouched(tmp_path):
    out = tmp_path / "frame.png"
    out.write_bytes(b"keep me")
    result = run_cli("render", "--out", str(out), "--camera", "1,2", cwd=tmp_path)
    assert result.returncode == 2
    assert result.stderr.strip().count("\n") == 0 and "--camera" in result.stderr
    assert out.read_bytes() == b"keep me"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["frame.png"]


def test_cli_unwritable_output_fails_cleanly(tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    result = run_cli("render", "--out", str(blocker / "frame.png"), "--size", "16x16", cwd=tmp_path)
    assert result.returncode != 0
    assert "Traceback" not in result.stderr and str(blocker) in result.stderr
