"""The budget's calibration (``mirrorlab bench calibrate``): random scenes of the
calibration class (:func:`mirrorlab.budget.scenes.calibration_scene`), each reflector's
every candidate drawn and scored against the ray-traced truth, and timed; the
predictions' models fitted to that (:func:`mirrorlab.budget.model.fit`) and written as
the calibration file the budget reads (the shipped one:
``mirrorlab/budget/calibration.json``).

As in the accuracy sweep, work that may run in parallel (the truths, the scoring) goes
to the executor (``--jobs``, Dask), and the timed frames run in this process while the
workers are idle, a batch of samples at a time.
"""

from __future__ import annotations

import csv
import io
import math
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

from mirrorlab.budget.candidates import (
    candidates_for,
    cost_family,
    error_family,
)
from mirrorlab.budget.features import candidate_features, texture_texels, view_features
from mirrorlab.budget.measure import (
    FLIP_MARGIN,
    FrameBench,
    Truth,
    frame_bench,
    score_images,
    trace_truth,
)
from mirrorlab.budget.model import Calibration, ErrorModel
from mirrorlab.budget.scenes import ReflectorKind, calibration_scene
from mirrorlab.errors import BatchError
from mirrorlab.jobs import Executor, Outcome
from mirrorlab.scene.model import Scene
from mirrorlab.views import camera_view

MIN_PIXELS = 150
"""A sample whose reflector covers fewer pixels of its truth is left out."""

FIELDS = (
    "sample",
    "kind",
    "width",
    "height",
    "family",
    "cost_family",
    "label",
    "technique",
    "map_size",
    "pixels",
    "grazing",
    "objects",
    "offscreen",
    "near",
    "wrong",
    "shift",
    "texels",
    "texture_texels",
    "parts",
    "flip",
    "mae",
    "scored",
    "full_ms",
    "draw_ms",
    "base_ms",
)
"""The columns of a calibration sample row (one per sample and candidate)."""


@dataclass(frozen=True)
class CalibrationSettings:
    """``planar`` and ``curved`` samples (each a random scene and view, from seed
    ``first_seed`` on), the candidates' costs timed on every ``timed_every``-th sample,
    each the median of ``frames`` frames, ``batch`` samples drawn before their scoring
    is sent out."""

    planar: int = 160
    curved: int = 200
    first_seed: int = 0
    timed_every: int = 4
    frames: int = 3
    batch: int = 8
    largest: int = 512
    """Maps larger than this are not measured (the models extrapolate to them along
    their texel counts: a map of 1024 texels a side is baked in 6 to 55 s)."""

    @classmethod
    def quick(cls) -> CalibrationSettings:
        """A few samples, to check that the calibration runs (not a calibration)."""
        return cls(planar=2, curved=2, timed_every=2, frames=1, batch=2)


def _truth_job(seed: int, kind: ReflectorKind) -> Truth:
    scene, size = calibration_scene(seed, kind)
    return trace_truth(scene, size)


