"""Hints from the student's own call trace: every lab's, one module.

The trusted checker records every call a student's file made (``call`` events: the call
as made, its line, the lab function it ran in, and the state it acted in: the active
unit, the textures bound there, the matrix mode, the program, inside glBegin or not;
see :meth:`.state.Tracker.trace`). The reference solution's run records the same. This
module reads both as :class:`Trace` s and, for a lab function, aligns the calls the
student's made with the calls the solution's made there, in order (a sequence alignment
over normalised calls: the call's family, such as ``glVertex`` for ``glVertex3fv``, and its
arguments as numbers, enum names and the textures' roles, with the equivalences the
handouts allow). The first divergence that changes something is named in the student's
own terms, with the line: a call missing, one extra, one out of order (the copy before
the draw it should follow, the texture coordinate after its vertex), other arguments, or
a call that took no effect because of the state it met (the texture bound, the unit
active, the matrix mode, the program in use), a call GL refused, or one whose arguments
cannot work (:func:`.calls.degenerate`). A lab function the frame never calls is named
as such before anything about its contents. A hint never asks for a call the file
already makes with the same arguments: it says why that call did not take effect
(:meth:`Hints.guard`).

Numpy only: it reads :class:`~.evidence.Evidence`, which only the trusted process made.
"""

from __future__ import annotations

import functools
import math
import re
from collections.abc import Iterable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mirrorlab.labs.trusted.evidence import Evidence
from mirrorlab.labs.trusted.judging import COLOUR_FORMATS

GL_TEXTURE_2D, GL_TEXTURE_CUBE_MAP = 0x0DE1, 0x8513
GL_MODELVIEW, GL_PROJECTION, GL_TEXTURE = 0x1700, 0x1701, 0x1702
GL_TEXTURE0 = 0x84C0
CUBE_FACES = tuple(range(0x8515, 0x851B))
UNIT_CAPS = frozenset({0x0DE1, 0x8513, 0x0C60, 0x0C61, 0x0C62, 0x0C63})
"""Switches that belong to the active texture unit (GL_TEXTURE_2D ... GL_TEXTURE_GEN_Q)."""
MODE_NAMES = {
    GL_MODELVIEW: "GL_MODELVIEW",
    GL_PROJECTION: "GL_PROJECTION",
    GL_TEXTURE: "GL_TEXTURE",
}
CLAMP = 0x2900
FILL_MODES = frozenset({0x0004, 0x0005, 0x0006, 0x0007, 0x0008, 0x0009})
"""glBegin's modes that fill (triangles, strips, fans, quads, polygons): the handouts allow
any of them for a quad, with the vertices they need."""

FORM = re.compile(
    r"^gl(?P<base>Vertex|TexCoord|MultiTexCoord|Color|Normal|Translate|Scale|Rotate|"
    r"LoadTransposeMatrix|MultTransposeMatrix|LoadMatrix|MultMatrix|TexParameter|TexEnv|"
    r"TexGen|Uniform|ClearDepth|DepthRange|PixelStore)"
    r"(?P<n>[1-4])?(?P<type>ub|us|ui|b|s|i|f|d)?(?P<v>v)?$"
)
QUERIES = re.compile(r"^gl(Get|Is)\w*$")
TYPE_TOP = {"b": 127, "s": 32767, "i": 2147483647, "ub": 255, "us": 65535, "ui": 4294967295}
"""The largest value of each integer type: GL's colour conversion makes it 1.0."""
ARGUMENT_NAMES: dict[str, tuple[str, ...]] = {
    "glOrtho": ("left", "right", "bottom", "top", "zNear", "zFar"),
    "glFrustum": ("left", "right", "bottom", "top", "zNear", "zFar"),
    "gluPerspective": ("fovy", "aspect", "zNear", "zFar"),
    "gluOrtho2D": ("left", "right", "bottom", "top"),
    "gluLookAt": (
        "eyeX",
        "eyeY",
        "eyeZ",
        "centerX",
        "centerY",
        "centerZ",
        "upX",
        "upY",
        "upZ",
    ),
}
"""Argument names where the trace's own (:attr:`Trace.signatures`, PyOpenGL's) are missing,
as in evidence made before it kept them."""
DEPTH_ARGUMENTS = frozenset({"zNear", "zFar"})
"""A projection's near and far planes: the handouts allow others that keep the scene, so an
alignment compares a projection without them (the task's own check judges them)."""


# ---------------------------------------------------------------------------- calls
@dataclass
class Call:
    """One call of a trace, or a lab function called (``kind`` ``function``): where it ran
    and what it did, normalised for an alignment (``key``) and for explaining what it
    changed (``writes``)."""

    at: int
    fn: str
    kind: str
    args: list[Any]
    names: dict[int, str]
    line: int
    function: str
    frame: int
    ctx: dict[str, int]
    error: str = ""
    note: str = ""
    family: str = ""
    key: tuple[Any, ...] = ()
    writes: tuple[tuple[Any, ...], ...] = ()
    values: dict[tuple[Any, ...], Any] = field(default_factory=dict)
    text: str = ""
    end: int = -1
    """For a lab function: the position of its last call."""


def _number(value: Any) -> Any:
    if isinstance(value, bool):
        return int(value)
    if isinstance(value, int | float):
        try:
            number = round(float(value), 4) + 0.0
        except OverflowError:
            return str(value)[:24]
        return number if math.isfinite(number) else str(number)
    return value


def _flat(args: list[Any]) -> list[Any]:
    """A vector form's one list argument, or the arguments as they are."""
    if len(args) == 1 and isinstance(args[0], list):
        return list(args[0])
    return list(args)


def fmt(values: Iterable[Any]) -> str:
    """Numbers as a person writes them: ``-6, 2, -3``."""
    return ", ".join(f"{float(v):g}" if isinstance(v, int | float) else str(v) for v in values)


class Roles:
    """The textures, programs and uniforms by the names the student knows them by
    (``tex_ids[ENVIRONMENT]``, ``lab.textureShader``, ``lab.texSampler``): each maps a key of
    the evidence's observations (``environment``) to the name; a texture without a role is
    ``texture N``."""

    def __init__(
        self,
        evidence: Evidence,
        textures: dict[str, str],
        programs: dict[str, str] | None = None,
        uniforms: dict[str, str] | None = None,
    ) -> None:
        def found(names: dict[str, str]) -> dict[int, str]:
            by_id: dict[int, str] = {}
            for key, name in names.items():
                value = evidence.state.get(key)
                if isinstance(value, int) and value not in by_id and (value or names is uniforms):
                    by_id[value] = name
            return by_id

        self.by_id = found(textures)
        self.programs = found(programs or {})
        self.uniforms = found(uniforms or {})

    def __call__(self, texture: Any) -> str:
        if not isinstance(texture, int | float) or not texture:
            return "no texture"
        return self.by_id.get(int(texture), f"texture {int(texture)}")

    def program(self, value: Any) -> str:
        if not isinstance(value, int | float) or not value:
            return "0"
        return self.programs.get(int(value), f"program {int(value)}")

    def uniform(self, value: Any) -> str:
        if not isinstance(value, int | float):
            return str(value)
        return self.uniforms.get(int(value), f"{int(value)}")


