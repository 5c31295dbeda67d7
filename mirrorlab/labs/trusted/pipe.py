"""Reading the sandbox's side of the pipe as untrusted input.

A message (:mod:`mirrorlab.labs.student.wire`) is parsed only as JSON and raw bytes; the
header's length, each array's declared type, shape and size, and the bytes left in the
run's budget are all checked before the payload is read (small reads read ahead at most
64 KiB), so a message that asks for 1 GiB is refused while it is still a promise. Every
read has a deadline.
"""

from __future__ import annotations

import json
import math
import os
import select
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mirrorlab.labs.student.wire import DTYPES, LENGTH, encode

MAX_HEADER = 64 << 10
"""The largest JSON header the sandbox may send (a call's name and scalar arguments)."""


def wait_readable(fd: int, timeout: float) -> bool:
    """Whether the pipe ``fd`` (its reading end) has bytes, or has been closed at the other
    end, within ``timeout`` seconds: ``select`` on POSIX; on Windows, where ``select``
    takes only sockets, the pipe is peeked at until then."""
    if sys.platform != "win32":
        ready, _, _ = select.select([fd], [], [], max(timeout, 0.0))
        return bool(ready)
    import _winapi
    import msvcrt

    handle = msvcrt.get_osfhandle(fd)
    end = time.monotonic() + timeout
    while True:
        try:
            available = _winapi.PeekNamedPipe(handle)[0]  # bytes waiting
        except OSError:  # the other end is gone: a read says so at once
            return True
        if available:
            return True
        left = end - time.monotonic()
        if left <= 0:
            return False
        time.sleep(min(left, 0.001))


class PipeClosed(EOFError):
    """The sandbox closed its end (it exited or was stopped)."""


class PipeTimeout(TimeoutError):
    """Nothing came within the deadline."""


class PipeError(ValueError):
    """The sandbox broke the pipe's rules; the message is one line for the student."""


@dataclass
class PipeBudget:
    """What one run may send: bytes of arrays in one message and in all."""

    message_bytes: int = 16 << 20
    total_bytes: int = 256 << 20
    received: int = 0


def _mib(count: int) -> str:
    return f"{count / (1 << 20):.0f} MiB" if count >= 1 << 20 else f"{count} bytes"


class TrustedChannel:
    """The checker's end: ``read_fd`` from the sandbox, ``write_fd`` to it."""

    def __init__(self, read_fd: int, write_fd: int, budget: PipeBudget) -> None:
        self.read_fd, self.write_fd, self.budget = read_fd, write_fd, budget
        self._buffer = bytearray()
        """Bytes read ahead of the message being parsed (at most 64 KiB)."""

    def close(self) -> None:
        for fd in (self.read_fd, self.write_fd):
            try:
                os.close(fd)
            except OSError:
                pass

    def send(self, header: dict, arrays: Sequence[tuple[str, list[int], bytes]] = ()) -> None:
        data = memoryview(encode(header, arrays))
        try:
            while data:
                written = os.write(self.write_fd, data)
                data = data[written:]
        except (BrokenPipeError, OSError) as exc:
            raise PipeClosed("the sandbox closed the pipe") from exc

    def _read_into(self, buffer: bytearray | memoryview, deadline: float) -> None:
        view = memoryview(buffer)
        if self._buffer:
            taken = min(len(view), len(self._buffer))
            view[:taken] = self._buffer[:taken]
            del self._buffer[:taken]
            view = view[taken:]
        if len(view) <= 1 << 16:
            # a small read (a length, a header, a small array): what comes after it is read
            # ahead, in one call, and kept for the next
            while view:
                self._fill(deadline)
                taken = min(len(view), len(self._buffer))
                view[:taken] = self._buffer[:taken]
                del self._buffer[:taken]
                view = view[taken:]
            return
        while view:
            left = deadline - time.monotonic()
            if left <= 0:
                raise PipeTimeout("the sandbox sent nothing in time")
            if not wait_readable(self.read_fd, left):
                continue
            chunk = os.read(self.read_fd, min(len(view), 1 << 20))
            if not chunk:
                raise PipeClosed("the sandbox closed the pipe")
            view[: len(chunk)] = chunk
            view = view[len(chunk) :]

    def _fill(self, deadline: float) -> None:
        """Read what the sandbox has sent (at most 64 KiB) into the read-ahead buffer."""
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                raise PipeTimeout("the sandbox sent nothing in time")
            if wait_readable(self.read_fd, left):
                break
        chunk = os.read(self.read_fd, 1 << 16)
        if not chunk:
            raise PipeClosed("the sandbox closed the pipe")
        self._buffer += chunk

    def receive(self, deadline: float) -> tuple[dict, list[np.ndarray]]:
        """The next message: its header (a dict with a string ``op``) and its arrays, read
        as data; PipeError when it breaks a rule, PipeClosed, PipeTimeout."""
        length_bytes = bytearray(LENGTH.size)
        self._read_into(length_bytes, deadline)
        (length,) = LENGTH.unpack(length_bytes)
        if length > MAX_HEADER:
            raise PipeError(
                f"a message of {_mib(length)} without its arrays; the labs accept "
                f"{MAX_HEADER >> 10} KiB"
            )
        head = bytearray(length)
        self._read_into(head, deadline)
        try:
            header = json.loads(head.decode("utf-8"), parse_constant=_no_constant)
        except (UnicodeDecodeError, ValueError, RecursionError):
            raise PipeError("a message that is not valid JSON") from None
        if not isinstance(header, dict) or not isinstance(header.get("op"), str):
            raise PipeError("a message without an operation")
        declared = header.pop("arrays", [])
        arrays = []
        for dtype, shape, nbytes in self._check_arrays(declared, header):
            buffer = bytearray(nbytes)
            self._read_into(buffer, deadline)
            self.budget.received += nbytes
            arrays.append(np.frombuffer(buffer, dtype=np.dtype(dtype)).reshape(shape))
        return header, arrays

    def _check_arrays(self, declared: object, header: dict) -> list[tuple[str, tuple, int]]:
        where = _where(header)
        if not isinstance(declared, list) or len(declared) > 4:
            raise PipeError(f"a message with a malformed list of arrays{where}")
        checked, total = [], 0
        for entry in declared:
            if not (
                isinstance(entry, list)
                and len(entry) == 3
                and isinstance(entry[0], str)
                and entry[0] in DTYPES
                and isinstance(entry[1], list)
                and len(entry[1]) <= 4
                and all(type(d) is int and 0 <= d < 1 << 31 for d in entry[1])
                and type(entry[2]) is int
            ):
                raise PipeError(f"a malformed array{where}")
            dtype, shape, nbytes = entry
            if nbytes != math.prod(shape) * DTYPES[dtype]:
                raise PipeError(f"an array whose size does not match its shape{where}")
            total += nbytes
            checked.append((dtype, tuple(shape), nbytes))
        if total > self.budget.message_bytes:
            raise PipeError(
                f"an upload of {_mib(total)}{where}; the labs accept "
                f"{_mib(self.budget.message_bytes)} at once"
            )
        if self.budget.received + total > self.budget.total_bytes:
            raise PipeError(
                f"more than {_mib(self.budget.total_bytes)} of uploads in one run{where}"
            )
        return checked


def _no_constant(name: str) -> None:
    raise ValueError(f"{name} is not allowed")


def _where(header: dict) -> str:
    name, line = header.get("fn"), header.get("line")
    if not isinstance(name, str) or not name.isidentifier() or len(name) > 40:
        return ""
    return f" ({name}" + (f" at line {line}" if type(line) is int and line > 0 else "") + ")"
