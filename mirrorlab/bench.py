"""The accuracy-against-time sweep: every mirror technique, environment-texture size and
viewpoint, scored against the ray-traced ground truth inside the mirror, and timed.

Numbers only; the command line prints and saves what :func:`run_accuracy` returns.
"""

from __future__ import annotations

import csv
import io
import math
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from dataclasses import asdict, dataclass, fields
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from mirrorlab.plan import CAPTURE_MODES
from mirrorlab.scene.robot import Camera, build_lab_scene

if TYPE_CHECKING:
    from mirrorlab.gl.context import ResourceRegistry
    from mirrorlab.gl.resources import Framebuffer, TimerQuery

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

    def around(distance: float, degrees: float, height: float = 0.0) -> tuple[float, ...]:
        angle = math.radians(degrees)
        offset = np.array([math.cos(angle), height, math.sin(angle)]) * distance
        return tuple(float(v) for v in center + offset)

    target = tuple(float(v) for v in center)
    return {
        "head-on far": Camera(eye=around(60.0, 0.0), target=target, fovy=10.0),
        "head-on near": Camera(eye=around(14.0, 0.0), target=target),
        "30 deg": Camera(eye=around(16.0, 30.0), target=target),
        "60 deg": Camera(eye=around(16.0, 60.0), target=target),
        "close": Camera(eye=around(3.0, 15.0, 0.1), target=target, fovy=60.0),
    }


@dataclass(frozen=True)
class ImageError:
    """Error of an image against the truth over a region, channels in 0..255 units:
    mean absolute error, 95th percentile of the per-pixel worst channel, PSNR in dB
    (inf when identical), and the share of pixels off by more than ``OFF_BY``."""

    mae: float
    p95: float
    psnr: float
    share_off: float


def image_error(image: np.ndarray, truth: np.ndarray, mask: np.ndarray) -> ImageError:
    """Compare ``image`` and ``truth`` ``(h, w, 3)`` uint8 where ``mask`` ``(h, w)`` is True.

    An empty mask scores zero error (nothing reflective was in view).
    """
    if not mask.any():
        return ImageError(0.0, 0.0, math.inf, 0.0)
    diff = np.abs(image.astype(np.float64) - truth.astype(np.float64))[mask]
    worst = diff.max(axis=1)
    mse = float(np.mean(diff ** 2))
    psnr = math.inf if mse == 0.0 else 10.0 * math.log10(255.0 ** 2 / mse)
    return ImageError(float(diff.mean()), float(np.percentile(worst, 95)), psnr,
                      float(np.mean(worst > OFF_BY)))


@dataclass(frozen=True)
class SweepRow:
    """One measured configuration: ``scene`` ("lab" mirror, or "sphere-sky" and
    "sphere-objects" for the environment maps),
    technique, map size (0: the technique has no texture) and viewpoint; times are
    medians in milliseconds (``gpu_ms`` from GL timer queries, NaN where there is no
    GL work)."""

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


@dataclass(frozen=True)
class SweepSettings:
    """``frame`` side in pixels, texture ``sizes``, ``frames`` timed per configuration
    after ``warmup`` frames, and which viewpoints to use (None: all)."""

    frame: int = 512
    sizes: tuple[int, ...] = FULL_SIZES
    frames: int = 15
    warmup: int = 3
    viewpoints: tuple[str, ...] | None = None

    @classmethod
    def quick(cls) -> SweepSettings:
        """A small sweep for tests: 128-pixel frames, two sizes, two viewpoints."""
        return cls(frame=128, sizes=QUICK_SIZES, frames=3, warmup=1,
                   viewpoints=("head-on far", "60 deg"))


Progress = Callable[[int, int, str], None]


def lab_techniques(sizes: Sequence[int]) -> list[tuple[str, str, str, int]]:
    """``(label, method, capture, map_size)`` for each rasterised configuration."""
    rows = []
    for method in ("ortho", "reflected"):
        for capture in CAPTURE_MODES:
            rows += [(f"{method}-{capture}", method, capture, size) for size in sizes]
    rows.append(("stencil", "stencil", "copy", 0))
    return rows


