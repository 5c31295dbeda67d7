"""``mirrorlab bench accuracy`` and ``mirrorlab bench speed``: their arguments read into
the settings of :mod:`mirrorlab.accuracy` and :mod:`mirrorlab.benchmarks.speed`, which do
the work."""

from __future__ import annotations

import argparse
from dataclasses import replace
from pathlib import Path

from mirrorlab.commands.arguments import add_executor_arguments
from mirrorlab.files import check_folder
from mirrorlab.options import OptionError, parse_choices, parse_count, parse_counts
from mirrorlab.scene.loader import load_scene
from mirrorlab.scene.model import Scene

NAME = "bench"


def add_parser(commands: argparse._SubParsersAction) -> None:
    """The ``bench`` command and its benchmarks' arguments, as a subcommand of ``commands``."""
    bench = commands.add_parser(NAME, help="measure error against the ray tracer, and time")
    benchmarks = bench.add_subparsers(dest="what", required=True, metavar="BENCHMARK")
    _add_accuracy_parser(benchmarks)
    _add_speed_parser(benchmarks)


def _add_accuracy_parser(benchmarks: argparse._SubParsersAction) -> None:
    accuracy = benchmarks.add_parser(
        "accuracy",
        help="every technique's error against the ray-traced truth (MAE, p95, PSNR, share off, "
        "FLIP, a fallback's miss share) and its time, with each scene's Pareto frontier",
    )
    accuracy.add_argument(
        "--quick",
        action="store_true",
        help="a small sweep (128-pixel frames, the mirror's captures at 64 and 128, the "
        "environment maps at 128, few viewpoints)",
    )
    accuracy.add_argument(
        "--out-dir",
        default="out/bench",
        help="where accuracy.csv, accuracy.md and accuracy.png go (default %(default)s)",
    )
    accuracy.add_argument("--frame", metavar="N", help="frame side in pixels (default 512)")
    accuracy.add_argument(
        "--sizes", metavar="N,N,...", help="texture sides (default 64,128,256,512,1024,2048)"
    )
    accuracy.add_argument(
        "--frames", metavar="N", help="timed frames per configuration (default 15)"
    )
    accuracy.add_argument(
        "--from-csv",
        metavar="PATH",
        help="measure nothing: re-make the tables and plot from a saved accuracy.csv",
    )
    add_executor_arguments(
        accuracy,
        jobs="ray trace the truths and score the frames in J processes; the timed "
        "frames stay in this process, run while the others are idle",
        scheduler="trace and score on",
    )
    accuracy.add_argument(
        "--scene",
        action="append",
        help="lab (the mirror techniques), sphere (the environment maps), "
        "all (default), or a scene file: every technique its reflectors "
        "can use, from its own camera; give it again for more scenes (a table, a "
        "Pareto frontier and a row of the plot each)",
    )


def _add_speed_parser(benchmarks: argparse._SubParsersAction) -> None:
    speed = benchmarks.add_parser(
        "speed",
        help="frame times against pyrender and at scale (many objects and mirrors)",
        description="Time mirrorlab's frames (two passes, ortho and reflected; the capture "
        "reused; one pass) on the lab's meshes at several sizes and subdivisions, and frames "
        "of scenes with many objects or mirrors, seen and unseen; with --pyrender, "
        "pyrender's frames of the same meshes beside them. Every frame is read back; the "
        "variants take turns in blocks. Writes speed.md, speed.csv, scale.csv and speed.png.",
    )
    speed.add_argument(
        "--quick",
        action="store_true",
        help="3 frames a variant at 32x32 and 64x64, the lab meshes and their "
        "first subdivision, scale scenes of 3 and 12 items at 64x64, for the "
        "--parts and --scale-modes given (checks that the benchmark works, "
        "not its figures)",
    )
    speed.add_argument(
        "--parts",
        metavar="sweep,scale",
        default="sweep,scale",
        help="sweep (sizes and triangles), scale (many objects and mirrors), "
        "or both (default %(default)s)",
    )
    speed.add_argument(
        "--sizes",
        metavar="N,N,...",
        default="256,512,1024,2048",
        help="frame sides of the sweep (default %(default)s)",
    )
    speed.add_argument(
        "--subdivisions",
        metavar="N,N,...",
        default="0,2,4,6",
        help="the lab's meshes subdivided this many times, x4 triangles each "
        "(default %(default)s: 400 to 1.6 million triangles)",
    )
    speed.add_argument(
        "--scale-size",
        metavar="N",
        default="256",
        help="frame side of the scale scenes (default %(default)s)",
    )
    speed.add_argument(
        "--scale-objects",
        metavar="N,N,...",
        default="10,100,1000",
        help="object counts of the scale scenes (default %(default)s)",
    )
    speed.add_argument(
        "--scale-mirrors",
        metavar="N,N,...",
        default="10,100,400",
        help="mirror counts of the scale scenes (default %(default)s)",
    )
    speed.add_argument(
        "--scale-modes",
        metavar="still,moving",
        default="still,moving",
        help="still (the same scene every frame), moving (the camera moves a "
        "hair every frame), or both (default %(default)s)",
    )
    speed.add_argument(
        "--frames", metavar="N", default="30", help="timed frames a variant (default %(default)s)"
    )
    speed.add_argument(
        "--scale-frames",
        metavar="N",
        default="100",
        help="timed frames a variant of the scale scenes (default "
        "%(default)s: their frames are short, and a ratio to the base frame "
        "is the median of one a round)",
    )
    speed.add_argument(
        "--warmup",
        metavar="N",
        default="5",
        help="frames a variant before timing (default %(default)s)",
    )
    speed.add_argument(
        "--block",
        metavar="N",
        default="5",
        help="frames a variant runs before the next one's turn (default %(default)s)",
    )
    speed.add_argument(
        "--out-dir",
        default="out/bench/speed",
        help="where the report goes (default %(default)s); the meshes are "
        "written to its meshes folder",
    )
    speed.add_argument(
        "--pyrender",
        metavar="PYTHON",
        help="the Python of an environment with pyrender==0.1.45, numpy<2 "
        "and Pillow, to time pyrender beside mirrorlab (./dev bench speed "
        "makes one in a clone)",
    )
    speed.add_argument(
        "--from-csv",
        metavar="PATH",
        help="time nothing: re-make the report from a saved speed.csv (and "
        "the scale.csv beside it)",
    )


