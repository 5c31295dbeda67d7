"""``mirrorlab render``: its arguments, and without ``--out-dir`` its work: one picture
(the last of the frames drawn), with what the planner ran and saved. With ``--out-dir``
the frames are a batch: see :mod:`mirrorlab.batch`."""

from __future__ import annotations

import argparse
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from mirrorlab.commands.arguments import (
    DEBUG_HELP,
    TINY_HELP,
    UsageError,
    add_executor_arguments,
    add_scene_arguments,
    scene_from_args,
    tiny_pixels_of,
)
from mirrorlab.files import Outputs, check_folder, check_output
from mirrorlab.options import parse_count, parse_size
from mirrorlab.plan import TINY_PIXELS
from mirrorlab.scene.model import Scene

NAME = "render"


def add_parser(commands: argparse._SubParsersAction) -> None:
    """The ``render`` command's arguments, as a subcommand of ``commands``."""
    render = commands.add_parser(NAME, help="render a scene headless to a PNG")
    add_scene_arguments(render)
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
    add_executor_arguments(
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
    render.add_argument(
        "--save-ssr-mask",
        metavar="PATH",
        help="also write the miss mask of screen-space reflections (technique ssr) as a "
        "PNG: white where a reflector pixel's ray was found on the screen (grey where it "
        "fades into the probe), a colour for each reason it fell back to the probe",
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


def run(args: argparse.Namespace) -> int:
    """``mirrorlab render``: every argument checked (and every output path) before any
    drawing; one picture, or with ``--out-dir`` a batch."""
    size = parse_size("--size", args.size)
    jobs = parse_count("--jobs", args.jobs, 1, 1024)
    fps = parse_count("--fps", args.fps, 1, 100)
    out = check_output("--out", args.out) if args.out else None
    save_env = check_output("--save-env", args.save_env) if args.save_env else None
    save_mask = check_output("--save-ssr-mask", args.save_ssr_mask) if args.save_ssr_mask else None
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
        for option, given in (
            ("--stats", args.stats),
            ("--save-env", save_env),
            ("--save-ssr-mask", save_mask),
        ):
            if given:
                raise UsageError(
                    f"{option}: measures frames in one renderer; give it without --out-dir"
                )
    frame_technique = frame_technique_of(args)
    scene = scene_from_args(args)
    if out is None and out_dir is None:
        out = check_output("--out", Path("out") / f"{scene.name}.png", make_folder=True)
    frames = frame_list(args, scene)
    if save_mask is not None:
        from mirrorlab.techniques import technique

        if frame_technique is not None:
            raise UsageError(
                f"--save-ssr-mask: the frame is drawn by {frame_technique}; screen-space "
                "reflections are drawn by OpenGL (--method ssr)"
            )
        if not any(technique(r.technique).texture == "screen" for r in scene.reflectors):
            raise UsageError(
                f"--save-ssr-mask: scene {scene.name} has no reflector drawn by screen-space "
                "reflections (--method ssr makes every reflector one)"
            )
    outputs = ([("--out", out)] if out else []) + ([("--save-env", save_env)] if save_env else [])
    outputs += [("--save-ssr-mask", save_mask)] if save_mask else []
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
    assert out is not None
    return render_frames(
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
        save_mask=save_mask,
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
    """The frames ``--frame`` or ``--frames`` name, checked against the scene's animation."""
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


def render_frames(
    scene: Scene,
    size: tuple[int, int],
    out: Path,
    frames: list[int],
    stats: bool = False,
    use_plan: bool = True,
    save_env: Path | None = None,
    frame_technique: str | None = None,
    say: Callable[[str], None] = print,
    debug: bool = False,
    tiny_pixels: float = TINY_PIXELS,
    save_mask: Path | None = None,
) -> int:
    """Render ``frames`` of ``scene`` in order; the last goes to ``out`` (with ``save_env``,
    its capture texture too; with ``save_mask``, the miss mask of its screen-space
    reflections), all files together at the end, or none. With ``stats``, each
    frame is also drawn with every pass (--no-plan) by a second renderer, in turn with the
    planned one, so both are timed under the same conditions, and the two frames are
    compared pixel for pixel. ``frame_technique`` names a technique that draws the whole
    frame instead of OpenGL (:mod:`mirrorlab.techniques`). ``debug`` checks the GL's debug
    messages after every pass. ``tiny_pixels`` above 0 turns on the planner's lossy
    small-reflector rule."""
    start = time.perf_counter()
    with Outputs() as outputs:
        if frame_technique is not None:
            from mirrorlab.techniques import technique

            draw_frame = technique(frame_technique).frame_function()
            for frame in frames:
                image = draw_frame(scene.at_frame(frame), size, progress=True)
            outputs.add_png(out, image)
            if save_env is not None:
                say(f"no capture texture when drawn by {frame_technique}; {save_env} not written")
            say(
                f"wrote {out} ({size[0]}x{size[1]}, {scene.name}, drawn by "
                f"{frame_technique}, {(time.perf_counter() - start) * 1e3:.0f} ms)"
            )
            return 0
        from mirrorlab.api import Renderer

        with Renderer(size, debug=debug) as renderer, Renderer(size, debug=debug) as unplanned:
            records = []
            comparison: list[tuple[int, float, np.ndarray]] = []
            image = None
            compare = stats and use_plan
            if compare:  # one untimed frame each: start-up work (shaders, meshes) is paid
                for warm in (renderer, unplanned):
                    warm.render(scene, frame=frames[0], use_plan=False)
                    warm.scene_renderer.state.clear()  # and forgotten: frame 0 captures
            for index, frame in enumerate(frames):
                if compare and index % 2:  # take turns at going first
                    comparison.append(_unplanned(unplanned, scene, frame))
                began = time.perf_counter()
                image = renderer.render(
                    scene, frame=frame, use_plan=use_plan, tiny_pixels=tiny_pixels
                )
                elapsed = (time.perf_counter() - began) * 1e3
                assert renderer.last_stats is not None
                records.append((frame, renderer.last_stats, elapsed, image))
                if compare and not index % 2:
                    comparison.append(_unplanned(unplanned, scene, frame))
            assert image is not None
            outputs.add_png(out, image)
            environment = _environment(renderer, scene) if save_env is not None else None
            if save_env is not None and environment is not None:
                outputs.add_png(save_env, environment)
            mask = renderer.ssr_mask() if save_mask is not None else None
            if save_mask is not None and mask is not None:
                outputs.add_png(save_mask, mask.image())
            gl_renderer = renderer.gl_renderer
            described = renderer.gl_description if stats else None
    last = records[-1][1]
    total = (time.perf_counter() - start) * 1e3
    say(
        f"wrote {out} ({size[0]}x{size[1]}, {scene.name}, "
        f"{'frame' if len(frames) == 1 else 'frames'} {_span(frames)}, last frame's passes: "
        f"{' + '.join(last.ran)}, {total:.0f} ms with start-up, {gl_renderer})"
    )
    if save_env is not None:
        if environment is None:
            say(f"scene {scene.name} has no capture texture to save; {save_env} not written")
        else:
            say(
                f"wrote {save_env} (capture texture, {environment.shape[1]}x{environment.shape[0]})"
            )
    if save_mask is not None and mask is not None:
        shares = (
            "no reflector pixel drawn by ssr"
            if not mask.reflector.any()
            else f"{100 * mask.miss_share:.1f}% of its reflector pixels fell back to the probe"
        )
        say(f"wrote {save_mask} (screen-space reflections' miss mask: {shares})")
    if described is not None:
        from mirrorlab.gl.context import summary

        say(f"OpenGL: {summary(described)}; draw path {described['draw_path']}")
    if stats:
        _report(records, comparison, use_plan, say)
    return 0


def _span(frames: list[int]) -> str:
    return str(frames[0]) if len(frames) == 1 else f"{frames[0]}-{frames[-1]}"


def _environment(renderer, scene: Scene) -> np.ndarray | None:
    """The capture texture the camera's view of the first capturing planar mirror used."""
    from mirrorlab.scene.model import PlanarReflector

    plan = renderer.last_stats.plan
    for draw in plan.top.draws:
        if isinstance(draw.reflector, PlanarReflector) and draw.mode == "texture":
            return renderer.read_texture(draw.reflector.name, slot=draw.slot)
    from mirrorlab.techniques import technique

    for reflector in scene.reflectors:
        if (
            isinstance(reflector, PlanarReflector)
            and not technique(reflector.technique).draws_inline
        ):
            try:
                return renderer.read_texture(reflector.name)
            except ValueError:
                return None
    return None


def _unplanned(renderer, scene: Scene, frame: int) -> tuple[int, float, np.ndarray]:
    """Passes run, milliseconds and the picture of ``frame`` drawn with every pass
    (--no-plan)."""
    began = time.perf_counter()
    image = renderer.render(scene, frame=frame, use_plan=False)
    return len(renderer.last_stats.plan.ran), (time.perf_counter() - began) * 1e3, image


def differing_pixels(a: np.ndarray, b: np.ndarray) -> int:
    """How many pixels of two ``(h, w, 3)`` pictures differ in any channel."""
    return int(np.count_nonzero((a != b).any(axis=-1)))


def _report(records, comparison, use_plan: bool, say: Callable[[str], None]) -> None:
    differing = [
        differing_pixels(image, unplanned)
        for (*_, image), (*_, unplanned) in zip(records, comparison, strict=False)
    ]
    for index, (frame, stats, elapsed, _) in enumerate(records):
        skips = f"; skipped {', '.join(stats.skipped)}" if stats.skipped else ""
        against = ""
        if index < len(differing):
            against = (
                "; the same as --no-plan"
                if not differing[index]
                else f"; {differing[index]} pixels differ from --no-plan"
            )
        say(f"frame {frame}: ran {', '.join(stats.ran)}{skips} ({elapsed:.1f} ms{against})")
    ran = [len(stats.plan.ran) for _, stats, _, _ in records]
    skipped = [len(stats.plan.skipped) for _, stats, _, _ in records]
    times = [elapsed for _, _, elapsed, _ in records]
    label = "planned" if use_plan else "every pass (--no-plan)"
    say(
        f"{label}: {sum(ran)} passes run and {sum(skipped)} skipped over {len(records)} "
        f"frames; median {np.median(times):.2f} ms a frame, {sum(times):.0f} ms in all"
    )
    if comparison:
        passes = sum(count for count, _, _ in comparison)
        unplanned = [ms for _, ms, _ in comparison]
        say(
            f"--no-plan on the same frames: {passes} passes run; median "
            f"{np.median(unplanned):.2f} ms a frame, {sum(unplanned):.0f} ms in all; planning "
            f"saved {passes - sum(ran)} passes and {sum(unplanned) - sum(times):.0f} ms "
            f"({_share(sum(times), sum(unplanned))})"
        )
        changed = [d for d in differing if d]
        if not changed:
            say(
                f"planned and --no-plan frames are the same, pixel for pixel, in all "
                f"{len(differing)} frames"
            )
        else:
            say(
                f"planned and --no-plan frames differ in {len(changed)} of {len(differing)} "
                f"frames: {sum(changed)} pixels in all, at most {max(changed)} in a frame"
            )


def _share(planned: float, unplanned: float) -> str:
    if unplanned <= 0:
        return "no time to compare"
    return f"{100.0 * (1.0 - planned / unplanned):.0f}% of the unplanned time"
