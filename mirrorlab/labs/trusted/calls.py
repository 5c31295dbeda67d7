"""The OpenGL and GLU calls a student's file may make, and how each argument is checked.

Every call the sandbox sends is looked up here by name; one that is not here is refused.
Each argument is checked by kind (an integer in a range, a finite number, an enum from
the call's own list, a vector of a set length, a short string) before anything is
executed; arrays reach only the calls that upload pixels, and their sizes are checked
against what GL will read (:mod:`.call_executor`). The checks raise :class:`CallError`, which
the student sees as the error PyOpenGL would raise (``GLError`` for a bad enum, as GL
reports it, ``TypeError`` for a wrong argument).
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from typing import Any

from mirrorlab.gl.opengl import GL

GL_INVALID_ENUM, GL_INVALID_VALUE, GL_INVALID_OPERATION = 0x0500, 0x0501, 0x0502
GL_OUT_OF_MEMORY = 0x0505
ERROR_NAMES = {
    GL_INVALID_ENUM: "invalid enumerant",
    GL_INVALID_VALUE: "invalid value",
    GL_INVALID_OPERATION: "invalid operation",
    0x0503: "stack overflow",
    0x0504: "stack underflow",
    GL_OUT_OF_MEMORY: "out of memory",
}


class CallError(Exception):
    """A call refused or failed: ``kind`` names the exception the student gets."""

    def __init__(self, kind: str, message: str, err: int = 0) -> None:
        super().__init__(message)
        self.kind, self.message, self.err = kind, message, err


def gl_error(err: int, detail: str = "") -> CallError:
    text = ERROR_NAMES.get(err, "error")
    return CallError("GLError", text + (f" ({detail})" if detail else ""), err)


class Enums(frozenset[int]):
    """A set of GL enums a call takes: each value's GL name (``names``), what one of them is
    (``noun``: "a capability") and, for a run of consecutive values, what each is
    (``member``: "face"), for a refusal that names what it got and what the call takes."""

    names: dict[int, str]
    noun: str
    member: str


def enums(*names: str, noun: str = "", member: str = "", numbers: tuple[int, ...] = ()) -> Enums:
    """The GL enums ``names`` (and plain ``numbers`` a call also takes, such as the legacy
    internal formats 1 to 4), knowing their names, what one is and what a run's member is."""
    values = {int(getattr(GL, name)): name for name in names}
    values.update({n: str(n) for n in numbers})
    found = Enums(values)
    found.names, found.noun, found.member = values, noun, member
    return found


@lru_cache(maxsize=1)
def _gl_constants() -> dict[int, list[str]]:
    """Every GL_ constant PyOpenGL defines, by value (several names may share one)."""
    found: dict[int, list[str]] = {}
    for name in dir(GL):
        value = getattr(GL, name, None)
        if name.startswith("GL_") and type(value) is not bool and isinstance(value, int):
            found.setdefault(int(value), []).append(name)
    return found


VENDOR = re.compile(r"_(ARB|EXT|NV|AMD|ATI|SGIS|SGIX|SGI|APPLE|MESA|IBM|INTEL|OES|KHR|3DFX|HP)$")


def gl_name(value: int, allowed: Enums | None = None) -> str:
    """GL's name for ``value``: the name the allow-list gives it (in ``allowed`` first, then in
    any of its sets), else PyOpenGL's (core names before a vendor's, shorter first), else
    its number in hex."""
    if allowed is not None and value in allowed.names:
        return allowed.names[value]
    for known in ENUM_SETS:
        if value in known.names:
            return known.names[value]
    names = _gl_constants().get(value, [])
    if not names:
        return f"{value:#x}"
    return sorted(names, key=lambda n: (bool(VENDOR.search(n)), len(n), n))[0]


def _listed(names: list[str]) -> str:
    return names[0] if len(names) == 1 else ", ".join(names[:-1]) + " or " + names[-1]


def _runs(values: frozenset[int]) -> list[tuple[int, int]]:
    """The runs of three or more consecutive values in ``values``, (first, last) each."""
    ordered, runs = sorted(values), []
    start = 0
    for i in range(1, len(ordered) + 1):
        if i == len(ordered) or ordered[i] != ordered[i - 1] + 1:
            if i - start >= 3:
                runs.append((ordered[start], ordered[i - 1]))
            start = i
    return runs


def refused_enum(value: int, allowed: Enums, call: str) -> str:
    """Why ``value`` is not one of ``allowed`` (``call``'s), by GL's names: what it is (another
    kind of enum, or a step past the end of a run such as the cube map's faces) and what
    ``call`` takes."""
    taken = [allowed.names[v] for v in sorted(allowed) if v in allowed.names]
    for first, last in _runs(allowed):  # a run of consecutive enums as its ends
        names = [allowed.names[v] for v in range(first, last + 1) if v in allowed.names]
        if len(names) > 4 and names[0] in taken:
            at = taken.index(names[0])
            taken[at : at + len(names)] = [f"{names[0]} ... {names[-1]}"]
    what = ""
    for first, last in _runs(allowed):
        member = allowed.member or "one"
        if last < value <= last + 4:
            what = f"{gl_name(last, allowed)} + {value - last} is past the last {member}"
        elif first - 4 <= value < first:
            what = f"{gl_name(first, allowed)} - {first - value} is before the first {member}"
    if not what and 0 <= value < 0x100 and _runs(allowed):
        first, last = _runs(allowed)[0]
        member = allowed.member or "one"
        what = f"{value} is a number, not a GL enum"
        if value <= last - first:
            what += f" (the {member} number {value} is {gl_name(first, allowed)} + {value})"
    if not what:
        name = gl_name(value)
        kinds = [
            k.noun
            for k in ENUM_SETS
            if value in k.names and not k.names[value].isdigit() and k.noun != allowed.noun
        ]
        if kinds:
            what = f"{name} is {kinds[0]}"
        elif name.startswith("0x"):
            what = f"{name} is no GL enum"
        else:
            what = f"{name} is not {allowed.noun or 'one it takes'}"
    if len(taken) <= 8:
        takes = _listed(taken)
    else:
        # the names nearest the one given first (most words shared): GL_S -> GL_TEXTURE_GEN_S
        words = set(gl_name(value).split("_")[1:])
        nearest = sorted(taken, key=lambda n: (-len(words & set(n.split("_")[1:])), n.isdigit()))
        takes = f"{allowed.noun or 'an enum'} such as {', '.join(nearest[:4])}"
    return f"{what}; {call} takes {takes}"


# ------------------------------------------------------------------------------ checks
Check = Callable[[Any, str], Any]


def shown(value: Any) -> str:
    """``value`` for a one-line message: a long number by its first digits and length."""
    text = repr(value)
    if len(text) <= 24:
        return text
    if type(value) is int:
        return f"{text[:8]}... (an integer of {len(text.lstrip('-'))} digits)"
    return text[:21] + "..."


def integer(lo: int = -(1 << 31), hi: int = (1 << 32) - 1) -> Check:
    def check(value: Any, what: str) -> int:
        if type(value) is not int:
            raise CallError("TypeError", f"{what}: expected an integer")
        if not lo <= value <= hi:
            raise gl_error(GL_INVALID_VALUE, f"{what} = {shown(value)} is outside {lo}..{hi}")
        return value

    return check


NON_FINITE = {"nan": math.nan, "inf": math.inf, "-inf": -math.inf}
"""What the student side sends for a number JSON cannot carry (``{"$f": "nan"}``)."""


