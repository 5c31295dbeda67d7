"""Speed against pyrender: mirrorlab's frames and pyrender's, side by side in one run, on the
same meshes at the same sizes, every frame read back to numpy; and frames at scale.

Run as ``mirrorlab bench speed`` (see ``--help``); ``./dev bench speed`` in a clone makes
pyrender's environment first and passes it with ``--pyrender``.

pyrender runs in an environment of its own (its PyOpenGL pin conflicts with mirrorlab's,
and its last release needs numpy < 2), given by ``--pyrender PYTHON``, as a worker process
(:mod:`mirrorlab.benchmarks.pyrender_worker`) driven over a pipe; both use headless EGL on
the same GL driver. Without ``--pyrender`` only mirrorlab's frames are timed. The meshes
are the lab scene's parts moved to world space (400 triangles: the robot and the mirror's
frame) and the same parts subdivided ``--subdivisions`` times (x4 triangles each: 6 gives
about 1.6 million), written to ``OUT/meshes`` as OBJ files that both renderers load. The
variants:

- ``mirrorlab two passes``: the lab's mirror, the orthographic capture copied into its
  texture, then the camera pass; a part moves by 1 mm every frame, so every frame plans
  and captures again, as an animation would;
- ``mirrorlab reflected two passes``: the same with the mirror made ``reflected`` (the
  viewer's mirror image captures it), captured again every frame;
- ``mirrorlab capture reused``: the same scene standing still: the planner reuses the
  capture, only the camera pass runs;
- ``mirrorlab one pass``: the meshes with no mirror;
- ``pyrender default``: lit, physically based, multisampled, colour and depth read back;
- ``pyrender flat``: ``RenderFlags.FLAT``, no lighting: the least work pyrender does.

The scale part times the scenes of :mod:`mirrorlab.benchmarks.scale` (many objects or
mirrors, seen and unseen), and pyrender's flat frame of those without mirrors.

The variants take turns in blocks of ``--block`` frames, the order rotating every round,
so that a shared machine's load falls on all of them alike. The report (``speed.md``,
``speed.csv``, ``scale.csv``, ``speed.png``) gives the median of ``--frames`` frames
(``--scale-frames`` for the scale scenes) after ``--warmup`` per variant, the ratios to
pyrender's frames and of each scale scene to its base frame (paired round by round,
:func:`mirrorlab.benchmarks.scale.paired_ratio`), and how frame time grows with pixels,
triangles and items (the exponent ``k`` of ``time ~ amount ** k`` between the smallest
and largest amount: 1 is linear).
"""

from __future__ import annotations

import contextlib
import csv
import io
import json
import math
import statistics
import subprocess
import sys
from collections.abc import Callable
from dataclasses import dataclass, replace
from importlib import resources
from pathlib import Path

import numpy as np

from mirrorlab.benchmarks.scale import (
    Variant,
    interleave,
    mirrorlab_variants,
    paired_ratio,
    scale_scenes,
    timed_frames,
)
from mirrorlab.errors import BenchmarkError
from mirrorlab.options import OptionError

MIRRORLAB_VARIANTS = (
    "mirrorlab two passes",
    "mirrorlab reflected two passes",
    "mirrorlab capture reused",
    "mirrorlab one pass",
)
PYRENDER_VARIANTS = ("pyrender default", "pyrender flat")
PYRENDER_PACKAGES = ("pyrender==0.1.45", "numpy<2", "Pillow")
"""What pyrender's environment needs (``./dev bench speed`` makes one with them)."""
STEP = 0.001
"""How far (scene units) the moving part of the two-pass variant goes and comes back."""


def log(message: str) -> None:
    print(f"[speed] {message}", file=sys.stderr, flush=True)


# --------------------------------------------------------------------------- pyrender


