"""Calls from the student's file to the trusted checker: pack the arguments, send them,
wait for the reply, and return its value or raise its error where the student called."""

from __future__ import annotations

import array
import os
import sys
from typing import Any

from .wire import DTYPES, Channel


def loaded_numpy() -> Any:
    """numpy if the student's file has imported it, else None: a value can be a numpy
    array only then, and the runner starts sooner without importing it itself."""
    return sys.modules.get("numpy")


def offered_numpy() -> Any:
    """numpy where the sandbox offers it (imported on the first reply that carries an
    array, as PyOpenGL returns one), else None; nothing here needs it."""
    try:
        import numpy
    except ImportError:  # pragma: no cover - depends on the sandbox
        return None
    return numpy


class GLError(Exception):
    """An OpenGL error, as PyOpenGL's ``OpenGL.error.GLError`` reports it."""

    def __init__(
        self, err: int = 0, description: str = "", baseOperation: str = "", cArguments: tuple = ()
    ) -> None:
        self.err, self.description = err, description
        self.baseOperation, self.cArguments = baseOperation, cArguments
        super().__init__(
            f"GLError(err = {err}, description = {description!r}, "
            f"baseOperation = {baseOperation}, cArguments = {cArguments})"
        )


class LabSetupError(RuntimeError):
    """The lab could not do what was asked (no session, a bad argument); one line."""


class StudentShaderError(LabSetupError):
    """The student's GLSL did not compile: ``variable`` names the Python string, ``line``
    the line inside it (1-based, or 0 when unknown)."""

    def __init__(self, message: str, variable: str = "", line: int = 0) -> None:
        self.variable, self.line = variable, line
        super().__init__(message)


ERRORS: dict[str, type[BaseException]] = {
    "GLError": GLError,
    "TypeError": TypeError,
    "ValueError": ValueError,
    "LabSetupError": LabSetupError,
    "StudentShaderError": StudentShaderError,
    "NotImplementedError": NotImplementedError,
    "IndexError": IndexError,
}


def flatten(value: Any, what: str) -> list:
    """The numbers in ``value`` (a number, a sequence of any depth, a numpy array, a ctypes
    array or another buffer), in order."""
    numpy = loaded_numpy()
    if numpy is not None and isinstance(value, numpy.ndarray):
        return value.ravel().tolist()
    scalar = _scalar(value)
    if scalar is not None:
        return [scalar]
    if isinstance(value, bytes | bytearray | memoryview | str):
        raise TypeError(f"{what}: expected numbers, got {type(value).__name__}")
    try:
        items = list(value)
    except TypeError:
        raise TypeError(
            f"{what}: expected a number or a sequence of numbers, got {type(value).__name__}"
        ) from None
    out: list = []
    for item in items:
        scalar = _scalar(item)
        if scalar is not None:
            out.append(scalar)
        else:
            out.extend(flatten(item, what))
        if len(out) > 1 << 20:
            raise ValueError(f"{what}: too many numbers")
    return out


def _scalar(value: Any) -> int | float | None:
    """``value`` as a Python number when it is one (numpy and ctypes scalars too)."""
    if isinstance(value, bool | int | float):
        return value
    if hasattr(value, "__len__") or hasattr(value, "__iter__"):
        return None
    for convert in (int, float):
        method = "__index__" if convert is int else "__float__"
        if hasattr(value, method):
            try:
                return convert(value)
            except (TypeError, ValueError, OverflowError):
                return None
    inner = getattr(value, "value", None)  # ctypes c_float and friends
    return inner if isinstance(inner, int | float) else None


def finite(value: Any) -> Any:
    """``value`` with each number JSON cannot carry (nan, inf, -inf) as ``{"$f": "nan"}``, for
    the checker to name in its reply."""
    if isinstance(value, float) and value != value:
        return {"$f": "nan"}
    if isinstance(value, float) and value in (float("inf"), float("-inf")):
        return {"$f": "inf" if value > 0 else "-inf"}
    if isinstance(value, list):
        return [finite(v) for v in value]
    if isinstance(value, dict):
        return {k: finite(v) for k, v in value.items()}
    return value


def checked_number(value: Any, kind: str, what: str) -> int | float:
    try:
        if kind == "f":
            return float(value)
        if kind == "b":
            return int(bool(value))
        return (
            int(value.__index__() if hasattr(value, "__index__") else value)
            if not isinstance(value, float)
            else _integral(value, what)
        )
    except OverflowError:
        raise ValueError(f"{what}: {_short(value)} is out of range for a GL number") from None
    except (TypeError, ValueError):
        expected = "a number" if kind == "f" else "an integer"
        raise TypeError(
            f"{what}: expected {expected}, got {type(value).__name__} {_short(value)}"
        ) from None


def _integral(value: float, what: str) -> int:
    if not value.is_integer():
        raise TypeError(f"{what}: expected an integer, got {value!r}")
    return int(value)


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."


