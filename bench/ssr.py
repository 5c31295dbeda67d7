"""What screen-space reflections cost, against the objects a scene holds and the area its
reflector covers, timed side by side.

Run from the repository root::

    python bench/ssr.py [--size 512] [--frames 30] [--block 5] [--counts 10,100,1000]
                        [--json PATH]

The scene is ``ssr_box_room`` (a mirror floor in a room, its probe a live cube map with
the room as its box proxy), with N boxes (``mirrorlab.benchmarks.scale``'s box) on a
grid standing across the room above the floor: the viewer sees them, and the floor
reflects them, but they cover none of the floor. Its floor comes in two sizes: the
room's (8 x 8) and a quarter of that (4 x 4, the same centre). For every count and
floor, one :class:`mirrorlab.Renderer` draws frames whose camera moves a hair each
frame (so every frame is drawn anew; the probe's capture is kept, as nothing it shows
moves).

Timed per frame: the whole frame (to the readback), and screen-space reflections' own
work, from the frame copy to the mix (``ScreenSpaceReflections.march``, between two
``glFinish`` calls: the work of the shader on llvmpipe, which renders on the CPU), with
the floor's pixels (from the miss mask). The variants take turns in blocks of
``--block`` frames, the order rotating every round, until each has ``--frames``
samples: a shared machine's load falls on all of them alike. Reported: medians, SSR's
milliseconds per 10,000 floor pixels, and the ratios a claim needs (1,000 objects to 10
at each floor size; the large floor to the small at each count), each the median over
the rounds of the ratio of the two variants' medians in that round. One more variant
marches the plain DDA (every sample looked at, the nearest-depth pyramid off) beside
the pyramid's march, at the middle count on the large floor.
"""

from __future__ import annotations

import argparse
import json
import statistics
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

import mirrorlab
from mirrorlab.benchmarks.scale import box_mesh, grid, paired_ratio
from mirrorlab.gl.opengl import GL
from mirrorlab.passes import ssr as ssr_pass
from mirrorlab.scene.model import MeshObject, PlanarReflector, Scene, Transform

FLOORS = {"floor 8x8": 1.0, "floor 4x4": 0.5}
"""The floor's sides, as a share of the room's."""


def boxes_scene(count: int, floor_scale: float) -> Scene:
    """``ssr_box_room`` with ``count`` boxes across the room above its floor, and its floor
    scaled by ``floor_scale`` about its centre."""
    scene = mirrorlab.load_scene("ssr_box_room")
    points = grid(
        count,
        np.array([0.0, 2.2, -1.5]),
        np.array([1.0, 0.0, 0.0]),
        np.array([0.0, 1.0, 0.0]),
        3.4,
        1.6,
    )
    columns = int(np.ceil(np.sqrt(count * 3.4 / 1.6)))
    side = min(0.35, 0.6 * 6.8 / columns)
    boxes = tuple(
        MeshObject(
            name=f"box_{i}",
            mesh=box_mesh(),
            color=((0.8, 0.3, 0.2), (0.2, 0.7, 0.3), (0.25, 0.35, 0.85))[i % 3],
            transform=Transform(position=tuple(float(v) for v in p), scale=(side,) * 3),  # type: ignore[arg-type]
        )
        for i, p in enumerate(points)
    )
    (floor,) = scene.reflectors
    assert isinstance(floor, PlanarReflector)
    corners = np.asarray(floor.corners) * floor_scale  # the floor's centre is the origin
    floor = replace(floor, corners=tuple(tuple(float(v) for v in c) for c in corners))  # type: ignore[arg-type]
    return replace(scene, objects=scene.objects + boxes, reflectors=(floor,))


