"""Cost at scale: what a frame costs when a scene holds many objects or many mirrors,
seen and unseen, against the same frame without them, side by side in one run.

``mirrorlab bench speed --parts scale`` times these scenes (with pyrender's flat frame of
those without mirrors beside them, given ``--pyrender``). The base scene is the lab's,
with its mirror made ``reflected``: the robot, the mirror's frame and one mirror
captured for the viewer. Added to it:

- ``N mirrors unseen``: N small ``reflected`` mirrors on a grid behind the camera, facing
  the scene (so the viewer is on their reflecting side): the frame is the base frame;
- ``N mirrors seen``: N small ``reflected`` mirrors on a grid across the view, facing the
  camera; each is captured in the first frame, then reused;
- ``N objects unseen``: N small boxes on a grid behind the camera: the frame is the base
  frame;
- ``N objects seen``: N small boxes on a grid across the view;
- ``N tiny objects seen``: the same grid of boxes a fiftieth of a unit across, most
  covering no pixel.

Frames are ``still`` (the same scene every frame, as a program showing a scene that
stands still draws them) or ``moving`` (the camera moves a hair every frame, so every
frame is planned and its reflected captures run again). Every frame is drawn with
:class:`mirrorlab.Renderer` (one a variant, as a program drawing that scene would keep
it) and read back to numpy.
The variants take turns in blocks of frames, the order rotating every round; each one's
median is divided by the base frame's median measured in the same run.
"""

from __future__ import annotations

import statistics
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from mirrorlab.errors import BenchmarkError

if TYPE_CHECKING:
    from mirrorlab.scene.model import Scene

BOX_SIZE = 0.3
TINY_BOX_SIZE = 0.02
MIRROR_SIZE = 0.5
MOVE = 1e-5
"""How far (scene units) the camera moves each frame in the ``moving`` mode: a new place
every frame, so nothing recorded for an earlier view is drawn again."""


def log(message: str) -> None:
    print(f"[scale] {message}", file=sys.stderr, flush=True)


# --------------------------------------------------------------------------- scenes


def base_scene():
    """The lab scene with a ``reflected`` mirror: robot, mirror frame, one mirror."""
    import mirrorlab
    from mirrorlab.options import apply_options

    return apply_options(mirrorlab.load_scene("lab20"), {"method": "reflected"})


def _camera_frame(scene) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, float]:
    """The camera's eye, unit forward, right and up ``(3,)`` and distance to its target."""
    camera = scene.camera
    eye = np.asarray(camera.eye, dtype=np.float64)
    target = np.asarray(camera.target, dtype=np.float64)
    forward = target - eye
    distance = float(np.linalg.norm(forward))
    forward /= distance
    right = np.cross(forward, np.asarray(camera.up, dtype=np.float64))
    right /= np.linalg.norm(right)
    up = np.cross(right, forward)
    return eye, forward, right, up, distance


def grid(
    count: int,
    center: np.ndarray,
    right: np.ndarray,
    up: np.ndarray,
    half_width: float,
    half_height: float,
) -> np.ndarray:
    """``(count, 3)`` points on a near-square grid across a rectangle."""
    columns = int(np.ceil(np.sqrt(count * half_width / half_height)))
    rows = int(np.ceil(count / columns))
    points = []
    for index in range(count):
        row, column = divmod(index, columns)
        u = (column + 0.5) / columns * 2.0 - 1.0
        v = (row + 0.5) / rows * 2.0 - 1.0
        points.append(center + u * half_width * right + v * half_height * up)
    return np.array(points)


def _points(scene, count: int, seen: bool) -> tuple[np.ndarray, np.ndarray]:
    """Grid points in view (on the plane through the camera's target, across 80% of the
    view) or behind the camera (6 units back), and the unit direction they face."""
    eye, forward, right, up, distance = _camera_frame(scene)
    if seen:
        half_height = 0.8 * distance * np.tan(np.radians(scene.camera.fovy / 2.0))
        return grid(count, eye + distance * forward, right, up, half_height, half_height), -forward
    return grid(count, eye - 6.0 * forward, right, up, 10.0, 5.0), forward


def with_mirrors(scene, count: int, seen: bool):
    """``scene`` with ``count`` small ``reflected`` mirrors (see the module's docstring)."""
    from mirrorlab.scene.model import PlanarReflector

    points, normal = _points(scene, count, seen)
    _, _, right, up, _ = _camera_frame(scene)
    if not seen:
        right = -right  # corners counter-clockwise seen from the reflecting side
    half = MIRROR_SIZE / 2.0
    mirrors = tuple(
        PlanarReflector(
            name=f"extra_mirror_{index}",
            technique="reflected",
            corners=tuple(  # type: ignore[arg-type]
                tuple(float(v) for v in point + a * half * right + b * half * up)
                for a, b in ((-1, -1), (1, -1), (1, 1), (-1, 1))
            ),
        )
        for index, point in enumerate(points)
    )
    for made in mirrors[:1]:
        assert made.normal @ normal > 0.99, "a mirror faces the wrong way"
    return replace(scene, reflectors=scene.reflectors + mirrors)


def box_mesh() -> Path:
    from mirrorlab.data import data_path

    return data_path("models") / "hand.obj"


def with_boxes(scene, count: int, seen: bool, size: float):
    """``scene`` with ``count`` boxes of side about ``size``."""
    from mirrorlab.scene.model import MeshObject, Transform

    points, _ = _points(scene, count, seen)
    colors = ((0.8, 0.3, 0.2), (0.2, 0.7, 0.3), (0.25, 0.35, 0.85))
    boxes = tuple(
        MeshObject(
            name=f"box_{index}",
            mesh=box_mesh(),
            color=colors[index % len(colors)],
            transform=Transform(
                position=(float(point[0]), float(point[1]), float(point[2])),
                scale=(size, size, size),
            ),
        )
        for index, point in enumerate(points)
    )
    return replace(scene, objects=scene.objects + boxes)