def _pixels(value: Any, type_code: str, what: str) -> tuple[str, list[int], bytes] | None:
    """Pixel data as (dtype, shape, bytes): its raw bytes, as PyOpenGL passes them."""
    if value is None:
        return None
    numpy = loaded_numpy()
    if numpy is not None and isinstance(value, numpy.ndarray):
        array_ = numpy.ascontiguousarray(value)
        code = array_.dtype.str.lstrip("<>|=")
        if code not in DTYPES:
            raise TypeError(f"{what}: a numpy array of {array_.dtype} cannot be uploaded")
        return code, list(array_.shape), array_.tobytes()
    if isinstance(value, bytes | bytearray | memoryview):
        data = bytes(value)
        return "u1", [len(data)], data
    if isinstance(value, list | tuple):
        numbers = flatten(value, what)
        packed = array.array(
            {
                "u1": "B",
                "i1": "b",
                "u2": "H",
                "i2": "h",
                "u4": "I",
                "i4": "i",
                "f4": "f",
                "f8": "d",
            }[type_code],
            numbers,
        )
        return type_code, [len(numbers)], packed.tobytes()
    try:
        data = bytes(memoryview(value).cast("B"))
    except TypeError:
        raise TypeError(
            f"{what}: expected bytes, an array or None, got {type(value).__name__}"
        ) from None
    return "u1", [len(data)], data


class Remote:
    """The checker at the other end of ``channel``; ``path`` is the student's file (its
    line numbers go with each call)."""

    def __init__(self, channel: Channel, path: str, pixel_types: dict[int, str]) -> None:
        self.channel, self.path = channel, path
        self.pixel_types = pixel_types

    def line(self) -> int:
        frame: Any = sys._getframe(2)
        while frame is not None:
            if frame.f_code.co_filename == self.path:
                return frame.f_lineno
            frame = frame.f_back
        return 0

    def notify(self, header: dict) -> None:
        self.channel.send(header)

    def call(self, op: str, name: str, kinds: list[str], args: tuple) -> Any:
        required = sum(not k.endswith("?") for k in kinds)
        if not required <= len(args) <= len(kinds):
            count = required if required == len(kinds) else f"{required} to {len(kinds)}"
            raise TypeError(f"{name}() takes {count} arguments ({len(args)} given)")
        packed: list = []
        arrays: list[tuple[str, list[int], bytes]] = []
        for index, (kind, value) in enumerate(zip(kinds, args, strict=False)):
            kind = kind.rstrip("?")
            what = f"{name}() argument {index + 1}"
            if kind in ("i", "f", "b"):
                packed.append(checked_number(value, kind, what))
            elif kind == "v":
                packed.append([float(v) for v in flatten(value, what)])
            elif kind == "n":
                packed.append([checked_number(v, "i", what) for v in flatten(value, what)])
            elif kind == "s":
                if isinstance(value, bytes):
                    value = value.decode("utf-8", "replace")
                if not isinstance(value, str):
                    raise TypeError(f"{what}: expected a string, got {type(value).__name__}")
                packed.append(value)
            elif kind == "p":
                type_code = self.pixel_types.get(packed[-1] if packed else 0, "u1")
                payload = _pixels(value, type_code, what)
                if payload is None:
                    packed.append(None)
                else:
                    packed.append({"$a": len(arrays)})
                    arrays.append(payload)
            else:  # "j": plain data for the lab's own calls
                packed.append(value)
        self.channel.send(
            {"op": op, "fn": name, "args": finite(packed), "line": self.line()}, arrays
        )
        reply, payloads = self.channel.receive()
        if "stop" in reply:
            os._exit(3)  # the checker has ended this run
        if not reply.get("ok"):
            error = ERRORS.get(reply.get("type", ""), RuntimeError)
            if error is GLError:
                raise GLError(
                    reply.get("err", 0),
                    reply.get("message", ""),
                    name,
                    tuple(a for a in packed if not isinstance(a, dict)),
                )
            if error is StudentShaderError:
                raise StudentShaderError(
                    reply.get("message", ""), reply.get("variable", ""), reply.get("shader_line", 0)
                )
            raise error(reply.get("message", ""))
        return decode(reply.get("value"), payloads)


def decode(value: Any, payloads: list[tuple[str, list[int], bytes]]) -> Any:
    """A reply's value: arrays become numpy arrays (nested lists without numpy), or bytes."""
    if isinstance(value, dict) and "$a" in value:
        dtype, shape, data = payloads[value["$a"]]
        if value.get("as") == "bytes":
            return data
        numpy = offered_numpy()
        if numpy is not None:
            return numpy.frombuffer(data, dtype=dtype).reshape(shape).copy()
        items: list[Any] = array.array(
            {
                "u1": "B",
                "i1": "b",
                "u2": "H",
                "i2": "h",
                "u4": "I",
                "i4": "i",
                "f4": "f",
                "f8": "d",
            }[dtype],
            data,
        ).tolist()
        for size in reversed(shape[1:]):
            items = [items[i : i + size] for i in range(0, len(items), size)]
        return items
    if isinstance(value, list):
        return [decode(v, payloads) for v in value]
    return value