def collect(
    settings: CalibrationSettings,
    executor: Executor | None = None,
    progress: bool = True,
    say: Callable[[str], None] = print,
    partial: Path | None = None,
) -> list[dict[str, Any]]:
    """Measure the calibration samples: one row (:data:`FIELDS`) per sample and candidate.
    With ``partial``, the rows of each batch are appended to that CSV file as they are
    scored, and the samples it already holds are not measured again (a calibration takes
    hours: one stopped part way resumes)."""
    from tqdm import tqdm

    executor = executor or Executor()
    samples: list[tuple[int, ReflectorKind]] = sorted(
        [(settings.first_seed + i, "planar") for i in range(settings.planar)]
        + [(settings.first_seed + i, "curved") for i in range(settings.curved)]
    )  # the kinds alternate, so that a run stopped part way has some of each
    rows: list[dict[str, Any]] = []
    if partial is not None and partial.is_file():
        rows = rows_from_csv(partial.read_text())
        done = {str(row["sample"]) for row in rows}
        samples = [(seed, kind) for seed, kind in samples if f"{kind}-{seed}" not in done]
        wanted = {
            f"{kind}-{seed + settings.first_seed}"
            for kind, count in (("planar", settings.planar), ("curved", settings.curved))
            for seed in range(count)
        }
        rows = [row for row in rows if str(row["sample"]) in wanted]
        say(f"calibration: resuming, {len(done)} samples measured before")
    kept = 0
    with tqdm(
        total=3 * len(samples),
        desc="calibration",
        unit="step",
        disable=not progress,
        file=sys.stderr,
        dynamic_ncols=True,
        mininterval=0.5,
    ) as bar:
        chunks = [samples[i : i + settings.batch] for i in range(0, len(samples), settings.batch)]
        # the first truths are traced before the OpenGL context is opened: a pool's
        # workers are forked at its first run, from this process as it is then
        truths = _trace(executor, chunks[0], bar) if chunks else {}
        with frame_bench() as bench:
            for number, chunk in enumerate(chunks):
                if number:
                    truths = _trace(executor, chunk, bar)
                batch = [i for i in range(len(chunk)) if truths[i].masks[0].sum() >= MIN_PIXELS]
                bar.update(2 * (len(chunk) - len(batch)))
                kept += len(batch)
                pending: dict[str, tuple] = {}
                measured: dict[int, list[dict[str, Any]]] = {}
                for i in batch:
                    seed, kind = chunk[i]
                    bar.set_postfix_str(f"{kind} sample {seed}", refresh=False)
                    timed = (seed % settings.timed_every) == 0
                    measured[i], crops = _measure(bench, seed, kind, truths[i], timed, settings)
                    pending[f"score-{i}"] = crops
                    bar.update()
                bar.set_postfix_str("scoring", refresh=False)
                scored: list[dict[str, Any]] = []
                for outcome in executor.run(score_images, pending):
                    i = int(outcome.key.split("-")[1])
                    for row, found in zip(measured[i], _value(outcome, "scoring"), strict=True):
                        row.update(flip=found.flip, mae=found.mae, scored=found.pixels)
                    scored += measured[i]
                    bar.update()
                rows += scored
                if partial is not None:
                    _append(partial, scored)
    say(f"calibration: {kept} of {len(samples)} samples measured ({len(rows)} rows in all)")
    return rows


def _trace(executor: Executor, chunk: Sequence[tuple[int, ReflectorKind]], bar) -> dict[int, Truth]:
    """The truths of ``chunk``'s samples, by their index in it."""
    bar.set_postfix_str("ray tracing the truths", refresh=False)
    truths: dict[int, Truth] = {}
    for outcome in executor.run(_truth_job, {f"truth-{i}": s for i, s in enumerate(chunk)}):
        truths[int(outcome.key.split("-")[1])] = _value(outcome, "ray tracing")
        bar.update()
    return truths


def _measure(
    bench: FrameBench,
    seed: int,
    kind: ReflectorKind,
    truth: Truth,
    timed: bool,
    settings: CalibrationSettings,
) -> tuple[list[dict[str, Any]], tuple]:
    """One sample's candidates: features, pictures (cropped to the reflector for the
    scoring job) and, when ``timed``, costs."""
    scene, size = calibration_scene(seed, kind)
    reflector = scene.reflectors[0]
    view = camera_view(scene.camera, size)
    from mirrorlab.plan import reflector_footprint

    found = view_features(scene, reflector, view, reflector_footprint(reflector, view))
    mask = truth.masks[0]
    crop = _crop(mask)
    base = (
        bench.measure(replace(scene, reflectors=()), size, settings.frames)[2]
        if timed
        else math.nan
    )
    parts = _parts(scene)
    rows, images = [], []
    for candidate in candidates_for(reflector, scene):
        if candidate.map_size > settings.largest:
            continue
        drawn = candidate.apply(reflector)
        posed = replace(scene, reflectors=(drawn,))
        image, full, draw = bench.measure(posed, size, settings.frames if timed else 0)
        images.append((0, image[crop]))
        wrong, shift, texels = (
            candidate_features(found, reflector, candidate) if found is not None else (0, 0, 0)
        )
        vector = found.vector() if found is not None else np.full(5, math.nan)
        rows.append(
            {
                "sample": f"{kind}-{seed}",
                "kind": kind,
                "width": size[0],
                "height": size[1],
                "family": error_family(drawn),
                "cost_family": cost_family(drawn),
                "label": candidate.label,
                "technique": candidate.technique,
                "map_size": candidate.map_size,
                "pixels": float(2.0 ** vector[0]),
                "grazing": float(vector[1]),
                "objects": float(vector[2]),
                "offscreen": float(vector[3]),
                "near": float(vector[4]),
                "wrong": float(wrong),
                "shift": float(shift),
                "texels": float(texels),
                "texture_texels": texture_texels(drawn, size, found.pixels if found else 0.0),
                "parts": parts,
                "full_ms": full,
                "draw_ms": draw,
                "base_ms": base,
            }
        )
    cropped_truth = Truth(truth.image[crop], (mask[crop],), truth.milliseconds)
    return rows, (cropped_truth, images)


