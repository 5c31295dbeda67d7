"""The desktop demo: any scene in a glfw window, under the keyboard and the mouse.

The controls are listed in :mod:`mirrorlab.app.controls` (and in the window: H). The
title shows the scene, the reflector the number keys act on and its technique, the
frame's time, the passes it ran and a frame counter. A frame is drawn when something
changed (a key, the mouse, a resize, an animated scene), so an idle demo costs nothing.
"""

from __future__ import annotations

import math
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from mirrorlab.app.controls import CONTROLS
from mirrorlab.app.picking import framebuffer_pixel, pick_reflector
from mirrorlab.gl.context import WindowContext, gl_pass, window_context
from mirrorlab.options import with_technique
from mirrorlab.scene.model import Camera, CurvedReflector, Scene
from mirrorlab.techniques import technique, technique_names

if TYPE_CHECKING:
    from mirrorlab.gl.resources import Texture2D

JOINT_STEP_DEG = 5.0
ZOOM_FACTOR = 1.1
DRAG_DEG_PER_PIXEL = 0.4
REFLECTOR_STEP = 0.25
REFLECTOR_RANGE = 3.0
"""How far (world units) Up/Down may move a curved reflector from where the file puts it."""
IDLE_WAIT_S = 0.5
"""How long an idle demo sleeps in glfw.wait_events_timeout before looking again."""


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
            [math.cos(el) * math.cos(az), math.sin(el), math.cos(el) * math.sin(az)]
        )
        x, y, z = (float(v) for v in np.asarray(self.target) + offset)
        return (x, y, z)


@dataclass
class Changes:
    """What the keys and the mouse changed, applied to the scene each frame: joint
    offsets (degrees; on top of an animation), the lift of the first curved reflector,
    techniques by reflector, and the orbit camera."""

    orbit: Orbit
    joints: list[float] = field(default_factory=lambda: [0.0, 0.0, 0.0])
    lift: float = 0.0
    techniques: dict[str, str] = field(default_factory=dict)


def _first_curved(scene: Scene) -> CurvedReflector | None:
    return next((r for r in scene.reflectors if isinstance(r, CurvedReflector)), None)


