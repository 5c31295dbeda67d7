"""Measuring candidates against the truth, for the budget's calibration
(:mod:`mirrorlab.budget.calibrate`) and its benchmark (:mod:`mirrorlab.budget.bench`):
the ray-traced truth of a frame with each reflector's pixels, a frame's error per
reflector, and a frame's cost.

**Error** is the mean LDR-FLIP (or the MAE, in levels of 255) over a reflector's pixels
against the truth (:func:`mirrorlab.accuracy.image_error`), the truth traced as the
accuracy sweep traces it (4 x 4 rays a pixel when the scene has a curved reflector, the
curved reflectors' pixels shrunk by one pixel). FLIP looks at each pixel's
neighbourhood, so it is computed on the reflector's bounding rectangle grown by
:data:`FLIP_MARGIN` pixels, which gives the same values there as the whole picture does
(FLIP's widest filter at its 67 pixels per degree reaches less far).

**Cost** is a frame's CPU time in milliseconds (``time.process_time``, which counts
every thread of the process: llvmpipe rasterises on the CPU, in threads of its own),
``glFinish`` included: on a machine shared with other work, wall time measured 2 to 3
times more spread than CPU time. It is the median of a few frames, drawn either with
every capture and bake made again (:data:`FULL`: what a frame costs when whatever its
textures show has changed) or with all of them kept (:data:`DRAW`: the frame's draws
alone).
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from typing import TYPE_CHECKING, Literal

import numpy as np

from mirrorlab.scene.model import Scene

if TYPE_CHECKING:
    from mirrorlab.gl.resources import Framebuffer
    from mirrorlab.renderer import SceneRenderer

FLIP_MARGIN = 20
"""Pixels around a reflector's rectangle that its FLIP is computed with."""
FULL: Literal["full"] = "full"
DRAW: Literal["draw"] = "draw"
Regime = Literal["full", "draw"]


@dataclass(frozen=True)
class Truth:
    """A frame's truth: ``image`` ``(h, w, 3)`` uint8, ``masks`` ``(h, w)`` bool per
    reflector of the scene (its pixels scored), the tracer's ``milliseconds``."""

    image: np.ndarray
    masks: tuple[np.ndarray, ...]
    milliseconds: float


def supersample_of(scene: Scene) -> int:
    """Rays a pixel side the truth of ``scene`` is traced with: 4 with a curved reflector
    (a sphere compresses what it shows), else 1, as in the accuracy sweep."""
    return 4 if any(r.kind == "curved" for r in scene.reflectors) else 1


def trace_truth(scene: Scene, size: tuple[int, int]) -> Truth:
    """The truth of ``scene`` at ``size`` (a job: runs on any worker)."""
    from mirrorlab.accuracy import erode
    from mirrorlab.raytrace import trace_scene

    start = time.perf_counter()
    traced = trace_scene(scene, size, supersample_of(scene))
    milliseconds = (time.perf_counter() - start) * 1e3
    assert traced.reflector is not None
    masks = []
    for index, reflector in enumerate(scene.reflectors):
        mask = (traced.reflector == index) & traced.reflective_mask
        masks.append(erode(mask, 1) if reflector.kind == "curved" else mask)
    return Truth(traced.to_uint8(), tuple(masks), milliseconds)


@dataclass(frozen=True)
class Score:
    """A reflector's error in one frame: mean ``flip`` (NaN without flip-evaluator),
    ``mae`` in levels of 255, over ``pixels`` pixels (0: none to score, both NaN)."""

    flip: float
    mae: float
    pixels: int

    def of(self, metric: str) -> float:
        return self.flip if metric == "flip" else self.mae


def score(image: np.ndarray, truth: np.ndarray, mask: np.ndarray) -> Score:
    """``image`` against ``truth`` (``(h, w, 3)`` uint8) over ``mask`` ``(h, w)``."""
    from mirrorlab.accuracy import image_error

    found = np.nonzero(mask)
    if not len(found[0]):
        return Score(math.nan, math.nan, 0)
    height, width = mask.shape
    top = max(int(found[0].min()) - FLIP_MARGIN, 0)
    bottom = min(int(found[0].max()) + FLIP_MARGIN + 1, height)
    left = max(int(found[1].min()) - FLIP_MARGIN, 0)
    right = min(int(found[1].max()) + FLIP_MARGIN + 1, width)
    crop = (slice(top, bottom), slice(left, right))
    error = image_error(image[crop], truth[crop], mask[crop])
    return Score(error.flip, error.mae, error.pixels)


def score_images(truth: Truth, images: Sequence[tuple[int, np.ndarray]]) -> list[Score]:
    """Each ``(reflector index, image)`` of ``images`` against ``truth`` (a job)."""
    return [score(image, truth.image, truth.masks[index]) for index, image in images]


class FrameBench:
    """One offscreen context for measuring: a renderer and a frame target per size. Use
    :func:`frame_bench`."""

    def __init__(self, renderer: SceneRenderer, resources) -> None:
        self.renderer = renderer
        self.resources = resources
        self.targets: dict[tuple[int, int], Framebuffer] = {}

    def target(self, size: tuple[int, int]) -> Framebuffer:
        from mirrorlab.gl.resources import Framebuffer

        if size not in self.targets:
            self.targets[size] = Framebuffer(self.resources, *size)
        return self.targets[size]

    def forget(self, keep_bakes: bool) -> None:
        """Drop what the textures hold (all of it, or all but the baked maps), the last
        plan and the recorded frame, so the next frame is planned and drawn anew."""
        held = self.renderer.state.held
        for key in [k for k, v in held.items() if not (keep_bakes and v[0] in ("bake", "picture"))]:
            del held[key]
        self.renderer.memo.clear()

    def measure(
        self, scene: Scene, size: tuple[int, int], frames: int = 0
    ) -> tuple[np.ndarray, float, float]:
        """``scene`` drawn afresh at ``size`` (``(h, w, 3)`` uint8), and with ``frames``
        above 0 its costs: the median CPU milliseconds of ``frames`` frames drawn in each
        regime (:data:`FULL`: every capture and bake made again; :data:`DRAW`: all kept,
        the frame planned and drawn anew), the first, fresh frame one of the full ones
        (NaN without ``frames``)."""
        from mirrorlab.gl.opengl import GL

        target = self.target(size)
        full: list[float] = []
        draw: list[float] = []
        self.forget(keep_bakes=False)
        start = time.process_time()
        self.renderer.render(scene, target)
        GL.glFinish()
        full.append((time.process_time() - start) * 1e3)
        image = target.read()
        for regime in (DRAW, FULL) if frames else ():
            into = draw if regime == DRAW else full
            while len(into) < frames:
                if regime == FULL:
                    self.forget(keep_bakes=False)
                else:
                    self.renderer.memo.clear()
                start = time.process_time()
                self.renderer.render(scene, target)
                GL.glFinish()
                into.append((time.process_time() - start) * 1e3)
        if not frames:
            return image, math.nan, math.nan
        return image, float(np.median(full)), float(np.median(draw))


@contextmanager
def frame_bench() -> Iterator[FrameBench]:
    """A :class:`FrameBench` in an offscreen context of its own, released on leaving."""
    from mirrorlab.gl.context import offscreen_context
    from mirrorlab.renderer import SceneRenderer

    with offscreen_context() as context:
        renderer = SceneRenderer(context.resources)
        bench = FrameBench(renderer, context.resources)
        try:
            yield bench
        finally:
            for target in bench.targets.values():
                target.release()
            renderer.release()
