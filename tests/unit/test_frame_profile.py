"""bench/frame_profile.py's bookkeeping, which needs no perf to check: which library a
sample counts for, and whose an "either" sample (the C library's or the kernel's on the
main thread) is, read from the call chains of ``perf script -F comm,ip,dso``."""

from __future__ import annotations

import importlib.util
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def frame_profile():
    spec = importlib.util.spec_from_file_location(
        "frame_profile", REPO / "bench" / "frame_profile.py"
    )
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def sample(thread: str, *libraries: str) -> str:
    """One sample as perf script prints it: its thread, then a line a frame, leaf first."""
    return "\n".join(
        [
            f"{thread} 4242 ",
            *(f"\t    7f00{i:04x} ({library})" for i, library in enumerate(libraries)),
        ]
    )


def test_each_library_counts_for_its_owner():
    classify = frame_profile().classify
    assert classify("llvmpipe-0", "libc.so.6") == "driver"  # a rasteriser thread's
    assert classify("python", "swrast_dri.so") == "driver"
    assert classify("python", "perf-311.map") == "driver"  # llvmpipe's compiled shaders
    assert classify("python", "[JIT] tid 311") == "driver"
    assert classify("python", "libpython3.11.so.1.0") == "python"
    assert classify("python", "_multiarray_umath.cpython-311-x86_64-linux-gnu.so") == "python"
    assert classify("python", "libc.so.6") == "either"
    assert classify("python", "[kernel.kallsyms]") == "either"


def test_an_either_sample_goes_to_its_nearest_caller_of_python_or_the_driver():
    script = (
        "\n\n".join(
            [
                # memcpy called by Mesa's readback, through another libc frame: the driver's
                sample(
                    "python",
                    "/usr/lib/x86_64-linux-gnu/libc.so.6",
                    "/usr/lib/x86_64-linux-gnu/libc.so.6",
                    "/usr/lib/x86_64-linux-gnu/dri/swrast_dri.so",
                    "/root/.pyenv/versions/3.11.7/lib/libpython3.11.so.1.0",
                ),
                # the kernel's wait in a futex Mesa called: the driver's
                sample(
                    "python",
                    "[kernel.kallsyms]",
                    "/usr/lib/x86_64-linux-gnu/libc.so.6",
                    "/usr/lib/x86_64-linux-gnu/dri/swrast_dri.so",
                ),
                # malloc called by numpy: Python's
                sample(
                    "python",
                    "/usr/lib/x86_64-linux-gnu/libc.so.6",
                    "/venv/lib/python3.11/site-packages/numpy/_core/"
                    "_multiarray_umath.cpython-311-x86_64-linux-gnu.so",
                    "/usr/lib/x86_64-linux-gnu/dri/swrast_dri.so",
                ),
                # a stack that unwinds no further: no one's
                sample("python", "/usr/lib/x86_64-linux-gnu/libc.so.6", "[unknown]"),
                # not "either" samples, so not counted: Python's own, a rasteriser thread's
                sample("python", "/root/.pyenv/versions/3.11.7/lib/libpython3.11.so.1.0"),
                sample(
                    "llvmpipe-1",
                    "/usr/lib/x86_64-linux-gnu/libc.so.6",
                    "/usr/lib/x86_64-linux-gnu/dri/swrast_dri.so",
                ),
            ]
        )
        + "\n\n"
    )
    assert frame_profile().either_callers(script) == {"driver": 2, "python": 1, "either": 1}
