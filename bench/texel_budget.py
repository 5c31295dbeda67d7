"""The same texel budget for every map: cube, octahedral, dual-paraboloid,
latitude-longitude and sphere maps compared at equal texel counts.

Run from the repository root::

    python bench/texel_budget.py [--budgets 128,256,512] [--frame 512]
                                 [--directions 500000] [--out-dir out/bench] [--quick]
    python bench/texel_budget.py --from-csv out/bench/texel_budget.csv

A budget is named by the cube face's edge ``n``: ``6 n^2`` texels at level 0, borders
and margins counted. Each map gets the largest size that stays within it
(:func:`mirrorlab.texel_budget.layout_for_budget`), and the octahedral map is measured a
second time at 0.87 of the budget (the share at which its coarsest texel is the cube's).
For each: the angular error of the looked-up direction over uniformly spread directions
(nearest texel: mean, 95th percentile, worst; bilinear: mean, worst), the texel
solid-angle ratio (largest over smallest), the share of texels a lookup can land in, and
the mean FLIP (LDR, Andersson et al. 2020) over the chrome sphere in the sky, close up
from above and from below (``--frame`` pixels square, against the ray tracer's 4 x 4
rays a pixel), drawn by each map's static technique. Writes ``texel_budget.csv``,
``texel_budget.md`` (the table) and ``texel_budget.png`` (matplotlib) into
``--out-dir``; ``--from-csv`` re-makes the table and plot from a saved CSV.
"""

from __future__ import annotations

import argparse
import csv
import io
import math
import sys
import time
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path

from mirrorlab import texel_budget as tb
from mirrorlab.files import write_bytes_atomic

OCTAHEDRAL_SHARE = 0.87
"""The share of the cube's texels the octahedral map is measured at a second time."""
VIEWS = {
    "above": ((0.6, 0.8, 2.4), 40.0),  # the sweep's close-up of the chrome sphere
    "below": ((0.5, -0.9, -2.6), 45.0),  # -z and the lower half's edges in the middle
}
"""Close-ups of the chrome sphere: eye and vertical field of view, looking at its centre."""


@dataclass(frozen=True)
class Row:
    """One map at one budget (``cube_edge``: the budget is ``6 cube_edge^2`` texels;
    ``share`` of it used for the map's size): its ``size`` and stored ``texels``, the
    angular errors in degrees, the texel solid-angle ratio, the share of texels used,
    and the mean FLIP over the sphere in each view (NaN where not measured)."""

    cube_edge: int
    share: float
    map: str
    size: int
    texels: int
    mean: float
    p95: float
    worst: float
    bilinear_mean: float
    bilinear_worst: float
    ratio: float
    used: float
    flip_above: float = math.nan
    flip_below: float = math.nan

    @property
    def label(self) -> str:
        return self.map if self.share == 1.0 else f"{self.map} {self.share:g}x"


def configurations(edges: list[int]) -> list[tuple[int, float, tb.Layout]]:
    """Each (cube edge, share of the budget, layout) measured."""
    found = []
    for edge in edges:
        budget = 6 * edge * edge
        for kind in tb.MAPS:
            found.append((edge, 1.0, tb.layout_for_budget(kind, budget)))
        found.append(
            (edge, OCTAHEDRAL_SHARE, tb.layout_for_budget("octahedral", OCTAHEDRAL_SHARE * budget))
        )
    return found


def numpy_rows(edges: list[int], directions: int, progress) -> list[Row]:
    """The numpy half of every configuration's row."""
    spread = tb.uniform_directions(directions)
    rows = []
    for edge, share, layout in configurations(edges):
        error = tb.lookup_error(layout, spread)
        angles = tb.texel_solid_angles(layout)
        rows.append(
            Row(
                edge,
                share,
                layout.kind,
                layout.size,
                layout.texels,
                error.mean,
                error.p95,
                error.worst,
                error.bilinear_mean,
                error.bilinear_worst,
                float(angles.max() / angles.min()),
                len(angles) / layout.texels,
            )
        )
        progress(f"{rows[-1].label} at 6x{edge}^2: size {layout.size}")
    return rows


def flip_rows(rows: list[Row], frame: int, progress) -> list[Row]:
    """Each row with its FLIP over the chrome sphere in the sky, in each view."""
    from mirrorlab.accuracy import erode, sweep_gl
    from mirrorlab.flip import flip_map
    from mirrorlab.options import apply_options
    from mirrorlab.raytrace import trace_scene
    from mirrorlab.scene.loader import load_scene
    from mirrorlab.scene.model import Camera

    sky = replace(load_scene("chrome_sphere"), objects=())
    scenes, truths = {}, {}
    for name, (eye, fovy) in VIEWS.items():
        scenes[name] = replace(sky, camera=Camera(eye=eye, target=(0.0, 0.0, 0.0), fovy=fovy))
        start = time.perf_counter()
        traced = trace_scene(scenes[name], (frame, frame), supersample=4)
        truths[name] = (traced.to_uint8(), erode(traced.reflective_mask, 1))
        progress(f"the truth from {name}: {time.perf_counter() - start:.0f} s")
    measured = []
    with sweep_gl((frame, frame)) as (renderer, target, _):
        for row in rows:
            flips = {}
            for name, scene in scenes.items():
                configured = apply_options(scene, {"method": row.map, "map_size": row.size})
                renderer.render(configured, target)
                renderer.render(configured, target)  # the map made, a frame as any other
                image = target.read()
                truth, mask = truths[name]
                error = flip_map(image, truth)
                if error is None:
                    raise SystemExit("FLIP needs the flip extra: pip install 'mirrorlab[flip]'")
                flips[name] = float(error[mask].mean())
            measured.append(replace(row, flip_above=flips["above"], flip_below=flips["below"]))
            progress(
                f"{row.label} size {row.size}: FLIP {flips['above']:.4f}, {flips['below']:.4f}"
            )
    return measured


