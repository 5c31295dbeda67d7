"""Options that change a scene, declared once: the command line makes a flag of each, the
Python API takes each as a keyword (``mirrorlab.render(scene, camera=(1, 2, 3))``) and the
demo takes the same flags. An option edits the scene's TOML document, and the scene is
then read again, so an overridden value is checked exactly as a value in a file is.

Also here: the parsing of sizes and numbers that every entry point shares. Numpy only.
"""

from __future__ import annotations

import itertools
import math
import re
import tomllib
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from mirrorlab.scene.loader import SceneError, from_document, scene_to_document
from mirrorlab.scene.model import CAPTURE_MODES, FOOTPRINT_TEXTURE, Scene
from mirrorlab.techniques import (
    Technique,
    frame_technique,
    reflector_technique_names,
    technique,
    technique_names,
    techniques,
)

MAX_SIZE = 8192
"""Largest render or window side accepted, in pixels."""


class OptionError(ValueError):
    """A bad option value: ``option`` names it (``--camera``), ``problem`` says what was
    expected."""

    def __init__(self, option: str, problem: str) -> None:
        self.option, self.problem = option, problem
        super().__init__(f"{option}: {problem}")


# --------------------------------------------------------------------------- parsing


def parse_floats(option: str, text: str, count: int, names: str) -> tuple[float, ...]:
    """``'1,2,3'`` -> (1.0, 2.0, 3.0); OptionError naming ``option`` otherwise."""
    parts = [p.strip() for p in str(text).split(",")]
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        values = ()
    if len(values) != count:
        raise OptionError(option, f"expected {count} numbers {names}, got {text!r}")
    if not all(math.isfinite(v) for v in values):
        raise OptionError(option, f"expected finite numbers {names}, got {text!r}")
    return values


def parse_size(option: str, text: str) -> tuple[int, int]:
    """``'640x480'`` -> (640, 480); OptionError naming ``option`` otherwise."""
    match = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", str(text))
    if match:
        width, height = int(match.group(1)), int(match.group(2))
        if 1 <= width <= MAX_SIZE and 1 <= height <= MAX_SIZE:
            return width, height
    raise OptionError(option, f"expected WIDTHxHEIGHT with each from 1 to {MAX_SIZE}, got {text!r}")


def check_size(size: Sequence[float] | str, option: str = "size") -> tuple[int, int]:
    """A (width, height) pair of whole numbers (ints or whole floats) from 1 to
    :data:`MAX_SIZE` (or its ``'WxH'`` text); OptionError naming ``option`` otherwise."""
    if isinstance(size, str):
        return parse_size(option, size)
    try:
        width, height = size
    except (TypeError, ValueError):
        raise OptionError(option, f"expected (width, height), got {size!r}") from None
    for value in (width, height):
        if (
            isinstance(value, bool)
            or not isinstance(value, int | float)
            or value != int(value)
            or not 1 <= value <= MAX_SIZE
        ):
            raise OptionError(
                option, f"expected two whole numbers from 1 to {MAX_SIZE}, got {tuple(size)!r}"
            )
    return int(width), int(height)


def parse_count(option: str, text: str, low: int = 1, high: int = MAX_SIZE) -> int:
    """``'256'`` -> 256 when ``low <= value <= high``; OptionError naming ``option``."""
    text = str(text).strip()
    if text.isdigit() and low <= int(text) <= high:
        return int(text)
    raise OptionError(option, f"expected a whole number from {low} to {high}, got {text!r}")


def parse_counts(option: str, text: str, low: int = 1, high: int = MAX_SIZE) -> tuple[int, ...]:
    """``'1,2,3'`` -> (1, 2, 3), each :func:`parse_count`-ed; OptionError naming
    ``option``."""
    return tuple(parse_count(option, part, low, high) for part in str(text).split(","))


def parse_choice(option: str, text: str, choices: Sequence[str]) -> str:
    if text not in choices:
        raise OptionError(option, f"expected one of {', '.join(choices)}, got {text!r}")
    return text


