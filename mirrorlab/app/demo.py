"""The desktop demo: any scene in a glfw window, under the keyboard and the mouse.

Keys:
  Left/Right        turn the robot's base (a scene with a robot)
  Up/Down           the robot's lower arm; with Shift (or PageUp/PageDown) the upper arm;
                    in a scene without a robot, move the first curved reflector up and down
  1-9               the technique of the first reflector (its kind's techniques in order)
  M                 the next technique of the first reflector
  A/D, W/S          orbit the camera; dragging with the left mouse button orbits too
  +/-, mouse wheel  zoom
  R                 reset the scene and the camera
  H                 print this help
  Esc               quit

The title shows the technique, the frame rate and how many captures have run: the
planner captures only when something the capture shows has changed.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from mirrorlab.gl.context import WindowContext, check_gl_errors
from mirrorlab.scene.model import (
    CURVED_TECHNIQUES,
    PLANAR_TECHNIQUES,
    Camera,
    CurvedReflector,
    Scene,
    Transform,
)

JOINT_STEP_DEG = 5.0
ORBIT_STEP_DEG = 5.0
ZOOM_FACTOR = 1.1
REFLECTOR_STEP = 0.25
REFLECTOR_RANGE = 3.0
"""How far (world units) Up/Down may move a curved reflector from where the file puts it."""
HELP = __doc__.split("\n\n")[1]


@dataclass
class Orbit:
    """A camera on a sphere around ``target``: azimuth and elevation in degrees, distance in
    scene units."""

    target: tuple[float, float, float]
    azimuth: float
    elevation: float
    distance: float

    @classmethod
    def from_eye(cls, eye: Sequence[float], target: Sequence[float]) -> Orbit:
        offset = np.asarray(eye, dtype=np.float64) - np.asarray(target, dtype=np.float64)
        distance = float(np.linalg.norm(offset))
        return cls(
            target=tuple(float(v) for v in target),  # type: ignore[arg-type]
            azimuth=math.degrees(math.atan2(offset[2], offset[0])),
            elevation=math.degrees(math.asin(offset[1] / distance)),
            distance=distance,
        )

    def turn(self, d_azimuth: float, d_elevation: float) -> None:
        self.azimuth = (self.azimuth + d_azimuth) % 360.0
        self.elevation = min(85.0, max(-85.0, self.elevation + d_elevation))

    def zoom(self, factor: float) -> None:
        self.distance = min(60.0, max(1.0, self.distance * factor))

    def eye(self) -> tuple[float, float, float]:
        az, el = math.radians(self.azimuth), math.radians(self.elevation)
        offset = self.distance * np.array(
            [math.cos(el) * math.cos(az), math.sin(el), math.cos(el) * math.sin(az)])
        x, y, z = (float(v) for v in np.asarray(self.target) + offset)
        return (x, y, z)


class DemoApp:
    """One scene in the window: the scene as the file gives it, the changes the keys make,
    the orbit camera, and the renderer."""

    def __init__(self, context: WindowContext, scene: Scene) -> None:
        import glfw

        from mirrorlab.gl.resources import DefaultFramebuffer
        from mirrorlab.renderer import SceneRenderer

        self.context = context
        self.initial = scene
        self.scene = scene
        self.orbit = Orbit.from_eye(scene.camera.eye, scene.camera.target)
        self.target = DefaultFramebuffer(context.framebuffer_size)
        self.renderer = SceneRenderer(context.resources)
        self._drag_from: tuple[float, float] | None = None
        self.frames = 0
        self.captures = 0
        window = context.window
        glfw.set_key_callback(window, self.on_key)
        glfw.set_scroll_callback(window, self.on_scroll)
        glfw.set_mouse_button_callback(window, self.on_mouse_button)
        glfw.set_cursor_pos_callback(window, self.on_cursor)

    # ------------------------------------------------------------- changes

    def camera(self) -> Camera:
        """The scene's camera (lens, clip planes) moved to the orbit's eye and target."""
        return replace(self.scene.camera, eye=self.orbit.eye(), target=self.orbit.target)

    def turn_joint(self, index: int, delta: float) -> None:
        robot = self.scene.robot
        if robot is None:
            return
        angles = list(robot.angles)
        angles[index] += delta
        self.scene = self.scene.with_angles(angles)

    def move_reflector(self, dy: float) -> None:
        """Move the first curved reflector up (``dy`` > 0) or down, within
        :data:`REFLECTOR_RANGE` of where the scene file puts it."""
        curved = [r for r in self.scene.reflectors if isinstance(r, CurvedReflector)]
        if not curved:
            return
        reflector = curved[0]
        home = self.initial.reflector(reflector.name).transform.position[1]
        x, y, z = reflector.transform.position
        new_y = min(home + REFLECTOR_RANGE, max(home - REFLECTOR_RANGE, y + dy))
        transform: Transform = replace(reflector.transform, position=(x, new_y, z))
        self.scene = self.scene.with_reflector(reflector.name, transform=transform)

    def techniques(self) -> tuple[str, ...]:
        """The techniques the first reflector can take."""
        if not self.scene.reflectors:
            return ()
        first = self.scene.reflectors[0]
        return PLANAR_TECHNIQUES if first.kind == "planar" else CURVED_TECHNIQUES

    def use_technique(self, name: str) -> None:
        if self.scene.reflectors and name in self.techniques():
            first = self.scene.reflectors[0]
            self.scene = self.scene.with_reflector(first.name, technique=name)

    def next_technique(self) -> None:
        names = self.techniques()
        if names:
            current = self.scene.reflectors[0].technique
            self.use_technique(names[(names.index(current) + 1) % len(names)])

    def reset(self) -> None:
        self.scene = self.initial
        self.orbit = Orbit.from_eye(self.initial.camera.eye, self.initial.camera.target)

    # ------------------------------------------------------------- input

    def on_key(self, window, key: int, scancode: int, action: int, mods: int) -> None:
        import glfw

        if action not in (glfw.PRESS, glfw.REPEAT):
            return
        shift = bool(mods & glfw.MOD_SHIFT)
        orbit_keys = {
            glfw.KEY_A: (-ORBIT_STEP_DEG, 0.0), glfw.KEY_D: (ORBIT_STEP_DEG, 0.0),
            glfw.KEY_W: (0.0, ORBIT_STEP_DEG), glfw.KEY_S: (0.0, -ORBIT_STEP_DEG),
        }
        joint_keys = {
            glfw.KEY_LEFT: (0, -JOINT_STEP_DEG), glfw.KEY_RIGHT: (0, JOINT_STEP_DEG),
            glfw.KEY_UP: (2 if shift else 1, JOINT_STEP_DEG),
            glfw.KEY_DOWN: (2 if shift else 1, -JOINT_STEP_DEG),
            glfw.KEY_PAGE_UP: (2, JOINT_STEP_DEG), glfw.KEY_PAGE_DOWN: (2, -JOINT_STEP_DEG),
        }
        number_keys = {glfw.KEY_1 + i: i for i in range(9)}
        if key == glfw.KEY_ESCAPE:
            glfw.set_window_should_close(window, True)
        elif key in orbit_keys:
            self.orbit.turn(*orbit_keys[key])
        elif key in (glfw.KEY_EQUAL, glfw.KEY_KP_ADD):
            self.orbit.zoom(1.0 / ZOOM_FACTOR)
        elif key in (glfw.KEY_MINUS, glfw.KEY_KP_SUBTRACT):
            self.orbit.zoom(ZOOM_FACTOR)
        elif key in (glfw.KEY_UP, glfw.KEY_DOWN) and self.scene.robot is None:
            self.move_reflector(REFLECTOR_STEP if key == glfw.KEY_UP else -REFLECTOR_STEP)
        elif key in joint_keys:
            self.turn_joint(*joint_keys[key])
        elif key in number_keys and action == glfw.PRESS:
            names = self.techniques()
            if number_keys[key] < len(names):
                self.use_technique(names[number_keys[key]])
        elif key == glfw.KEY_M and action == glfw.PRESS:
            self.next_technique()
        elif key == glfw.KEY_R:
            self.reset()
        elif key == glfw.KEY_H and action == glfw.PRESS:
            print(HELP, flush=True)

    def on_scroll(self, window, dx: float, dy: float) -> None:
        self.orbit.zoom(ZOOM_FACTOR ** (-dy))

    def on_mouse_button(self, window, button: int, action: int, mods: int) -> None:
        import glfw

        if button == glfw.MOUSE_BUTTON_LEFT:
            self._drag_from = glfw.get_cursor_pos(window) if action == glfw.PRESS else None

    def on_cursor(self, window, x: float, y: float) -> None:
        if self._drag_from is not None:
            x0, y0 = self._drag_from
            self.orbit.turn((x - x0) * 0.4, (y - y0) * 0.4)
            self._drag_from = (x, y)

    # ------------------------------------------------------------- frames

    def draw(self) -> None:
        """Render one frame into the window's back buffer."""
        width, height = self.target.size
        if width == 0 or height == 0:  # minimised
            return
        scene = replace(self.scene, camera=self.camera())
        stats = self.renderer.render(scene, self.target)
        self.frames += 1
        self.captures += sum(1 for p in stats.plan.ran if p.name == "capture")

    def title(self, fps: float) -> str:
        parts = [f"mirrorlab demo - {self.scene.name}"]
        robot = self.scene.robot
        if robot is not None:
            base, lower, upper = robot.angles
            parts.append(f"base {base:.0f} lower {lower:.0f} upper {upper:.0f} deg")
        curved = [r for r in self.scene.reflectors if isinstance(r, CurvedReflector)]
        if robot is None and curved:
            parts.append(f"height {curved[0].transform.position[1]:.2f}")
        if self.scene.reflectors:
            parts.append(self.scene.reflectors[0].technique)
        parts.append(f"{fps:.0f} fps, {self.captures} captures - H for help")
        return " - ".join(parts)

    def release(self) -> None:
        self.renderer.release()


