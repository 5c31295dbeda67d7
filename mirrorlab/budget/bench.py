"""``mirrorlab bench budget``: proves that a budget held. Each scene is rendered as an
animated sequence (:func:`mirrorlab.budget.scenes.motion`: the camera swings, objects
drift, mirrors turn, spheres float; or still), and every frame is measured against the
full-resolution ray-traced truth, per reflector.

For each scene, first a **table**, by brute force: every candidate of every reflector
drawn on every frame of the sequence (the other reflectors as the scene gives them),
scored against the truth (its true error) and timed as a sequence (each frame after the
last one drawn the same way, so captures are kept or made again as they would be; the
CPU time of each frame, the median of ``repeats`` runs). A reflector's cost in a frame is
what its candidate adds to the frame drawn with every reflector as given, so a frame's
cost is that frame's cost plus each reflector's addition.

Then, for each budget, the **planner** runs over the sequence (a fresh
:class:`~mirrorlab.budget.chooser.BudgetChooser`, its own time measured), the frames it
chose are drawn and scored (their true errors), and its cost is the table's cost of its
choices plus its own time. It is compared with, by brute force over the table:

- the **per-frame oracle**: in each frame, for each reflector, the cheapest candidate
  whose true error is within the budget (none: the most accurate); with ``--max-ms``,
  the combination with the lowest error (over all the reflectors' pixels) whose cost fits;
- the **best fixed choice**: for each reflector the one candidate, kept for the whole
  sequence, that is within the budget on every frame, the cheapest such (none: there is
  no fixed choice that holds).

Reported per scene and budget and over all (``summary.json``): ``held_share`` (the share
of reflector-frames within the budget; under a time budget, of frames within the time),
``worst_overrun`` (the largest true error over the budget, or cost over the time),
``cost_vs_oracle``, ``cost_vs_best_fixed`` and, with ``--max-ms``, ``error_vs_oracle``
(the planner's mean error over the oracle's). ``budget.csv`` has a row per reflector and
frame; ``budget.png`` shows error against cost: every candidate kept fixed, their
frontier, the oracle and the planner (and the planner's frames).

The truths and the scoring go to the executor (``--jobs``, Dask) while this process
waits; the timed frames run in this process while the workers are idle.
"""

from __future__ import annotations

import csv
import io
import json
import math
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from mirrorlab.budget.candidates import Candidate, candidates_for
from mirrorlab.budget.chooser import BudgetChooser, BudgetFrame
from mirrorlab.budget.measure import (
    FrameBench,
    Score,
    Truth,
    frame_bench,
    score_images,
    trace_truth,
)
from mirrorlab.budget.model import Calibration
from mirrorlab.budget.scenes import Motion, motion
from mirrorlab.errors import BatchError
from mirrorlab.jobs import Executor, Outcome
from mirrorlab.scene.model import Budget, Scene

DEFAULT_SCENES = (
    "lab20",
    "robot_wave",
    "two_mirrors",
    "mirror_and_sphere",
    "chrome_sphere",
    "sphere_room",
    "spheremap_cone",
)
"""The shipped scenes with a reflector in view, measured when no scene is named."""


@dataclass(frozen=True)
class BenchSettings:
    """``frames`` a sequence, the frame ``size``, ``repeats`` timed runs of each
    sequence, the ``motion`` (moving or still), and the largest map a candidate may have
    (``largest``: the quick run leaves out the maps that take seconds to bake)."""

    frames: int = 16
    size: tuple[int, int] = (192, 192)
    repeats: int = 3
    motion: Motion = "moving"
    largest: int = 4096

    @classmethod
    def quick(cls) -> BenchSettings:
        """A short run that checks the benchmark works (not its figures)."""
        return cls(frames=3, size=(64, 64), repeats=1, largest=256)


@dataclass
class Table:
    """One scene's brute-force table: per reflector, its ``candidates`` and, per candidate
    and frame, the true ``errors`` (:class:`~mirrorlab.budget.measure.Score`) and the
    milliseconds it adds (``extra``) to the frame as given (``given`` per frame)."""

    candidates: list[list[Candidate]]
    errors: list[list[list[Score]]]
    extra: list[np.ndarray]
    given: np.ndarray
    visible: np.ndarray
    """``(reflectors, frames)`` bool: the reflector has pixels in the frame's truth."""
    pixels: np.ndarray
    """``(reflectors, frames)``: its pixels in the truth."""