class DemoApp:
    """One scene in the window: the scene as the file gives it, the changes the keys and
    the mouse make, the renderer, and what is drawn over the frame."""

    def __init__(self, context: WindowContext, scene: Scene, shot_dir: Path = Path(".")) -> None:
        import glfw

        from mirrorlab.app.overlay import Overlay
        from mirrorlab.renderer import SceneRenderer

        self.context = context
        self.initial = scene
        self.changes = Changes(Orbit.from_eye(scene.camera.eye, scene.camera.target))
        self.configured = scene  # the file's scene with the chosen techniques
        self.shot_dir = shot_dir
        self.renderer = SceneRenderer(context.resources)
        self.overlay = Overlay(context.resources)
        self.frames = 0
        self.dirty = True
        self.show_help = False
        self.show_inset = False
        self.show_mask = False
        self._mask_texture: Texture2D | None = None
        self.save_next = False
        self.print_plan = False
        self.last_ms = 0.0
        self.last_ran: list[str] = []
        self.message = ""
        self._drag_from: tuple[float, float] | None = None
        self._cursor: tuple[float, float] | None = None
        self._size = context.framebuffer_size()
        window = context.window
        glfw.set_key_callback(window, self.on_key)
        glfw.set_scroll_callback(window, self.on_scroll)
        glfw.set_mouse_button_callback(window, self.on_mouse_button)
        glfw.set_cursor_pos_callback(window, self.on_cursor)
        glfw.set_cursor_enter_callback(window, self.on_cursor_enter)
        glfw.set_framebuffer_size_callback(window, lambda *_: self.touch())
        glfw.set_window_refresh_callback(window, lambda *_: self.touch())

    def touch(self) -> None:
        self.dirty = True

    @property
    def animated(self) -> bool:
        return self.initial.animation is not None

    # ------------------------------------------------------------- the scene

    def camera(self, scene: Scene) -> Camera:
        orbit = self.changes.orbit
        return replace(scene.camera, eye=orbit.eye(), target=orbit.target)

    def scene_now(self) -> Scene:
        """The scene to draw this frame: animated, the techniques chosen, the joints and
        the reflector moved, seen from the orbit camera."""
        scene = self.configured.at_frame(self.frames % self.configured.frame_count)
        robot = scene.robot
        if robot is not None and any(self.changes.joints):
            scene = scene.with_angles(
                [a + d for a, d in zip(robot.angles, self.changes.joints, strict=True)]
            )
        curved = _first_curved(scene)
        if curved is not None and self.changes.lift:
            x, y, z = curved.transform.position
            moved = replace(curved.transform, position=(x, y + self.changes.lift, z))
            scene = scene.with_reflector(curved.name, transform=moved)
        return replace(scene, camera=self.camera(scene))

    def turn_joint(self, index: int, delta: float) -> None:
        if self.configured.robot is not None:
            self.changes.joints[index] += delta

    def move_reflector(self, dy: float) -> None:
        if _first_curved(self.configured) is not None:
            lift = self.changes.lift + dy
            self.changes.lift = min(REFLECTOR_RANGE, max(-REFLECTOR_RANGE, lift))

    def target_index(self) -> int | None:
        """The reflector under the mouse, else the first; None for a scene without one."""
        if not self.configured.reflectors:
            return None
        import glfw

        window = self.context.window
        pixel = framebuffer_pixel(self.cursor(), glfw.get_window_size(window), self._size)
        picked = None
        if pixel is not None and min(self._size) > 0:
            picked = pick_reflector(self.scene_now(), self._size, pixel)
        return 0 if picked is None else picked

    def techniques_of(self, index: int) -> tuple[str, ...]:
        reflector = self.configured.reflectors[index]
        return technique_names(reflector.kind)

    def use_technique(self, index: int, name: str) -> None:
        reflector = self.configured.reflectors[index]
        self.configured = with_technique(self.configured, reflector.name, name)
        self.changes.techniques[reflector.name] = name

    def pick_technique(self, number: int) -> None:
        index = self.target_index()
        if index is None:
            return
        names = self.techniques_of(index)
        if number < len(names):
            self.use_technique(index, names[number])

    def next_technique(self) -> None:
        index = self.target_index()
        if index is None:
            return
        names = self.techniques_of(index)
        current = self.configured.reflectors[index].technique
        self.use_technique(index, names[(names.index(current) + 1) % len(names)])

    def reset(self) -> None:
        self.configured = self.initial
        self.changes = Changes(Orbit.from_eye(self.initial.camera.eye, self.initial.camera.target))

    # ------------------------------------------------------------- input

    def on_key(self, window, key: int, scancode: int, action: int, mods: int) -> None:
        import glfw

        if action not in (glfw.PRESS, glfw.REPEAT):
            return
        shift = bool(mods & glfw.MOD_SHIFT)
        joint_keys = {
            glfw.KEY_LEFT: (0, -JOINT_STEP_DEG),
            glfw.KEY_RIGHT: (0, JOINT_STEP_DEG),
            glfw.KEY_UP: (2 if shift else 1, JOINT_STEP_DEG),
            glfw.KEY_DOWN: (2 if shift else 1, -JOINT_STEP_DEG),
            glfw.KEY_PAGE_UP: (2, JOINT_STEP_DEG),
            glfw.KEY_PAGE_DOWN: (2, -JOINT_STEP_DEG),
        }
        number_keys = {glfw.KEY_1 + i: i for i in range(9)}
        number_keys.update({glfw.KEY_KP_1 + i: i for i in range(9)})
        once = action == glfw.PRESS
        if key == glfw.KEY_ESCAPE:
            glfw.set_window_should_close(window, True)
        elif key in (glfw.KEY_EQUAL, glfw.KEY_KP_ADD):
            self.changes.orbit.zoom(1.0 / ZOOM_FACTOR)
        elif key in (glfw.KEY_MINUS, glfw.KEY_KP_SUBTRACT):
            self.changes.orbit.zoom(ZOOM_FACTOR)
        elif key in (glfw.KEY_UP, glfw.KEY_DOWN) and self.configured.robot is None:
            self.move_reflector(REFLECTOR_STEP if key == glfw.KEY_UP else -REFLECTOR_STEP)
        elif key in joint_keys:
            self.turn_joint(*joint_keys[key])
        elif key in number_keys and once:
            self.pick_technique(number_keys[key])
        elif key == glfw.KEY_M and once:
            self.next_technique()
        elif key == glfw.KEY_E and once:
            self.show_inset = not self.show_inset
        elif key == glfw.KEY_X and once:
            self.show_mask = not self.show_mask
        elif key == glfw.KEY_P and once:
            self.print_plan = True
        elif key == glfw.KEY_S and once:
            self.save_next = True
        elif key == glfw.KEY_R and once:
            self.reset()
        elif key == glfw.KEY_H and once:
            self.show_help = not self.show_help
        else:
            return
        self.touch()

    def on_scroll(self, window, dx: float, dy: float) -> None:
        self.changes.orbit.zoom(ZOOM_FACTOR ** (-dy))
        self.touch()

    def cursor(self) -> tuple[float, float]:
        """Where the pointer is, in window coordinates, as the events have told so far."""
        import glfw

        if self._cursor is None:
            self._cursor = glfw.get_cursor_pos(self.context.window)
        return self._cursor

    def on_mouse_button(self, window, button: int, action: int, mods: int) -> None:
        import glfw

        if button == glfw.MOUSE_BUTTON_LEFT:
            # From the last motion event, not a query: a query answers where the pointer
            # is now, which may be ahead of the events still queued.
            self._drag_from = self.cursor() if action == glfw.PRESS else None

    def on_cursor_enter(self, window, entered: int) -> None:
        if not entered:
            self._cursor = (-1.0, -1.0)  # outside: the number keys act on the first reflector

    def on_cursor(self, window, x: float, y: float) -> None:
        self._cursor = (x, y)
        if self._drag_from is not None:
            x0, y0 = self._drag_from
            self.changes.orbit.turn((x - x0) * DRAG_DEG_PER_PIXEL, (y - y0) * DRAG_DEG_PER_PIXEL)
            self._drag_from = (x, y)
            self.touch()

    # ------------------------------------------------------------- frames

    def draw(self) -> np.ndarray | None:
        """Render one frame (and what goes over it) into the back buffer; returns the
        frame as ``(h, w, 3)`` uint8 when a screenshot was asked for."""
        from mirrorlab.gl.opengl import GL
        from mirrorlab.gl.resources import DefaultFramebuffer

        self._size = size = self.context.framebuffer_size()
        if size[0] == 0 or size[1] == 0:  # minimised
            return None
        target = DefaultFramebuffer(lambda: size)  # one size for the whole frame
        began = time.perf_counter()
        scene = self.scene_now()
        stats = self.renderer.render(scene, target)
        with gl_pass("demo overlay"):
            self.draw_overlay(scene, stats, size)
            GL.glFinish()  # the frame's time includes the rasterising, not only the calls
        self.last_ms = (time.perf_counter() - began) * 1e3
        self.last_ran = stats.ran
        self.frames += 1
        if self.print_plan:
            self.print_plan = False
            self.report_plan(scene, stats, size)
        image = None
        if self.save_next:
            self.save_next = False
            with gl_pass("reading the frame back"):
                image = target.read()
        return image

    def read_frame(self) -> np.ndarray:
        """The back buffer as ``(h, w, 3)`` uint8 (the frame just drawn, before the swap)."""
        from mirrorlab.gl.resources import DefaultFramebuffer

        size = self._size
        return DefaultFramebuffer(lambda: size).read()

    def scale(self) -> float:
        """Framebuffer pixels per window unit (2 on a high-DPI screen)."""
        import glfw

        width, _ = glfw.get_window_size(self.context.window)
        return self._size[0] / width if width > 0 else 1.0

    def draw_overlay(self, scene: Scene, stats, size: tuple[int, int]) -> None:
        scale = self.scale()
        margin = round(8 * scale)
        if self.show_mask:
            self.draw_mask(stats, size, scale, margin)
        if self.show_inset:
            self.draw_inset(scene, stats, size, scale, margin)
        if self.show_help:
            lines: list = [
                f"mirrorlab demo: {scene.name} (the title shows the technique, "
                f"frame time and passes)",
                "",
                *CONTROLS,
            ]
            index = self.target_index()
            if index is not None:
                names = "  ".join(f"{i + 1} {n}" for i, n in enumerate(self.techniques_of(index)))
                lines += ["", f"techniques of {scene.reflectors[index].name}: {names}"]
            self.overlay.text("help", lines, (margin, margin), size, scale)

    def draw_mask(self, stats, size: tuple[int, int], scale: float, margin: int) -> None:
        """Screen-space reflections' miss mask of the frame over the whole window: white
        where a reflector pixel's ray was found on the screen (grey as it fades into the
        probe), a colour for each reason it fell back to the probe, black elsewhere."""
        from mirrorlab.gl.resources import Texture2D
        from mirrorlab.passes.ssr import frame_mask
        from mirrorlab.screen_space import REASONS

        mask = frame_mask(self.renderer, stats.plan.top)
        if self._mask_texture is not None:
            self._mask_texture.release()
        texture = self._mask_texture = Texture2D(
            self.context.resources, size[0], size[1], mask.image(), mipmaps=False, clamp=True
        )
        self.overlay.texture(texture, (0, 0), size, size)
        if mask.reflector.any():
            counts = mask.counts()
            pixels = int(mask.reflector.sum())
            lines = [
                f"miss mask: {100 * mask.miss_share:.1f}% of {pixels} reflector pixels fell "
                "back to the probe",
                ", ".join(f"{reason} {counts[reason]}" for reason in REASONS[1:] if counts[reason]),
            ]
        else:
            lines = ["miss mask: no reflector drawn by ssr (M picks a technique)"]
        self.overlay.text(
            "mask", lines, (margin, size[1] - margin - 20 * scale * len(lines)), size, scale
        )

    def draw_inset(
        self, scene: Scene, stats, size: tuple[int, int], scale: float, margin: int
    ) -> None:
        """The target reflector's texture as the camera's view used it, in the bottom
        left corner: a planar capture, a sphere or latitude-longitude map, or a cube
        map's six faces."""
        from mirrorlab.gl.resources import TextureCube

        index = self.target_index()
        label = "no reflector in this scene"
        texture = None
        if index is not None:
            reflector = scene.reflectors[index]
            draw = next(
                (d for d in stats.plan.top.draws if d.reflector.name == reflector.name), None
            )
            label = f"{reflector.name} ({reflector.technique})"
            texture = None if draw is None else self.renderer.shown_texture(draw)
            if texture is None:
                inline = technique(reflector.technique).draws_inline
                why = (
                    "drawn straight into the frame"
                    if inline
                    else (draw.reason if draw is not None else "not drawn")
                )
                label += f": no texture ({why})"
        width, height = size
        if isinstance(texture, TextureCube):
            face = min((width - 2 * margin) / 6 - 2, height / 4)
            top = height - margin - face
            self.overlay.cube_faces(texture, (margin, top), face, size)
            label += f": cube map, {texture.size} a face; +X -X +Y -Y +Z -Z"
        elif texture is not None:
            box = min(width, height) * 0.4
            aspect = texture.width / texture.height
            inset = (box, box / aspect) if aspect >= 1.0 else (box * aspect, box)
            top = height - margin - inset[1]
            self.overlay.texture(texture, (margin, top), inset, size)
            label += f": {texture.width}x{texture.height}"
            face = inset[1]
        else:
            face = 0.0
        self.overlay.text(
            "label", [label], (margin, height - margin - face - 24 * scale), size, scale
        )

    def report_plan(self, scene: Scene, stats, size: tuple[int, int]) -> None:
        print(f"plan of frame {self.frames} ({scene.name}, {size[0]}x{size[1]}):")
        for line in stats.plan.describe():
            print(f"  {line}")
        print(f"live GL objects: {len(self.context.resources)}", flush=True)

    def save(self, image: np.ndarray) -> None:
        from mirrorlab.errors import WriteError
        from mirrorlab.files import write_png_atomic

        number = 1
        while (path := self.shot_dir / f"demo-{self.initial.name}-{number:03d}.png").exists():
            number += 1
        try:
            write_png_atomic(path, image)
        except WriteError as exc:
            self.message = str(exc)
            print(f"mirrorlab demo: {exc}", file=sys.stderr, flush=True)
        else:
            self.message = f"saved {path}"
            print(f"saved {path}", flush=True)

    def status(self, scene: Scene) -> str:
        parts = []
        robot = scene.robot
        if robot is not None:
            base, lower, upper = robot.angles
            parts.append(f"base {base:.0f} lower {lower:.0f} upper {upper:.0f} deg")
        curved = _first_curved(scene)
        if robot is None and curved is not None:
            parts.append(f"height {curved.transform.position[1]:.2f}")
        index = self.target_index()
        if index is not None:
            reflector = scene.reflectors[index]
            parts.append(f"{reflector.name}: {reflector.technique}")
        x, y, z = scene.camera.eye
        parts.append(f"eye {x:.2f},{y:.2f},{z:.2f}")
        parts.append(f"{self.last_ms:.1f} ms")
        parts.append(" + ".join(self.last_ran))
        return " - ".join(parts)

    def title(self, scene: Scene) -> str:
        message = f" - {self.message}" if self.message else ""
        return (
            f"mirrorlab demo - {scene.name} - {self.status(scene)} - frame {self.frames}"
            f"{message} - H: help"
        )

    def release(self) -> None:
        if self._mask_texture is not None:
            self._mask_texture.release()
            self._mask_texture = None
        self.overlay.release()
        self.renderer.release()