def run(args: argparse.Namespace) -> int:
    """``mirrorlab bench BENCHMARK``: the benchmark named."""
    return _run_speed(args) if args.what == "speed" else _run_accuracy(args)


def _run_accuracy(args: argparse.Namespace) -> int:
    """``mirrorlab bench accuracy``: the sweep's settings from the arguments, then the sweep."""
    from mirrorlab.accuracy import SweepSettings, run_command

    changes: dict = {}
    if args.frame:
        changes["frame"] = parse_count("--frame", args.frame, 16, 4096)
    if args.sizes:
        changes["sizes"] = parse_counts("--sizes", args.sizes, 1, 8192)
        changes["curved_sizes"] = None  # every map at the sizes asked for
    if args.frames:
        changes["frames"] = parse_count("--frames", args.frames, 1, 10000)
    jobs = parse_count("--jobs", args.jobs, 1, 1024)
    out_dir = check_folder("--out-dir", args.out_dir)
    settings = SweepSettings.quick() if args.quick else SweepSettings()
    settings = replace(settings, **changes)
    scenes: list[str | Scene] = [
        name if name in ("lab", "sphere", "all") else load_scene(name)
        for name in args.scene or ["all"]
    ]
    return run_command(
        settings,
        scenes,
        out_dir,
        Path(args.from_csv) if args.from_csv else None,
        jobs=jobs,
        scheduler=args.scheduler,
        engine=args.engine,
    )


def _run_speed(args: argparse.Namespace) -> int:
    """``mirrorlab bench speed``: the benchmark's settings from the arguments, then the run."""
    from mirrorlab.benchmarks.speed import SpeedSettings, run_command

    out_dir = check_folder("--out-dir", args.out_dir)
    pyrender = Path(args.pyrender) if args.pyrender else None
    if pyrender is not None and not pyrender.is_file():
        raise OptionError(
            "--pyrender",
            f"{args.pyrender!r} is not a file (give the Python of an environment with pyrender)",
        )
    settings = SpeedSettings(
        sizes=parse_counts("--sizes", args.sizes, 16, 4096),
        levels=parse_counts("--subdivisions", args.subdivisions, 0, 7),
        parts=frozenset(parse_choices("--parts", args.parts, ("sweep", "scale"))),
        scale_size=parse_count("--scale-size", args.scale_size, 16, 4096),
        object_counts=parse_counts("--scale-objects", args.scale_objects, 1, 100_000),
        mirror_counts=parse_counts("--scale-mirrors", args.scale_mirrors, 1, 10_000),
        modes=parse_choices("--scale-modes", args.scale_modes, ("still", "moving")),
        frames=parse_count("--frames", args.frames, 1, 100_000),
        scale_frames=parse_count("--scale-frames", args.scale_frames, 1, 100_000),
        warmup=parse_count("--warmup", args.warmup, 1, 100_000),
        block=parse_count("--block", args.block, 1, 100_000),
    )
    if args.quick:
        settings = replace(SpeedSettings.quick(), parts=settings.parts, modes=settings.modes)
    return run_command(settings, out_dir, pyrender, Path(args.from_csv) if args.from_csv else None)