class PyrenderWorker:
    """pyrender in its own process and environment (the interpreter ``python``), driven one
    JSON line at a time."""

    def __init__(self, python: Path) -> None:
        try:
            check = subprocess.run(
                [str(python), "-c", "import pyrender, trimesh, PIL"], capture_output=True, text=True
            )
        except OSError as exc:
            raise OptionError("--pyrender", f"cannot run {python}: {exc.strerror or exc}") from None
        if check.returncode != 0:
            said = check.stderr.strip().splitlines()
            raise OptionError(
                "--pyrender",
                f"{python} cannot import pyrender, trimesh and "
                f"Pillow ({said[-1] if said else f'exit {check.returncode}'}); "
                f"give the Python of an environment with "
                f"{' '.join(PYRENDER_PACKAGES)}",
            )
        self._files = contextlib.ExitStack()
        script = self._files.enter_context(
            resources.as_file(
                resources.files("mirrorlab.benchmarks").joinpath("pyrender_worker.py")
            )
        )
        self.process = subprocess.Popen(
            [str(python), str(script)], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True
        )

    def ask(self, **command) -> dict:
        assert self.process.stdin is not None and self.process.stdout is not None
        try:
            self.process.stdin.write(json.dumps(command) + "\n")
            self.process.stdin.flush()
            line = self.process.stdout.readline()
        except BrokenPipeError:
            line = ""
        if not line:
            raise BenchmarkError(
                f"pyrender's worker ended (exit {self.process.wait()}) "
                f"before it answered {command.get('cmd')!r}"
            )
        return json.loads(line)

    def close(self) -> None:
        try:
            if self.process.poll() is None:
                self.ask(cmd="quit")
                self.process.wait(timeout=60)
        finally:
            self._files.close()


# --------------------------------------------------------------------------- meshes


@dataclass(frozen=True)
class MeshSet:
    """World-space OBJ files with their colours, and the triangles a pass draws."""

    level: int
    files: tuple[tuple[Path, tuple[float, float, float]], ...]
    triangles: int


def write_mesh_sets(folder: Path, levels: tuple[int, ...]) -> list[MeshSet]:
    """The lab scene's parts in world space, each subdivided ``level`` times, as OBJ files
    (kept in ``folder`` for the next run)."""
    import trimesh

    import mirrorlab
    from mirrorlab.scene.mesh import load_mesh
    from mirrorlab.scene.robot import scene_parts

    parts = scene_parts(mirrorlab.load_scene("lab20"))
    sets = []
    for level in levels:
        target = folder / f"lab_x{4**level}"
        target.mkdir(parents=True, exist_ok=True)
        files, triangles = [], 0
        for index, part in enumerate(parts):
            path = target / f"{index:02d}_{part.name}.obj"
            data = load_mesh(part.mesh)
            triangles += len(data.indices) * 4**level
            if not path.exists():
                vertices = (part.model[:3, :3] @ data.positions.T.astype(np.float64)).T
                vertices += part.model[:3, 3]
                faces = data.indices.astype(np.int64)
                for _ in range(level):
                    vertices, faces = trimesh.remesh.subdivide(vertices, faces)
                partial = path.with_suffix(".partial.obj")
                trimesh.Trimesh(vertices=vertices, faces=faces, process=False).export(partial)
                partial.replace(path)
            files.append((path, part.color))
        sets.append(MeshSet(level, tuple(files), triangles))
    return sets


# --------------------------------------------------------------------------- timing


def mirrorlab_variant(renderer, scenes: list, size: int) -> Callable[[int], list[float]]:
    """Frames of ``scenes`` in turn (one scene: a still frame), each read back."""
    return timed_frames(renderer, lambda turn: scenes[turn % len(scenes)], size)


def pyrender_variant(
    worker: PyrenderWorker, flags: str, scene: str = ""
) -> Callable[[int], list[float]]:
    """Frames of the worker's scene ``scene`` drawn by pyrender with ``flags`` ("default" or
    "flat"), timed by the worker."""
    return lambda count: worker.ask(cmd="frames", count=count, flags=flags, scene=scene)["ms"]