def _made_of(what: str) -> str:
    """What GL makes from the arguments of the call ``what`` names, for a message."""
    call = what.split("(")[0]
    for prefix, made in (
        ("glVertex", "the vertex's position"),
        ("glTexCoord", "the texture coordinates"),
        ("glMultiTexCoord", "the texture coordinates"),
        ("glColor", "the colour"),
        ("glNormal", "the normal"),
        ("glClearColor", "the clear colour"),
        ("glUniform", "the uniform's value"),
        ("glViewport", "the viewport"),
    ):
        if call.startswith(prefix):
            return made
    if call in MATRIX_CALLS:
        return "the matrix, and so every point it transforms,"
    return "what GL makes of it"


def real(lo: float = -1e9, hi: float = 1e9) -> Check:
    def check(value: Any, what: str) -> float:
        if isinstance(value, dict) and set(value) == {"$f"} and value["$f"] in NON_FINITE:
            text = {"nan": "nan (not a number)", "inf": "infinite", "-inf": "-infinite"}[
                value["$f"]
            ]
            raise CallError(
                "ValueError",
                f"{what} is {text}: {_made_of(what)} would be undefined (not a finite "
                f"number); the labs take finite numbers",
            )
        if type(value) not in (int, float):
            raise CallError("TypeError", f"{what}: expected a number")
        if type(value) is int and not -(1 << 64) < value < 1 << 64:
            raise CallError(
                "ValueError",
                f"{what} = {shown(value)} is out of range: the "
                f"labs take numbers from {lo:g} to {hi:g}",
            )
        value = float(value)
        if not math.isfinite(value):
            raise CallError("ValueError", f"{what} is {value}: the labs take finite numbers")
        if not lo <= value <= hi:
            raise gl_error(GL_INVALID_VALUE, f"{what} = {value:g} is outside {lo:g}..{hi:g}")
        return value

    return check


def one_of(allowed: Enums) -> Check:
    def check(value: Any, what: str) -> int:
        if type(value) is not int:
            raise CallError("TypeError", f"{what}: expected a GL enum (an integer)")
        if value not in allowed:
            call = what.split("(")[0]
            if not -(1 << 64) < value < 1 << 64:
                raise gl_error(GL_INVALID_ENUM, f"{what} = {shown(value)} is no GL enum")
            raise gl_error(GL_INVALID_ENUM, f"{what}: {refused_enum(value, allowed, call)}")
        return value

    check.enums = allowed  # type: ignore[attr-defined]
    return check


def bit_names(value: int, allowed: Enums) -> str:
    """``value``'s bits by their GL names (``GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT``)."""
    names = [allowed.names[bit] for bit in sorted(allowed.names) if value & bit == bit]
    rest = value & ~sum(allowed.names)
    return " | ".join([*names, *([gl_name(rest)] if rest else [])]) or "0"


def bits(allowed: Enums) -> Check:
    every = sum(allowed.names)

    def check(value: Any, what: str) -> int:
        if type(value) is not int:
            raise CallError("TypeError", f"{what}: expected GL bits (an integer)")
        if value & ~every or value < 0:
            shown_value = (
                shown(value)
                if value < 0 or value >= 1 << 32
                else f"{value:#x} ({bit_names(value, allowed)})"
            )
            raise gl_error(
                GL_INVALID_VALUE,
                f"{what}: {shown_value} has bits other than "
                f"{_listed([allowed.names[b] for b in sorted(allowed.names)])}",
            )
        return value

    check.bits = allowed  # type: ignore[attr-defined]
    return check


def vector(
    lengths: tuple[int, ...], lo: float = -1e9, hi: float = 1e9, integral: bool = False
) -> Check:
    """A list of ``lengths`` numbers from ``lo`` to ``hi`` (integers with ``integral``)."""
    number = integer(int(lo), int(hi)) if integral else real(lo, hi)

    def check(value: Any, what: str) -> list[float]:
        if not isinstance(value, list) or len(value) not in lengths:
            expected = " or ".join(map(str, lengths))
            got = len(value) if isinstance(value, list) else type(value).__name__
            raise CallError("ValueError", f"{what}: expected {expected} numbers, got {got}")
        return [number(v, what) for v in value]

    return check


def names(limit: int = 64) -> Check:
    name = integer(0)

    def check(value: Any, what: str) -> list[int]:
        if not isinstance(value, list) or len(value) > limit:
            raise CallError("ValueError", f"{what}: expected at most {limit} names")
        return [name(v, what) for v in value]

    return check


def text(limit: int) -> Check:
    def check(value: Any, what: str) -> str:
        if not isinstance(value, str):
            raise CallError("TypeError", f"{what}: expected a string")
        if len(value) > limit:
            raise CallError(
                "ValueError",
                f"{what}: a string of {len(value)} characters; the labs take {limit} at most",
            )
        return value

    return check


def anything(value: Any, what: str) -> Any:
    return value


def pixels(value: Any, what: str) -> Any:
    """None, or an array of the message (``{"$a": i}``; :mod:`.call_executor` resolves it)."""
    if value is None or (
        isinstance(value, dict) and set(value) == {"$a"} and type(value["$a"]) is int
    ):
        return value
    raise CallError("TypeError", f"{what}: expected pixel data or None")


