"""The demo's cone mode (the textbook's sphere-mapping experiment) in a real glfw window:
the first frame is the headless render, and the Down key moves the cone and changes what
it reflects."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import mirrorlab
from tests.imagecheck import assert_images_close, save_failure
from tests.scenekit import curved_reflector
from tests.window.xwindow import GIVE_UP_S, find_window, press, screenshot, title, wait_for

WIDTH, HEIGHT = 256, 256


@pytest.fixture
def cone_demo():
    proc = subprocess.Popen(
        [sys.executable, "-m", "mirrorlab.cli", "demo", "cone", "--size", f"{WIDTH}x{HEIGHT}"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    yield proc
    if proc.poll() is None:
        proc.kill()
        proc.wait()


def test_cone_demo_moves_the_cone_and_its_reflection_changes(xdisplay, cone_demo):
    window = find_window(xdisplay, "mirrorlab demo - spheremap_cone")
    headless = mirrorlab.render("cone", size=(WIDTH, HEIGHT))

    def drawn():
        image = screenshot(xdisplay, window)
        if image.shape != (HEIGHT, WIDTH, 3):
            return None
        return image if np.abs(image.astype(int) - headless.astype(int)).mean() < 2 else None

    try:
        first = wait_for(drawn, "the first frame to match the headless render")
    except AssertionError:
        save_failure("cone_demo_first", screen=screenshot(xdisplay, window), headless=headless)
        raise
    assert_images_close(
        "cone_demo_vs_headless",
        first,
        headless,
        channel_tolerance=8,
        min_fraction_within=0.99,
        max_mean_abs=1.0,
    )
    for height in ("0.75", "0.50", "0.25", "0.00"):  # one key at a time, as a user would
        press(xdisplay, window, "Down")
        try:
            wait_for(
                lambda h=height: f"height {h}" in title(window) or None,
                f"the cone to move down to {height}",
            )
        except AssertionError:
            raise AssertionError(f"title is {title(window)!r}") from None
    lowered = mirrorlab.render(
        "cone", size=(WIDTH, HEIGHT), set=["reflectors[0].position=[0.0, 0.0, 0.0]"]
    )
    second = wait_for(
        lambda: (
            lambda img: img if np.abs(img.astype(int) - lowered.astype(int)).mean() < 2 else None
        )(screenshot(xdisplay, window)),
        "the frame with the cone lowered",
    )
    changed = np.abs(second.astype(int) - first.astype(int)).max(axis=-1) > 24
    assert changed.sum() > 500, "the frame barely changed after Down"
    press(xdisplay, window, "Escape")
    assert cone_demo.wait(timeout=GIVE_UP_S) == 0, cone_demo.stderr.read()


def test_the_2d_maps_of_directions_draw_in_the_demo_as_headless(tmp_path):
    """The octahedral and dual-paraboloid maps in a real window (a debug context, so a GL
    error stops the demo): five chrome balls in the sky, one a technique, in one scene
    file; the demo's last frame is the headless render's."""
    from dataclasses import replace

    from PIL import Image

    from mirrorlab.scene.loader import dumps
    from mirrorlab.scene.model import Camera, Transform

    sky = mirrorlab.load_scene("chrome_sphere")
    ball = curved_reflector(sky, "sphere")
    methods = (
        "octahedral",
        "octahedral-live",
        "paraboloid",
        "paraboloid-live",
        "paraboloid-warped",
    )
    balls = tuple(
        replace(
            ball,
            name=f"ball_{index}",
            technique=method,
            map_size=64,
            transform=Transform(position=(2.4 * index - 4.8, 0.0, 0.0), scale=(1.0, 1.0, 1.0)),
        )
        for index, method in enumerate(methods)
    )
    camera = Camera(eye=(0.0, 2.0, 13.0), target=(0.0, 0.0, 0.0), fovy=50.0)
    scene = replace(sky, objects=(), reflectors=balls, camera=camera)
    path = tmp_path / "balls.toml"
    path.write_text(dumps(scene, tmp_path))
    shot = tmp_path / "demo.png"
    result = subprocess.run(
        [
            sys.executable,
            "-m",
            "mirrorlab.cli",
            "demo",
            str(path),
            "--size",
            f"{WIDTH}x{HEIGHT}",
            "--max-frames",
            "3",
            "--debug",
            "--screenshot",
            str(shot),
        ],
        capture_output=True,
        text=True,
        timeout=2 * GIVE_UP_S,
    )
    assert result.returncode == 0, result.stderr
    window_frame = np.asarray(Image.open(shot).convert("RGB"))
    headless = mirrorlab.render(path, size=(WIDTH, HEIGHT))
    assert_images_close(
        "demo_2d_maps",
        window_frame,
        np.asarray(headless),
        channel_tolerance=8,
        min_fraction_within=0.99,
        max_mean_abs=1.0,
    )
