"""Command line: ``mirrorlab render | plan | bench | demo | techniques | lab``.

Argument parsing only: each command's work lives in its own module. Bad input ends
with a one-line message naming the option or file and what was expected, exit status
2, and no output file written or clobbered.
"""

from __future__ import annotations

import argparse
import re
import sys
import warnings
from collections.abc import Sequence
from pathlib import Path

from mirrorlab.errors import BatchError, BenchmarkError, GLContextError, GLPassError, WriteError
from mirrorlab.files import OutputError, check_folder, check_output
from mirrorlab.options import (
    OPTIONS,
    OptionError,
    apply_options,
    parse_choices,
    parse_count,
    parse_counts,
    parse_size,
)
from mirrorlab.scene.loader import DEFAULT_SCENE, SceneError, load_scene, shipped_scene_names
from mirrorlab.scene.model import Scene


class UsageError(Exception):
    """Bad input from the command line; the message is shown as is."""


DEBUG_HELP = (
    "a debug OpenGL context whose KHR_debug messages are checked after every "
    "pass: a GL error stops the command, naming the pass"
)
EXIT_BAD_INPUT, EXIT_MACHINE, EXIT_INTERRUPTED = 2, 1, 130
TINY_HELP = (
    "LOSSY: draw a reflector that may cover fewer than N pixels plain, without "
    "its capture (default 0: off, and the plan changes no pixel)"
)


def tiny_pixels_of(args: argparse.Namespace) -> float:
    return float(
        parse_count("--tiny-pixels", args.tiny_pixels, 0, 10**9)
        if args.tiny_pixels is not None
        else 0
    )


def _add_executor_arguments(parser: argparse.ArgumentParser, jobs: str, scheduler: str) -> None:
    """``--jobs``, ``--scheduler`` and ``--engine``: where a command's independent jobs run
    (:func:`mirrorlab.jobs.open_executor`). ``jobs`` says what J counts, ``scheduler``
    what is done on the scheduler's workers."""
    parser.add_argument("--jobs", metavar="J", default="1", help=f"{jobs} (default %(default)s)")
    parser.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help=f"{scheduler} a running Dask scheduler's workers (tcp://host:8786)",
    )
    parser.add_argument(
        "--engine",
        choices=("pool", "dask"),
        default="pool",
        help="with --jobs > 1 and no --scheduler: a local process pool "
        "(default; measured faster here) or a local Dask cluster",
    )


def _add_scene_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "scene_file",
        nargs="?",
        metavar="SCENE",
        help=f"a scene file (.toml) or a shipped scene: "
        f"{', '.join(shipped_scene_names())} (default {DEFAULT_SCENE})",
    )
    parser.add_argument("--scene", help="the same as SCENE (kept for older command lines)")
    group = parser.add_argument_group("scene changes (override the scene file)")
    for option in OPTIONS:
        group.add_argument(
            option.flag,
            dest=f"option_{option.name}",
            metavar=option.metavar,
            help=option.help_text,
            action="append" if option.repeat else "store",
        )


