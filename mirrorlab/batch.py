"""Batch rendering (``mirrorlab render SCENE --frames N --out-dir DIR --jobs J``): the frames
of a scene sent across the executor of :mod:`mirrorlab.jobs` (this process for one job, a
process pool, or a Dask cluster), each frame written to ``DIR/SCENE_NNNN.png`` whole, as
soon as it is done, so that an interrupted batch resumes where it stopped.

How the work is cut: **one job per frame, and one renderer per worker process, kept for
all the frames that process draws.** A job is a function call (:func:`render_frame`); it
finds its process's :class:`~mirrorlab.api.Renderer` in a thread-local cache, made by the
first frame of the batch that process draws (a context and its shaders take about 0.3 s
here, a 512x512 frame after that 10-20 ms, so a renderer per job would cost more than the
frames). Per-frame jobs give a progress bar that moves frame by frame, spread frames of
unequal cost evenly over the workers, lose at most the frames in flight when a batch is
killed, and return each frame as PNG bytes, so the command writes every file itself and
Dask workers on other machines need no shared folder for the output.

Why the frames are identical whatever the number of jobs: a worker draws a scattered
subset of the frames, in order, so its planner may reuse a capture (TextureState) made
for an earlier frame of its own where a single renderer would have reused one from the
frame just before. A capture is reused only when its key, everything the capture shows
(the scene's content, the capture camera, the texture size), is equal (a reflected
capture's camera matrices, and a sphere map's view rotation, are compared rounded to 12
decimals: two views closer than that, far below float32's precision, count as one). The
tests (``tests/batch``) compare, pixel for pixel, frames drawn in sequence with the same
frames drawn from the middle on, every other one, backwards and by a fresh renderer.

The renderer's lifetime: from the first frame of a batch in a thread to
:func:`release_frame_renderer` (the command calls it for its own process at the end of a
batch), or to the first frame of the next batch in that thread, which releases it first.
A pool's worker processes and a local Dask cluster end with the batch's executor, taking
their contexts with them; a worker of a running ``--scheduler`` keeps its renderer until
its next batch or its end.
"""

from __future__ import annotations

import io
import json
import sys
import threading
import time
import uuid
from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

from mirrorlab.errors import BatchError
from mirrorlab.files import png_bytes, write_bytes_atomic
from mirrorlab.jobs import open_executor
from mirrorlab.scene.model import Scene


@dataclass(frozen=True)
class FrameJob:
    """What every frame of a batch is drawn with: the ``scene``, ``size`` (width, height),
    whether the planner may skip passes (``use_plan``), the technique that draws the whole
    frame instead of OpenGL (``frame_technique``, e.g. the ray tracer; None: OpenGL), a
    debug context, and the batch's ``token`` (a worker's renderer belongs to one batch)."""

    scene: Scene
    size: tuple[int, int]
    use_plan: bool = True
    frame_technique: str | None = None
    debug: bool = False
    token: str = ""
    tiny_pixels: float = 0.0
    """Above 0: the planner's lossy small-reflector rule (see :mod:`mirrorlab.plan`)."""

    def description(self) -> str:
        """Everything that decides the frames' pixels, as text (the folder's record)."""
        from mirrorlab.scene.loader import dumps

        return json.dumps(
            {
                "scene": dumps(self.scene),
                "size": list(self.size),
                "use_plan": self.use_plan,
                "tiny_pixels": self.tiny_pixels,
                "frame_technique": self.frame_technique,
            },
            sort_keys=True,
        )


_cache = threading.local()


def _frame_renderer(job: FrameJob):
    from mirrorlab.api import Renderer

    held = getattr(_cache, "held", None)
    if held is not None and held[0] == (job.token, job.debug):
        return held[1]
    release_frame_renderer()
    renderer = Renderer(job.size, debug=job.debug)
    renderer.open()
    _cache.held = ((job.token, job.debug), renderer)
    return renderer


def release_frame_renderer() -> None:
    """Close the renderer :func:`render_frame` keeps in the calling thread, if any."""
    held = getattr(_cache, "held", None)
    _cache.held = None
    if held is not None:
        held[1].close()


