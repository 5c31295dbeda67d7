"""Where a frame's time goes: Python's share of its CPU time, and each pass's time.

Run from the repository root as root or with perf allowed (``./dev bench profile`` does the
set-up, with Debian's ``linux-perf``)::

    python bench/frame_profile.py [--size 512] [--seconds 6] [--chain-seconds 3]
                                  [--frames 100] [--json PATH]

Three frames of the lab scene are measured: ``two passes`` (the robot's elbow turns
between two poses every frame, so the planner plans again and the capture runs),
``two passes, a new pose every frame`` (the elbow turns a hundredth of a degree further
every frame: nothing worked out for an earlier frame is used again, as in an animation)
and ``capture reused`` (the scene stands still: the camera pass only, a still frame
replayed); each ends with the readback to numpy.

**Python's share.** Each variant draws frames in a process of its own; after a warm-up,
``perf record`` samples every thread of it ~1000 times a second of CPU time for
``--seconds``: only while a thread runs on a CPU, so the samples are CPU time, spread over
the main thread and llvmpipe's rasteriser threads as it was spent. Each sample is counted
by the library it fell in:

- the GL driver: any sample on a rasteriser thread; on the main thread Mesa's libraries
  (``swrast_dri``/``libgallium``, ``libGL*``, ``libEGL``, ``libglapi``, ``libLLVM``) and
  llvmpipe's compiled shaders (``[JIT]``);
- Python: the interpreter (``libpython``) and the extension modules Python code calls for
  itself (numpy, ctypes and libffi, PyOpenGL-accelerate, ...);
- either: the C library and the kernel on the main thread (a ``memcpy`` may be numpy's or
  Mesa's).

Python's share is Python's samples over all samples, given with "either" counted out and
in (a lower and an upper bound). Then ``perf record --call-graph dwarf`` samples the same
process for ``--chain-seconds`` more, at half the rate, and each "either" sample of that
run goes to the nearest caller on its stack that is Python's or the driver's (a
``memcpy`` called by Mesa's readback is the driver's; the kernel's wait inside a
``glReadPixels`` is too). The share of the "either" samples that went to Python (or to
no one: counted as Python) gives the first run's "either" samples their owner: the
attributed share, between the bounds. The split comes from its own run because taking
the stacks costs every sample more, and would weigh on what is measured.

**Per-pass times.** In this process, without perf: every pass of the frame, and the
readback, end with ``glFinish``, so each one's wall time includes its rasterisation.
A frame planned as the last one was makes the recorded calls of the frame before it as
one pass, ``frame (replayed)`` (its capture and camera pass together). The medians of
``--frames`` frames are printed. (The finishes cost a little: the sum is a little more
than an unmeasured frame.)
"""

from __future__ import annotations

import argparse
import contextlib
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections import Counter, defaultdict
from pathlib import Path
from typing import Any
from unittest import mock

VARIANTS = ("two passes", "two passes, a new pose every frame", "capture reused")
DRIVER = re.compile(
    r"swrast_dri|libgallium|libGL|libEGL|libOpenGL|libglapi|libLLVM|\[JIT\]"
    r"|^perf-\d+\.map$"
)  # llvmpipe's compiled shaders, as perf script names them
PYTHON = re.compile(r"libpython|^python|\.cpython-|libffi|openblas|_umath")
RATE = 999
CHAIN_RATE = 499


def log(message: str) -> None:
    print(f"[profile] {message}", file=sys.stderr, flush=True)


def scenes(variant: str) -> list:
    """The scenes a variant's frames take in turn."""
    import mirrorlab

    lab = mirrorlab.load_scene("lab20")
    if variant == "capture reused":
        return [lab]
    assert lab.robot is not None
    base, shoulder, elbow = lab.robot.angles
    if variant == "two passes, a new pose every frame":
        # a hundredth of a degree a frame: nothing drawn before is drawn again
        return [lab.with_angles((base, shoulder, elbow + 0.01 * step)) for step in range(20000)]
    return [lab.with_angles((base, shoulder, elbow + step)) for step in (0.0, 0.5)]


def child(variant: str, size: int) -> None:
    """Frames of ``variant`` after a warm-up (announced with a line ``ready`` on stdout,
    when the sampler may start), until a line comes on stdin: the sampler says when it is
    done, so a sampler slowed by a busy machine never finds the process gone."""
    import mirrorlab

    frames = scenes(variant)
    stop = threading.Event()
    with mirrorlab.Renderer((size, size)) as renderer:
        for index in range(20):
            renderer.render(frames[index % len(frames)])

        def wait_for_stop() -> None:
            sys.stdin.readline()
            stop.set()

        threading.Thread(target=wait_for_stop, daemon=True).start()
        print("ready", flush=True)
        count = 0
        while not stop.is_set():
            renderer.render(frames[count % len(frames)])
            count += 1
    print(json.dumps({"frames": count}), flush=True)