# -------------------------------------------------------------------------------- enums
MATRIX_MODES = enums(
    "GL_MODELVIEW",
    "GL_PROJECTION",
    "GL_TEXTURE",
    noun="a matrix mode (glMatrixMode's)",
)
CAPS = enums(
    "GL_DEPTH_TEST",
    "GL_CULL_FACE",
    "GL_BLEND",
    "GL_SCISSOR_TEST",
    "GL_STENCIL_TEST",
    "GL_TEXTURE_2D",
    "GL_TEXTURE_CUBE_MAP",
    "GL_TEXTURE_CUBE_MAP_SEAMLESS",
    "GL_TEXTURE_GEN_S",
    "GL_TEXTURE_GEN_T",
    "GL_TEXTURE_GEN_R",
    "GL_TEXTURE_GEN_Q",
    "GL_NORMALIZE",
    "GL_RESCALE_NORMAL",
    "GL_LIGHTING",
    "GL_LIGHT0",
    "GL_LIGHT1",
    "GL_COLOR_MATERIAL",
    "GL_POLYGON_OFFSET_FILL",
    "GL_LINE_SMOOTH",
    "GL_POINT_SMOOTH",
    "GL_MULTISAMPLE",
    "GL_DITHER",
    "GL_ALPHA_TEST",
    "GL_FOG",
    noun="a capability (glEnable's)",
)
BEGIN_MODES = enums(
    "GL_POINTS",
    "GL_LINES",
    "GL_LINE_STRIP",
    "GL_LINE_LOOP",
    "GL_TRIANGLES",
    "GL_TRIANGLE_STRIP",
    "GL_TRIANGLE_FAN",
    "GL_QUADS",
    "GL_QUAD_STRIP",
    "GL_POLYGON",
    noun="a primitive (glBegin's)",
)
CLEAR_BITS = enums(
    "GL_COLOR_BUFFER_BIT",
    "GL_DEPTH_BUFFER_BIT",
    "GL_STENCIL_BUFFER_BIT",
    "GL_ACCUM_BUFFER_BIT",
    noun="a buffer bit (glClear's)",
)
BIND_TARGETS = enums(
    "GL_TEXTURE_2D",
    "GL_TEXTURE_CUBE_MAP",
    noun="a texture target (glBindTexture's)",
)
IMAGE_TARGETS = enums(
    "GL_TEXTURE_2D",
    *(f"GL_TEXTURE_CUBE_MAP_{s}_{a}" for s in ("POSITIVE", "NEGATIVE") for a in "XYZ"),
    noun="a texture image target",
    member="face",
)
TEX_PARAMS = enums(
    "GL_TEXTURE_MIN_FILTER",
    "GL_TEXTURE_MAG_FILTER",
    "GL_TEXTURE_WRAP_S",
    "GL_TEXTURE_WRAP_T",
    "GL_TEXTURE_WRAP_R",
    "GL_TEXTURE_BASE_LEVEL",
    "GL_TEXTURE_MAX_LEVEL",
    "GL_TEXTURE_MIN_LOD",
    "GL_TEXTURE_MAX_LOD",
    "GL_TEXTURE_LOD_BIAS",
    "GL_GENERATE_MIPMAP",
    noun="a texture parameter",
)
TEX_PARAM_VALUES = enums(
    "GL_NEAREST",
    "GL_LINEAR",
    "GL_NEAREST_MIPMAP_NEAREST",
    "GL_LINEAR_MIPMAP_NEAREST",
    "GL_NEAREST_MIPMAP_LINEAR",
    "GL_LINEAR_MIPMAP_LINEAR",
    "GL_CLAMP",
    "GL_CLAMP_TO_EDGE",
    "GL_CLAMP_TO_BORDER",
    "GL_REPEAT",
    "GL_MIRRORED_REPEAT",
    noun="a filter or wrap mode",
)
TEX_PARAM_VECTORS = enums(
    "GL_TEXTURE_BORDER_COLOR",
    noun="a texture parameter of four numbers",
)
PIXEL_FORMAT_CHANNELS = (
    ("GL_RGB", 3),
    ("GL_RGBA", 4),
    ("GL_BGR", 3),
    ("GL_BGRA", 4),
    ("GL_RED", 1),
    ("GL_GREEN", 1),
    ("GL_BLUE", 1),
    ("GL_ALPHA", 1),
    ("GL_LUMINANCE", 1),
    ("GL_LUMINANCE_ALPHA", 2),
    ("GL_DEPTH_COMPONENT", 1),
)
PIXEL_FORMATS = {int(getattr(GL, name)): channels for name, channels in PIXEL_FORMAT_CHANNELS}
PIXEL_FORMAT_ENUMS = enums(*(name for name, _ in PIXEL_FORMAT_CHANNELS), noun="a pixel format")
PIXEL_TYPE_SIZES = (
    ("GL_UNSIGNED_BYTE", 1, "u1"),
    ("GL_BYTE", 1, "i1"),
    ("GL_UNSIGNED_SHORT", 2, "u2"),
    ("GL_SHORT", 2, "i2"),
    ("GL_UNSIGNED_INT", 4, "u4"),
    ("GL_INT", 4, "i4"),
    ("GL_FLOAT", 4, "f4"),
)
PIXEL_TYPES = {int(getattr(GL, name)): (size, code) for name, size, code in PIXEL_TYPE_SIZES}
PIXEL_TYPE_ENUMS = enums(*(name for name, _, _ in PIXEL_TYPE_SIZES), noun="a pixel type")
INTERNAL_FORMATS = enums(
    "GL_RGB",
    "GL_RGBA",
    "GL_RGB8",
    "GL_RGBA8",
    "GL_RGB16",
    "GL_RGBA16",
    "GL_RGB16F",
    "GL_RGBA16F",
    "GL_RGB32F",
    "GL_RGBA32F",
    "GL_R8",
    "GL_RG8",
    "GL_RED",
    "GL_LUMINANCE",
    "GL_LUMINANCE8",
    "GL_ALPHA",
    "GL_LUMINANCE_ALPHA",
    "GL_SRGB8",
    "GL_SRGB8_ALPHA8",
    "GL_DEPTH_COMPONENT",
    "GL_DEPTH_COMPONENT16",
    "GL_DEPTH_COMPONENT24",
    noun="an internal format",
    numbers=(1, 2, 3, 4),
)
TEXGEN_COORDS = enums(
    "GL_S",
    "GL_T",
    "GL_R",
    "GL_Q",
    noun="a texture coordinate (glTexGen's)",
)
TEXGEN_MODES = enums(
    "GL_EYE_LINEAR",
    "GL_OBJECT_LINEAR",
    "GL_SPHERE_MAP",
    "GL_NORMAL_MAP",
    "GL_REFLECTION_MAP",
    noun="a texgen mode",
)
TEXGEN_PARAMS = enums("GL_TEXTURE_GEN_MODE", noun="the texgen mode's name")
TEXENV_TARGETS = enums("GL_TEXTURE_ENV", noun="the texture environment")
TEXENV_PARAMS = enums("GL_TEXTURE_ENV_MODE", noun="the texture environment mode's name")
TEXGEN_PLANES = enums(
    "GL_EYE_PLANE",
    "GL_OBJECT_PLANE",
    noun="a texgen plane",
)
TEXENV_MODES = enums(
    "GL_MODULATE",
    "GL_REPLACE",
    "GL_DECAL",
    "GL_BLEND",
    "GL_ADD",
    noun="a texture environment mode",
)
UNITS = enums(*(f"GL_TEXTURE{i}" for i in range(8)), noun="a texture unit", member="unit")
DEPTH_FUNCS = enums(
    "GL_NEVER",
    "GL_LESS",
    "GL_EQUAL",
    "GL_LEQUAL",
    "GL_GREATER",
    "GL_NOTEQUAL",
    "GL_GEQUAL",
    "GL_ALWAYS",
    noun="a depth function",
)
BLEND_FACTORS = enums(
    "GL_ZERO",
    "GL_ONE",
    "GL_SRC_COLOR",
    "GL_ONE_MINUS_SRC_COLOR",
    "GL_SRC_ALPHA",
    "GL_ONE_MINUS_SRC_ALPHA",
    "GL_DST_ALPHA",
    "GL_ONE_MINUS_DST_ALPHA",
    "GL_DST_COLOR",
    "GL_ONE_MINUS_DST_COLOR",
    noun="a blend factor",
)
FACES = enums(
    "GL_FRONT",
    "GL_BACK",
    "GL_FRONT_AND_BACK",
    noun="a polygon face",
)
WINDINGS = enums(
    "GL_CW",
    "GL_CCW",
    noun="a winding",
)
POLYGON_MODES = enums(
    "GL_POINT",
    "GL_LINE",
    "GL_FILL",
    noun="a polygon mode",
)
SHADE_MODELS = enums(
    "GL_FLAT",
    "GL_SMOOTH",
    noun="a shade model",
)
HINT_TARGETS = enums(
    "GL_PERSPECTIVE_CORRECTION_HINT",
    "GL_LINE_SMOOTH_HINT",
    "GL_POINT_SMOOTH_HINT",
    "GL_POLYGON_SMOOTH_HINT",
    "GL_FOG_HINT",
    "GL_GENERATE_MIPMAP_HINT",
    noun="a hint target",
)
HINT_MODES = enums(
    "GL_FASTEST",
    "GL_NICEST",
    "GL_DONT_CARE",
    noun="a hint mode",
)
STORE_PARAMS = enums(
    "GL_UNPACK_ALIGNMENT",
    "GL_PACK_ALIGNMENT",
    noun="a pixel-store parameter",
)
STRINGS = enums(
    "GL_VENDOR",
    "GL_RENDERER",
    "GL_VERSION",
    "GL_SHADING_LANGUAGE_VERSION",
    noun="a string name (glGetString's)",
)
LEVEL_PARAMS = enums(
    "GL_TEXTURE_WIDTH",
    "GL_TEXTURE_HEIGHT",
    "GL_TEXTURE_INTERNAL_FORMAT",
    noun="a texture level parameter",
)