def time_configuration(
    renderers,
    worker: PyrenderWorker | None,
    lab,
    meshes: MeshSet,
    size: int,
    frames: int,
    warmup: int,
    block: int,
) -> list[dict]:
    """Median frame times of every variant for one mesh set at ``size`` x ``size`` (no
    pyrender variant without a ``worker``)."""
    from mirrorlab.scene.model import MeshObject, Transform

    objects = tuple(
        MeshObject(name=path.stem, mesh=path, color=color) for path, color in meshes.files
    )
    mirrored = replace(lab, objects=objects, animation=None)
    moved = mirrored.with_object(objects[0].name, transform=Transform(position=(0, 0, STEP)))
    plain = replace(mirrored, reflectors=())
    gl = None
    if worker is not None:
        camera = lab.camera
        gl = worker.ask(
            cmd="setup",
            size=[size, size],
            meshes=[{"path": str(path), "color": list(color)} for path, color in meshes.files],
            camera={
                "view": camera.view().ravel().tolist(),
                "yfov": float(np.radians(camera.fovy)),
                "znear": camera.near,
                "zfar": camera.far,
            },
            light={"direction": list(lab.lights[0].direction), "intensity": 3.0},
        )["gl"]
    two_pass, reflected_pass, reused, one_pass = renderers
    reflected = [
        replace(
            scene, reflectors=tuple(replace(r, technique="reflected") for r in scene.reflectors)
        )
        for scene in (mirrored, moved)
    ]
    variants = [
        Variant(MIRRORLAB_VARIANTS[0], mirrorlab_variant(two_pass, [mirrored, moved], size)),
        Variant(MIRRORLAB_VARIANTS[1], mirrorlab_variant(reflected_pass, reflected, size)),
        Variant(MIRRORLAB_VARIANTS[2], mirrorlab_variant(reused, [mirrored], size)),
        Variant(MIRRORLAB_VARIANTS[3], mirrorlab_variant(one_pass, [plain], size)),
    ]
    if worker is not None:
        variants += [
            Variant(name, pyrender_variant(worker, name.split()[1])) for name in PYRENDER_VARIANTS
        ]
    interleave(variants, frames, warmup, block)
    expected = ["capture:mirror", "camera"]
    if (
        two_pass.last_stats.ran != expected
        or reflected_pass.last_stats.ran != expected
        or reused.last_stats.ran != ["camera"]
    ):
        raise BenchmarkError(
            f"the variants did not run the passes they stand for: "
            f"{two_pass.last_stats.ran}, {reflected_pass.last_stats.ran}, "
            f"{reused.last_stats.ran}"
        )
    medians = {v.name: statistics.median(v.samples) for v in variants}
    log(
        f"{meshes.triangles} triangles, {size}x{size}: "
        + ", ".join(f"{name} {ms:.2f} ms" for name, ms in medians.items())
    )
    return [
        {
            "triangles": meshes.triangles,
            "size": size,
            "variant": v.name,
            "median_ms": round(medians[v.name], 3),
            "p10_ms": round(float(np.percentile(v.samples, 10)), 3),
            "p90_ms": round(float(np.percentile(v.samples, 90)), 3),
            "frames": len(v.samples),
            "gl": gl or two_pass.gl_renderer,
        }
        for v in variants
    ]


def run(
    worker: PyrenderWorker | None,
    mesh_sets: list[MeshSet],
    sizes: list[int],
    frames: int,
    warmup: int,
    block: int,
) -> list[dict]:
    import mirrorlab

    lab = mirrorlab.load_scene("lab20")
    rows: list[dict] = []
    # a renderer (and context) a variant, as a program drawing that scene would keep
    with contextlib.ExitStack() as stack:
        renderers = [stack.enter_context(mirrorlab.Renderer((64, 64))) for _ in MIRRORLAB_VARIANTS]
        for meshes in mesh_sets:
            for size in sizes:
                rows += time_configuration(
                    renderers, worker, lab, meshes, size, frames, warmup, block
                )
    return rows


# --------------------------------------------------------------------------- scale


SCALE_FAMILIES = (
    "mirrors unseen",
    "mirrors seen",
    "objects unseen",
    "objects seen",
    "tiny objects seen",
)
"""The scale scenes (:mod:`mirrorlab.benchmarks.scale`), each at several counts."""


def pyrender_meshes(scene, lab: MeshSet) -> list[dict]:
    """pyrender's meshes for a scale scene: the lab's parts in world space (``lab``, the
    mesh set of level 0) and each added box placed by its transform."""
    meshes = [{"path": str(path), "color": list(color)} for path, color in lab.files]
    for item in scene.objects:
        if item.name.startswith("box_"):
            meshes.append(
                {
                    "path": str(item.mesh),
                    "color": list(item.color),
                    "pose": item.transform.matrix().ravel().tolist(),
                }
            )
    return meshes


