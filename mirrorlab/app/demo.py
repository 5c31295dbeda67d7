"""The desktop demo: the lab scene in a glfw window, robot and camera under the keyboard.

Keys: Left/Right turn the base, Up/Down the lower arm, Shift+Up/Down (or
PageUp/PageDown) the upper arm; A/D and W/S orbit the camera, +/- or the
scroll wheel zoom, dragging with the left mouse button orbits too; M cycles the
mirror technique (ortho, reflected, stencil); R resets, H prints this help, Esc quits.

With the lab's ortho technique the capture runs only when the robot moved or
the window was resized: orbiting the camera re-uses the capture, since the
orthographic capture does not depend on the viewer. The reflected technique
re-captures whenever the viewer moves; stencil needs no capture.

Environment-mapping scenes (``run(..., scene="cone")``, the textbook's
sphere-mapping experiment, or ``scene="sphere"``): Up/Down move the reflective
cone (or sphere) and its reflection changes; keys 1-7 choose the technique
(sphere, sphere-vertex, sphere-texgen, cube, cube-live, latlong, normal);
A/D and W/S orbit the camera, +/- zoom; R resets, H prints this help, Esc quits.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from mirrorlab.gl.context import WindowContext, check_gl_errors
from mirrorlab.scene.envscenes import (
    CONE_LIMITS,
    ENV_SCENES,
    ENVMAP_METHODS,
    build_env_scene,
    check_method,
)
from mirrorlab.scene.robot import DEFAULT_CAMERA, DEFAULT_TARGET, Camera, build_lab_scene

JOINT_STEP_DEG = 5.0
ORBIT_STEP_DEG = 5.0
ZOOM_FACTOR = 1.1
HELP = __doc__.split("\n\n")[1]
ENV_HELP = __doc__.split("\n\n")[3]
REFLECTOR_STEP = 0.25


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
        self.distance = min(60.0, max(2.0, self.distance * factor))

    def camera(self) -> Camera:
        az, el = math.radians(self.azimuth), math.radians(self.elevation)
        offset = self.distance * np.array(
            [math.cos(el) * math.cos(az), math.sin(el), math.cos(el) * math.sin(az)]
        )
        eye = tuple(float(v) for v in np.asarray(self.target) + offset)
        return Camera(eye=eye, target=self.target)  # type: ignore[arg-type]


def handle_view_key(orbit: Orbit, window, key: int) -> bool:
    """The keys every demo scene shares: Esc closes the window, A/D and W/S orbit the
    camera, +/- zoom. Returns True when ``key`` was one of them."""
    import glfw

    orbit_keys = {
        glfw.KEY_A: (-ORBIT_STEP_DEG, 0.0), glfw.KEY_D: (ORBIT_STEP_DEG, 0.0),
        glfw.KEY_W: (0.0, ORBIT_STEP_DEG), glfw.KEY_S: (0.0, -ORBIT_STEP_DEG),
    }
    if key == glfw.KEY_ESCAPE:
        glfw.set_window_should_close(window, True)
    elif key in orbit_keys:
        orbit.turn(*orbit_keys[key])
    elif key in (glfw.KEY_EQUAL, glfw.KEY_KP_ADD):
        orbit.zoom(1.0 / ZOOM_FACTOR)
    elif key in (glfw.KEY_MINUS, glfw.KEY_KP_SUBTRACT):
        orbit.zoom(ZOOM_FACTOR)
    else:
        return False
    return True


class DemoApp:
    """Scene, orbit camera and renderer of one demo window; input handlers change them."""

    def __init__(self, context: WindowContext, angles: Sequence[float],
                 method: str = "ortho") -> None:
        import glfw

        from mirrorlab.gl.resources import DefaultFramebuffer
        from mirrorlab.renderer import Renderer

        self.context = context
        self.method = method
        self.initial_angles = tuple(float(a) for a in angles)
        self.scene = build_lab_scene(self.initial_angles)
        self.orbit = Orbit.from_eye(DEFAULT_CAMERA, DEFAULT_TARGET)
        self.target = DefaultFramebuffer(context.framebuffer_size)
        self.renderer = Renderer(context.resources, self.scene, method)
        self._drag_from: tuple[float, float] | None = None
        self.frames = 0
        self.captures = 0
        window = context.window
        glfw.set_key_callback(window, self.on_key)
        glfw.set_scroll_callback(window, self.on_scroll)
        glfw.set_mouse_button_callback(window, self.on_mouse_button)
        glfw.set_cursor_pos_callback(window, self.on_cursor)

    def turn_joint(self, index: int, delta: float) -> None:
        angles = list(self.scene.angles)
        angles[index] += delta
        self.scene.set_angles(angles)

    def reset(self) -> None:
        self.scene.set_angles(self.initial_angles)
        self.orbit = Orbit.from_eye(DEFAULT_CAMERA, DEFAULT_TARGET)

    def next_method(self) -> None:
        """Switch to the next mirror technique (a fresh renderer; the old one is released)."""
        from mirrorlab.plan import METHODS
        from mirrorlab.renderer import Renderer

        self.method = METHODS[(METHODS.index(self.method) + 1) % len(METHODS)]
        self.renderer.release()
        self.renderer = Renderer(self.context.resources, self.scene, self.method)

    def on_key(self, window, key: int, scancode: int, action: int, mods: int) -> None:
        import glfw

        if action not in (glfw.PRESS, glfw.REPEAT):
            return
        shift = bool(mods & glfw.MOD_SHIFT)
        joint_keys = {
            glfw.KEY_LEFT: (0, -JOINT_STEP_DEG), glfw.KEY_RIGHT: (0, JOINT_STEP_DEG),
            glfw.KEY_UP: (2 if shift else 1, JOINT_STEP_DEG),
            glfw.KEY_DOWN: (2 if shift else 1, -JOINT_STEP_DEG),
            glfw.KEY_PAGE_UP: (2, JOINT_STEP_DEG), glfw.KEY_PAGE_DOWN: (2, -JOINT_STEP_DEG),
        }
        if handle_view_key(self.orbit, window, key):
            return
        if key in joint_keys:
            self.turn_joint(*joint_keys[key])
        elif key == glfw.KEY_R:
            self.reset()
        elif key == glfw.KEY_M and action == glfw.PRESS:
            self.next_method()
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

    def draw(self) -> None:
        """Render one frame into the window's back buffer."""
        width, height = self.target.size
        if width == 0 or height == 0:  # minimised
            return
        stats = self.renderer.render(self.target, self.orbit.camera())
        self.frames += 1
        self.captures += bool({"capture", "reflected-capture"} & set(stats.ran))

    def title(self, fps: float) -> str:
        base, lower, upper = self.scene.angles
        return (f"mirrorlab demo - base {base:.0f} lower {lower:.0f} upper {upper:.0f} deg - "
                f"{self.method} - {fps:.0f} fps, {self.captures} captures - H for help")


