"""Helpers of the environment-map tests: a frame into a uint8 or float target (optionally
with the curved reflectors' lookup coordinates instead of colours, or from a view other
than the camera's), and errors against the ray tracer."""

from __future__ import annotations

import numpy as np
import pytest

from mirrorlab.gl.context import check_gl_errors
from mirrorlab.gl.resources import FloatFramebuffer, Framebuffer
from mirrorlab.passes.envmap import OUTPUT_COLOR
from mirrorlab.scene.model import CurvedReflector
from mirrorlab.testing import difference_image
from tests.imagecheck import save_failure


def render(
    renderer, scene, size: int, float_target: bool = False, output: int = OUTPUT_COLOR, view=None
):
    """``(image, stats)`` of one frame of ``scene`` in a ``size`` square target (float32 RGB
    for ``float_target``, else uint8), seen by its camera or ``view``
    (:class:`mirrorlab.views.View`). ``output`` (e.g. OUTPUT_COORDINATES) is set on every
    curved reflector's pass after a first frame has made them, for a second frame, and
    put back to colour afterwards."""
    target = (FloatFramebuffer if float_target else Framebuffer)(renderer.registry, size, size)
    try:
        stats = renderer.render(scene, target, view=view)
        if output != OUTPUT_COLOR:
            passes = [
                renderer.pass_for(r.name)
                for r in scene.reflectors
                if isinstance(r, CurvedReflector)
            ]
            for curved in passes:
                curved.output_mode = output
            try:
                stats = renderer.render(scene, target, view=view)
            finally:
                for curved in passes:
                    curved.output_mode = OUTPUT_COLOR
        image = target.read()
        check_gl_errors(f"a frame of {scene.name}")
        return image, stats
    finally:
        target.release()


def region_error(image: np.ndarray, truth: np.ndarray, mask: np.ndarray) -> tuple[float, float]:
    """Mean absolute channel error (0-255) and share of pixels with a channel off by > 10."""
    diff = np.abs(image.astype(np.int32) - truth.astype(np.int32))[mask]
    return float(diff.mean()), float(np.mean(diff.max(axis=-1) > 10))


def assert_close_to_truth(name, image, truth, mask, max_mean, max_share):
    """Fails (writing actual, expected and difference images) when ``image`` is further
    from ``truth`` under ``mask`` than ``max_mean`` /255 on average or has more than
    ``max_share`` of its pixels off by > 10/255; returns (mean, share)."""
    mean, share = region_error(image, truth, mask)
    if mean > max_mean or share > max_share:
        folder = save_failure(
            name, actual=image, expected=truth, diff=difference_image(image, truth)
        )
        pytest.fail(
            f"{name}: mean abs error {mean:.2f}/255 (max {max_mean}), "
            f"{share:.1%} of pixels off by > 10 (max {max_share:.0%}); images in {folder}"
        )
    return mean, share


def drawn_mode(stats, reflector: str) -> str:
    """How the camera's view drew ``reflector`` in the frame of ``stats``."""
    return next(d.mode for d in stats.plan.top.draws if d.reflector.name == reflector)
