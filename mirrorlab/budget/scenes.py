"""Scenes and motion for the budget's calibration and benchmark.

:func:`calibration_scene` makes the scenes the predictions are calibrated on: a class of
scene, not a list of files. Each is drawn at random (from a seed) from what mirrorlab's
users build: one reflector (a rectangular planar mirror, or a sphere of the shipped
sphere mesh) among the shipped meshes, placed, turned, scaled, coloured and textured at
random, on a floor or not, under the procedural sky, six cube faces or a plain colour,
or in a closed room of textured walls; seen from a random place in front of the
reflector, from close to far, from head-on to grazing, with a random lens and frame
size. The benchmark's held-out scenes (``bench/budget_scenes/``) are written by hand, of
other shapes (a cone, an egg, non-rectangular mirrors, a mirror on the floor, two
mirrors), and nothing here reads them.

:func:`motion` poses a scene for each frame of a benchmark sequence: the camera swings
around its target, moving in and out and up and down; objects drift and bob, robots wave;
planar mirrors turn; curved reflectors float. ``still`` poses every frame alike.

Numpy only.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import Any, Literal

import numpy as np

from mirrorlab.data import data_path, model_file, texture_file
from mirrorlab.scene.loader import from_document
from mirrorlab.scene.model import (
    Camera,
    CurvedReflector,
    MeshObject,
    PlanarReflector,
    RobotObject,
    Scene,
    Transform,
)

OBJECT_MESHES = ("hand", "joint", "lower_arm", "upper_arm", "base", "cone", "backdrop")
"""The shipped meshes calibration scenes place as objects (and the robot)."""
STILL_MESHES = ("panel", "backdrop")
"""Meshes (walls, floors, backdrops) that stay put in a moving sequence."""
FRAME_SIZES = (96, 128, 160, 192, 256)
BACKGROUND_COLOURS = ((0.16, 0.18, 0.22), (0.05, 0.05, 0.08), (0.3, 0.22, 0.15))
"""The plain backgrounds (few: a static map baked from one is kept for the next)."""
"""Frame sides calibration samples are drawn at."""

ReflectorKind = Literal["planar", "curved"]


def calibration_scene(seed: int, kind: ReflectorKind) -> tuple[Scene, tuple[int, int]]:
    """A random scene of the calibration class with one reflector of ``kind``, and the
    frame size to draw it at; the same for the same ``seed``."""
    rng = np.random.default_rng([seed, 0 if kind == "planar" else 1])
    document: dict[str, Any] = {"name": f"calibration-{kind}-{seed}", "max_bounces": 1}
    setting = rng.choice(["sky", "cube", "color", "room"], p=[0.35, 0.15, 0.2, 0.3])
    room = setting == "room"
    half = float(rng.uniform(3.0, 7.0))  # half the size of the room, or of the stage
    if setting == "sky":
        document["background"] = {"sky": "procedural"}
    elif setting == "cube":
        document["background"] = {"cube_faces": str(data_path("textures", "sky_cube"))}
    else:
        document["background"] = {"color": list(BACKGROUND_COLOURS[int(rng.integers(3))])}
    document["ambient"] = float(rng.uniform(0.2, 0.5))
    document["lights"] = [
        {"direction": _unit(rng, up=True).tolist(), "intensity": float(rng.uniform(0.4, 0.8))}
    ]
    objects: list[dict[str, Any]] = []
    floor = -float(rng.uniform(1.0, 2.5))
    if room:
        objects += _room(rng, half, floor)
    elif rng.random() < 0.6:
        objects.append(_panel(rng, "floor", (0.0, floor, 0.0), (-90.0, 0.0, 0.0), 4 * half))
    reflector = _planar(rng) if kind == "planar" else _curved(rng)
    document["reflectors"] = [reflector]
    center, size = _reflector_place(reflector)
    camera = _camera(rng, reflector, center, size, half if room else None, floor)
    document["camera"] = camera
    eye = np.array(camera["eye"])
    for i in range(int(rng.integers(1, 8))):
        objects.append(_object(rng, i, center, size, half, floor, eye))
    document["objects"] = objects
    frame = int(rng.choice(FRAME_SIZES))
    scene = from_document(document)
    return scene, (frame, frame)


def _colour(rng: np.random.Generator, dark: bool = False) -> list[float]:
    top = 0.35 if dark else 1.0
    return [float(v) for v in rng.uniform(0.05, top, 3)]


def _unit(rng: np.random.Generator, up: bool = False) -> np.ndarray:
    v = rng.normal(size=3)
    if up:
        v[1] = abs(v[1]) + 0.3
    return v / np.linalg.norm(v)


def _panel(
    rng: np.random.Generator, name: str, position, rotation, scale: float, height: float = 0.0
) -> dict[str, Any]:
    return {
        "name": name,
        "mesh": str(model_file("panel")),
        "texture": str(texture_file("wall" if rng.random() < 0.7 else "metal")),
        "color": _colour(rng),
        "position": [float(v) for v in position],
        "rotation": [float(v) for v in rotation],
        "scale": [float(scale), float(height or scale), 1.0],
    }


def _room(rng: np.random.Generator, half: float, floor: float) -> list[dict[str, Any]]:
    """Six walls around the stage, facing in."""
    top = floor + 2.0 * half
    middle = (floor + top) / 2.0
    side = 2.0 * half
    return [
        _panel(rng, "floor", (0, floor, 0), (-90, 0, 0), side),
        _panel(rng, "ceiling", (0, top, 0), (90, 0, 0), side),
        _panel(rng, "back", (0, middle, -half), (0, 0, 0), side),
        _panel(rng, "front", (0, middle, half), (0, 180, 0), side),
        _panel(rng, "left", (-half, middle, 0), (0, 90, 0), side),
        _panel(rng, "right", (half, middle, 0), (0, -90, 0), side),
    ]


def _planar(rng: np.random.Generator) -> dict[str, Any]:
    normal = rng.normal(size=3)
    normal[1] *= 0.5
    if rng.random() < 0.2:  # a mirror lying on the floor, facing up
        normal = np.array([rng.normal() * 0.1, 1.0, rng.normal() * 0.1])
    normal /= np.linalg.norm(normal)
    up = [0.0, 1.0, 0.0] if abs(normal[1]) < 0.9 else [0.0, 0.0, 1.0]
    return {
        "name": "mirror",
        "technique": "reflected",
        "center": rng.uniform(-0.5, 0.5, 3).tolist(),
        "normal": normal.tolist(),
        "width": float(rng.uniform(1.5, 6.0)),
        "height": float(rng.uniform(1.5, 6.0)),
        "up": up,
    }


def _curved(rng: np.random.Generator) -> dict[str, Any]:
    return {
        "name": "sphere",
        "technique": "cube-live",
        "mesh": str(model_file("env_sphere")),
        "position": rng.uniform(-0.5, 0.5, 3).tolist(),
        "scale": float(rng.uniform(0.4, 1.8)),
        "map_size": 256,
    }


def _reflector_place(reflector: dict[str, Any]) -> tuple[np.ndarray, float]:
    """The centre of a reflector's table and half its size."""
    if "center" in reflector:
        return np.array(reflector["center"]), max(reflector["width"], reflector["height"]) / 2
    return np.array(reflector["position"]), float(reflector["scale"])


