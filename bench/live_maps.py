"""What each live map costs a frame, timed side by side: the live cube map, the octahedral
map resampled from it, the dual paraboloid converted from a half-size cube capture and
the dual paraboloid warped per vertex.

Run from the repository root::

    python bench/live_maps.py [--scene chrome_sphere] [--size 512] [--map-size 256]
                              [--frames 30] [--block 5] [--json PATH]

One headless context draws the scene's curved reflectors with each live technique of the
registry (``texture = "fixed"``), each frame capturing afresh as a moving scene would.
The techniques take turns in blocks of ``--block`` frames, the order rotating every
round, until each has ``--frames`` samples, so that a shared machine's load falls on all
alike. Reported: the median, p10 and p90 wall time of a frame (``glFinish`` included), its
ratio to ``cube-live`` in the same run, and each one's error against the ray tracer
(4 x 4 rays a pixel) in the reflector.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
from parallax import time_against_truth  # bench/parallax.py, beside this file

from mirrorlab.options import apply_options
from mirrorlab.scene.loader import load_scene
from mirrorlab.techniques import technique, techniques


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--scene", default="chrome_sphere")
    parser.add_argument("--size", type=int, default=512)
    parser.add_argument("--map-size", type=int, default=256)
    parser.add_argument("--frames", type=int, default=30)
    parser.add_argument("--block", type=int, default=5)
    parser.add_argument("--json", type=Path)
    args = parser.parse_args(argv)
    scene = load_scene(args.scene)
    live = [t.name for t in techniques("curved") if t.texture == "fixed"]
    configured = {}
    for name in live:
        options: dict = {"method": name, "map_size": args.map_size}
        if technique(name).parallax:  # the plain lookup: what the capture costs
            options["parallax"] = "none"
        configured[name] = apply_options(scene, options)
    times, errors = time_against_truth(
        scene, configured, (args.size, args.size), args.frames, args.block
    )
    plain = float(np.median(times["cube-live"]))
    print(
        f"{args.scene}, {args.size}x{args.size} frames, map {args.map_size}, "
        f"{args.frames}+ frames each in blocks of {args.block}:"
    )
    print(f"{'technique':<20} {'median ms':>9} {'p10':>7} {'p90':>7} {'x cube':>7} {'MAE':>6}")
    report = []
    for label, samples in times.items():
        median = float(np.median(samples))
        p10, p90 = (float(v) for v in np.percentile(samples, [10, 90]))
        report.append(
            {
                "technique": label,
                "median_ms": median,
                "p10_ms": p10,
                "p90_ms": p90,
                "ratio": median / plain,
                **errors[label],
            }
        )
        print(
            f"{label:<20} {median:9.2f} {p10:7.2f} {p90:7.2f} {median / plain:7.2f} "
            f"{errors[label]['mae']:6.2f}"
        )
    if args.json is not None:
        args.json.write_text(json.dumps(report, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