class Trace:
    """The calls of one run (set-up, then each frame), normalised, with the lab functions
    called among them. ``roles`` names the textures."""

    def __init__(self, evidence: Evidence, roles: Roles) -> None:
        self.evidence, self.roles = evidence, roles
        self.calls: list[Call] = []
        self.signatures: dict[str, list[str]] = dict(evidence.state.get("signatures") or {})
        sources = [(-1, evidence.setup)] + [
            (i, frame.get("events") or []) for i, frame in enumerate(evidence.frames)
        ]
        self.last = len(evidence.frames) - 1
        for frame, events in sources:
            open_functions: list[Call] = []
            for event in events if isinstance(events, list) else []:
                if not isinstance(event, dict):
                    continue
                kind = event.get("kind")
                if kind == "call":
                    self._add(event, frame)
                elif kind == "enter":
                    steps = event.get("steps") or []
                    call = Call(
                        len(self.calls),
                        f"{event.get('function', '')}()",
                        "function",
                        [],
                        {},
                        int(event.get("line") or 0),
                        str(steps[-2]) if len(steps) >= 2 else "",
                        frame,
                        {},
                    )
                    call.family = "function"
                    call.key = ("function", event.get("function", ""))
                    call.text = call.fn
                    self.calls.append(call)
                    open_functions.append(call)
                elif kind == "leave" and open_functions:
                    opened = open_functions.pop()
                    opened.end = len(self.calls) - 1
            for opened in open_functions:
                opened.end = len(self.calls) - 1
        for call in self.calls:
            if call.kind == "function":
                writes: dict[tuple[Any, ...], Any] = {}
                for inner in self.calls[call.at + 1 : call.end + 1]:
                    for slot in inner.writes:
                        writes[slot] = inner.values.get(slot)
                call.writes, call.values = tuple(writes), writes

    # ------------------------------------------------------------------ reading
    def _add(self, event: dict[str, Any], frame: int) -> None:
        names = event.get("names") or {}
        ctx = event.get("ctx") or {}
        op = str(event.get("op", "gl"))
        fn = str(event.get("fn", ""))
        args = event.get("args")
        call = Call(
            len(self.calls),
            f"lab.{fn}" if op == "kit" else fn,
            op,
            list(args) if isinstance(args, list) else [],
            {int(k): str(v) for k, v in names.items() if str(k).isdigit()}
            if isinstance(names, dict)
            else {},
            int(event.get("line") or 0),
            str(event.get("function", "")),
            frame,
            {k: int(v) for k, v in ctx.items() if isinstance(v, int | float)}
            if isinstance(ctx, dict)
            else {},
            str(event.get("error") or ""),
            str(event.get("note") or ""),
        )
        try:
            _normalise(call, self.roles)
        except Exception:  # arguments of a shape no call takes: kept, unread
            call.family, call.key, call.writes, call.values = "unread", ("unread", fn), (), {}
            call.text = f"{call.fn}(...)"
        self.calls.append(call)

    def argument_names(self, fn: str) -> tuple[str, ...]:
        found = self.signatures.get(fn)
        return tuple(found) if found else ARGUMENT_NAMES.get(fn, ())

    def made_in(self, function: str, frame: int) -> list[Call]:
        """The calls ``function`` made itself, the last time it ran in ``frame`` (-1: the
        set-up), with the lab functions it called as calls of their own, in order; queries
        left out. (A function run more often than the solution's is its caller's divergence.)"""
        runs = self.entered(function, frame)
        start, end = (runs[-1].at + 1, runs[-1].end + 1) if runs else (0, len(self.calls))
        return [
            c
            for c in self.calls[start:end]
            if c.frame == frame and c.function == function and c.family != "query"
        ]

    def entered(self, function: str, frame: int | None = None) -> list[Call]:
        """Where lab function ``function`` was called (in ``frame``; None: ever)."""
        return [
            c
            for c in self.calls
            if c.kind == "function" and c.key[1] == function and (frame is None or c.frame == frame)
        ]

    def value_before(self, slot: tuple[Any, ...], at: float) -> tuple[Any, Call | None]:
        """The value ``slot`` held just before position ``at``, and the call that set it
        (None: GL's default, when it is known, else unknown)."""
        for call in reversed(self.calls[: max(math.ceil(at), 0)]):
            if call.kind != "function" and slot in call.values:
                return call.values[slot], call
        return DEFAULTS.get(slot[0], UNKNOWN), None

    def with_key(self, key: tuple[Any, ...]) -> list[Call]:
        return [c for c in self.calls if c.key == key and c.kind != "function"]


UNKNOWN = object()
DEFAULTS: dict[str, Any] = {
    "unit": (0,),
    "matrix_mode": (GL_MODELVIEW,),
    "program": (0,),
    "enable": (0,),
    "texgen": (0x2400,),
}
"""GL's state before any call, where an alignment may take it as known (the lab functions'
own drawing keeps these as it found them)."""


def _normalise(call: Call, roles: Roles) -> None:
    """``call``'s family, alignment key, shown text and the state it writes."""
    fn, args, ctx = call.fn, call.args, call.ctx
    unit = ctx.get("u", 0)
    if call.kind == "kit":
        _kit(call, roles)
        return
    if QUERIES.match(fn) or fn in ("glGetError", "glFlush", "glFinish"):
        call.family, call.key, call.text = "query", ("query", fn), fn + "(...)"
        return
    form = FORM.match(fn)
    family = f"gl{form.group('base')}" if form else fn
    if form and form.group("base") in ("LoadTransposeMatrix", "MultTransposeMatrix"):
        family = "glLoadMatrix" if "Load" in family else "glMultMatrix"
        flat = [_number(v) for v in _flat(args)]
        args = (
            list(np.asarray(flat, dtype=float).reshape(4, 4).T.reshape(-1))
            if len(flat) == 16
            else flat
        )
    if form and form.group("base") == "TexGen" and form.group("v"):
        family = "glTexGenv"
    if form and form.group("base") == "MultiTexCoord":
        family = "glTexCoord"
        unit_arg = args[0] - GL_TEXTURE0 if args and isinstance(args[0], int) else 0
        coords = _flat(args[1:])
        key_args: list[Any] = [unit_arg, *_padded(coords, (0.0, 0.0, 0.0, 1.0))]
        call.writes = (("texcoord", unit_arg),)
    elif family == "glTexCoord":
        key_args = [0, *_padded(_flat(args), (0.0, 0.0, 0.0, 1.0))]
        call.writes = (("texcoord", 0),)
    elif family == "glVertex":
        key_args = _padded(_flat(args), (0.0, 0.0, 0.0, 1.0))
        call.writes = (("vertex",),)
    elif family == "glColor":
        top = TYPE_TOP.get(form.group("type") or "f", 1) if form else 1
        key_args = _padded([_number(v / top) for v in _flat(args)], (0.0, 0.0, 0.0, 1.0))
        call.writes = (("color",),)
    elif family == "glNormal":
        key_args = [_number(v) for v in _flat(args)]
        call.writes = (("normal",),)
    else:
        key_args = [_value(fn, i, v, call.names) for i, v in enumerate(args)]
    call.family = family
    writes: list[tuple[Any, ...]] = list(call.writes)
    values: dict[tuple[Any, ...], Any] = {}
    slot: tuple[Any, ...]

    def bound(target: Any) -> str:
        kind = "tc" if target == GL_TEXTURE_CUBE_MAP or target in CUBE_FACES else "t2"
        return roles(ctx.get(kind, 0))

    if family == "glActiveTexture" and args:
        writes, values = [("unit",)], {("unit",): (args[0] - GL_TEXTURE0,)}
    elif family == "glBindTexture" and len(args) == 2:
        key_args = [key_args[0], roles(args[1])]
        slot = ("binding", unit, args[0])
        writes, values = [slot], {slot: (roles(args[1]),)}
    elif family == "glTexParameter" and len(args) == 3:
        slot = ("texparam", bound(args[0]), args[1])
        value = key_args[2]
        writes, values = [slot], {slot: (value,)}
        key_args = [*key_args[:2], value]
    elif family in ("glTexImage2D", "glTexSubImage2D", "glCopyTexImage2D", "glCopyTexSubImage2D"):
        if len(args) >= 2:
            face = args[0] - CUBE_FACES[0] if args[0] in CUBE_FACES else 0
            slot = ("image", bound(args[0]), face, args[1])
            writes, values = [slot], {slot: None}
    elif family == "glGenerateMipmap" and args:
        slot = ("mipmaps", bound(args[0]))
        writes, values = [slot], {slot: None}
    elif family in ("glEnable", "glDisable") and args:
        cap = args[0]
        slot = ("enable", cap, unit if cap in UNIT_CAPS else -1)
        family = "glEnable"
        key_args = [key_args[0], int(fn == "glEnable")]
        writes, values = [slot], {slot: (int(fn == "glEnable"),)}
    elif family == "glTexGen" and len(args) == 3:
        slot = ("texgen", unit, args[0])
        writes, values = [slot], {slot: (key_args[2],)}
    elif family == "glTexEnv":
        slot = ("texenv", unit)
        writes, values = [slot], {slot: tuple(key_args[1:])}
    elif family == "glMatrixMode" and args:
        writes, values = [("matrix_mode",)], {("matrix_mode",): (args[0],)}
    elif fn in MATRIX_OPS or family in (
        "glTranslate",
        "glScale",
        "glRotate",
        "glLoadMatrix",
        "glMultMatrix",
    ):
        slot = ("matrix", ctx.get("m", GL_MODELVIEW))
        writes, values = [slot], {slot: None}
        key_args = _matrix_key(fn, family, key_args)
    elif family == "glUseProgram" and args:
        key_args = [roles.program(args[0])]
        writes, values = [("program",)], {("program",): (key_args[0],)}
    elif family in ("glViewport", "glScissor", "glClearColor"):
        slot = {"glViewport": ("viewport",), "glScissor": ("scissor",)}.get(
            family, ("clear_color",) if family == "glClearColor" else ("program",)
        )
        writes, values = [slot], {slot: tuple(key_args)}
    elif family == "glClear":
        writes, values = [("framebuffer",)], {("framebuffer",): None}
    elif family == "glUniform" and args:
        key_args = [roles.uniform(args[0]), *key_args[1:]]
        slot = ("uniform", roles.program(ctx.get("p", 0)), roles.uniform(args[0]))
        writes, values = [slot], {slot: tuple(_number(v) for v in _flat(args[1:]))}
    elif family == "glBegin" and args:
        key_args = ["fill" if args[0] in FILL_MODES else key_args[0]]
        writes, values = [("primitive",)], {("primitive",): None}
    elif family == "glEnd":
        writes, values = [("framebuffer",)], {("framebuffer",): None}
    elif family in ("glTexCoord", "glVertex", "glColor", "glNormal"):
        values = {w: tuple(key_args) for w in writes}
    elif family in ("glGenTextures", "glDeleteTextures"):
        writes, values = [], {}
    else:
        writes, values = [(family,)], {(family,): tuple(key_args)}
    call.family, call.writes, call.values = family, tuple(writes), values
    call.key = (family, *[_hashable(v) for v in key_args])
    call.text = _text(call, roles)


