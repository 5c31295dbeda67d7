"""FLIP, the perceptual error of Andersson et al. 2020 ("FLIP: A Difference Evaluator for
Alternating Images"), in its low-dynamic-range form, through NVIDIA's ``flip-evaluator``
package (the ``flip`` extra). It has wheels for Linux x86_64, macOS and Windows but none
for Linux aarch64: where it cannot be imported, :func:`flip_map` returns None and
:data:`MISSING` says why, so tables leave the column empty instead of failing.

Numpy only besides the package; no OpenGL.
"""

from __future__ import annotations

import importlib
import math
from types import ModuleType

import numpy as np

MISSING: str | None = None
"""Why FLIP cannot be computed here (None where it can)."""

_evaluator: ModuleType | None
try:
    _evaluator = importlib.import_module("flip_evaluator")
except ImportError as error:  # no wheel for this platform, or the extra not installed
    _evaluator = None
    MISSING = (
        f"FLIP needs the flip-evaluator package ({error}); "
        "install mirrorlab[flip] (no wheel exists for Linux aarch64)"
    )


def available() -> bool:
    """Whether :func:`flip_map` computes FLIP here."""
    return _evaluator is not None


def flip_map(image: np.ndarray, truth: np.ndarray) -> np.ndarray | None:
    """LDR-FLIP of ``image`` against ``truth``, both ``(h, w, 3)`` uint8 sRGB pictures:
    an ``(h, w)`` float32 map in [0, 1] (0: indistinguishable), at FLIP's default 67 pixels
    per degree. None where flip-evaluator is missing (:data:`MISSING`)."""
    if _evaluator is None:
        return None
    if image.shape != truth.shape or image.ndim != 3 or image.shape[2] != 3:
        raise ValueError(f"FLIP needs two (h, w, 3) pictures, got {image.shape} and {truth.shape}")
    reference = truth.astype(np.float32) / 255.0
    test = image.astype(np.float32) / 255.0
    error, _mean, _parameters = _evaluator.evaluate(reference, test, "LDR", applyMagma=False)
    return np.asarray(error, dtype=np.float32).reshape(image.shape[:2])


PIXELS_PER_DEGREE = 0.7 * 3840 / 0.7 * math.pi / 180
"""FLIP's default viewing condition, which :func:`flip_map` uses: a 4K monitor 0.7 m wide
seen from 0.7 m, about 67 pixels per degree."""

REACH = max(
    math.ceil(3.0 * math.sqrt(0.04 / (2.0 * math.pi**2)) * PIXELS_PER_DEGREE),
    math.ceil(3.0 * 0.5 * 0.082 * PIXELS_PER_DEGREE),
)
"""How far, in pixels, a pixel's FLIP value looks at its surroundings (10 at 67 pixels per
degree): the radius of FLIP's widest filter, the colour pipeline's contrast-sensitivity
Gaussian (its largest scale, 0.04 square degrees, out to 3 standard deviations) or the
edge and point detectors' (a standard deviation of half of 0.082 degrees, out to 3)."""


def region_mean(image: np.ndarray, truth: np.ndarray, mask: np.ndarray) -> float | None:
    """The mean of :func:`flip_map` over the pixels where ``mask`` ``(h, w)`` is True, as
    on the whole pictures, computed on the mask's bounding box grown by :data:`REACH`
    pixels only (what falls within them is all those pixels' values depend on). None
    where flip-evaluator is missing; NaN for an empty mask."""
    if _evaluator is None:
        return None
    rows, columns = np.nonzero(mask)
    if len(rows) == 0:
        return math.nan
    top, bottom = max(int(rows.min()) - REACH, 0), int(rows.max()) + 1 + REACH
    left, right = max(int(columns.min()) - REACH, 0), int(columns.max()) + 1 + REACH
    window = np.s_[top:bottom, left:right]
    error = flip_map(image[window], truth[window])
    assert error is not None
    return float(error[mask[window]].mean())
