"""The choice, per reflector and frame: which candidate draws each reflector under a
budget (:class:`mirrorlab.scene.model.Budget`).

Each frame, for each reflector in view, every candidate's error and cost are predicted
(:mod:`mirrorlab.budget.model`) from the reflector's features in this view
(:mod:`mirrorlab.budget.features`).

- **An error budget** (``max_error``): the cheapest candidate whose predicted *bound* (the
  prediction plus the calibration's margin) is within the budget; when none is, the one
  with the lowest bound, and the frame says the budget is not met.
- **A time budget** (``max_ms``, Funkhouser and Sequin's problem): the combination of
  candidates whose predicted frame cost fits, with the lowest predicted error over all
  the reflectors' pixels (each reflector's candidates cut to those no other beats in
  both error and cost, then every combination tried, or, for many reflectors, the best
  upgrade per millisecond taken greedily); when none fits, the cheapest.

A predicted cost counts a candidate's captures and bakes only when what they show changed
since the last frame (the viewer moved, the view turned, an object moved), as the
planner then runs them; the first frame is taken as still.

**Steady choices.** A reflector keeps its candidate while it is predicted to stay within
the budget and the best one would save less than :data:`SWITCH_SAVING` of its cost (or
is not within the budget by :data:`SWITCH_MARGIN` more); a frame whose scene and size
are the last frame's gets the last frame's choice as it is, without predicting again. So
on a still scene the choice never changes after the first frame.

The choice's own time (features, predictions, choice) is measured and reported with the
frame (:attr:`BudgetFrame.milliseconds`). Numpy only.
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, replace

import numpy as np

from mirrorlab.budget.candidates import Candidate, candidates_for, cost_family, error_family
from mirrorlab.budget.features import ViewFeatures, lookup_error, view_features
from mirrorlab.budget.model import (
    Calibration,
    base_basis,
    cost_basis,
    error_basis,
    load_calibration,
)
from mirrorlab.scene.model import Budget, DistanceSearch, PlanarReflector, Reflector, Scene
from mirrorlab.techniques import technique

SWITCH_SAVING = 0.15
"""A reflector within its budget moves to a cheaper candidate only when that saves more
than this share of its predicted cost."""
SWITCH_MARGIN = 0.1
"""... and the cheaper candidate's bound is within the budget by this share more."""
TIME_KEEP = 0.05
"""Under a time budget, the last frame's combination is kept while it fits and its
predicted error is within this share of the best combination's."""
MAX_HELD = 8
"""A choice is predicted again at least every this many frames."""
EYE_DRIFT = 0.04
"""The choice is predicted again when the eye has moved this share of its distance to a
reflector since the last prediction (or a reflector this share of its distance to the
eye) ..."""
TURN_DRIFT = math.radians(2.0)
"""... or the view, or a planar mirror, has turned this much ..."""
OBJECT_DRIFT = 0.02
"""... or an object has moved this share of the scene's radius (or anything else about
the scene, the budget or a reflector's configuration changed)."""
EXHAUSTIVE = 20_000
"""Under a time budget, up to this many combinations are all tried."""


@dataclass(frozen=True)
class Prediction:
    """A candidate's predictions for one reflector in one frame: ``error`` and its
    ``bound`` (in the budget's metric; FLIP under a time budget), and ``cost`` (the
    milliseconds it adds to the frame)."""

    candidate: Candidate
    error: float
    bound: float
    cost: float


@dataclass(frozen=True)
class ReflectorChoice:
    """What a reflector is drawn by this frame: ``chosen`` among ``predictions`` (empty
    when it is not in view), whether it is predicted to be within the budget (``met``),
    and ``reason`` in words; ``pixels``: its footprint's."""

    reflector: str
    chosen: Prediction | None
    predictions: tuple[Prediction, ...]
    met: bool
    reason: str
    pixels: float = 0.0
    label: str = ""

    @property
    def candidate_label(self) -> str:
        return self.chosen.candidate.label if self.chosen is not None else self.label


