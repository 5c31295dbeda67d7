"""`mirrorlab demo` in a real glfw window on the X server, driven by real key, button,
motion and wheel events (XTEST): a screenshot before and after each control, each frame
checked against the headless render of the state the title reports.

Tolerance for window against headless frames: 99% of pixels within 8/255 and a mean
difference under 1/255 (the same renderer on the same llvmpipe; only the path to the
screen differs)."""

from __future__ import annotations

import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest
from PIL import Image

import mirrorlab
from mirrorlab import math3d
from mirrorlab.app.demo import ZOOM_FACTOR, Orbit
from mirrorlab.options import apply_options
from mirrorlab.techniques import technique_names
from tests.imagecheck import assert_images_close, save_failure
from tests.scenekit import curved_reflector, planar_reflector
from tests.window.xwindow import (
    GIVE_UP_S,
    Demo,
    drag,
    find_window,
    frame_number,
    move_pointer,
    press,
    screenshot,
    scroll,
    settled,
    title,
    wait_for,
)

WIDTH, HEIGHT = 320, 240


def shows(d, window, text: str) -> np.ndarray:
    """The window's pixels once its title shows ``text``, read while no new frame came."""

    def read():
        before = title(window)
        if text not in before:
            return None
        image = screenshot(d, window)
        return image if title(window) == before else None

    try:
        return wait_for(read, f"the title to show {text!r}")
    except AssertionError:
        raise AssertionError(f"the title is {title(window)!r}, not showing {text!r}") from None


def headless(scene, orbit: Orbit, size=(WIDTH, HEIGHT), **options) -> np.ndarray:
    scene = apply_options(mirrorlab.load_scene(scene), options)
    camera = replace(scene.camera, eye=orbit.eye(), target=orbit.target)
    return mirrorlab.render(replace(scene, camera=camera), size=size)


def same_picture(name: str, window_frame: np.ndarray, expected: np.ndarray) -> None:
    assert_images_close(
        name,
        window_frame,
        expected,
        channel_tolerance=8,
        min_fraction_within=0.99,
        max_mean_abs=1.0,
    )


def changed_pixels(a: np.ndarray, b: np.ndarray) -> int:
    return int((np.abs(a.astype(int) - b.astype(int)).max(axis=-1) > 24).sum())


def eye_text(orbit: Orbit) -> str:
    x, y, z = orbit.eye()
    return f"eye {x:.2f},{y:.2f},{z:.2f}"


def pixel_of(scene, point, orbit: Orbit) -> tuple[int, int]:
    scene = mirrorlab.load_scene(scene)
    camera = replace(scene.camera, eye=orbit.eye(), target=orbit.target)
    x, y, _ = math3d.project_to_pixels(
        camera.projection(WIDTH / HEIGHT) @ camera.view(),
        np.asarray(point, dtype=np.float64),
        WIDTH,
        HEIGHT,
    )
    return int(x), int(y)


@pytest.fixture
def lab_demo(tmp_path):
    demo = Demo("lab20", "--size", f"{WIDTH}x{HEIGHT}", "--shot-dir", str(tmp_path))
    yield demo
    demo.stop()


