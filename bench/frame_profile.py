"""Where a frame's time goes: Python's share of its CPU time, and each pass's time.

Run from the repository root (``./dev bench profile`` does the set-up, with py-spy)::

    python bench/frame_profile.py [--size 512] [--seconds 8] [--frames 100]
                                  [--json PATH]

Two frames of the lab scene are measured: ``two passes`` (the robot's elbow turns a
little every frame, so the planner plans again and the capture runs) and ``capture
reused`` (the scene stands still: the camera pass only); each ends with the readback
to numpy.

**Python's share.** Each variant runs for ``--seconds`` in a process of its own under
py-spy (``--native``: C frames too), which samples the main thread's stack 250 times a
second while it is on the CPU. A sample whose stack reaches into Mesa (the GL driver:
``swrast_dri``/``libgallium``, ``libGL*``, ``libEGL*``, ``libglapi``, ``libLLVM``) is the
driver's; any other is Python's side: the interpreter running mirrorlab, PyOpenGL and
numpy code, and the C code they call for themselves (ctypes, numpy, PyOpenGL-accelerate).
The process also measures its CPU time (``time.process_time``: every thread, llvmpipe's
rasteriser threads too) and its main thread's (``time.thread_time``) over the same frames,
so

    Python's share = (Python samples / main-thread samples) x main-thread CPU / process CPU

is the part of all the CPU time a frame costs that Python spends.

**Per-pass times.** In this process, without py-spy: every pass of the frame, and the
readback, end with ``glFinish``, so each one's wall time includes its rasterisation.
The medians of ``--frames`` frames are printed. (The finishes cost a little: the sum is a
little more than an unmeasured frame.)
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
import time
from collections import Counter, defaultdict
from pathlib import Path

VARIANTS = ("two passes", "capture reused")
DRIVER = re.compile(r"\((?:lib(?:gallium|GLX|EGL|GL|glapi|LLVM|GLdispatch|OpenGL|gbm|drm)"
                    r"[^)]*|[^)]*_dri\.so[^)]*)\)")
RATE = 250


def log(message: str) -> None:
    print(f"[profile] {message}", file=sys.stderr, flush=True)


def scenes(variant: str) -> list:
    """The scenes a variant's frames take in turn."""
    import mirrorlab

    lab = mirrorlab.load_scene("lab20")
    if variant == "capture reused":
        return [lab]
    base, shoulder, elbow = lab.robot.angles
    return [lab.with_angles((base, shoulder, elbow + step)) for step in (0.0, 0.5)]


def child(variant: str, size: int, seconds: float) -> None:
    """Frames of ``variant`` for ``seconds`` after a warm-up; prints the CPU times."""
    import mirrorlab

    frames = scenes(variant)
    with mirrorlab.Renderer((size, size)) as renderer:
        for index in range(20):
            renderer.render(frames[index % len(frames)])
        count = timed_frames(renderer, frames, seconds)
    print(json.dumps(count))


def timed_frames(renderer, frames: list, seconds: float) -> dict:
    """The timed loop (py-spy's samples are counted only inside it, by its name)."""
    end = time.perf_counter() + seconds
    process, thread = time.process_time(), time.thread_time()
    count = 0
    while time.perf_counter() < end:
        renderer.render(frames[count % len(frames)])
        count += 1
    return {"frames": count, "process_cpu_s": time.process_time() - process,
            "main_cpu_s": time.thread_time() - thread}


def py_spy() -> str:
    found = shutil.which("py-spy") or str(Path(sys.executable).with_name("py-spy"))
    if not Path(found).exists():
        raise SystemExit("frame_profile.py: py-spy is not installed; pip install py-spy "
                         "(or: ./dev bench profile)")
    return found