def build_parser() -> argparse.ArgumentParser:
    from mirrorlab import __version__

    parser = argparse.ArgumentParser(
        prog="mirrorlab",
        description="Mirrors and environment maps, rendered headless or in a window and "
        "measured against a ray tracer. A scene is a TOML file (see the documentation's "
        "'Writing a scene').",
    )
    parser.add_argument("--version", action="version", version=f"mirrorlab {__version__}")
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    render = commands.add_parser("render", help="render a scene headless to a PNG")
    _add_scene_arguments(render)
    render.add_argument("--out", help="output PNG (default out/SCENE.png)")
    render.add_argument("--size", default="512x512", help="WIDTHxHEIGHT (default %(default)s)")
    render.add_argument("--frame", metavar="N", help="the animation frame to render (default 0)")
    render.add_argument(
        "--frames", metavar="N", help="render frames 0 to N-1 (the last is written to --out)"
    )
    render.add_argument(
        "--out-dir",
        metavar="DIR",
        help="a batch: write every frame as "
        "DIR/SCENE_NNNN.png, each as soon as it is drawn; a rerun skips the "
        "frames already written whole",
    )
    _add_executor_arguments(
        render,
        jobs="with --out-dir: frames drawn by J processes at once, each keeping one OpenGL context",
        scheduler="with --out-dir: draw the frames on",
    )
    render.add_argument(
        "--gif", metavar="PATH", help="with --out-dir: also write the frames as an animated GIF"
    )
    render.add_argument(
        "--webp",
        metavar="PATH",
        help="with --out-dir: also write the frames as an animated WebP (lossless)",
    )
    render.add_argument(
        "--fps",
        metavar="N",
        default="12",
        help="frames a second of --gif and --webp (default %(default)s)",
    )
    render.add_argument(
        "--stats",
        action="store_true",
        help="print the passes each frame "
        "ran and skipped, the time planning saved against --no-plan, and "
        "how many pixels the two frames differ in",
    )
    render.add_argument(
        "--no-plan", action="store_true", help="run every pass of every frame (for comparison)"
    )
    render.add_argument("--tiny-pixels", metavar="N", help=TINY_HELP)
    render.add_argument(
        "--save-env",
        metavar="PATH",
        help="also write the first planar mirror's capture texture as a PNG",
    )
    from mirrorlab.techniques import techniques

    for entry in techniques("frame"):  # --raytrace: the whole frame by another renderer
        render.add_argument(
            f"--{entry.name}",
            dest="frame_techniques",
            action="append_const",
            const=entry.name,
            help=f"draw {entry.summary} (--method {entry.name} says the same)",
        )
    render.add_argument("--debug", action="store_true", help=DEBUG_HELP)

    plan = commands.add_parser("plan", help="print the passes each frame would run, and why")
    _add_scene_arguments(plan)
    plan.add_argument("--size", default="512x512", help="WIDTHxHEIGHT (default %(default)s)")
    plan.add_argument(
        "--frames",
        metavar="N",
        default="2",
        help="frames to plan (default %(default)s; later frames reuse what earlier ones captured)",
    )
    plan.add_argument("--json", action="store_true", help="print the plans as JSON")
    plan.add_argument("--no-plan", action="store_true", help="plan every pass to run")
    plan.add_argument("--tiny-pixels", metavar="N", help=TINY_HELP)

    bench = commands.add_parser("bench", help="measure error against the ray tracer, and time")
    benchmarks = bench.add_subparsers(dest="what", required=True, metavar="BENCHMARK")
    accuracy = benchmarks.add_parser(
        "accuracy", help="every technique's error against the ray-traced truth, and its time"
    )
    accuracy.add_argument(
        "--quick",
        action="store_true",
        help="a small sweep (128-pixel frames, maps 64 and 128, few viewpoints)",
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
    _add_executor_arguments(
        accuracy,
        jobs="ray trace the truths and score the frames in J processes; the timed "
        "frames stay in this process, run while the others are idle",
        scheduler="trace and score on",
    )
    accuracy.add_argument(
        "--scene",
        default="all",
        help="lab (the mirror techniques), sphere (the environment maps), "
        "all (default), or a scene file: every technique its reflectors "
        "can use",
    )
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

    from mirrorlab.app.controls import control_lines

    demo = commands.add_parser(
        "demo",
        help="open a window on a scene (needs a display)",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description="Open a window on a scene and change it live. It needs a display (on "
        "a machine without one: xvfb-run -a mirrorlab demo); 'mirrorlab render' needs none.",
        epilog="controls in the window (H shows them there too):\n  "
        + "\n  ".join(control_lines(16)),
    )
    _add_scene_arguments(demo)
    demo.add_argument("--size", default="800x800", help="window WIDTHxHEIGHT (default %(default)s)")
    demo.add_argument(
        "--max-frames",
        metavar="N",
        default="0",
        help="close after this many frames (0: run until Esc or the window closes)",
    )
    demo.add_argument(
        "--screenshot", metavar="PATH", help="write the last frame as a PNG when the demo ends"
    )
    demo.add_argument(
        "--shot-dir",
        metavar="DIR",
        default=".",
        help="where S saves screenshots, as demo-SCENE-NNN.png (default: the current folder)",
    )
    demo.add_argument("--debug", action="store_true", help=DEBUG_HELP)

    commands.add_parser("techniques", help="list the reflection techniques")

    lab = commands.add_parser("lab", help="start, check, run, release and grade the lab exercises")
    lab_commands = lab.add_subparsers(dest="lab_command", required=True, metavar="ACTION")
    from mirrorlab.labs import lab_names

    lab_help = f"{', '.join(lab_names())} (or the lab's folder name)"
    limits = argparse.ArgumentParser(add_help=False)
    limits.add_argument(
        "--timeout",
        metavar="SECONDS",
        default="20",
        help="CPU-time limit of one submission (default %(default)s); it may "
        "take three times as long on the clock, plus 30 s",
    )
    limits.add_argument(
        "--memory",
        metavar="MB",
        default="1536",
        help="memory limit of one submission (default %(default)s)",
    )
    solutions = argparse.ArgumentParser(add_help=False)
    solutions.add_argument(
        "--solutions",
        metavar="DIR",
        help="the teacher's solutions (the repository's labs/solutions; "
        "default $MIRRORLAB_SOLUTIONS): references are made from them",
    )
    start = lab_commands.add_parser(
        "start", help="write a lab's handout (README.md) and starter.py into a folder"
    )
    start.add_argument("lab_name", metavar="LAB", help=lab_help)
    start.add_argument("folder", metavar="DIR", help="a new or empty folder")
    check = lab_commands.add_parser(
        "check",
        parents=[limits, solutions],
        help="check one file: each task passed or failed, with a hint; exit 0 only when all pass",
    )
    check.add_argument("lab_name", metavar="LAB", help=lab_help)
    check.add_argument(
        "file",
        metavar="FILE",
        nargs="?",
        help="the student's file (default: starter.py of the current folder, "
        "where lab start puts it); a variant.json beside it (from lab release) "
        "names its variant",
    )
    check.add_argument(
        "--out", help="the picture student | reference | difference (default out/LAB_check.png)"
    )
    run = lab_commands.add_parser(
        "run", help="run a lab file in a window (the file itself runs in the sandbox)"
    )
    run.add_argument("lab_name", metavar="LAB")
    run.add_argument("file", metavar="FILE", nargs="?")
    run.add_argument("--size", default="512x512", help="WIDTHxHEIGHT (default %(default)s)")
    run.add_argument(
        "--max-frames", metavar="N", default="0", help="close after this many frames (0: until Esc)"
    )
    run.add_argument("--screenshot", metavar="PATH", help="write the last frame as a PNG")
    grade = lab_commands.add_parser(
        "grade",
        parents=[limits, solutions],
        help="grade a folder of submissions: grades.csv, "
        "gradebook.csv, feedback pages, pictures and report.html",
    )
    grade.add_argument("lab_name", metavar="LAB")
    grade.add_argument(
        "submissions", metavar="SUBMISSIONS_DIR", help="one .py file or one folder per student"
    )
    _add_executor_arguments(grade, jobs="submissions graded at once", scheduler="grade on")
    grade.add_argument(
        "--out-dir",
        metavar="DIR",
        help="where grades.csv, report.html and the pictures go (default: "
        "SUBMISSIONS_DIR-grades beside the submissions)",
    )
    grade.add_argument(
        "--key",
        metavar="KEYFILE",
        help="the course key the class was "
        "released with: each student is judged against their own variant "
        "(needs --students)",
    )
    grade.add_argument(
        "--students",
        metavar="FILE",
        help="the class list (one name a line, "
        "as for lab release): submissions by other names are reported and not "
        "graded",
    )
    grade.add_argument(
        "--copies",
        metavar="POLICY",
        default="flag",
        help="a file carrying another student's variant or the lab's own, in "
        "gradebook.csv: flag (the score as judged, copy_of names whose), zero "
        "(score 0) or hold (no score until you decide); default %(default)s",
    )
    grade.add_argument(
        "--unsandboxed",
        action="store_true",
        help="grade even where there is no sandbox (bubblewrap, Linux only): "
        "each submission then runs as you, able to read and write what you "
        "can; without it, grading there stops (exit 2)",
    )
    release = lab_commands.add_parser(
        "release",
        parents=[limits, solutions],
        help="one folder per student: a handout and starter "
        "with the student's own numbers, and their reference",
    )
    release.add_argument("lab_name", metavar="LAB")
    release.add_argument("out", metavar="OUT", help="where the students' folders go")
    release.add_argument(
        "--students", metavar="FILE", required=True, help="the class list: one name a line"
    )
    release.add_argument(
        "--key",
        metavar="KEYFILE",
        required=True,
        help="the course key (made, mode 0600, if the file does not exist)",
    )
    release.add_argument(
        "--jobs",
        metavar="J",
        default="1",
        help="references made by J processes at once (default %(default)s)",
    )
    solution = lab_commands.add_parser(
        "solution",
        parents=[solutions],
        help="print one student's variant of the reference solution (teachers only)",
    )
    solution.add_argument("lab_name", metavar="LAB")
    solution.add_argument("--student", metavar="NAME", required=True)
    solution.add_argument("--key", metavar="KEYFILE", required=True)
    return parser


def check_executor(args: argparse.Namespace) -> None:
    """Before any work: ``--scheduler`` and ``--engine dask`` need Dask, an optional
    dependency; without it, one line saying what to install (exit 2)."""
    from mirrorlab.jobs import require_dask

    if getattr(args, "scheduler", None):
        require_dask("--scheduler")
    elif getattr(args, "engine", None) == "dask":
        require_dask("--engine dask")


def scene_from_args(args: argparse.Namespace) -> Scene:
    """The scene the arguments name, with the scene options applied."""
    if args.scene is not None and args.scene_file is not None and args.scene != args.scene_file:
        raise UsageError(
            f"--scene: give the scene once, got {args.scene_file!r} and {args.scene!r}"
        )
    scene = load_scene(args.scene_file or args.scene or DEFAULT_SCENE)
    values = {option.name: getattr(args, f"option_{option.name}") for option in OPTIONS}
    parsed = {}
    for option in OPTIONS:
        text = values[option.name]
        if text is None:
            continue
        if option.repeat:
            parsed[option.name] = tuple(item for t in text for item in option.parse(option.flag, t))
        else:
            parsed[option.name] = option.parse(option.flag, text)
    return apply_options(scene, parsed)


def run_render(args: argparse.Namespace) -> int:
    size = parse_size("--size", args.size)
    jobs = parse_count("--jobs", args.jobs, 1, 1024)
    fps = parse_count("--fps", args.fps, 1, 100)
    out = check_output("--out", args.out) if args.out else None
    save_env = check_output("--save-env", args.save_env) if args.save_env else None
    out_dir = check_folder("--out-dir", args.out_dir) if args.out_dir else None
    animations = [
        (kind, check_output(f"--{kind}", path, f".{kind}"))
        for kind, path in (("gif", args.gif), ("webp", args.webp))
        if path
    ]
    if out_dir is None:
        batch_only = [
            ("--jobs", jobs > 1),
            ("--scheduler", args.scheduler),
            *((f"--{kind}", True) for kind, _ in animations),
        ]
        for option, given in batch_only:
            if given:
                raise UsageError(f"{option}: works on a batch of frames; give --out-dir DIR too")
    else:
        for option, given in (("--stats", args.stats), ("--save-env", save_env)):
            if given:
                raise UsageError(
                    f"{option}: measures frames in one renderer; give it without --out-dir"
                )
    frame_technique = frame_technique_of(args)
    scene = scene_from_args(args)
    if out is None and out_dir is None:
        out = check_output("--out", Path("out") / f"{scene.name}.png", make_folder=True)
    frames = frame_list(args, scene)
    outputs = ([("--out", out)] if out else []) + ([("--save-env", save_env)] if save_env else [])
    outputs += [(f"--{kind}", path) for kind, path in animations]
    if out_dir is not None:
        from mirrorlab.batch import frame_name

        outputs += [("--out-dir", frame_name(out_dir, scene, f)) for f in frames]
    check_distinct(outputs)
    if out_dir is not None:
        from mirrorlab.batch import FrameJob, run_batch

        return run_batch(
            FrameJob(
                scene,
                size,
                not args.no_plan,
                frame_technique,
                args.debug,
                tiny_pixels=tiny_pixels_of(args),
            ),
            frames,
            out_dir,
            jobs,
            args.scheduler,
            args.engine,
            out,
            animations,
            fps,
        )
    from mirrorlab.commands.render import run_render as render

    assert out is not None
    return render(
        scene,
        size,
        out,
        frames,
        args.stats,
        not args.no_plan,
        save_env,
        frame_technique,
        debug=args.debug,
        tiny_pixels=tiny_pixels_of(args),
    )


def frame_technique_of(args: argparse.Namespace) -> str | None:
    """The technique drawing the whole frame (``--raytrace``, or ``--method`` naming one),
    taken out of the scene options; None for OpenGL."""
    from mirrorlab.techniques import frame_technique

    named = list(dict.fromkeys(args.frame_techniques or []))
    if frame_technique(args.option_method) is not None:
        named.append(args.option_method)
        args.option_method = None
    named = list(dict.fromkeys(named))
    if len(named) > 1:
        raise UsageError(f"--{named[1]}: the frame is drawn by one of {', '.join(named)}, not all")
    return named[0] if named else None


def check_distinct(outputs: list[tuple[str, Path]]) -> None:
    """UsageError when two of a command's outputs are one file: one would silently
    replace the other (``--out a.png --save-env a.png``)."""
    seen: dict[Path, str] = {}
    for option, path in outputs:
        key = path.resolve()
        if key in seen:
            raise UsageError(
                f"{option}: {path} is also the file of {seen[key]}; give each output its own file"
            )
        seen[key] = option


def frame_list(args: argparse.Namespace, scene: Scene) -> list[int]:
    if args.frame is not None and args.frames is not None:
        raise UsageError("--frame and --frames: give one or the other")
    if args.frames is not None:
        count = parse_count("--frames", args.frames, 1, 100_000)
        if scene.animation is not None and count > scene.frame_count:
            raise UsageError(
                f"--frames: scene {scene.name} has {scene.frame_count} frames, got {count}"
            )
        return list(range(count))
    frame = parse_count("--frame", args.frame, 0, 100_000) if args.frame is not None else 0
    if frame >= scene.frame_count and scene.animation is not None:
        raise UsageError(
            f"--frame: scene {scene.name} has frames 0 to {scene.frame_count - 1}, got {frame}"
        )
    return [frame]


def run_plan(args: argparse.Namespace) -> int:
    from mirrorlab.commands.plan import run_plan as plan

    size = parse_size("--size", args.size)
    frames = parse_count("--frames", args.frames, 1, 10_000)
    return plan(
        scene_from_args(args),
        size,
        frames,
        args.json,
        not args.no_plan,
        tiny_pixels=tiny_pixels_of(args),
    )


def run_bench(args: argparse.Namespace) -> int:
    if args.what == "speed":
        return run_speed(args)
    from mirrorlab.accuracy import SweepSettings, run_command

    changes: dict = {}
    if args.frame:
        changes["frame"] = parse_count("--frame", args.frame, 16, 4096)
    if args.sizes:
        changes["sizes"] = parse_counts("--sizes", args.sizes, 1, 8192)
    if args.frames:
        changes["frames"] = parse_count("--frames", args.frames, 1, 10000)
    jobs = parse_count("--jobs", args.jobs, 1, 1024)
    out_dir = check_folder("--out-dir", args.out_dir)
    settings = SweepSettings.quick() if args.quick else SweepSettings()
    from dataclasses import replace

    settings = replace(settings, **changes)
    scenes: str | Scene = args.scene
    if args.scene not in ("lab", "sphere", "all"):
        scenes = load_scene(args.scene)
    return run_command(
        settings,
        scenes,
        out_dir,
        Path(args.from_csv) if args.from_csv else None,
        jobs=jobs,
        scheduler=args.scheduler,
        engine=args.engine,
    )


def run_speed(args: argparse.Namespace) -> int:
    from dataclasses import replace

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


def run_demo(args: argparse.Namespace) -> int:
    size = parse_size("--size", args.size)
    max_frames = parse_count("--max-frames", args.max_frames, 0, 10**9)
    screenshot = check_output("--screenshot", args.screenshot) if args.screenshot else None
    shot_dir = Path(args.shot_dir)
    if not shot_dir.is_dir():
        raise UsageError(f"--shot-dir: {args.shot_dir!r} is not a folder")
    scene = scene_from_args(args)

    from mirrorlab.gl.context import prepare

    prepare("window")  # before anything imports OpenGL in this process
    from mirrorlab.app.demo import run

    return run(
        scene,
        size,
        max_frames=max_frames,
        screenshot=screenshot,
        debug=args.debug,
        shot_dir=shot_dir,
    )


def run_techniques(args: argparse.Namespace) -> int:
    from mirrorlab.techniques import techniques

    for entry in techniques():
        print(f"{entry.name:<14} {entry.kind:<7} {entry.summary}")
    return 0


def run_lab(args: argparse.Namespace) -> int:
    action = args.lab_command
    if action == "start":
        from mirrorlab.labs.trusted.release import run_start

        return run_start(args.lab_name, Path(args.folder))
    if action == "solution":
        from mirrorlab.labs.trusted.release import run_solution

        return run_solution(args.lab_name, args.student, Path(args.key), args.solutions)
    if action == "run":
        from mirrorlab.labs.trusted.window import run_window

        size = parse_size("--size", args.size)
        max_frames = parse_count("--max-frames", args.max_frames, 0, 10**9)
        screenshot = check_output("--screenshot", args.screenshot) if args.screenshot else None
        return run_window(args.lab_name, args.file, size, max_frames, screenshot)
    from mirrorlab.labs.trusted.sandbox import Limits

    cpu = parse_count("--timeout", args.timeout, 1, 3600)
    limits = Limits(
        cpu_seconds=cpu,
        seconds=3.0 * cpu + 30,
        memory_mb=parse_count("--memory", args.memory, 256, 1 << 20),
        # without a sandbox: one's own file or solutions, or a grade told so
        unsandboxed=action != "grade" or args.unsandboxed,
    )
    if action == "check":
        from mirrorlab.labs.trusted.checker import run_check

        out = check_output("--out", args.out) if args.out else None
        return run_check(args.lab_name, args.file, out, limits, args.solutions)
    if action == "release":
        from mirrorlab.labs.trusted.release import run_release

        jobs = parse_count("--jobs", args.jobs, 1, 1024)
        return run_release(
            args.lab_name,
            Path(args.out),
            Path(args.students),
            Path(args.key),
            args.solutions,
            jobs,
            limits,
        )
    from mirrorlab.labs.trusted.grading import run_grade

    jobs = parse_count("--jobs", args.jobs, 1, 1024)
    return run_grade(
        args.lab_name,
        Path(args.submissions),
        jobs,
        args.scheduler,
        args.engine,
        Path(args.out_dir) if args.out_dir else None,
        limits,
        Path(args.key) if args.key else None,
        args.solutions,
        Path(args.students) if args.students else None,
        args.copies,
    )


_VECTOR_FLAGS = (*tuple(o.flag for o in OPTIONS if "," in o.metavar), "--fovy", "--size")


def join_negative_vectors(argv: Sequence[str]) -> list[str]:
    """``['--target', '-4,1,-2']`` -> ``['--target=-4,1,-2']``: argparse would otherwise
    take a leading minus for an option."""
    out: list[str] = []
    tokens = list(argv)
    i = 0
    while i < len(tokens):
        token = tokens[i]
        following = tokens[i + 1] if i + 1 < len(tokens) else ""
        if token in _VECTOR_FLAGS and re.match(r"^-[\d.]", following):
            out.append(f"{token}={following}")
            i += 2
        else:
            out.append(token)
            i += 1
    return out


def _close_progress_bars() -> None:
    """Close the tqdm bars an interrupt left open, so the next line starts a line."""
    tqdm_module = sys.modules.get("tqdm")
    if tqdm_module is None:
        return
    for bar in list(getattr(tqdm_module.tqdm, "_instances", ())):
        try:
            bar.close()
        except Exception:  # a bar interrupted while it was being made
            pass


BAD_INPUT = (
    UsageError,
    OptionError,
    OutputError,
    SceneError,
    WriteError,
    ValueError,
    FileNotFoundError,
)


def main(argv: Sequence[str] | None = None) -> int:
    """Run one command; returns its exit status: 0 done, 2 bad input (including a write
    the system refuses and a size the GL cannot allocate), 1 a problem with the machine
    (no display, no OpenGL, an OpenGL too old or failing), 130 interrupted (Ctrl-C).
    Every failure is one line on stderr, never a traceback or a numpy warning."""
    command = "mirrorlab"
    try:
        parser = build_parser()
        args = parser.parse_args(join_negative_vectors(sys.argv[1:] if argv is None else argv))
        command = f"mirrorlab {args.command}"
        check_executor(args)
        runners = {
            "render": run_render,
            "plan": run_plan,
            "bench": run_bench,
            "demo": run_demo,
            "techniques": run_techniques,
            "lab": run_lab,
        }
        with warnings.catch_warnings():
            # A numeric warning means a value out of range slipped past the checks: stop
            # with one line rather than print numpy's warning and go on.
            warnings.simplefilter("error", RuntimeWarning)
            return runners[args.command](args)
    except KeyboardInterrupt:
        _close_progress_bars()
        # An interrupt inside a progress bar's own drawing can leave its line open: go
        # back to the line's start (and, on a terminal, clear it) before the message.
        clear = "\r\033[K" if sys.stderr.isatty() else "\r"
        print(f"{clear}{command}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except RuntimeWarning as exc:
        print(
            f"{command}: error: a value is out of range for the computation ({exc})",
            file=sys.stderr,
        )
        return EXIT_BAD_INPUT
    except BAD_INPUT as exc:
        print(f"{command}: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except OSError as exc:  # reading a file the checks let through
        where = exc.filename or "a file"
        print(f"{command}: error: cannot read {where}: {exc.strerror or exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except (GLContextError, GLPassError, BatchError, BenchmarkError) as exc:
        print(f"{command}: error: {exc}", file=sys.stderr)
        return EXIT_MACHINE
    except Exception as exc:
        from mirrorlab.labs.trusted.checker import CheckError
        from mirrorlab.labs.trusted.gl_process import CheckerError
        from mirrorlab.labs.trusted.sandbox import SandboxError

        if isinstance(exc, SandboxError | CheckError):
            print(f"{command}: error: {exc}", file=sys.stderr)
            return EXIT_BAD_INPUT
        if isinstance(exc, CheckerError):
            print(f"{command}: error: {exc}", file=sys.stderr)
            return EXIT_MACHINE
        raise


if __name__ == "__main__":
    sys.exit(main())