class EnvDemoApp:
    """An environment-mapping scene in the window: the reflector moves under Up/Down, the
    technique changes under 1-7, the camera orbits under A/D/W/S and +/-."""

    def __init__(self, context: WindowContext, scene_name: str, envmap: str) -> None:
        import glfw

        from mirrorlab.gl.resources import DefaultFramebuffer

        self.context = context
        self.scene_name = scene_name
        self.scene = build_env_scene(scene_name)
        self.method = check_method(envmap)
        self.initial_position = self.scene.reflector.position.copy()
        camera = self.scene.camera
        self.initial_orbit = Orbit.from_eye(camera.eye, camera.target)
        self.orbit = Orbit.from_eye(camera.eye, camera.target)
        self.target = DefaultFramebuffer(context.framebuffer_size)
        self.renderer = self._make_renderer()
        self.frames = 0
        glfw.set_key_callback(context.window, self.on_key)

    def _make_renderer(self):
        from mirrorlab.envmap_renderer import EnvmapRenderer

        return EnvmapRenderer(self.context.resources, self.scene, self.method)

    def use_method(self, method: str) -> None:
        """Switch to technique ``method`` (its maps are made afresh)."""
        if method != self.method:
            self.renderer.release()
            self.method = check_method(method)
            self.renderer = self._make_renderer()

    def move_reflector(self, dy: float) -> None:
        """Move the reflector up (``dy`` > 0) or down, within the scene's limits."""
        low, high = CONE_LIMITS if self.scene_name == "cone" else (-1.0, 2.0)
        y = float(self.scene.reflector.position[1])
        new_y = min(high, max(low, y + dy))
        self.scene.move_reflector((0.0, new_y - y, 0.0))

    def reset(self) -> None:
        self.scene.move_reflector(self.initial_position - self.scene.reflector.position)
        self.orbit = Orbit(**vars(self.initial_orbit))

    def camera(self) -> Camera:
        """The scene's own camera (lens, clip planes) moved to the orbit's eye and target."""
        orbit = self.orbit.camera()
        return replace(self.scene.camera, eye=orbit.eye, target=orbit.target)

    def on_key(self, window, key: int, scancode: int, action: int, mods: int) -> None:
        import glfw

        if action not in (glfw.PRESS, glfw.REPEAT):
            return
        method_keys = {glfw.KEY_1 + i: name for i, name in enumerate(ENVMAP_METHODS)}
        if handle_view_key(self.orbit, window, key):
            return
        if key == glfw.KEY_UP:
            self.move_reflector(REFLECTOR_STEP)
        elif key == glfw.KEY_DOWN:
            self.move_reflector(-REFLECTOR_STEP)
        elif key in method_keys and action == glfw.PRESS:
            self.use_method(method_keys[key])
        elif key == glfw.KEY_R:
            self.reset()
        elif key == glfw.KEY_H and action == glfw.PRESS:
            print(ENV_HELP, flush=True)

    def draw(self) -> None:
        """Render one frame into the window's back buffer."""
        width, height = self.target.size
        if width == 0 or height == 0:  # minimised
            return
        self.renderer.render(self.target, self.camera())
        self.frames += 1

    def title(self, fps: float) -> str:
        y = float(self.scene.reflector.position[1])
        return (f"mirrorlab demo - {self.scene_name} at height {y:.2f} - {self.method} - "
                f"{fps:.0f} fps - H for help")