def python_share(variant: str, size: int, seconds: float) -> dict:
    """Run ``variant`` under py-spy and split its main thread's samples."""
    with tempfile.TemporaryDirectory() as folder:
        raw = Path(folder) / "samples.txt"
        done = subprocess.run(
            [py_spy(), "record", "--native", "--rate", str(RATE), "--format", "raw",
             "--output", str(raw), "--", sys.executable, __file__, "--child", variant,
             "--size", str(size), "--seconds", str(seconds)],
            capture_output=True, text=True)
        if done.returncode != 0 or not raw.exists():
            raise SystemExit(f"frame_profile.py: py-spy failed: {done.stderr.strip()[-500:]}")
        # py-spy writes its own lines around the child's
        times = json.loads(next(line for line in reversed(done.stdout.splitlines())
                                if line.startswith("{")))
        samples = Counter()
        python_leaves: Counter = Counter()
        for line in raw.read_text().splitlines():
            stack, _, count = line.rpartition(" ")
            if "timed_frames" not in stack:
                continue
            frames = stack.split(";")
            if any(DRIVER.search(frame) for frame in frames[1:]):
                samples["driver"] += int(count)
            else:
                samples["python"] += int(count)
                named = [f for f in frames if ".py:" in f]
                if named:
                    python_leaves[named[-1].split(" (")[0]] += int(count)
    main = samples["python"] + samples["driver"]
    share = samples["python"] / main * times["main_cpu_s"] / times["process_cpu_s"]
    frames = times["frames"]
    return {"variant": variant, "size": size, "frames": frames,
            "process_cpu_ms_per_frame": round(times["process_cpu_s"] / frames * 1e3, 3),
            "main_cpu_ms_per_frame": round(times["main_cpu_s"] / frames * 1e3, 3),
            "main_thread_samples": main, "python_samples": samples["python"],
            "python_share": round(share, 4),
            "top_python_functions": python_leaves.most_common(8)}


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
    mirrorlab.renderer.gl_pass = finished_pass
    try:
        with mirrorlab.Renderer((size, size)) as renderer:
            for index in range(frames + 10):
                current.clear()
                start = time.perf_counter()
                posed = scene_list[index % len(scene_list)]
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
                    (drawn - start) * 1e3 - sum(current.values()))
    finally:
        mirrorlab.renderer.gl_pass = original
    assert stats.ran == (["capture:mirror", "camera"] if variant == "two passes"
                         else ["camera"]), stats.ran
    return {name: round(statistics.median(values), 3) for name, values in timings.items()}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--seconds", type=float, default=8.0)
    parser.add_argument("--frames", type=int, default=100)
    parser.add_argument("--json", metavar="PATH")
    parser.add_argument("--child", choices=VARIANTS, help=argparse.SUPPRESS)
    args = parser.parse_args(argv)
    if args.child:
        child(args.child, args.size, args.seconds)
        return 0
    if not 16 <= args.size <= 4096 or args.seconds <= 0 or args.frames < 1:
        parser.error("--size 16 to 4096, --seconds above 0, --frames at least 1")
    report = {"shares": [], "passes": {}}
    for variant in VARIANTS:
        log(f"{variant}: {args.seconds:g} s under py-spy")
        share = python_share(variant, args.size, args.seconds)
        report["shares"].append(share)
        print(f"{variant}, {args.size}x{args.size}: Python's share {share['python_share']:.1%} "
              f"of {share['process_cpu_ms_per_frame']:.2f} ms CPU a frame (main thread "
              f"{share['main_cpu_ms_per_frame']:.2f} ms, {share['python_samples']} of "
              f"{share['main_thread_samples']} of its samples on Python's side; "
              f"{share['frames']} frames)")
        print("  most sampled Python functions: " + ", ".join(
            f"{name} {count}" for name, count in share["top_python_functions"]))
    for variant in VARIANTS:
        times = pass_times(variant, args.size, args.frames)
        report["passes"][variant] = times
        print(f"{variant}, per pass (median ms, each ended by glFinish): " + ", ".join(
            f"{name} {ms:.2f}" for name, ms in times.items()))
    if args.json:
        from mirrorlab.files import Outputs

        with Outputs() as outputs:
            outputs.add(Path(args.json), (json.dumps(report, indent=2) + "\n").encode())
    return 0


if __name__ == "__main__":
    os.environ.setdefault("PYTHONUNBUFFERED", "1")
    sys.exit(main())