QUERY_NAME_SIZES = (
    ("GL_VIEWPORT", 4),
    ("GL_SCISSOR_BOX", 4),
    ("GL_COLOR_CLEAR_VALUE", 4),
    ("GL_DEPTH_CLEAR_VALUE", 1),
    ("GL_MATRIX_MODE", 1),
    ("GL_MODELVIEW_MATRIX", 16),
    ("GL_PROJECTION_MATRIX", 16),
    ("GL_TEXTURE_MATRIX", 16),
    ("GL_ACTIVE_TEXTURE", 1),
    ("GL_TEXTURE_BINDING_2D", 1),
    ("GL_TEXTURE_BINDING_CUBE_MAP", 1),
    ("GL_CURRENT_PROGRAM", 1),
    ("GL_MAX_TEXTURE_SIZE", 1),
    ("GL_MAX_TEXTURE_UNITS", 1),
    ("GL_MAX_COMBINED_TEXTURE_IMAGE_UNITS", 1),
    ("GL_CURRENT_COLOR", 4),
    ("GL_CURRENT_TEXTURE_COORDS", 4),
    ("GL_MODELVIEW_STACK_DEPTH", 1),
    ("GL_PROJECTION_STACK_DEPTH", 1),
    ("GL_DEPTH_FUNC", 1),
    ("GL_CULL_FACE_MODE", 1),
    ("GL_FRONT_FACE", 1),
    ("GL_PACK_ALIGNMENT", 1),
    ("GL_UNPACK_ALIGNMENT", 1),
    ("GL_MAX_VIEWPORT_DIMS", 2),
    ("GL_DEPTH_RANGE", 2),
    ("GL_DEPTH_WRITEMASK", 1),
    ("GL_COLOR_WRITEMASK", 4),
    ("GL_POLYGON_MODE", 2),
    ("GL_SHADE_MODEL", 1),
    ("GL_LINE_WIDTH", 1),
    ("GL_POINT_SIZE", 1),
    ("GL_BLEND_SRC", 1),
    ("GL_BLEND_DST", 1),
    ("GL_MAX_CUBE_MAP_TEXTURE_SIZE", 1),
)
QUERY_SIZES = {int(getattr(GL, name)): size for name, size in QUERY_NAME_SIZES} | {
    cap: 1 for cap in CAPS
}
QUERIES = enums(
    *(name for name, _ in QUERY_NAME_SIZES), *CAPS.names.values(), noun="a state glGet takes"
)

ENUM_SETS: tuple[Enums, ...] = (
    TEXGEN_COORDS,
    UNITS,
    MATRIX_MODES,
    BEGIN_MODES,
    TEXGEN_MODES,
    TEXENV_MODES,
    TEX_PARAMS,
    TEX_PARAM_VALUES,
    IMAGE_TARGETS,
    BIND_TARGETS,
    CAPS,
    INTERNAL_FORMATS,
    PIXEL_FORMAT_ENUMS,
    PIXEL_TYPE_ENUMS,
    CLEAR_BITS,
    TEXGEN_PLANES,
    TEXGEN_PARAMS,
    TEXENV_TARGETS,
    TEXENV_PARAMS,
    DEPTH_FUNCS,
    BLEND_FACTORS,
    FACES,
    WINDINGS,
    POLYGON_MODES,
    SHADE_MODELS,
    HINT_TARGETS,
    HINT_MODES,
    STORE_PARAMS,
    STRINGS,
    LEVEL_PARAMS,
)
"""Every set of enums the allow-list takes, the more telling first: what names a value and
says what kind of enum it is in a refusal."""

SIDE = 1024
"""The largest texture side, viewport and copy the labs accept."""


@dataclass(frozen=True)
class Spec:
    """A call the student may make: what the student side packs (``kinds``), the check of
    each argument, the executor's handler (``handler``; '' for a plain call of the GL
    function of the same name) and whether it may run between glBegin and glEnd."""

    kinds: tuple[str, ...]
    checks: tuple[Check, ...]
    handler: str = ""
    in_begin: bool = False


def spec(kinds: str, *checks: Check, handler: str = "", in_begin: bool = False) -> Spec:
    return Spec(tuple(kinds.split()) if kinds else (), checks, handler, in_begin)


TYPE_RANGES = {
    "b": (-(1 << 7), (1 << 7) - 1),
    "s": (-(1 << 15), (1 << 15) - 1),
    "i": (-(1 << 31), (1 << 31) - 1),
    "ub": (0, (1 << 8) - 1),
    "us": (0, (1 << 16) - 1),
    "ui": (0, (1 << 32) - 1),
}
"""The integer types of GL's call forms (the suffix of ``glVertex3s``, ``glColor3ub``)
and the values each holds."""
FORM = re.compile(r"(?P<n>[1-4])?(?P<type>ub|us|ui|b|s|i|f|d)(?P<v>v?)$")


def form_type(name: str) -> str:
    """The type suffix of call form ``name`` (``"s"`` for glVertex3sv, ``"ub"`` for
    glColor4ub), '' when it has none."""
    match = FORM.search(name)
    return match.group("type") if match else ""


def immediate(
    base: str,
    sizes: tuple[int, ...],
    types: Any,
    handler: str,
    lo: float = -1e9,
    hi: float = 1e9,
    unit: bool = False,
) -> dict[str, Spec]:
    """Every form of an immediate-mode call: ``base`` + size + type (+ ``v``), each
    argument checked by its type (integers in the type's range, finite numbers in
    ``lo``..``hi``); ``unit``: a texture unit first (glMultiTexCoord)."""
    found: dict[str, Spec] = {}
    for size in sizes:
        count = "" if base.endswith("3") else str(size)
        for kind in types:
            integral = kind in TYPE_RANGES
            low, high = TYPE_RANGES[kind] if integral else (lo, hi)
            check = integer(int(low), int(high)) if integral else real(low, high)
            code = "i" if integral else "f"
            first, first_check = ("i ", (one_of(UNITS),)) if unit else ("", ())
            found[f"{base}{count}{kind}"] = spec(
                first + " ".join(code * size),
                *first_check,
                *[check] * size,
                handler=handler,
                in_begin=True,
            )
            found[f"{base}{count}{kind}v"] = spec(
                first + ("n" if integral else "v"),
                *first_check,
                vector((size,), low, high, integral),
                handler=handler or "vector_call",
                in_begin=True,
            )
    return found


ANY_INT, SIDE_INT = integer(), integer(-SIDE * 16, SIDE * 16)
SIZE_INT, LEVEL = integer(0, SIDE), integer(0, 10)
NUMBER, UNIT_RANGE = real(), real(-1e6, 1e6)