def test_every_control_of_the_lab_demo(xdisplay, lab_demo, tmp_path):
    d = xdisplay
    window = find_window(d, "mirrorlab demo - lab20")
    scene = mirrorlab.load_scene("lab20")
    orbit = Orbit.from_eye(scene.camera.eye, scene.camera.target)
    first = settled(d, window, 0, "the first frame")
    try:
        same_picture("demo_first", first, headless("lab20", orbit))
    except AssertionError:
        save_failure("demo_first_title", screen=first)
        raise
    assert "mirror: ortho" in title(window) and "capture:mirror + camera" in title(window)

    # E shows the mirror's texture as an inset in the bottom left, and hides it again. (The
    # lab's ortho capture, of the whole view: a reflected one holds only what its glass shows.)
    count = frame_number(window)
    press(d, window, "e")
    inset = settled(d, window, count, "the frame with the inset")
    box = (slice(HEIGHT - 8 - 72, HEIGHT - 8), slice(8, 8 + 96))  # 0.4 x 240 high, 4:3
    assert changed_pixels(first[box], inset[box]) > 500, "no inset"
    with mirrorlab.Renderer((WIDTH, HEIGHT)) as renderer:
        renderer.render(mirrorlab.load_scene("lab20"))
        capture = renderer.read_texture("mirror")
    shrunk = np.asarray(
        Image.fromarray(capture).resize((96, 72), Image.Resampling.BILINEAR)
    ).astype(int)
    # where the capture differs from what the frame shows there (the frame's own mirror
    # shows a copy of the capture, smaller)
    drawn = np.abs(shrunk - first[box]).max(axis=-1) > 40
    agrees = float((np.abs(inset[box].astype(int) - shrunk).max(axis=-1) < 48)[drawn].mean())
    assert drawn.sum() > 300 and agrees > 0.8, (drawn.sum(), agrees)
    count = frame_number(window)
    press(d, window, "e")
    assert np.array_equal(settled(d, window, count, "the frame without the inset"), first)

    # Arrow keys turn the joints: Left/Right the base, Up/Down the lower arm, Shift+Up/Down
    # (and PageUp/PageDown) the upper arm.
    expected_angles = [(-30, 30, -75), (-30, 35, -75), (-30, 35, -70), (-30, 35, -75)]
    keys = [("Right", False), ("Up", False), ("Up", True), ("Next", False)]
    before = first
    for (key, shift), angles in zip(keys, expected_angles, strict=True):
        press(d, window, key, shift=shift)
        after = shows(d, window, "base {} lower {} upper {} deg".format(*angles))
        assert changed_pixels(before, after) > 50, f"{key} changed nothing on screen"
        same_picture(f"demo_{key}", after, headless("lab20", orbit, angles=angles))
        before = after
    angles = expected_angles[-1]

    # Dragging with the left button orbits the camera: 50 pixels right, 0.4 degrees each.
    middle = (WIDTH // 2, HEIGHT // 2)
    drag(d, window, middle, (middle[0] + 50, middle[1]))
    orbit.turn(50 * 0.4, 0.0)
    after = shows(d, window, eye_text(orbit))
    assert changed_pixels(before, after) > 50
    same_picture("demo_drag", after, headless("lab20", orbit, angles=angles))
    before = after

    # The wheel zooms: one notch up brings the camera 1.1 times closer.
    scroll(d, window, 1)
    orbit.zoom(1.0 / ZOOM_FACTOR)
    after = shows(d, window, eye_text(orbit))
    assert changed_pixels(before, after) > 50
    same_picture("demo_wheel", after, headless("lab20", orbit, angles=angles))
    before = after

    # 1-9 pick the technique of the reflector under the mouse, in the registry's order.
    move_pointer(d, window, *pixel_of("lab20", (-7.0, 1.0, -2.0), orbit))
    press(d, window, str(technique_names("planar").index("reflected") + 1))
    after = shows(d, window, "mirror: reflected")
    assert changed_pixels(before, after) > 50
    same_picture(
        "demo_technique", after, headless("lab20", orbit, angles=angles, method="reflected")
    )
    before = after

    # H shows the help over the frame, and hides it again.
    count = frame_number(window)
    press(d, window, "h")
    helped = settled(d, window, count, "the frame with the help")
    corner = (slice(2, 40), slice(2, 120))
    assert helped[corner].mean() < 0.6 * before[corner].mean() + 20, "no dark help panel"
    assert changed_pixels(before, helped) > 500
    count = frame_number(window)
    press(d, window, "h")
    assert np.array_equal(settled(d, window, count, "the frame without the help"), before)

    # P prints the frame's plan.
    lines = len(lab_demo.out)
    press(d, window, "p")
    printed = lab_demo.output_after(lines, r"^live GL objects: \d+$", "the printed plan")
    assert any(line.startswith("plan of frame") for line in printed)
    assert any("camera" in line for line in printed)

    # S saves a screenshot: the picture in the window.
    press(d, window, "s")
    saved = lab_demo.output_after(
        len(lab_demo.out), r"^saved .*demo-lab20-001\.png$", "the screenshot"
    )
    path = tmp_path / "demo-lab20-001.png"
    assert saved and path.is_file()
    with Image.open(path) as image:
        assert np.array_equal(np.asarray(image.convert("RGB")), before)

    # R resets the scene and the camera: the first frame again.
    press(d, window, "r")
    initial = Orbit.from_eye(scene.camera.eye, scene.camera.target)
    reset = shows(d, window, "base -35 lower 30 upper -75 deg")
    assert eye_text(initial) in title(window) and "mirror: ortho" in title(window)
    assert np.array_equal(reset, first)

    press(d, window, "Escape")
    assert lab_demo.finish() == 0
    assert lab_demo.err == [], lab_demo.err


def test_number_keys_and_inset_follow_the_reflector_under_the_mouse(xdisplay):
    d = xdisplay
    demo = Demo("mirror_and_sphere", "--size", f"{WIDTH}x{HEIGHT}")
    try:
        window = find_window(d, "mirrorlab demo - mirror_and_sphere")
        scene = mirrorlab.load_scene("mirror_and_sphere")
        orbit = Orbit.from_eye(scene.camera.eye, scene.camera.target)
        before = settled(d, window, 0, "the first frame")
        sphere = curved_reflector(scene, "sphere")
        move_pointer(d, window, *pixel_of("mirror_and_sphere", sphere.center(), orbit))
        press(d, window, str(technique_names("curved").index("cube") + 1))  # a static cube map
        after = shows(d, window, "sphere: cube -")
        assert changed_pixels(before, after) > 20
        same_picture(
            "demo_sphere_cube",
            after,
            headless("mirror_and_sphere", orbit, set=['reflectors[1].technique="cube"']),
        )
        # The inset shows the sphere's cube map: six faces along the bottom.
        count = frame_number(window)
        press(d, window, "e")
        inset = settled(d, window, count, "the frame with the six faces")
        strip = (slice(HEIGHT - 8 - 40, HEIGHT - 8), slice(8, WIDTH - 8))
        assert changed_pixels(after[strip], inset[strip]) > 2000
        press(d, window, "e")
        # Over the mirror (away from the sphere), 3 makes the mirror a stencil mirror.
        mirror = planar_reflector(scene, "mirror")
        corner = mirror.corner_array[0] * 0.8 + mirror.center * 0.2
        move_pointer(d, window, *pixel_of("mirror_and_sphere", corner, orbit))
        press(d, window, "3")
        shows(d, window, "mirror: stencil -")
        press(d, window, "Escape")
        assert demo.finish() == 0
        assert demo.err == [], demo.err
    finally:
        demo.stop()


@pytest.mark.parametrize("method", ["ortho", "stencil"])
def test_demo_screenshot_matches_the_headless_render(tmp_path, method):
    shot = tmp_path / "demo.png"
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "mirrorlab.cli",
            "demo",
            "--size",
            f"{WIDTH}x{HEIGHT}",
            "--method",
            method,
            "--max-frames",
            "3",
            "--screenshot",
            str(shot),
        ],
        capture_output=True,
        text=True,
        timeout=2 * GIVE_UP_S,
    )
    assert result.returncode == 0, result.stderr
    window_frame = np.asarray(Image.open(shot).convert("RGB"))
    headless_frame = mirrorlab.render("lab20", size=(WIDTH, HEIGHT), method=method)
    same_picture(f"demo_vs_headless_{method}", window_frame, headless_frame)