def _object(
    rng: np.random.Generator,
    i: int,
    center: np.ndarray,
    size: float,
    half: float,
    floor: float,
    eye: np.ndarray,
) -> dict[str, Any]:
    """An object somewhere on the stage, out of the reflector's way and out of the line
    from the eye to it."""
    for _ in range(30):
        place = center + rng.uniform(-half * 0.8, half * 0.8, 3)
        place[1] = floor + float(rng.uniform(0.0, 2.5))
        if np.linalg.norm(place - center) > size + 0.8 and _off_line(place, eye, center, size):
            break
    rotation = [0.0, float(rng.uniform(0, 360)), 0.0]
    if rng.random() < 0.15:
        return {
            "name": f"robot{i}",
            "type": "robot",
            "angles": rng.uniform(-60, 60, 3).tolist(),
            "position": [float(place[0]), floor + 1.0, float(place[2])],
            "rotation": rotation,
            "scale": float(rng.uniform(0.25, 0.6)),
        }
    mesh = str(rng.choice(OBJECT_MESHES))
    entry: dict[str, Any] = {
        "name": f"object{i}",
        "mesh": str(model_file(mesh)),
        "color": _colour(rng),
        "position": place.tolist(),
        "rotation": rotation,
        "scale": float(rng.uniform(0.5, 2.0)),
    }
    if rng.random() < 0.3:
        entry["texture"] = str(texture_file("metal" if rng.random() < 0.5 else "wall"))
    return entry


def _off_line(point: np.ndarray, eye: np.ndarray, center: np.ndarray, size: float) -> bool:
    """Whether ``point`` lies clear of the segment from ``eye`` to ``center``."""
    line = center - eye
    t = float(np.clip((point - eye) @ line / max(line @ line, 1e-12), 0.0, 1.0))
    return float(np.linalg.norm(eye + t * line - point)) > 0.5 * size + 1.0


