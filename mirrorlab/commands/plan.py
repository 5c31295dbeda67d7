"""``mirrorlab plan``: the passes each frame of a scene would run, and why, worked out
without drawing anything (no OpenGL): what a capture leaves in its texture is recorded
as if it had run."""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable
from typing import TYPE_CHECKING

from mirrorlab.commands.arguments import (
    TINY_HELP,
    add_scene_arguments,
    scene_from_args,
    tiny_pixels_of,
)
from mirrorlab.options import parse_count, parse_size
from mirrorlab.plan import TINY_PIXELS, FramePlan, TextureState, plan_frame
from mirrorlab.scene.model import Scene

if TYPE_CHECKING:
    from mirrorlab.budget.chooser import BudgetFrame

NAME = "plan"


def add_parser(commands: argparse._SubParsersAction) -> None:
    """The ``plan`` command's arguments, as a subcommand of ``commands``."""
    plan = commands.add_parser(NAME, help="print the passes each frame would run, and why")
    add_scene_arguments(plan)
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


def run(args: argparse.Namespace) -> int:
    """``mirrorlab plan``: the arguments checked, then the plans printed."""
    size = parse_size("--size", args.size)
    frames = parse_count("--frames", args.frames, 1, 10_000)
    return print_plans(
        scene_from_args(args),
        size,
        frames,
        args.json,
        not args.no_plan,
        tiny_pixels=tiny_pixels_of(args),
    )


def plan_frames(
    scene: Scene,
    size: tuple[int, int],
    frames: int,
    use_plan: bool = True,
    tiny_pixels: float = TINY_PIXELS,
    choices: list[BudgetFrame] | None = None,
) -> list[FramePlan]:
    """The plans of frames 0 .. ``frames`` - 1, each knowing what the earlier ones made.
    Under the scene's budget each frame's reflectors are first chosen (one chooser for
    the frames, in order), and each choice appended to ``choices`` when given."""
    state = TextureState()
    plans = []
    chooser = None
    if scene.budget is not None:
        from mirrorlab.budget.chooser import BudgetChooser

        chooser = BudgetChooser()
    for frame in range(frames):
        posed = scene.at_frame(min(frame, scene.frame_count - 1))
        if chooser is not None:
            posed, chosen = chooser.choose(posed, size)
            if choices is not None:
                choices.append(chosen)
        plan = plan_frame(posed, size, state, use_plan, tiny_pixels)
        for step in plan.ran:
            if step.reflector is not None:
                state.record(step)
        plans.append(plan)
    return plans


def plan_document(plans: list[FramePlan], choices: list[BudgetFrame] | None = None) -> list[dict]:
    """The plans as JSON-ready dicts: each frame's passes and how each reflector is drawn
    (and, under a budget, the choice: every candidate's predictions)."""
    document = []
    for frame, plan in enumerate(plans):
        entry: dict = {
            "frame": frame,
            "passes": [step.as_dict() for step in plan.passes],
            "draws": [
                {
                    "reflector": d.reflector.name,
                    "technique": d.reflector.technique,
                    "mode": d.mode,
                    "reason": d.reason,
                }
                for d in plan.top.draws
            ],
        }
        if choices:
            entry["budget"] = choices[frame].as_dict()
        document.append(entry)
    return document


def print_plans(
    scene: Scene,
    size: tuple[int, int],
    frames: int,
    as_json: bool,
    use_plan: bool,
    say: Callable[[str], None] = print,
    tiny_pixels: float = TINY_PIXELS,
) -> int:
    """Say (print) the plans of frames 0 .. ``frames`` - 1 of ``scene`` at ``size``: each
    frame's passes run and skipped with their reasons, or with ``as_json`` one JSON
    document; returns the exit status, 0."""
    choices: list[BudgetFrame] = []
    plans = plan_frames(scene, size, frames, use_plan, tiny_pixels, choices)
    if as_json:
        say(
            json.dumps(
                {
                    "scene": scene.name,
                    "size": list(size),
                    "frames": plan_document(plans, choices),
                },
                indent=2,
            )
        )
        return 0
    for frame, plan in enumerate(plans):
        ran = sum(1 for p in plan.passes if p.runs)
        say(
            f"frame {frame}: {ran} pass{'es' if ran != 1 else ''} run, "
            f"{len(plan.passes) - ran} skipped"
        )
        if choices:
            for line in choices[frame].describe(candidates=not choices[frame].repeated):
                say(f"  {line}")
        for line in plan.describe():
            say(f"  {line}")
    return 0
