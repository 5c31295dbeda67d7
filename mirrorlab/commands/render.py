"""``mirrorlab render`` without ``--out-dir``: one picture (the last of the frames drawn),
with what the planner ran and saved. With ``--out-dir`` the frames are a batch: see
:mod:`mirrorlab.batch`."""

from __future__ import annotations

import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from mirrorlab.files import Outputs
from mirrorlab.plan import TINY_PIXELS
from mirrorlab.scene.model import Scene


def run_render(
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
) -> int:
    """Render ``frames`` of ``scene`` in order; the last goes to ``out`` (with ``save_env``,
    its capture texture too), all files together at the end, or none. With ``stats``, each
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
            gl_renderer = renderer.gl_renderer
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
