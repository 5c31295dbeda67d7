"""FLIP, the perceptual error of Andersson et al. 2020 ("FLIP: A Difference Evaluator for
Alternating Images"), in its low-dynamic-range form, through NVIDIA's ``flip-evaluator``
package (the ``flip`` extra). It has wheels for Linux x86_64, macOS and Windows but none
for Linux aarch64: where it cannot be imported, :func:`flip_map` returns None and
:data:`MISSING` says why, so tables leave the column empty instead of failing.

Numpy only besides the package; no OpenGL.
"""

from __future__ import annotations

import importlib
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
