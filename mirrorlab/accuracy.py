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
    # FLIP looks at each pixel's surroundings, so it is computed on the whole picture and
    # only then averaged over the region.
    flip_error = flip.flip_map(image, truth)
    return ImageError(
        float(diff.mean()),
        float(np.percentile(worst, 95)),
        psnr,
        float(np.mean(worst > OFF_BY)),
        count,
        math.nan if flip_error is None else float(flip_error[mask].mean()),
    )


@dataclass(frozen=True)
class SweepRow:
    """One measured configuration: ``scene`` ("lab" mirror, or "sphere-sky",
    "sphere-objects" and "sphere-room" for the environment maps),
    technique, map size (0: the technique has no texture) and viewpoint; times are
    medians in milliseconds (``gpu_ms`` from GL timer queries, NaN where there is no
    GL work); ``pixels`` the reflector pixels scored (0: none, and the error figures
    NaN; -1: not recorded, in a CSV from before the column)."""

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
    for entry in (t for t in planar if not t.draws_inline):
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
    rows += [(entry.name, {"method": entry.name}) for entry in planar if entry.draws_inline]
    return rows


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
    at the :func:`search_map_size` (labelled ``cube-live distance STEPS``)."""
    sizes = [size for size in sizes if size <= ENVMAP_MAX_SIZE]
    rows = []
    for entry in techniques("curved"):
        plain = {"parallax": "none"} if entry.parallax else {}
        rows += [(entry.name, {"method": entry.name, "map_size": size, **plain}) for size in sizes]
    searched = search_map_size(sizes)
    for name in (entry.name for entry in techniques("curved") if entry.parallax):
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


def score_frames(truth: Truth, images: Sequence[np.ndarray]) -> list[ImageError]:
    """Each of ``images`` ``(h, w, 3)`` uint8 against ``truth``: a job of the third phase."""
    return [image_error(image, truth.image, truth.mask) for image in images]


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
    configurations = [
        scene_techniques(scene, settings.sizes, panel.proxies, settings.steps, settings.map_sizes)
        for panel, _, scene in views
    ]
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
    frames: dict[int, list[np.ndarray]] = {}
    timings: dict[int, list[tuple[str, int, float, float]]] = {}
    errors: dict[int, list[ImageError]] = {}
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
                    image, wall, gpu = measure_frames(
                        renderer, configured, framebuffer, timer, settings
                    )
                    frames[index].append(image)
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
            "raytrace"
            if panel.supersample == 1
            else (f"raytrace {panel.supersample}x{panel.supersample}")
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
            )
        )
        for (technique_label, map_size, wall, gpu), error in zip(
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
) -> tuple[np.ndarray, float, float]:
    """Time frames of ``scene`` (see :func:`time_frames`), each capturing its reflectors
    afresh as a moving scene would (maps baked from the background are kept). Returns
    the last frame ``(h, w, 3)`` uint8 and the median wall and GL milliseconds."""
    from mirrorlab.gl.context import check_gl_errors

    def frame() -> None:
        held = renderer.state.held
        for key in [k for k, v in held.items() if v[0] not in ("bake", "picture")]:
            del held[key]
        renderer.render(scene, framebuffer)

    wall, gpu = time_frames(frame, timer, settings)
    image = framebuffer.read()
    check_gl_errors("a sweep frame")
    return image, wall, gpu


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
    """A technique and size over all viewpoints: mean error figures, median times."""

    scene: str
    technique: str
    map_size: int
    mae: float
    p95: float
    share_off: float
    wall_ms: float
    gpu_ms: float
    worst_viewpoint: str


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

        def mean(values: list[float]) -> float:
            return float(np.mean(values)) if values else math.nan

        summary.append(
            SummaryRow(
                scene,
                technique,
                map_size,
                mean([r.mae for r in scored]),
                mean([r.p95 for r in scored]),
                mean([r.share_off for r in scored]),
                float(np.median([r.wall_ms for r in group])),
                float(np.median(gpu)) if gpu else math.nan,
                worst.viewpoint if worst is not None else NO_REFLECTOR_PIXELS,
            )
        )
    return summary


def rows_to_csv(rows: Sequence[SweepRow]) -> str:
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow([f.name for f in fields(SweepRow)])
    for row in rows:
        writer.writerow([_csv_cell(v) for v in asdict(row).values()])
    return buffer.getvalue()


def rows_from_csv(text: str) -> list[SweepRow]:
    """Rows written by :func:`rows_to_csv` (to re-make the tables and plot without
    measuring again); ValueError naming the line that does not fit."""
    reader = csv.DictReader(io.StringIO(text))
    names = [f.name for f in fields(SweepRow)]
    if reader.fieldnames not in (names, names[:-1]):  # a CSV from before "pixels" too
        raise ValueError(f"expected the columns {','.join(names)}, got {reader.fieldnames}")
    rows = []
    for line, record in enumerate(reader, start=2):
        try:
            number = {n: float(record[n]) if record[n] else math.nan for n in names[4:-1]}
            rows.append(
                SweepRow(
                    record["scene"],
                    record["technique"],
                    int(record["map_size"]),
                    record["viewpoint"],
                    number["mae"],
                    number["p95"],
                    number["psnr"],
                    number["share_off"],
                    number["wall_ms"],
                    number["gpu_ms"],
                    int(record.get("pixels") or -1),
                )
            )
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
    """Header plus one row of text cells per summary row."""
    table = [
        ["technique", "map", "MAE /255", "p95 /255", "off >10", "wall ms", "GL ms", "worst view"]
    ]
    for row in summary:
        if math.isnan(row.mae):  # nothing to score: said so, never a zero error
            errors = [NO_REFLECTOR_PIXELS, "-", "-"]
        else:
            errors = [f"{row.mae:.2f}", f"{row.p95:.1f}", f"{row.share_off:.1%}"]
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


def plot_summary(summary: Sequence[SummaryRow], path: Path, title: str) -> bool:
    """Error against time, one marker per technique and size (and per step count of a
    distance search), one panel per scene, saved as PNG at ``path``. Returns False (and
    writes nothing) when matplotlib is not installed."""
    data = plot_png(summary, title)
    if data is None:
        return False
    write_bytes_atomic(path, data)
    return True


def plot_png(summary: Sequence[SummaryRow], title: str) -> bytes | None:
    """:func:`plot_summary`'s picture as PNG bytes; None without matplotlib."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return None
    markers = "osD^v<>Px*hX"
    scenes = list(dict.fromkeys(r.scene for r in summary))
    columns = min(2, len(scenes))
    rows_of_panels = math.ceil(len(scenes) / columns)
    figure, panels = plt.subplots(
        rows_of_panels,
        columns,
        figsize=(8.0 * columns, 6.0 * rows_of_panels),
        dpi=100,
        squeeze=False,
    )
    for axes in panels.flat[len(scenes) :]:
        axes.set_visible(False)
    for axes, scene in zip(panels.flat, scenes, strict=False):
        # The ray tracer has no error by definition and is far slower: named in the
        # panel's title rather than drawn, so that the techniques keep the axes.
        traced = [r for r in summary if r.scene == scene and r.technique.startswith("raytrace")]
        rows = [
            r for r in summary if r.scene == scene and r not in traced and not math.isnan(r.mae)
        ]
        palette = plt.get_cmap("tab20")
        for index, (name, points) in enumerate(_series(rows).items()):
            times = [row.wall_ms for row, _ in points]
            errors = [max(row.mae, 1e-3) for row, _ in points]
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
                    axes.annotate(
                        note, (x, y), fontsize=7, textcoords="offset points", xytext=(4, 3)
                    )
        axes.set_xscale("log")
        axes.set_yscale("log")
        axes.set_xlabel("median wall time per frame (ms, log)")
        axes.set_ylabel("mean absolute error, /255 (log; 0 drawn at 0.001)")
        heading = SCENE_TITLES.get(scene, scene)
        if traced:
            truth = traced[0]
            heading += f"\n(ground truth: {truth.technique}, {truth.wall_ms:.0f} ms a frame)"
        axes.set_title(heading, fontsize=10)
        axes.grid(True, which="both", alpha=0.3)
        if rows:
            axes.legend(fontsize=7, ncol=2)
        else:
            axes.text(
                0.5, 0.5, NO_REFLECTOR_PIXELS, transform=axes.transAxes, ha="center", va="center"
            )
    figure.suptitle(title)
    figure.tight_layout()
    with io.BytesIO() as buffer:
        figure.savefig(buffer, format="png")
        data = buffer.getvalue()
    plt.close(figure)
    return data