MATRIX_OPS = frozenset(
    {"glOrtho", "glFrustum", "gluOrtho2D", "gluPerspective", "gluLookAt", "glLoadIdentity"}
    | {"glPushMatrix", "glPopMatrix"}
)


def _padded(values: list[Any], default: tuple[float, ...]) -> list[Any]:
    numbers = [_number(v) for v in values][:4]
    return numbers + list(default[len(numbers) :])


def _hashable(value: Any) -> Any:
    if isinstance(value, list):
        return tuple(_hashable(v) for v in value)
    if isinstance(value, dict):
        return tuple(sorted((k, _hashable(v)) for k, v in value.items()))
    return value


def _value(fn: str, index: int, value: Any, names: dict[int, str]) -> Any:
    """One argument of a call for its alignment key: an enum by its name (with the
    handouts' equivalences: GL_CLAMP is GL_CLAMP_TO_EDGE, the colour formats are one), a
    number rounded."""
    if index in names and isinstance(value, int | float):
        if int(value) == CLAMP:
            return "GL_CLAMP_TO_EDGE"
        if fn.startswith(("glCopyTexImage2D", "glTexImage2D")) and int(value) in COLOUR_FORMATS:
            if index == 2:
                return "colour"
        return names[index]
    if fn.startswith(("glCopyTexImage2D", "glTexImage2D")) and index == 2:
        return "colour" if value in COLOUR_FORMATS else value
    if isinstance(value, list):
        return [_number(v) for v in value]
    return _number(value)


def _matrix_key(fn: str, family: str, args: list[Any]) -> list[Any]:
    """A matrix call's arguments as an alignment compares them: gluLookAt by the view it
    gives (the same eye, direction and up however far the centre), a projection without
    its near and far planes."""
    if fn == "gluLookAt" and len(args) == 9:
        eye, center, up = (np.asarray(args[i : i + 3], dtype=float) for i in (0, 3, 6))
        forward = center - eye
        if np.linalg.norm(forward) < 1e-12 or np.linalg.norm(np.cross(forward, up)) < 1e-12:
            return [_number(v) for v in args]
        forward = forward / np.linalg.norm(forward)
        side = np.cross(forward, up)
        up2 = np.cross(side / np.linalg.norm(side), forward)
        return [_number(v) for v in (*eye, *forward, *up2)]
    names = ARGUMENT_NAMES.get(fn, ())
    if names:
        return [_number(a) for a, n in zip(args, names, strict=False) if n not in DEPTH_ARGUMENTS]
    return [_number(v) if not isinstance(v, list) else [_number(x) for x in v] for v in args]


def _text(call: Call, roles: Roles) -> str:
    """The call as a person writes it: enums by name, textures by their roles."""
    shown = []
    for i, value in enumerate(call.args):
        if i in call.names:
            shown.append(call.names[i])
        elif call.family == "glBindTexture" and i == 1:
            shown.append(roles(value))
        elif call.family == "glUseProgram" and i == 0:
            shown.append(roles.program(value))
        elif call.family == "glUniform" and i == 0:
            shown.append(roles.uniform(value))
        elif isinstance(value, list):
            shown.append("(" + fmt(value) + ",)" if len(value) == 1 else "(" + fmt(value) + ")")
        elif isinstance(value, float | int) and not isinstance(value, bool):
            shown.append(f"{float(value):g}")
        elif isinstance(value, dict) and set(value) == {"$f"}:
            shown.append(str(value["$f"]))
        else:
            shown.append(str(value) if value is not None else "None")
    return f"{call.fn}({', '.join(shown)})"


KIT_DRAW_WRITES = (("framebuffer",), ("unit",), ("binding", 0, GL_TEXTURE_2D), ("matrix_mode",))
"""What a drawing of the kit leaves (:meth:`.call_executor.Executor.after_kit_draw`)."""


def _kit(call: Call, roles: Roles) -> None:
    """A call of the lab object (``lab.draw_scene``, ``lab.set_viewer`` ...)."""
    name = call.fn[4:]
    args: list[Any] = []
    for value in call.args:
        if isinstance(value, dict) and isinstance(value.get("textures"), dict):
            args.append({k: roles(v) if v else None for k, v in value["textures"].items()})
        elif isinstance(value, int) and not isinstance(value, bool) and name != "set_viewer":
            args.append(roles(value))
        elif value == "<glsl>":
            args.append("GLSL")
        else:
            args.append(_number(value))
    call.family = call.fn
    call.key = (call.fn, *[_hashable(a) for a in args])
    shown = []
    for value in args:
        if isinstance(value, dict):
            shown.append("robot")
        elif isinstance(value, float):
            shown.append(f"{value:g}")
        elif value is None:
            shown.append("None")
        else:
            shown.append(str(value) if value != "GLSL" else "GLSL")
    call.text = f"{call.fn}({', '.join(shown)})"
    slots: tuple[tuple[Any, ...], ...]
    if name == "set_viewer":
        slots = (("matrix", GL_PROJECTION), ("matrix", GL_MODELVIEW), ("matrix_mode",))
        call.writes, call.values = slots, {s: None for s in slots}
        call.values[("matrix_mode",)] = (GL_MODELVIEW,)
    elif name == "load_picture_texture":
        role = args[0] if args else "no texture"
        slots = (("image", role, 0, 0), ("unit",), ("binding", 0, GL_TEXTURE_2D))
        call.writes = slots
        call.values = {slots[0]: None, slots[1]: (0,), slots[2]: (role,)}
    elif name.startswith("draw_"):
        call.writes = KIT_DRAW_WRITES
        call.values = {s: None for s in KIT_DRAW_WRITES}
        call.values[("unit",)] = (0,)
        call.values[("matrix_mode",)] = (GL_MODELVIEW,)
    else:
        call.writes, call.values = (), {}


# ------------------------------------------------------------------------- alignment
MATCH, SAME_FAMILY, GAP = 3.0, 1.0, -1.0


def _pair(a: Call, b: Call) -> float:
    if a.key == b.key:
        return MATCH + (0.5 if a.writes == b.writes else 0.0)
    return SAME_FAMILY if a.family == b.family else -1e9


