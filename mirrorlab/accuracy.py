"""The accuracy-against-time sweep (``mirrorlab bench accuracy``): every reflection
technique, texture size and viewpoint, scored against the ray-traced ground truth inside
the reflector, and timed; then a table, a CSV and a plot.

:func:`run_panels` measures; :func:`run_command` is the command's whole work.
"""

from __future__ import annotations

import csv
import io
import math
import re
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from mirrorlab import flip
from mirrorlab.errors import BatchError
from mirrorlab.files import Outputs, write_bytes_atomic
from mirrorlab.jobs import Executor, Outcome, open_executor
from mirrorlab.options import apply_options
from mirrorlab.scene.loader import load_scene
from mirrorlab.scene.model import (
    CAPTURE_MODES,
    FOOTPRINT_TEXTURE,
    Camera,
    CurvedReflector,
    DistanceSearch,
    Scene,
)
from mirrorlab.techniques import techniques

if TYPE_CHECKING:
    from mirrorlab.gl.resources import Framebuffer, TimerQuery
    from mirrorlab.renderer import SceneRenderer

FULL_SIZES = (64, 128, 256, 512, 1024, 2048)
QUICK_SIZES = (64, 128)
OFF_BY = 10  # a pixel is "off" when a channel differs from the truth by more than 10/255


def lab_viewpoints() -> dict[str, Camera]:
    """The sweep's viewers, all looking at the mirror's centre (-7, 1, -2).

    ``head-on far`` stands 60 units out along the normal with a 10 degree
    field of view (the mirror fills most of the frame, nearly the
    orthographic capture's view); ``head-on near`` 14 units out; ``30 deg``
    and ``60 deg`` 16 units away, turned about the vertical; ``close`` 3 units
    from the glass, slightly off the normal.
    """
    center = np.array([-7.0, 1.0, -2.0])

    def around(distance: float, degrees: float, height: float = 0.0) -> tuple[float, float, float]:
        angle = math.radians(degrees)
        x, y, z = center + np.array([math.cos(angle), height, math.sin(angle)]) * distance
        return float(x), float(y), float(z)

    target = (float(center[0]), float(center[1]), float(center[2]))
    return {
        "head-on far": Camera(eye=around(60.0, 0.0), target=target, fovy=10.0),
        "head-on near": Camera(eye=around(14.0, 0.0), target=target),
        "30 deg": Camera(eye=around(16.0, 30.0), target=target),
        "60 deg": Camera(eye=around(16.0, 60.0), target=target),
        "close": Camera(eye=around(3.0, 15.0, 0.1), target=target, fovy=60.0),
    }


@dataclass(frozen=True)
class ImageError:
    """Error of an image against the truth over a region of ``pixels`` pixels, channels
    in 0..255 units: mean absolute error, 95th percentile of the per-pixel worst channel,
    PSNR in dB (inf when identical), and the share of pixels off by more than
    ``OFF_BY``; ``flip``, the mean LDR-FLIP over the region (0..1; NaN where the
    flip-evaluator package is missing, :data:`mirrorlab.flip.MISSING`). A region with no
    pixels has no error to tell: every figure is NaN (reported as "no reflector pixels",
    never as zero error; see :attr:`empty`)."""

    mae: float
    p95: float
    psnr: float
    share_off: float
    pixels: int = -1
    flip: float = math.nan

    @property
    def empty(self) -> bool:
        return self.pixels == 0


NO_REFLECTOR_PIXELS = "no reflector pixels"
"""What a table says where the truth saw no reflector (the camera inside a sphere, a
mirror out of view): there is nothing to score."""


def image_error(image: np.ndarray, truth: np.ndarray, mask: np.ndarray) -> ImageError:
    """Compare ``image`` and ``truth`` ``(h, w, 3)`` uint8 where ``mask`` ``(h, w)`` is True.

    An empty mask (nothing reflective in view) has no error: NaN figures, 0 pixels.
    """
    count = int(np.count_nonzero(mask))
    if count == 0:
        return ImageError(math.nan, math.nan, math.nan, math.nan, 0)
    diff = np.abs(image.astype(np.float64) - truth.astype(np.float64))[mask]
    worst = diff.max(axis=1)
    mse = float(np.mean(diff**2))
    psnr = math.inf if mse == 0.0 else 10.0 * math.log10(255.0**2 / mse)
    # FLIP looks at each pixel's surroundings: its map is computed on the region and what
    # lies within reach of it, and only then averaged over the region.
    flip_error = flip.region_mean(image, truth, mask)
    return ImageError(
        float(diff.mean()),
        float(np.percentile(worst, 95)),
        psnr,
        float(np.mean(worst > OFF_BY)),
        count,
        math.nan if flip_error is None else flip_error,
    )


@dataclass(frozen=True)
class SweepRow:
    """One measured configuration: ``scene`` ("lab" mirror, or "sphere-sky",
    "sphere-objects" and "sphere-room" for the environment maps),
    technique, map size (0: the technique has no texture) and viewpoint; the error
    figures of :class:`ImageError`; times are medians in milliseconds (``gpu_ms`` from
    GL timer queries, NaN where there is no GL work); ``pixels`` the reflector pixels
    scored (0: none, and the error figures NaN; -1: not recorded, in a CSV from before
    the column); ``flip`` the mean LDR-FLIP over them (NaN where flip-evaluator is
    missing, or in a CSV from before the column); ``miss_share`` the share of them that
    the technique filled from its fallback (:func:`fallback_share`; NaN for a technique
    without one)."""

    scene: str
    technique: str
    map_size: int
    viewpoint: str
    mae: float
    p95: float
    psnr: float
    share_off: float
    wall_ms: float
    gpu_ms: float
    pixels: int = -1
    flip: float = math.nan
    miss_share: float = math.nan


REQUIRED_COLUMNS = 10
"""A sweep's CSV holds at least the first ten of :class:`SweepRow`'s fields, in order;
the later ones (``pixels``, ``flip``, ``miss_share``) came later, and a CSV written before
any of them still loads (its missing figures NaN, ``pixels`` -1)."""

TRUTH = "raytrace"
"""The technique whose rows are the ground truth itself (labelled ``raytrace`` or
``raytrace NxN`` when supersampled): zero error by definition, never a point of a plot's
axes or of a Pareto frontier."""