@dataclass(frozen=True)
class BudgetFrame:
    """The budget's choice for one frame: ``budget``, a :class:`ReflectorChoice` per
    reflector, the frame's predicted cost (``predicted_ms``: its base and every chosen
    candidate's), whether every reflector in view is predicted within the budget
    (``met``), the choice's own time (``milliseconds``), whether it is the last frame's
    for the same scene (``repeated``), and whether it was predicted for this frame
    (``predicted``: False when the view and the scene moved too little since the last
    prediction to change it, see :func:`_drifted`)."""

    budget: Budget
    choices: tuple[ReflectorChoice, ...]
    predicted_ms: float
    met: bool
    milliseconds: float
    repeated: bool = False
    predicted: bool = True

    def describe(self, candidates: bool = False) -> list[str]:
        """Lines for people: the budget, then each reflector's choice and why (and with
        ``candidates``, each candidate's predictions)."""
        state = "met" if self.met else "NOT met"
        lines = [
            f"budget {self.budget.describe()}: predicted {state}; frame predicted "
            f"{self.predicted_ms:.1f} ms; choosing took {self.milliseconds:.2f} ms"
            + (" (the last frame's choice)" if self.repeated else "")
            + (
                ""
                if self.predicted or self.repeated
                else " (kept: little moved since it was predicted)"
            )
        ]
        metric = (
            "MAE" if self.budget.max_error is not None and self.budget.metric == "mae" else "FLIP"
        )
        for choice in self.choices:
            chosen = choice.chosen
            if chosen is None:
                lines.append(f"  {choice.reflector}: {choice.candidate_label} ({choice.reason})")
                continue
            lines.append(
                f"  {choice.reflector}: {chosen.candidate.label}: predicted {metric} "
                f"{chosen.error:.4g} (bound {chosen.bound:.4g}), {chosen.cost:.2f} ms: "
                f"{choice.reason}"
            )
            if candidates:
                for p in sorted(choice.predictions, key=lambda p: p.cost):
                    mark = "*" if p.candidate == chosen.candidate else " "
                    lines.append(
                        f"    {mark} {p.candidate.label:<34} {metric} {p.error:8.4g} "
                        f"bound {p.bound:8.4g}  {p.cost:8.2f} ms"
                    )
        return lines

    def as_dict(self) -> dict:
        return {
            "budget": self.budget.text(),
            "kind": "max_ms" if self.budget.max_ms is not None else self.budget.metric,
            "met": self.met,
            "predicted_ms": self.predicted_ms,
            "choosing_ms": self.milliseconds,
            "reflectors": [
                {
                    "reflector": c.reflector,
                    "chosen": c.candidate_label,
                    "met": c.met,
                    "reason": c.reason,
                    "predicted_error": None if c.chosen is None else c.chosen.error,
                    "bound": None if c.chosen is None else c.chosen.bound,
                    "cost_ms": None if c.chosen is None else c.chosen.cost,
                    "candidates": [
                        {
                            "candidate": p.candidate.label,
                            "error": p.error,
                            "bound": p.bound,
                            "cost_ms": p.cost,
                        }
                        for p in c.predictions
                    ],
                }
                for c in self.choices
            ],
        }


@dataclass(frozen=True)
class _Prepared:
    """Per candidate of a reflector: which share a lookup (``lookups``: key -> their
    indices), their texture ``kinds``, map ``sides``, how their texels per pixel and
    texel counts are worked out (:func:`_texel_modes`), and their models' weights."""

    lookups: dict[tuple, np.ndarray]
    kinds: tuple[str, ...]
    sides: np.ndarray
    texel_mode: np.ndarray
    texel_count: np.ndarray
    coefficients: np.ndarray
    margins: np.ndarray
    draw: np.ndarray
    capture: np.ndarray


def _texel_modes(drawn: Reflector) -> tuple[int, int, float]:
    """How a candidate's texels per pixel are measured (0: not at all; 1: its side over
    the view's; 2: over its footprint's; 3: over its footprint's diameter, a curved
    map), how its texel count is (0: none; 1: its side squared; 2: the view's pixels; 3:
    its footprint's pixels), and its side (:func:`mirrorlab.budget.features.texels_of`,
    :func:`mirrorlab.budget.features.texture_texels`)."""
    entry = technique(drawn.technique)
    if entry.texture == "inline":
        return 0, 0, 1.0
    if isinstance(drawn, PlanarReflector):
        size = drawn.texture_size
        if not isinstance(size, int):
            return 0, (2 if size is None else 3), 1.0
        return (2 if entry.own_camera else 1), 1, float(size)
    return 3, 1, float(drawn.map_size)