def _crop(mask: np.ndarray) -> tuple[slice, slice]:
    """The reflector's rectangle grown by FLIP's margin."""
    ys, xs = np.nonzero(mask)
    height, width = mask.shape
    return (
        slice(max(int(ys.min()) - FLIP_MARGIN, 0), min(int(ys.max()) + FLIP_MARGIN + 1, height)),
        slice(max(int(xs.min()) - FLIP_MARGIN, 0), min(int(xs.max()) + FLIP_MARGIN + 1, width)),
    )


def _parts(scene: Scene) -> int:
    from mirrorlab.bounds import scene_index

    return len(scene_index(scene).objects_part.parts)


def _value(outcome: Outcome, what: str):
    if outcome.error is not None:
        raise BatchError(f"{what} failed on a worker: {outcome.error}")
    return outcome.value


def rows_to_csv(rows: Sequence[dict[str, Any]]) -> str:
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, FIELDS, lineterminator="\n")
    writer.writeheader()
    for row in rows:
        writer.writerow(
            {k: ("" if isinstance(v, float) and math.isnan(v) else v) for k, v in row.items()}
        )
    return buffer.getvalue()


def _append(path: Path, rows: Sequence[dict[str, Any]]) -> None:
    """Add ``rows`` to the CSV file at ``path`` (made, with its header, if missing)."""
    text = rows_to_csv(rows)
    if path.is_file():
        text = text.split("\n", 1)[1]
    with path.open("a", encoding="utf-8") as stream:
        stream.write(text)


def rows_from_csv(text: str) -> list[dict[str, Any]]:
    """Rows written by :func:`rows_to_csv`; ValueError naming the line that does not fit."""
    reader = csv.DictReader(io.StringIO(text))
    if reader.fieldnames is None or tuple(reader.fieldnames) != FIELDS:
        raise ValueError(f"expected the columns {','.join(FIELDS)}, got {reader.fieldnames}")
    words = ("sample", "kind", "family", "cost_family", "label", "technique")
    rows = []
    for line, record in enumerate(reader, start=2):
        try:
            rows.append(
                {
                    k: (v if k in words else (float(v) if v != "" else math.nan))
                    for k, v in record.items()
                }
            )
        except ValueError as exc:
            raise ValueError(f"line {line}: {exc}") from None
    return rows


def save(rows: Sequence[dict[str, Any]], path: Path) -> None:
    from mirrorlab.files import write_bytes_atomic

    write_bytes_atomic(path, rows_to_csv(rows).encode())


# --------------------------------------------------------------------------- fitting


