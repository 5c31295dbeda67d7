"""Soak: many frames in one Renderer, and many one-shot renders, watching for growth.

    python bench/soak.py [--frames 5000] [--switch-every 100] [--size 256x256]
                         [--one-shot 1000] [--one-shot-size 64x64] [--json PATH]

Frames: one headless :class:`mirrorlab.Renderer` draws ``--frames`` frames. Every
``--switch-every`` frames it moves on to the next (scene, technique) pair: every shipped
scene with every technique its first reflector can take (30 pairs), so the renderer
keeps making and dropping passes, textures and programs. Within a block the camera
orbits its target (half a degree a frame) and the robot's joints swing, so captures
re-run. Every ``--sample-every`` frames it records the resident memory of the process,
the live GL objects of the context and the open file descriptors.

One-shot: ``--one-shot`` calls of :func:`mirrorlab.render`, each making and freeing its
own EGL context, cycling through the shipped scenes, sampled the same way.

Nothing here is a pass condition: the script prints what it saw (and writes it as JSON)
for a person to read; ``tests/gl/test_soak.py`` runs a short version with its checks.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import time
from dataclasses import asdict, dataclass, replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

import mirrorlab
from mirrorlab.options import apply_options, parse_size
from mirrorlab.scene.loader import SCENE_ALIASES, shipped_scene_names
from mirrorlab.scene.model import Scene
from mirrorlab.techniques import technique_names


@dataclass
class Sample:
    """The process after ``step`` frames (or calls): resident memory in MB, live GL
    objects in the renderer's context (-1 when no context is open), open file
    descriptors."""

    step: int
    rss_mb: float
    gl_objects: int
    fds: int


def resident_mb() -> float:
    """This process's resident memory (VmRSS), MB."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1]) / 1024.0
    return math.nan


def open_fds() -> int:
    return len(os.listdir("/proc/self/fd"))


def scene_names() -> list[str]:
    """The shipped scenes, each once (not the short names kept for older command lines)."""
    return [name for name in shipped_scene_names() if name not in SCENE_ALIASES]


def schedule() -> list[tuple[Scene, str | None]]:
    """Every shipped scene with every technique of its first reflector (the scene as it
    is when it has none), loaded and configured once."""
    pairs: list[tuple[Scene, str | None]] = []
    for name in scene_names():
        scene = mirrorlab.load_scene(name)
        if not scene.reflectors:
            pairs.append((scene, None))
            continue
        kind = scene.reflectors[0].kind
        for technique in technique_names(kind):
            configured = apply_options(scene, {"method": technique})
            pairs.append((configured, technique))
    return pairs


def posed(scene: Scene, frame: int) -> Scene:
    """``scene`` at ``frame`` of its animation, the camera orbited by half a degree a
    frame about the vertical through its target, the robot's joints swinging."""
    scene = scene.at_frame(frame % scene.frame_count)
    camera = scene.camera
    angle = math.radians(0.5 * frame)
    ex, ey, ez = camera.eye
    tx, _, tz = camera.target
    dx, dz = ex - tx, ez - tz
    eye = (
        tx + dx * math.cos(angle) - dz * math.sin(angle),
        ey,
        tz + dx * math.sin(angle) + dz * math.cos(angle),
    )
    scene = replace(scene, camera=replace(camera, eye=eye))
    if scene.robot is not None:
        base, lower, upper = scene.robot.angles
        swing = 15.0 * math.sin(frame / 7.0)
        scene = scene.with_angles((base + swing, lower + swing / 2, upper - swing))
    return scene


def frame_soak(
    frames: int, switch_every: int, size: tuple[int, int], sample_every: int, progress: bool = False
) -> tuple[list[Sample], list[str]]:
    """Draw ``frames`` frames in one Renderer as the module says; returns the samples and
    the (scene, technique) of each block."""
    from tqdm import tqdm

    pairs = schedule()
    samples: list[Sample] = []
    blocks: list[str] = []
    with mirrorlab.Renderer(size) as renderer:
        for frame in tqdm(
            range(frames), desc="frames", disable=not progress, file=sys.stderr, mininterval=1.0
        ):
            block = frame // switch_every
            scene, technique = pairs[block % len(pairs)]
            if frame % switch_every == 0:
                blocks.append(f"{scene.name}/{technique or '-'}")
            # The camera's path repeats with each round of pairs, so that a round
            # finds the renderer exactly as the one before left it.
            renderer.render(posed(scene, frame % (len(pairs) * switch_every)))
            if (frame + 1) % sample_every == 0:
                samples.append(Sample(frame + 1, resident_mb(), renderer.gl_objects, open_fds()))
    return samples, blocks