@dataclass
class Run:
    """The planner's run under one budget: per frame its choice (:class:`BudgetFrame`),
    its own CPU milliseconds, the chosen candidate per reflector (None: as given), and
    the true errors of the frames it chose."""

    budget: Budget
    frames: list[BudgetFrame]
    plan_ms: np.ndarray
    chosen: list[list[Candidate | None]]
    errors: list[list[Score]] = field(default_factory=list)
    measured_ms: np.ndarray | None = None


@dataclass
class SceneResult:
    name: str
    reflectors: list[str]
    table: Table
    runs: list[Run]
    truth_ms: float


# --------------------------------------------------------------------------- measuring


def _truth_job(scene: Scene, size: tuple[int, int]) -> Truth:
    return trace_truth(scene, size)


def measure_scene(
    scene: Scene,
    budgets: Sequence[Budget],
    settings: BenchSettings,
    gl: FrameBench,
    executor: Executor,
    calibration: Calibration | None,
    bar,
) -> SceneResult:
    """Everything the benchmark needs of one scene (see the module's text)."""
    frames = settings.frames
    size = settings.size
    posed = [replace(motion(scene, f, frames, settings.motion), budget=None) for f in range(frames)]
    bar.set_postfix_str(f"{scene.name}: ray tracing the truths", refresh=False)
    truths: dict[int, Truth] = {}
    for outcome in executor.run(
        _truth_job, {f"truth-{f}": (posed[f], size) for f in range(frames)}
    ):
        truths[int(outcome.key.split("-")[1])] = _value(outcome, "ray tracing")
        bar.update()
    names = [r.name for r in scene.reflectors]
    candidates = [
        [c for c in candidates_for(r, posed[0]) if c.map_size <= settings.largest]
        for r in posed[0].reflectors
    ]
    # the table's sequences, timed here while the workers are idle
    given_ms = _time_sequence(gl, posed, settings, images=None)
    table_images: list[list[list[np.ndarray]]] = []
    extra: list[np.ndarray] = []
    for index, options in enumerate(candidates):
        per_candidate, costs = [], []
        for candidate in options:
            bar.set_postfix_str(f"{scene.name}: {names[index]} {candidate.label}", refresh=False)
            sequence = [_with(p, index, candidate) for p in posed]
            images: list[np.ndarray] = []
            costs.append(_time_sequence(gl, sequence, settings, images) - given_ms)
            per_candidate.append(images)
            bar.update()
        table_images.append(per_candidate)
        extra.append(np.array(costs))
    runs = []
    for budget in budgets:
        bar.set_postfix_str(f"{scene.name}: planning {budget.describe()}", refresh=False)
        run = _plan(scene, posed, budget, size, calibration, settings.largest)
        chosen_scenes = [_with_all(p, run.chosen[f]) for f, p in enumerate(posed)]
        images = []
        run.measured_ms = _time_sequence(gl, chosen_scenes, settings, images)
        run.errors = [[] for _ in range(frames)]
        runs.append((run, images))
        bar.update()
    bar.set_postfix_str(f"{scene.name}: scoring", refresh=False)
    work = {}
    for f in range(frames):
        items = []
        for r, per_candidate in enumerate(table_images):
            items += [(r, images[f]) for images in per_candidate]
        for _, images in runs:
            items += [(r, images[f]) for r in range(len(names))]
        work[f"score-{f}"] = (truths[f], items)
    scores: dict[int, list[Score]] = {}
    for outcome in executor.run(score_images, work):
        scores[int(outcome.key.split("-")[1])] = _value(outcome, "scoring")
        bar.update()
    errors: list[list[list[Score]]] = [[[] for _ in options] for options in candidates]
    for f in range(frames):
        found = iter(scores[f])
        for r, options in enumerate(candidates):
            for c in range(len(options)):
                errors[r][c].append(next(found))
        for run, _ in runs:
            run.errors[f] = [next(found) for _ in names]
    visible = np.array(
        [[truths[f].masks[r].any() for f in range(frames)] for r in range(len(names))]
    ).reshape(len(names), frames)
    pixels = np.array(
        [[int(truths[f].masks[r].sum()) for f in range(frames)] for r in range(len(names))]
    ).reshape(len(names), frames)
    table = Table(candidates, errors, extra, given_ms, visible, pixels)
    truth_ms = float(np.median([t.milliseconds for t in truths.values()]))
    return SceneResult(scene.name, names, table, [run for run, _ in runs], truth_ms)