def run_command(
    settings: SweepSettings,
    scenes: str | Scene,
    out_dir: Path,
    from_csv: Path | None = None,
    say: Callable[[str], None] = print,
    jobs: int = 1,
    scheduler: str | None = None,
    engine: str = "pool",
) -> int:
    """``mirrorlab bench accuracy``: measure (or read ``from_csv``), print the tables, and
    write accuracy.csv, accuracy.md and accuracy.png into ``out_dir``. The truths and the
    scoring run on ``jobs`` processes (or the Dask ``scheduler``'s workers; see
    :func:`run_panels`), the timed frames in this process."""
    if from_csv is not None:
        try:
            rows = rows_from_csv(from_csv.read_text())
        except (OSError, UnicodeDecodeError) as exc:
            raise ValueError(f"--from-csv: cannot read {from_csv}: {exc}") from None
        except ValueError as exc:
            raise ValueError(f"--from-csv: {from_csv}: {exc}") from None
        title = f"accuracy vs time, from {from_csv.name}"
    else:
        if isinstance(scenes, Scene):
            panels = [file_panel(scenes)]
        else:
            panels = ([lab_panel(settings)] if scenes in ("lab", "all") else []) + (
                sphere_panels(settings) if scenes in ("sphere", "all") else []
            )
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
    summary = summarise(rows)
    markdown = [title, ""]
    for scene in dict.fromkeys(r.scene for r in summary):
        table = summary_table([r for r in summary if r.scene == scene])
        heading = SCENE_TITLES.get(scene, scene)
        say(f"\n{heading}:\n{format_text(table)}")
        markdown += [f"### {heading}", "", format_markdown(table), ""]
    plot = plot_png(summary, title)
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