def render_frame(job: FrameJob, frame: int, reflectors: tuple | None = None) -> bytes:
    """One frame of ``job``'s scene as PNG file bytes: what a worker runs. OpenGL frames
    are drawn by this thread's kept renderer; a frame technique's (the ray tracer's) need
    no context. ``reflectors``: the frame's reflectors as a budget chose them (the
    choices of a budget are made for the whole batch first, in frame order, so that a
    frame does not depend on which worker draws it)."""
    if job.frame_technique is not None:
        from mirrorlab.techniques import technique

        draw_frame = technique(job.frame_technique).frame_function()
        image = draw_frame(job.scene.at_frame(frame), job.size, progress=False)
    else:
        scene = job.scene
        if reflectors is not None:
            scene = replace(
                scene.at_frame(frame), reflectors=reflectors, budget=None, animation=None
            )
            frame = 0
        image = _frame_renderer(job).render(
            scene,
            frame=frame,
            size=job.size,
            use_plan=job.use_plan,
            tiny_pixels=job.tiny_pixels,
        )
    return png_bytes(image)


def frame_name(out_dir: Path, scene: Scene, frame: int) -> Path:
    return out_dir / f"{scene.name}_{frame:04d}.png"


def record_name(out_dir: Path, scene: Scene) -> Path:
    """The hidden file that says how the frames of ``scene`` in ``out_dir`` were made."""
    return out_dir / f".{scene.name}.mirrorlab-batch.json"


_PNG_END = b"\x00\x00\x00\x00IEND\xaeB`\x82"
"""The last chunk of every PNG file: an empty IEND and its CRC."""


def is_whole_frame(path: Path, size: tuple[int, int]) -> bool:
    """True when ``path`` is a complete PNG of ``size`` (width, height), RGB: it ends with
    its end chunk, and its pixels decode to the last row."""
    from PIL import Image

    try:
        with path.open("rb") as stream:
            stream.seek(-len(_PNG_END), 2)
            if stream.read() != _PNG_END:
                return False
        with Image.open(path) as image:
            if image.format != "PNG" or image.size != tuple(size) or image.mode != "RGB":
                return False
            image.load()
    except (OSError, SyntaxError, ValueError):
        return False
    return True


def _remove_staged(out_dir: Path, names: Sequence[Path]) -> None:
    """Remove the temporary files a killed batch left beside its frames (``.NAME.*.tmp``,
    see :mod:`mirrorlab.files`)."""
    if not out_dir.is_dir():
        return
    for name in names:
        for leftover in out_dir.glob(f".{name.name}.*.tmp"):
            leftover.unlink(missing_ok=True)


def animation_bytes(paths: Sequence[Path], kind: str, fps: float) -> bytes:
    """The frames at ``paths`` as one animated ``kind`` ("gif" or "webp") file, looping,
    ``fps`` frames a second. WebP is lossless; GIF has 256 colours a frame."""
    from PIL import Image

    images = []
    for path in paths:
        with Image.open(path) as image:
            images.append(image.convert("RGB"))
    options = {"lossless": True, "quality": 100, "method": 4} if kind == "webp" else {}
    with io.BytesIO() as buffer:
        images[0].save(
            buffer,
            format=kind.upper(),
            save_all=True,
            append_images=images[1:],
            duration=round(1000.0 / fps),
            loop=0,
            **options,
        )
        return buffer.getvalue()