class Timed:
    """One variant: its renderer and scene, and what each of its frames took."""

    def __init__(self, name: str, scene: Scene, size: int) -> None:
        self.name = name
        self.scene = scene
        self.size = size
        self.renderer = mirrorlab.Renderer((size, size))
        self.turn = 0
        self.frame_blocks: list[list[float]] = []
        self.ssr_blocks: list[list[float]] = []
        self.pixels = 0

    def frames(self, count: int, spent: list[float]) -> tuple[list[float], list[float]]:
        frames, own = [], []
        for _ in range(count):
            camera = self.scene.camera
            eye = (camera.eye[0] + 1e-5 * self.turn, camera.eye[1], camera.eye[2])
            self.turn += 1
            scene = replace(self.scene, camera=replace(camera, eye=eye))
            spent.clear()
            start = time.perf_counter()
            self.renderer.render(scene)
            frames.append((time.perf_counter() - start) * 1e3)
            own.append(sum(spent))
        return frames, own


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--frames", type=int, default=30)
    parser.add_argument("--block", type=int, default=5)
    parser.add_argument("--counts", default="10,100,1000")
    parser.add_argument("--json", type=Path)
    args = parser.parse_args(argv)
    counts = [int(c) for c in args.counts.split(",")]

    spent: list[float] = []
    march = ssr_pass.ScreenSpaceReflections.march

    def timed_march(self, draw, view, target):
        GL.glFinish()
        start = time.perf_counter()
        drawn = march(self, draw, view, target)
        GL.glFinish()
        spent.append((time.perf_counter() - start) * 1e3)
        return drawn

    ssr_pass.ScreenSpaceReflections.march = timed_march  # type: ignore[method-assign]
    variants = [
        Timed(f"{count} objects, {floor}", boxes_scene(count, scale), args.size)
        for floor, scale in FLOORS.items()
        for count in counts
    ]
    middle = counts[len(counts) // 2]
    plain = Timed(
        f"{middle} objects, {next(iter(FLOORS))}, DDA", boxes_scene(middle, 1.0), args.size
    )
    variants.append(plain)
    try:
        for variant in variants:  # warm up: shaders, meshes, the probe's capture
            variant.frames(3, spent)
            variant.pixels = int(variant.renderer.ssr_mask().reflector.sum())
        # the plain DDA: every sample looked at, no nearest-depth pyramid
        plain.renderer.scene_renderer.pass_for("floor").pyramid_levels = 1  # type: ignore[attr-defined]
        turn = 0
        while min(sum(map(len, v.frame_blocks)) for v in variants) < args.frames:
            shift = turn % len(variants)
            for variant in variants[shift:] + variants[:shift]:
                frames, own = variant.frames(args.block, spent)
                variant.frame_blocks.append(frames)
                variant.ssr_blocks.append(own)
            turn += 1
    finally:
        for variant in variants:
            variant.renderer.close()
        ssr_pass.ScreenSpaceReflections.march = march  # type: ignore[method-assign]

    rows = []
    print(f"{args.size}x{args.size}, {args.frames} frames a variant, blocks of {args.block}")
    print(f"{'variant':<36} {'floor px':>9} {'frame ms':>9} {'ssr ms':>8} {'ssr ms/10k px':>14}")
    for variant in variants:
        frame_ms = statistics.median(x for b in variant.frame_blocks for x in b)
        ssr_ms = statistics.median(x for b in variant.ssr_blocks for x in b)
        per = ssr_ms / variant.pixels * 1e4 if variant.pixels else float("nan")
        rows.append(
            {
                "variant": variant.name,
                "pixels": variant.pixels,
                "frame_ms": frame_ms,
                "ssr_ms": ssr_ms,
            }
        )
        print(
            f"{variant.name:<36} {variant.pixels:>9} {frame_ms:>9.2f} {ssr_ms:>8.2f} {per:>14.3f}"
        )
    by_name = {v.name: v for v in variants}
    ratios = {}
    for floor in FLOORS:
        few, many = (
            by_name[f"{counts[0]} objects, {floor}"],
            by_name[f"{counts[-1]} objects, {floor}"],
        )
        ratios[f"{floor}: ssr {counts[-1]}/{counts[0]} objects"] = paired_ratio(
            many.ssr_blocks, few.ssr_blocks
        )
        ratios[f"{floor}: frame {counts[-1]}/{counts[0]} objects"] = paired_ratio(
            many.frame_blocks, few.frame_blocks
        )
    pyramid = by_name[f"{middle} objects, {next(iter(FLOORS))}"]
    ratios["pyramid march / plain DDA (ssr ms)"] = paired_ratio(
        pyramid.ssr_blocks, plain.ssr_blocks
    )
    large, small = list(FLOORS)
    for count in counts:
        big, little = by_name[f"{count} objects, {large}"], by_name[f"{count} objects, {small}"]
        ratios[f"{count} objects: ssr {large}/{small}"] = paired_ratio(
            big.ssr_blocks, little.ssr_blocks
        )
        ratios[f"{count} objects: floor pixels {large}/{small}"] = big.pixels / max(
            little.pixels, 1
        )
    for label, value in ratios.items():
        print(f"{label}: {value:.2f}x")
    if args.json is not None:
        args.json.write_text(json.dumps({"rows": rows, "ratios": ratios}, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