@dataclass
class _Last:
    """The last frame: its input scene and size, output scene and choice; the scene the
    choice was last predicted for, which reflectors were in view then, and the frames
    since that kept it (``held``)."""

    scene: Scene
    size: tuple[int, int]
    output: Scene
    frame: BudgetFrame
    predicted: Scene
    shown: tuple[bool, ...]
    held: int = 0


class BudgetChooser:
    """Chooses each reflector's candidate frame by frame under the scene's budget, keeping
    what it chose (for steady choices). One per sequence of frames (a renderer keeps
    one); ``calibration`` None reads the shipped one; ``largest`` (texels a side) leaves
    out the candidates with larger maps (the benchmark's short runs)."""

    def __init__(self, calibration: Calibration | None = None, largest: int | None = None) -> None:
        self.calibration = calibration or load_calibration()
        self.largest = largest
        self._last: _Last | None = None
        self._chosen: dict[str, Candidate] = {}  # reflector -> its candidate
        self._prepared_for: dict[tuple, _Prepared] = {}
        self._candidates: dict[tuple, tuple[Candidate, ...]] = {}

    def reset(self) -> None:
        """Forget the last frame and the choices (the next frame chooses afresh)."""
        self._last = None
        self._chosen.clear()

    def choose(self, scene: Scene, size: tuple[int, int]) -> tuple[Scene, BudgetFrame]:
        """``scene`` (posed, with a budget) with each reflector set to its chosen
        candidate, and the choice."""
        start = time.perf_counter()
        budget = scene.budget
        if budget is None:
            raise ValueError("the scene has no budget to choose by")
        last = self._last
        if last is not None and last.size == size and (last.scene is scene or last.scene == scene):
            frame = replace(
                last.frame, milliseconds=(time.perf_counter() - start) * 1e3, repeated=True
            )
            self._last = replace(last, scene=scene, frame=frame)
            return last.output, frame
        from mirrorlab.plan import reflector_footprint
        from mirrorlab.views import camera_view

        view = camera_view(scene.camera, size)
        footprints = [reflector_footprint(r, view) for r in scene.reflectors]
        shown = tuple(not f.empty for f in footprints)
        if (
            last is not None
            and last.size == size
            and last.held < MAX_HELD
            and last.shown == shown
            and not _drifted(last.predicted, scene)
        ):
            output = _apply(scene, last.frame.choices, self._chosen, last)
            frame = replace(
                last.frame,
                milliseconds=(time.perf_counter() - start) * 1e3,
                repeated=False,
                predicted=False,
            )
            self._last = replace(last, scene=scene, output=output, frame=frame, held=last.held + 1)
            return output, frame
        changes = _changes(last.scene if last is not None else None, scene, size, last)
        metric = budget.metric if budget.max_error is not None else "flip"
        parts = _parts(scene)
        options: list[tuple[Reflector, list[Prediction], float] | None] = []
        for reflector, footprint in zip(scene.reflectors, footprints, strict=True):
            found = None if footprint.empty else view_features(scene, reflector, view, footprint)
            if found is None:
                options.append(None)
                continue
            predictions = self._predict(scene, reflector, found, metric, changes, parts, size)
            options.append((reflector, predictions, found.pixels))
        base = float(base_basis(size[0] * size[1], parts) @ np.asarray(self.calibration.base))
        if budget.max_ms is not None:
            choices = self._by_time(scene, options, budget.max_ms - base)
        else:
            assert budget.max_error is not None
            choices = tuple(
                self._by_error(scene.reflectors[i], option, budget.max_error)
                for i, option in enumerate(options)
            )
        output = _apply(scene, choices, self._chosen, last)
        predicted = base + sum(c.chosen.cost for c in choices if c.chosen is not None)
        met = all(c.met for c in choices)
        frame = BudgetFrame(budget, choices, predicted, met, (time.perf_counter() - start) * 1e3)
        self._last = _Last(scene, size, output, frame, scene, shown)
        for choice in choices:
            if choice.chosen is not None:
                self._chosen[choice.reflector] = choice.chosen.candidate
        return output, frame

    def candidates(self, reflector: Reflector, scene: Scene) -> tuple[Candidate, ...]:
        """``reflector``'s candidates, made when the chooser first sees it (a live map's
        box and sphere proxies from that frame's objects) and kept while its
        configuration is the same."""
        key = (reflector.name, reflector.kind, reflector.technique, reflector.allow)
        found = self._candidates.get(key)
        if found is None:
            found = candidates_for(reflector, scene)
            if self.largest is not None:
                found = tuple(c for c in found if c.map_size <= self.largest)
            self._candidates[key] = found
        return found

    def _unseen(self, name: str) -> ReflectorChoice:
        """A reflector not in view: it keeps what it was drawn by (or the scene's own)."""
        held = self._chosen.get(name)
        label = held.label if held is not None else "as the scene gives it"
        return ReflectorChoice(name, None, (), True, "not in view: kept", 0.0, label)

    # ------------------------------------------------------------- predictions

    def _predict(
        self,
        scene: Scene,
        reflector: Reflector,
        found: ViewFeatures,
        metric: str,
        changes: frozenset[str],
        parts: int,
        size: tuple[int, int],
    ) -> list[Prediction]:
        candidates = self.candidates(reflector, scene)
        prepared = self._prepared(candidates, reflector, metric)
        count = len(candidates)
        rows = np.empty((count, 8))
        rows[:, :5] = found.vector()
        for members in prepared.lookups.values():
            drawn = candidates[members[0]].apply(reflector)
            rows[members, 5:7] = lookup_error(found, drawn)
        sides = prepared.sides
        pixels = max(found.pixels, 1.0)
        with np.errstate(divide="ignore"):
            rows[:, 7] = np.select(
                [prepared.texel_mode == 1, prepared.texel_mode == 2, prepared.texel_mode == 3],
                [
                    np.log2(sides / max(found.view.size)),
                    np.log2(sides / max(math.sqrt(pixels), 1.0)),
                    np.log2(sides / max(found.diameter, 1.0)),
                ],
                0.0,
            )
        texels = np.select(
            [prepared.texel_count == 1, prepared.texel_count == 2, prepared.texel_count == 3],
            [sides**2, np.full(count, float(size[0] * size[1])), np.full(count, pixels)],
            0.0,
        )
        basis = error_basis(rows)
        root = np.maximum(np.einsum("ij,ij->i", basis, prepared.coefficients), 0.0)
        errors, bounds = root**2, (root + prepared.margins) ** 2
        terms = cost_basis(np.full(count, found.pixels), texels, np.full(count, parts))
        draw = np.maximum(np.einsum("ij,ij->i", terms, prepared.draw), 0.0)
        capture = np.maximum(np.einsum("ij,ij->i", terms, prepared.capture), 0.0)
        runs = np.array([_captures(kind, changes) for kind in prepared.kinds], dtype=np.float64)
        costs = draw + runs * capture
        return [
            Prediction(c, float(e), float(b), float(k))
            for c, e, b, k in zip(candidates, errors, bounds, costs, strict=True)
        ]

    def _prepared(
        self, candidates: tuple[Candidate, ...], reflector: Reflector, metric: str
    ) -> _Prepared:
        """What the predictions of ``candidates`` need that does not change from frame to
        frame (kept for the candidates)."""
        key = (candidates, metric)
        known = self._prepared_for.get(key)
        if known is not None:
            return known
        lookups: dict[tuple, list[int]] = {}
        kinds, sides, texel_mode, texel_count = [], [], [], []
        coefficients, margins, draws, captures = [], [], [], []
        for i, candidate in enumerate(candidates):
            drawn = candidate.apply(reflector)
            entry = technique(drawn.technique)
            kind = str(entry.texture)
            lookups.setdefault(_lookup_key(drawn), []).append(i)
            kinds.append(kind)
            mode, count, side = _texel_modes(drawn)
            texel_mode.append(mode)
            texel_count.append(count)
            sides.append(side)
            model = self.calibration.error_model(metric, error_family(drawn), kind)
            coefficients.append(model.coefficients)
            margins.append(model.margin)
            cost = self.calibration.cost_model(cost_family(drawn), kind)
            draws.append(cost.draw)
            captures.append(cost.capture)
        made = _Prepared(
            {k: np.array(v) for k, v in lookups.items()},
            tuple(kinds),
            np.array(sides, dtype=np.float64),
            np.array(texel_mode),
            np.array(texel_count),
            np.array(coefficients),
            np.array(margins),
            np.array(draws),
            np.array(captures),
        )
        if len(self._prepared_for) > 64:
            self._prepared_for.clear()
        self._prepared_for[key] = made
        return made

    # ------------------------------------------------------------- choices

    def _by_error(
        self,
        reflector: Reflector,
        option: tuple[Reflector, list[Prediction], float] | None,
        limit: float,
    ) -> ReflectorChoice:
        name = reflector.name
        if option is None:
            return self._unseen(name)
        _, predictions, pixels = option
        current = next((p for p in predictions if p.candidate == self._chosen.get(name)), None)
        within = [p for p in predictions if p.bound <= limit]
        if not within:
            best = min(predictions, key=lambda p: (p.bound, p.cost))
            if current is not None and current.bound <= best.bound * 1.05:
                best = current
            return ReflectorChoice(
                name,
                best,
                tuple(predictions),
                False,
                f"none predicted within the budget: the most accurate (bound "
                f"{best.bound:.3g} > {limit:.3g})",
                pixels,
            )
        cheapest = min(within, key=lambda p: (p.cost, p.bound))
        if current is not None and current.bound <= limit:
            saves = cheapest.cost < current.cost * (1.0 - SWITCH_SAVING)
            clear = cheapest.bound <= limit * (1.0 - SWITCH_MARGIN)
            if not (saves and clear):
                return ReflectorChoice(
                    name,
                    current,
                    tuple(predictions),
                    True,
                    f"kept: still within the budget (bound {current.bound:.3g} <= "
                    f"{limit:.3g}); the cheapest ({cheapest.candidate.label}) would save "
                    f"{max(current.cost - cheapest.cost, 0.0):.2f} ms",
                    pixels,
                )
        return ReflectorChoice(
            name,
            cheapest,
            tuple(predictions),
            True,
            f"the cheapest predicted within the budget (bound {cheapest.bound:.3g} <= {limit:.3g})",
            pixels,
        )

    def _by_time(
        self,
        scene: Scene,
        options: list[tuple[Reflector, list[Prediction], float] | None],
        room: float,
    ) -> tuple[ReflectorChoice, ...]:
        shown = [(i, o) for i, o in enumerate(options) if o is not None]
        if not shown:
            return tuple(self._unseen(r.name) for r in scene.reflectors)
        weights = np.array([o[2] for _, o in shown])
        weights = weights / max(weights.sum(), 1e-12)
        frontiers = [_frontier(o[1]) for _, o in shown]
        best = _best_within(frontiers, weights, room)
        fits = best is not None
        if best is None:
            best = tuple(min(f, key=lambda p: p.cost) for f in frontiers)
        current = []
        for _, option in shown:
            held = self._chosen.get(option[0].name)
            current.append(next((p for p in option[1] if p.candidate == held), None))
        if fits and all(c is not None for c in current):
            kept = tuple(c for c in current if c is not None)
            if sum(p.cost for p in kept) <= room and _objective(kept, weights) <= (
                _objective(best, weights) * (1.0 + TIME_KEEP) + 1e-9
            ):
                best = kept
        total = sum(p.cost for p in best)
        chosen = {i: p for (i, _), p in zip(shown, best, strict=True)}
        choices = []
        for i, reflector in enumerate(scene.reflectors):
            seen = options[i]
            if seen is None:
                choices.append(self._unseen(reflector.name))
                continue
            reason = (
                f"the most accurate combination predicted to fit ({total:.2f} of "
                f"{room:.2f} ms left after the frame's base)"
                if fits
                else f"nothing fits the time ({room:.2f} ms left after the frame's base): "
                "the cheapest"
            )
            choices.append(
                ReflectorChoice(reflector.name, chosen[i], tuple(seen[1]), fits, reason, seen[2])
            )
        return tuple(choices)