def table(rows: list[Row]) -> str:
    """The rows as a Markdown table."""
    head = (
        "| budget | map | size | texels | angle mean | p95 | worst | bilinear mean | worst "
        "| solid-angle ratio | texels used | FLIP above | FLIP below |\n"
        "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n"
    )
    lines = [
        f"| 6x{r.cube_edge}^2 | {r.label} | {r.size} | {r.texels:,} | {r.mean:.3f} | "
        f"{r.p95:.3f} | {r.worst:.3f} | {r.bilinear_mean:.4f} | {r.bilinear_worst:.3f} | "
        f"{r.ratio:.2f} | {r.used:.1%} | {r.flip_above:.4f} | {r.flip_below:.4f} |"
        for r in rows
    ]
    return head + "\n".join(lines) + "\n"


def to_csv(rows: list[Row]) -> str:
    out = io.StringIO()
    writer = csv.DictWriter(out, fieldnames=[f.name for f in fields(Row)])
    writer.writeheader()
    for row in rows:
        writer.writerow(asdict(row))
    return out.getvalue()


def from_csv(text: str) -> list[Row]:
    types = {f.name: f.type for f in fields(Row)}
    rows = []
    for record in csv.DictReader(io.StringIO(text)):
        values = {
            key: (int(value) if types[key] in ("int", int) else float(value))
            for key, value in record.items()
        }
        rows.append(Row(**values))  # type: ignore[arg-type]
    return rows


def plot(rows: list[Row], path: Path) -> bool:
    """Angular error and FLIP against the budget, one line per map (False without
    matplotlib)."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return False
    figure, (angle_axis, flip_axis) = plt.subplots(1, 2, figsize=(11, 4.2))
    for label in dict.fromkeys(row.label for row in rows):
        mine = [row for row in rows if row.label == label]
        texels = [row.texels for row in mine]
        style = "--" if "x" in label.split()[-1] else "-"
        angle_axis.plot(texels, [row.mean for row in mine], style, marker="o", label=label)
        flip = [(row.flip_above + row.flip_below) / 2 for row in mine]
        flip_axis.plot(texels, flip, style, marker="o", label=label)
    for axis, title in (
        (angle_axis, "mean angle to the nearest texel's direction (degrees)"),
        (flip_axis, "mean FLIP on the chrome sphere (above and below)"),
    ):
        axis.set_xscale("log", base=2)
        axis.set_yscale("log")
        axis.set_xlabel("texels at level 0")
        axis.set_title(title, fontsize=10)
        axis.grid(True, which="both", alpha=0.3)
    angle_axis.legend(fontsize=8)
    figure.tight_layout()
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=110)
    plt.close(figure)
    write_bytes_atomic(path, buffer.getvalue())
    return True


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--budgets", default="128,256,512", help="cube face edges, e.g. 128,256")
    parser.add_argument("--frame", type=int, default=512, help="frame size for FLIP")
    parser.add_argument("--directions", type=int, default=500_000)
    parser.add_argument("--out-dir", type=Path, default=Path("out/bench"))
    parser.add_argument("--quick", action="store_true", help="small budgets and frames")
    parser.add_argument("--from-csv", type=Path, help="re-make the table and plot")
    parser.add_argument("--no-flip", action="store_true", help="the numpy half only")
    args = parser.parse_args(argv)

    def progress(message: str) -> None:
        print(message, file=sys.stderr, flush=True)

    if args.from_csv is not None:
        rows = from_csv(args.from_csv.read_text())
    else:
        try:
            edges = [int(v) for v in args.budgets.split(",")]
        except ValueError:
            parser.error(f"--budgets: expected whole numbers such as 128,256, got {args.budgets!r}")
        if args.quick:
            edges, args.frame, args.directions = [16, 32], 96, 20_000
        if any(edge < 4 for edge in edges) or args.frame < 16 or args.directions < 1:
            parser.error("--budgets from 4, --frame from 16, --directions from 1")
        rows = numpy_rows(edges, args.directions, progress)
        if not args.no_flip:
            rows = flip_rows(rows, args.frame, progress)
    args.out_dir.mkdir(parents=True, exist_ok=True)
    markdown = table(rows)
    if args.from_csv is None:
        write_bytes_atomic(args.out_dir / "texel_budget.csv", to_csv(rows).encode())
    write_bytes_atomic(args.out_dir / "texel_budget.md", markdown.encode())
    if not plot(rows, args.out_dir / "texel_budget.png"):
        progress("no plot: matplotlib is missing (pip install 'mirrorlab[plot]')")
    print(markdown)
    return 0


if __name__ == "__main__":
    sys.exit(main())
