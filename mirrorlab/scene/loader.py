"""Scene files: TOML to :class:`~mirrorlab.scene.model.Scene` and back.

A scene file is read with :mod:`tomllib` into a plain document (nested dicts and lists),
checked key by key, and turned into a Scene. Every problem is a :class:`SceneError`
whose one-line message names the file, the key path (``reflectors[1].corners``) and what
was expected. :func:`scene_to_document` and :func:`dumps` write a Scene back; reading
that again gives an equal Scene.

File names in a scene (meshes, textures, cube-face folders) are relative to the scene
file's folder. The format is described key by key in docs/scenes.md.
Numpy only.
"""

from __future__ import annotations

import difflib
import functools
import json
import math
import re
import tomllib
from collections.abc import Callable, Mapping
from dataclasses import replace
from pathlib import Path
from typing import Any, Literal

import numpy as np

from mirrorlab.data import scenes_dir
from mirrorlab.scene.animation import (
    CAMERA_FIELDS,
    OBJECT_FIELDS,
    PLANAR_FIELDS,
    REFLECTOR_FIELDS,
)
from mirrorlab.scene.backgrounds import CUBE_FACE_FILES
from mirrorlab.scene.model import (
    CAPTURE_MODES,
    DEFAULT_BACKING,
    DEFAULT_PLAIN_COLOR,
    FOOTPRINT_TEXTURE,
    PARALLAX_PROXIES,
    SSR_NO_PROBE,
    Animation,
    Background,
    BoxProxy,
    Camera,
    CurvedReflector,
    DistanceSearch,
    Keyframe,
    Light,
    MeshObject,
    OrthoCapture,
    Parallax,
    PlanarReflector,
    RobotObject,
    Scene,
    ScreenSpace,
    SphereProxy,
    Transform,
)
from mirrorlab.techniques import (
    Technique,
    names_where,
    reflector_technique_names,
    technique,
    techniques,
)

"""The shipped scene files."""
DEFAULT_SCENE = "lab20"
SCENE_ALIASES = {"lab": "lab20", "cone": "spheremap_cone", "sphere": "chrome_sphere"}
"""Short names kept from before scenes were files."""
MAX_LIGHTS = 4
"""Directional lights the scene shader takes."""
MAX_BOUNCES = 6
MAX_MAP_SIZE = 4096
MAX_FRAMES = 100_000
MAX_SEARCH_STEPS = 64
"""Most linear-search steps (and secant steps) a distance-search lookup may take."""
MAX_MAGNITUDE = 1e6
"""Largest magnitude of any number in a scene: GL computes in 32-bit floats, which keep
about 7 digits, so beyond a million units a scene has no precision left (and beyond 3.4e38
no value at all)."""

MIN_FOVY = 0.01
"""Narrowest vertical field of view, in degrees. GL places a vertex in 32-bit floats
(about 7 digits) relative to the eye. Their rounding, seen through a view this narrow,
is about a fifth of a pixel of a 512-pixel frame (1.4 pixels of a 4096-pixel one), and
grows as the view narrows; below about 1e-36 degrees the projection overflows them."""

MAX_DEPTH_RATIO = 1e7
"""Largest ``far / near`` of a camera. The depth buffer keeps 24 bits of ``1 - near /
distance`` (roughly), so the farther part of a range is lost to its last step: the
farthest 0.6% of a range of 1e5, 6% of 1e6, a third of 1e7, and beyond that most of it,
everything at 1e30 (where the ray tracer's inverse of the projection fails as well)."""

_TOP_KEYS = (
    "name",
    "description",
    "max_bounces",
    "ambient",
    "camera",
    "background",
    "lights",
    "objects",
    "reflectors",
    "animation",
)
_CAMERA_KEYS = ("eye", "target", "up", "fovy", "near", "far")
_BACKGROUND_SOURCES = ("color", "sky", "cube_faces", "sphere_map")
_LIGHT_KEYS = ("direction", "intensity", "color")
_TRANSFORM_KEYS = ("position", "rotation", "scale")
_MESH_KEYS = ("name", "type", "mesh", *_TRANSFORM_KEYS, "color", "texture")
_ROBOT_KEYS = ("name", "type", "angles", *_TRANSFORM_KEYS)
_PLANAR_KEYS = (
    "name",
    "technique",
    "corners",
    "center",
    "normal",
    "width",
    "height",
    "up",
    "capture",
    "texture_size",
    "ortho",
    "color",
    "backing",
    "map_size",
    "source",
    "capture_center",
    "parallax",
    "ssr",
)
_PLANAR_MAP_KEYS = ("map_size", "source", "capture_center", "parallax")
"""A planar mirror's keys for the map of a technique that falls back to one (``ssr``)."""
_SSR_KEYS = ("probe", "stride", "steps", "thickness", "max_distance", "refine", "edge_fade")
_CURVED_KEYS = (
    "name",
    "technique",
    "mesh",
    *_TRANSFORM_KEYS,
    "map_size",
    "source",
    "capture_center",
    "color",
    "parallax",
    "ssr",
)
_PARALLAX_KEYS = {
    "box": ("min", "max"),
    "sphere": ("radius",),
    "distance": ("steps", "secant", "thickness"),
}
"""The keys of each proxy in a ``parallax`` table, besides ``proxy``."""
_ORTHO_KEYS = ("eye", "target", "up", "extents")
_KEYFRAME_KEYS = ("frame", "camera", "objects", "reflectors")


class SceneError(ValueError):
    """A scene file, or a change to a scene, that cannot be used: ``file``, ``key`` (a key
    path such as ``reflectors[1].corners``, empty for the whole file) and ``problem``."""

    def __init__(self, file: str, key: str, problem: str) -> None:
        self.file, self.key, self.problem = file, key, problem
        where = f"{file}: {key}" if key else file
        super().__init__(_one_line(f"{where}: {problem}"))


def _one_line(text: str) -> str:
    """``text`` with line breaks and other control characters (from file names or keys
    in the file) written as escapes, so that a message stays one line."""
    if text.isprintable():
        return text
    return "".join(c if c.isprintable() or c == " " else repr(c)[1:-1] for c in text)


# --------------------------------------------------------------------------- reading


def scene_path(name_or_path: str | Path) -> Path:
    """The file a scene name stands for: a path to a file as it is, or a shipped scene's
    name (``lab20``, or a short name ``lab``/``cone``/``sphere``). SceneError when there
    is no such file."""
    text = str(name_or_path)
    candidate = Path(text)
    if candidate.suffix == ".toml" or _is_file(candidate) or "/" in text:
        if not _is_file(candidate):
            raise SceneError(text, "", "no such scene file")
        return candidate
    stem = SCENE_ALIASES.get(text, text)
    shipped = scenes_dir() / f"{stem}.toml"
    if _is_file(shipped):
        return shipped
    raise SceneError(
        text,
        "",
        f"unknown scene; expected a .toml file or one of {', '.join(shipped_scene_names())}",
    )


@functools.cache
def mesh_formats() -> frozenset[str]:
    """The file types trimesh reads meshes from (``obj``, ``glb``, ``ply``, ...), by name."""
    import trimesh

    return frozenset(trimesh.available_formats())