def _lookup_key(drawn: Reflector) -> tuple:
    """What decides where a candidate looks a ray up (its texture kind, a planar
    capture's own camera, a curved map's parallax correction), not its map size: the
    candidates with one key share their ``wrong`` and ``shift``."""
    entry = technique(drawn.technique)
    if entry.texture in ("static", "baked"):
        return ("background",)
    parallax = getattr(drawn, "parallax", None)
    if entry.texture == "fixed" and not isinstance(parallax, DistanceSearch):
        return ("fixed", drawn.kind, entry.own_camera, parallax)
    if entry.texture in ("viewer", "inline", "fixed"):
        return ("exact",)
    return ("other", entry.texture)


def _frontier(predictions: list[Prediction]) -> list[Prediction]:
    """The predictions no other beats in both cost and error, cheapest first."""
    ordered = sorted(predictions, key=lambda p: (p.cost, p.error))
    kept: list[Prediction] = []
    for p in ordered:
        if not kept or p.error < kept[-1].error:
            kept.append(p)
    return kept


def _objective(combination, weights: np.ndarray) -> float:
    return float(sum(w * p.error for w, p in zip(weights, combination, strict=True)))


def _best_within(
    frontiers: list[list[Prediction]], weights: np.ndarray, room: float
) -> tuple[Prediction, ...] | None:
    """The combination (one of each frontier) with the lowest weighted error whose cost is
    at most ``room``; None when even the cheapest does not fit."""
    if sum(f[0].cost for f in frontiers) > room:
        return None
    if math.prod(len(f) for f in frontiers) <= EXHAUSTIVE:
        best, score = None, math.inf
        for combination in itertools.product(*frontiers):
            if sum(p.cost for p in combination) <= room:
                value = _objective(combination, weights)
                if value < score:
                    best, score = combination, value
        return best
    picked = [0] * len(frontiers)  # greedy: the best error saved per millisecond
    spent = sum(f[0].cost for f in frontiers)
    while True:
        step, gain = None, 0.0
        for r, frontier in enumerate(frontiers):
            if picked[r] + 1 < len(frontier):
                now, then = frontier[picked[r]], frontier[picked[r] + 1]
                extra = then.cost - now.cost
                if spent + extra <= room:
                    value = weights[r] * (now.error - then.error) / max(extra, 1e-9)
                    if value > gain:
                        step, gain = r, value
        if step is None:
            return tuple(f[i] for f, i in zip(frontiers, picked, strict=True))
        spent += frontiers[step][picked[step] + 1].cost - frontiers[step][picked[step]].cost
        picked[step] += 1