def align(student: list[Call], reference: list[Call]) -> list[tuple[Call | None, Call | None]]:
    """The alignment of two call sequences (Needleman-Wunsch): equal keys pair at best (and
    better where they also acted on the same state), calls of one family pair as "other
    arguments", anything else is missing or extra. Rows in order: (the student's call or
    None, the solution's call or None)."""
    n, m = len(student), len(reference)
    score = np.zeros((n + 1, m + 1))
    score[:, 0] = np.arange(n + 1) * GAP
    score[0, :] = np.arange(m + 1) * GAP
    for i in range(1, n + 1):
        a = student[i - 1]
        for j in range(1, m + 1):
            score[i, j] = max(
                score[i - 1, j - 1] + _pair(a, reference[j - 1]),
                score[i - 1, j] + GAP,
                score[i, j - 1] + GAP,
            )
    rows: list[tuple[Call | None, Call | None]] = []
    i, j = n, m
    while i > 0 or j > 0:
        if i > 0 and j > 0:
            a, b = student[i - 1], reference[j - 1]
            if score[i, j] == score[i - 1, j - 1] + _pair(a, b):
                rows.append((a, b))
                i, j = i - 1, j - 1
                continue
        if i > 0 and score[i, j] == score[i - 1, j] + GAP:
            rows.append((student[i - 1], None))
            i -= 1
        else:
            rows.append((None, reference[j - 1]))
            j -= 1
    rows.reverse()
    return rows


# ------------------------------------------------------------------------ divergences
@dataclass
class Divergence:
    """One place where the student's calls in a function part from the solution's:
    ``kind`` is missing, extra, moved, arguments, context, note or refused."""

    kind: str
    student: Call | None
    reference: Call | None
    text: str
    slots: frozenset[str] = frozenset()


WHY_ORDER = {
    "texcoord": "a vertex takes the texture coordinates set before it",
    "color": "a vertex takes the colour set before it",
    "normal": "a vertex takes the normal set before it",
    "framebuffer": "what is drawn or copied depends on what was drawn before it",
    "matrix": "a draw uses the matrices set before it",
    "enable": "a draw uses the switches as they are at that moment",
    "texgen": "a draw uses the texgen modes set before it",
    "binding": "it acts on the texture bound at that moment",
    "unit": "it acts on the texture unit active at that moment",
    "matrix_mode": "a matrix call applies to the matrix glMatrixMode chose last",
    "program": "glUniform sets a uniform of the program in use at that moment",
    "texparam": "a draw samples the texture as its parameters are at that moment",
    "image": "a draw shows the texture's pictures as they are at that moment",
    "mipmaps": "mipmaps are made from the pictures the texture holds at that moment",
    "viewport": "a draw or a copy uses the viewport set before it",
    "clear_color": "a clear uses the colour set before it",
    "primitive": "vertices count only between glBegin and glEnd",
    "vertex": "vertices count only between glBegin and glEnd",
}
"""Why one call must come before another, by the state the first writes and the second
reads: GL's own rules, not a lab's."""
ORDER_KINDS = tuple(WHY_ORDER)


def reads(call: Call) -> frozenset[str]:
    """The kinds of state ``call`` depends on (what an earlier call may have set for it)."""
    family = call.family
    if family == "glVertex":
        return frozenset({"texcoord", "color", "normal", "primitive"})
    if family in ("glTexCoord", "glColor", "glNormal", "glEnd"):
        return frozenset({"primitive", "vertex"})
    if family in ("glBindTexture", "glEnable", "glTexGen", "glTexEnv"):
        return frozenset({"unit"})
    if family in ("glTexParameter", "glTexImage2D", "glTexSubImage2D", "glGenerateMipmap"):
        return frozenset({"unit", "binding", "image"})
    if family in ("glCopyTexImage2D", "glCopyTexSubImage2D"):
        return frozenset({"unit", "binding", "framebuffer", "viewport"})
    if family == "glUniform":
        return frozenset({"program"})
    if family == "glClear":
        return frozenset({"clear_color", "framebuffer"})
    if call.writes and call.writes[0][0] == "matrix" and call.kind != "kit":
        return frozenset({"matrix_mode", "matrix"})
    if family.startswith("lab.draw") or family == "glBegin" or call.kind == "function":
        return frozenset(
            {"matrix", "viewport", "unit", "binding", "enable", "texgen", "texparam"}
            | {"image", "program", "uniform", "framebuffer", "mipmaps"}
        )
    return frozenset()


def kinds(call: Call) -> frozenset[str]:
    """The kinds of state ``call`` writes."""
    return frozenset(str(slot[0]) for slot in call.writes)


def _blocks(calls: list[Call]) -> list[tuple[int, int]]:
    """The glBegin ... glEnd blocks of ``calls``: (index of glBegin, index of glEnd)."""
    found, start = [], -1
    for i, call in enumerate(calls):
        if call.family == "glBegin":
            start = i
        elif call.family == "glEnd" and start >= 0:
            found.append((start, i))
            start = -1
    return found


def _never_fails(fallback: Any) -> Any:
    """A hint's reasoning over a trace the student's file made (arguments of any shape): a
    case it does not foresee gives no divergence (or the hint as it was), never a run that
    cannot be judged. ``fallback(self, *args)`` is what it gives then."""

    def wrap(method: Any) -> Any:
        @functools.wraps(method)
        def safe(self: Any, *args: Any, **kwargs: Any) -> Any:
            try:
                return method(self, *args, **kwargs)
            except Exception:  # the verdicts stand; only the words fall back
                return fallback(*args)

        return safe

    return wrap