def _camera(
    rng: np.random.Generator,
    reflector: dict[str, Any],
    center: np.ndarray,
    size: float,
    room: float | None,
    floor: float,
) -> dict[str, Any]:
    """A viewer in front of the reflector: 1.3 to 9 times its size away (inside the room,
    when there is one), 0 to 85 degrees off its normal, looking near its centre."""
    if "normal" in reflector:
        normal = np.array(reflector["normal"])
    else:
        normal = _unit(rng)
    tilt = math.radians(
        float(rng.uniform(0.0, 85.0) if rng.random() < 0.8 else rng.uniform(60, 85))
    )
    side = _unit(rng)
    side -= (side @ normal) * normal
    side /= max(np.linalg.norm(side), 1e-9)
    direction = math.cos(tilt) * normal + math.sin(tilt) * side
    distance = size * float(np.exp(rng.uniform(math.log(1.3), math.log(9.0))))
    if room is not None:
        distance = min(distance, 0.9 * room)
    eye = center + direction * distance
    if room is not None:
        eye = np.clip(eye, -0.9 * room, 0.9 * room)
    eye[1] = max(eye[1], floor + 0.3)
    target = center + rng.normal(size=3) * size * 0.3
    if np.linalg.norm(eye - target) < 1e-3:
        eye = target + normal
    fovy = float(rng.uniform(25.0, 70.0))
    return {
        "eye": eye.tolist(),
        "target": target.tolist(),
        "fovy": fovy,
        "near": 0.05,
        "far": 200.0,
    }


# --------------------------------------------------------------------------- motion

Motion = Literal["moving", "still"]


def motion(scene: Scene, frame: int, frames: int, kind: Motion = "moving") -> Scene:
    """``scene`` posed for ``frame`` of a benchmark sequence of ``frames`` (its own
    animation first, when it has one): with ``kind`` ``moving``, the camera swings up to
    30 degrees either way around its target, moves in and out by a third and up and down;
    mesh objects drift and bob, robots wave; planar mirrors turn by up to 12 degrees
    about their centres; curved reflectors float up and down; ``still``, every frame is
    frame 0."""
    if kind == "still":
        return scene.at_frame(0)
    posed = scene.at_frame(min(frame, scene.frame_count - 1) if scene.animation else 0)
    phase = frame / max(frames - 1, 1)
    wave = math.sin(2.0 * math.pi * phase)
    camera = _swing(posed.camera, phase, wave)
    objects = tuple(_move_object(o, i, wave) for i, o in enumerate(posed.objects))
    reflectors = tuple(_move_reflector(r, i, wave) for i, r in enumerate(posed.reflectors))
    return replace(posed, camera=camera, objects=objects, reflectors=reflectors)


def _swing(camera: Camera, phase: float, wave: float) -> Camera:
    eye = np.array(camera.eye)
    target = np.array(camera.target)
    offset = eye - target
    angle = math.radians(30.0) * math.sin(2.0 * math.pi * phase * 0.5 + 0.3) - math.radians(9)
    turn = np.array(
        [
            [math.cos(angle), 0.0, math.sin(angle)],
            [0.0, 1.0, 0.0],
            [-math.sin(angle), 0.0, math.cos(angle)],
        ]
    )
    offset = turn @ offset * (1.0 + 0.33 * wave)
    offset[1] += 0.15 * np.linalg.norm(offset) * math.cos(2.0 * math.pi * phase)
    new_eye = target + offset
    return replace(camera, eye=tuple(float(v) for v in new_eye))  # type: ignore[arg-type]


def _move_object(item, index: int, wave: float):
    if isinstance(item, RobotObject):
        base, lower, upper = item.angles
        return replace(item, angles=(base + 40.0 * wave, lower + 15.0 * wave, upper - 25.0 * wave))
    assert isinstance(item, MeshObject)
    if item.mesh.stem in STILL_MESHES:
        return item  # walls and floors stay
    x, y, z = item.transform.position
    drift = 0.6 * wave * (1 if index % 2 else -1)
    moved = Transform(
        (x + drift, y + 0.3 * abs(wave), z), item.transform.rotation, item.transform.scale
    )
    return replace(item, transform=moved)


def _move_reflector(reflector, index: int, wave: float):
    if isinstance(reflector, PlanarReflector):
        return reflector.moved(rotation=(0.0, 12.0 * wave, 4.0 * wave))
    assert isinstance(reflector, CurvedReflector)
    x, y, z = reflector.transform.position
    transform = replace(reflector.transform, position=(x, y + 0.4 * wave, z))
    return replace(reflector, transform=transform)