def is_truth(technique: str) -> bool:
    """Whether ``technique`` (a row's label) is the ground truth's row."""
    return technique == TRUTH or technique.startswith(f"{TRUTH} ")


def fallback_share(fallback: np.ndarray | None, mask: np.ndarray) -> float:
    """The share of the scored pixels (``mask`` ``(h, w)`` bool) that a technique filled
    from its fallback (``fallback`` ``(h, w)`` bool, from
    :meth:`mirrorlab.renderer.SceneRenderer.fallback_mask`): NaN where the technique has
    none (``fallback`` None) or nothing is scored."""
    count = int(np.count_nonzero(mask))
    if fallback is None or count == 0:
        return math.nan
    if fallback.shape != mask.shape:
        raise ValueError(f"a fallback mask of shape {fallback.shape} for a frame of {mask.shape}")
    return float(np.count_nonzero(fallback & mask)) / count


DEFAULT_STEPS = f"{DistanceSearch().steps}+{DistanceSearch().secant}"
DISTANCE_STEPS = ("2+0", "4+1", DEFAULT_STEPS, "16+2", "32+4")
"""Linear + secant steps of the distance search, measured at one map size (see
:func:`search_map_size`); the default steps (8+2) are measured at every size."""


@dataclass(frozen=True)
class SweepSettings:
    """``frame`` side in pixels, texture ``sizes``, ``frames`` timed per configuration
    after ``warmup`` frames, which viewpoints to use (None: all), the distance search's
    ``steps`` (linear+secant) compared at one map size, and ``curved_sizes``, the
    environment maps' sizes where they are not ``sizes``."""

    frame: int = 512
    sizes: tuple[int, ...] = FULL_SIZES
    frames: int = 15
    warmup: int = 3
    viewpoints: tuple[str, ...] | None = None
    steps: tuple[str, ...] = DISTANCE_STEPS
    curved_sizes: tuple[int, ...] | None = None

    @property
    def map_sizes(self) -> tuple[int, ...]:
        """The environment maps' sizes: ``curved_sizes``, else ``sizes``."""
        return self.sizes if self.curved_sizes is None else self.curved_sizes

    @classmethod
    def quick(cls) -> SweepSettings:
        """A small sweep for tests: 128-pixel frames, two sizes for the mirror's captures
        and the larger for the environment maps (each curved technique of the registry
        adds a row per size, panel and correction: a sweep of them all at both sizes
        would grow with each), two viewpoints, the distance search with its default
        steps only."""
        return cls(
            frame=128,
            sizes=QUICK_SIZES,
            frames=3,
            warmup=1,
            viewpoints=("head-on far", "60 deg"),
            steps=(),
            curved_sizes=QUICK_SIZES[-1:],
        )


def lab_techniques(sizes: Sequence[int]) -> list[tuple[str, dict]]:
    """``(label, options)`` for each planar configuration: every capturing technique with
    each capture mode and texture size (and, for one with a camera of its own, a texture
    the size of the mirror's footprint on screen: labelled ``... footprint``, its map
    size 0, as it differs from view to view), and the stencil mirror."""
    rows = []
    planar = techniques("planar")
    for entry in (t for t in planar if t.texture in CAPTURED):
        for capture in CAPTURE_MODES:
            rows += [
                (
                    f"{entry.name}-{capture}",
                    {"method": entry.name, "capture": capture, "env_size": size},
                )
                for size in sizes
            ]
            if entry.own_camera:
                rows.append(
                    (
                        f"{entry.name}-{capture} {FOOTPRINT_TEXTURE}",
                        {"method": entry.name, "capture": capture, "env_size": FOOTPRINT_TEXTURE},
                    )
                )
    rows += [
        (entry.name, {"method": entry.name}) for entry in planar if entry.texture not in CAPTURED
    ]
    return rows


CAPTURED = ("fixed", "viewer")
"""The texture kinds of the planar techniques that capture into a texture (measured at
each capture mode and size); the others (drawn in place, or from the view's own frame)
are measured once."""


def search_map_size(sizes: Sequence[int]) -> int:
    """The map size the distance search's steps are compared at: 256, or the largest
    of ``sizes`` below it."""
    below = [size for size in sizes if size <= 256]
    return max(below) if below else min(sizes)


def curved_techniques(
    sizes: Sequence[int],
    proxies: Sequence[tuple[str, str]] = (),
    steps: Sequence[str] = DISTANCE_STEPS,
) -> list[tuple[str, dict]]:
    """``(label, options)`` for every curved technique at each map size, and the live cube
    map with each parallax correction: the ``proxies`` (``(label, --parallax text)``), and
    the distance search at every size and with each other of ``steps`` (linear+secant)
    at the :func:`search_map_size` (labelled ``cube-live distance STEPS``); a technique
    with a probe that takes a parallax correction (``ssr``), plain and with its probe's
    distance search at each size."""
    sizes = [size for size in sizes if size <= ENVMAP_MAX_SIZE]
    rows = []
    for entry in techniques("curved"):
        plain = {"parallax": "none"} if entry.parallax else {}
        rows += [(entry.name, {"method": entry.name, "map_size": size, **plain}) for size in sizes]
    searched = search_map_size(sizes)
    for entry in techniques("curved"):
        if entry.probe and entry.parallax:  # its probe with the distance search
            rows += [
                (
                    f"{entry.name} distance",
                    {"method": entry.name, "map_size": size, "parallax": "distance"},
                )
                for size in sizes
            ]
    for name in (
        entry.name for entry in techniques("curved") if entry.parallax and not entry.probe
    ):
        corrections = [(f"{name} {label}", text) for label, text in proxies]
        corrections.append((f"{name} distance", "distance"))
        for label, text in corrections:
            rows += [
                (label, {"method": name, "map_size": size, "parallax": text}) for size in sizes
            ]
        rows += [
            (
                f"{name} distance {other}",
                {"method": name, "map_size": searched, "parallax": f"distance:{other}"},
            )
            for other in steps
            if other != DEFAULT_STEPS
        ]
    return rows


def panel_configurations(panel: Panel, settings: SweepSettings) -> list[tuple[str, dict]]:
    """The configurations measured at each of ``panel``'s viewpoints (see
    :func:`scene_techniques`), as :func:`run_panels` measures them: one row each per
    viewpoint, after the ground truth's own row."""
    return scene_techniques(
        panel.scene, settings.sizes, panel.proxies, settings.steps, settings.map_sizes
    )