class Hints:
    """The hints of one student's run against the solution's: ``student`` and
    ``reference`` evidence, ``roles`` (evidence key -> the texture's name), ``setup`` (the
    lab's set-up functions)."""

    def __init__(
        self,
        student: Evidence,
        reference: Evidence,
        roles: dict[str, str],
        setup: tuple[str, ...],
        programs: dict[str, str] | None = None,
        uniforms: dict[str, str] | None = None,
    ) -> None:
        self.student, self.reference = student, reference
        self.mine = Trace(student, Roles(student, roles, programs, uniforms))
        self.theirs = Trace(reference, Roles(reference, roles, programs, uniforms))
        self.setup = setup
        self.traced = any(c.kind != "function" for c in self.theirs.calls)
        """Whether the reference has a call trace (evidence made before the trace was kept,
        a released folder's from an older version, has none: then no divergence is said)."""

    # ------------------------------------------------------------------ where
    def frame_of(self, function: str, trace: Trace) -> int:
        return -1 if function in self.setup else trace.last

    def at(self, call: Call) -> str:
        """``line N (code)`` of the student's call (a call written over several lines
        closed with ``...)``)."""
        code = self.student.line_text(call.line)
        if not code:
            return f"line {call.line}" if call.line else "the lab's own code"
        open_ = code.count("(") - code.count(")")
        if open_ > 0:
            code += "...)" + ")" * (open_ - 1)
        return f"line {call.line} ({code})"

    def said(self, call: Call) -> str:
        """The student's call as a hint names it: ``glOrtho at line 59 (glOrtho(...))``, and
        which time it ran where its line runs more than once in that function (a loop)."""
        same = [
            c
            for c in self.mine.calls
            if c.line == call.line
            and c.frame == call.frame
            and c.function == call.function
            and c.fn == call.fn
        ]
        again = ""
        if len(same) > 1 and call in same:
            again = f" in its {ordinal(same.index(call))} run"
        return f"{call.fn} at {self.at(call)}{again}"

    # ------------------------------------------------------------------ never called
    @_never_fails(lambda *args: "")
    def never_called(self, function: str) -> str:
        """'F() is never called ...' when the solution calls lab function ``function`` in
        the judged frame (or the set-up) and the student's file does not, else ''."""
        theirs = self.theirs.entered(function, self.frame_of(function, self.theirs))
        frame = self.frame_of(function, self.mine)
        if not self.traced:
            return ""
        if not theirs or self.mine.entered(function, frame):
            return ""
        caller = theirs[0].function
        when = "in the last frame" if frame >= 0 else "in the set-up"
        ever = self.mine.entered(function)
        if ever:
            where = "the set-up" if ever[0].frame < 0 else f"frame {ever[0].frame + 1}"
            return (
                f"{function}() is not called {when}: the file calls it only in {where} "
                f"({self.said(ever[0])})"
            )
        if not caller:
            return f"{function}() is never called"
        sequence = self.theirs.made_in(caller, self.frame_of(caller, self.theirs))
        mine = self.mine.made_in(caller, self.frame_of(caller, self.mine))
        return (
            f"{function}() is never called: {caller}() must call it"
            f"{self._around(theirs[-1], sequence, mine)}"
        )

    def _around(self, call: Call, sequence: list[Call], mine: list[Call]) -> str:
        """' after X at line N' / ' before X at line N': where among the student's calls
        ``mine`` the solution's ``call`` belongs, by its neighbours in the solution's
        ``sequence`` that the student makes too ('' when none is)."""
        index = next((i for i, c in enumerate(sequence) if c is call), -1)

        def found(other: Call) -> Call | None:
            return next((c for c in reversed(mine) if c.key == other.key), None)

        for other in reversed(sequence[:index]):
            if other.family != "glActiveTexture" and (seen := found(other)) is not None:
                return f", after {self.said(seen)}"
        for other in sequence[index + 1 :]:
            if (seen := found(other)) is not None:
                return f", before {self.said(seen)}"
        return ""

    # ------------------------------------------------------------------ divergences
    @_never_fails(lambda *args: [])
    def divergences(
        self, function: str, families: frozenset[str] | None = None
    ) -> list[Divergence]:
        """Where the student's calls in ``function`` part from the solution's there, in the
        student's order; each changes something (a call that sets what the state holds
        already is not one). ``families`` (``glTexParameter`` ...; None: every call)
        limits them to the calls a task judges."""
        if not self.traced:
            return []
        mine = self.mine.made_in(function, self.frame_of(function, self.mine))
        theirs = self.theirs.made_in(function, self.frame_of(function, self.theirs))
        found: list[Divergence] = []
        mine, theirs, blocks = self._blocks(mine, theirs, function)
        rows = align(mine, theirs)
        extra = [a for a, b in rows if a is not None and b is None]
        missing = [b for a, b in rows if b is not None and a is None]
        moved: dict[int, Call] = {}
        for one_extra in extra:
            partner = next(
                (b for b in missing if b.key == one_extra.key and b not in moved.values()), None
            )
            if partner is not None:
                moved[id(one_extra)] = partner
        moved_theirs = {id(b) for b in moved.values()}
        matched = {id(a) for a, b in rows if a is not None and b is not None}
        mine_at = mine[0].at - 0.5 if mine else 0.0
        theirs_at = theirs[0].at - 0.5 if theirs else 0.0
        for a, b in rows:
            if a is not None:
                mine_at = a.at + 0.5
            if b is not None:
                theirs_at = b.at + 0.5
            one = a if a is not None else b
            assert one is not None
            if a is not None and id(a) in blocks:
                found.append(blocks[id(a)])
                continue
            if (
                families is not None
                and one.family not in families
                and not (a is not None and (a.note or a.error))
            ):
                continue
            divergence: Divergence | None = None
            if a is not None and a.error:
                divergence = Divergence("refused", a, b, f"{self.said(a)} was refused: {a.error}")
            elif a is not None and a.note:
                divergence = Divergence("note", a, b, f"{self.said(a)}: {a.note}", kinds(a))
            elif a is not None and b is not None:
                if a.key != b.key:
                    divergence = self._other_arguments(a, b)
                elif a.writes != b.writes and a.kind != "function":
                    divergence = self._context(a, b)
            elif a is not None:
                if id(a) in moved:
                    divergence = self._moved(a, moved[id(a)], mine, rows)
                elif self._changes(a, theirs_at):
                    divergence = self._extra(a, function)
            elif b is not None and id(b) not in moved_theirs and self._needed(b, mine_at):
                divergence = self._missing(b, function, theirs, mine, mine_at, matched)
            if divergence is not None:
                found.append(divergence)
        rank = {"refused": 0, "note": 0, "context": 1}
        return sorted(found, key=lambda d: rank.get(d.kind, 2))

    def _blocks(
        self, mine: list[Call], theirs: list[Call], function: str
    ) -> tuple[list[Call], list[Call], dict[int, Divergence]]:
        """Each glBegin ... glEnd as one call where the student's draws what the solution's
        does (the same vertices with the same texture coordinates, in any order and any
        filling mode the handouts allow); where it does not, its divergence (texture
        coordinates given after their vertex, flipped, other vertices), by its glBegin."""
        a_blocks, b_blocks = _blocks(mine), _blocks(theirs)
        said: dict[int, Divergence] = {}
        if not a_blocks or len(a_blocks) != len(b_blocks):
            return mine, theirs, said
        keep_a, keep_b = list(mine), list(theirs)
        for (a0, a1), (b0, b1) in reversed(list(zip(a_blocks, b_blocks, strict=True))):
            pairs_a = self._vertices(mine[a0 : a1 + 1], self.mine)
            pairs_b = self._vertices(theirs[b0 : b1 + 1], self.theirs)
            begin_a, begin_b = mine[a0], theirs[b0]
            same_mode = begin_a.key == begin_b.key
            if (
                same_mode
                and {p for p, _ in pairs_a} == {p for p, _ in pairs_b}
                and set(pairs_a) == set(pairs_b)
            ):
                block = Call(begin_a.at, "glBegin", "gl", [], {}, begin_a.line, function, 0, {})
                block.family, block.key = "block", ("block",)
                other = Call(begin_b.at, "glBegin", "gl", [], {}, begin_b.line, function, 0, {})
                other.family, other.key = "block", ("block",)
                keep_a[a0 : a1 + 1] = [block]
                keep_b[b0 : b1 + 1] = [other]
                continue
            divergence = self._block(mine[a0 : a1 + 1], pairs_a, pairs_b)
            if divergence is not None:
                block = Call(begin_a.at, "glBegin", "gl", [], {}, begin_a.line, function, 0, {})
                block.family, block.key = "block", ("block",)
                other = Call(begin_b.at, "glBegin", "gl", [], {}, begin_b.line, function, 0, {})
                other.family, other.key = "block", ("block",)
                keep_a[a0 : a1 + 1] = [block]
                keep_b[b0 : b1 + 1] = [other]
                said[id(block)] = divergence
        return keep_a, keep_b, said

    @staticmethod
    def _vertices(block: list[Call], trace: Trace) -> list[tuple[tuple[Any, ...], Any]]:
        """(position, unit 0's texture coordinates then) of each vertex of a block."""
        current, _ = trace.value_before(("texcoord", 0), block[0].at)
        found = []
        for call in block:
            if call.family == "glTexCoord" and call.key[1] == 0:
                current = tuple(call.key[2:])
            elif call.family == "glVertex":
                found.append(
                    (tuple(call.key[1:]), tuple(current) if current is not UNKNOWN else None)
                )
        return found

    def _block(
        self,
        block: list[Call],
        mine: list[tuple[tuple[Any, ...], Any]],
        theirs: list[tuple[tuple[Any, ...], Any]],
    ) -> Divergence | None:
        """The divergence of a block that draws other vertices or texture coordinates."""
        want = dict(theirs)
        vertices = [c for c in block if c.family == "glVertex"]
        texcoords = [c for c in block if c.family == "glTexCoord"]
        if {p for p, _ in mine} == set(want):
            # the same corners: are the texture coordinates given after their vertex?
            after = []
            for vertex in vertices:
                following = next((t for t in texcoords if t.at > vertex.at), None)
                after.append(
                    following is not None
                    and tuple(following.key[2:]) == want.get(tuple(vertex.key[1:]))
                )
            if after and all(after):
                first = vertices[0]
                late = next(t for t in texcoords if t.at > first.at)
                return Divergence(
                    "moved",
                    late,
                    None,
                    f"in the wrong order: {self.said(late)} comes after {self.said(first)}; it "
                    f"belongs before it: {WHY_ORDER['texcoord']}, so every vertex gets the "
                    f"coordinates meant for the one before",
                    frozenset({"texcoord"}),
                )
            have = np.array([(t or (0, 0, 0, 1))[:2] for _, t in mine], dtype=float)
            should = np.array([(want[p] or (0, 0, 0, 1))[:2] for p, _ in mine], dtype=float)
            pattern = relation_2d(have, should)
            wrong = next(
                ((v, t) for v, (p, t) in zip(vertices, mine, strict=False) if t != want[p]),
                None,
            )
            if wrong is None:
                return None
            vertex, texcoord = wrong
            shown = texcoord[:2] if texcoord else (0, 0)
            words = f"texture coordinates {pattern}: " if pattern else ""
            return Divergence(
                "arguments",
                vertex,
                None,
                f"{words}{self.said(vertex)} gets the texture coordinates ({fmt(shown)}); the "
                f"solution gives that corner ({fmt((want[tuple(vertex.key[1:])] or (0, 0))[:2])})",
                frozenset({"texcoord"}),
            )
        corners = [p for p, _ in theirs]
        for vertex, (position, _) in zip(vertices, mine, strict=False):
            if position not in want:
                nearest = min(
                    corners, key=lambda c: float(np.linalg.norm(np.subtract(c, position)))
                )
                return Divergence(
                    "arguments",
                    vertex,
                    None,
                    f"{self.said(vertex)} gives the vertex ({fmt(position[:3])}); the "
                    f"solution's nearest is ({fmt(nearest[:3])})",
                    frozenset({"vertex"}),
                )
        return None

    def _changes(self, call: Call, theirs_at: float) -> bool:
        """Whether the student's extra ``call`` changes anything: not when it sets what the
        state already holds from earlier in the same frame, or what the solution's state
        holds at that point."""
        if call.family == "query" or not call.writes:
            return False
        for slot in call.writes:
            value = call.values.get(slot)
            if value is None:
                return True
            before, setter = self.mine.value_before(slot, call.at)
            theirs, _ = self.theirs.value_before(slot, theirs_at)
            redundant = value == before and (setter is None or setter.frame == call.frame)
            if not redundant and value != theirs:
                return True
        return False

    def _needed(self, call: Call, mine_at: float) -> bool:
        """Whether the solution's ``call``, missing from the student's, changes anything: not
        when the student's state holds its values there already."""
        if call.family == "query" or not call.writes:
            return False
        for slot in call.writes:
            value = call.values.get(slot)
            if value is None:
                return True
            mine, _ = self.mine.value_before(slot, mine_at)
            if mine != value:
                return True
        return False

    # ------------------------------------------------------------------ phrasing
    def _other_arguments(self, mine: Call, theirs: Call) -> Divergence:
        if mine.kind == "kit":
            differ = []
            for a, b in zip(mine.key[1:], theirs.key[1:], strict=False):
                if a == b:
                    continue
                if isinstance(a, tuple) and isinstance(b, tuple):
                    mine_of, theirs_of = dict(a), dict(b)
                    differ += [
                        f"{key} wears {mine_of.get(key) or 'no texture'} (the solution's: "
                        f"{theirs_of.get(key) or 'no texture'})"
                        for key in sorted(set(mine_of) | set(theirs_of))
                        if mine_of.get(key) != theirs_of.get(key)
                    ]
                else:
                    differ.append(f"is given {a} (the solution's: {b})")
            return Divergence(
                "arguments",
                mine,
                theirs,
                f"at {self.said(mine)}, " + ", ".join(differ or ["other arguments"]),
                kinds(mine),
            )
        names = self.mine.argument_names(mine.fn) or self.theirs.argument_names(theirs.fn)
        return Divergence(
            "arguments",
            mine,
            theirs,
            f"{self.said(mine)} {describe_difference(mine, theirs, names)}",
            kinds(mine),
        )

    def _context(self, mine: Call, theirs: Call) -> Divergence:
        """The same call, in the same place, that acted on other state: the unit active, the
        texture bound, the matrix mode or the program in use then."""
        return Divergence(
            "context",
            mine,
            theirs,
            f"{self.said(mine)} {self.acted_on(mine, theirs)}",
            kinds(mine),
        )

    def acted_on(self, mine: Call, theirs: Call) -> str:
        """What the student's ``mine`` acted on that the solution's ``theirs`` did not."""
        for slot_m, slot_t in zip(mine.writes, theirs.writes, strict=False):
            if slot_m == slot_t:
                continue
            kind, unit = slot_m[0], mine.ctx.get("u", 0)
            if kind == "binding":
                return (
                    f"bound the texture on unit {slot_m[1]} (GL_TEXTURE{slot_m[1]} was active"
                    f"{self._set_by(('unit',), mine)}); the solution binds it on unit {slot_t[1]}"
                )
            if kind in ("texparam", "image", "mipmaps"):
                what = {
                    "texparam": "set the parameters of",
                    "image": "filled",
                    "mipmaps": "made the mipmaps of",
                }[kind]
                target = mine.args[0] if mine.args else GL_TEXTURE_2D
                target = GL_TEXTURE_CUBE_MAP if target in CUBE_FACES else target
                return (
                    f"{what} {slot_m[1]}, the texture bound on unit {unit} at that moment"
                    f"{self._set_by(('binding', unit, target), mine)}, not {slot_t[1]}"
                )
            if kind in ("enable", "texgen", "texenv", "texcoord"):
                mine_unit = slot_m[2] if kind == "enable" else slot_m[1]
                their_unit = slot_t[2] if kind == "enable" else slot_t[1]
                return (
                    f"acted on texture unit {mine_unit} (GL_TEXTURE{mine_unit} was active"
                    f"{self._set_by(('unit',), mine)}), not unit {their_unit}"
                )
            if kind == "matrix":
                mode, their_mode = MODE_NAMES.get(slot_m[1], "?"), MODE_NAMES.get(slot_t[1], "?")
                return (
                    f"was applied to the {mode[3:].lower()} matrix (the matrix mode was {mode}"
                    f"{self._set_by(('matrix_mode',), mine)}); the solution applies it to the "
                    f"{their_mode[3:].lower()} matrix"
                )
            if kind == "uniform":
                return (
                    f"set a uniform of the program in use{self._set_by(('program',), mine)}, "
                    f"not of the solution's"
                )
        return "acted on other state than the solution's"

    def _set_by(self, slot: tuple[Any, ...], call: Call) -> str:
        _, setter = self.mine.value_before(slot, call.at)
        return ", as GL starts" if setter is None else f", by {self.said(setter)}"

    def _moved(
        self,
        mine: Call,
        theirs: Call,
        sequence: list[Call],
        rows: list[tuple[Call | None, Call | None]],
    ) -> Divergence:
        """``mine`` is in the solution too, elsewhere in the order: which of the calls it
        passed matters most to it (the state one writes and the other reads), and why."""
        partners = {id(a): b for a, b in rows if a is not None and b is not None}
        index = next(i for i, c in enumerate(sequence) if c is mine)
        crossed: list[tuple[int, int, Call, bool]] = []
        for distance, other in enumerate(reversed(sequence[:index])):
            partner = partners.get(id(other))
            if partner is not None and partner.at > theirs.at:
                crossed.append((self._priority(mine, other), distance, other, True))
        for distance, other in enumerate(sequence[index + 1 :]):
            partner = partners.get(id(other))
            if partner is not None and partner.at < theirs.at:
                crossed.append((self._priority(mine, other), distance, other, False))
        if not crossed:
            return Divergence(
                "moved", mine, theirs, f"{self.said(mine)} is not where the solution makes it"
            )
        _, _, other, after = min(crossed, key=lambda c: (c[0], c[1]))
        which = "after" if after else "before"
        belongs = "before" if after else "after"
        return Divergence(
            "moved",
            mine,
            theirs,
            f"in the wrong order: {self.said(mine)} comes {which} {self.said(other)}; it "
            f"belongs {belongs} it{self._why(mine, other)}",
            kinds(mine),
        )

    @classmethod
    def _priority(cls, mover: Call, other: Call) -> int:
        """How much the order of ``mover`` and ``other`` matters: the rank of the state they
        share in :data:`ORDER_KINDS` (the framebuffer first), past the end when none."""
        why = cls._why(mover, other)
        for rank, kind in enumerate(ORDER_KINDS):
            if why == f": {WHY_ORDER[kind]}":
                return rank
        return len(ORDER_KINDS) if not why else 0

    @staticmethod
    def _why(mover: Call, other: Call) -> str:
        """': why' the order of ``mover`` and ``other`` matters (the state one writes and
        the other reads), or ''."""
        copies = ("glCopyTexImage2D", "glCopyTexSubImage2D")
        for copy, drawer in ((mover, other), (other, mover)):
            if copy.family in copies and "framebuffer" in kinds(drawer):
                return ": a copy takes only what was drawn before it"
        for clear, drawer in ((mover, other), (other, mover)):
            if clear.family == "glClear" and drawer.family != "glClear":
                if "framebuffer" in kinds(drawer):
                    return (
                        ": a clear wipes what was drawn before it, and what is drawn after it "
                        "stays in the frame"
                    )
        for writer, reader in ((other, mover), (mover, other)):
            shared = kinds(writer) & reads(reader)
            for kind in ORDER_KINDS:
                if kind in shared:
                    return f": {WHY_ORDER[kind]}"
        return ""

    def _extra(self, mine: Call, function: str) -> Divergence:
        if mine.kind == "function":
            return Divergence(
                "extra",
                mine,
                None,
                f"{mine.fn} is called inside {function}() at {self.at(mine)}; the solution "
                f"does not call it there, so what it draws or sets lands in {function}()'s "
                f"work",
                kinds(mine),
            )
        effect = ""
        for slot in mine.writes:
            value = mine.values.get(slot)
            if value is not None:
                effect = f": it sets {describe_slot(slot)} to {describe_value(slot, value)}"
                break
        return Divergence(
            "extra",
            mine,
            None,
            f"{self.said(mine)} in {function}() is a call the solution does not make there{effect}",
            kinds(mine),
        )

    def _missing(
        self,
        theirs: Call,
        function: str,
        sequence: list[Call],
        mine: list[Call],
        mine_at: float,
        matched: set[int],
    ) -> Divergence:
        around = self._around(theirs, sequence, mine)
        if theirs.kind == "function":
            return Divergence(
                "missing",
                None,
                theirs,
                f"{function}() never calls {theirs.fn}{around}",
                kinds(theirs),
            )
        found = self.mine.with_key(theirs.key)
        if found and "framebuffer" in kinds(theirs):
            nearest = min(found, key=lambda c: (abs(c.at - mine_at), c.at))
            verb = "clears" if theirs.family == "glClear" else "draws"
            return Divergence(
                "missing",
                nearest,
                theirs,
                f"{function}() needs one more {theirs.fn}{around}: the file's "
                f"{self.said(nearest)} {verb} {'before' if nearest.at < mine_at else 'after'} "
                f"that, not there",
                kinds(theirs),
            )
        if found:
            return Divergence(
                "missing",
                found[-1],
                theirs,
                f"{function}() needs {theirs.fn}{self.on_what(theirs)}{around}: "
                + self.elsewhere(found, theirs, function, mine_at),
                kinds(theirs),
            )
        return Divergence(
            "missing",
            None,
            theirs,
            f"{function}() makes no {theirs.text}{self.on_what(theirs)}{around}",
            kinds(theirs),
        )

    @staticmethod
    def on_what(call: Call) -> str:
        """' on the projection matrix', ' on unit 1', ' for tex_ids[ENVIRONMENT]': the state
        ``call`` acts on, where the call alone does not say it."""
        for slot in call.writes:
            if slot[0] == "matrix" and call.family in (
                "glLoadIdentity",
                "glPushMatrix",
                "glPopMatrix",
            ):
                return f" on the {MODE_NAMES.get(slot[1], '?')[3:].lower()} matrix"
            if slot[0] in ("texparam", "image", "mipmaps"):
                return f" for {slot[1]}"
            if slot[0] in ("texgen", "texenv") or (slot[0] == "enable" and slot[2] >= 0):
                unit = slot[2] if slot[0] == "enable" else slot[1]
                return f" with unit {unit} active"
        return ""

    def elsewhere(self, found: list[Call], theirs: Call, function: str, mine_at: float) -> str:
        """Why the student's calls ``found`` (the same as the solution's ``theirs``, which
        belongs in ``function`` at the student's position ``mine_at``) took no effect there:
        where they run instead, what they acted on, what undid them. The calls are named by
        the student's lines, never asked for."""
        call = min(found, key=lambda c: (abs(c.at - mine_at), c.at))
        if call.frame < 0:
            where = f"runs once, in {call.function or 'the top level'}() before the first frame"
        elif call.function != function:
            where = f"runs in {call.function or 'the top level'}()"
        elif call.at > mine_at:
            where = "comes later"
        else:
            where = "comes earlier"
        parts = [f"the file's {self.said(call)} {where}"]
        if call.writes != theirs.writes:
            parts.append(f"it {self.acted_on(call, theirs)}")
        else:
            for slot in theirs.writes:
                value, setter = self.mine.value_before(slot, mine_at)
                if setter is not None and setter is not call and value != theirs.values.get(slot):
                    parts.append(f"{self.said(setter)} undoes it before {function}() needs it")
                    break
        return ", and ".join(parts)

    # ------------------------------------------------------------------ the guard
    @_never_fails(lambda hint: hint)
    def guard(self, hint: str) -> str:
        """``hint`` unless it asks for a call the file already makes with the same
        arguments; then why that call took no effect (where it runs, what it acted on,
        what undid it) instead."""
        explained = ""
        for fn, args in suggested_calls(hint):
            made = [c for c in self.mine.calls if c.kind != "function" and same_call(c, fn, args)]
            if not made:
                continue
            theirs = [
                c for c in self.theirs.calls if c.kind != "function" and same_call(c, fn, args)
            ]
            if theirs and not explained:
                function = theirs[-1].function
                inside = self.mine.made_in(function, self.frame_of(function, self.mine))
                mine_at = inside[0].at if inside else float(len(self.mine.calls))
                sequence = self.theirs.made_in(function, self.frame_of(function, self.theirs))
                around = self._around(theirs[-1], sequence, inside)
                explained = (
                    f"{function}() needs {fn}{self.on_what(theirs[-1])}{around}: "
                    + self.elsewhere(made, theirs[-1], function, mine_at)
                )
            blanked = QUOTED.sub(_blank, hint)
            spot = next(
                (
                    m
                    for m in CALL_TEXT.finditer(blanked)
                    if m.group(1) == fn and _split(m.group(2)) == args
                ),
                None,
            )
            if spot is not None:
                said = f"{fn} (as the file makes it at line {made[-1].line})"
                hint = hint[: spot.start()] + said + hint[spot.end() :]
        return f"{explained}; {hint}" if explained else hint


