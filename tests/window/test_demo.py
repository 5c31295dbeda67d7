"""`mirrorlab demo` in a real glfw window on the X server: it draws both passes, answers
key presses sent through XTEST, and quits on Esc."""

from __future__ import annotations

import subprocess
import sys
import time

import numpy as np
import pytest
from PIL import Image

import mirrorlab
from mirrorlab import math3d
from mirrorlab.scene.robot import hand_center
from tests.imagecheck import (
    assert_images_close,
    mirror_image_point,
    near,
    red_dominant,
    save_failure,
    viewer_matrix,
)

WIDTH, HEIGHT = 320, 240
GIVE_UP_S = 60.0
"""How long a window test waits for a condition before it fails. Only a limit: every wait
ends as soon as its condition holds (within a second or so on llvmpipe), so this can be
generous enough for a loaded machine."""


@pytest.fixture
def xdisplay():
    from Xlib import display

    d = display.Display()
    yield d
    d.close()


def find_window(d, prefix: str, timeout: float = GIVE_UP_S):
    """The top-level window whose title starts with ``prefix``, once it is viewable.

    glfw names its window before it maps it: the title is set when the X window is
    made, the GLX context is made next, and only then is the window mapped, some
    10-20 ms later on llvmpipe. A window found in between is not viewable, and
    GetImage and SetInputFocus on it fail with BadMatch, so a named window counts as
    found only once its map state is IsViewable.
    """
    from Xlib import X, error

    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        stack = [d.screen().root]
        while stack:
            window = stack.pop()
            try:
                name = window.get_wm_name()
                if isinstance(name, bytes):
                    name = name.decode(errors="replace")
                if (name and name.startswith(prefix)
                        and window.get_attributes().map_state == X.IsViewable):
                    return window
                stack.extend(window.query_tree().children)
            except error.BadWindow:  # destroyed since its parent listed it
                continue
        time.sleep(0.1)
    raise AssertionError(f"no viewable window titled {prefix!r} appeared within {timeout} s")


def title(window) -> str:
    name = window.get_wm_name()
    return name.decode(errors="replace") if isinstance(name, bytes) else (name or "")


def screenshot(d, window) -> np.ndarray:
    """The window's pixels as the X server has them, ``(h, w, 3)`` uint8 RGB.

    GetImage on a window is a BadMatch unless the window is viewable and lies wholly on
    the screen; both are checked with the server grabbed, so that nothing can change
    between the check, the geometry and the read.
    """
    from Xlib import X

    root = d.screen().root
    d.grab_server()
    try:
        viewable = window.get_attributes().map_state == X.IsViewable
        geometry = window.get_geometry()
        origin = root.translate_coords(window, 0, 0)
        screen = root.get_geometry()
        on_screen = (origin.x >= 0 and origin.y >= 0
                     and origin.x + geometry.width <= screen.width
                     and origin.y + geometry.height <= screen.height)
        raw = (window.get_image(0, 0, geometry.width, geometry.height, X.ZPixmap, 0xFFFFFFFF)
               if viewable and on_screen else None)
    finally:
        d.ungrab_server()
        d.flush()
    assert viewable, f"window {window.id:#x} is not viewable (unmapped or closed)"
    assert on_screen, (f"window {window.id:#x} ({geometry.width}x{geometry.height} at "
                       f"{origin.x},{origin.y}) is not wholly on the "
                       f"{screen.width}x{screen.height} screen")
    pixels = np.frombuffer(raw.data, np.uint8).reshape(geometry.height, geometry.width, 4)
    return pixels[..., [2, 1, 0]].copy()  # BGRX -> RGB


def press(d, window, keysym_name: str) -> None:
    from Xlib import XK, X
    from Xlib.ext import xtest

    window.set_input_focus(X.RevertToParent, X.CurrentTime)
    d.sync()
    keycode = d.keysym_to_keycode(XK.string_to_keysym(keysym_name))
    xtest.fake_input(d, X.KeyPress, keycode)
    xtest.fake_input(d, X.KeyRelease, keycode)
    d.sync()