def sweep_rows(panels: Sequence[Panel], settings: SweepSettings) -> int:
    """How many rows :func:`run_panels` gives for ``panels``: at each viewpoint, the
    truth's and one per configuration."""
    return sum(
        len(panel.viewpoints) * (1 + len(panel_configurations(panel, settings))) for panel in panels
    )


def scene_techniques(
    scene: Scene,
    sizes: Sequence[int],
    proxies: Sequence[tuple[str, str]] = (),
    steps: Sequence[str] = DISTANCE_STEPS,
    curved_sizes: Sequence[int] | None = None,
) -> list[tuple[str, dict]]:
    """The configurations a scene's reflectors can take: the planar ones when it has a
    planar mirror, the curved ones (see :func:`curved_techniques`, at ``curved_sizes``
    when given) when it has a curved reflector."""
    kinds = {reflector.kind for reflector in scene.reflectors}
    rows = lab_techniques(sizes) if "planar" in kinds else []
    maps = sizes if curved_sizes is None else curved_sizes
    return rows + (curved_techniques(maps, proxies, steps) if "curved" in kinds else [])


def surroundings_box(scene: Scene) -> tuple[np.ndarray, np.ndarray] | None:
    """World min and max ``(3,)`` corners of the box around the scene's objects (None
    without objects)."""
    from mirrorlab import math3d
    from mirrorlab.scene.mesh import load_mesh
    from mirrorlab.scene.robot import scene_parts

    points = [
        math3d.transform_points(part.model, load_mesh(part.mesh).positions.astype(np.float64))[
            :, :3
        ]
        for part in scene_parts(scene)
    ]
    if not points:
        return None
    every = np.vstack(points)
    return every.min(axis=0), every.max(axis=0)


def proxies_for(scene: Scene) -> tuple[tuple[str, str], ...]:
    """The box and sphere proxies the sweep gives a scene's live cube maps, as
    ``(label, --parallax text)``: the box around the scene's objects (a room's walls, or
    everything around a sphere outdoors) and the largest sphere around the first curved
    reflector's capture centre inside that box. None when the box does not hold that
    centre."""
    curved = [r for r in scene.reflectors if isinstance(r, CurvedReflector)]
    box = surroundings_box(scene)
    if not curved or box is None:
        return ()
    low, high = box
    center = curved[0].center()
    radius = float(min((center - low).min(), (high - center).min()))
    if not radius > 0:
        return ()
    corners = ",".join(f"{v:.6g}" for v in (*low, *high))
    return (("box", f"box:{corners}"), ("sphere", f"sphere:{radius:.6g}"))


@dataclass(frozen=True)
class Panel:
    """One scene of the sweep: ``name`` in the table, the ``scene``, its viewpoints, how
    the truth is traced (``supersample`` rays per pixel side, the reflective region
    shrunk by ``inset`` pixels: curved reflectors leave out the silhouette), and the
    ``proxies`` of its live cube maps."""

    name: str
    scene: Scene
    viewpoints: dict[str, Camera]
    supersample: int = 1
    inset: int = 0
    proxies: tuple[tuple[str, str], ...] = ()
    """The parallax proxies its live cube maps are measured with (see :func:`proxies_for`)."""


def lab_panel(settings: SweepSettings) -> Panel:
    viewpoints = lab_viewpoints()
    names = settings.viewpoints or tuple(viewpoints)
    unknown = [n for n in names if n not in viewpoints]
    if unknown:
        raise ValueError(f"unknown viewpoint {unknown[0]!r}; known: {', '.join(viewpoints)}")
    return Panel("lab", load_scene("lab20"), {n: viewpoints[n] for n in names})


def sphere_panels(settings: SweepSettings) -> list[Panel]:
    """The chrome sphere in the sky alone (what every map can hold), from the scene's
    camera and close up; among its lit objects (only ``cube-live`` reflects them); and
    in a room (``sphere_room``: indoors, where a box proxy is exact). The live cube map
    is measured with the proxies of the scene with its objects (:func:`proxies_for`)."""
    scene = load_scene("chrome_sphere")
    default = scene.camera
    close = Camera(eye=(0.6, 0.8, 2.4), target=(0.0, 0.0, 0.0), fovy=40.0)
    sky_views = {"default": default, "close": close}
    if settings.viewpoints is not None:  # the quick sweep: one view of each scene
        sky_views = {"default": default}
    proxies = proxies_for(scene)
    room = load_scene("sphere_room")
    return [
        Panel("sphere-sky", replace(scene, objects=()), sky_views, 4, 1, proxies),
        Panel("sphere-objects", scene, {"default": default}, 4, 1, proxies),
        Panel("sphere-room", room, {"default": room.camera}, 4, 1, proxies_for(room)),
    ]


def file_panel(scene: Scene) -> Panel:
    """Any scene file: its own camera, traced 4 x 4 when it has a curved reflector, whose
    live cube map is measured with the proxies of :func:`proxies_for`."""
    curved = any(r.kind == "curved" for r in scene.reflectors)
    return Panel(
        scene.name,
        scene,
        {"camera": scene.camera},
        4 if curved else 1,
        1 if curved else 0,
        proxies_for(scene) if curved else (),
    )


@dataclass(frozen=True)
class Truth:
    """A viewpoint's ground truth: the traced ``image`` ``(h, w, 3)`` uint8, the ``mask``
    ``(h, w)`` bool of the pixels scored (the reflective region shrunk by the panel's
    inset), and the median milliseconds the ray tracer took."""

    image: np.ndarray
    mask: np.ndarray
    milliseconds: float


def trace_truth(
    scene: Scene, size: tuple[int, int], supersample: int, inset: int, repeats: int
) -> Truth:
    """Trace ``scene`` ``repeats`` times (to time the ray tracer) at ``size`` with
    ``supersample`` x ``supersample`` rays a pixel: a job of the sweep's first phase."""
    from mirrorlab.raytrace import trace_scene

    times, truth = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        truth = trace_scene(scene, size, supersample)
        times.append((time.perf_counter() - start) * 1e3)
    assert truth is not None
    return Truth(truth.to_uint8(), erode(truth.reflective_mask, inset), float(np.median(times)))