def scale_rows(
    worker: PyrenderWorker | None,
    lab: MeshSet,
    size: int,
    object_counts: list[int],
    mirror_counts: list[int],
    modes: tuple[str, ...],
    frames: int,
    warmup: int,
    block: int,
) -> list[dict]:
    """Median frame times of the scale scenes: mirrorlab in each of ``modes``, and
    pyrender's flat frame of every scene without mirrors (it has none; with a
    ``worker``), interleaved."""
    scenes = scale_scenes(object_counts, mirror_counts)
    with contextlib.ExitStack() as stack:
        variants = mirrorlab_variants(stack, scenes, size, modes)
        camera = scenes["base"].camera
        for name, scene in scenes.items():
            if "mirrors" in name or worker is None:
                continue
            setup = worker.ask(
                cmd="setup",
                name=name,
                size=[size, size],
                meshes=pyrender_meshes(scene, lab),
                camera={
                    "view": camera.view().ravel().tolist(),
                    "yfov": float(np.radians(camera.fovy)),
                    "znear": camera.near,
                    "zfar": camera.far,
                },
                light={"direction": list(scene.lights[0].direction), "intensity": 3.0},
            )
            log(f"pyrender {name}: {setup['nodes']} nodes, {setup['triangles']} triangles")
            variants.append(
                Variant(f"pyrender flat, {name}", pyrender_variant(worker, "flat", name))
            )
        interleave(variants, frames, warmup, block)
    bases = {_scale_parts(v.name)[0]: v for v in variants if v.name.endswith(", base")}
    return [
        {
            "variant": v.name,
            "size": size,
            "median_ms": round(statistics.median(v.samples), 3),
            "p10_ms": round(float(np.percentile(v.samples, 10)), 3),
            "p90_ms": round(float(np.percentile(v.samples, 90)), 3),
            "to_base": round(paired_ratio(v.blocks, bases[_scale_parts(v.name)[0]].blocks), 3),
            "frames": len(v.samples),
        }
        for v in variants
    ]


def _scale_parts(variant: str) -> tuple[str, int, str]:
    """``("mirrorlab still", 100, "objects unseen")`` from a scale variant's name."""
    kind, scene = variant.split(", ", 1)
    if scene == "base":
        return kind, 0, "base"
    count, family = scene.split(" ", 1)
    return kind, int(count), family


