"""The demo under a budget, in a real window on the X server: the overlay shows the budget
and each reflector's technique, [ and ] tighten and loosen the budget live, B turns it off
and on; each frame is the headless frame of the candidate the title names (below the
overlay's panel), and with the budget off the file's own frame."""

from __future__ import annotations

from dataclasses import replace

import mirrorlab
from mirrorlab.app.demo import BUDGET_STEP
from mirrorlab.budget.candidates import candidates_for
from tests.window.test_demo import HEIGHT, WIDTH, same_picture, shows
from tests.window.xwindow import Demo, find_window, frame_number, press, settled, title

PANEL = 90
"""Rows at the top the budget's panel may cover (three lines of text at 320x240)."""


def chosen_frame(label: str):
    """The headless frame of lab20 with its mirror drawn by the candidate ``label``."""
    scene = mirrorlab.load_scene("lab20")
    mirror = scene.reflectors[0]
    candidate = next(c for c in candidates_for(mirror, scene) if c.label == label)
    drawn = replace(scene, reflectors=(candidate.apply(mirror),))
    return mirrorlab.render(drawn, size=(WIDTH, HEIGHT))


def label_in(text: str) -> str:
    """The mirror's candidate as the title names it: ``mirror: LABEL - ...``."""
    return text.split("mirror: ", 1)[1].split(" - ", 1)[0]


def test_the_budget_in_the_overlay_and_its_keys(xdisplay, tmp_path):
    demo = Demo("lab20", "--size", f"{WIDTH}x{HEIGHT}", "--max-error", "0.05")
    try:
        d = xdisplay
        window = find_window(d, "mirrorlab demo - lab20")
        first = settled(d, window, 0, "the first frame")
        assert "budget FLIP <= 0.05" in title(window)
        label = label_in(title(window))
        same_picture("budget_first", first[PANEL:], chosen_frame(label)[PANEL:])
        # the panel is drawn over the frame's top left
        plain = chosen_frame(label)
        assert (
            abs(first[:PANEL, :160].astype(int) - plain[:PANEL, :160]).max(axis=-1) > 24
        ).sum() > 200

        tight = 0.05 / BUDGET_STEP**3
        for _ in range(3):
            count = frame_number(window)
            press(d, window, "bracketleft")
            settled(d, window, count)
        image = shows(d, window, f"budget FLIP <= {tight:g}")
        same_picture("budget_tight", image[PANEL:], chosen_frame(label_in(title(window)))[PANEL:])

        count = frame_number(window)
        press(d, window, "bracketright")
        settled(d, window, count)
        shows(d, window, f"budget FLIP <= {tight * BUDGET_STEP:g}")

        count = frame_number(window)
        press(d, window, "b")  # off: the file's own technique, no panel
        settled(d, window, count)
        off = shows(d, window, "mirror: ortho -")
        assert "budget" not in title(window)
        same_picture("budget_off", off, mirrorlab.render("lab20", size=(WIDTH, HEIGHT)))

        count = frame_number(window)
        press(d, window, "b")  # on again: the file's (the command line's) budget
        settled(d, window, count)
        shows(d, window, "budget FLIP <= 0.05")
        press(d, window, "Escape")
        assert demo.finish() == 0
    finally:
        demo.stop()
