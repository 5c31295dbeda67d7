"""The demo's controls, in one place: the window's help overlay, ``mirrorlab demo --help``
and the docs (docs/demo.md) list them from here. Plain text (no markup): it is read in a
terminal and in the window. Imports nothing (the command line reads it before choosing a
GL platform).
"""

from __future__ import annotations

CONTROLS: tuple[tuple[str, str], ...] = (
    ("Left/Right", "turn the robot's base"),
    ("Up/Down", "the robot's lower arm (no robot: move the cone or sphere)"),
    ("Shift+Up/Down", "the robot's upper arm (also PageUp/PageDown)"),
    ("drag", "orbit the camera (left mouse button)"),
    ("wheel, +/-", "zoom"),
    ("1-9", "technique of the reflector under the mouse (else the first)"),
    ("M", "that reflector's next technique"),
    ("E", "show its texture (a cube map: six faces) as an inset"),
    ("X", "show screen-space reflections' miss mask over the frame (technique ssr)"),
    ("P", "print the frame's plan to the terminal"),
    ("S", "save a screenshot"),
    ("R", "reset scene and camera"),
    ("H", "show or hide this help"),
    ("Esc", "quit"),
)


def control_lines(width: int = 14) -> list[str]:
    """The controls as aligned lines (in a fixed-width font): key(s), then what they do."""
    return [f"{keys:<{width}} {what}" for keys, what in CONTROLS]