GL_SPECS: dict[str, Spec] = {
    # matrices
    "glMatrixMode": spec("i", one_of(MATRIX_MODES), handler="matrix_mode"),
    "glLoadIdentity": spec("", handler="matrix_op"),
    "glPushMatrix": spec("", handler="push_matrix"),
    "glPopMatrix": spec("", handler="pop_matrix"),
    "glOrtho": spec("f f f f f f", *[NUMBER] * 6, handler="matrix_op"),
    "glFrustum": spec("f f f f f f", *[NUMBER] * 6, handler="matrix_op"),
    **{f"glTranslate{t}": spec("f f f", *[NUMBER] * 3, handler="matrix_op") for t in "fd"},
    **{f"glScale{t}": spec("f f f", *[NUMBER] * 3, handler="matrix_op") for t in "fd"},
    **{f"glRotate{t}": spec("f f f f", *[NUMBER] * 4, handler="matrix_op") for t in "fd"},
    **{
        f"gl{op}Matrix{t}": spec("v", vector((16,)), handler="matrix_op")
        for op in ("Load", "Mult", "LoadTranspose", "MultTranspose")
        for t in "fd"
    },
    # the frame
    "glViewport": spec("i i i i", SIDE_INT, SIDE_INT, SIZE_INT, SIZE_INT, handler="viewport"),
    "glScissor": spec("i i i i", SIDE_INT, SIDE_INT, SIZE_INT, SIZE_INT),
    "glClear": spec("i", bits(CLEAR_BITS), handler="clear"),
    "glClearColor": spec("f f f f", *[UNIT_RANGE] * 4, handler="clear_color"),
    "glClearDepth": spec("f", UNIT_RANGE),
    "glClearDepthf": spec("f", UNIT_RANGE),
    "glDepthRange": spec("f f", UNIT_RANGE, UNIT_RANGE),
    "glDepthRangef": spec("f f", UNIT_RANGE, UNIT_RANGE),
    "glFlush": spec(""),
    "glFinish": spec(""),
    "glEnable": spec("i", one_of(CAPS), handler="enable"),
    "glDisable": spec("i", one_of(CAPS), handler="enable"),
    "glDepthFunc": spec("i", one_of(DEPTH_FUNCS)),
    "glDepthMask": spec("b", integer(0, 1)),
    "glColorMask": spec("b b b b", *[integer(0, 1)] * 4),
    "glBlendFunc": spec("i i", one_of(BLEND_FACTORS), one_of(BLEND_FACTORS)),
    "glCullFace": spec("i", one_of(FACES)),
    "glFrontFace": spec("i", one_of(WINDINGS)),
    "glPolygonMode": spec("i i", one_of(FACES), one_of(POLYGON_MODES)),
    "glShadeModel": spec("i", one_of(SHADE_MODELS)),
    "glHint": spec("i i", one_of(HINT_TARGETS), one_of(HINT_MODES)),
    "glLineWidth": spec("f", real(0.0, 16.0)),
    "glPointSize": spec("f", real(0.0, 16.0)),
    "glPolygonOffset": spec("f f", UNIT_RANGE, UNIT_RANGE),
    "glPixelStorei": spec("i i", one_of(STORE_PARAMS), integer(1, 8), handler="pixel_store"),
    "glPixelStoref": spec("i f", one_of(STORE_PARAMS), real(1, 8), handler="pixel_store"),
    # immediate mode
    "glBegin": spec("i", one_of(BEGIN_MODES), handler="begin"),
    "glEnd": spec("", handler="end", in_begin=True),
    **immediate("glVertex", (2, 3, 4), "sifd", "vertex"),
    **immediate("glTexCoord", (1, 2, 3, 4), "sifd", "texcoord"),
    **immediate("glMultiTexCoord", (1, 2, 3, 4), "sifd", "texcoord", unit=True),
    **immediate(
        "glColor", (3, 4), ("b", "s", "i", "f", "d", "ub", "us", "ui"), "color", lo=-1e3, hi=1e3
    ),
    **immediate("glNormal3", (3,), "bsifd", ""),
    # textures
    "glGenTextures": spec("i", integer(0, 64), handler="gen_textures"),
    "glDeleteTextures": spec("n n?", names(), names(), handler="delete_textures"),
    "glIsTexture": spec("i", ANY_INT, handler="is_texture"),
    "glBindTexture": spec("i i", one_of(BIND_TARGETS), ANY_INT, handler="bind_texture"),
    "glActiveTexture": spec("i", one_of(UNITS), handler="active_texture"),
    "glTexImage2D": spec(
        "i i i i i i i i p",
        one_of(IMAGE_TARGETS),
        LEVEL,
        one_of(INTERNAL_FORMATS),
        SIZE_INT,
        SIZE_INT,
        integer(0, 1),
        one_of(PIXEL_FORMAT_ENUMS),
        one_of(PIXEL_TYPE_ENUMS),
        pixels,
        handler="tex_image",
    ),
    "glTexSubImage2D": spec(
        "i i i i i i i i p",
        one_of(IMAGE_TARGETS),
        LEVEL,
        SIZE_INT,
        SIZE_INT,
        SIZE_INT,
        SIZE_INT,
        one_of(PIXEL_FORMAT_ENUMS),
        one_of(PIXEL_TYPE_ENUMS),
        pixels,
        handler="tex_sub_image",
    ),
    "glCopyTexImage2D": spec(
        "i i i i i i i i",
        one_of(IMAGE_TARGETS),
        LEVEL,
        one_of(INTERNAL_FORMATS),
        SIDE_INT,
        SIDE_INT,
        SIZE_INT,
        SIZE_INT,
        integer(0, 1),
        handler="copy_tex_image",
    ),
    "glCopyTexSubImage2D": spec(
        "i i i i i i i i",
        one_of(IMAGE_TARGETS),
        LEVEL,
        SIZE_INT,
        SIZE_INT,
        SIDE_INT,
        SIDE_INT,
        SIZE_INT,
        SIZE_INT,
        handler="copy_tex_image",
    ),
    "glTexParameteri": spec(
        "i i i",
        one_of(BIND_TARGETS),
        one_of(TEX_PARAMS),
        integer(-1000, 1 << 16),
        handler="tex_parameter",
    ),
    "glTexParameterf": spec(
        "i i f",
        one_of(BIND_TARGETS),
        one_of(TEX_PARAMS),
        real(-1000, 1 << 16),
        handler="tex_parameter",
    ),
    "glTexParameterfv": spec(
        "i i v",
        one_of(BIND_TARGETS),
        one_of(TEX_PARAM_VECTORS),
        vector((4,)),
        handler="tex_parameter",
    ),
    "glTexParameteriv": spec(
        "i i n",
        one_of(BIND_TARGETS),
        one_of(TEX_PARAM_VECTORS),
        vector((4,), *TYPE_RANGES["i"], integral=True),
        handler="tex_parameter",
    ),
    "glGenerateMipmap": spec("i", one_of(BIND_TARGETS), handler="generate_mipmap"),
    "glTexEnvi": spec(
        "i i i",
        one_of(TEXENV_TARGETS),
        one_of(TEXENV_PARAMS),
        one_of(TEXENV_MODES),
    ),
    "glTexEnvf": spec(
        "i i f",
        one_of(TEXENV_TARGETS),
        one_of(TEXENV_PARAMS),
        real(0, 1 << 16),
        handler="texenv_f",
    ),
    "glTexEnviv": spec(
        "i i n",
        one_of(TEXENV_TARGETS),
        one_of(TEXENV_PARAMS),
        vector((1,), 0, 1 << 16, True),
        handler="texenv_f",
    ),
    "glTexEnvfv": spec(
        "i i v",
        one_of(TEXENV_TARGETS),
        one_of(TEXENV_PARAMS),
        vector((1,), 0, 1 << 16),
        handler="texenv_f",
    ),
    "glTexGeni": spec(
        "i i i",
        one_of(TEXGEN_COORDS),
        one_of(TEXGEN_PARAMS),
        one_of(TEXGEN_MODES),
        handler="texgen",
    ),
    **{
        f"glTexGen{t}": spec(
            "i i f",
            one_of(TEXGEN_COORDS),
            one_of(TEXGEN_PARAMS),
            real(0, 1 << 16),
            handler="texgen",
        )
        for t in "fd"
    },
    **{
        f"glTexGen{t}v": spec(
            "i i v",
            one_of(TEXGEN_COORDS),
            one_of(TEXGEN_PLANES),
            vector((4,)),
            handler="vector_call",
        )
        for t in "fd"
    },
    "glTexGeniv": spec(
        "i i n",
        one_of(TEXGEN_COORDS),
        one_of(TEXGEN_PLANES),
        vector((4,), *TYPE_RANGES["i"], integral=True),
        handler="vector_call",
    ),
    # programs: only the lab's
    "glUseProgram": spec("i", ANY_INT, handler="use_program"),
    "glGetUniformLocation": spec("i s", ANY_INT, text(128), handler="uniform_location"),
    **{
        f"glUniform{n}{t}": spec(
            "i " + " ".join(t * n),
            integer(-1, 1 << 16),
            *[integer() if t == "i" else NUMBER] * n,
            handler="uniform",
        )
        for n in (1, 2, 3, 4)
        for t in "if"
    },
    **{
        f"glUniform{n}ui": spec(
            "i " + " ".join("i" * n),
            integer(-1, 1 << 16),
            *[integer(*TYPE_RANGES["ui"])] * n,
            handler="uniform",
        )
        for n in (1, 2, 3, 4)
    },
    **{
        f"glUniform{n}{t}v": spec(
            "i i " + ("v" if t == "f" else "n"),
            integer(-1, 1 << 16),
            integer(0, 64),
            vector(
                tuple(range(0, 64 * n + 1)),
                TYPE_RANGES.get(t, (-1e9, 1e9))[0],
                TYPE_RANGES.get(t, (-1e9, 1e9))[1],
                integral=t != "f",
            ),
            handler="uniform_vector",
        )
        for n in (1, 2, 3, 4)
        for t in ("i", "f", "ui")
    },
    **{
        f"glUniformMatrix{n}fv": spec(
            "i i b v",
            integer(-1, 1 << 16),
            integer(0, 16),
            integer(0, 1),
            vector(tuple(range(0, 16 * n * n + 1))),
            handler="uniform_matrix",
        )
        for n in (2, 3, 4)
    },
    # queries
    "glGetError": spec("", handler="get_error"),
    **{
        name: spec("i", one_of(QUERIES), handler="get")
        for name in ("glGetIntegerv", "glGetFloatv", "glGetDoublev", "glGetBooleanv")
    },
    "glIsEnabled": spec("i", one_of(CAPS), handler="is_enabled"),
    "glGetString": spec("i", one_of(STRINGS), handler="get_string"),
    "glGetTexParameteriv": spec(
        "i i", one_of(BIND_TARGETS), one_of(TEX_PARAMS), handler="get_tex_parameter"
    ),
    "glGetTexParameterfv": spec(
        "i i", one_of(BIND_TARGETS), one_of(TEX_PARAMS), handler="get_tex_parameter"
    ),
    **{
        f"glGetTexLevelParameter{t}v": spec(
            "i i i",
            one_of(IMAGE_TARGETS),
            LEVEL,
            one_of(LEVEL_PARAMS),
            handler="get_level_parameter",
        )
        for t in "if"
    },
    **{
        f"glGetTexGen{t}v": spec(
            "i i", one_of(TEXGEN_COORDS), one_of(TEXGEN_PARAMS), handler="get_texgen"
        )
        for t in "ifd"
    },
}

