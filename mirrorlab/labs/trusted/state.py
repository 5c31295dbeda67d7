"""What the trusted side knows of the GL state the student's calls made, and who made it.

The executor updates a :class:`Tracker` after each call it executed: the matrix mode and
the operations on each matrix, the viewport, the clear colour, the active texture unit,
the textures bound on each unit, the enabled switches and the texgen modes per unit, the
current program; for each of them the student's line that set it and the lab function
that was running. Each texture keeps where each level of each face came from
(:class:`Image`): blank (a file uploads only None or zeros), a lab picture, a copy of the
framebuffer, or mipmaps made from level 0 (by glGenerateMipmap or GL_GENERATE_MIPMAP).
Nothing here is read from the sandbox but the calls.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import Any

GL_MODELVIEW, GL_PROJECTION, GL_TEXTURE = 0x1700, 0x1701, 0x1702
GL_TEXTURE_2D, GL_TEXTURE_CUBE_MAP = 0x0DE1, 0x8513
CUBE_FACE_TARGETS = tuple(range(0x8515, 0x851B))
UNIT_CAPS = {
    0x0DE1: "GL_TEXTURE_2D",
    0x8513: "GL_TEXTURE_CUBE_MAP",
    0x0C60: "GL_TEXTURE_GEN_S",
    0x0C61: "GL_TEXTURE_GEN_T",
    0x0C62: "GL_TEXTURE_GEN_R",
    0x0C63: "GL_TEXTURE_GEN_Q",
}
"""Switches that belong to the active texture unit."""
TEXGEN_COORDS = {0x2000: "s", 0x2001: "t", 0x2002: "r", 0x2003: "q"}
UNITS = 8
TRACED = 3000
"""Call records kept a frame (and for the set-up): a file that makes more is a flood."""


def small(value: Any, depth: int = 0) -> Any:
    """``value`` (a call's arguments, JSON-like) made small for the call trace: strings cut to
    40 characters (GLSL becomes ``"<glsl>"``), lists to 16 items, dicts to 16 keys, pixel
    data to ``"<data>"``, three levels deep."""
    if isinstance(value, str):
        return "<glsl>" if len(value) > 40 or "\n" in value else value
    if isinstance(value, int) and not isinstance(value, bool) and not -(1 << 63) <= value < 1 << 63:
        return f"{str(value)[:8]}... (an integer of {len(str(abs(value)))} digits)"
    if isinstance(value, bool | int | float) or value is None:
        return value
    if depth >= 3:
        return "..."
    if isinstance(value, dict):
        if set(value) == {"$a"}:
            return "<data>"
        return {str(k)[:40]: small(v, depth + 1) for k, v in list(value.items())[:16]}
    if isinstance(value, list | tuple):
        return [small(v, depth + 1) for v in list(value)[:16]]
    return str(value)[:40]


@dataclass
class Setting:
    """A value and where the student set it: ``line`` of their file (0: the lab or GL's
    default) and the lab ``function`` running then."""

    value: Any
    line: int = 0
    function: str = ""

    def plain(self) -> dict[str, Any]:
        return {"value": self.value, "line": self.line, "function": self.function}


@dataclass
class Image:
    """One level of one face of a texture: its size and format, and where its texels came
    from (``blank``, ``picture:NAME``, ``copy``, ``mipmap``)."""

    width: int
    height: int
    internalformat: int
    source: str
    line: int
    function: str
    frame: int

    def plain(self) -> dict[str, Any]:
        return dict(vars(self))


@dataclass
class Texture:
    """A texture the student made (``glGenTextures``)."""

    name: int
    target: int = 0
    images: dict[tuple[int, int], Image] = field(default_factory=dict)
    params: dict[int, Setting] = field(default_factory=dict)
    picture: str = ""
    mipmaps: Setting | None = None
    mipmaps_fresh: bool = False
    """Whether glGenerateMipmap ran after the last write to a level-0 picture."""
    writes: int = 0

    def nbytes(self) -> int:
        return sum(i.width * i.height * texel_bytes(i.internalformat) for i in self.images.values())

    def plain(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "target": self.target,
            "picture": self.picture,
            "images": [[f, lv, im.plain()] for (f, lv), im in sorted(self.images.items())],
            "params": {str(k): v.plain() for k, v in self.params.items()},
            "mipmaps": self.mipmaps.plain() if self.mipmaps else None,
            "mipmaps_fresh": self.mipmaps_fresh,
        }


TEXEL_BYTES = {
    0x8058: 4,
    0x1907: 4,
    0x1908: 4,
    0x8051: 4,
    3: 4,
    4: 4,
    1: 4,
    2: 4,
    0x881A: 8,
    0x881B: 8,
    0x8814: 16,
    0x8815: 16,
    0x805B: 8,
    0x8054: 8,
}


def texel_bytes(internalformat: int) -> int:
    """What one texel of ``internalformat`` may cost (at least 4 bytes)."""
    return TEXEL_BYTES.get(internalformat, 4)


@dataclass
class Primitive:
    """A glBegin ... glEnd being drawn: its vertices as (position (4,), texture coordinates
    of units 0-3 ((4,) each), colour (4,))."""

    mode: int
    line: int
    function: str
    vertices: list[tuple[list[float], list[list[float]], list[float]]] = field(default_factory=list)


class Tracker:
    """The tracked state of one run (see the module's text)."""

    def __init__(self) -> None:
        self.matrix_mode = Setting(GL_MODELVIEW)
        self.matrix_ops: dict[int, list[dict[str, Any]]] = {
            GL_MODELVIEW: [],
            GL_PROJECTION: [],
            GL_TEXTURE: [],
        }
        self.matrix_stacks: dict[int, list[list[dict[str, Any]]]] = {}
        self.viewport: Setting = Setting(None)
        self.clear_color = Setting((0.0, 0.0, 0.0, 0.0))
        self.active_unit = Setting(0)
        self.bindings: dict[tuple[int, int], Setting] = {}
        self.enabled: dict[tuple[int, int], Setting] = {}
        self.texgen: dict[tuple[int, int], Setting] = {}
        self.program = Setting(0)
        self.uniforms: dict[tuple[int, int], Setting] = {}
        self.textures: dict[int, Texture] = {}
        self.texcoords = [[0.0, 0.0, 0.0, 1.0] for _ in range(4)]
        self.color = [1.0, 1.0, 1.0, 1.0]
        self.primitive: Primitive | None = None
        self.steps: list[str] = []
        self.frames: list[dict[str, Any]] = []
        self.setup_events: list[dict[str, Any]] = []
        self.line = 0
        self.frame_bytes = 0
        """What the events of this frame (or of the set-up) take as JSON, about: the
        executor caps it (:class:`~.call_executor.RunLimits`)."""
        self._snapshot: dict[str, Any] | None = None
        """The last state snapshot: events share it while the state does not change."""
        self._counted: dict[str, Any] | None = None
        self.traced = 0
        """Call records of this frame (or of the set-up) so far (:meth:`trace`)."""

    # ---------------------------------------------------------------- who and where
    @property
    def function(self) -> str:
        return self.steps[-1] if self.steps else ""

    def setting(self, value: Any) -> Setting:
        return Setting(value, self.line, self.function)

    @property
    def events(self) -> list[dict[str, Any]]:
        return self.frames[-1]["events"] if self.frames else self.setup_events

    def event(self, kind: str, **values: Any) -> dict[str, Any]:
        record = {
            "kind": kind,
            "line": self.line,
            "function": self.function,
            "steps": list(self.steps),
            **values,
        }
        state = values.get("state")
        shared = state is not None and state is self._counted
        plain = {k: v for k, v in record.items() if k != "state" or not shared}
        self.frame_bytes += len(json.dumps(plain, default=str))
        if isinstance(state, dict):
            self._counted = state  # saved once however many events share it
        self.events.append(record)
        return record

    def begin_frame(self) -> None:
        self.frames.append({"events": []})
        self.frame_bytes, self._counted, self.traced = 0, None, 0

    def trace(self, op: str, name: str, args: Any) -> dict[str, Any] | None:
        """The call trace: one ``call`` event per call the student's file made (``fn``, its
        arguments made small, the student's line and lab function) with the state it acted
        in (``ctx``: the active unit ``u``, the 2D and cube-map textures bound there ``t2``
        and ``tc``, the matrix mode ``m``, the program ``p``, inside glBegin ``b``), before
        it runs; the executor adds ``error`` when it failed. At most :data:`TRACED` a frame
        (the labs make a few dozen), not counted in the evidence's cap."""
        if self.traced >= TRACED:
            return None
        self.traced += 1
        unit = self.active_unit.value
        record = {
            "kind": "call",
            "line": self.line,
            "function": self.function,
            "steps": list(self.steps),
            "fn": name,
            "op": op,
            "args": small(args),
            "ctx": {
                "u": unit,
                "t2": self.bound(GL_TEXTURE_2D, unit),
                "tc": self.bound(GL_TEXTURE_CUBE_MAP, unit),
                "m": self.matrix_mode.value,
                "p": self.program.value,
                "b": int(self.primitive is not None),
            },
        }
        self.events.append(record)
        return record

    # ---------------------------------------------------------------- state changes
    def bound(self, target: int, unit: int | None = None) -> int:
        setting = self.bindings.get((self.active_unit.value if unit is None else unit, target))
        return int(setting.value) if setting else 0

    def is_enabled(self, cap: int, unit: int | None = None) -> bool:
        key = (cap, (self.active_unit.value if unit is None else unit) if cap in UNIT_CAPS else -1)
        setting = self.enabled.get(key)
        return bool(setting and setting.value)

    def set_enabled(self, cap: int, on: bool) -> None:
        key = (cap, self.active_unit.value if cap in UNIT_CAPS else -1)
        self.enabled[key] = self.setting(bool(on))

    def matrix_op(self, name: str, args: list[Any], replaces: bool = False) -> None:
        ops = self.matrix_ops.setdefault(self.matrix_mode.value, [])
        if replaces:
            ops.clear()
        if len(ops) < 64:
            ops.append(
                {
                    "op": name,
                    "args": args,
                    "line": self.line,
                    "function": self.function,
                    "mode": self.matrix_mode.value,
                }
            )

    def texture_bound(self, target: int) -> Texture | None:
        """The student's texture bound to ``target`` (its binding target, GL_TEXTURE_2D or
        GL_TEXTURE_CUBE_MAP) on the active unit."""
        return self.textures.get(self.bound(target))

    def snapshot(self) -> dict[str, Any]:
        """The state a draw or copy is judged by (JSON-able)."""
        units = {}
        for unit in range(UNITS):
            entry = {}
            for target, key in ((GL_TEXTURE_2D, "2d"), (GL_TEXTURE_CUBE_MAP, "cube")):
                setting = self.bindings.get((unit, target))
                if setting and setting.value:
                    entry[key] = setting.plain()
            for cap, name in UNIT_CAPS.items():
                setting = self.enabled.get((cap, unit))
                if setting and setting.value:
                    entry[name] = setting.plain()
            for coord, name in TEXGEN_COORDS.items():
                setting = self.texgen.get((unit, coord))
                if setting is not None:
                    entry[f"texgen_{name}"] = setting.plain()
            if entry:
                units[str(unit)] = entry
        enabled = {str(cap): s.plain() for (cap, unit), s in self.enabled.items() if unit == -1}
        snapshot = {
            "matrix_mode": self.matrix_mode.plain(),
            "viewport": self.viewport.plain(),
            "clear_color": self.clear_color.plain(),
            "active_unit": self.active_unit.plain(),
            "program": self.program.plain(),
            "units": units,
            "enabled": enabled,
            "matrix_ops": {str(k): list(v) for k, v in self.matrix_ops.items()},
        }
        if snapshot != self._snapshot:
            self._snapshot = snapshot
        return self._snapshot  # the same object while the state is the same: shared
