"""The budget's predictions: each candidate's error and cost for one reflector in one
view, from the features of :mod:`mirrorlab.budget.features`, by models fitted to measured
sweeps (:mod:`mirrorlab.budget.calibrate`) and shipped as data
(``mirrorlab/budget/calibration.json``).

**Error.** One model per error family (a technique, with a live map's parallax correction:
:func:`mirrorlab.budget.candidates.error_family`) and metric (mean FLIP, MAE), linear in
the square root of the error::

    sqrt(error) ~ b . basis(features)

over :data:`ERROR_BASIS`, fitted by least squares. The square root evens out the spread
(an exact technique's errors are small and close together, a wrong one's large and far
apart) and keeps the prediction non-negative once squared. Its **bound** adds the
margin: the 95th percentile of the model's errors on samples it was not fitted to
(five-fold cross-validation, by scene), in the same square-root units, so that the
bound is met by about 95% of reflectors of the calibration class. A family with too few
samples is predicted by its texture kind's pooled model (a technique registered after
the calibration is predicted so until the calibration is made again).

**Cost.** Per cost family, the extra CPU milliseconds of a frame when the reflector is
drawn by the candidate, split into its draw (every frame) and its captures and bakes
(the frames where what its texture shows changed), each linear in a few counts
(:data:`COST_BASIS`) with non-negative weights; a frame's base (the view without
reflectors) is one model for all.

Numpy only.
"""

from __future__ import annotations

import functools
import json
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from importlib.resources import files
from pathlib import Path
from typing import Any

import numpy as np

CALIBRATION_VERSION = 1
COVERAGE = 0.95
"""The share of the calibration's held-out samples a bound must cover."""
MIN_ROWS = 40
"""A family fitted on fewer samples is predicted by its texture kind's pooled model."""
ERROR_BASIS = (
    "one",
    "wrong",
    "shift",
    "coarse",
    "coarse2",
    "fine",
    "objects",
    "grazing",
    "pixels",
    "near",
    "offscreen",
)
"""The error models' terms: a constant; ``wrong``; ``shift`` (/64, saturating); the map's
resolution below one texel a pixel (``coarse`` = max(0, -texels), and its square) and
above it (``fine`` = max(0, texels)); the reflector's share of object rays; its grazing;
its size on screen (log2 pixels, centred on 2^13 and in units of 4); how near what it
shows is; its rays that leave the screen."""
COST_BASIS = ("one", "pixels", "texels", "parts")
"""The cost models' terms: a constant, the reflector's pixels (/1e4), its texture's
texels (/1e5), the scene's object parts."""
BASE_BASIS = ("one", "frame", "parts")
"""The base cost's terms: a constant, the frame's pixels (/1e4), the object parts."""


def error_basis(features: np.ndarray) -> np.ndarray:
    """``(n, len(ERROR_BASIS))`` terms from features ``(n, 8)``: ``log2 pixels, grazing,
    objects, offscreen, near, wrong, shift, texels`` per row."""
    f = np.atleast_2d(np.asarray(features, dtype=np.float64))
    log_pixels, grazing, objects, offscreen, near, wrong, shift, texels = f.T
    coarse = np.maximum(-texels, 0.0)
    return np.column_stack(
        [
            np.ones(len(f)),
            wrong,
            1.0 - np.exp(-shift / 8.0),
            coarse,
            coarse**2,
            np.maximum(texels, 0.0),
            objects,
            grazing,
            (log_pixels - 13.0) / 4.0,
            np.minimum(near, 2.0),
            offscreen,
        ]
    )


def cost_basis(pixels: np.ndarray, texels: np.ndarray, parts: np.ndarray) -> np.ndarray:
    """``(n, len(COST_BASIS))`` cost terms."""
    pixels = np.asarray(pixels, dtype=np.float64)
    return np.column_stack(
        [
            np.ones(len(pixels)),
            pixels / 1e4,
            np.asarray(texels, dtype=np.float64) / 1e5,
            np.asarray(parts, dtype=np.float64),
        ]
    )


def base_basis(frame_pixels: float, parts: float) -> np.ndarray:
    return np.array([1.0, frame_pixels / 1e4, float(parts)])


