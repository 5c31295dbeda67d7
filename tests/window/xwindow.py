"""Driving a real window on the X server from a test: find it, read its pixels and title,
and send it key, button, motion and wheel events through XTEST, as a user's would arrive.

Every wait here ends as soon as its condition holds; GIVE_UP_S only stops a hung demo.
"""

from __future__ import annotations

import re
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np

GIVE_UP_S = 60.0
POLL_S = 0.05
"""How often a wait looks again (not a pass condition: waits end on their condition)."""


def find_window(d, prefix: str, timeout: float = GIVE_UP_S):
    """The top-level window whose title starts with ``prefix``, once it is viewable.

    glfw names its window before it maps it, and GetImage and SetInputFocus on an
    unmapped window fail with BadMatch, so a named window counts as found only once its
    map state is IsViewable.
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
                if (
                    name
                    and name.startswith(prefix)
                    and window.get_attributes().map_state == X.IsViewable
                ):
                    return window
                stack.extend(window.query_tree().children)
            except error.BadWindow:  # destroyed since its parent listed it
                continue
        time.sleep(POLL_S)
    raise AssertionError(f"no viewable window titled {prefix!r} appeared within {timeout} s")


def title(window) -> str:
    name = window.get_wm_name()
    return name.decode(errors="replace") if isinstance(name, bytes) else (name or "")


def frame_number(window) -> int:
    """The demo's frame counter, from its title (0 before its first frame)."""
    match = re.search(r" - frame (\d+)", title(window))
    return int(match.group(1)) if match else 0


def screenshot(d, window) -> np.ndarray:
    """The window's pixels as the X server has them, ``(h, w, 3)`` uint8 RGB, read with the
    server grabbed so nothing changes between the checks and the read."""
    from Xlib import X

    root = d.screen().root
    d.grab_server()
    try:
        viewable = window.get_attributes().map_state == X.IsViewable
        geometry = window.get_geometry()
        origin = root.translate_coords(window, 0, 0)
        screen = root.get_geometry()
        on_screen = (
            origin.x >= 0
            and origin.y >= 0
            and origin.x + geometry.width <= screen.width
            and origin.y + geometry.height <= screen.height
        )
        raw = (
            window.get_image(0, 0, geometry.width, geometry.height, X.ZPixmap, 0xFFFFFFFF)
            if viewable and on_screen
            else None
        )
    finally:
        d.ungrab_server()
        d.flush()
    assert viewable, f"window {window.id:#x} is not viewable (unmapped or closed)"
    assert on_screen, f"window {window.id:#x} is not wholly on the screen"
    assert raw is not None
    pixels = np.frombuffer(raw.data, np.uint8).reshape(geometry.height, geometry.width, 4)
    return pixels[..., [2, 1, 0]].copy()  # BGRX -> RGB


def wait_for(condition, what: str, timeout: float = GIVE_UP_S):
    deadline = time.monotonic() + timeout
    value = None
    while time.monotonic() < deadline:
        value = condition()
        if value is not None and value is not False:
            return value
        time.sleep(POLL_S)
    raise AssertionError(f"timed out after {timeout} s waiting for {what}")


def settled(d, window, after: int, what: str = "a new frame") -> np.ndarray:
    """The window's pixels once the demo has drawn a frame numbered above ``after`` and
    drawn nothing more while they were read (its title is set after each swap)."""

    def read():
        before = frame_number(window)
        if before <= after:
            return None
        image = screenshot(d, window)
        return image if frame_number(window) == before else None

    return wait_for(read, what)


def _focus(d, window) -> None:
    from Xlib import X

    window.set_input_focus(X.RevertToParent, X.CurrentTime)
    d.sync()


def press(d, window, keysym_name: str, shift: bool = False) -> None:
    """Press and release a key (with Shift held, if asked) in ``window``."""
    from Xlib import XK, X
    from Xlib.ext import xtest

    _focus(d, window)
    keycode = d.keysym_to_keycode(XK.string_to_keysym(keysym_name))
    shift_code = d.keysym_to_keycode(XK.XK_Shift_L)
    if shift:
        xtest.fake_input(d, X.KeyPress, shift_code)
    xtest.fake_input(d, X.KeyPress, keycode)
    xtest.fake_input(d, X.KeyRelease, keycode)
    if shift:
        xtest.fake_input(d, X.KeyRelease, shift_code)
    d.sync()


def move_pointer(d, window, x: int, y: int) -> None:
    """Put the pointer at ``(x, y)`` in the window's coordinates."""
    from Xlib import X
    from Xlib.ext import xtest

    origin = d.screen().root.translate_coords(window, 0, 0)
    xtest.fake_input(d, X.MotionNotify, x=origin.x + x, y=origin.y + y)
    d.sync()


def drag(d, window, start: tuple[int, int], end: tuple[int, int], steps: int = 5) -> None:
    """Press the left button at ``start``, move to ``end`` in ``steps`` moves, release."""
    from Xlib import X
    from Xlib.ext import xtest

    _focus(d, window)
    move_pointer(d, window, *start)
    xtest.fake_input(d, X.ButtonPress, 1)
    d.sync()
    for step in range(1, steps + 1):
        move_pointer(
            d,
            window,
            round(start[0] + (end[0] - start[0]) * step / steps),
            round(start[1] + (end[1] - start[1]) * step / steps),
        )
    xtest.fake_input(d, X.ButtonRelease, 1)
    d.sync()


def scroll(d, window, notches: int) -> None:
    """Turn the wheel: up (away from the user) for positive ``notches``."""
    from Xlib import X
    from Xlib.ext import xtest

    _focus(d, window)
    button = 4 if notches > 0 else 5
    for _ in range(abs(notches)):
        xtest.fake_input(d, X.ButtonPress, button)
        xtest.fake_input(d, X.ButtonRelease, button)
    d.sync()


class Demo:
    """``mirrorlab demo ARGS`` in a process of its own, its output collected as it comes."""

    def __init__(self, *args: str, cwd: Path | None = None) -> None:
        self.process = subprocess.Popen(
            [sys.executable, "-m", "mirrorlab.cli", "demo", "--debug", *args],
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            cwd=cwd,
        )
        self.out: list[str] = []
        self.err: list[str] = []
        self._readers = [
            threading.Thread(target=self._read, args=(stream, into), daemon=True)
            for stream, into in ((self.process.stdout, self.out), (self.process.stderr, self.err))
        ]
        for reader in self._readers:
            reader.start()

    @staticmethod
    def _read(stream, into: list[str]) -> None:
        for line in stream:
            into.append(line.rstrip("\n"))

    def output_after(self, count: int, pattern: str, what: str) -> list[str]:
        """Stdout lines after the first ``count``, once one of them matches ``pattern``."""
        return wait_for(
            lambda: (
                self.out[count:]
                if any(re.search(pattern, line) for line in self.out[count:])
                else None
            ),
            what,
        )

    def finish(self) -> int:
        code = self.process.wait(timeout=GIVE_UP_S)
        for reader in self._readers:
            reader.join(GIVE_UP_S)
        return code

    def stop(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
            self.process.wait()