@dataclass(frozen=True)
class Frame:
    """A configuration's last timed frame: the ``image`` ``(h, w, 3)`` uint8 and, for a
    technique with a fallback, the ``fallback`` ``(h, w)`` bool of the pixels it filled
    from it (None for the others)."""

    image: np.ndarray
    fallback: np.ndarray | None = None


def score_frames(truth: Truth, frames: Sequence[Frame]) -> list[tuple[ImageError, float]]:
    """Each of ``frames`` against ``truth``: its :class:`ImageError` and its
    :func:`fallback_share` over the scored pixels. A job of the third phase."""
    return [
        (
            image_error(frame.image, truth.image, truth.mask),
            fallback_share(frame.fallback, truth.mask),
        )
        for frame in frames
    ]


def run_panels(
    panels: Sequence[Panel],
    settings: SweepSettings,
    progress: bool = True,
    executor: Executor | None = None,
) -> list[SweepRow]:
    """Measure every technique of every panel at every viewpoint: one row per
    configuration and viewpoint, the ray tracer's own rows included (zero error, its
    time).

    Three phases, so that parallel work never runs while frames are timed:

    1. the ground truth of each viewpoint (:func:`trace_truth`), all sent to ``executor``
       at once (the slowest, supersampled ones first) while this process waits;
    2. every configuration's timed frames, one after another in this process, in one
       headless context, with the executor idle; the last frame of each is kept
       (512x512: 0.8 MB each, 270 MB for the full sweep);
    3. each viewpoint's error measurements (:func:`score_frames`), sent to the executor.

    Without an ``executor`` every phase runs here, in that order. The figures are the
    same either way (the ray tracer and the scoring are deterministic); only the times
    differ, and the ray tracer's own time is measured where its truth is traced (with
    two jobs, beside another trace).
    """
    from tqdm import tqdm

    executor = executor or Executor()
    size = (settings.frame, settings.frame)
    views = [
        (panel, name, replace(panel.scene, camera=camera))
        for panel in panels
        for name, camera in panel.viewpoints.items()
    ]
    configurations = [panel_configurations(panel, settings) for panel, _, _ in views]
    total = 2 * len(views) + sum(len(c) for c in configurations)
    bar = tqdm(
        total=total,
        desc="accuracy",
        unit="step",
        disable=not progress,
        file=sys.stderr,
        dynamic_ncols=True,
        mininterval=0.5,
    )
    truths: dict[int, Truth] = {}
    frames: dict[int, list[Frame]] = {}
    timings: dict[int, list[tuple[str, int, float, float]]] = {}
    errors: dict[int, list[tuple[ImageError, float]]] = {}
    with bar:
        bar.set_postfix_str("ray tracing the truths", refresh=False)
        order = sorted(range(len(views)), key=lambda i: -views[i][0].supersample)
        work = {
            f"truth-{i}": (
                views[i][2],
                size,
                views[i][0].supersample,
                views[i][0].inset,
                _truth_repeats(views[i][0], settings),
            )
            for i in order
        }
        for outcome in executor.run(trace_truth, work):
            truths[int(outcome.key.split("-")[1])] = _value(outcome, "ray tracing")
            bar.update()
        with sweep_gl(size) as (renderer, framebuffer, timer):
            for index, (panel, name, scene) in enumerate(views):
                frames[index], timings[index] = [], []
                for technique_label, options in configurations[index]:
                    configured = apply_options(scene, options)
                    size_option = options.get("env_size", options.get("map_size", 0))
                    map_size = size_option if isinstance(size_option, int) else 0
                    bar.set_postfix_str(
                        f"{technique_label} {map_size or ''} {panel.name} {name}", refresh=False
                    )
                    frame, wall, gpu = measure_frames(
                        renderer, configured, framebuffer, timer, settings
                    )
                    frames[index].append(frame)
                    timings[index].append((technique_label, map_size, wall, gpu))
                    bar.update()
        bar.set_postfix_str("scoring the frames", refresh=False)
        scoring = {f"score-{i}": (truths[i], frames[i]) for i in range(len(views))}
        for outcome in executor.run(score_frames, scoring):
            index = int(outcome.key.split("-")[1])
            errors[index] = _value(outcome, "scoring")
            frames[index] = []
            bar.update()
    rows: list[SweepRow] = []
    for index, (panel, name, _) in enumerate(views):
        label = (
            TRUTH if panel.supersample == 1 else f"{TRUTH} {panel.supersample}x{panel.supersample}"
        )
        scored = int(np.count_nonzero(truths[index].mask))
        none = math.nan if scored == 0 else 0.0  # the truth itself: no error, if any pixels
        rows.append(
            SweepRow(
                panel.name,
                label,
                0,
                name,
                none,
                none,
                math.nan if scored == 0 else math.inf,
                none,
                truths[index].milliseconds,
                math.nan,
                scored,
                none if flip.available() else math.nan,
            )
        )
        for (technique_label, map_size, wall, gpu), (error, missed) in zip(
            timings[index], errors[index], strict=True
        ):
            rows.append(
                SweepRow(
                    panel.name,
                    technique_label,
                    map_size,
                    name,
                    error.mae,
                    error.p95,
                    error.psnr,
                    error.share_off,
                    wall,
                    gpu,
                    error.pixels,
                    error.flip,
                    missed,
                )
            )
    return rows