def one_shot_soak(
    calls: int, size: tuple[int, int], sample_every: int, progress: bool = False
) -> list[Sample]:
    """``calls`` calls of mirrorlab.render(), cycling through the shipped scenes."""
    from tqdm import tqdm

    names = scene_names()
    samples = []
    for call in tqdm(
        range(calls), desc="one-shot", disable=not progress, file=sys.stderr, mininterval=1.0
    ):
        mirrorlab.render(names[call % len(names)], size=size)
        if (call + 1) % sample_every == 0:
            samples.append(Sample(call + 1, resident_mb(), -1, open_fds()))
    return samples


def summary(samples: list[Sample], warm: int) -> str:
    """First sample at or after ``warm`` against the last, and the peak."""
    after = [s for s in samples if s.step >= warm] or samples
    first, last = after[0], after[-1]
    peak = max(s.rss_mb for s in after)
    gl = {s.gl_objects for s in after}
    return (
        f"after {first.step}: {first.rss_mb:.0f} MB, {first.gl_objects} GL objects, "
        f"{first.fds} fds; at {last.step}: {last.rss_mb:.0f} MB, {last.gl_objects} GL "
        f"objects, {last.fds} fds; peak {peak:.0f} MB; GL objects seen "
        f"{min(gl)}-{max(gl)}"
    )


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--frames", type=int, default=5000)
    parser.add_argument("--switch-every", type=int, default=100)
    parser.add_argument("--size", default="256x256")
    parser.add_argument("--sample-every", type=int, default=250)
    parser.add_argument("--one-shot", type=int, default=1000)
    parser.add_argument("--one-shot-size", default="64x64")
    parser.add_argument("--json", metavar="PATH")
    args = parser.parse_args(argv)
    size, one_size = (
        parse_size("--size", args.size),
        parse_size("--one-shot-size", args.one_shot_size),
    )
    report: dict = {"renderer": "", "started": time.strftime("%Y-%m-%d %H:%M:%S")}
    start = time.perf_counter()
    samples, blocks = frame_soak(
        args.frames, args.switch_every, size, args.sample_every, progress=True
    )
    took = time.perf_counter() - start
    pairs = len(schedule())
    warm = min(pairs * args.switch_every, args.frames)  # every pair made once
    print(
        f"{args.frames} frames at {size[0]}x{size[1]}, (scene, technique) switched every "
        f"{args.switch_every} frames over {pairs} pairs, {took:.0f} s"
    )
    print("  frame  RSS MB  GL objects  fds")
    for sample in samples:
        print(f"  {sample.step:5d}  {sample.rss_mb:6.1f}  {sample.gl_objects:10d}  {sample.fds:3d}")
    print(f"frames: {summary(samples, warm)}")
    report["frames"] = {
        "count": args.frames,
        "size": list(size),
        "switch_every": args.switch_every,
        "seconds": took,
        "blocks": blocks,
        "samples": [asdict(s) for s in samples],
    }
    if args.one_shot:
        start = time.perf_counter()
        shots = one_shot_soak(args.one_shot, one_size, max(1, args.one_shot // 20), progress=True)
        took = time.perf_counter() - start
        print(
            f"{args.one_shot} one-shot mirrorlab.render() calls at {one_size[0]}x"
            f"{one_size[1]}, {took:.0f} s"
        )
        for sample in shots:
            print(f"  call {sample.step:5d}  {sample.rss_mb:6.1f} MB  {sample.fds:3d} fds")
        print(f"one-shot: {summary(shots, shots[0].step if shots else 0)}")
        report["one_shot"] = {
            "count": args.one_shot,
            "size": list(one_size),
            "seconds": took,
            "samples": [asdict(s) for s in shots],
        }
    with mirrorlab.Renderer((8, 8)) as renderer:
        report["renderer"] = renderer.gl_renderer
    if args.json:
        Path(args.json).write_text(json.dumps(report, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