def run(scene: Scene, size: tuple[int, int], max_frames: int = 0,
        screenshot: Path | None = None, debug: bool = False) -> int:
    """Open the window on ``scene`` and run until Esc, the window closes, or ``max_frames``
    frames; with ``screenshot``, the last frame drawn is written there as a PNG."""
    import glfw

    from mirrorlab.files import write_png_atomic

    context = WindowContext(size[0], size[1], f"mirrorlab demo - {scene.name}", debug=debug)
    try:
        app = DemoApp(context, scene)
        print(f"mirrorlab demo of {scene.name} on {context.info()['renderer']}.\n{HELP}",
              flush=True)
        last_image = None
        started, frames_at_title = time.perf_counter(), 0
        while not context.should_close():
            glfw.poll_events()
            app.draw()
            if screenshot is not None:
                last_image = app.target.read()
            check_gl_errors("a demo frame")
            context.swap_buffers()
            now = time.perf_counter()
            if now - started >= 0.5:
                glfw.set_window_title(context.window,
                                      app.title((app.frames - frames_at_title) / (now - started)))
                started, frames_at_title = now, app.frames
            if max_frames and app.frames >= max_frames:
                break
        app.release()
        if screenshot is not None and last_image is not None:
            write_png_atomic(screenshot, last_image)
            print(f"wrote {screenshot}", flush=True)
        return 0
    finally:
        context.release()