def parse_choices(option: str, text: str, choices: Sequence[str]) -> tuple[str, ...]:
    """``'a,b'`` -> ("a", "b") (each once), each one of ``choices``; OptionError naming
    ``option``."""
    words = tuple(dict.fromkeys(w.strip() for w in str(text).split(",") if w.strip()))
    if not words:
        raise OptionError(option, f"expected {' or '.join(choices)}, got {text!r}")
    return tuple(parse_choice(option, word, choices) for word in words)


# --------------------------------------------------------------------------- scene options


@dataclass(frozen=True)
class Option:
    """A scene change: ``name`` (the API keyword; the flag is ``--name`` with dashes),
    ``metavar`` and ``help`` for the command line, ``parse`` from command-line text to a
    value, ``apply`` to write the value into a scene document."""

    name: str
    metavar: str
    help: str | Callable[[], str]
    """For the command line's help: the text, or a function making it when the parser is
    built (for lists that can grow, such as the techniques)."""
    parse: Callable[[str, str], Any]
    apply: Callable[[dict, Any, str], None]
    writes: str = ""
    """A regular expression for the start of the key paths it writes (to name it when the
    scene refuses a value; the most specific match is named)."""
    repeat: bool = False

    @property
    def flag(self) -> str:
        return "--" + self.name.replace("_", "-")

    @property
    def help_text(self) -> str:
        return self.help() if callable(self.help) else self.help


def _vec3(names: str) -> Callable[[str, str], tuple[float, ...]]:
    return lambda flag, text: parse_floats(flag, text, 3, names)


def _set_camera(field: str) -> Callable[[dict, Any, str], None]:
    def apply(document: dict, value: Any, flag: str) -> None:
        document.setdefault("camera", {})[field] = _toml_floats(value)

    return apply


def _apply_angles(document: dict, value: Any, flag: str) -> None:
    robots = [o for o in document.get("objects", []) if o.get("type") == "robot"]
    if not robots:
        raise OptionError(flag, f"scene {document.get('name')!r} has no robot to pose")
    for robot in robots:
        robot["angles"] = _toml_floats(value)


def _entry(name: Any) -> Technique | None:
    """The reflector technique called ``name`` (None for anything else)."""
    try:
        entry = technique(name) if isinstance(name, str) else None
    except ValueError:
        return None
    return entry if entry is not None and entry.kind != "frame" else None


def _reflector_technique_names() -> tuple[str, ...]:
    return reflector_technique_names()


def _is_planar(reflector: Mapping) -> bool:
    """Whether a scene document's reflector table is a planar mirror's (a curved
    reflector's names its mesh), whatever its technique."""
    return "mesh" not in reflector


def _apply_technique(document: dict, value: Any, flag: str) -> None:
    entry = _entry(value)
    if entry is None:
        if frame_technique(value) is not None:
            raise OptionError(
                flag,
                f"{value} draws the whole frame, not a reflector: give "
                f"it to mirrorlab.render(method={value!r}) or as "
                f"'mirrorlab render --{value}'",
            )
        # A value from the Python API, not parsed: no kind of reflector to pick by it.
        # Given to every reflector, it is refused by the scene check with its key path
        # and the names (or here, when there is no reflector at all).
        reflectors = document.get("reflectors", [])
        if not reflectors:
            parse_choice(flag, value, _reflector_technique_names())
        for reflector in reflectors:
            reflector["technique"] = value
        return
    if entry.kind == "both":
        reflectors = document.get("reflectors", [])
        if not reflectors:
            raise OptionError(flag, f"scene {document.get('name')!r} has no reflector")
        for reflector in reflectors:
            _set_technique(reflector, value)
        return
    planar = entry.kind == "planar"
    for reflector in _reflectors_of_kind(
        document, planar, flag, f"{value} is a technique for a {_KIND_NAMES[planar]}, and "
    ):
        _set_technique(reflector, value)