def row_features(rows: Sequence[dict[str, Any]]) -> np.ndarray:
    """``(n, 8)`` features of each row (:func:`mirrorlab.budget.model.error_basis`'s
    order), worked out again from the row's sample (its scene, made again from its seed)
    and candidate: the features may change without measuring again."""
    from mirrorlab.plan import reflector_footprint

    out = np.full((len(rows), 8), np.nan)
    by_sample: dict[str, list[int]] = {}
    for i, row in enumerate(rows):
        by_sample.setdefault(str(row["sample"]), []).append(i)
    for sample, indices in by_sample.items():
        kind, seed = sample.split("-")
        scene, size = calibration_scene(int(seed), kind)  # type: ignore[arg-type]
        reflector = scene.reflectors[0]
        view = camera_view(scene.camera, size)
        found = view_features(scene, reflector, view, reflector_footprint(reflector, view))
        if found is None:
            continue
        by_label = {c.label: c for c in candidates_for(reflector, scene)}
        for i in indices:
            candidate = by_label.get(str(rows[i]["label"]))
            if candidate is None:
                continue
            out[i, :5] = found.vector()
            out[i, 5:] = candidate_features(found, reflector, candidate)
    return out


def fit(
    rows: Sequence[dict[str, Any]],
    features: np.ndarray | None = None,
    meta: dict[str, Any] | None = None,
) -> tuple[Calibration, dict[str, Any]]:
    """The calibration fitted to measured ``rows`` (their ``features``, worked out again
    when not given), and a report of how its bounds held on the samples each model was
    not fitted to (per family: rows, the share of held-out errors within the bound, the
    median bound over the error)."""
    from mirrorlab.budget.model import (
        BASE_BASIS,
        MIN_ROWS,
        CostModel,
        base_basis,
        cost_basis,
        error_basis,
        fit_error_model,
        nnls,
    )

    if features is None:
        features = row_features(rows)
    usable = np.all(np.isfinite(features), axis=1)
    basis = error_basis(np.where(usable[:, None], features, 0.0))
    groups = np.array([str(r["sample"]) for r in rows])
    families = np.array([str(r["family"]) for r in rows])
    kinds = np.array([_texture_kind(str(r["technique"])) for r in rows])
    errors: dict[str, dict[str, ErrorModel]] = {}
    pooled: dict[str, dict[str, ErrorModel]] = {}
    report: dict[str, Any] = {"families": {}}
    for metric in ("flip", "mae"):
        values = np.array([float(r[metric]) for r in rows])
        ok = usable & np.isfinite(values)
        errors[metric], pooled[metric] = {}, {}
        for family in sorted({str(f) for f in families[ok]}):
            chosen = ok & (families == family)
            if chosen.sum() < MIN_ROWS:
                continue
            model, held = fit_error_model(basis[chosen], values[chosen], groups[chosen])
            errors[metric][family] = model
            bound = (held + model.margin) ** 2
            truth = values[chosen]
            report["families"].setdefault(family, {})[metric] = {
                "rows": int(chosen.sum()),
                "covered": float(np.mean(truth <= bound)),
                "bound_over_error": float(np.median(bound / np.maximum(truth, 1e-6))),
            }
        for kind in [*sorted({str(k) for k in kinds[ok]}), "any"]:
            chosen = ok & ((kinds == kind) if kind != "any" else True)
            if chosen.sum() >= MIN_ROWS:
                pooled[metric][kind], _ = fit_error_model(
                    basis[chosen], values[chosen], groups[chosen]
                )
    costs: dict[str, CostModel] = {}
    kind_costs: dict[str, CostModel] = {}
    timed = np.array(
        [all(math.isfinite(float(r[k])) for k in ("full_ms", "draw_ms", "base_ms")) for r in rows]
    )
    terms = cost_basis(
        np.array([float(r["pixels"]) for r in rows]),
        np.array([float(r["texture_texels"]) for r in rows]),
        np.array([float(r["parts"]) for r in rows]),
    )
    full = np.array([float(r["full_ms"]) for r in rows])
    draw = np.array([float(r["draw_ms"]) for r in rows])
    base_ms = np.array([float(r["base_ms"]) for r in rows])
    cost_families = np.array([str(r["cost_family"]) for r in rows])

    def cost_model(chosen: np.ndarray) -> CostModel:
        drawn = np.maximum(draw[chosen] - base_ms[chosen], 0.0)
        captured = np.maximum(full[chosen] - draw[chosen], 0.0)
        return CostModel(
            tuple(float(v) for v in nnls(terms[chosen], drawn)),
            tuple(float(v) for v in nnls(terms[chosen], captured)),
            int(chosen.sum()),
        )

    for family in sorted({str(f) for f in cost_families[timed]}):
        chosen = timed & (cost_families == family)
        if chosen.sum() >= 6:
            costs[family] = cost_model(chosen)
    for kind in [*sorted({str(k) for k in kinds[timed]}), "any"]:
        chosen = timed & ((kinds == kind) if kind != "any" else True)
        if chosen.sum() >= 6:
            kind_costs[kind] = cost_model(chosen)
    samples = {}
    for row, ok in zip(rows, timed, strict=True):
        if ok:
            samples[row["sample"]] = (
                base_basis(float(row["width"]) * float(row["height"]), float(row["parts"])),
                float(row["base_ms"]),
            )
    if samples:
        matrix = np.array([b for b, _ in samples.values()])
        base = tuple(float(v) for v in nnls(matrix, np.array([m for _, m in samples.values()])))
    else:
        base = (0.0,) * len(BASE_BASIS)
    info = dict(meta or {})
    info.update(
        samples=len(set(groups)),
        rows=len(rows),
        timed_samples=len(samples),
    )
    return Calibration(errors, pooled, costs, kind_costs, base, info), report


