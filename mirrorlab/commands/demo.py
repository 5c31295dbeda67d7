"""``mirrorlab demo``: its arguments; the window itself is :mod:`mirrorlab.app.demo`."""

from __future__ import annotations

import argparse
from pathlib import Path

from mirrorlab.commands.arguments import (
    DEBUG_HELP,
    UsageError,
    add_scene_arguments,
    scene_from_args,
)
from mirrorlab.files import check_output
from mirrorlab.options import parse_count, parse_size

NAME = "demo"


def add_parser(commands: argparse._SubParsersAction) -> None:
    """The ``demo`` command's arguments, as a subcommand of ``commands``."""
    from mirrorlab.app.controls import control_lines

    demo = commands.add_parser(
        NAME,
        help="open a window on a scene (needs a display)",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description="Open a window on a scene and change it live. It needs a display (on "
        "a machine without one: xvfb-run -a mirrorlab demo); 'mirrorlab render' needs none.",
        epilog="controls in the window (H shows them there too):\n  "
        + "\n  ".join(control_lines(16)),
    )
    add_scene_arguments(demo)
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


def run(args: argparse.Namespace) -> int:
    """``mirrorlab demo``: the arguments checked, then the window until it closes."""
    size = parse_size("--size", args.size)
    max_frames = parse_count("--max-frames", args.max_frames, 0, 10**9)
    screenshot = check_output("--screenshot", args.screenshot) if args.screenshot else None
    shot_dir = Path(args.shot_dir)
    if not shot_dir.is_dir():
        raise UsageError(f"--shot-dir: {args.shot_dir!r} is not a folder")
    scene = scene_from_args(args)

    from mirrorlab.gl.context import prepare

    prepare("window")  # before anything imports OpenGL in this process
    from mirrorlab.app import demo

    return demo.run(
        scene,
        size,
        max_frames=max_frames,
        screenshot=screenshot,
        debug=args.debug,
        shot_dir=shot_dir,
    )