@pytest.mark.parametrize("scene", ["ssr_box_room", "ssr_sphere_near"])
def test_screen_space_reflections_in_the_demo_and_their_miss_mask(xdisplay, scene):
    """Screen-space reflections (a planar floor, a curved sphere) in the window, as the
    headless render draws them (the frame copied from the window's own framebuffer);
    X shows their miss mask over the window, as the API gives it (its label aside)."""
    d = xdisplay
    demo = Demo(scene, "--size", f"{WIDTH}x{HEIGHT}")
    try:
        window = find_window(d, f"mirrorlab demo - {scene}")
        loaded = mirrorlab.load_scene(scene)
        orbit = Orbit.from_eye(loaded.camera.eye, loaded.camera.target)
        frame = settled(d, window, 0, "the first frame")
        same_picture(f"demo_{scene}", frame, headless(scene, orbit))
        count = frame_number(window)
        press(d, window, "x")
        masked = settled(d, window, count, "the frame with the miss mask")
        with mirrorlab.Renderer((WIDTH, HEIGHT)) as renderer:
            camera = replace(loaded.camera, eye=orbit.eye(), target=orbit.target)
            renderer.render(replace(loaded, camera=camera))
            expected = renderer.ssr_mask().image()
        top = slice(0, HEIGHT * 2 // 3)  # its label lies along the bottom
        same_picture(f"demo_{scene}_mask", masked[top], expected[top])
        press(d, window, "Escape")
        assert demo.finish() == 0
        assert demo.err == [], demo.err
    finally:
        demo.stop()