GLU_SPECS: dict[str, Spec] = {
    "gluLookAt": spec("f f f f f f f f f", *[NUMBER] * 9, handler="matrix_op"),
    "gluPerspective": spec("f f f f", real(-1e4, 1e4), NUMBER, NUMBER, NUMBER, handler="matrix_op"),
    "gluOrtho2D": spec("f f f f", *[NUMBER] * 4, handler="matrix_op"),
}

# ------------------------------------------------------------ what each lab leaves out
_READS = "the labs never read back what was drawn (the checker looks at the frame itself)"
REFUSED: dict[str, str] = {
    **{
        name: _READS
        for name in (
            "glReadPixels",
            "glReadnPixels",
            "glReadBuffer",
            "glCopyPixels",
            "glDrawPixels",
            "glBlitFramebuffer",
        )
    },
    **{
        name: "no lab reads a texture back"
        for name in (
            "glGetTexImage",
            "glGetnTexImage",
            "glGetTextureImage",
            "glGetTextureSubImage",
            "glGetCompressedTexImage",
        )
    },
    **{
        name: "no lab uses feedback or selection mode"
        for name in (
            "glRenderMode",
            "glFeedbackBuffer",
            "glSelectBuffer",
            "glPassThrough",
            "glInitNames",
            "glPushName",
            "glLoadName",
        )
    },
    **{
        name: "no lab queries what was drawn"
        for name in (
            "glBeginQuery",
            "glEndQuery",
            "glGenQueries",
            "glGetQueryObjectiv",
            "glGetQueryObjectuiv",
            "glGetQueryObjecti64v",
            "glGetQueryObjectui64v",
            "glGetQueryiv",
            "glBeginConditionalRender",
        )
    },
}
"""Calls no lab offers, with why, for the refusal the student reads: every way to learn
what the trusted side drew (pixels, textures, feedback, selection, queries)."""

# Each family whole, every form the allow-list has (glTexGend, glUniform1ui...), so that
# a form added to GL_SPECS is left out with its family: what a lab's ``left_out()`` takes.
UNIFORMS = tuple(
    name for name in GL_SPECS if name.startswith(("glUniform", "glGetUniformLocation"))
)
"""The uniform calls, every form."""
COPIES = ("glCopyTexImage2D", "glCopyTexSubImage2D")
"""The copies from the framebuffer into a texture."""
TEXGEN = tuple(name for name in GL_SPECS if name.startswith(("glTexGen", "glGetTexGen")))
"""The texgen calls, every form."""

SETUP_DRAWS = frozenset({"glBegin", "glCopyTexImage2D", "glCopyTexSubImage2D"})
"""Calls that draw or capture: refused before the first frame (the file's top level and
the set-up functions), like the kit's drawing calls; a lab draws only in its frame."""


# ------------------------------------------------------------------------ the channels
@dataclass(frozen=True)
class Channel:
    """A way a file's own numbers could reach the frame, closed unless a lab's handout
    teaches it (the lab's ``trusted.channels()``): the calls that open it (every form),
    the ``glBegin`` modes and the ``glEnable`` switches that do, and the matrix modes."""

    name: str
    carries: str
    """What of the file's numbers it would carry to the frame, for a person."""
    calls: tuple[str, ...] = ()
    modes: frozenset[int] = frozenset()
    caps: frozenset[int] = frozenset()
    matrix_modes: frozenset[int] = frozenset()


def _forms(*prefixes: str) -> tuple[str, ...]:
    return tuple(name for name in GL_SPECS if name.startswith(prefixes))


FILLED_MODES = enums(
    "GL_TRIANGLES",
    "GL_TRIANGLE_STRIP",
    "GL_TRIANGLE_FAN",
    "GL_QUADS",
    "GL_QUAD_STRIP",
    "GL_POLYGON",
)
CHANNELS: dict[str, Channel] = {
    c.name: c
    for c in (
        Channel(
            "immediate_mode",
            "vertex positions: filled shapes of the file's own drawn wherever it says",
            ("glBegin", "glEnd", *_forms("glVertex")),
            modes=FILLED_MODES,
        ),
        Channel(
            "texture_coordinates",
            "which texel of a lab picture or of a copy each vertex shows",
            _forms("glTexCoord"),
        ),
        Channel(
            "multitexture_coordinates",
            "texture coordinates on units other than 0",
            _forms("glMultiTexCoord"),
        ),
        Channel(
            "vertex_colours",
            "colours: each vertex a colour of the file's own",
            (*(name for name in _forms("glColor") if form_type(name)), "glShadeModel"),
        ),
        Channel(
            "lines_and_points",
            "lines and points, which GL draws even where a viewport is empty and past "
            "its edges (wide lines, big points)",
            ("glPolygonMode", "glLineWidth", "glPointSize"),
            modes=enums("GL_POINTS", "GL_LINES", "GL_LINE_STRIP", "GL_LINE_LOOP"),
            caps=enums("GL_LINE_SMOOTH", "GL_POINT_SMOOTH"),
        ),
        Channel(
            "lighting",
            "normals, lit: each vertex a grey of the file's own; fog",
            _forms("glNormal"),
            caps=enums(
                "GL_LIGHTING",
                "GL_LIGHT0",
                "GL_LIGHT1",
                "GL_COLOR_MATERIAL",
                "GL_NORMALIZE",
                "GL_RESCALE_NORMAL",
                "GL_FOG",
            ),
        ),
        Channel(
            "fixed_texturing",
            "textures combined by the fixed pipeline's texture environments (replace, "
            "add, blend ...) on any unit",
            _forms("glTexEnv"),
            caps=enums("GL_TEXTURE_2D", "GL_TEXTURE_CUBE_MAP"),
        ),
        Channel(
            "texgen",
            "texture coordinates made by texgen from the geometry",
            (
                *(name for name in _forms("glTexGen") if not name.endswith("v")),
                *_forms("glGetTexGen"),
            ),
            caps=enums("GL_TEXTURE_GEN_S", "GL_TEXTURE_GEN_T"),
        ),
        Channel(
            "texgen_planes",
            "texgen planes and the r and q coordinates: any linear map from the window "
            "to a picture",
            tuple(n for n in _forms("glTexGen") if n.endswith("v")),
            caps=enums("GL_TEXTURE_GEN_R", "GL_TEXTURE_GEN_Q"),
        ),
        Channel(
            "texture_matrix",
            "the texture matrix: any linear map of texture coordinates",
            matrix_modes=enums("GL_TEXTURE"),
        ),
        Channel(
            "copies",
            "copies of what was drawn into a texture (whole pictures)",
            ("glCopyTexImage2D",),
        ),
        Channel(
            "copy_parts",
            "parts of what was drawn copied into parts of a texture: a picture painted "
            "rectangle by rectangle from clears",
            ("glCopyTexSubImage2D",),
        ),
        Channel(
            "scissor",
            "the scissor box: clears that paint rectangles of the file's colours",
            ("glScissor",),
            caps=enums("GL_SCISSOR_TEST"),
        ),
        Channel(
            "blending",
            "blending: pixels added to, or mixed with, what is drawn",
            ("glBlendFunc",),
            caps=enums("GL_BLEND", "GL_ALPHA_TEST"),
        ),
        Channel(
            "border_colour",
            "a texture's border colour, shown outside its picture",
            ("glTexParameterfv", "glTexParameteriv"),
        ),
        Channel("stencil", "the stencil test", caps=enums("GL_STENCIL_TEST")),
    )
}
"""Every way a file's numbers could reach the frame other than those closed for every
lab (pixel data: only None or zeros; copies from outside the framebuffer), each closed
unless a lab's handout teaches it. docs/labs-teachers.md lists them with why."""