def _texture_kind(name: str) -> str:
    from mirrorlab.techniques import technique

    try:
        return str(technique(name).texture)
    except ValueError:
        return "unknown"


def run_command(
    settings: CalibrationSettings,
    out_dir: Path,
    from_csv: Path | None = None,
    say: Callable[[str], None] = print,
    jobs: int = 1,
    scheduler: str | None = None,
    engine: str = "pool",
) -> int:
    """``mirrorlab bench calibrate``: measure the samples (or read them ``from_csv``),
    fit, say how the bounds held on held-out samples, and write calibration.json (and the
    samples, samples.csv) into ``out_dir``, all or none."""
    from mirrorlab.files import Outputs
    from mirrorlab.jobs import open_executor

    started = time.perf_counter()
    if from_csv is not None:
        try:
            rows = rows_from_csv(from_csv.read_text())
        except (OSError, UnicodeDecodeError) as exc:
            raise ValueError(f"--from-csv: cannot read {from_csv}: {exc}") from None
        except ValueError as exc:
            raise ValueError(f"--from-csv: {from_csv}: {exc}") from None
    else:
        partial = out_dir / "samples.partial.csv"
        out_dir.mkdir(parents=True, exist_ok=True)
        with open_executor(jobs, scheduler, engine) as executor:
            rows = collect(settings, executor, say=say, partial=partial)
    if not rows:
        raise ValueError("no calibration samples were measured (every one was left out)")
    calibration, report = fit(
        rows,
        meta={
            "made_by": "mirrorlab bench calibrate",
            "planar": settings.planar,
            "curved": settings.curved,
            "first_seed": settings.first_seed,
        },
    )
    say(format_report(report))
    with Outputs() as outputs:
        outputs.add(out_dir / "calibration.json", calibration.to_json().encode())
        if from_csv is None:
            outputs.add(out_dir / "samples.csv", rows_to_csv(rows).encode())
    if from_csv is None:
        (out_dir / "samples.partial.csv").unlink(missing_ok=True)
    say(
        f"wrote {out_dir / 'calibration.json'}"
        + ("" if from_csv is not None else f" and {out_dir / 'samples.csv'}")
        + f" in {time.perf_counter() - started:.0f} s"
    )
    return 0


def format_report(report: dict[str, Any]) -> str:
    """The held-out coverage of each family's bound, as text."""
    lines = ["family                        FLIP covered  bound/error   MAE covered  rows"]
    for family, metrics in sorted(report["families"].items()):
        flip = metrics.get("flip", {})
        mae = metrics.get("mae", {})
        lines.append(
            f"{family:<29} {flip.get('covered', math.nan):>12.1%} "
            f"{flip.get('bound_over_error', math.nan):>11.2f} {mae.get('covered', math.nan):>13.1%}"
            f"  {flip.get('rows', mae.get('rows', 0))}"
        )
    return "\n".join(lines)