def _set_technique(reflector: dict, value: str) -> None:
    """Give one reflector's table the technique ``value`` (of its kind)."""
    entry = technique(value)
    old = _entry(reflector.get("technique"))
    # A source is kept only where it means the same: a picture for the sphere maps, a
    # folder of faces for a static cube map.
    if "source" in reflector and (old is None or entry.source != old.source):
        del reflector["source"]
    reflector["technique"] = value
    if not entry.probe:
        reflector.pop("ssr", None)  # the settings of a technique that falls back to a map
        if _is_planar(reflector):
            for key in ("map_size", "source", "capture_center", "parallax"):
                reflector.pop(key, None)  # a planar mirror's map is its probe's
    if not entry.own_camera:
        reflector.pop("ortho", None)
        if reflector.get("texture_size") == FOOTPRINT_TEXTURE:
            reflector.pop("texture_size")  # a size that follows a camera of its own
    if not entry.parallax:
        reflector.pop("parallax", None)  # a correction of live cube-map lookups only


def with_technique(scene: Scene, name: str, value: str) -> Scene:
    """``scene`` with its reflector ``name`` drawn by technique ``value`` (one of its
    kind's), as ``--method`` would set it: a ``source`` that means something else for
    the new technique is dropped. OptionError for a technique of the other kind."""
    document = scene_to_document(scene)
    for reflector in document.get("reflectors", []):
        if reflector.get("name") == name:
            allowed = technique_names("planar" if _is_planar(reflector) else "curved")
            parse_choice(f"technique of {name}", value, allowed)
            _set_technique(reflector, value)
            return from_document(document, scene.source)
    raise OptionError("technique", f"scene {scene.name!r} has no reflector {name!r}")


_KIND_NAMES = {True: "planar mirror", False: "curved reflector"}


def _reflectors_of_kind(document: dict, planar: bool, flag: str, why: str = "") -> list[dict]:
    """The document's planar (or curved) reflectors; OptionError when it has none."""
    targets = [r for r in document.get("reflectors", []) if _is_planar(r) == planar]
    if not targets:
        what = "none" if why else f"no {_KIND_NAMES[planar]}"
        raise OptionError(flag, f"{why}scene {document.get('name')!r} has {what}")
    return targets


def _apply_to(kind: str, key: str) -> Callable[[dict, Any, str], None]:
    def apply(document: dict, value: Any, flag: str) -> None:
        for reflector in _reflectors_of_kind(document, kind == "planar", flag):
            reflector[key] = value

    return apply


PARALLAX_FORMS = ("none", "box:X0,Y0,Z0,X1,Y1,Z1", "sphere:RADIUS", "distance[:STEPS[+SECANT]]")
"""How ``--parallax`` is written on a command line."""


def parse_parallax(flag: str, text: str) -> dict[str, Any] | str:
    """``--parallax`` text -> a scene file's ``parallax`` table, or ``"none"``:
    ``box:-4,-1,-4,4,3,4`` (the box's min and max corners), ``sphere:5`` (the radius),
    ``distance``, ``distance:16`` or ``distance:16+3`` (linear and secant steps).
    OptionError naming ``flag`` when the text has none of these forms; the values are
    checked as the scene file's would be."""
    proxy, _, rest = str(text).strip().partition(":")
    if proxy == "none" and not rest:
        return "none"
    if proxy == "box":
        values = parse_floats(flag, rest, 6, "X0,Y0,Z0,X1,Y1,Z1 after box:")
        return {"proxy": "box", "min": list(values[:3]), "max": list(values[3:])}
    if proxy == "sphere":
        return {"proxy": "sphere", "radius": parse_floats(flag, rest, 1, "RADIUS after sphere:")[0]}
    match = re.fullmatch(r"(?::(\d+)(?:\+(\d+))?)?", f":{rest}" if rest else "")
    if proxy == "distance" and match:
        table: dict[str, Any] = {"proxy": "distance"}
        if match.group(1):
            table["steps"] = int(match.group(1))
        if match.group(2):
            table["secant"] = int(match.group(2))
        return table
    raise OptionError(flag, f"expected one of {', '.join(PARALLAX_FORMS)}, got {text!r}")