def _truth_repeats(panel: Panel, settings: SweepSettings) -> int:
    """How often a truth is traced to time the ray tracer: a fifth of the timed frames
    when it traces one ray a pixel, once when supersampled (seconds a frame)."""
    return max(1, settings.frames // 5) if panel.supersample == 1 else 1


def _value(outcome: Outcome, what: str):
    if outcome.error is not None:
        raise BatchError(f"{what} failed on a worker: {outcome.error}")
    return outcome.value


@contextmanager
def sweep_gl(
    size: tuple[int, int],
) -> Iterator[tuple[SceneRenderer, Framebuffer, TimerQuery]]:
    """An offscreen context for a sweep: a renderer, a ``size`` (width, height) frame
    target and a GL timer query; all released on leaving."""
    from mirrorlab.gl.context import offscreen_context
    from mirrorlab.gl.resources import Framebuffer, TimerQuery
    from mirrorlab.renderer import SceneRenderer

    with offscreen_context() as context:
        renderer = SceneRenderer(context.resources)
        framebuffer = Framebuffer(context.resources, *size)
        timer = TimerQuery(context.resources)
        try:
            yield renderer, framebuffer, timer
        finally:
            timer.release()
            framebuffer.release()
            renderer.release()


def time_frames(
    render_frame: Callable[[], object],
    timer,
    settings: SweepSettings,
) -> tuple[float, float]:
    """Median wall and GL-timer milliseconds of ``settings.frames`` calls of
    ``render_frame`` after ``settings.warmup`` untimed ones."""
    from mirrorlab.gl.opengl import GL

    walls, gpus = [], []
    for frame in range(settings.warmup + settings.frames):
        start = time.perf_counter()
        timer.begin()
        render_frame()
        # llvmpipe rasterises lazily, at the next flush: finish inside the query, or
        # it would time little more than the recording of the commands.
        GL.glFinish()
        timer.end()
        wall = (time.perf_counter() - start) * 1e3
        gpu = timer.milliseconds()
        if frame >= settings.warmup:
            walls.append(wall)
            gpus.append(gpu)
    return float(np.median(walls)), float(np.median(gpus))


def measure_frames(
    renderer: SceneRenderer, scene: Scene, framebuffer, timer, settings: SweepSettings
) -> tuple[Frame, float, float]:
    """Time frames of ``scene`` (see :func:`time_frames`), each capturing its reflectors
    afresh as a moving scene would (maps baked from the background are kept). Returns
    the last frame (with the pixels its techniques filled from a fallback, where one
    has one: :meth:`~mirrorlab.renderer.SceneRenderer.fallback_mask`) and the median
    wall and GL milliseconds."""
    from mirrorlab.gl.context import check_gl_errors

    def frame() -> None:
        held = renderer.state.held
        for key in [k for k, v in held.items() if v[0] not in ("bake", "picture")]:
            del held[key]
        renderer.render(scene, framebuffer)

    wall, gpu = time_frames(frame, timer, settings)
    image = framebuffer.read()
    fallback = renderer.fallback_mask()
    check_gl_errors("a sweep frame")
    return Frame(image, fallback), wall, gpu


ENVMAP_MAX_SIZE = 1024
"""Largest environment map in the sweep: a 2048 cube is 25 million numpy-baked texels."""


def erode(mask: np.ndarray, pixels: int) -> np.ndarray:
    """``mask`` ``(h, w)`` bool shrunk by ``pixels`` (4-neighbour steps); outside is False."""
    out = np.asarray(mask, dtype=bool).copy()
    for _ in range(int(pixels)):
        padded = np.pad(out, 1, constant_values=False)
        out = (
            padded[1:-1, 1:-1]
            & padded[:-2, 1:-1]
            & padded[2:, 1:-1]
            & padded[1:-1, :-2]
            & padded[1:-1, 2:]
        )
    return out


@dataclass(frozen=True)
class SummaryRow:
    """A technique and size over all viewpoints: each error figure's mean over the
    viewpoints with reflector pixels (``psnr`` that of their mean squared error;
    ``flip`` and ``miss_share`` NaN where none of them has one), median times, and the
    viewpoint of the largest MAE."""

    scene: str
    technique: str
    map_size: int
    mae: float
    p95: float
    share_off: float
    wall_ms: float
    gpu_ms: float
    worst_viewpoint: str
    psnr: float = math.nan
    flip: float = math.nan
    miss_share: float = math.nan


def summarise(rows: Sequence[SweepRow]) -> list[SummaryRow]:
    """Group rows by (scene, technique, size) in first-seen order."""
    groups: dict[tuple[str, str, int], list[SweepRow]] = {}
    for row in rows:
        groups.setdefault((row.scene, row.technique, row.map_size), []).append(row)
    summary = []
    for (scene, technique, map_size), group in groups.items():
        # Viewpoints with no reflector pixels have no error: they are left out of the
        # means (and when every one is empty, so is the summary: NaN, not zero).
        scored = [r for r in group if not math.isnan(r.mae)]
        worst = max(scored, key=lambda r: r.mae) if scored else None
        gpu = [r.gpu_ms for r in group if not math.isnan(r.gpu_ms)]
        summary.append(
            SummaryRow(
                scene,
                technique,
                map_size,
                _mean([r.mae for r in scored]),
                _mean([r.p95 for r in scored]),
                _mean([r.share_off for r in scored]),
                float(np.median([r.wall_ms for r in group])),
                float(np.median(gpu)) if gpu else math.nan,
                worst.viewpoint if worst is not None else NO_REFLECTOR_PIXELS,
                _pooled_psnr([r.psnr for r in scored]),
                _mean([r.flip for r in scored if not math.isnan(r.flip)]),
                _mean([r.miss_share for r in scored if not math.isnan(r.miss_share)]),
            )
        )
    return summary


def _mean(values: Sequence[float]) -> float:
    return float(np.mean(values)) if values else math.nan


def _pooled_psnr(psnrs: Sequence[float]) -> float:
    """The PSNR (dB) of the mean of the squared errors the ``psnrs`` stand for (inf where
    every one is exact; NaN where there is none)."""
    known = [p for p in psnrs if not math.isnan(p)]
    if not known:
        return math.nan
    mse = float(np.mean([0.0 if math.isinf(p) else 255.0**2 / 10.0 ** (p / 10.0) for p in known]))
    return math.inf if mse == 0.0 else 10.0 * math.log10(255.0**2 / mse)


_INT_FIELDS = ("map_size", "pixels")
_TEXT_FIELDS = ("scene", "technique", "viewpoint")


def rows_to_csv(rows: Sequence[SweepRow]) -> str:
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow([f.name for f in fields(SweepRow)])
    for row in rows:
        writer.writerow([_csv_cell(v) for v in asdict(row).values()])
    return buffer.getvalue()


def rows_from_csv(text: str) -> list[SweepRow]:
    """Rows written by :func:`rows_to_csv` (to re-make the tables and plot without
    measuring again), also by an earlier version without the later columns (see
    :data:`REQUIRED_COLUMNS`: their figures NaN, ``pixels`` -1); ValueError naming the
    line that does not fit."""
    reader = csv.DictReader(io.StringIO(text))
    names = [f.name for f in fields(SweepRow)]
    columns = list(reader.fieldnames or [])
    if len(columns) < REQUIRED_COLUMNS or columns != names[: len(columns)]:
        raise ValueError(
            f"expected the columns {','.join(names)} (the last {len(names) - REQUIRED_COLUMNS} "
            f"may be left out), got {reader.fieldnames}"
        )
    rows = []
    for line, record in enumerate(reader, start=2):
        try:
            if None in record:
                raise ValueError(f"more cells than the {len(columns)} columns")
            values: dict[str, object] = {}
            for name in columns:
                cell = record[name]
                if cell is None:
                    raise ValueError(f"no cell for {name!r}")
                if name in _TEXT_FIELDS:
                    values[name] = cell
                elif name in _INT_FIELDS:
                    values[name] = int(cell) if cell or name == "map_size" else -1
                else:
                    values[name] = float(cell) if cell else math.nan
            rows.append(SweepRow(**values))  # type: ignore[arg-type]
        except ValueError as exc:
            raise ValueError(f"line {line}: {exc}") from None
    return rows


def _csv_cell(value: object) -> str:
    """A sweep row's value as CSV text: ``inf`` for an infinite float, an empty cell for
    NaN (nothing measured), ``repr`` for other floats (read back exactly), ``str`` for the
    rest."""
    if isinstance(value, float):
        return "inf" if math.isinf(value) else ("" if math.isnan(value) else repr(value))
    return str(value)


def summary_table(summary: Sequence[SummaryRow]) -> list[list[str]]:
    """Header plus one row of text cells per summary row. The ``FLIP`` cell is empty where
    FLIP is missing (see :func:`flip_note`); a ``miss share`` column is there when a
    technique among the rows has a fallback (``-`` for the others)."""
    misses = any(not math.isnan(row.miss_share) for row in summary)
    table = [
        [
            "technique",
            "map",
            "MAE /255",
            "p95 /255",
            "PSNR dB",
            "off >10",
            "FLIP",
            *(["miss share"] if misses else []),
            "wall ms",
            "GL ms",
            "worst view",
        ]
    ]
    for row in summary:
        if math.isnan(row.mae):  # nothing to score: said so, never a zero error
            errors = [NO_REFLECTOR_PIXELS, "-", "-", "-", "-"]
        else:
            errors = [
                f"{row.mae:.2f}",
                f"{row.p95:.1f}",
                f"{row.psnr:.1f}",
                f"{row.share_off:.1%}",
                "" if math.isnan(row.flip) else f"{row.flip:.3f}",
            ]
        if misses:
            errors.append("-" if math.isnan(row.miss_share) else f"{row.miss_share:.1%}")
        table.append(
            [
                row.technique,
                str(row.map_size) if row.map_size else "-",
                *errors,
                f"{row.wall_ms:.2f}",
                "-" if math.isnan(row.gpu_ms) else f"{row.gpu_ms:.2f}",
                row.worst_viewpoint,
            ]
        )
    return table


def _measured(summary: Sequence[SummaryRow]) -> list[SummaryRow]:
    """The rows that score a technique: not the truth's, with reflector pixels."""
    return [r for r in summary if not is_truth(r.technique) and not math.isnan(r.mae)]


def flip_note(summary: Sequence[SummaryRow], reason: str | None) -> str | None:
    """What a table says under its empty FLIP column: ``reason`` (why FLIP is missing),
    where no technique among the rows has a FLIP figure; None where one has (or there is
    nothing to score)."""
    measured = _measured(summary)
    if not measured or any(not math.isnan(r.flip) for r in measured):
        return None
    return f"FLIP is empty: {reason or 'no FLIP figures were measured'}"


@dataclass(frozen=True)
class Frontier:
    """The Pareto frontier of one scene's configurations, error against median wall time:
    the ``rows`` no other configuration beats in both (none is as fast and as accurate
    and better in one), cheapest first. ``metric`` the error it is drawn by (``flip``, or
    ``mae`` where a configuration lacks FLIP; ``note`` then says why)."""

    scene: str
    metric: str
    rows: tuple[SummaryRow, ...]
    note: str | None = None


def pareto_front(points: Sequence[tuple[float, float]]) -> list[int]:
    """The indices of the ``(cost, error)`` points on the Pareto frontier (both to be
    small): those no other point dominates, that is, none has a cost and an error no
    greater and one of them smaller. Points with a NaN are neither on it nor dominate.
    In the order of cost, then error, then index."""
    if not points:
        return []
    values = np.asarray(points, dtype=np.float64).reshape(-1, 2)
    finite: np.ndarray = np.asarray(~np.isnan(values).any(axis=1))
    cost, error = values[:, 0][:, None], values[:, 1][:, None]
    # dominated[i, j]: point j beats point i
    no_worse = (values[:, 0][None, :] <= cost) & (values[:, 1][None, :] <= error)
    better = (values[:, 0][None, :] < cost) | (values[:, 1][None, :] < error)
    dominated = (no_worse & better & finite[None, :]).any(axis=1)
    front = [int(i) for i in np.flatnonzero(finite & ~dominated)]
    return sorted(front, key=lambda i: (values[i, 0], values[i, 1], i))


def frontier(summary: Sequence[SummaryRow], scene: str) -> Frontier:
    """``scene``'s :class:`Frontier` among ``summary``'s rows (the truth left out: it is
    the reference, exact by definition), by mean FLIP where every configuration has one,
    by MAE otherwise (:func:`flip_note` says why FLIP is empty)."""
    rows = _measured([r for r in summary if r.scene == scene])
    missing = sum(math.isnan(r.flip) for r in rows)
    metric, note = "flip", None
    if missing:
        metric = "mae"
        if missing == len(rows):
            note = "by MAE, as FLIP is empty"
        else:
            note = f"by MAE: {missing} of {len(rows)} configurations have no FLIP figure"
    front = pareto_front([(r.wall_ms, getattr(r, metric)) for r in rows])
    return Frontier(scene, metric, tuple(rows[i] for i in front), note)


def frontier_table(front: Frontier) -> list[list[str]]:
    """Header plus one row of text cells per configuration on ``front``, cheapest first."""
    table = [["wall ms", "technique", "map", "FLIP", "MAE /255", "off >10"]]
    for row in front.rows:
        table.append(
            [
                f"{row.wall_ms:.2f}",
                row.technique,
                str(row.map_size) if row.map_size else "-",
                "" if math.isnan(row.flip) else f"{row.flip:.3f}",
                f"{row.mae:.2f}",
                f"{row.share_off:.1%}",
            ]
        )
    return table


def frontier_heading(front: Frontier) -> str:
    """The line above a frontier's table."""
    metric = "mean FLIP" if front.metric == "flip" else "MAE"
    heading = (
        f"Pareto frontier ({metric} against median wall time: no other configuration is "
        "both faster and more accurate), cheapest first"
    )
    return heading + (f"; {front.note}" if front.note else "")


def format_text(table: Sequence[Sequence[str]]) -> str:
    """Aligned plain-text columns for the terminal."""
    widths = [max(len(row[i]) for row in table) for i in range(len(table[0]))]
    lines = [
        "  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True)).rstrip()
        for row in table
    ]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


def format_markdown(table: Sequence[Sequence[str]]) -> str:
    lines = ["| " + " | ".join(table[0]) + " |", "|" + "|".join("---" for _ in table[0]) + "|"]
    lines += ["| " + " | ".join(row) + " |" for row in table[1:]]
    return "\n".join(lines)


SCENE_TITLES = {
    "lab": "lab mirror (robot)",
    "sphere-sky": "environment maps: sphere in the sky",
    "sphere-objects": "environment maps: sphere among objects",
    "sphere-room": "environment maps: sphere in a room",
}


_STEPS_LABEL = re.compile(r"^(?P<series>.+ distance) (?P<steps>\d+\+\d+)$")
"""A distance search with other steps than the default: one point of a "steps" series."""


def _series(summary: Sequence[SummaryRow]) -> dict[str, list[tuple[SummaryRow, str]]]:
    """The lines of one panel's plot: each technique over its map sizes, and the distance
    search over its steps (its default steps joining at their map size), each point with
    its annotation."""
    series: dict[str, list[tuple[SummaryRow, str]]] = {}
    stepped = {m.group("series"): r for r in summary if (m := _STEPS_LABEL.match(r.technique))}
    for row in summary:
        match = _STEPS_LABEL.match(row.technique)
        if match:
            series.setdefault(f"{match.group('series')} by steps (map {row.map_size})", []).append(
                (row, match.group("steps"))
            )
            continue
        series.setdefault(row.technique, []).append((row, str(row.map_size or "")))
        single = stepped.get(row.technique)
        if single is not None and row.map_size == single.map_size:
            name = f"{row.technique} by steps (map {row.map_size})"
            series.setdefault(name, []).append((row, DEFAULT_STEPS))
    for name, points in series.items():
        if name.endswith(")") and " by steps " in name:
            points.sort(key=lambda point: int(point[1].split("+")[0]))
    return series


PLOTTED = {
    "mae": ("mean absolute error, /255 (log; 0 drawn at 0.001)", 1e-3),
    "flip": ("mean FLIP, 0..1 (log; 0 drawn at 0.0001)", 1e-4),
}
"""The error figures the plot draws, one panel each per scene: axis label and the floor a
zero is drawn at on the log axis."""


def plot_summary(
    summary: Sequence[SummaryRow], path: Path, title: str, flip_reason: str | None = None
) -> bool:
    """Error against time, one marker per technique and size (and per step count of a
    distance search), a row of panels per scene (MAE and FLIP), the Pareto frontier
    marked in each; saved as PNG at ``path``. Returns False (and writes nothing) when
    matplotlib is not installed."""
    data = plot_png(summary, title, flip_reason)
    if data is None:
        return False
    write_bytes_atomic(path, data)
    return True


def plot_png(
    summary: Sequence[SummaryRow], title: str, flip_reason: str | None = None
) -> bytes | None:
    """:func:`plot_summary`'s picture as PNG bytes; None without matplotlib. A panel
    without FLIP figures says ``flip_reason``."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return None
    scenes = list(dict.fromkeys(r.scene for r in summary))
    figure, panels = plt.subplots(
        len(scenes),
        len(PLOTTED),
        figsize=(8.0 * len(PLOTTED), 6.0 * len(scenes)),
        dpi=100,
        squeeze=False,
        layout="constrained",  # room for the figure's title above the panels' own
    )
    for row_of_panels, scene in zip(panels, scenes, strict=True):
        for axes, metric in zip(row_of_panels, PLOTTED, strict=True):
            _plot_panel(axes, summary, scene, metric, flip_reason)
    figure.suptitle(title)
    with io.BytesIO() as buffer:
        figure.savefig(buffer, format="png")
        data = buffer.getvalue()
    plt.close(figure)
    return data


def _plot_panel(
    axes, summary: Sequence[SummaryRow], scene: str, metric: str, flip_reason: str | None
) -> None:
    """One panel: ``scene``'s configurations, ``metric`` (a key of :data:`PLOTTED`)
    against median wall time, each technique a line over its sizes, and the Pareto
    frontier of those points as a grey staircase with its points ringed."""
    import matplotlib.pyplot as plt

    markers = "osD^v<>Px*hX"
    label, floor = PLOTTED[metric]
    # The ray tracer has no error by definition and is far slower: named in the panel's
    # title rather than drawn, so that the techniques keep the axes.
    traced = [r for r in summary if r.scene == scene and is_truth(r.technique)]
    rows = [
        r
        for r in _measured([r for r in summary if r.scene == scene])
        if not math.isnan(getattr(r, metric))
    ]
    palette = plt.get_cmap("tab20")
    for index, (name, points) in enumerate(_series(rows).items()):
        times = [row.wall_ms for row, _ in points]
        errors = [max(getattr(row, metric), floor) for row, _ in points]
        dashed = " by steps " in name
        # a colour of its own each (tab20's dark shades), the steps of a search black
        colour = "black" if dashed else palette((2 * index) % 20 + (2 * index) // 20 % 2)
        axes.plot(
            times,
            errors,
            marker=markers[index % len(markers)],
            color=colour,
            linestyle=("--" if dashed else "-") if len(points) > 1 else "",
            label=name,
        )
        for (_, note), x, y in zip(points, times, errors, strict=True):
            if note:
                axes.annotate(note, (x, y), fontsize=7, textcoords="offset points", xytext=(4, 3))
    front = [rows[i] for i in pareto_front([(r.wall_ms, getattr(r, metric)) for r in rows])]
    if front:
        times = [r.wall_ms for r in front]
        errors = [max(getattr(r, metric), floor) for r in front]
        axes.plot(
            times,
            errors,
            drawstyle="steps-post",
            color="grey",
            linewidth=6,
            alpha=0.35,
            zorder=0,
            label="Pareto frontier",
        )
        axes.scatter(times, errors, s=160, facecolors="none", edgecolors="grey", zorder=1)
    axes.set_xscale("log")
    axes.set_yscale("log")
    axes.set_xlabel("median wall time per frame (ms, log)")
    axes.set_ylabel(label)
    heading = f"{SCENE_TITLES.get(scene, scene)}: {'MAE' if metric == 'mae' else 'FLIP'}"
    if traced:
        truth = traced[0]
        heading += f"\n(ground truth: {truth.technique}, {truth.wall_ms:.0f} ms a frame)"
    axes.set_title(heading, fontsize=10)
    axes.grid(True, which="both", alpha=0.3)
    if rows:
        axes.legend(fontsize=7, ncol=2)
    else:
        scored = _measured([r for r in summary if r.scene == scene])
        empty = NO_REFLECTOR_PIXELS
        if scored and metric == "flip":
            empty = f"no FLIP figures: {flip_reason or 'none were measured'}"
        axes.text(
            0.5,
            0.5,
            "\n".join(_wrapped(empty, 60)),
            transform=axes.transAxes,
            ha="center",
            va="center",
            fontsize=9,
        )


def _wrapped(text: str, width: int) -> list[str]:
    import textwrap

    return textwrap.wrap(text, width) or [text]


CSV_WITHOUT_FLIP = (
    "{name} holds no FLIP figures (written before the column, or measured where "
    "flip-evaluator was missing)"
)
"""Why FLIP is empty in a report re-made from a CSV (``name`` the file's)."""


SweptScenes = str | Scene | Sequence[str | Scene]
"""What a sweep measures: ``lab`` (the mirror techniques), ``sphere`` (the environment
maps), ``all`` (both), a scene (from its own camera: every technique its reflectors can
take), or several of these."""


def panels_for(scenes: SweptScenes, settings: SweepSettings) -> list[Panel]:
    """The panels of :data:`SweptScenes`, in the order given; ValueError when two would
    have one name (their rows could not be told apart)."""
    items = [scenes] if isinstance(scenes, str | Scene) else list(scenes)
    panels: list[Panel] = []
    for item in items:
        if isinstance(item, Scene):
            panels.append(file_panel(item))
        elif item in ("lab", "sphere", "all"):
            panels += [lab_panel(settings)] if item in ("lab", "all") else []
            panels += sphere_panels(settings) if item in ("sphere", "all") else []
        else:
            raise ValueError(f"--scene: expected lab, sphere, all or a scene, got {item!r}")
    names = [panel.name for panel in panels]
    twice = sorted({name for name in names if names.count(name) > 1})
    if twice:
        raise ValueError(
            f"--scene: two scenes named {twice[0]!r} (give each scene once; a scene file's "
            "name key tells its rows from another's)"
        )
    return panels


def run_command(
    settings: SweepSettings,
    scenes: SweptScenes,
    out_dir: Path,
    from_csv: Path | None = None,
    say: Callable[[str], None] = print,
    jobs: int = 1,
    scheduler: str | None = None,
    engine: str = "pool",
) -> int:
    """``mirrorlab bench accuracy``: measure (or read ``from_csv``), print the tables (and
    each scene's Pareto frontier), and write accuracy.csv, accuracy.md and accuracy.png
    into ``out_dir``. The truths and the scoring run on ``jobs`` processes (or the Dask
    ``scheduler``'s workers; see :func:`run_panels`), the timed frames in this process."""
    if from_csv is not None:
        try:
            rows = rows_from_csv(from_csv.read_text())
        except (OSError, UnicodeDecodeError) as exc:
            raise ValueError(f"--from-csv: cannot read {from_csv}: {exc}") from None
        except ValueError as exc:
            raise ValueError(f"--from-csv: {from_csv}: {exc}") from None
        title = f"accuracy vs time, from {from_csv.name}"
        flip_reason: str | None = CSV_WITHOUT_FLIP.format(name=from_csv.name)
    else:
        panels = panels_for(scenes, settings)
        started = time.perf_counter()
        with open_executor(jobs, scheduler, engine) as executor:
            rows = run_panels(panels, settings, executor=executor)
            workers = f"{executor.engine} ({executor.workers} worker"
            workers += "s)" if executor.workers != 1 else ")"
        say(
            f"measured {len(rows)} rows in {time.perf_counter() - started:.1f} s; truths "
            f"and scoring on {workers}, timed frames in this process"
        )
        title = (
            f"accuracy vs time, {settings.frame}x{settings.frame} frames, llvmpipe; "
            f"medians of {settings.frames} frames"
        )
        flip_reason = flip.MISSING
    summary = summarise(rows)
    markdown = [title, ""]
    for scene in dict.fromkeys(r.scene for r in summary):
        mine = [r for r in summary if r.scene == scene]
        table = summary_table(mine)
        heading = SCENE_TITLES.get(scene, scene)
        note = flip_note(mine, flip_reason)
        front = frontier(summary, scene)
        text = [f"\n{heading}:", format_text(table)]
        markdown += [f"### {heading}", "", format_markdown(table), ""]
        if note is not None:
            text.append(note)
            markdown += [note, ""]
        if front.rows:
            text += ["", f"{frontier_heading(front)}:", format_text(frontier_table(front))]
            markdown += [
                f"{frontier_heading(front)}:",
                "",
                format_markdown(frontier_table(front)),
                "",
            ]
        say("\n".join(text))
    plot = plot_png(summary, title, flip_reason)
    written = []
    with Outputs() as outputs:  # all three files, or none
        if from_csv is None:
            outputs.add(out_dir / "accuracy.csv", rows_to_csv(rows).encode())
            written.append("accuracy.csv")
        outputs.add(out_dir / "accuracy.md", "\n".join(markdown).encode())
        written.append("accuracy.md")
        if plot is not None:
            outputs.add(out_dir / "accuracy.png", plot)
            written.append("accuracy.png")
    if plot is None:
        say("matplotlib is not installed, so no plot (pip install 'mirrorlab[plot]')")
    say(f"wrote {', '.join(str(out_dir / name) for name in written)}")
    return 0