def _with(scene: Scene, index: int, candidate: Candidate) -> Scene:
    reflectors = list(scene.reflectors)
    reflectors[index] = candidate.apply(reflectors[index])
    return replace(scene, reflectors=tuple(reflectors))


def _with_all(scene: Scene, chosen: Sequence[Candidate | None]) -> Scene:
    reflectors = tuple(
        c.apply(r) if c is not None else r for r, c in zip(scene.reflectors, chosen, strict=True)
    )
    return replace(scene, reflectors=reflectors)


def _time_sequence(
    gl: FrameBench,
    sequence: Sequence[Scene],
    settings: BenchSettings,
    images: list[np.ndarray] | None,
) -> np.ndarray:
    """CPU milliseconds of each frame of ``sequence`` drawn in order (the median of
    ``settings.repeats`` runs, each starting afresh); the first run's pictures appended
    to ``images`` when given."""
    from mirrorlab.gl.opengl import GL

    target = gl.target(settings.size)
    times = np.zeros((settings.repeats, len(sequence)))
    for run in range(settings.repeats):
        gl.forget(keep_bakes=False)
        for f, scene in enumerate(sequence):
            start = time.process_time()
            gl.renderer.render(scene, target)
            GL.glFinish()
            times[run, f] = (time.process_time() - start) * 1e3
            if run == 0 and images is not None:
                images.append(target.read())
    return np.median(times, axis=0)


def _plan(
    scene: Scene,
    posed: Sequence[Scene],
    budget: Budget,
    size: tuple[int, int],
    calibration: Calibration | None,
    largest: int,
) -> Run:
    """The planner over the sequence under ``budget``, choosing among the table's
    candidates (maps up to ``largest``): its choices and CPU time a frame."""
    chooser = BudgetChooser(calibration, largest)
    frames, times, chosen = [], [], []
    for p in posed:
        start = time.process_time()
        _, frame = chooser.choose(replace(p, budget=budget), size)
        times.append((time.process_time() - start) * 1e3)
        frames.append(frame)
        chosen.append(_candidates_of(chooser, p, frame))
    return Run(budget, frames, np.array(times), chosen)


def _candidates_of(
    chooser: BudgetChooser, posed: Scene, frame: BudgetFrame
) -> list[Candidate | None]:
    """Which candidate each reflector was drawn by (None: as the scene gives it)."""
    found: list[Candidate | None] = []
    for reflector, choice in zip(posed.reflectors, frame.choices, strict=True):
        if choice.chosen is not None:
            found.append(choice.chosen.candidate)
            continue
        match = [c for c in chooser.candidates(reflector, posed) if c.label == choice.label]
        found.append(match[0] if match else None)
    return found


def _value(outcome: Outcome, what: str):
    if outcome.error is not None:
        raise BatchError(f"{what} failed on a worker: {outcome.error}")
    return outcome.value


# --------------------------------------------------------------------------- analysis


def _error(score: Score, metric: str) -> float:
    return score.of(metric)


def _index(options: Sequence[Candidate], candidate: Candidate | None) -> int | None:
    if candidate is None:
        return None
    for i, c in enumerate(options):
        if c == candidate:
            return i
    return None