def ordinal(index: int) -> str:
    """``1st``, ``2nd``, ``3rd``, ``4th`` ... for the 0-based ``index``."""
    number = index + 1
    suffix = {1: "st", 2: "nd", 3: "rd"}.get(
        number % 10 if number % 100 not in (11, 12, 13) else 0, "th"
    )
    return f"{number}{suffix}"


def _blank(match: re.Match[str]) -> str:
    """A quoted line of the file, blanked to its length (so positions stay)."""
    return " " * len(match.group(0))


def describe_difference(mine: Call, theirs: Call, names: tuple[str, ...]) -> str:
    """How ``mine``'s arguments differ from ``theirs`` (same family), by their names:
    ``has left, right = -4, 4 (the solution's -6, 2)``, with the pattern when there is one
    (the opposite sign, two swapped, flipped)."""
    if mine.family in ("glTexCoord", "glVertex", "glColor", "glNormal"):
        a, b = list(mine.key[1:]), list(theirs.key[1:])
        return f"gives ({fmt(a)}) {relation(a, b)}".rstrip()
    a_args, b_args = mine.args, theirs.args
    differ = []
    for i, (x, y) in enumerate(zip(a_args, b_args, strict=False)):
        nx = mine.names.get(i, x)
        ny = theirs.names.get(i, y)
        if isinstance(x, list) or isinstance(y, list):
            if _hashable(x) != _hashable(y):
                differ.append((i, x, y))
            continue
        if mine.family == "glBindTexture" and i == 1:
            continue
        if isinstance(nx, str) or isinstance(ny, str):
            if _value(mine.fn, i, x, mine.names) != _value(theirs.fn, i, y, theirs.names):
                differ.append((i, nx, ny))
        elif isinstance(x, int | float) and isinstance(y, int | float) and abs(x - y) > 1e-4:
            if i < len(names) and names[i] in DEPTH_ARGUMENTS and mine.fn in ARGUMENT_NAMES:
                continue
            differ.append((i, x, y))
    if mine.family == "glBindTexture" and len(a_args) == 2 and len(b_args) == 2:
        if mine.key[2:] != theirs.key[2:]:
            differ.append((1, mine.key[2], theirs.key[2]))
    if not differ and mine.fn == "gluLookAt":
        return "looks another way"
    if not differ:
        return "differs"
    labels = [names[i] if i < len(names) else f"argument {i + 1}" for i, _, _ in differ]
    shown_a = [
        v if isinstance(v, str) else fmt([v]) if not isinstance(v, list) else f"({fmt(v)})"
        for _, v, _ in differ
    ]
    shown_b = [
        v if isinstance(v, str) else fmt([v]) if not isinstance(v, list) else f"({fmt(v)})"
        for _, _, v in differ
    ]
    grouped = _grouped(labels)
    numbers_a = [v for _, v, _ in differ if isinstance(v, int | float)]
    numbers_b = [v for _, _, v in differ if isinstance(v, int | float)]
    pattern = relation(numbers_a, numbers_b) if len(numbers_a) == len(differ) else ""
    return f"has {grouped} = {', '.join(shown_a)} (the solution's: {', '.join(shown_b)})" + (
        f" {pattern}" if pattern else ""
    )