def wait_for(condition, what: str, timeout: float = GIVE_UP_S):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = condition()
        if value is not None:
            return value
        time.sleep(0.1)
    raise AssertionError(f"timed out after {timeout} s waiting for {what}")


@pytest.fixture
def demo():
    proc = subprocess.Popen(
        [sys.executable, "-m", "mirrorlab.cli", "demo", "--size", f"{WIDTH}x{HEIGHT}"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    yield proc
    if proc.poll() is None:
        proc.kill()
        proc.wait()


def expected_hand_pixels(angles=None):
    """Where the lab scene's camera sees the hand and, in the ortho capture, its image."""
    scene = mirrorlab.load_scene("lab20")
    if angles is not None:
        scene = scene.with_angles(angles)
    vp = viewer_matrix(scene.camera, WIDTH, HEIGHT)
    assert scene.robot is not None
    hand = hand_center(scene.robot)
    real = math3d.project_to_pixels(vp, hand, WIDTH, HEIGHT)
    reflected = math3d.project_to_pixels(
        vp, mirror_image_point(scene.reflector("mirror"), hand), WIDTH, HEIGHT)
    return real, reflected


def test_demo_window_draws_both_passes_answers_keys_and_quits_on_escape(xdisplay, demo):
    window = find_window(xdisplay, "mirrorlab demo")
    real, reflected = expected_hand_pixels()

    def drawn():
        image = screenshot(xdisplay, window)
        ok = image.shape == (HEIGHT, WIDTH, 3) and red_dominant(near(image, reflected, 2)).any()
        return image if ok else None

    try:
        first = wait_for(drawn, "the first frame with the reflected hand")
    except AssertionError:
        save_failure("demo_first", screen=screenshot(xdisplay, window))
        raise
    assert red_dominant(near(first, real, 2)).any(), "the robot's own hand is missing"

    press(xdisplay, window, "Right")  # base joint +5 degrees
    def changed():
        image = screenshot(xdisplay, window)
        moved_pixels = (np.abs(image.astype(int) - first.astype(int)).max(axis=-1) > 24).sum()
        return image if moved_pixels > 50 else None

    second = wait_for(changed, "the frame to change after the Right key")
    wait_for(lambda: "base -30" in title(window) or None, "the title to show base -30")
    _, moved = expected_hand_pixels((-30.0, 30.0, -75.0))
    assert red_dominant(near(second, moved, 2)).any(), "reflection did not follow the joint"

    press(xdisplay, window, "m")  # the next mirror technique: reflected
    wait_for(lambda: " - reflected - " in title(window) or None,
             "the title to name the reflected technique")

    def reflected_drawn():
        image = screenshot(xdisplay, window)
        return image if (np.abs(image.astype(int) - second.astype(int)).max(axis=-1)
                         > 24).sum() > 50 else None

    wait_for(reflected_drawn, "the reflection to change with the technique")

    press(xdisplay, window, "Escape")
    assert demo.wait(timeout=GIVE_UP_S) == 0, demo.stderr.read()


@pytest.mark.parametrize("method", ["ortho", "stencil"])
def test_demo_screenshot_matches_the_headless_render(tmp_path, method):
    # --screenshot reads the back buffer with glReadPixels right after the last frame is
    # drawn, which waits for that frame, so no frame count is "too early": frames 1, 2
    # and 3 are identical. The timeout only stops a hung demo.
    shot = tmp_path / "demo.png"
    result = subprocess.run(
        [sys.executable, "-m", "mirrorlab.cli", "demo", "--size", f"{WIDTH}x{HEIGHT}",
         "--method", method, "--max-frames", "3", "--screenshot", str(shot)],
        capture_output=True, text=True, timeout=2 * GIVE_UP_S)
    assert result.returncode == 0, result.stderr
    window_frame = np.asarray(Image.open(shot).convert("RGB"))
    headless = mirrorlab.render("lab20", size=(WIDTH, HEIGHT), method=method)  # EGL, this process
    assert_images_close(f"demo_vs_headless_{method}", window_frame, headless, channel_tolerance=8,
                        min_fraction_within=0.99, max_mean_abs=1.0)