def _apply_parallax(document: dict, value: Any, flag: str) -> None:
    """Give every reflector whose technique takes a parallax correction (``cube-live``,
    ``octahedral-live``, ``paraboloid-live``: its entry's ``parallax`` flag) the
    ``parallax`` ``value``: a ``parallax`` table as in a scene file, or its
    ``--parallax`` text; ``"none"`` removes the correction."""
    if isinstance(value, str):
        value = parse_parallax(flag, value)
    live = [
        r
        for r in document.get("reflectors", [])
        if getattr(_entry(r.get("technique")), "parallax", False)
    ]
    if not live:
        _reflectors_of_kind(document, False, flag)  # with no curved reflector, says so
        names = [t.name for t in techniques("curved") if t.parallax and not t.probe]
        raise OptionError(
            flag,
            f"scene {document.get('name')!r} has no {' or '.join(names)} "
            f"reflector (--method {names[0] if names else 'NAME'} makes every "
            f"curved reflector one)",
        )
    for reflector in live:
        if value == "none":
            reflector.pop("parallax", None)
        else:
            reflector["parallax"] = _plain_table(value)


def _plain_table(value: Any) -> Any:
    """A table from the API as TOML values: numpy arrays and tuples become lists, and whole
    numbers stay whole (``steps``), unlike :func:`_toml_floats`."""
    if isinstance(value, Mapping):
        return {str(k): _plain_table(v) for k, v in value.items()}
    if hasattr(value, "tolist"):
        return value.tolist()
    if isinstance(value, tuple):
        return [_plain_table(v) for v in value]
    return value


def _apply_cube_faces(document: dict, value: Any, flag: str) -> None:
    folder = Path(value).resolve()
    if not folder.is_dir():
        raise OptionError(flag, f"{value!r} is not a folder of six cube faces")
    document["background"] = {"cube_faces": str(folder)}


def _apply_set(document: dict, value: Any, flag: str) -> None:
    for key, item in value:
        _mirror_form_for(document, key, flag)
        set_key(document, key, item, flag)


_SHAPE_KEYS = ("center", "normal", "width", "height", "up")
"""How a scene file may give a planar mirror instead of its corners."""


def _mirror_form_for(document: dict, key: str, flag: str) -> None:
    """Before ``key`` is set: a planar mirror is written in a document by its corners (a
    file's center/normal/width/height/up become corners when it is read), so setting
    one of those shape keys puts the mirror back in that form first, and setting its
    corners drops them. OptionError when its corners are no rectangle."""
    match = re.fullmatch(r"reflectors\[(\d+)\]\.([A-Za-z_][\w-]*)(?:\[\d+\])?", key)
    reflectors = document.get("reflectors")
    if not match or not isinstance(reflectors, list) or int(match.group(1)) >= len(reflectors):
        return
    table = reflectors[int(match.group(1))]
    if not isinstance(table, dict):
        return
    field = match.group(2)
    if field == "corners":
        for name in _SHAPE_KEYS:
            table.pop(name, None)
        return
    if field not in _SHAPE_KEYS or "corners" not in table:
        return
    try:
        corners = np.asarray(table["corners"], dtype=np.float64).reshape(4, 3)
    except (TypeError, ValueError):
        return  # left to the scene's own check, which names what is wrong
    shape = rectangle_of(corners)
    if shape is None:
        raise OptionError(
            flag,
            f"{key}: reflectors[{match.group(1)}] is given by corners "
            f"that are no rectangle; set reflectors[{match.group(1)}].corners "
            f"instead",
        )
    del table["corners"]
    table.update(shape)


def rectangle_of(corners: np.ndarray) -> dict[str, list[float] | float] | None:
    """A rectangular mirror's corners ``(4, 3)`` (counter-clockwise from the front, the
    first edge along its height, as a scene file's center/normal/width/height/up make
    them) as those keys; None when they are no rectangle."""
    height_edge, width_edge = corners[1] - corners[0], corners[3] - corners[0]
    height, width = float(np.linalg.norm(height_edge)), float(np.linalg.norm(width_edge))
    if not (height > 0 and width > 0):
        return None
    size = max(height, width)
    closes = np.linalg.norm(corners[2] - (corners[1] + width_edge)) <= 1e-9 * size
    square = abs(float(height_edge @ width_edge)) <= 1e-9 * height * width
    if not (closes and square):
        return None
    up = height_edge / height
    normal = np.cross(up, width_edge / width)  # the loader takes right = normal x up
    return {
        "center": corners.mean(axis=0).tolist(),
        "normal": normal.tolist(),
        "width": width,
        "height": height,
        "up": up.tolist(),
    }