def perf() -> str:
    found = shutil.which("perf")
    if found is None:
        raise SystemExit(
            "frame_profile.py: perf is not installed (Debian: apt-get install "
            "linux-perf; or ./dev bench profile)"
        )
    return found


def classify(thread: str, library: str) -> str:
    """``driver``, ``python`` or ``either`` for a sample of ``thread`` in ``library``."""
    if thread.startswith("llvmpipe") or DRIVER.search(library):
        return "driver"
    return "python" if PYTHON.search(library) else "either"


def record(pid: int, data: Path, seconds: float, options: list[str]) -> None:
    """``perf record`` of every thread of ``pid`` for ``seconds`` into ``data``."""
    sampled = subprocess.run(
        [perf(), "record", *options, "-p", str(pid), "-o", str(data), "--", "sleep", str(seconds)],
        capture_output=True,
        text=True,
    )
    if sampled.returncode != 0 or not data.exists():
        raise SystemExit(f"frame_profile.py: perf record failed: {sampled.stderr.strip()[-500:]}")


def either_callers(script: str) -> Counter:
    """The "either" samples of ``perf script -F comm,ip,dso`` output with call chains
    (blank-line separated; a sample's first line names its thread, then one ``ip (dso)``
    line a frame, the sampled one first), each counted for the nearest caller whose
    library is ``python``'s or the ``driver``'s; ``either`` when no frame is."""
    callers: Counter = Counter()
    for block in script.split("\n\n"):
        lines = block.strip().splitlines()
        if not lines:
            continue
        thread = lines[0].split()[0]
        libraries = [
            Path(line[line.rfind("(") + 1 : -1]).name
            for line in lines[1:]
            if line.rstrip().endswith(")")
        ]
        if not libraries or classify(thread, libraries[0]) != "either":
            continue
        owners = (classify(thread, library) for library in libraries[1:])
        callers[next((kind for kind in owners if kind != "either"), "either")] += 1
    return callers