def _parts(scene: Scene) -> int:
    from mirrorlab.bounds import scene_index

    return len(scene_index(scene).objects_part)


def _changes(
    before: Scene | None, scene: Scene, size: tuple[int, int], last: _Last | None
) -> frozenset[str]:
    """What changed since the last frame: ``viewer`` (moved), ``turned`` (the view's
    rotation), ``content`` (what captures show: objects, lights, background, other
    reflectors' places). The first frame is taken as still."""
    if before is None or last is None:
        return frozenset()
    found = set()
    if before.camera != scene.camera or last.size != size:
        found.add("viewer")
        from mirrorlab.views import camera_view

        old = camera_view(before.camera, last.size).view[:3, :3]
        new = camera_view(scene.camera, size).view[:3, :3]
        if not np.allclose(old, new, rtol=0.0, atol=1e-12):
            found.add("turned")
    if (
        before.objects != scene.objects
        or before.lights != scene.lights
        or before.background != scene.background
        or before.ambient != scene.ambient
        or _places(before) != _places(scene)
    ):
        found.add("content")
    return frozenset(found)


def _drifted(before: Scene, scene: Scene) -> bool:
    """Whether ``scene`` moved far enough from ``before`` (the scene of the last
    prediction) that the choice is predicted again (see :data:`EYE_DRIFT`)."""
    if (
        before.budget != scene.budget
        or before.background != scene.background
        or before.lights != scene.lights
        or before.ambient != scene.ambient
        or before.max_bounces != scene.max_bounces
        or len(before.reflectors) != len(scene.reflectors)
    ):
        return True
    old, new = before.camera, scene.camera
    if (old.fovy, old.near, old.far, old.up) != (new.fovy, new.near, new.far, new.up):
        return True
    eye0, eye1 = np.asarray(old.eye), np.asarray(new.eye)
    forward0 = np.asarray(old.target) - eye0
    forward1 = np.asarray(new.target) - eye1
    if _turn(forward0, forward1) > TURN_DRIFT:
        return True
    for a, b in zip(before.reflectors, scene.reflectors, strict=True):
        if _configuration_of(a) != _configuration_of(b):
            return True
        center0, center1 = _center(a), _center(b)
        distance = max(float(np.linalg.norm(center1 - eye1)), 1e-12)
        moved = float(np.linalg.norm(eye1 - eye0)) + float(np.linalg.norm(center1 - center0))
        if moved > EYE_DRIFT * distance:
            return True
        if isinstance(a, PlanarReflector) and isinstance(b, PlanarReflector):
            if _turn(a.normal, b.normal) > TURN_DRIFT:
                return True
        elif not isinstance(a, PlanarReflector) and not isinstance(b, PlanarReflector):
            if not np.allclose(a.model_matrix()[:3, :3], b.model_matrix()[:3, :3], atol=1e-3):
                return True
    if before.objects is not scene.objects and before.objects != scene.objects:
        from mirrorlab.bounds import scene_index

        first, second = scene_index(before), scene_index(scene)
        a_centres, b_centres = first.part_centers, second.part_centers
        if a_centres.shape != b_centres.shape:
            return True
        radius = max(second.sphere[1], 1e-12)
        if len(a_centres) and float(np.abs(a_centres - b_centres).max()) > OBJECT_DRIFT * radius:
            return True
    return False