def scale_scenes(object_counts: list[int], mirror_counts: list[int]) -> dict[str, Scene]:
    """Every variant's scene by name, the base first."""
    base = base_scene()
    scenes: dict[str, Scene] = {"base": base}
    for count in mirror_counts:
        scenes[f"{count} mirrors unseen"] = with_mirrors(base, count, seen=False)
    for count in mirror_counts:
        scenes[f"{count} mirrors seen"] = with_mirrors(base, count, seen=True)
    for count in object_counts:
        scenes[f"{count} objects unseen"] = with_boxes(base, count, False, BOX_SIZE)
    for count in object_counts:
        scenes[f"{count} objects seen"] = with_boxes(base, count, True, BOX_SIZE)
    for count in object_counts:
        scenes[f"{count} tiny objects seen"] = with_boxes(base, count, True, TINY_BOX_SIZE)
    return scenes


def moved_camera(scene, step: int):
    """``scene`` with its camera moved ``step * MOVE`` along x."""
    camera = scene.camera
    eye = (camera.eye[0] + step * MOVE, camera.eye[1], camera.eye[2])
    return replace(scene, camera=replace(camera, eye=eye))


# --------------------------------------------------------------------------- timing


@dataclass
class Variant:
    name: str
    frames: Callable[[int], list[float]]
    blocks: list[list[float]] = field(default_factory=list)
    """The ms of the timed frames, one list a round of :func:`interleave`."""

    @property
    def samples(self) -> list[float]:
        """Every timed frame's ms."""
        return [ms for block in self.blocks for ms in block]


def timed_frames(
    renderer, scene_of_turn: Callable[[int], Scene], size: int
) -> Callable[[int], list[float]]:
    """``count`` frames -> their ms: frame n of the variant draws ``scene_of_turn(n)`` with
    ``renderer`` (a :class:`mirrorlab.Renderer`) at ``size`` x ``size``, read back."""
    turn = [0]

    def frames(count: int) -> list[float]:
        times = []
        for _ in range(count):
            frame = scene_of_turn(turn[0])
            turn[0] += 1
            start = time.perf_counter()
            renderer.render(frame, size=(size, size))
            times.append((time.perf_counter() - start) * 1e3)
        return times

    return frames


def mirrorlab_frames(
    renderer, scene: Scene, size: int, moving: bool
) -> Callable[[int], list[float]]:
    """Frames of ``scene``, its camera moved a hair further every frame when ``moving``."""
    return timed_frames(
        renderer, (lambda turn: moved_camera(scene, turn)) if moving else (lambda turn: scene), size
    )


def interleave(variants: list[Variant], frames: int, warmup: int, block: int) -> None:
    """Warm every variant up, then run blocks in rotating order until each has ``frames``."""
    for variant in variants:
        variant.frames(warmup)
    turn = 0
    while min(len(v.samples) for v in variants) < frames:
        shift = turn % len(variants)
        for variant in variants[shift:] + variants[:shift]:
            variant.blocks.append(variant.frames(block))
        turn += 1


def paired_ratio(blocks: list[list[float]], base_blocks: list[list[float]]) -> float:
    """How many times a base frame another takes, from their frame times in ms, one list a
    round of blocks taken in turn (:attr:`Variant.blocks` after :func:`interleave`): the
    median over the rounds of the ratio of their medians in that round.

    The two variants' blocks of a round run within milliseconds of each other; the
    machine's speed changes by as much as twice within a run (a shared virtual machine),
    and a burst of other work can slow one block. Pairing by round leaves both out, where
    the ratio of the whole runs' medians keeps them: nine renderers drawing the same frame
    came out 0.81x to 1.72x of one another by their medians, 0.93x to 1.09x paired."""
    return statistics.median(
        statistics.median(ours) / statistics.median(theirs)
        for ours, theirs in zip(blocks, base_blocks, strict=True)
    )


MOVING_SEEN_MIRRORS = 100
"""With the camera moving, every seen mirror is captured again every frame: seen-mirror
scenes of more than this many are left out of the moving frames (400 take seconds a
frame)."""


def mirrorlab_variants(
    stack, scenes: dict[str, Scene], size: int, modes: tuple[str, ...] = ("still",)
) -> list[Variant]:
    """A :class:`Variant` of every scene in every mode (``still``, ``moving``), each with a
    renderer of its own (entered on ``stack``); an unseen scene's first frame is checked to
    be the base frame, pixel for pixel."""
    import mirrorlab

    base_image = None
    variants = []
    for mode in modes:
        for name, scene in scenes.items():
            count = int(name.split()[0]) if name[0].isdigit() else 0
            if mode == "moving" and "mirrors seen" in name and count > MOVING_SEEN_MIRRORS:
                continue
            renderer = stack.enter_context(mirrorlab.Renderer((size, size)))
            started = time.perf_counter()
            image = renderer.render(scene)
            log(
                f"{name}: first frame {(time.perf_counter() - started) * 1e3:.0f} ms, "
                f"passes {len(renderer.last_stats.ran)}"
            )
            if name == "base":
                base_image = image
            elif name.endswith("unseen") and (
                base_image is None or not np.array_equal(image, base_image)
            ):
                raise BenchmarkError(f"{name}: the frame differs from the base frame")
            variants.append(
                Variant(
                    f"mirrorlab {mode}, {name}",
                    mirrorlab_frames(renderer, scene, size, mode == "moving"),
                )
            )
    return variants