def scale_table(rows: list[dict]) -> str:
    """Every scale scene: each renderer's median and its ratio to that renderer's base
    frame (paired round by round, :func:`mirrorlab.benchmarks.scale.paired_ratio`), and
    mirrorlab's still frame against pyrender's flat one (the ratio of the medians)."""
    by = {_scale_parts(r["variant"]): r["median_ms"] for r in rows}
    to_base = {_scale_parts(r["variant"]): r["to_base"] for r in rows}
    kinds = list(dict.fromkeys(_scale_parts(r["variant"])[0] for r in rows))
    scenes = list(dict.fromkeys(_scale_parts(r["variant"])[1:] for r in rows))
    header = "| scene | " + " | ".join(f"{kind} ms | {kind} / its base" for kind in kinds)
    compare = [k for k in kinds if k.startswith("mirrorlab")]
    has_pyrender = "pyrender flat" in kinds
    if has_pyrender:
        header += " | " + " | ".join(f"{kind} / pyrender flat" for kind in compare)
    lines = [
        header + " |",
        "|---|" + "---:|" * (2 * len(kinds) + (len(compare) if has_pyrender else 0)),
    ]
    for count, family in scenes:
        cells = []
        for kind in kinds:
            ms = by.get((kind, count, family))
            cells += [
                "" if ms is None else f"{ms:.2f}",
                "" if ms is None else f"{to_base[kind, count, family]:.2f}x",
            ]
        if has_pyrender:
            flat = by.get(("pyrender flat", count, family))
            for kind in compare:
                ms = by.get((kind, count, family))
                cells.append("" if ms is None or flat is None else f"{ms / flat:.2f}x")
        name = "base" if family == "base" else f"{count:,} {family}"
        lines.append(f"| {name} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def scale_growth_table(rows: list[dict]) -> str:
    """For each family and renderer: the exponent k of time ~ count^k between the fewest
    and most items, and what each item adds to the base frame (µs, at the most items)."""
    by = {_scale_parts(r["variant"]): r["median_ms"] for r in rows}
    kinds = list(dict.fromkeys(_scale_parts(r["variant"])[0] for r in rows))
    lines = [
        "| scene | renderer | counts | k in count | µs an item added to the base frame |",
        "|---|---|---|---:|---:|",
    ]
    for family in SCALE_FAMILIES:
        for kind in kinds:
            counts = sorted(c for (k, c, f) in by if k == kind and f == family)
            base = by.get((kind, 0, "base"))
            if len(counts) < 2 or base is None:
                continue
            first, last = by[(kind, counts[0], family)], by[(kind, counts[-1], family)]
            k = growth_exponent([counts[0], counts[-1]], [first, last])
            added = (last - base) * 1e3 / counts[-1]
            lines.append(
                f"| {family} | {kind} | {counts[0]:,} to {counts[-1]:,} | {k:.2f} | {added:.2f} |"
            )
    return "\n".join(lines)


# --------------------------------------------------------------------------- report


def growth_exponent(amounts: list[float], times: list[float]) -> float:
    """``k`` in ``time ~ amount ** k`` between the first and last point."""
    return math.log(times[-1] / times[0]) / math.log(amounts[-1] / amounts[0])


def ratio_table(rows: list[dict]) -> str:
    """Each configuration's medians, and their ratios to pyrender's frames when it ran."""
    by_key = {(r["triangles"], r["size"], r["variant"]): r["median_ms"] for r in rows}
    with_pyrender = any(r["variant"] in PYRENDER_VARIANTS for r in rows)
    header = (
        "| triangles | size | two passes (ortho) ms | two passes (reflected) ms "
        "| reused ms | one pass ms |"
    )
    if with_pyrender:
        header += (
            " pyrender default ms | pyrender flat ms | ortho two passes / flat "
            "| reflected two passes / flat | reused / flat | one pass / flat | ortho "
            "two passes / default | reused / default |"
        )
    lines = [header, "|" + "---:|" * (header.count("|") - 1)]
    for triangles, size in dict.fromkeys((r["triangles"], r["size"]) for r in rows):
        two, reflected, reused, one = (
            by_key[(triangles, size, name)] for name in MIRRORLAB_VARIANTS
        )
        line = (
            f"| {triangles:,} | {size} | {two:.2f} | {reflected:.2f} | {reused:.2f} | {one:.2f} |"
        )
        if with_pyrender:
            default, flat = (by_key[(triangles, size, name)] for name in PYRENDER_VARIANTS)
            line += (
                f" {default:.2f} | {flat:.2f} | {two / flat:.2f}x | "
                f"{reflected / flat:.2f}x | {reused / flat:.2f}x | {one / flat:.2f}x | "
                f"{two / default:.2f}x | {reused / default:.2f}x |"
            )
        lines.append(line)
    return "\n".join(lines)


def growth_table(rows: list[dict]) -> str:
    """Exponents of frame time in pixels (per mesh set) and triangles (per size)."""
    variants = list(dict.fromkeys(r["variant"] for r in rows))
    by_key = {(r["triangles"], r["size"], r["variant"]): r["median_ms"] for r in rows}
    triangle_counts = sorted({r["triangles"] for r in rows})
    sizes = sorted({r["size"] for r in rows})
    lines = [
        "| variant | "
        + " | ".join(
            [f"k in pixels, {t:,} triangles" for t in triangle_counts]
            + [f"k in triangles, {s}x{s}" for s in sizes]
        )
        + " |",
        "|---|" + "---:|" * (len(triangle_counts) + len(sizes)),
    ]
    pixels = [s * s for s in sizes]
    for variant in variants:
        cells = []
        for triangles in triangle_counts:
            times = [by_key[(triangles, s, variant)] for s in sizes]
            cells.append(f"{growth_exponent(pixels, times):.2f}" if len(sizes) > 1 else "")
        for size in sizes:
            times = [by_key[(t, size, variant)] for t in triangle_counts]
            cells.append(
                f"{growth_exponent(triangle_counts, times):.2f}" if len(triangle_counts) > 1 else ""
            )
        lines.append(f"| {variant} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def plot(rows: list[dict]) -> bytes | None:
    """Frame time against pixels (at the fewest and most triangles) and against triangles
    (at each size), log-log, as PNG bytes; None without matplotlib."""
    try:
        import matplotlib
    except ImportError:
        return None
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    variants = list(dict.fromkeys(r["variant"] for r in rows))
    triangle_counts = sorted({r["triangles"] for r in rows})
    sizes = sorted({r["size"] for r in rows})
    by_key = {(r["triangles"], r["size"], r["variant"]): r["median_ms"] for r in rows}
    figure, (by_pixels, by_triangles) = plt.subplots(1, 2, figsize=(12, 5))
    colors = dict(zip(variants, plt.rcParams["axes.prop_cycle"].by_key()["color"], strict=False))
    for triangles, style in ((triangle_counts[0], "-"), (triangle_counts[-1], "--")):
        for variant in variants:
            pixels = [s * s for s in sizes]
            by_pixels.plot(
                pixels,
                [by_key[(triangles, s, variant)] for s in sizes],
                style,
                marker="o",
                color=colors[variant],
                label=f"{variant}, {triangles:,} tris",
            )
    for size, style in ((sizes[0], ":"), (512 if 512 in sizes else sizes[-1], "-")):
        for variant in variants:
            by_triangles.plot(
                triangle_counts,
                [by_key[(t, size, variant)] for t in triangle_counts],
                style,
                marker="o",
                color=colors[variant],
                label=f"{variant}, {size}²",
            )
    for axes, amounts, label in (
        (by_pixels, [s * s for s in sizes], "pixels"),
        (by_triangles, triangle_counts, "triangles"),
    ):
        axes.set_xscale("log")
        axes.set_yscale("log")
        axes.set_xlabel(label)
        axes.set_ylabel("median frame time, ms (readback included)")
        if len(amounts) > 1:
            top = max(r["median_ms"] for r in rows)
            guide = [top * a / amounts[-1] for a in amounts]
            axes.plot(amounts, guide, color="grey", linewidth=0.8, label="linear (slope 1)")
        axes.grid(True, which="both", alpha=0.3)
        axes.legend(fontsize=6)
    by_pixels.set_title("frame time against frame size")
    by_triangles.set_title("frame time against triangles")
    figure.tight_layout()
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=110)
    plt.close(figure)
    return buffer.getvalue()


def report(rows: list[dict], scale: list[dict], out_dir: Path, how: str, scale_how: str) -> str:
    """Write the report of ``rows`` (the sweep) and ``scale`` into ``out_dir`` and return
    its text; ``how`` and ``scale_how`` say how each one's figures were timed."""
    from mirrorlab.files import Outputs

    parts = []
    if not any(r["variant"].startswith("pyrender") for r in (*rows, *scale)):
        parts.append(
            "pyrender was not timed (give --pyrender PYTHON, the Python of an "
            f"environment with {' '.join(PYRENDER_PACKAGES)}, to time it beside "
            "these)"
        )
    if rows:
        parts += [
            f"{how}; {rows[0]['gl']}",
            ratio_table(rows),
            "Growth of frame time (k in time ~ amount^k, first to last point; 1 is linear):",
            growth_table(rows),
        ]
    if scale:
        parts += [
            f"Scenes at scale, {scale[0]['size']}x{scale[0]['size']}: the lab scene with a "
            f"reflected mirror, and objects or mirrors added "
            f"(mirrorlab.benchmarks.scale); "
            f"{scale_how}; each ratio to its base is the median of the ratios of the two "
            f"variants' medians in each round",
            scale_table(scale),
            "Growth with the number of items (k in time ~ count^k, fewest to most):",
            scale_growth_table(scale),
        ]
    text = "\n\n".join(parts) + "\n"
    picture = plot(rows) if rows else None
    with Outputs() as outputs:
        for name, table_rows in (("speed.csv", rows), ("scale.csv", scale)):
            if not table_rows:
                continue
            buffer = io.StringIO()
            writer = csv.DictWriter(buffer, fieldnames=list(table_rows[0]), lineterminator="\n")
            writer.writeheader()
            writer.writerows(table_rows)
            outputs.add(out_dir / name, buffer.getvalue().encode())
        outputs.add(out_dir / "speed.md", text.encode())
        if picture is not None:
            outputs.add(out_dir / "speed.png", picture)
    log(f"wrote {out_dir}/speed.md and its tables" + (", speed.png" if picture else ""))
    return text


def rows_from_csv(path: Path, required: bool = True) -> list[dict]:
    """The rows of a ``speed.csv`` or ``scale.csv`` this benchmark wrote (none for a missing
    file that is not ``required``); OptionError naming ``--from-csv`` for anything else."""
    if not path.is_file():
        if required:
            raise OptionError("--from-csv", f"{str(path)!r} is not a file")
        return []
    try:
        with open(path, newline="") as stream:
            rows = list(csv.DictReader(stream))
        for row in rows:
            for key in ("triangles", "size", "frames"):
                if key in row:
                    row[key] = int(row[key])
            for key in (
                "median_ms",
                "p10_ms",
                "p90_ms",
                *(("to_base",) if path.name == "scale.csv" else ()),
            ):
                row[key] = float(row[key])
            if not isinstance(row.get("variant"), str):
                raise KeyError("variant")
    except (KeyError, ValueError, TypeError, UnicodeDecodeError) as exc:
        raise OptionError(
            "--from-csv",
            f"{path} is not a table this benchmark wrote ({type(exc).__name__}: {exc})",
        ) from None
    return rows


@dataclass(frozen=True)
class SpeedSettings:
    """What ``mirrorlab bench speed`` runs (see its ``--help``)."""

    sizes: tuple[int, ...] = (256, 512, 1024, 2048)
    levels: tuple[int, ...] = (0, 2, 4, 6)
    parts: frozenset[str] = frozenset({"sweep", "scale"})
    scale_size: int = 256
    object_counts: tuple[int, ...] = (10, 100, 1000)
    mirror_counts: tuple[int, ...] = (10, 100, 400)
    modes: tuple[str, ...] = ("still", "moving")
    frames: int = 30
    scale_frames: int = 100
    warmup: int = 5
    block: int = 5

    @classmethod
    def quick(cls) -> SpeedSettings:
        """A run that checks the benchmark works, not its figures: 3 frames a variant at
        32x32 and 64x64, the lab meshes and their first subdivision, scale scenes of 3 and
        12 items at 64x64."""
        return cls(
            sizes=(32, 64),
            levels=(0, 1),
            scale_size=64,
            object_counts=(3, 12),
            mirror_counts=(3, 12),
            frames=3,
            scale_frames=3,
            warmup=1,
            block=3,
        )


def run_command(
    settings: SpeedSettings,
    out_dir: Path,
    pyrender: Path | None = None,
    from_csv: Path | None = None,
) -> int:
    """Time (or, with ``from_csv``, re-make the report of a saved ``speed.csv`` and the
    ``scale.csv`` beside it), write the report into ``out_dir`` and print it."""
    if from_csv is not None:
        rows = rows_from_csv(from_csv)
        scale_results = rows_from_csv(from_csv.with_name("scale.csv"), required=False)
        how = scale_how = f"the figures of {from_csv} and the scale.csv beside it"
    else:
        worker = PyrenderWorker(pyrender) if pyrender is not None else None
        try:
            mesh_sets = write_mesh_sets(out_dir / "meshes", settings.levels)
            rows = (
                run(
                    worker,
                    mesh_sets,
                    list(settings.sizes),
                    settings.frames,
                    settings.warmup,
                    settings.block,
                )
                if "sweep" in settings.parts
                else []
            )
            scale_results = (
                scale_rows(
                    worker,
                    mesh_sets[0],
                    settings.scale_size,
                    list(settings.object_counts),
                    list(settings.mirror_counts),
                    settings.modes,
                    settings.scale_frames,
                    settings.warmup,
                    settings.block,
                )
                if "scale" in settings.parts
                else []
            )
        finally:
            if worker is not None:
                worker.close()
        how, scale_how = (
            f"{frames} timed frames a variant after {settings.warmup} "
            f"warm-up, in turns of {settings.block}"
            for frames in (settings.frames, settings.scale_frames)
        )
    sys.stdout.write(report(rows, scale_results, out_dir, how, scale_how))
    return 0