def run(
    scene: Scene,
    size: tuple[int, int],
    max_frames: int = 0,
    screenshot: Path | None = None,
    debug: bool = False,
    shot_dir: Path = Path("."),
) -> int:
    """Open the window on ``scene`` and run until Esc, the window closes, or ``max_frames``
    frames; with ``screenshot``, the last frame drawn is written there as a PNG. S saves
    screenshots into ``shot_dir``."""
    import glfw

    from mirrorlab.files import write_png_atomic

    context = window_context(size[0], size[1], f"mirrorlab demo - {scene.name}", debug=debug)
    app = None
    try:
        app = DemoApp(context, scene, shot_dir)
        print(
            f"mirrorlab demo of {scene.name} on {context.info()['renderer']}: press H in "
            f"the window for the controls (also: mirrorlab demo --help).",
            flush=True,
        )
        last_image = None
        continuous = app.animated or max_frames > 0
        while not context.should_close():
            if continuous or app.dirty:
                glfw.poll_events()
            else:
                glfw.wait_events_timeout(IDLE_WAIT_S)
            if not (continuous or app.dirty) or context.should_close():
                continue
            app.dirty = False
            image = app.draw()
            if screenshot is not None:
                with gl_pass("reading the frame back"):
                    last_image = app.read_frame() if image is None else image
            context.swap_buffers()
            if image is not None:
                app.save(image)
            glfw.set_window_title(context.window, app.title(app.scene_now()))
            if max_frames and app.frames >= max_frames:
                break
        if screenshot is not None and last_image is not None:
            write_png_atomic(screenshot, last_image)
            print(f"wrote {screenshot}", flush=True)
        return 0
    finally:
        if app is not None:
            context.make_current()
            app.release()
        context.release()