def python_share(variant: str, size: int, seconds: float, chain_seconds: float) -> dict:
    """Sample ``variant``'s process with perf and split its CPU time."""
    with tempfile.TemporaryDirectory() as folder:
        data, chains = Path(folder) / "perf.data", Path(folder) / "chains.data"
        process = subprocess.Popen(
            [
                sys.executable,
                __file__,
                "--child",
                variant,
                "--size",
                str(size),
            ],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        assert process.stdin is not None and process.stdout is not None
        try:
            if process.stdout.readline().strip() != "ready":
                raise SystemExit(f"frame_profile.py: the {variant} process did not start")
            record(process.pid, data, seconds, ["-F", str(RATE)])
            if chain_seconds > 0:
                record(
                    process.pid,
                    chains,
                    chain_seconds,
                    ["-F", str(CHAIN_RATE), "--call-graph", "dwarf,8192"],
                )
        finally:
            process.stdin.write("stop\n")
            process.stdin.close()
            frames_line = process.stdout.readline()
            process.wait()
        frames = json.loads(frames_line)["frames"]
        callers: Counter = Counter()
        if chain_seconds > 0:
            callers = either_callers(
                subprocess.run(
                    [perf(), "script", "--no-inline", "-i", str(chains), "-F", "comm,ip,dso"],
                    capture_output=True,
                    text=True,
                    check=True,
                ).stdout
            )
        table = subprocess.run(
            [
                perf(),
                "report",
                "-i",
                str(data),
                "--stdio",
                "--sort",
                "comm,dso",
                "-F",
                "sample,comm,dso",
                "--percent-limit",
                "0",
            ],
            capture_output=True,
            text=True,
            check=True,
        ).stdout
    samples: Counter = Counter()
    libraries: Counter = Counter()
    for line in table.splitlines():
        fields = line.split(None, 2)
        if line.startswith("#") or len(fields) < 3 or not fields[0].isdigit():
            continue
        count, thread, library = int(fields[0]), fields[1], fields[2].strip()
        kind = classify(thread, library)
        samples[kind] += count
        if not thread.startswith("llvmpipe"):
            libraries[f"{library} ({kind})"] += count
    total = sum(samples.values())
    split = sum(callers.values())
    either_to_python = (callers["python"] + callers["either"]) / split if split else 1.0
    return {
        "variant": variant,
        "size": size,
        "frames_while_sampled": frames,
        "samples": dict(samples),
        "python_share_low": round(samples["python"] / total, 4),
        "python_share_high": round((samples["python"] + samples["either"]) / total, 4),
        "either_callers": dict(callers),
        "python_share_attributed": round(
            (samples["python"] + samples["either"] * either_to_python) / total, 4
        ),
        "driver_share": round(samples["driver"] / total, 4),
        "main_thread_libraries": libraries.most_common(8),
    }


def pass_times(variant: str, size: int, frames: int) -> dict[str, float]:
    """Median wall ms of each pass (and the readback), each ended by glFinish."""
    import mirrorlab
    import mirrorlab.api
    import mirrorlab.renderer
    from mirrorlab.gl.opengl import GL

    original = mirrorlab.renderer.gl_pass
    current: dict[str, float] = {}

    @contextlib.contextmanager
    def finished_pass(name: str):
        start = time.perf_counter()
        with original(name):
            yield
            GL.glFinish()
        current[name.split(":")[0]] = (time.perf_counter() - start) * 1e3

    timings: defaultdict[str, list[float]] = defaultdict(list)
    scene_list = scenes(variant)
    timed_passes = mock.patch.object(mirrorlab.renderer, "gl_pass", finished_pass)
    timed_passes.start()
    try:
        with mirrorlab.Renderer((size, size)) as renderer:
            for index in range(frames + 10):
                current.clear()
                start = time.perf_counter()
                posed = scene_list[index % len(scene_list)]
                assert renderer._context is not None
                renderer._context.make_current()
                target = renderer._target_of((size, size))
                stats = renderer.scene_renderer.render(posed, target)
                drawn = time.perf_counter()
                target.read()
                read = time.perf_counter()
                if index < 10:
                    continue
                for name, ms in current.items():
                    timings[name].append(ms)
                timings["readback"].append((read - drawn) * 1e3)
                timings["whole frame"].append((read - start) * 1e3)
                timings["planning and Python between passes"].append(
                    (drawn - start) * 1e3 - sum(current.values())
                )
    finally:
        timed_passes.stop()
    assert stats.ran == (
        ["capture:mirror", "camera"] if variant.startswith("two passes") else ["camera"]
    ), stats.ran
    return {name: round(statistics.median(values), 3) for name, values in timings.items()}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--seconds", type=float, default=6.0)
    parser.add_argument(
        "--chain-seconds",
        type=float,
        default=3.0,
        help="seconds sampled with call chains, to split the C library's "
        "and the kernel's samples by caller (0: not done)",
    )
    parser.add_argument("--frames", type=int, default=100)
    parser.add_argument("--json", metavar="PATH")
    parser.add_argument("--child", choices=VARIANTS, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child:
        child(args.child, args.size)
        return 0
    if (
        not 16 <= args.size <= 4096
        or args.seconds <= 0
        or args.chain_seconds < 0
        or args.frames < 1
    ):
        parser.error(
            "--size 16 to 4096, --seconds above 0, --chain-seconds 0 or more, --frames at least 1"
        )
    report: dict[str, Any] = {"shares": [], "passes": {}}
    for variant in VARIANTS:
        log(f"{variant}: {args.seconds:g} s under perf, {args.chain_seconds:g} s with call chains")
        share = python_share(variant, args.size, args.seconds, args.chain_seconds)
        report["shares"].append(share)
        print(
            f"{variant}, {args.size}x{args.size}: Python's share {share['python_share_low']:.1%}"
            f" to {share['python_share_high']:.1%} of the CPU time (the GL driver "
            f"{share['driver_share']:.1%}; {sum(share['samples'].values())} samples)"
        )
        if args.chain_seconds > 0:
            callers = share["either_callers"]
            print(
                f"  the C library's and the kernel's samples by caller: "
                f"{callers.get('python', 0)} Python's, {callers.get('driver', 0)} the "
                f"driver's, {callers.get('either', 0)} no one's; so Python's share is "
                f"{share['python_share_attributed']:.1%}"
            )
        print(
            "  main thread: "
            + ", ".join(f"{name} {count}" for name, count in share["main_thread_libraries"])
        )
    for variant in VARIANTS:
        times = pass_times(variant, args.size, args.frames)
        report["passes"][variant] = times
        print(
            f"{variant}, per pass (median ms, each ended by glFinish): "
            + ", ".join(f"{name} {ms:.2f}" for name, ms in times.items())
        )
    if args.json:
        from mirrorlab.files import Outputs

        with Outputs() as outputs:
            outputs.add(Path(args.json), (json.dumps(report, indent=2) + "\n").encode())
    return 0


if __name__ == "__main__":
    os.environ.setdefault("PYTHONUNBUFFERED", "1")
    sys.exit(main())