def analyse(result: SceneResult, run: Run) -> dict[str, Any]:
    """The figures of one scene under one budget (see the module's text)."""
    table = result.table
    budget = run.budget
    frames = len(table.given)
    reflectors = len(result.reflectors)
    metric = budget.metric if budget.max_error is not None else "flip"
    err = [
        np.array([[_error(s, metric) for s in scores] for scores in table.errors[r]])
        for r in range(reflectors)
    ]  # per reflector: (candidates, frames)
    chosen_index = [
        [_index(table.candidates[r], run.chosen[f][r]) for r in range(reflectors)]
        for f in range(frames)
    ]
    planner_cost = np.array(
        [
            table.given[f]
            + sum(
                table.extra[r][chosen_index[f][r], f]
                for r in range(reflectors)
                if chosen_index[f][r] is not None
            )
            for f in range(frames)
        ]
    )
    planner_total = float(planner_cost.sum() + run.plan_ms.sum())
    true = np.array(
        [[run.errors[f][r].of(metric) for r in range(reflectors)] for f in range(frames)]
    )
    visible = table.visible.T  # (frames, reflectors)
    switches = sum(
        1
        for f in range(1, frames)
        for r in range(reflectors)
        if run.chosen[f][r] != run.chosen[f - 1][r]
    )
    figures: dict[str, Any] = {
        "scene": result.name,
        "budget": budget.text(),
        "kind": "max_ms" if budget.max_ms is not None else metric,
        "frames": frames,
        "reflector_frames": int(visible.sum()),
        "planner_ms": planner_total,
        "plan_ms": float(run.plan_ms.sum()),
        "measured_planner_ms": float(np.sum(run.measured_ms))
        if run.measured_ms is not None
        else math.nan,
        "switches": switches,
        "switches_after_first": switches,
        "frame_ms": float(np.median(planner_cost)),
        "truth_ms": result.truth_ms,
    }
    if budget.max_error is not None:
        limit = budget.max_error
        scored = visible & np.isfinite(true)
        held = (true <= limit) & scored
        figures["held_share"] = float(held.sum() / max(scored.sum(), 1)) if scored.any() else 1.0
        figures["worst_overrun"] = (
            float(np.nanmax(np.where(scored, true, np.nan)) / limit) if scored.any() else 0.0
        )
        oracle_cost = table.given.copy()
        for r in range(reflectors):
            for f in range(frames):
                within = np.flatnonzero(err[r][:, f] <= limit)
                if not table.visible[r, f]:
                    pick = int(np.argmin(table.extra[r][:, f]))
                elif len(within):
                    pick = int(within[np.argmin(table.extra[r][within, f])])
                else:
                    pick = int(np.nanargmin(err[r][:, f]))
                oracle_cost[f] += table.extra[r][pick, f]
        figures["oracle_ms"] = float(oracle_cost.sum())
        figures["cost_vs_oracle"] = planner_total / max(figures["oracle_ms"], 1e-9)
        fixed_total = float(table.given.sum())
        fixed_labels: list[str | None] = []
        for r in range(reflectors):
            seen = table.visible[r]
            holds = [c for c in range(len(table.candidates[r])) if np.all(err[r][c, seen] <= limit)]
            if not holds:
                fixed_total = math.inf
                fixed_labels.append(None)
                continue
            best = min(holds, key=lambda c: table.extra[r][c].sum())
            fixed_total += float(table.extra[r][best].sum())
            fixed_labels.append(table.candidates[r][best].label)
        figures["best_fixed_ms"] = fixed_total
        figures["best_fixed"] = fixed_labels
        figures["cost_vs_best_fixed"] = (
            planner_total / fixed_total if math.isfinite(fixed_total) else None
        )
    else:
        assert budget.max_ms is not None
        limit = budget.max_ms
        figures["held_share"] = float(np.mean(planner_cost + run.plan_ms <= limit))
        figures["worst_overrun"] = float(np.max((planner_cost + run.plan_ms) / limit))
        weights = np.where(table.visible, table.pixels, 0).astype(np.float64)
        planner_error, oracle_error = [], []
        for f in range(frames):
            w = weights[:, f]
            if w.sum() <= 0:
                continue
            w = w / w.sum()
            planner_error.append(float(np.nansum(w * true[f])))
            oracle_error.append(_oracle_within(err, table, f, w, limit))
        figures["planner_error"] = float(np.mean(planner_error)) if planner_error else 0.0
        figures["oracle_error"] = float(np.mean(oracle_error)) if oracle_error else 0.0
        figures["error_vs_oracle"] = (
            figures["planner_error"] / figures["oracle_error"]
            if figures["oracle_error"] > 0
            else (1.0 if figures["planner_error"] == 0 else math.inf)
        )
        figures["cost_vs_oracle"] = None
        figures["cost_vs_best_fixed"] = None
    return figures