def _grouped(labels: list[str]) -> str:
    """``eyeX, eyeY, eyeZ`` as ``eye``; other names listed."""
    text = ", ".join(labels)
    for stem in ("eye", "center", "up"):
        text = text.replace(f"{stem}X, {stem}Y, {stem}Z", stem)
    return text


def relation(mine: list[Any], theirs: list[Any]) -> str:
    """The pattern that turns ``theirs`` into ``mine`` (numbers), in words: '(the opposite
    sign)', '(swapped)', '(flipped: 1 - s)' ..., or ''."""
    try:
        a = np.asarray(mine, dtype=float)
        b = np.asarray(theirs, dtype=float)
    except (TypeError, ValueError):
        return ""
    if a.shape != b.shape or not a.size:
        return ""
    if np.allclose(a, -b, atol=1e-4) and not np.allclose(b, 0):
        return "(the opposite sign)"
    if a.size >= 2 and np.allclose(a[:2], b[1::-1], atol=1e-4) and np.allclose(a[2:], b[2:]):
        return "(the first two swapped)"
    if np.allclose(a, 2 * b, atol=1e-4) and not np.allclose(b, 0):
        return "(twice the solution's)"
    if np.allclose(2 * a, b, atol=1e-4) and not np.allclose(b, 0):
        return "(half the solution's)"
    return ""


