"""A resize storm: the demo window resized 100 times under Xvfb, as fast as the requests
go, then once more to a final size. With --debug any GL error ends the demo with exit
status 1, so a clean exit says there was none; the live GL objects are the same before
and after (counted once the first resize has drawn); and the last frame is the headless
render at the final size (the capture texture followed the framebuffer, the aspect is
right)."""

from __future__ import annotations

import re

import numpy as np

import mirrorlab
from tests.imagecheck import assert_images_close
from tests.window.xwindow import (
    Demo,
    find_window,
    frame_number,
    press,
    screenshot,
    settled,
    wait_for,
)

FINAL = (400, 300)


def gl_objects(demo: Demo, d, window) -> int:
    count = len(demo.out)
    press(d, window, "p")
    lines = demo.output_after(count, r"^live GL objects: \d+$", "the printed plan")
    return int(
        next(
            re.match(r"^live GL objects: (\d+)$", line).group(1)  # type: ignore[union-attr]
            for line in lines
            if line.startswith("live GL objects")
        )
    )


def test_a_hundred_resizes(xdisplay):
    d = xdisplay
    demo = Demo("lab20", "--size", "320x240")
    try:
        window = find_window(d, "mirrorlab demo - lab20")
        settled(d, window, 0, "the first frame")
        # Counted after one resize: the views it no longer draws leave their buffers as
        # the spares the storm's frames fill (a fixed few; mirrorlab.passes.scene_draw).
        drawn = frame_number(window)
        window.configure(width=FINAL[0], height=FINAL[1])
        d.sync()
        settled(d, window, drawn, "a frame at the final size")
        before = gl_objects(demo, d, window)
        rng = np.random.default_rng(12)
        for index, (width, height) in enumerate(
            zip(rng.integers(64, 700, 100), rng.integers(48, 560, 100), strict=True)
        ):
            window.configure(width=int(width), height=int(height))
            if index % 10 == 9:
                d.sync()  # let some frames be drawn between the bursts
        window.configure(width=FINAL[0], height=FINAL[1])
        d.sync()
        expected = mirrorlab.render("lab20", size=FINAL)

        def final_frame():
            image = screenshot(d, window)
            if image.shape != (FINAL[1], FINAL[0], 3):
                return None
            close = np.abs(image.astype(int) - expected.astype(int)).max(axis=-1) <= 8
            return image if close.mean() >= 0.99 else None

        last = wait_for(final_frame, "the frame drawn at the final size")
        assert_images_close(
            "resize_last",
            last,
            expected,
            channel_tolerance=8,
            min_fraction_within=0.99,
            max_mean_abs=1.0,
        )
        assert gl_objects(demo, d, window) == before
        press(d, window, "Escape")
        assert demo.finish() == 0, demo.err
        assert demo.err == [], demo.err
    finally:
        demo.stop()