def _is_file(path: Path) -> bool:
    """``path.is_file()``, False where the name cannot be a file at all (too long, say)."""
    try:
        return path.is_file()
    except (OSError, ValueError):
        return False


def _is_dir(path: Path) -> bool:
    try:
        return path.is_dir()
    except (OSError, ValueError):
        return False


def shipped_scene_names() -> list[str]:
    """Names of the shipped scene files (package data), and the short names."""
    names = sorted(p.stem for p in scenes_dir().glob("*.toml"))
    return names + sorted(SCENE_ALIASES)


def load_scene(name_or_path: str | Path) -> Scene:
    """Read a scene file (or a shipped scene by name); SceneError on any problem."""
    path = scene_path(name_or_path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise SceneError(str(path), "", f"cannot be read ({exc})") from None
    return loads(text, path)


def loads(text: str, source: Path | str | None = None) -> Scene:
    """A scene from TOML ``text``; ``source`` names the file for messages and relative
    paths (None: ``<string>``, paths relative to the working folder)."""
    label = str(source) if source is not None else "<string>"
    try:
        document = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(label, "", f"not valid TOML ({exc})") from None
    except (ValueError, RecursionError) as exc:
        raise SceneError(label, "", f"not valid TOML ({exc})") from None
    return from_document(document, Path(source) if source is not None else None)


def from_document(document: Mapping[str, Any], source: Path | None = None) -> Scene:
    """A scene from a TOML document (nested dicts and lists, as :mod:`tomllib` gives)."""
    return _Reader(source).scene(document)


# --------------------------------------------------------------------------- writing


def scene_to_document(scene: Scene, base: Path | None = None) -> dict[str, Any]:
    """``scene`` as a TOML document, file names relative to ``base`` (default: the folder
    of the scene's own file, else the working folder). Every value is written out, so
    nothing depends on defaults."""
    folder = (
        base
        if base is not None
        else (scene.source.parent if scene.source is not None else Path.cwd())
    )

    def rel(path: Path) -> str:
        return _relative(path, folder)

    document: dict[str, Any] = {"name": scene.name}
    if scene.description:
        document["description"] = scene.description
    document["max_bounces"] = scene.max_bounces
    document["ambient"] = scene.ambient
    document["camera"] = _camera_document(scene.camera)
    background = scene.background
    if background.kind == "color":
        document["background"] = {"color": list(background.color)}
    elif background.kind == "sky":
        document["background"] = {"sky": "procedural"}
    else:
        assert background.path is not None
        document["background"] = {background.kind: rel(background.path)}
        if background.sphere_map_camera is not None:
            camera = background.sphere_map_camera
            document["background"]["sphere_map_camera"] = {
                "eye": list(camera.eye),
                "target": list(camera.target),
                "up": list(camera.up),
            }
    document["lights"] = [
        {
            "direction": list(light.direction),
            "intensity": light.intensity,
            "color": list(light.color),
        }
        for light in scene.lights
    ]
    objects = []
    for item in scene.objects:
        if isinstance(item, RobotObject):
            entry: dict[str, Any] = {
                "name": item.name,
                "type": "robot",
                "angles": list(item.angles),
            }
        else:
            entry = {"name": item.name, "type": "mesh", "mesh": rel(item.mesh)}
            if item.color is not None:
                entry["color"] = list(item.color)
            if item.texture is not None:
                entry["texture"] = rel(item.texture)
        entry.update(_transform_document(item.transform))
        objects.append(entry)
    document["objects"] = objects
    reflectors = []
    for reflector in scene.reflectors:
        if isinstance(reflector, PlanarReflector):
            entry = {
                "name": reflector.name,
                "technique": reflector.technique,
                "corners": [list(c) for c in reflector.corners],
                "capture": reflector.capture,
            }
            if reflector.texture_size is not None:
                entry["texture_size"] = reflector.texture_size
            if reflector.ortho is not None:
                ortho = reflector.ortho
                entry["ortho"] = {
                    "eye": list(ortho.eye),
                    "target": list(ortho.target),
                    "up": list(ortho.up),
                    "extents": list(ortho.extents),
                }
            entry["color"] = list(reflector.color)
            entry["backing"] = list(reflector.backing)
            if technique(reflector.technique).probe:
                entry["map_size"] = reflector.map_size
                entry["capture_center"] = list(reflector.capture_center)
                if reflector.source is not None:
                    entry["source"] = rel(reflector.source)
                if reflector.parallax is not None:
                    entry["parallax"] = parallax_document(reflector.parallax)
        else:
            entry = {
                "name": reflector.name,
                "technique": reflector.technique,
                "mesh": rel(reflector.mesh),
                **_transform_document(reflector.transform),
                "map_size": reflector.map_size,
                "capture_center": list(reflector.capture_center),
                "color": list(reflector.color),
            }
            if reflector.source is not None:
                entry["source"] = rel(reflector.source)
            if reflector.parallax is not None:
                entry["parallax"] = parallax_document(reflector.parallax)
        if reflector.ssr is not None:
            entry["ssr"] = screen_space_document(reflector.ssr)
        reflectors.append(entry)
    document["reflectors"] = reflectors
    if scene.animation is not None:
        keyframes = []
        for key in scene.animation.keyframes:
            entry = {"frame": key.frame}
            for group in ("camera", "objects", "reflectors"):
                values = getattr(key, group)
                if values:
                    entry[group] = _tuples_as_lists(values)
            keyframes.append(entry)
        document["animation"] = {"frames": scene.animation.frames, "keyframes": keyframes}
    return document


def dumps(scene: Scene, base: Path | None = None) -> str:
    """``scene`` as TOML text (see :func:`scene_to_document`)."""
    import tomlkit

    return tomlkit.dumps(scene_to_document(scene, base))


def parallax_document(parallax: Parallax) -> dict[str, Any]:
    """A curved reflector's ``parallax`` table."""
    if isinstance(parallax, BoxProxy):
        return {"proxy": "box", "min": list(parallax.min), "max": list(parallax.max)}
    if isinstance(parallax, SphereProxy):
        return {"proxy": "sphere", "radius": parallax.radius}
    return {
        "proxy": "distance",
        "steps": parallax.steps,
        "secant": parallax.secant,
        "thickness": parallax.thickness,
    }


def screen_space_document(settings: ScreenSpace) -> dict[str, Any]:
    """A reflector's ``ssr`` table."""
    return {
        "probe": settings.probe,
        "stride": settings.stride,
        "steps": settings.steps,
        "thickness": settings.thickness,
        "max_distance": settings.max_distance,
        "refine": settings.refine,
        "edge_fade": settings.edge_fade,
    }


def _camera_document(camera: Camera) -> dict[str, Any]:
    return {
        "eye": list(camera.eye),
        "target": list(camera.target),
        "up": list(camera.up),
        "fovy": camera.fovy,
        "near": camera.near,
        "far": camera.far,
    }


def _transform_document(transform: Transform) -> dict[str, Any]:
    return {
        "position": list(transform.position),
        "rotation": list(transform.rotation),
        "scale": list(transform.scale),
    }


def _tuples_as_lists(value: Any) -> Any:
    """``value`` with every mapping a dict and every tuple a list, as TOML writes them."""
    if isinstance(value, Mapping):
        return {k: _tuples_as_lists(v) for k, v in value.items()}
    if isinstance(value, tuple | list):
        return [_tuples_as_lists(v) for v in value]
    return value


def _relative(path: Path, folder: Path) -> str:
    try:
        return Path(path).resolve().relative_to(folder.resolve()).as_posix()
    except ValueError:
        import os

        return Path(os.path.relpath(Path(path).resolve(), folder.resolve())).as_posix()


# --------------------------------------------------------------------------- checking


class _Reader:
    """Turns a document into a Scene, raising SceneError at the first problem."""

    def __init__(self, source: Path | None) -> None:
        self.source = source
        self.label = str(source) if source is not None else "<string>"
        self.folder = source.parent if source is not None else Path.cwd()

    def fail(self, key: str, problem: str) -> SceneError:
        return SceneError(self.label, key, problem)

    # ------------------------------------------------------------- value checks

    def table(self, value: Any, key: str, known: tuple[str, ...]) -> Mapping[str, Any]:
        if not isinstance(value, Mapping):
            raise self.fail(key, f"expected a table, got {_kind(value)}")
        for name in value:
            if name not in known:
                where = f"{key}.{key_name(name)}" if key else key_name(name)
                close = difflib.get_close_matches(str(name), known, n=1, cutoff=0.6)
                hint = (
                    f"; did you mean {close[0]!r}?"
                    if close
                    else (f"; expected one of {', '.join(known)}")
                )
                raise self.fail(where, f"unknown key{hint}")
        return value

    def array(self, value: Any, key: str) -> list[Any]:
        if not isinstance(value, list):
            raise self.fail(key, f"expected an array, got {_kind(value)}")
        return value

    def number(
        self,
        value: Any,
        key: str,
        low: float | None = None,
        high: float | None = None,
        low_open: bool = False,
    ) -> float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise self.fail(key, f"expected a number, got {_kind(value)}")
        try:
            number = float(value)
        except OverflowError:  # a whole number beyond float64
            number = math.inf if value > 0 else -math.inf
        else:
            if not math.isfinite(number):
                why = " (a number beyond 1.8e308 overflows to inf)" if math.isinf(number) else ""
                raise self.fail(key, f"expected a finite number, got {value}{why}")
        if not abs(number) <= MAX_MAGNITUDE:
            shown = (
                f"{number:g}"
                if math.isfinite(number)
                else (
                    f"a {len(str(abs(value)))}-digit number"
                    if isinstance(value, int)
                    else str(value)
                )
            )
            raise self.fail(
                key,
                f"{shown} is too large: it overflows OpenGL's 32-bit "
                f"floats or loses all precision in them; expected a number from "
                f"{-MAX_MAGNITUDE:g} to {MAX_MAGNITUDE:g}",
            )
        if low is not None and (number < low or (low_open and number == low)):
            bound = f"greater than {low:g}" if low_open else f"at least {low:g}"
            raise self.fail(key, f"expected a number {bound}, got {value}")
        if high is not None and number > high:
            raise self.fail(key, f"expected a number at most {high:g}, got {value}")
        return number

    def fovy(self, value: Any, key: str) -> float:
        """A vertical field of view in degrees, from :data:`MIN_FOVY` to 179."""
        degrees = self.number(value, key, 0.0, 179.0, low_open=True)
        if degrees < MIN_FOVY:
            raise self.fail(
                key,
                f"{degrees:g} degrees is too narrow: below {MIN_FOVY:g} "
                f"degrees, GL's 32-bit floats move vertices by a good part of a "
                f"pixel or more; expected {MIN_FOVY:g} to 179",
            )
        return degrees

    def integer(self, value: Any, key: str, low: int, high: int) -> int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise self.fail(key, f"expected a whole number, got {_kind(value)}")
        if not low <= value <= high:
            raise self.fail(key, f"expected a whole number from {low} to {high}, got {value}")
        return int(value)

    def text(self, value: Any, key: str) -> str:
        if not isinstance(value, str):
            raise self.fail(key, f"expected a string, got {_kind(value)}")
        return value

    def choice(self, value: Any, key: str, choices: tuple[str, ...]) -> str:
        text = self.text(value, key)
        if text not in choices:
            close = difflib.get_close_matches(text, choices, n=1, cutoff=0.6)
            hint = f" (did you mean {close[0]!r}?)" if close else ""
            raise self.fail(key, f"expected one of {', '.join(choices)}, got {text!r}{hint}")
        return text

    def vector(self, value: Any, key: str, count: int = 3) -> tuple[float, ...]:
        items = self.array(value, key)
        if len(items) != count:
            raise self.fail(key, f"expected {count} numbers, got {len(items)}")
        return tuple(self.number(v, f"{key}[{i}]") for i, v in enumerate(items))

    def vec3(self, value: Any, key: str) -> tuple[float, float, float]:
        x, y, z = self.vector(value, key, 3)
        return (x, y, z)

    def direction(self, value: Any, key: str) -> tuple[float, float, float]:
        vector = self.vec3(value, key)
        with np.errstate(over="ignore"):
            length = float(np.linalg.norm(vector))
        if not length > 0.0:
            raise self.fail(key, f"expected a non-zero direction, got {list(vector)}")
        if not math.isfinite(length):
            raise self.fail(
                key, f"expected a direction whose length is a finite number, got {list(vector)}"
            )
        return vector

    def color(self, value: Any, key: str) -> tuple[float, float, float]:
        rgb = self.vec3(value, key)
        for i, channel in enumerate(rgb):
            if not 0.0 <= channel <= 1.0:
                raise self.fail(
                    f"{key}[{i}]", f"expected a colour channel from 0 to 1, got {channel:g}"
                )
        return rgb

    def file(self, value: Any, key: str, what: str) -> Path:
        path = self.folder / self.text(value, key)
        if not _is_file(path):
            raise self.fail(key, f"{what} {path} does not exist")
        return path.resolve()

    def mesh_file(self, value: Any, key: str) -> Path:
        """A mesh file of a format trimesh reads (checked by its name, as trimesh picks
        its reader: a picture named as a mesh is refused here, not when first drawn)."""
        path = self.file(value, key, "mesh file")
        formats = mesh_formats()
        suffix = path.name.lower().split(".", 1)[1] if "." in path.name else ""
        if suffix not in formats and path.suffix.lower().lstrip(".") not in formats:
            raise self.fail(
                key,
                f"mesh file {path} is not of a format trimesh reads: "
                f"expected a name ending in "
                f"{', '.join('.' + f for f in sorted(formats))}",
            )
        return path

    def folder_of_faces(self, value: Any, key: str) -> Path:
        folder = self.folder / self.text(value, key)
        if not _is_dir(folder):
            raise self.fail(key, f"cube-face folder {folder} does not exist")
        missing = [
            f"{stem}.png" for stem in CUBE_FACE_FILES if not _is_file(folder / f"{stem}.png")
        ]
        if missing:
            raise self.fail(
                key,
                f"cube-face folder {folder} lacks {', '.join(missing)}; "
                f"expected {', '.join(s + '.png' for s in CUBE_FACE_FILES)}",
            )
        return folder.resolve()

    # ------------------------------------------------------------- sections

    def scene(self, document: Mapping[str, Any]) -> Scene:
        document = self.table(document, "", _TOP_KEYS)
        default_name = self.source.stem if self.source is not None else "scene"
        name = self.text(document.get("name", default_name), "name")
        description = self.text(document.get("description", ""), "description")
        max_bounces = self.integer(document.get("max_bounces", 1), "max_bounces", 0, MAX_BOUNCES)
        ambient = self.number(document.get("ambient", 0.3), "ambient", 0.0, 1.0)
        camera = self.camera(document.get("camera", {}), "camera")
        background = self.background(document.get("background", {}), camera)
        lights = self.lights(document.get("lights", [{}]))
        objects = self.objects(document.get("objects", []))
        reflectors = self.reflectors(document.get("reflectors", []))
        scene = Scene(
            name=name,
            description=description,
            max_bounces=max_bounces,
            ambient=ambient,
            camera=camera,
            background=background,
            lights=lights,
            objects=objects,
            reflectors=reflectors,
            source=self.source,
        )
        if "animation" in document:
            scene = replace(scene, animation=self.animation(document["animation"], scene))
        return scene

    def camera(self, value: Any, key: str) -> Camera:
        table = self.table(value, key, _CAMERA_KEYS)
        default = Camera()
        eye = self.vec3(table.get("eye", list(default.eye)), f"{key}.eye")
        target = self.vec3(table.get("target", list(default.target)), f"{key}.target")
        up = self.direction(table.get("up", list(default.up)), f"{key}.up")
        fovy = self.fovy(table.get("fovy", default.fovy), f"{key}.fovy")
        near = self.number(table.get("near", default.near), f"{key}.near", 0.0, low_open=True)
        far = self.number(table.get("far", default.far), f"{key}.far")
        if not far > near:
            raise self.fail(f"{key}.far", f"expected more than near ({near:g}), got {far:g}")
        if far > MAX_DEPTH_RATIO * near:
            raise self.fail(
                f"{key}.near",
                f"{near:g} is too small for far {far:g}: the depth "
                f"buffer loses the farther part of a range more than "
                f"{MAX_DEPTH_RATIO:g} times near; expected at least "
                f"{far / MAX_DEPTH_RATIO:.8g}",
            )
        self.check_view(eye, target, up, key)
        return Camera(eye=eye, target=target, up=up, fovy=fovy, near=near, far=far)

    def check_view(self, eye, target, up, key: str) -> None:
        with np.errstate(over="ignore", invalid="ignore"):
            offset = np.subtract(target, eye)
            length = float(np.linalg.norm(offset))
        if not length > 0.0:
            raise self.fail(f"{key}.target", f"must differ from {key}.eye, both are {list(eye)}")
        if not math.isfinite(length):
            raise self.fail(f"{key}.target", f"too far from {key}.eye (the distance overflows)")
        side = np.cross(offset / length, np.asarray(up) / np.linalg.norm(up))
        if float(np.linalg.norm(side)) < 1e-9:
            raise self.fail(
                f"{key}.up",
                f"must not be parallel to the view direction from eye to target, got {list(up)}",
            )
        if float(np.linalg.norm(np.cross(offset / length, up))) < 1e-12:  # as look_at does
            raise self.fail(
                f"{key}.up",
                f"is too short to orient the camera, got "
                f"{list(up)}; expected a direction of length 1 or so",
            )

    def background(self, value: Any, camera: Camera) -> Background:
        table = self.table(value, "background", (*_BACKGROUND_SOURCES, "sphere_map_camera"))
        sources = [k for k in _BACKGROUND_SOURCES if k in table]
        if len(sources) > 1:
            raise self.fail(
                f"background.{sources[1]}",
                f"a background has one source; remove {sources[1]!r} or {sources[0]!r}",
            )
        if "sphere_map_camera" in table and sources != ["sphere_map"]:
            raise self.fail(
                "background.sphere_map_camera", "applies to a sphere_map background only"
            )
        kind = sources[0] if sources else "color"
        if kind == "color":
            color = self.color(table.get("color", list(Background().color)), "background.color")
            return Background(kind="color", color=color)
        if kind == "sky":
            self.choice(table["sky"], "background.sky", ("procedural",))
            return Background(kind="sky")
        if kind == "cube_faces":
            return Background(
                kind="cube_faces",
                path=self.folder_of_faces(table["cube_faces"], "background.cube_faces"),
            )
        path = self.file(table["sphere_map"], "background.sphere_map", "picture")
        if "sphere_map_camera" in table:
            key = "background.sphere_map_camera"
            seen = self.table(table["sphere_map_camera"], key, ("eye", "target", "up"))
            eye = self.vec3(seen.get("eye", list(camera.eye)), f"{key}.eye")
            target = self.vec3(seen.get("target", list(camera.target)), f"{key}.target")
            up = self.direction(seen.get("up", list(camera.up)), f"{key}.up")
            self.check_view(eye, target, up, key)
            seen_from = Camera(eye=eye, target=target, up=up)
        else:
            seen_from = Camera(eye=camera.eye, target=camera.target, up=camera.up)
        return Background(kind="sphere_map", path=path, sphere_map_camera=seen_from)

    def lights(self, value: Any) -> tuple[Light, ...]:
        items = self.array(value, "lights")
        if len(items) > MAX_LIGHTS:
            raise self.fail("lights", f"expected at most {MAX_LIGHTS} lights, got {len(items)}")
        lights = []
        for i, item in enumerate(items):
            key = f"lights[{i}]"
            table = self.table(item, key, _LIGHT_KEYS)
            default = Light()
            lights.append(
                Light(
                    direction=self.direction(
                        table.get("direction", list(default.direction)), f"{key}.direction"
                    ),
                    intensity=self.number(
                        table.get("intensity", default.intensity), f"{key}.intensity", 0.0, 10.0
                    ),
                    color=self.color(table.get("color", list(default.color)), f"{key}.color"),
                )
            )
        return tuple(lights)

    def transform(self, table: Mapping[str, Any], key: str) -> Transform:
        position = self.vec3(table.get("position", [0, 0, 0]), f"{key}.position")
        rotation = self.vec3(table.get("rotation", [0, 0, 0]), f"{key}.rotation")
        raw_scale = table.get("scale", [1, 1, 1])
        if isinstance(raw_scale, int | float) and not isinstance(raw_scale, bool):
            factor = self.number(raw_scale, f"{key}.scale")
            scale = (factor, factor, factor)
        else:
            scale = self.vec3(raw_scale, f"{key}.scale")
        for i, factor in enumerate(scale):
            if not 1e-6 <= abs(factor) <= 1e6:
                raise self.fail(
                    f"{key}.scale",
                    f"expected scale factors from 1e-6 to 1e6 in size, got {scale[i]:g}",
                )
        return Transform(position=position, rotation=rotation, scale=scale)

    def objects(self, value: Any) -> tuple:
        items = self.array(value, "objects")
        objects: list = []
        for i, item in enumerate(items):
            key = f"objects[{i}]"
            if not isinstance(item, Mapping):
                raise self.fail(key, f"expected a table, got {_kind(item)}")
            kind = self.choice(
                item.get("type", "robot" if "angles" in item else "mesh"),
                f"{key}.type",
                ("mesh", "robot"),
            )
            if kind == "robot":
                table = self.table(item, key, _ROBOT_KEYS)
                name = self.text(table.get("name", "robot"), f"{key}.name")
                angles = self.vec3(table.get("angles", [-35.0, 30.0, -75.0]), f"{key}.angles")
                objects.append(
                    RobotObject(name=name, angles=angles, transform=self.transform(table, key))
                )
                continue
            table = self.table(item, key, _MESH_KEYS)
            if "mesh" not in table:
                raise self.fail(f"{key}.mesh", "missing: a mesh object needs a mesh file")
            mesh = self.mesh_file(table["mesh"], f"{key}.mesh")
            texture = (
                self.file(table["texture"], f"{key}.texture", "texture picture")
                if "texture" in table
                else None
            )
            objects.append(
                MeshObject(
                    name=self.text(table.get("name", mesh.stem), f"{key}.name"),
                    mesh=mesh,
                    transform=self.transform(table, key),
                    color=(
                        self.color(table["color"], f"{key}.color") if "color" in table else None
                    ),
                    texture=texture,
                )
            )
        self.unique([o.name for o in objects], "objects")
        return tuple(objects)

    def unique(self, names: list[str], group: str) -> None:
        seen: dict[str, int] = {}
        for i, name in enumerate(names):
            if name in seen:
                raise self.fail(
                    f"{group}[{i}].name",
                    f"{name!r} is already the name of "
                    f"{group}[{seen[name]}]; give each a name of its own",
                )
            seen[name] = i

    def reflectors(self, value: Any) -> tuple:
        items = self.array(value, "reflectors")
        reflectors: list = []
        for i, item in enumerate(items):
            key = f"reflectors[{i}]"
            if not isinstance(item, Mapping):
                raise self.fail(key, f"expected a table, got {_kind(item)}")
            names = reflector_technique_names()
            if "technique" not in item:
                raise self.fail(f"{key}.technique", f"missing; expected one of {', '.join(names)}")
            name = self.choice(item["technique"], f"{key}.technique", names)
            entry = technique(name)
            # a technique for either kind: a mesh makes a curved reflector
            if entry.kind == "planar" or (entry.kind == "both" and "mesh" not in item):
                reflectors.append(self.planar(item, key, name))
            else:
                reflectors.append(self.curved(item, key, name))
        self.unique([r.name for r in reflectors], "reflectors")
        return tuple(reflectors)

    def planar(self, item: Mapping[str, Any], key: str, name: str) -> PlanarReflector:
        table = self.table(item, key, _PLANAR_KEYS)
        shape_keys = ("center", "normal", "width", "height", "up")
        given = [k for k in shape_keys if k in table]
        if "corners" in table:
            if given:
                raise self.fail(
                    f"{key}.{given[0]}",
                    "give corners, or center, normal, width and height, not both",
                )
            corners = self.corners(table["corners"], f"{key}.corners")
        else:
            missing = [k for k in ("center", "normal", "width", "height") if k not in table]
            if missing:
                raise self.fail(
                    f"{key}.{missing[0]}",
                    "missing: a planar mirror needs corners, or center, normal, width and height",
                )
            corners = self.rectangle(table, key)
        texture_size: int | Literal["footprint"] | None = None
        if "texture_size" in table:
            texture_size = self.texture_size(table["texture_size"], f"{key}.texture_size", name)
        ortho = self.ortho(table["ortho"], f"{key}.ortho") if "ortho" in table else None
        entry = technique(name)
        if ortho is not None and not entry.own_camera:
            owners = _techniques_with(lambda t: t.own_camera)
            raise self.fail(f"{key}.ortho", f"applies to {owners}, not {name!r}")
        given = [k for k in (*_PLANAR_MAP_KEYS, "ssr") if k in table]
        if given and not entry.probe:
            owners = _techniques_with(lambda t: bool(t.probe))
            raise self.fail(
                f"{key}.{given[0]}",
                f"applies to a planar mirror of {owners} (a map it falls back to), not {name!r}",
            )
        ssr = self.screen_space(table["ssr"], f"{key}.ssr") if "ssr" in table else None
        mirror = PlanarReflector(
            name=self.text(table.get("name", "mirror"), f"{key}.name"),
            corners=corners,
            technique=name,
            capture=self.choice(table.get("capture", "copy"), f"{key}.capture", CAPTURE_MODES),
            texture_size=texture_size,
            ortho=ortho,
            color=self.color(table.get("color", list(DEFAULT_PLAIN_COLOR)), f"{key}.color"),
            backing=self.color(table.get("backing", list(DEFAULT_BACKING)), f"{key}.backing"),
            map_size=self.integer(table.get("map_size", 256), f"{key}.map_size", 4, MAX_MAP_SIZE),
            capture_center=self.vec3(
                table.get("capture_center", [0, 0, 0]), f"{key}.capture_center"
            ),
            ssr=ssr,
        )
        mapped = _map_technique(entry, ssr)
        source = self.map_source(table, key, name, mapped)
        parallax = self.map_parallax(table, key, name, mapped, mirror.probe_center())
        return replace(mirror, source=source, parallax=parallax)

    def map_source(
        self, table: Mapping[str, Any], key: str, name: str, mapped: Technique | None
    ) -> Path | None:
        """A reflector's ``source``, as the technique of its map (``mapped``) takes it."""
        if "source" not in table:
            return None
        kind = None if mapped is None else mapped.source
        if kind == "faces":
            return self.folder_of_faces(table["source"], f"{key}.source")
        if kind is not None and mapped is not None:  # a picture: the map in its layout
            return self.file(table["source"], f"{key}.source", f"{mapped.name} map's picture")
        via = "" if mapped is None or mapped.name == name else f" (its probe {mapped.name!r})"
        raise self.fail(
            f"{key}.source",
            f"technique {name!r}{via} takes no source (only "
            f"{_techniques_with(lambda t: t.source is not None)} do: a "
            "live map captures the scene, the others are baked from the "
            "background)",
        )

    def map_parallax(
        self,
        table: Mapping[str, Any],
        key: str,
        name: str,
        mapped: Technique | None,
        center: np.ndarray,
    ) -> Parallax | None:
        """A reflector's ``parallax``, which the technique of its map (``mapped``) must
        take; a box proxy must hold the capture centre ``center`` ``(3,)``."""
        if "parallax" not in table:
            return None
        if mapped is None or not mapped.parallax:
            via = "" if mapped is None or mapped.name == name else f" with probe {mapped.name!r}"
            owners = _techniques_with(lambda t: t.parallax and not t.probe)
            raise self.fail(f"{key}.parallax", f"applies to {owners}, not {name!r}{via}")
        parallax = self.parallax(table["parallax"], f"{key}.parallax")
        if isinstance(parallax, BoxProxy):
            if not (np.all(center >= parallax.min) and np.all(center <= parallax.max)):
                raise self.fail(
                    f"{key}.parallax",
                    "the reflector's capture centre "
                    f"{[round(float(v), 6) for v in center]} is outside the box "
                    "proxy; the box must enclose the reflector",
                )
        return parallax

    def screen_space(self, value: Any, key: str) -> ScreenSpace:
        """An ``ssr`` table: screen-space reflections' settings."""
        from mirrorlab.screen_space import MAX_REFINE, MAX_STEPS, MAX_STRIDE

        table = self.table(value, key, _SSR_KEYS)
        default = ScreenSpace()
        probes = (*probe_technique_names(), SSR_NO_PROBE)
        return ScreenSpace(
            probe=self.choice(table.get("probe", default.probe), f"{key}.probe", probes),
            stride=self.number(
                table.get("stride", default.stride), f"{key}.stride", 0.25, MAX_STRIDE
            ),
            steps=self.integer(table.get("steps", default.steps), f"{key}.steps", 1, MAX_STEPS),
            thickness=self.number(
                table.get("thickness", default.thickness),
                f"{key}.thickness",
                0.0,
                100.0,
                low_open=True,
            ),
            max_distance=self.number(
                table.get("max_distance", default.max_distance), f"{key}.max_distance", 0.0
            ),
            refine=self.integer(
                table.get("refine", default.refine), f"{key}.refine", 0, MAX_REFINE
            ),
            edge_fade=self.number(
                table.get("edge_fade", default.edge_fade), f"{key}.edge_fade", 0.0, 0.5
            ),
        )

    def texture_size(self, value: Any, key: str, name: str) -> int | Literal["footprint"]:
        """A whole number of pixels, or ``"footprint"`` for a technique whose capture
        camera is its own."""
        if isinstance(value, str):
            if value != FOOTPRINT_TEXTURE:
                raise self.fail(
                    key, f'expected a whole number or "{FOOTPRINT_TEXTURE}", got {value!r}'
                )
            if not technique(name).own_camera:
                owners = _techniques_with(lambda t: t.own_camera)
                raise self.fail(
                    key,
                    f'"{FOOTPRINT_TEXTURE}" applies to {owners} (a capture '
                    f"camera of its own), not {name!r}",
                )
            return "footprint"
        return self.integer(value, key, 1, MAX_MAP_SIZE)

    def corners(self, value: Any, key: str):
        items = self.array(value, key)
        if len(items) != 4:
            raise self.fail(key, f"expected 4 corners of 3 numbers, got {len(items)} corners")
        points = np.array([self.vec3(p, f"{key}[{i}]") for i, p in enumerate(items)])
        check_quad(points, lambda problem: self.fail(key, problem))
        return tuple((float(x), float(y), float(z)) for x, y, z in points)

    def rectangle(self, table: Mapping[str, Any], key: str):
        center = np.array(self.vec3(table["center"], f"{key}.center"))
        normal = np.array(self.direction(table["normal"], f"{key}.normal"))
        width = self.number(table["width"], f"{key}.width", 0.0, low_open=True)
        height = self.number(table["height"], f"{key}.height", 0.0, low_open=True)
        normal /= np.linalg.norm(normal)
        up_hint = np.array(self.direction(table.get("up", [0, 1, 0]), f"{key}.up"))
        up = up_hint - (up_hint @ normal) * normal
        if np.linalg.norm(up) < 1e-9 * np.linalg.norm(up_hint):
            raise self.fail(
                f"{key}.up",
                f"must not be parallel to the normal "
                f"{list(table['normal'])}; give an up direction along the glass",
            )
        up /= np.linalg.norm(up)
        right = np.cross(normal, up)
        w, h = width / 2.0, height / 2.0
        points = np.array(
            [
                center - w * right - h * up,
                center - w * right + h * up,
                center + w * right + h * up,
                center + w * right - h * up,
            ]
        )
        check_quad(points, lambda problem: self.fail(f"{key}.width", problem))
        return tuple((float(x), float(y), float(z)) for x, y, z in points)

    def ortho(self, value: Any, key: str) -> OrthoCapture:
        table = self.table(value, key, _ORTHO_KEYS)
        for required in _ORTHO_KEYS:
            if required not in table:
                raise self.fail(
                    f"{key}.{required}",
                    "missing: an ortho capture needs eye, target, up and extents",
                )
        eye = self.vec3(table["eye"], f"{key}.eye")
        target = self.vec3(table["target"], f"{key}.target")
        up = self.direction(table["up"], f"{key}.up")
        self.check_view(eye, target, up, key)
        extents = self.vector(table["extents"], f"{key}.extents", 6)
        left, right, bottom, top, near, far = extents
        if left == right or bottom == top or near == far:
            raise self.fail(
                f"{key}.extents",
                f"expected left != right, bottom != top and near != far, got {list(extents)}",
            )
        return OrthoCapture(
            eye=eye, target=target, up=up, extents=(left, right, bottom, top, near, far)
        )

    def curved(self, item: Mapping[str, Any], key: str, name: str) -> CurvedReflector:
        table = self.table(item, key, _CURVED_KEYS)
        if "mesh" not in table:
            raise self.fail(f"{key}.mesh", "missing: a curved reflector needs a mesh file")
        mesh = self.mesh_file(table["mesh"], f"{key}.mesh")
        entry = technique(name)
        if "ssr" in table and not entry.probe:
            owners = _techniques_with(lambda t: bool(t.probe))
            raise self.fail(f"{key}.ssr", f"applies to {owners}, not {name!r}")
        ssr = self.screen_space(table["ssr"], f"{key}.ssr") if "ssr" in table else None
        mapped = _map_technique(entry, ssr)
        source = self.map_source(table, key, name, mapped)
        reflector = CurvedReflector(
            name=self.text(table.get("name", mesh.stem), f"{key}.name"),
            mesh=mesh,
            transform=self.transform(table, key),
            technique=name,
            map_size=self.integer(table.get("map_size", 256), f"{key}.map_size", 4, MAX_MAP_SIZE),
            source=source,
            capture_center=self.vec3(
                table.get("capture_center", [0, 0, 0]), f"{key}.capture_center"
            ),
            color=self.color(table.get("color", list(DEFAULT_PLAIN_COLOR)), f"{key}.color"),
            ssr=ssr,
        )
        parallax = self.map_parallax(table, key, name, mapped, reflector.center())
        return reflector if parallax is None else replace(reflector, parallax=parallax)

    def parallax(self, value: Any, key: str) -> Parallax:
        known = ("proxy", *dict.fromkeys(k for keys in _PARALLAX_KEYS.values() for k in keys))
        table = self.table(value, key, known)
        if "proxy" not in table:
            raise self.fail(
                f"{key}.proxy", f"missing; expected one of {', '.join(PARALLAX_PROXIES)}"
            )
        proxy = self.choice(table["proxy"], f"{key}.proxy", PARALLAX_PROXIES)
        for name in table:
            owner = next((p for p, keys in _PARALLAX_KEYS.items() if name in keys), proxy)
            if owner != proxy:
                raise self.fail(f"{key}.{name}", f"applies to proxy {owner!r}, not {proxy!r}")
        if proxy == "box":
            for required in ("min", "max"):
                if required not in table:
                    raise self.fail(
                        f"{key}.{required}",
                        "missing: a box proxy needs its world corners min and max",
                    )
            low = self.vec3(table["min"], f"{key}.min")
            high = self.vec3(table["max"], f"{key}.max")
            for i in range(3):
                if not low[i] < high[i]:
                    raise self.fail(
                        f"{key}.max[{i}]",
                        f"expected more than min[{i}] = {low[i]:g}, got {high[i]:g}",
                    )
            return BoxProxy(min=low, max=high)
        if proxy == "sphere":
            if "radius" not in table:
                raise self.fail(f"{key}.radius", "missing: a sphere proxy needs its radius")
            return SphereProxy(
                radius=self.number(table["radius"], f"{key}.radius", 0.0, low_open=True)
            )
        default = DistanceSearch()
        return DistanceSearch(
            steps=self.integer(
                table.get("steps", default.steps), f"{key}.steps", 1, MAX_SEARCH_STEPS
            ),
            secant=self.integer(
                table.get("secant", default.secant), f"{key}.secant", 0, MAX_SEARCH_STEPS
            ),
            thickness=self.number(
                table.get("thickness", default.thickness),
                f"{key}.thickness",
                0.0,
                1.0,
                low_open=True,
            ),
        )

    def animation(self, value: Any, scene: Scene) -> Animation:
        table = self.table(value, "animation", ("frames", "keyframes"))
        items = self.array(table.get("keyframes", []), "animation.keyframes")
        if not items:
            raise self.fail("animation.keyframes", "expected at least one keyframe")
        keyframes = [
            self.keyframe(item, f"animation.keyframes[{i}]", scene) for i, item in enumerate(items)
        ]
        last = max(k.frame for k in keyframes)
        frames = self.integer(table.get("frames", last + 1), "animation.frames", 1, MAX_FRAMES)
        if last >= frames:
            index = next(i for i, k in enumerate(keyframes) if k.frame == last)
            raise self.fail(
                f"animation.keyframes[{index}].frame",
                f"frame {last} is past the animation's last frame {frames - 1}",
            )
        frames_seen: dict[int, int] = {}
        for i, key in enumerate(keyframes):
            if key.frame in frames_seen:
                raise self.fail(
                    f"animation.keyframes[{i}].frame",
                    f"frame {key.frame} is already keyframes[{frames_seen[key.frame]}]",
                )
            frames_seen[key.frame] = i
        ordered = tuple(sorted(keyframes, key=lambda k: k.frame))
        self.check_camera_frames(scene.camera, ordered, frames, frames_seen)
        self.check_placement_frames(ordered, frames, frames_seen)
        return Animation(frames=frames, keyframes=ordered)

    def check_camera_frames(
        self, camera: Camera, keyframes: tuple[Keyframe, ...], frames: int, index_of: dict[int, int]
    ) -> None:
        """The camera must be a camera at every frame, not only at its keyframes: between
        them eye, target and up are interpolated and can meet (an eye moving through
        its target, an up turning over)."""
        keyed = [k.frame for k in keyframes if k.camera]
        if not keyed:
            return
        tracks = {}
        for field in ("eye", "target", "up"):
            keys = [(k.frame, k.camera[field]) for k in keyframes if field in k.camera]
            tracks[field] = (
                _track_values(keys, frames)
                if keys
                else np.broadcast_to(np.asarray(getattr(camera, field), float), (frames, 3))
            )
        eye, target, up = tracks["eye"], tracks["target"], tracks["up"]
        with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
            offset = target - eye
            length = np.linalg.norm(offset, axis=1)
            up_length = np.linalg.norm(up, axis=1)
            forward = offset / length[:, None]
            turned = np.linalg.norm(np.cross(forward, up / up_length[:, None]), axis=1)
            side = np.linalg.norm(np.cross(forward, up), axis=1)  # as look_at measures it
        finite = (
            np.isfinite(eye).all(axis=1)
            & np.isfinite(target).all(axis=1)
            & np.isfinite(up).all(axis=1)
            & np.isfinite(length)
            & np.isfinite(up_length)
        )
        problems = (
            (
                ~finite,
                "the camera's eye, target or up is not a finite number (interpolating "
                "between keyframes overflows)",
            ),
            (
                finite & ~(length > 0.0),
                "the camera's eye reaches its target; keep them apart at every frame",
            ),
            (
                finite & (length > 0.0) & ~((turned >= 1e-9) & (side >= 1e-12)),
                "the camera's up is zero or along its view direction; keep it off the line of "
                "sight at every frame",
            ),
        )
        self._first_bad_frame(problems, keyed, index_of, "camera")

    def check_placement_frames(
        self, keyframes: tuple[Keyframe, ...], frames: int, index_of: dict[int, int]
    ) -> None:
        """Every animated position, rotation, scale and joint angle must stay finite at
        every frame, and scales within range (interpolating from -1 to 1 passes 0)."""
        for group in ("objects", "reflectors"):
            names = dict.fromkeys(name for k in keyframes for name in getattr(k, group))
            for name in names:
                for field in OBJECT_FIELDS:
                    keys = [
                        (k.frame, getattr(k, group)[name][field])
                        for k in keyframes
                        if field in getattr(k, group).get(name, {})
                    ]
                    if not keys:
                        continue
                    values = _track_values(keys, frames)
                    finite = np.isfinite(values).all(axis=1)
                    problems = [
                        (
                            ~finite,
                            f"{field} is not a finite number (interpolating "
                            f"between keyframes overflows)",
                        )
                    ]
                    if field == "scale":
                        size = np.abs(values)
                        problems.append(
                            (
                                finite & ~((size >= 1e-6) & (size <= 1e6)).all(axis=1),
                                "a scale factor leaves 1e-6 to 1e6 in size (it is "
                                "interpolated between keyframes); keep each factor's "
                                "sign at every keyframe",
                            )
                        )
                    self._first_bad_frame(
                        problems,
                        [f for f, _ in keys],
                        index_of,
                        f"{group}.{key_name(name)}.{field}",
                    )

    def _first_bad_frame(
        self, problems, keyed: list[int], index_of: dict[int, int], where: str
    ) -> None:
        """Raise for the earliest frame any of ``problems`` ``(mask (frames,), words)``
        marks, blaming the keyframe (of the frames ``keyed``) it follows."""
        bad = [(int(np.argmax(mask)), words) for mask, words in problems if mask.any()]
        if not bad:
            return
        frame, words = min(bad, key=lambda item: item[0])
        before = [f for f in keyed if f <= frame]
        blamed = max(before) if before else min(keyed)
        raise self.fail(
            f"animation.keyframes[{index_of[blamed]}].{where}", f"at frame {frame} {words}"
        )

    def keyframe(self, value: Any, key: str, scene: Scene) -> Keyframe:
        table = self.table(value, key, _KEYFRAME_KEYS)
        if "frame" not in table:
            raise self.fail(f"{key}.frame", "missing: a keyframe needs its frame number")
        frame = self.integer(table["frame"], f"{key}.frame", 0, MAX_FRAMES - 1)
        camera: dict[str, Any] = {}
        if "camera" in table:
            values = self.table(table["camera"], f"{key}.camera", CAMERA_FIELDS)
            for field, raw in values.items():
                where = f"{key}.camera.{field}"
                if field == "fovy":
                    camera[field] = self.fovy(raw, where)
                elif field == "up":
                    camera[field] = self.direction(raw, where)
                else:
                    camera[field] = self.vec3(raw, where)
        objects = self.keyed(table.get("objects", {}), f"{key}.objects", scene, "objects")
        reflectors = self.keyed(
            table.get("reflectors", {}), f"{key}.reflectors", scene, "reflectors"
        )
        return Keyframe(frame=frame, camera=camera, objects=objects, reflectors=reflectors)

    def keyed(self, value: Any, key: str, scene: Scene, group: str) -> dict[str, dict]:
        items = {o.name: o for o in (scene.objects if group == "objects" else scene.reflectors)}
        if not items and isinstance(value, Mapping) and value:
            name = next(iter(value))
            raise self.fail(
                f"{key}.{key_name(name)}", f"unknown name: the scene has no {group} to animate"
            )
        table = self.table(value, key, tuple(items))
        result: dict[str, dict] = {}
        for name, raw in table.items():
            item = items[name]
            where = f"{key}.{key_name(name)}"
            fields: tuple[str, ...] = OBJECT_FIELDS if group == "objects" else REFLECTOR_FIELDS
            if isinstance(item, MeshObject):
                fields = tuple(f for f in fields if f != "angles")
            if isinstance(item, PlanarReflector):
                if isinstance(raw, Mapping) and "scale" in raw:
                    raise self.fail(
                        f"{where}.scale",
                        "a planar mirror's keyframes take "
                        "position and rotation; its size is its corners'",
                    )
                fields = PLANAR_FIELDS
            values = self.table(raw, where, fields)
            posed: dict[str, Any] = {}
            for field, entry in values.items():
                if field == "scale":
                    posed[field] = self.transform({"scale": entry}, where).scale
                else:
                    posed[field] = self.vec3(entry, f"{where}.{field}")
            result[name] = posed
        return result


def check_quad(points: np.ndarray, fail: Callable[[str], Exception]) -> None:
    """Raise ``fail(problem)`` unless ``points`` ``(4, 3)`` form a flat, convex quadrilateral
    of non-zero area, corners in order around it (counter-clockwise from the front).

    Worked out on the corners scaled to unit size around their centre, so that the
    answer is the same at any scale and distance from the origin."""
    points = np.asarray(points, dtype=np.float64)
    if not np.all(np.isfinite(points)):
        raise fail("expected finite corners")
    reach = float(np.abs(points).max())
    if reach == 0.0:
        raise fail("corners coincide: the mirror has no area")
    scaled = points / reach  # within [-1, 1]: nothing below overflows
    offsets = scaled - scaled.mean(axis=0)
    size = float(np.linalg.norm(offsets, axis=1).max())
    if not size > 1e-12:  # closer than float precision at this distance from the origin
        raise fail("corners coincide: the mirror has no area")
    unit_points = offsets / size
    # The plane of the largest triangle of three corners (none: all on a line).
    triangles = [
        np.cross(unit_points[j] - unit_points[i], unit_points[k] - unit_points[i])
        for i, j, k in ((0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3))
    ]
    normal = max(triangles, key=lambda n: float(np.linalg.norm(n)))
    if not float(np.linalg.norm(normal)) > 1e-12:
        raise fail("corners span no area (they lie on a line or coincide)")
    unit = normal / np.linalg.norm(normal)
    off_plane = float(np.abs(unit_points @ unit).max())
    if off_plane > 1e-6:
        raise fail(f"corners are not in one plane (one lies {off_plane * size * reach:.3g} off it)")
    edges = np.roll(unit_points, -1, axis=0) - unit_points
    signs = np.cross(edges, np.roll(edges, -1, axis=0)) @ unit  # turns at corners 1, 2, 3, 0
    if np.all(signs > 0) or np.all(signs < 0):
        return
    q = unit_points
    if _segments_cross(q[0], q[1], q[2], q[3], unit) or _segments_cross(
        q[1], q[2], q[3], q[0], unit
    ):
        raise fail(
            "corners cross over each other: the quadrilateral is self-crossing; "
            "list them in order around the mirror"
        )
    raise fail("corners do not form a convex quadrilateral")


def _track_values(keys: list[tuple[int, Any]], count: int) -> np.ndarray:
    """A keyframe track, ``(frame, value)`` pairs sorted by frame, at every frame
    0 .. ``count`` - 1 as ``(count, n)``: the same float operations as
    :func:`mirrorlab.scene.animation.interpolate`, for all frames at once."""
    frames = np.arange(count, dtype=np.float64)
    values = np.array([np.atleast_1d(np.asarray(v, dtype=np.float64)) for _, v in keys])
    out = np.empty((count, values.shape[1]))
    out[:] = values[-1]
    with np.errstate(over="ignore", invalid="ignore"):
        # Later segments first, so that a frame on a shared key takes the earlier one's
        # value, as interpolate does.
        segments = list(zip(keys, keys[1:], values, values[1:], strict=False))
        for (f0, _), (f1, _), v0, v1 in reversed(segments):
            pick = (frames >= f0) & (frames <= f1)
            w = (frames[pick] - f0) / (f1 - f0)
            out[pick] = v0 + (v1 - v0) * w[:, None]
    out[frames <= keys[0][0]] = values[0]
    return out


def _segments_cross(a, b, c, d, normal) -> bool:
    def side(p, q, r):
        return float(np.cross(q - p, r - p) @ normal)

    return side(a, b, c) * side(a, b, d) < 0 and side(c, d, a) * side(c, d, b) < 0


def probe_technique_names() -> tuple[str, ...]:
    """The techniques a reflector's ``ssr.probe`` may name: every curved technique whose
    map is made from the scene or the background (not from the view's own frame, and
    with no probe of its own)."""
    return tuple(
        t.name
        for t in techniques("curved")
        if t.texture in ("static", "baked", "fixed") and not t.probe
    )


def _map_technique(entry: Technique, ssr: ScreenSpace | None) -> Technique:
    """The technique whose map a reflector of technique ``entry`` draws with: its own, or
    for a technique with a probe, the probe's (with :data:`SSR_NO_PROBE`, the default
    probe's: its map settings are kept for when a probe is named again, unused)."""
    if not entry.probe:
        return entry
    probe = (ssr or ScreenSpace()).probe
    return technique(ScreenSpace().probe if probe == SSR_NO_PROBE else probe)


def _techniques_with(test) -> str:
    """``technique 'a'`` or ``techniques 'a', 'b'``: the techniques ``test`` is true of."""
    names = names_where(test)
    listed = ", ".join(repr(n) for n in names)
    return f"technique {listed}" if len(names) == 1 else f"techniques {listed}"


_BARE_KEY = re.compile(r"[A-Za-z0-9_-]+")


def key_name(name: Any) -> str:
    """``name`` as it is written in a key path: bare when TOML allows, else quoted
    (``objects."my robot"``)."""
    text = str(name)
    return text if _BARE_KEY.fullmatch(text) else json.dumps(text, ensure_ascii=False)


def _kind(value: Any) -> str:
    if isinstance(value, bool):
        return f"the boolean {str(value).lower()}"
    if isinstance(value, int | float):
        return f"the number {value}"
    if isinstance(value, str):
        return f"the string {value!r}"
    if isinstance(value, list):
        return "an array"
    if isinstance(value, Mapping):
        return "a table"
    return type(value).__name__


__all__ = [
    "DEFAULT_SCENE",
    "SceneError",
    "check_quad",
    "dumps",
    "from_document",
    "load_scene",
    "loads",
    "scene_path",
    "scene_to_document",
    "shipped_scene_names",
]
