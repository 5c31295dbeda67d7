"""What a parallax correction costs a live cube map, timed side by side.

Run from the repository root::

    python bench/parallax.py [--scene chrome_sphere] [--size 512] [--map-size 256]
                             [--frames 40] [--block 5] [--json PATH]

One headless context draws the scene's curved reflectors as ``cube-live`` with each
correction (none, the sweep's box and sphere proxies, the distance search with several
step counts), each frame capturing the six faces afresh as a moving scene would (what
``mirrorlab bench accuracy`` times). The variants take turns in blocks of ``--block``
frames, the order rotating every round, until each has ``--frames`` samples: the load
of a shared machine falls on all of them alike. Reported: the median, p10 and p90 wall
time of a frame (``glFinish`` included), its ratio to plain ``cube-live``, and each
variant's error against the ray tracer (4 x 4 rays a pixel) in the reflector.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

from mirrorlab.accuracy import erode, image_error, proxies_for, sweep_gl
from mirrorlab.gl.opengl import GL
from mirrorlab.options import apply_options
from mirrorlab.raytrace import trace_scene
from mirrorlab.scene.loader import load_scene
from mirrorlab.scene.model import Scene


def variants(scene: Scene, map_size: int) -> dict[str, Scene]:
    """The scene configured with each correction, by label."""
    corrections = [("cube-live", "none")]
    corrections += [(f"cube-live {label}", text) for label, text in proxies_for(scene)]
    corrections += [
        (f"cube-live distance {steps}", f"distance:{steps}")
        for steps in ("2+0", "4+1", "8+2", "16+2", "32+4")
    ]
    return {
        label: apply_options(scene, {"method": "cube-live", "map_size": map_size, "parallax": text})
        for label, text in corrections
    }


def time_against_truth(
    scene: Scene, configured: dict[str, Scene], size: tuple[int, int], frames: int, block: int
) -> tuple[dict[str, list[float]], dict[str, dict[str, float]]]:
    """Each configured scene's frame times in ms (at least ``frames`` each, in blocks of
    ``block``, the order rotated every round; what the renderer holds but baked
    backgrounds and pictures dropped before each frame, so a frame pays its captures)
    and its MAE and share off against ``scene``'s traced truth (4x supersampled), by
    label."""
    truth = trace_scene(scene, size, supersample=4)
    expected, mask = truth.to_uint8(), erode(truth.reflective_mask, 1)
    times: dict[str, list[float]] = {label: [] for label in configured}
    errors = {}
    with sweep_gl(size) as (renderer, framebuffer, _):

        def frame(label: str) -> float:
            held = renderer.state.held
            for key in [k for k, v in held.items() if v[0] not in ("bake", "picture")]:
                del held[key]
            start = time.perf_counter()
            renderer.render(configured[label], framebuffer)
            GL.glFinish()
            return (time.perf_counter() - start) * 1e3

        for label in configured:  # warm-up: programs, textures, the background bake
            for _ in range(3):
                frame(label)
            error = image_error(framebuffer.read(), expected, mask)
            errors[label] = {"mae": error.mae, "share_off": error.share_off}
        labels = list(configured)
        round_number = 0
        while min(len(t) for t in times.values()) < frames:
            shift = round_number % len(labels)
            for label in labels[shift:] + labels[:shift]:
                times[label] += [frame(label) for _ in range(block)]
            round_number += 1
    return times, errors


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scene", default="chrome_sphere")
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--map-size", type=int, default=256)
    parser.add_argument("--frames", type=int, default=40)
    parser.add_argument("--block", type=int, default=5)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args(argv)
    scene = load_scene(args.scene)
    configured = variants(scene, args.map_size)
    times, errors = time_against_truth(
        scene, configured, (args.size, args.size), args.frames, args.block
    )
    plain = float(np.median(times["cube-live"]))
    report = []
    print(
        f"{args.scene}, {args.size}x{args.size} frames, map {args.map_size}, "
        f"{args.frames}+ frames each in blocks of {args.block}:"
    )
    print(
        f"{'variant':<26} {'median ms':>9} {'p10':>7} {'p90':>7} {'x plain':>7} "
        f"{'MAE':>6} {'off >10':>7}"
    )
    for label, samples in times.items():
        median = float(np.median(samples))
        p10, p90 = (float(v) for v in np.percentile(samples, [10, 90]))
        row = {
            "variant": label,
            "median_ms": median,
            "p10_ms": p10,
            "p90_ms": p90,
            "ratio": median / plain,
            **errors[label],
        }
        report.append(row)
        print(
            f"{label:<26} {median:9.2f} {p10:7.2f} {p90:7.2f} {median / plain:7.2f} "
            f"{errors[label]['mae']:6.2f} {errors[label]['share_off']:7.1%}"
        )
    if args.json is not None:
        args.json.write_text(json.dumps(report, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