def _oracle_within(
    err: list[np.ndarray], table: Table, frame: int, weights: np.ndarray, limit: float
) -> float:
    """The lowest weighted true error of frame ``frame`` over every combination whose
    cost fits ``limit``; the cheapest combination's when none fits."""
    import itertools

    options = []
    for r in range(len(err)):
        costs = table.extra[r][:, frame]
        errors = np.nan_to_num(err[r][:, frame], nan=0.0)
        order = np.argsort(costs)
        frontier: list[tuple[float, float]] = []
        for i in order:
            if not frontier or errors[i] < frontier[-1][1]:
                frontier.append((float(costs[i]), float(errors[i])))
        options.append(frontier)
    room = limit - float(table.given[frame])
    best, cheapest = math.inf, (math.inf, math.inf)
    for combination in itertools.product(*options):
        cost = sum(c for c, _ in combination)
        value = float(sum(w * e for w, (_, e) in zip(weights, combination, strict=True)))
        if cost < cheapest[0]:
            cheapest = (cost, value)
        if cost <= room and value < best:
            best = value
    return best if math.isfinite(best) else cheapest[1]


def summary(figures: Sequence[dict[str, Any]]) -> dict[str, Any]:
    """Over all scenes and budgets: held share of all reflector-frames, the worst
    overrun, and the cost ratios of the totals (error budgets), the error ratio (time
    budgets)."""
    errors = [f for f in figures if f["kind"] != "max_ms"]
    times = [f for f in figures if f["kind"] == "max_ms"]
    out: dict[str, Any] = {"scenes": list(figures)}
    if errors:
        frames = sum(f["reflector_frames"] for f in errors)
        out["held_share"] = (
            sum(f["held_share"] * f["reflector_frames"] for f in errors) / frames if frames else 1.0
        )
        out["worst_overrun"] = max(f["worst_overrun"] for f in errors)
        out["cost_vs_oracle"] = sum(f["planner_ms"] for f in errors) / sum(
            f["oracle_ms"] for f in errors
        )
        fixed = [f for f in errors if f["cost_vs_best_fixed"] is not None]
        out["cost_vs_best_fixed"] = (
            sum(f["planner_ms"] for f in fixed) / sum(f["best_fixed_ms"] for f in fixed)
            if fixed
            else None
        )
        out["switches_after_first"] = sum(f["switches_after_first"] for f in errors)
    if times:
        out["time_held_share"] = float(np.mean([f["held_share"] for f in times]))
        out["error_vs_oracle"] = sum(f["planner_error"] for f in times) / max(
            sum(f["oracle_error"] for f in times), 1e-12
        )
        out.setdefault("worst_overrun", 0.0)
        out["time_worst_overrun"] = max(f["worst_overrun"] for f in times)
    return out


# --------------------------------------------------------------------------- outputs

CSV_FIELDS = (
    "scene",
    "budget",
    "frame",
    "reflector",
    "chosen",
    "technique",
    "map_size",
    "settings",
    "predicted_error",
    "bound",
    "true_error",
    "cost_ms",
    "plan_ms",
    "pixels",
)


def csv_rows(result: SceneResult, run: Run) -> list[dict[str, Any]]:
    """A row per reflector and frame of ``run`` (:data:`CSV_FIELDS`)."""
    table = result.table
    metric = run.budget.metric if run.budget.max_error is not None else "flip"
    rows = []
    for f, frame in enumerate(run.frames):
        for r, name in enumerate(result.reflectors):
            choice = frame.choices[r]
            candidate = run.chosen[f][r]
            index = _index(table.candidates[r], candidate)
            rows.append(
                {
                    "scene": result.name,
                    "budget": run.budget.text() + (" ms" if run.budget.max_ms is not None else ""),
                    "frame": f,
                    "reflector": name,
                    "chosen": candidate.label if candidate is not None else choice.label,
                    "technique": candidate.technique if candidate is not None else "",
                    "map_size": candidate.map_size if candidate is not None else "",
                    "settings": _settings(candidate),
                    "predicted_error": choice.chosen.error if choice.chosen else "",
                    "bound": choice.chosen.bound if choice.chosen else "",
                    "true_error": run.errors[f][r].of(metric),
                    "cost_ms": float(table.extra[r][index, f] + table.given[f])
                    if index is not None
                    else "",
                    "plan_ms": float(run.plan_ms[f]),
                    "pixels": int(table.pixels[r, f]),
                }
            )
    return rows


