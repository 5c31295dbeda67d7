"""The pipe between a sandboxed lab run and the trusted checker.

A message is a 4-byte big-endian length, a JSON header of that many bytes, then the bytes
of each array the header declares in ``"arrays"``: ``[dtype, shape, nbytes]`` (dtype one
of :data:`DTYPES`, numpy's codes). Arguments refer to array ``i`` as ``{"$a": i}``. JSON
and raw bytes only: nothing on this pipe is ever unpickled or evaluated.

This side (the sandbox's) trusts what it reads; the checker reads with every size capped
before it is read (``mirrorlab.labs.trusted.pipe``).
"""

from __future__ import annotations

import json
import os
import struct
from collections.abc import Sequence

LENGTH = struct.Struct(">I")
DTYPES = {"u1": 1, "i1": 1, "u2": 2, "i2": 2, "u4": 4, "i4": 4, "f4": 4, "f8": 8}
"""Array element types the pipe carries, and their sizes in bytes."""


class PipeClosed(EOFError):
    """The other end closed the pipe."""


def encode(header: dict, arrays: Sequence[tuple[str, list[int], bytes]] = ()) -> bytes:
    """One message: ``header`` (JSON-able) and ``arrays`` as (dtype, shape, bytes)."""
    if arrays:
        header = {**header, "arrays": [[d, list(s), len(b)] for d, s, b in arrays]}
    head = json.dumps(header, separators=(",", ":"), allow_nan=False).encode()
    return b"".join([LENGTH.pack(len(head)), head, *(b for _, _, b in arrays)])


class Channel:
    """Blocking messages over two file descriptors (the sandbox's side)."""

    def __init__(self, read_fd: int, write_fd: int) -> None:
        self.read_fd, self.write_fd = read_fd, write_fd
        self._buffer = bytearray()

    def send(self, header: dict, arrays: Sequence[tuple[str, list[int], bytes]] = ()) -> None:
        data = memoryview(encode(header, arrays))
        while data:
            written = os.write(self.write_fd, data)
            data = data[written:]

    def _read(self, count: int) -> bytes:
        buffer = self._buffer
        while len(buffer) < count:
            chunk = os.read(self.read_fd, max(count - len(buffer), 1 << 16))
            if not chunk:
                raise PipeClosed("the checker closed the pipe")
            buffer += chunk
        data = bytes(buffer[:count])
        del buffer[:count]
        return data

    def receive(self) -> tuple[dict, list[tuple[str, list[int], bytes]]]:
        (length,) = LENGTH.unpack(self._read(LENGTH.size))
        header = json.loads(self._read(length))
        arrays = [(d, s, self._read(n)) for d, s, n in header.pop("arrays", [])]
        return header, arrays