NEUTRAL = frozenset(
    {
        "glMatrixMode",
        "glLoadIdentity",
        "glPushMatrix",
        "glPopMatrix",
        "glOrtho",
        "glFrustum",
        *_forms("glTranslate", "glScale", "glRotate", "glLoad", "glMult"),
        "glViewport",
        "glClear",
        "glClearColor",
        "glClearDepth",
        "glClearDepthf",
        "glDepthRange",
        "glDepthRangef",
        "glFlush",
        "glFinish",
        "glEnable",
        "glDisable",
        "glDepthFunc",
        "glDepthMask",
        "glColorMask",
        "glCullFace",
        "glFrontFace",
        "glHint",
        "glPolygonOffset",
        "glPixelStorei",
        "glPixelStoref",
        "glGenTextures",
        "glDeleteTextures",
        "glIsTexture",
        "glBindTexture",
        "glActiveTexture",
        "glTexImage2D",
        "glTexSubImage2D",
        "glTexParameteri",
        "glTexParameterf",
        "glGenerateMipmap",
        "glUseProgram",
        *_forms("glUniform", "glGetUniformLocation"),
        *_forms("glGet", "glIs"),
    }
) - {n for c in CHANNELS.values() for n in c.calls}
"""Calls that carry no number of the file's to a pixel: matrices and the viewport (where
the lab's own drawing lands), clears (the whole frame, one colour, with the scissor
closed), depth, culling and colour masks (which of the lab's pixels stay), texture
objects, their sampling and mipmaps made from level 0, uploads (checked: zeros only), the
lab's programs, queries."""
NEUTRAL_CAPS = enums(
    "GL_DEPTH_TEST",
    "GL_CULL_FACE",
    "GL_TEXTURE_CUBE_MAP_SEAMLESS",
    "GL_POLYGON_OFFSET_FILL",
    "GL_MULTISAMPLE",
    "GL_DITHER",
)
"""Switches that carry no number of the file's to a pixel (the others are a channel's)."""


@lru_cache(maxsize=16)
def left_out(lab: str) -> dict[str, str]:
    """Calls of :data:`GL_SPECS` ``lab``'s handout does not need, with why: its lab's
    ``trusted.left_out()`` (the registry's), and every call of a channel its handout does
    not teach (:func:`lab_channels`)."""
    from mirrorlab.labs import find_lab

    found: dict[str, str] = {}
    taught = lab_channels(lab)
    for channel in CHANNELS.values():
        if channel.name not in taught:
            found.update({name: closed(channel) for name in channel.calls})
    found.update(find_lab(lab).module("trusted").left_out())
    return found


@lru_cache(maxsize=16)
def lab_channels(lab: str) -> frozenset[str]:
    """The channels of :data:`CHANNELS` ``lab``'s handout teaches: its lab's
    ``trusted.channels()`` (none when it has no such function)."""
    from mirrorlab.labs import find_lab

    trusted = find_lab(lab).module("trusted")
    taught = frozenset(getattr(trusted, "channels", lambda: ())())
    unknown = taught - set(CHANNELS)
    if unknown:
        raise ValueError(f"lab {lab}: no channel named {', '.join(sorted(unknown))}")
    return taught


def closed(channel: Channel) -> str:
    """Why a call of ``channel`` is refused, for the student (one line)."""
    return f"this lab's handout draws nothing with it ({channel.carries})"


def lab_specs(lab: str) -> dict[str, Spec]:
    """The calls ``lab`` offers: :data:`GL_SPECS` without those it leaves out
    (:func:`left_out`)."""
    leaves = left_out(lab)
    return {name: s for name, s in GL_SPECS.items() if name not in leaves}


def refusal(lab: str, name: str) -> str:
    """Why ``lab`` does not offer ``name`` (one line), '' when no reason is on file."""
    return left_out(lab).get(name) or REFUSED.get(name, "")


def open_for(lab: str, kind: str, value: int) -> str:
    """'' when ``value`` (a glBegin mode, a glEnable switch or a matrix mode: ``kind`` is
    ``modes``, ``caps`` or ``matrix_modes``) is one ``lab`` allows, else why not."""
    taught = lab_channels(lab)
    for channel in CHANNELS.values():
        if value in getattr(channel, kind) and channel.name not in taught:
            return closed(channel)
    return ""


def refused_text(lab: str, name: str) -> str:
    """The one line a student reads when calling ``name``, which ``lab`` does not offer."""
    why = refusal(lab, name)
    return f"{name} is not one of the OpenGL calls this lab offers" + (f": {why}" if why else "")


MATRIX_REPLACES = {
    "glLoadIdentity",
    "glLoadMatrixf",
    "glLoadMatrixd",
    "glLoadTransposeMatrixf",
    "glLoadTransposeMatrixd",
}


def offered(specs: dict[str, Spec]) -> dict[str, list[str]]:
    """What the student side packs for each call (sent to the sandbox at the start)."""
    return {name: list(s.kinds) for name, s in specs.items()}


def check_arguments(name: str, call: Spec, args: Any) -> list[Any]:
    """``args`` checked against ``call``; CallError on the first that fails."""
    if not isinstance(args, list):
        raise CallError("TypeError", f"{name}: malformed arguments")
    required = sum(not k.endswith("?") for k in call.kinds)
    if not required <= len(args) <= len(call.kinds):
        raise CallError(
            "TypeError", f"{name}() takes {len(call.kinds)} arguments ({len(args)} given)"
        )
    names = arg_names(name)
    checked = [
        check(value, f"{name}() argument {i + 1}" + (f" ({names[i]})" if i < len(names) else ""))
        for i, (check, value) in enumerate(zip(call.checks, args, strict=False))
    ]
    why, refused = degenerate(name, checked)
    if refused:
        raise gl_error(GL_INVALID_VALUE, f"{name}: {why}")
    return checked


