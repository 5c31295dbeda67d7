"""The checker's end of the pipe reads the sandbox's messages as untrusted data: JSON and raw
bytes only, the header's length and every array's type, shape and size checked before a
byte of them is read (a message that promises 1 GiB is refused while it is a promise),
the run's total budget kept, every read under a deadline; what the student side sends is
read back exactly."""

from __future__ import annotations

import json
import os
import struct
import threading
import time

import numpy as np
import pytest

from mirrorlab.labs.student.wire import Channel, encode
from mirrorlab.labs.trusted.pipe import (
    MAX_HEADER,
    PipeBudget,
    PipeClosed,
    PipeError,
    PipeTimeout,
    TrustedChannel,
)


@pytest.fixture
def pipe():
    """(the sandbox's write end, the checker's channel reading it)."""
    read_fd, write_fd = os.pipe()
    back_read, back_write = os.pipe()
    channel = TrustedChannel(
        read_fd, back_write, PipeBudget(message_bytes=1 << 20, total_bytes=3 << 20)
    )
    yield write_fd, channel
    for fd in (write_fd, back_read):
        try:
            os.close(fd)
        except OSError:
            pass
    channel.close()


def raw(header: dict) -> bytes:
    head = json.dumps(header).encode()
    return struct.pack(">I", len(head)) + head


def soon() -> float:
    return time.monotonic() + 5


def test_a_message_and_its_arrays_come_through(pipe):
    write_fd, channel = pipe
    data = np.arange(12, dtype=np.float32).reshape(3, 4)
    os.write(
        write_fd,
        encode(
            {"op": "gl", "fn": "glLoadMatrixf", "args": [{"$a": 0}]},
            [("f4", [3, 4], data.tobytes())],
        ),
    )
    header, arrays = channel.receive(soon())
    assert header["fn"] == "glLoadMatrixf" and np.array_equal(arrays[0], data)
    assert channel.budget.received == data.nbytes


def test_a_1_gib_array_is_refused_on_its_promise(pipe):
    write_fd, channel = pipe
    size = 1 << 30
    os.write(
        write_fd,
        raw({"op": "gl", "fn": "glTexImage2D", "line": 12, "arrays": [["u1", [size], size]]}),
    )
    started = time.perf_counter()
    with pytest.raises(PipeError, match=r"an upload of 1024 MiB \(glTexImage2D at line 12\)"):
        channel.receive(soon())
    assert time.perf_counter() - started < 1  # refused at once, no byte of it read
    assert channel.budget.received == 0


@pytest.mark.parametrize(
    "header, words",
    [
        ({"op": "gl", "arrays": [["O", [1], 8]]}, "malformed array"),
        ({"op": "gl", "arrays": [["f4", [2, 2], 12]]}, "does not match its shape"),
        ({"op": "gl", "arrays": [["u1", [-1], 0]]}, "malformed array"),
        ({"op": "gl", "arrays": [["u1", [1], 1]] * 5}, "malformed list"),
        ({"op": "gl", "arrays": "all of them"}, "malformed list"),
        ({"fn": "glFlush"}, "without an operation"),
        ([1, 2, 3], "without an operation"),
    ],
)
def test_malformed_messages_are_refused(pipe, header, words):
    write_fd, channel = pipe
    os.write(write_fd, raw(header))
    with pytest.raises(PipeError, match=words):
        channel.receive(soon())


def test_not_json_a_long_header_and_deep_nesting_are_refused(pipe):
    write_fd, channel = pipe
    os.write(write_fd, struct.pack(">I", 9) + b"not json!")
    with pytest.raises(PipeError, match="not valid JSON"):
        channel.receive(soon())
    os.write(write_fd, struct.pack(">I", MAX_HEADER + 1))
    with pytest.raises(PipeError, match="64 KiB"):
        channel.receive(soon())


def test_deep_nesting_and_nan_are_refused(pipe):
    write_fd, channel = pipe
    deep = b"[" * 30000 + b"]" * 30000
    os.write(write_fd, struct.pack(">I", len(deep)))
    writer = threading.Thread(target=os.write, args=(write_fd, deep))
    writer.start()
    with pytest.raises(PipeError, match="not valid JSON"):
        channel.receive(soon())
    writer.join()
    text = b'{"op": "gl", "args": [NaN]}'
    os.write(write_fd, struct.pack(">I", len(text)) + text)
    with pytest.raises(PipeError, match="not valid JSON"):
        channel.receive(soon())


def test_the_runs_budget_is_kept(pipe):
    write_fd, channel = pipe
    chunk = bytes(1 << 20)
    for _ in range(3):
        writer = threading.Thread(
            target=os.write,
            args=(
                write_fd,
                encode({"op": "gl", "fn": "glTexSubImage2D"}, [("u1", [len(chunk)], chunk)]),
            ),
        )
        writer.start()
        channel.receive(soon())
        writer.join()
    os.write(write_fd, raw({"op": "gl", "fn": "glTexSubImage2D", "arrays": [["u1", [16], 16]]}))
    with pytest.raises(PipeError, match="more than 3 MiB of uploads in one run"):
        channel.receive(soon())


def test_reads_have_a_deadline_and_a_closed_pipe_says_so(pipe):
    write_fd, channel = pipe
    os.write(write_fd, struct.pack(">I", 20) + b'{"op":')  # a header that never ends
    with pytest.raises(PipeTimeout):
        channel.receive(time.monotonic() + 0.2)
    os.close(write_fd)
    with pytest.raises(PipeClosed):
        channel.receive(soon())


def test_the_student_side_reads_replies_back():
    to_student = os.pipe()
    from_student = os.pipe()
    student = Channel(to_student[0], from_student[1])
    checker = TrustedChannel(from_student[0], to_student[1], PipeBudget())
    try:
        checker.send(
            {"ok": True, "value": {"$a": 0, "as": "array"}},
            [("i4", [2, 2], np.arange(4, dtype=np.int32).tobytes())],
        )
        header, arrays = student.receive()
        assert header["ok"] and arrays[0][0] == "i4" and arrays[0][1] == [2, 2]
        student.send({"op": "enter", "function": "display"})
        assert checker.receive(soon())[0] == {"op": "enter", "function": "display"}
    finally:
        for fd in (*to_student, *from_student):
            os.close(fd)
