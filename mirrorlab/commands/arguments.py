"""The arguments several commands share, and their reading: the scene and its changes
(``render``, ``plan``, ``demo``), where independent jobs run (``render --out-dir``,
``bench accuracy``, ``lab grade``), ``--debug`` and ``--tiny-pixels``."""

from __future__ import annotations

import argparse

from mirrorlab.options import OPTIONS, apply_options, parse_count
from mirrorlab.scene.loader import DEFAULT_SCENE, load_scene, shipped_scene_names
from mirrorlab.scene.model import Scene


class UsageError(Exception):
    """Bad input from the command line; the message is shown as is."""


DEBUG_HELP = (
    "a debug OpenGL context whose KHR_debug messages are checked after every "
    "pass: a GL error stops the command, naming the pass"
)
TINY_HELP = (
    "LOSSY: draw a reflector that may cover fewer than N pixels plain, without "
    "its capture (default 0: off, and the plan changes no pixel)"
)


def add_executor_arguments(parser: argparse.ArgumentParser, jobs: str, scheduler: str) -> None:
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


def check_executor(args: argparse.Namespace) -> None:
    """Before any work: ``--scheduler`` and ``--engine dask`` need Dask, an optional
    dependency; without it, one line saying what to install (exit 2)."""
    from mirrorlab.jobs import require_dask

    if getattr(args, "scheduler", None):
        require_dask("--scheduler")
    elif getattr(args, "engine", None) == "dask":
        require_dask("--engine dask")


def add_scene_arguments(parser: argparse.ArgumentParser) -> None:
    """``SCENE`` (or ``--scene``) and every scene change of :data:`mirrorlab.options.OPTIONS`,
    read back by :func:`scene_from_args`."""
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


def tiny_pixels_of(args: argparse.Namespace) -> float:
    """``--tiny-pixels`` as a number of pixels (0, the default, turns the rule off)."""
    return float(
        parse_count("--tiny-pixels", args.tiny_pixels, 0, 10**9)
        if args.tiny_pixels is not None
        else 0
    )