@dataclass(frozen=True)
class ErrorModel:
    """``coefficients`` over :data:`ERROR_BASIS` (predicting the error's square root),
    the ``margin`` added (in square-root units) for the bound, and the ``rows`` fitted."""

    coefficients: tuple[float, ...]
    margin: float
    rows: int

    def predict(self, basis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Predicted error and its bound for each row of ``basis``."""
        root = np.maximum(basis @ np.asarray(self.coefficients), 0.0)
        return root**2, (root + self.margin) ** 2


@dataclass(frozen=True)
class CostModel:
    """A cost family's ``draw`` and ``capture`` weights over :data:`COST_BASIS`
    (milliseconds), from ``rows`` timed samples."""

    draw: tuple[float, ...]
    capture: tuple[float, ...]
    rows: int

    def predict(self, basis: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Draw and capture milliseconds for each row of ``basis``."""
        return basis @ np.asarray(self.draw), basis @ np.asarray(self.capture)


@dataclass(frozen=True)
class Calibration:
    """What the budget predicts with: per metric, the error models by family (and by
    texture kind, for families without one); the cost models by cost family (and by
    texture kind); the base cost's weights; and where it came from (``meta``)."""

    errors: Mapping[str, Mapping[str, ErrorModel]]
    kind_errors: Mapping[str, Mapping[str, ErrorModel]]
    costs: Mapping[str, CostModel]
    kind_costs: Mapping[str, CostModel]
    base: tuple[float, ...]
    meta: Mapping[str, Any] = field(default_factory=dict)

    def error_model(self, metric: str, family: str, kind: str) -> ErrorModel:
        """The model of ``family`` (texture kind ``kind``) for ``metric``: its own, its
        kind's pooled one, or the widest of all."""
        own = self.errors.get(metric, {}).get(family)
        if own is not None:
            return own
        pooled = self.kind_errors.get(metric, {})
        if kind in pooled:
            return pooled[kind]
        return pooled["any"]

    def cost_model(self, family: str, kind: str) -> CostModel:
        return self.costs.get(family) or self.kind_costs.get(kind) or self.kind_costs["any"]

    def to_json(self) -> str:
        def error_table(models: Mapping[str, Mapping[str, ErrorModel]]) -> dict:
            return {
                metric: {
                    name: {
                        "coefficients": list(m.coefficients),
                        "margin": m.margin,
                        "rows": m.rows,
                    }
                    for name, m in sorted(table.items())
                }
                for metric, table in models.items()
            }

        def cost_table(models: Mapping[str, CostModel]) -> dict:
            return {
                name: {"draw": list(m.draw), "capture": list(m.capture), "rows": m.rows}
                for name, m in sorted(models.items())
            }

        return json.dumps(
            {
                "version": CALIBRATION_VERSION,
                "error_basis": list(ERROR_BASIS),
                "cost_basis": list(COST_BASIS),
                "base_basis": list(BASE_BASIS),
                "errors": error_table(self.errors),
                "kind_errors": error_table(self.kind_errors),
                "costs": cost_table(self.costs),
                "kind_costs": cost_table(self.kind_costs),
                "base": list(self.base),
                "meta": dict(self.meta),
            },
            indent=1,
        )


class CalibrationError(ValueError):
    """A calibration file that cannot be used."""


def calibration_from_json(text: str, source: str = "calibration") -> Calibration:
    """A :class:`Calibration` from :meth:`Calibration.to_json` text; CalibrationError
    naming ``source`` and what is wrong otherwise."""
    try:
        data = json.loads(text)
        if data.get("version") != CALIBRATION_VERSION:
            raise CalibrationError(
                f"{source}: version {data.get('version')!r}, expected {CALIBRATION_VERSION} "
                "(make it again with mirrorlab bench calibrate)"
            )
        for key, basis in (
            ("error_basis", ERROR_BASIS),
            ("cost_basis", COST_BASIS),
            ("base_basis", BASE_BASIS),
        ):
            if tuple(data[key]) != basis:
                raise CalibrationError(f"{source}: {key} is {data[key]}, expected {list(basis)}")

        def errors(table: dict, width: int) -> dict[str, dict[str, ErrorModel]]:
            return {
                metric: {
                    name: ErrorModel(
                        _numbers(m["coefficients"], width), float(m["margin"]), int(m["rows"])
                    )
                    for name, m in models.items()
                }
                for metric, models in table.items()
            }

        def costs(table: dict) -> dict[str, CostModel]:
            return {
                name: CostModel(
                    _numbers(m["draw"], len(COST_BASIS)),
                    _numbers(m["capture"], len(COST_BASIS)),
                    int(m["rows"]),
                )
                for name, m in table.items()
            }

        made = Calibration(
            errors(data["errors"], len(ERROR_BASIS)),
            errors(data["kind_errors"], len(ERROR_BASIS)),
            costs(data["costs"]),
            costs(data["kind_costs"]),
            _numbers(data["base"], len(BASE_BASIS)),
            data.get("meta", {}),
        )
    except CalibrationError:
        raise
    except (KeyError, TypeError, ValueError, AttributeError) as exc:
        raise CalibrationError(f"{source}: not a budget calibration ({exc})") from None
    for metric in ("flip", "mae"):
        if "any" not in made.kind_errors.get(metric, {}):
            raise CalibrationError(f"{source}: no pooled {metric} model")
    if "any" not in made.kind_costs:
        raise CalibrationError(f"{source}: no pooled cost model")
    return made


def _numbers(values: Sequence[Any], width: int) -> tuple[float, ...]:
    numbers = tuple(float(v) for v in values)
    if len(numbers) != width or not all(math.isfinite(v) for v in numbers):
        raise ValueError(f"expected {width} finite numbers, got {list(values)}")
    return numbers


SHIPPED = "calibration.json"


@functools.lru_cache(maxsize=8)
def load_calibration(path: str | None = None) -> Calibration:
    """The calibration at ``path``, or the shipped one (package data)."""
    if path is None:
        text = files("mirrorlab.budget").joinpath(SHIPPED).read_text(encoding="utf-8")
        return calibration_from_json(text, f"mirrorlab/budget/{SHIPPED}")
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise CalibrationError(f"{path}: cannot read it ({exc})") from None
    return calibration_from_json(text, str(path))


# --------------------------------------------------------------------------- fitting


def nnls(matrix: np.ndarray, target: np.ndarray, iterations: int = 200) -> np.ndarray:
    """Non-negative least squares (Lawson and Hanson's active set method): the ``x >= 0``
    that minimises ``|matrix @ x - target|``."""
    a = np.asarray(matrix, dtype=np.float64)
    b = np.asarray(target, dtype=np.float64)
    n = a.shape[1]
    x = np.zeros(n)
    passive = np.zeros(n, dtype=bool)
    for _ in range(iterations):
        gradient = a.T @ (b - a @ x)
        if passive.all() or gradient[~passive].max(initial=-np.inf) <= 1e-10:
            break
        candidates = np.where(~passive, gradient, -np.inf)
        passive[int(np.argmax(candidates))] = True
        while True:
            z = np.zeros(n)
            z[passive] = np.linalg.lstsq(a[:, passive], b, rcond=None)[0]
            if (z[passive] > 0).all():
                x = z
                break
            shrinking = passive & (z <= 0)
            alpha = np.min(x[shrinking] / np.maximum(x[shrinking] - z[shrinking], 1e-300))
            x = x + alpha * (z - x)
            passive &= x > 1e-12
            x[~passive] = 0.0
    return x


def fit_error_model(
    basis: np.ndarray, error: np.ndarray, groups: np.ndarray, folds: int = 5
) -> tuple[ErrorModel, np.ndarray]:
    """An :class:`ErrorModel` of ``error`` ``(n,)`` on ``basis`` ``(n, k)``, its margin
    from ``folds``-fold cross-validation over ``groups`` (the samples' scenes: a scene's
    rows are held out together). Returns it and the held-out predictions' square roots."""
    root = np.sqrt(np.maximum(error, 0.0))
    coefficients = _ridge(basis, root)
    held_out = np.zeros(len(root))
    names = np.unique(groups)
    order = np.random.default_rng(0).permutation(len(names))
    for fold in range(folds):
        out = np.isin(groups, names[order[fold::folds]])
        if out.all() or not out.any():
            held_out[out] = basis[out] @ coefficients
            continue
        held_out[out] = basis[out] @ _ridge(basis[~out], root[~out])
    held_out = np.maximum(held_out, 0.0)
    margin = float(np.quantile(root - held_out, COVERAGE)) if len(root) else 1.0
    return ErrorModel(tuple(float(c) for c in coefficients), max(margin, 0.0), len(root)), held_out


def _ridge(basis: np.ndarray, target: np.ndarray, strength: float = 1e-3) -> np.ndarray:
    """Least squares with a little ridge, so that terms a family never varies stay 0."""
    k = basis.shape[1]
    penalty = strength * len(target) * np.eye(k)
    penalty[0, 0] = 0.0
    return np.linalg.solve(basis.T @ basis + penalty, basis.T @ target)