def _settings(candidate: Candidate | None) -> str:
    if candidate is None:
        return ""
    return ";".join(f"{k}={_plain(v)}" for k, v in candidate.changes if k != "technique")


def _plain(value: Any) -> str:
    if value is None:
        return "none"
    kind = getattr(value, "kind", None)
    if kind is not None:
        return f"{kind}({','.join(f'{k}={v}' for k, v in vars(value).items())})"
    return str(value)


def rows_to_csv(rows: Sequence[dict[str, Any]]) -> str:
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, CSV_FIELDS, lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow(
            {
                k: (
                    ""
                    if isinstance(v, float) and math.isnan(v)
                    else (repr(v) if isinstance(v, float) else v)
                )
                for k, v in row.items()
            }
        )
    return buffer.getvalue()


def plot_png(results: Sequence[SceneResult], figures_by_run) -> bytes | None:
    """Error against cost per scene and reflector: each candidate kept fixed (its mean
    true error and mean frame cost over the sequence), their frontier, and per budget the
    oracle and the planner (and the planner's frames, small). None without matplotlib."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return None
    panels = [(result, r) for result in results for r in range(len(result.reflectors))]
    if not panels:
        return None
    columns = min(3, len(panels))
    rows = math.ceil(len(panels) / columns)
    figure, axes_grid = plt.subplots(
        rows, columns, figsize=(6.0 * columns, 4.8 * rows), dpi=90, squeeze=False
    )
    for axes in axes_grid.flat[len(panels) :]:
        axes.set_visible(False)
    palette = plt.get_cmap("tab10")
    for axes, (result, r) in zip(axes_grid.flat, panels, strict=False):
        table = result.table
        seen = table.visible[r]
        if not seen.any():
            axes.set_title(f"{result.name}: {result.reflectors[r]} (never in view)", fontsize=9)
            continue
        metric = "flip"
        for run in result.runs:
            if run.budget.max_error is not None:
                metric = run.budget.metric
                break
        cost = np.array(
            [
                (table.extra[r][c] + table.given)[seen].mean()
                for c in range(len(table.candidates[r]))
            ]
        )
        error = np.array(
            [
                np.nanmean([table.errors[r][c][f].of(metric) for f in np.flatnonzero(seen)])
                for c in range(len(table.candidates[r]))
            ]
        )
        axes.scatter(cost, error, s=14, color="0.6", label="a candidate kept fixed")
        order = np.argsort(cost)
        frontier_x: list[float] = []
        frontier_y: list[float] = []
        for i in order:
            if np.isfinite(error[i]) and (not frontier_y or error[i] < frontier_y[-1]):
                frontier_x.append(cost[i])
                frontier_y.append(error[i])
        axes.plot(frontier_x, frontier_y, color="0.3", linewidth=1, label="their frontier")
        for k, run in enumerate(result.runs):
            colour = palette(k % 10)
            figures = figures_by_run[id(run)]
            run_metric = run.budget.metric if run.budget.max_error is not None else "flip"
            costs, errors = [], []
            for f in np.flatnonzero(seen):
                index = _index(table.candidates[r], run.chosen[f][r])
                if index is None:
                    continue
                costs.append(table.extra[r][index, f] + table.given[f] + run.plan_ms[f])
                errors.append(run.errors[f][r].of(run_metric))
            if not costs:
                continue
            axes.scatter(costs, errors, s=6, color=colour, alpha=0.5)
            axes.scatter(
                [np.mean(costs)],
                [np.nanmean(errors)],
                s=90,
                marker="*",
                color=colour,
                edgecolor="black",
                label=f"planner, {run.budget.describe()}",
            )
            if run.budget.max_error is not None:
                axes.axhline(run.budget.max_error, color=colour, linestyle=":", linewidth=1)
            else:
                axes.axvline(run.budget.max_ms, color=colour, linestyle=":", linewidth=1)
            del figures
        axes.set_xscale("log")
        axes.set_yscale("symlog", linthresh=1e-3)
        axes.set_xlabel("frame cost, ms of CPU (mean over the frames in view)")
        axes.set_ylabel(f"true error ({'mean FLIP' if metric == 'flip' else 'MAE /255'})")
        axes.set_title(f"{result.name}: {result.reflectors[r]}", fontsize=9)
        axes.grid(True, which="both", alpha=0.3)
        axes.legend(fontsize=6)
    figure.tight_layout()
    with io.BytesIO() as buffer:
        figure.savefig(buffer, format="png")
        data = buffer.getvalue()
    plt.close(figure)
    return data


def format_table(figures: Sequence[dict[str, Any]]) -> str:
    """The figures as an aligned text table."""
    header = [
        "scene",
        "budget",
        "held",
        "worst",
        "cost/oracle",
        "cost/fixed",
        "err/oracle",
        "plan ms",
        "switches",
    ]
    lines = [header]
    for f in figures:
        lines.append(
            [
                f["scene"],
                f["budget"] + (" ms" if f["kind"] == "max_ms" else ""),
                f"{f['held_share']:.1%}",
                f"{f['worst_overrun']:.2f}x",
                _ratio(f.get("cost_vs_oracle")),
                _ratio(f.get("cost_vs_best_fixed"), "no fixed holds"),
                _ratio(f.get("error_vs_oracle")),
                f"{f['plan_ms']:.1f}",
                str(f["switches"]),
            ]
        )
    widths = [max(len(row[i]) for row in lines) for i in range(len(header))]
    text = ["  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True)) for row in lines]
    text.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(text)


def _ratio(value: float | None, missing: str = "-") -> str:
    if value is None:
        return missing
    return f"{value:.3f}"


def run_command(
    scenes: Sequence[Scene],
    budgets: Sequence[Budget],
    settings: BenchSettings,
    out_dir: Path,
    say: Callable[[str], None] = print,
    jobs: int = 1,
    scheduler: str | None = None,
    engine: str = "pool",
    calibration: Calibration | None = None,
    progress: bool = True,
) -> int:
    """``mirrorlab bench budget``: measure, print the figures, write budget.csv,
    summary.json and budget.png into ``out_dir`` (all, or none)."""
    from tqdm import tqdm

    from mirrorlab.files import Outputs
    from mirrorlab.jobs import open_executor

    total = sum(
        2 * settings.frames
        + len(budgets)
        + sum(
            len([c for c in candidates_for(r, s) if c.map_size <= settings.largest])
            for r in s.reflectors
        )
        for s in scenes
    )
    started = time.perf_counter()
    results: list[SceneResult] = []
    with (
        tqdm(
            total=total,
            desc="budget",
            unit="step",
            disable=not progress,
            file=sys.stderr,
            dynamic_ncols=True,
            mininterval=0.5,
        ) as bar,
        open_executor(jobs, scheduler, engine) as executor,
        frame_bench() as gl,
    ):
        for scene in scenes:
            results.append(measure_scene(scene, budgets, settings, gl, executor, calibration, bar))
    figures, rows, by_run = [], [], {}
    for result in results:
        for run in result.runs:
            found = analyse(result, run)
            by_run[id(run)] = found
            figures.append(found)
            rows += csv_rows(result, run)
    overall = summary(figures)
    overall["settings"] = {
        "frames": settings.frames,
        "size": list(settings.size),
        "repeats": settings.repeats,
        "motion": settings.motion,
        "largest_map": settings.largest,
        "seconds": round(time.perf_counter() - started, 1),
    }
    say(format_table(figures))
    say(
        "over all: "
        + ", ".join(
            f"{k} {v:.3f}" if isinstance(v, float) else f"{k} {v}"
            for k, v in overall.items()
            if k not in ("scenes", "settings")
        )
    )
    plot = plot_png(results, by_run)
    with Outputs() as outputs:
        outputs.add(out_dir / "budget.csv", rows_to_csv(rows).encode())
        outputs.add(out_dir / "summary.json", json.dumps(overall, indent=1, default=_json).encode())
        if plot is not None:
            outputs.add(out_dir / "budget.png", plot)
    written = ["budget.csv", "summary.json"] + (["budget.png"] if plot is not None else [])
    if plot is None:
        say("matplotlib is not installed, so no plot (pip install 'mirrorlab[plot]')")
    say(f"wrote {', '.join(str(out_dir / name) for name in written)}")
    return 0


def _json(value: Any) -> Any:
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    raise TypeError(f"{type(value).__name__} is not JSON")


__all__ = ["DEFAULT_SCENES", "BenchSettings", "run_command"]