def relation_2d(mine: np.ndarray, theirs: np.ndarray) -> str:
    """How the pairs ``mine`` ``(n, 2)`` (texture coordinates at the same vertices) follow
    from ``theirs``: flipped left-right, upside down, rotated, swapped ... or ''."""
    s, t = theirs[:, 0], theirs[:, 1]
    for transform, words in (
        ((1 - s, t), "flipped left-right (s runs the other way: 1 - s)"),
        ((s, 1 - t), "upside down (t runs the other way: 1 - t)"),
        ((1 - s, 1 - t), "rotated by 180 degrees (1 - s and 1 - t)"),
        ((t, s), "s and t swapped"),
        ((t, 1 - s), "rotated by 90 degrees"),
        ((1 - t, s), "rotated by 90 degrees"),
        ((1 - t, 1 - s), "s and t swapped and flipped"),
    ):
        if np.allclose(mine, np.stack(transform, -1), atol=1e-3):
            return words
    return ""


def describe_slot(slot: tuple[Any, ...]) -> str:
    kind = slot[0]
    return {
        "unit": "the active texture unit",
        "matrix_mode": "the matrix mode",
        "viewport": "the viewport",
        "scissor": "the scissor box",
        "clear_color": "the clear colour",
        "program": "the program in use",
        "color": "the current colour",
        "normal": "the current normal",
    }.get(
        str(kind),
        f"texture unit {slot[1]}'s binding"
        if kind == "binding"
        else f"{slot[1]}'s parameter"
        if kind == "texparam"
        else f"the switch on unit {slot[2]}"
        if kind == "enable" and slot[2] >= 0
        else "a switch"
        if kind == "enable"
        else f"texgen on unit {slot[1]}"
        if kind == "texgen"
        else f"unit {slot[1]}'s texture coordinates"
        if kind == "texcoord"
        else str(kind),
    )


def describe_value(slot: tuple[Any, ...], value: Any) -> str:
    if slot[0] == "unit":
        return f"GL_TEXTURE{value[0]}"
    if slot[0] == "enable":
        return "on" if value and value[0] else "off"
    if isinstance(value, tuple):
        return (
            "(" + fmt(value) + ")"
            if len(value) != 1
            else str(value[0] if isinstance(value[0], str) else fmt(value))
        )
    return str(value)


# --------------------------------------------------------------------- hints' calls
CALL_TEXT = re.compile(r"\b((?:glu?|lab\.)[A-Za-z_]\w*)\(([^()]*(?:\([^()]*\)[^()]*)*)\)")
QUOTED = re.compile(
    r"line \d+ \((?:[^()]*(?:\([^()]*(?:\([^()]*\)[^()]*)*\)[^()]*)*)\)|line \d+: .*? -> "
)
"""A line of the student's file as a hint quotes it: ``line N (code)``, or an error's
``line N: code -> ``."""


def suggested_calls(hint: str) -> list[tuple[str, list[str]]]:
    """The calls ``hint`` asks for: every ``glName(arguments)`` in it but those quoting the
    student's own lines (``line N (code)``) and those followed by "at line" (a call of the
    file named with its line)."""
    text = QUOTED.sub("line", hint)
    found = []
    for match in CALL_TEXT.finditer(text):
        after = text[match.end() : match.end() + 9]
        if after.startswith((" at line", " at the l")):
            continue
        arguments = _split(match.group(2))
        found.append((match.group(1), arguments))
    return found


def _split(arguments: str) -> list[str]:
    parts, depth, current = [], 0, ""
    for char in arguments:
        if char == "," and depth == 0:
            parts.append(current.strip())
            current = ""
            continue
        depth += {"(": 1, ")": -1, "[": 1, "]": -1}.get(char, 0)
        current += char
    if current.strip():
        parts.append(current.strip())
    return parts


def same_call(call: Call, fn: str, arguments: list[str]) -> bool:
    """Whether ``call`` (of a trace) is the call ``fn(arguments)`` a hint names: the same
    name (or form family) and, argument by argument, the same number or GL name where the
    hint gives one (a name of the file's own, such as ``WIDTH``, stands for any value)."""
    form = FORM.match(fn)
    family = f"gl{form.group('base')}" if form else fn
    if (
        fn != call.fn
        and family != call.family
        and not (family == "glDisable" and call.fn == "glDisable")
    ):
        return False
    if fn in ("glEnable", "glDisable") and call.fn != fn:
        return False
    if not arguments:
        return not call.args or fn.startswith("lab.")
    shown = _split(call.text[call.text.index("(") + 1 : -1])
    if len(arguments) != len(shown):
        return False
    for wanted, have in zip(arguments, shown, strict=True):
        if wanted in ("...", have):
            continue
        try:
            if abs(float(eval_number(wanted)) - float(have)) <= 1e-4:
                continue
        except (ValueError, TypeError):
            pass
        if not re.fullmatch(r"(?!GL_)[A-Z_][A-Z0-9_]*|.*[-+*/%].*", wanted):
            return False  # a GL name, a number, a texture's or the lab's name: not this one
    return True


def eval_number(text: str) -> float:
    """A number written in a hint (``-6``, ``0.5``), ValueError otherwise."""
    return float(text)