VALUES_BY_NAME = {
    "GL_TEXTURE_MIN_FILTER": "TEX_PARAM_VALUES",
    "GL_TEXTURE_MAG_FILTER": "TEX_PARAM_VALUES",
    "GL_TEXTURE_WRAP_S": "TEX_PARAM_VALUES",
    "GL_TEXTURE_WRAP_T": "TEX_PARAM_VALUES",
    "GL_TEXTURE_WRAP_R": "TEX_PARAM_VALUES",
    "GL_TEXTURE_ENV_MODE": "TEXENV_MODES",
    "GL_TEXTURE_GEN_MODE": "TEXGEN_MODES",
}
"""Parameters whose value is an enum though the call takes a number (glTexParameteri's
filters, glTexEnvf's mode): the set that names the value."""


def trace_notes(name: str, call: Spec, args: list[Any]) -> dict[str, Any]:
    """What the call trace keeps of a checked call beside its numbers: the GL names of its
    enum arguments (``names``, by position) and why it cannot work (``note``, from
    :func:`degenerate`) when GL carries it out all the same."""
    found: dict[str, Any] = {}
    names: dict[str, str] = {}
    for i, (check, value) in enumerate(zip(call.checks, args, strict=False)):
        allowed = getattr(check, "enums", None)
        if allowed is not None and type(value) is int:
            names[str(i)] = gl_name(value, allowed)
        elif getattr(check, "bits", None) is not None and type(value) is int:
            names[str(i)] = bit_names(value, check.bits)  # type: ignore[attr-defined]
        elif i and str(i - 1) in names and names[str(i - 1)] in VALUES_BY_NAME:
            values = globals()[VALUES_BY_NAME[names[str(i - 1)]]]
            number = value[0] if isinstance(value, list) and value else value
            if isinstance(number, int | float) and int(number) == number and number in values:
                names[str(i)] = gl_name(int(number), values)
    if names:
        found["names"] = names
    why, _ = degenerate(name, args)
    if why:
        found["note"] = why
    return found


@lru_cache(maxsize=512)
def arg_names(name: str) -> tuple[str, ...]:
    """The names PyOpenGL gives the arguments of ``name`` (``('left', 'right', ...)``)."""
    from OpenGL import GLU

    function = getattr(GLU if name.startswith("glu") else GL, name, None)
    while function is not None and not getattr(function, "argNames", None):
        function = getattr(function, "wrappedOperation", None)  # PyOpenGL's lazy wrappers
    return tuple(str(n) for n in getattr(function, "argNames", None) or ())


MATRIX_CALLS = frozenset(
    {
        "glOrtho",
        "glFrustum",
        "gluOrtho2D",
        "gluPerspective",
        "gluLookAt",
        *(f"gl{op}{t}" for op in ("Translate", "Scale", "Rotate") for t in "fd"),
        *(
            f"gl{op}Matrix{t}"
            for op in ("Load", "Mult", "LoadTranspose", "MultTranspose")
            for t in "fd"
        ),
    }
)


def _point(values: Any) -> str:
    return "(" + ", ".join(f"{float(v):g}" for v in values) + ")"


def degenerate(name: str, args: list[Any]) -> tuple[str, bool]:
    """Why the call ``name`` with these (checked) ``args`` cannot do its work, naming the
    argument, and whether GL refuses it (``GL_INVALID_VALUE``) or carries it out to no use
    (a matrix that flattens space or looks nowhere, a viewport of no pixels): ('', False)
    when it can. The same on every context, since the checker says it before GL runs."""
    names = arg_names(name) or tuple(f"argument {i + 1}" for i in range(len(args)))
    values = {n: a for n, a in zip(names, args, strict=False)}

    def equal(a: str, b: str, what: str) -> str:
        if a in values and b in values and values[a] == values[b]:
            return f"{a} = {b} = {values[a]:g}: {what}"
        return ""

    if name in ("glOrtho", "glFrustum", "gluOrtho2D"):
        for a, b, what in (
            ("left", "right", "the box has no width, so x cannot be mapped to -1..1"),
            ("bottom", "top", "the box has no height, so y cannot be mapped to -1..1"),
            ("zNear", "zFar", "the box has no depth, so z cannot be mapped to -1..1"),
        ):
            if found := equal(a, b, what):
                return found, True
        if name == "glFrustum":
            for key in ("zNear", "zFar"):
                if values[key] <= 0:
                    return (
                        f"{key} = {values[key]:g}: a perspective box lies in front of the "
                        f"eye, so both of its planes must be at a distance > 0",
                        True,
                    )
    if name == "gluPerspective":
        fovy, aspect, near, far = (values[k] for k in ("fovy", "aspect", "zNear", "zFar"))
        if not 0 < fovy < 180:
            return (
                f"fovy = {fovy:g}: a field of view lies between 0 and 180 degrees; at "
                f"{fovy:g} the camera sees {'nothing' if fovy <= 0 else 'everything at once'}",
                False,
            )
        if aspect == 0:
            return "aspect = 0: the view has no width (GLU leaves the matrix unchanged)", False
        if near == far:
            return (
                f"zNear = zFar = {near:g}: the view has no depth (GLU leaves the matrix unchanged)",
                False,
            )
        if near <= 0:
            return (
                f"zNear = {near:g}: the near plane must lie in front of the eye (> 0), or "
                f"depth has no precision left",
                False,
            )
    if name == "gluLookAt":
        eye = [values[f"eye{a}"] for a in "XYZ"]
        center = [values[f"center{a}"] for a in "XYZ"]
        up = [values[f"up{a}"] for a in "XYZ"]
        forward = [c - e for c, e in zip(center, eye, strict=True)]
        if not any(forward):
            return (
                f"eye and center are both {_point(eye)}: the camera has no direction to look in",
                False,
            )
        if not any(up):
            return "up = (0, 0, 0): the camera has no up, so it can turn any way", False
        cross = (
            forward[1] * up[2] - forward[2] * up[1],
            forward[2] * up[0] - forward[0] * up[2],
            forward[0] * up[1] - forward[1] * up[0],
        )
        size = math.hypot(*forward) * math.hypot(*up)
        if math.hypot(*cross) <= 1e-6 * size:
            return (
                f"up {_point(up)} is parallel to the view direction {_point(forward)} "
                f"(center - eye): the camera's sideways direction is undefined, so it can "
                f"turn any way about it",
                False,
            )
    if name.startswith("glScale"):
        flat = [a for a, v in zip("xyz", args, strict=False) if v == 0]
        if flat:
            return (
                f"{' and '.join(flat)} = 0: a scale of 0 flattens everything onto "
                f"{'a plane' if len(flat) == 1 else 'a line or a point'} (the matrix is "
                f"singular)",
                False,
            )
    if name.startswith("glRotate") and not any(args[1:4]):
        return "the axis (0, 0, 0) has no direction: GL rotates nothing about it", False
    if name in MATRIX_CALLS and "Matrix" in name and isinstance(args[0], list):
        import numpy as np

        matrix = np.asarray(args[0], dtype=np.float64).reshape(4, 4)
        if abs(np.linalg.det(matrix)) < 1e-12 * max(1.0, float(np.abs(matrix).max()) ** 4):
            return "the matrix is singular (determinant 0): it flattens space", False
    if name in ("glViewport", "glScissor") and (args[2] == 0 or args[3] == 0):
        return (
            f"width {args[2]} x height {args[3]}: a box 0 pixels "
            f"{'wide' if args[2] == 0 else 'high'} holds no pixel, so nothing is drawn",
            False,
        )
    if name in ("glLineWidth", "glPointSize") and args[0] <= 0:
        return f"{names[0]} = {args[0]:g}: a {name[2:-5].lower()} must be wider than 0", True
    return "", False