def _parse_set(flag: str, text: str) -> tuple[tuple[str, Any], ...]:
    key, sep, raw = str(text).partition("=")
    if not sep or not key.strip():
        raise OptionError(flag, f"expected KEY=VALUE (e.g. camera.fovy=30), got {text!r}")
    try:
        value = tomllib.loads(f"value = {raw}")["value"]
    except tomllib.TOMLDecodeError:
        value = raw.strip()  # a bare word: a string
    return ((key.strip(), value),)


def _method_help() -> str:
    frames = technique_names("frame")
    drawn = f"; or the whole frame drawn by {', '.join(frames)}" if frames else ""
    return (
        f"technique for every reflector of its kind: planar "
        f"{', '.join(technique_names('planar'))}; curved "
        f"{', '.join(technique_names('curved'))}{drawn}"
    )


OPTIONS: tuple[Option, ...] = (
    Option(
        "camera",
        "X,Y,Z",
        "viewer position (the scene's camera.eye)",
        _vec3("X,Y,Z"),
        _set_camera("eye"),
        r"camera\.eye",
    ),
    Option(
        "target",
        "X,Y,Z",
        "point the viewer looks at (camera.target)",
        _vec3("X,Y,Z"),
        _set_camera("target"),
        r"camera\.target",
    ),
    Option(
        "fovy",
        "DEGREES",
        "vertical field of view (camera.fovy)",
        lambda flag, text: parse_floats(flag, text, 1, "DEGREES")[0],
        _set_camera("fovy"),
        r"camera\.fovy",
    ),
    Option(
        "angles",
        "BASE,LOWER,UPPER",
        "the robot's joint angles in degrees",
        _vec3("BASE,LOWER,UPPER"),
        _apply_angles,
        "objects",
    ),
    Option(
        "method",
        "NAME",
        _method_help,
        lambda flag, text: parse_choice(flag, text, technique_names()),
        _apply_technique,
        "reflectors",
    ),
    Option(
        "parallax",
        "PROXY",
        "how the lookups of the live maps that take a parallax correction correct for "
        f"nearby surroundings: {', '.join(PARALLAX_FORMS)}",
        parse_parallax,
        _apply_parallax,
        r"reflectors\[\d+\]\.parallax",
    ),
    Option(
        "capture",
        "MODE",
        "how planar captures reach their texture: copy (glCopyTexImage2D) or fbo (drawn into it)",
        lambda flag, text: parse_choice(flag, text, CAPTURE_MODES),
        _apply_to("planar", "capture"),
        "reflectors",
    ),
    Option(
        "env_size",
        "N",
        "planar capture texture side in pixels (default: the view's), "
        f"or {FOOTPRINT_TEXTURE} (ortho: the size of the mirror's footprint on screen)",
        lambda flag, text: text if text == FOOTPRINT_TEXTURE else parse_count(flag, text, 1, 4096),
        _apply_to("planar", "texture_size"),
        "reflectors",
    ),
    Option(
        "map_size",
        "N",
        "curved reflectors' map side in texels",
        lambda flag, text: parse_count(flag, text, 4, 4096),
        _apply_to("curved", "map_size"),
        "reflectors",
    ),
    Option(
        "max_bounces",
        "N",
        "how deep reflections of reflections go (0: plain)",
        lambda flag, text: parse_count(flag, text, 0, 6),
        lambda document, value, flag: document.__setitem__("max_bounces", value),
        "max_bounces",
    ),
    Option(
        "cube_faces",
        "DIR",
        "six pictures DIR/{px,nx,py,ny,pz,nz}.png as the background (and the static cube maps)",
        lambda flag, text: text,
        _apply_cube_faces,
        "background",
    ),
    Option(
        "set",
        "KEY=VALUE",
        "set any scene key, as in the file (e.g. camera.fovy=30, "
        "'reflectors[0].technique=\"stencil\"'); repeatable",
        _parse_set,
        _apply_set,
        repeat=True,
    ),
)
OPTION_NAMES = {option.name: option for option in OPTIONS}