def run(size: tuple[int, int], angles: Sequence[float], max_frames: int = 0,
        screenshot: Path | None = None,
        save_png: Callable[[Path, np.ndarray], None] | None = None,
        scene: str = "lab", envmap: str = "sphere-texgen", method: str = "ortho") -> int:
    """Open the window and run until Esc, the window closes, or ``max_frames`` frames.

    ``scene`` is ``"lab"`` (the robot and its mirror, drawn with mirror technique
    ``method``; ``envmap`` is unused) or an environment-mapping scene (``"cone"``,
    ``"sphere"``) drawn with technique ``envmap``. With ``screenshot``, the last frame
    drawn is written there by ``save_png``.
    """
    import glfw

    if scene != "lab" and scene not in ENV_SCENES:
        raise ValueError(f"unknown demo scene {scene!r}; expected one of lab, "
                         f"{', '.join(ENV_SCENES)}")
    if scene != "lab":
        check_method(envmap)
    context = WindowContext(size[0], size[1], "mirrorlab demo")
    try:
        if scene == "lab":
            app: DemoApp | EnvDemoApp = DemoApp(context, angles, method)
            help_text = HELP
        else:
            app = EnvDemoApp(context, scene, envmap)
            help_text = ENV_HELP
        print(f"mirrorlab demo on {context.info()['renderer']}. {help_text}", flush=True)
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
        if screenshot is not None and last_image is not None and save_png is not None:
            save_png(screenshot, last_image)
            print(f"wrote {screenshot}", flush=True)
        return 0
    finally:
        context.release()