def run_accuracy(settings: SweepSettings, progress: Progress | None = None) -> list[SweepRow]:
    """Run the sweep on the lab scene in a headless context; one row per configuration
    and viewpoint, the ray tracer's own rows included (zero error, its time)."""
    from mirrorlab.raytrace import lab_ray_scene
    from mirrorlab.renderer import Renderer

    scene = build_lab_scene()
    ray_scene = lab_ray_scene(scene)
    viewpoints = lab_viewpoints()
    names = settings.viewpoints or tuple(viewpoints)
    unknown = [n for n in names if n not in viewpoints]
    if unknown:
        raise ValueError(f"unknown viewpoint {unknown[0]!r}; known: {', '.join(viewpoints)}")
    techniques = lab_techniques(settings.sizes)
    total = len(names) * (len(techniques) + 1)
    done = 0
    rows: list[SweepRow] = []
    size = (settings.frame, settings.frame)
    with sweep_gl(size) as (registry, framebuffer, timer):
        for name in names:
            camera = viewpoints[name]
            truth_times, truth = [], None
            for _ in range(max(1, settings.frames // 5)):
                start = time.perf_counter()
                truth = ray_scene.render(camera.view(), camera.projection(1.0), size)
                truth_times.append((time.perf_counter() - start) * 1e3)
            truth_image, mask = truth.to_uint8(), truth.reflective_mask
            rows.append(SweepRow("lab", "raytrace", 0, name, 0.0, 0.0, math.inf, 0.0,
                                 float(np.median(truth_times)), math.nan))
            done += 1
            if progress:
                progress(done, total, f"raytrace {name}")
            for label, method, capture, map_size in techniques:
                env = (map_size, map_size) if map_size else None
                renderer = Renderer(registry, scene, method, capture, env)
                error, wall, gpu = measure(
                    renderer, partial(renderer.render, framebuffer, camera, force_capture=True),
                    framebuffer, timer, settings, truth_image, mask)
                rows.append(SweepRow("lab", label, map_size, name, error.mae, error.p95,
                                     error.psnr, error.share_off, wall, gpu))
                done += 1
                if progress:
                    progress(done, total, f"{label} {map_size or ''} {name}")
    return rows


@contextmanager
def sweep_gl(size: tuple[int, int],
             ) -> Iterator[tuple[ResourceRegistry, Framebuffer, TimerQuery]]:
    """A headless context for a sweep: its resource registry, a ``size`` (width, height)
    frame target and a GL timer query; all released on leaving."""
    from mirrorlab.gl.context import HeadlessContext
    from mirrorlab.gl.resources import Framebuffer, TimerQuery

    with HeadlessContext() as context:
        framebuffer = Framebuffer(context.resources, *size)
        timer = TimerQuery(context.resources)
        try:
            yield context.resources, framebuffer, timer
        finally:
            timer.release()
            framebuffer.release()


def time_frames(render_frame: Callable[[], object], timer, settings: SweepSettings,
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


def measure(renderer, render_frame: Callable[[], object], framebuffer, timer,
            settings: SweepSettings, truth: np.ndarray, mask: np.ndarray,
            ) -> tuple[ImageError, float, float]:
    """Time ``render_frame`` (see :func:`time_frames`), then score the last frame in
    ``framebuffer`` against ``truth`` ``(h, w, 3)`` uint8 under ``mask`` ``(h, w)``, and
    release ``renderer``. Returns the error and the median wall and GL milliseconds."""
    from mirrorlab.gl.context import check_gl_errors

    wall, gpu = time_frames(render_frame, timer, settings)
    image = framebuffer.read()
    renderer.release()
    check_gl_errors("a sweep frame")
    return image_error(image, truth, mask), wall, gpu


ENVMAP_MAX_SIZE = 1024
"""Largest environment map in the sweep: a 2048 cube is 25 million numpy-baked texels."""


def envmap_viewpoints() -> dict[tuple[str, str], Camera]:
    """The environment-map rows' views of the sphere scene, keyed by (scene, viewpoint).

    Scene ``sphere-sky`` is the sphere in the distant sky alone (what every map can
    hold), seen from the scene's camera (``default``) and from close up; scene
    ``sphere-objects`` adds the lit objects around it, which only ``cube-live`` can
    reflect.
    """
    from mirrorlab.scene.envscenes import build_sphere_scene

    default = build_sphere_scene(objects=False).camera
    close = Camera(eye=(0.6, 0.8, 2.4), target=(0.0, 0.0, 0.0), fovy=40.0)
    return {("sphere-sky", "default"): default, ("sphere-sky", "close"): close,
            ("sphere-objects", "default"): default}


def run_envmap_accuracy(settings: SweepSettings,
                        progress: Progress | None = None) -> list[SweepRow]:
    """Every environment-map technique and map size on the sphere scene, scored inside
    the sphere (shrunk by one pixel) against a 4 x 4 supersampled ray-traced truth."""
    from mirrorlab.envmap_renderer import ENVMAP_METHODS, EnvmapRenderer, erode, ground_truth
    from mirrorlab.scene.envscenes import build_sphere_scene

    views = envmap_viewpoints()
    names = list(views)
    if settings.viewpoints is not None:  # the quick sweep: one view of each scene
        names = [("sphere-sky", "default"), ("sphere-objects", "default")]
    sizes = [size for size in settings.sizes if size <= ENVMAP_MAX_SIZE]
    total = len(names) * (len(ENVMAP_METHODS) * len(sizes) + 1)
    done = 0
    rows: list[SweepRow] = []
    size = (settings.frame, settings.frame)
    with sweep_gl(size) as (registry, framebuffer, timer):
        for scene_name, name in names:
            camera = views[(scene_name, name)]
            scene = build_sphere_scene(objects=scene_name == "sphere-objects")
            start = time.perf_counter()
            truth = ground_truth(scene, camera, size, supersample=4)
            traced_ms = (time.perf_counter() - start) * 1e3
            truth_image = truth.to_uint8()
            mask = erode(truth.reflective_mask, 1)
            rows.append(SweepRow(scene_name, "raytrace 4x4", 0, name, 0.0, 0.0, math.inf, 0.0,
                                 traced_ms, math.nan))
            done += 1
            if progress:
                progress(done, total, f"raytrace {scene_name} {name}")
            for method in ENVMAP_METHODS:
                for map_size in sizes:
                    renderer = EnvmapRenderer(registry, scene, method, map_size)
                    live = method == "cube-live"  # time its capture in every frame
                    error, wall, gpu = measure(
                        renderer, partial(renderer.render, framebuffer, camera,
                                          force_capture=live),
                        framebuffer, timer, settings, truth_image, mask)
                    rows.append(SweepRow(scene_name, method, map_size, name, error.mae,
                                         error.p95, error.psnr, error.share_off, wall, gpu))
                    done += 1
                    if progress:
                        progress(done, total, f"{method} {map_size} {scene_name} {name}")
    return rows


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
        worst = max(group, key=lambda r: r.mae)
        gpu = [r.gpu_ms for r in group if not math.isnan(r.gpu_ms)]
        summary.append(SummaryRow(
            scene, technique, map_size,
            float(np.mean([r.mae for r in group])),
            float(np.mean([r.p95 for r in group])),
            float(np.mean([r.share_off for r in group])),
            float(np.median([r.wall_ms for r in group])),
            float(np.median(gpu)) if gpu else math.nan,
            worst.viewpoint,
        ))
    return summary


def rows_to_csv(rows: Sequence[SweepRow]) -> str:
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow([f.name for f in fields(SweepRow)])
    for row in rows:
        writer.writerow([_plain(v) for v in asdict(row).values()])
    return buffer.getvalue()


def rows_from_csv(text: str) -> list[SweepRow]:
    """Rows written by :func:`rows_to_csv` (to re-make the tables and plot without
    measuring again); ValueError naming the line that does not fit."""
    reader = csv.DictReader(io.StringIO(text))
    names = [f.name for f in fields(SweepRow)]
    if reader.fieldnames != names:
        raise ValueError(f"expected the columns {','.join(names)}, got {reader.fieldnames}")
    rows = []
    for line, record in enumerate(reader, start=2):
        try:
            rows.append(SweepRow(
                record["scene"], record["technique"], int(record["map_size"]),
                record["viewpoint"],
                *(float(record[n]) if record[n] else math.nan for n in names[4:])))
        except ValueError as exc:
            raise ValueError(f"line {line}: {exc}") from None
    return rows


def _plain(value) -> str:
    if isinstance(value, float):
        return "inf" if math.isinf(value) else ("" if math.isnan(value) else repr(value))
    return str(value)


def summary_table(summary: Sequence[SummaryRow]) -> list[list[str]]:
    """Header plus one row of text cells per summary row."""
    table = [["technique", "map", "MAE /255", "p95 /255", "off >10", "wall ms", "GL ms",
              "worst view"]]
    for row in summary:
        table.append([
            row.technique, str(row.map_size) if row.map_size else "-",
            f"{row.mae:.2f}", f"{row.p95:.1f}", f"{row.share_off:.1%}",
            f"{row.wall_ms:.2f}", "-" if math.isnan(row.gpu_ms) else f"{row.gpu_ms:.2f}",
            row.worst_viewpoint,
        ])
    return table


def format_text(table: Sequence[Sequence[str]]) -> str:
    """Aligned plain-text columns for the terminal."""
    widths = [max(len(row[i]) for row in table) for i in range(len(table[0]))]
    lines = ["  ".join(cell.ljust(w) for cell, w in zip(row, widths, strict=True)).rstrip()
             for row in table]
    lines.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(lines)


def format_markdown(table: Sequence[Sequence[str]]) -> str:
    lines = ["| " + " | ".join(table[0]) + " |",
             "|" + "|".join("---" for _ in table[0]) + "|"]
    lines += ["| " + " | ".join(row) + " |" for row in table[1:]]
    return "\n".join(lines)


SCENE_TITLES = {"lab": "lab mirror (robot)",
                "sphere-sky": "environment maps: sphere in the sky",
                "sphere-objects": "environment maps: sphere among objects"}


def plot_summary(summary: Sequence[SummaryRow], path: Path, title: str) -> bool:
    """Error against time, one marker per technique and size, one panel per scene,
    saved as PNG at ``path``. Returns False (and writes nothing) when matplotlib is
    not installed."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        return False
    markers = "osD^v<>Px*"
    scenes = list(dict.fromkeys(r.scene for r in summary))
    figure, panels = plt.subplots(1, len(scenes), figsize=(7.5 * len(scenes), 5.5), dpi=100,
                                  squeeze=False)
    for axes, scene in zip(panels[0], scenes, strict=True):
        # The ray tracer has no error by definition and is far slower: named in the
        # panel's title rather than drawn, so that the techniques keep the axes.
        traced = [r for r in summary if r.scene == scene and r.technique.startswith("raytrace")]
        rows = [r for r in summary if r.scene == scene and r not in traced]
        techniques = list(dict.fromkeys(r.technique for r in rows))
        for index, technique in enumerate(techniques):
            group = [r for r in rows if r.technique == technique]
            axes.plot([r.wall_ms for r in group], [max(r.mae, 1e-3) for r in group],
                      marker=markers[index % len(markers)],
                      linestyle="-" if len(group) > 1 else "", label=technique)
            for r in group:
                if r.map_size:
                    axes.annotate(str(r.map_size), (r.wall_ms, max(r.mae, 1e-3)), fontsize=7,
                                  textcoords="offset points", xytext=(4, 3))
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
        axes.legend(fontsize=8)
    figure.suptitle(title)
    figure.tight_layout()
    with io.BytesIO() as buffer:
        figure.savefig(buffer, format="png")
        data = buffer.getvalue()
    plt.close(figure)
    write_bytes_atomic(path, data)
    return True


def write_bytes_atomic(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file and a rename."""
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_name(f".{path.name}.tmp")
    try:
        temporary.write_bytes(data)
        temporary.replace(path)
    finally:
        temporary.unlink(missing_ok=True)


def progress_bar(stream=None, width: int = 28) -> Progress:
    """A one-line text progress bar on ``stream`` (default: standard error), redrawn in
    place on a terminal, one line per step otherwise."""
    stream = stream or sys.stderr
    interactive = stream.isatty()
    started = time.perf_counter()

    def show(done: int, total: int, label: str) -> None:
        filled = int(width * done / total)
        elapsed = time.perf_counter() - started
        line = (f"[{'#' * filled}{'.' * (width - filled)}] {done}/{total} "
                f"{elapsed:5.1f}s  {label}")
        if interactive:
            stream.write("\r" + line.ljust(100)[:100] + ("\n" if done == total else ""))
        else:
            stream.write(line + "\n")
        stream.flush()

    return show