def split_frame_technique(values: Mapping[str, Any]) -> tuple[Technique | None, dict]:
    """The frame technique ``values["method"]`` names (one that draws the whole frame, such
    as the ray tracer), and the other options; ``(None, values)`` when it names none."""
    entry = frame_technique(values.get("method"))
    rest = dict(values)
    if entry is not None:
        rest.pop("method")
    return entry, rest


def apply_options(scene: Scene, values: Mapping[str, Any]) -> Scene:
    """``scene`` with the options ``values`` (by :attr:`Option.name`) applied; the result is
    checked like a scene file. OptionError naming the option for a bad value."""
    chosen = {name: value for name, value in values.items() if value is not None}
    if not chosen:
        return scene
    unknown = [name for name in chosen if name not in OPTION_NAMES]
    if unknown:
        raise TypeError(f"unknown option {unknown[0]!r}; options are {', '.join(OPTION_NAMES)}")
    document = scene_to_document(scene)
    # In the declared order, whatever the order given: --method before --parallax.
    for option in (option for option in OPTIONS if option.name in chosen):
        name, value = option.name, chosen[option.name]
        if name == "set" and isinstance(value, str):
            value = (value,)  # one KEY=VALUE from the Python API
        if name == "set" and value and isinstance(value[0], str):
            value = tuple(_parse_set(option.flag, item)[0] for item in value)
        option.apply(document, value, option.flag)
    try:
        return from_document(document, scene.source)
    except SceneError as exc:
        raise OptionError(
            _blame(chosen, exc.key), f"{exc.key}: {exc.problem}" if exc.key else exc.problem
        ) from None


def _blame(chosen: Mapping[str, Any], key: str) -> str:
    """The flags of the chosen options that wrote ``key`` (all of them if none did)."""
    matched = {}
    for name in chosen:
        writes = OPTION_NAMES[name].writes
        found = re.match(writes, key) if writes else None
        if found:
            matched[OPTION_NAMES[name].flag] = found.end()
    named = [flag for flag, length in matched.items() if length == max(matched.values())]
    return " / ".join(named or [OPTION_NAMES[name].flag for name in chosen])


def set_key(document: dict, key: str, value: Any, flag: str = "--set") -> None:
    """Set ``key`` (``camera.eye``, ``reflectors[1].technique``) in ``document``."""
    if not re.fullmatch(r"[A-Za-z_][\w-]*(\[\d+\])*(\.[A-Za-z_][\w-]*(\[\d+\])*)*", key):
        raise OptionError(
            flag, f"expected a key path such as camera.eye or reflectors[0].technique, got {key!r}"
        )
    parts = re.findall(r"([A-Za-z_][\w-]*)|\[(\d+)\]", key)
    node: Any = document
    path = [name if name else int(index) for name, index in parts]
    if not path:
        raise OptionError(flag, f"expected a key path such as camera.eye, got {key!r}")
    for step, following in itertools.pairwise(path):
        if isinstance(step, int):
            if not isinstance(node, list) or step >= len(node):
                raise OptionError(flag, f"{key}: no item [{step}] there")
            node = node[step]
        else:
            if not isinstance(node, dict):
                raise OptionError(flag, f"{key}: {step!r} is not inside a table")
            node = node.setdefault(step, [] if isinstance(following, int) else {})
    last = path[-1]
    if isinstance(last, int):
        if not isinstance(node, list) or last >= len(node):
            raise OptionError(flag, f"{key}: no item [{last}] there")
        node[last] = value
    elif isinstance(node, dict):
        node[last] = value
    else:
        raise OptionError(flag, f"{key}: {last!r} is not inside a table")


def _toml_floats(value: Any) -> Any:
    """A number or vector from the API or a flag as a TOML value: numpy arrays, tuples and
    lists become lists, and every number a float."""
    if hasattr(value, "tolist"):  # numpy arrays and scalars
        value = value.tolist()
    if isinstance(value, tuple | list):
        return [_toml_floats(v) for v in value]
    if isinstance(value, int | float) and not isinstance(value, bool):
        return float(value)
    return value