def run_batch(
    job: FrameJob,
    frames: Sequence[int],
    out_dir: Path,
    jobs: int = 1,
    scheduler: str | None = None,
    engine: str = "pool",
    out: Path | None = None,
    animations: Sequence[tuple[str, Path]] = (),
    fps: float = 12.0,
    say: Callable[[str], None] = print,
    progress: bool = True,
) -> int:
    """Render ``frames`` of ``job.scene`` into ``out_dir`` across ``jobs`` processes (or
    the Dask scheduler at ``scheduler``; see :func:`mirrorlab.jobs.open_executor`), each
    frame's file written whole as it comes in. Frames already in ``out_dir`` whole, made
    with the same scene and settings (a hidden record file says how they were made), are
    skipped. Then the last frame is copied to ``out``, and ``animations`` (``("gif" or
    "webp", path)``) are written from the frame files. Raises :class:`BatchError` when a
    frame fails (the frames that worked stay written)."""

    scene = job.scene
    job = replace(job, token=uuid.uuid4().hex)
    names = {frame: frame_name(out_dir, scene, frame) for frame in frames}
    record = record_name(out_dir, scene)
    description = job.description()
    same = record.is_file() and record.read_text(errors="replace") == description
    todo = [f for f in frames if not (same and is_whole_frame(names[f], job.size))]
    skipped = len(frames) - len(todo)
    replaced = 0 if same else sum(names[f].exists() for f in frames)
    started = time.perf_counter()
    engine_name = "no engine"
    if todo:
        engine_name = _render_frames(
            job, todo, names, record, description, jobs, scheduler, engine, skipped, progress
        )
    seconds = time.perf_counter() - started
    if out is not None:
        write_bytes_atomic(out, names[frames[-1]].read_bytes())
    for kind, path in animations:
        write_bytes_atomic(path, animation_bytes([names[f] for f in frames], kind, fps))
    if todo:
        say(
            f"wrote {len(todo)} frame{'' if len(todo) == 1 else 's'} of {scene.name} "
            f"({job.size[0]}x{job.size[1]}) to "
            f"{out_dir} in {seconds:.1f} s on {engine_name}, "
            f"{len(todo) / seconds:.1f} frames a second, start-up included; skipped "
            f"{skipped} already written whole"
            + (f"; replaced {replaced} made with other settings" if replaced else "")
        )
    else:
        say(
            f"all {len(frames)} frames of {scene.name} were already written whole in "
            f"{out_dir}; skipped {skipped}, nothing to render"
        )
    written = ([str(out)] if out is not None else []) + [str(p) for _, p in animations]
    if written:
        say(f"wrote {', '.join(written)}")
    return 0


def _render_frames(
    job: FrameJob,
    todo: Sequence[int],
    names: dict[int, Path],
    record: Path,
    description: str,
    jobs: int,
    scheduler: str | None,
    engine: str,
    skipped: int,
    progress: bool,
) -> str:
    """Draw ``todo`` on the executor, writing each frame to ``names[frame]`` as it comes
    in; returns the engine's name. Nothing is written before the executor is up (an
    unreachable scheduler leaves the folder as it was)."""
    from tqdm import tqdm

    chosen: dict[int, tuple] = {}
    if job.scene.budget is not None and job.frame_technique is None:
        from mirrorlab.budget.chooser import choose_frames

        chosen = {
            frame: scene.reflectors
            for frame, (scene, _) in choose_frames(job.scene, sorted(names), job.size).items()
        }
    with open_executor(jobs, scheduler, engine) as executor:
        _remove_staged(record.parent, [names[f] for f in todo])
        if not (record.is_file() and record.read_text(errors="replace") == description):
            write_bytes_atomic(record, description.encode())
        failures: list[tuple[int, str]] = []
        bar = tqdm(
            total=len(todo) + skipped,
            initial=skipped,
            unit="frame",
            desc=f"rendering {job.scene.name}",
            disable=not progress,
            file=sys.stderr,
            dynamic_ncols=True,
            mininterval=0.2,
        )
        try:
            with bar:
                for outcome in executor.run(
                    render_frame, {f"frame-{f:04d}": (job, f, chosen.get(f)) for f in todo}
                ):
                    frame = int(outcome.key.split("-")[1])
                    if outcome.error is not None:
                        failures.append((frame, outcome.error))
                        continue
                    write_bytes_atomic(names[frame], outcome.value)
                    bar.update(1)
        finally:
            release_frame_renderer()  # the serial engine drew in this process
        name = f"{executor.engine} ({executor.workers} worker"
        name += "s)" if executor.workers != 1 else ")"
    if failures:
        failures.sort()
        frame, error = failures[0]
        raise BatchError(
            f"{len(failures)} of {len(todo)} frames failed (written: "
            f"{len(todo) - len(failures)}; a rerun renders only the missing "
            f"ones); frame {frame}: {error}"
        )
    return name