def _turn(a: np.ndarray, b: np.ndarray) -> float:
    """The angle between two directions (radians)."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    return float(np.arctan2(np.linalg.norm(np.cross(a, b)), float(a @ b)))


def _center(reflector: Reflector) -> np.ndarray:
    from mirrorlab.bounds import bounding_sphere

    return bounding_sphere(reflector)[0]


def _configuration_of(reflector: Reflector) -> tuple:
    """A reflector's fields but where it is."""
    from dataclasses import fields

    from mirrorlab.budget.candidates import PLACEMENT_FIELDS

    kept = [f.name for f in fields(reflector) if f.name not in PLACEMENT_FIELDS]
    return (reflector.name, *(getattr(reflector, name) for name in kept))


def _places(scene: Scene) -> tuple:
    return tuple(
        r.corners if isinstance(r, PlanarReflector) else r.transform for r in scene.reflectors
    )


def _captures(kind: str, changes: frozenset[str]) -> bool:
    """Whether a candidate's texture (of ``kind``) is made again this frame."""
    if kind == "static" or kind == "inline":
        return False
    if kind == "baked":
        return "turned" in changes
    if kind == "fixed":
        return "content" in changes
    if kind == "viewer":
        return bool(changes & {"viewer", "content"})
    return True


def _apply(
    scene: Scene,
    choices: tuple[ReflectorChoice, ...],
    chosen: dict[str, Candidate],
    last: _Last | None,
) -> Scene:
    """``scene`` with each reflector drawn by its chosen candidate (one not in view by the
    one it had, or as the scene gives it); the last output's reflectors themselves when
    they come out the same."""
    reflectors = []
    for reflector, choice in zip(scene.reflectors, choices, strict=True):
        candidate = (
            choice.chosen.candidate if choice.chosen is not None else chosen.get(choice.reflector)
        )
        reflectors.append(candidate.apply(reflector) if candidate is not None else reflector)
    made = tuple(reflectors)
    if last is not None and made == last.output.reflectors:
        made = last.output.reflectors
    return replace(scene, reflectors=made)


def choose_frames(
    scene: Scene,
    frames: Sequence[int],
    size: tuple[int, int],
    calibration: Calibration | None = None,
) -> dict[int, tuple[Scene, BudgetFrame]]:
    """The budget's choice for each of ``frames`` of ``scene`` (which has a budget), made
    by one chooser in frame order: each frame's posed scene as chosen, and the choice."""
    chooser = BudgetChooser(calibration)
    return {frame: chooser.choose(scene.at_frame(frame), size) for frame in sorted(frames)}
