"""Batch rendering (``mirrorlab render --out-dir --jobs/--scheduler``, mirrorlab/batch.py):
frames equal single renders whatever ran them (this process, a pool of two, a Dask cluster
of two); a frame does not depend on the frames its renderer drew before; a killed batch
resumes to the same files; animations; bad input refused before anything is written.

Batches with more than one job run as processes of their own (a process pool forks, and
this test process holds EGL contexts)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

import mirrorlab
from mirrorlab.api import Renderer, resolve_scene
from mirrorlab.batch import (
    FrameJob,
    animation_bytes,
    is_whole_frame,
    release_frame_renderer,
    render_frame,
)
from mirrorlab.cli import main
from mirrorlab.data import scenes_dir
from mirrorlab.scene.backgrounds import load_picture
from mirrorlab.scene.loader import loads

SIZE = (64, 64)


def mirrorlab_command(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "mirrorlab.cli", *args], capture_output=True, text=True
    )


def frames_in(folder: Path, scene: str = "robot_wave") -> list[Path]:
    return sorted(folder.glob(f"{scene}_*.png"))


def png(path: Path) -> np.ndarray:
    return load_picture(path)


@pytest.fixture(scope="module")
def single_renders():
    """robot_wave's first 8 frames at 64x64, each by a renderer of its own."""
    return [mirrorlab.render("robot_wave", size=SIZE, frame=f) for f in range(8)]


@pytest.fixture(scope="module")
def dask_scheduler():
    """A local Dask cluster of two worker processes on loopback, for --scheduler."""
    from distributed import LocalCluster

    with LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
    ) as cluster:
        yield cluster.scheduler_address


@pytest.mark.parametrize("engine", ["serial", "pool", "dask"])
def test_batch_frames_equal_single_renders(engine, tmp_path, single_renders, request):
    options = {
        "serial": ["--jobs", "1"],
        "pool": ["--jobs", "2"],
        "dask": ["--scheduler", request.getfixturevalue("dask_scheduler")],
    }[engine]
    out_dir = tmp_path / "frames"
    result = mirrorlab_command(
        "render",
        "robot_wave",
        "--frames",
        "8",
        "--size",
        "64x64",
        "--out-dir",
        str(out_dir),
        *options,
    )
    assert result.returncode == 0, result.stderr[-2000:]
    workers = {
        "serial": "serial (1 worker)",
        "pool": "pool (2 workers)",
        "dask": "dask (2 workers)",
    }[engine]
    assert f"wrote 8 frames of robot_wave (64x64) to {out_dir}" in result.stdout
    assert workers in result.stdout
    assert "100%" in result.stderr and "8/8" in result.stderr  # the progress bar
    paths = frames_in(out_dir)
    assert [p.name for p in paths] == [f"robot_wave_{f:04d}.png" for f in range(8)]
    for frame, path in enumerate(paths):
        assert np.array_equal(png(path), single_renders[frame]), f"frame {frame} differs"
    assert not list(out_dir.glob(".*.tmp"))


ANIMATIONS = {
    # the mirror's capture (2 bounces: the sphere's live cube map inside it) reused while
    # nothing moves, the viewer moving, then the robot and the sphere
    "mirror_and_sphere": """
[animation]
frames = 6
[[animation.keyframes]]
frame = 0
camera = { eye = [12.0, 5.5, 6.0] }
reflectors.sphere.position = [-2.0, 2.0, 0.0]
[[animation.keyframes]]
frame = 2
camera = { eye = [12.0, 5.5, 6.0] }
[[animation.keyframes]]
frame = 4
camera = { eye = [10.0, 6.5, 9.0] }
reflectors.sphere.position = [-2.0, 2.0, 0.0]
[[animation.keyframes]]
frame = 5
objects.robot.angles = [-20.0, 40.0, -60.0]
reflectors.sphere.position = [-1.0, 2.5, 1.0]
""",
    # a sphere map baked for the view: reused while the view holds, baked again as it turns
    "chrome_sphere": """
[animation]
frames = 6
[[animation.keyframes]]
frame = 0
camera = { eye = [0.0, 1.0, 7.0] }
[[animation.keyframes]]
frame = 2
camera = { eye = [0.0, 1.0, 7.0] }
[[animation.keyframes]]
frame = 5
camera = { eye = [3.0, 2.0, 6.0] }
""",
}


def animated(name: str, **options):
    if name == "robot_wave":
        return resolve_scene(name, **options)
    source = scenes_dir() / f"{name}.toml"
    return resolve_scene(loads(source.read_text() + ANIMATIONS[name], source), **options)


@pytest.mark.parametrize(
    "name, options",
    [
        ("robot_wave", {}),
        ("robot_wave", {"method": "reflected", "capture": "fbo"}),
        ("mirror_and_sphere", {}),
        ("mirror_and_sphere", {"method": "stencil"}),
        ("chrome_sphere", {"method": "sphere"}),
        ("chrome_sphere", {"method": "cube-live"}),
    ],
)
def test_a_frame_does_not_depend_on_the_frames_drawn_before(name, options):
    """What a batch worker does: draw a subset of the frames in one renderer, whose planner
    reuses what its own earlier frames captured. Whole sequence, a run from the middle,
    every other frame, backwards and a fresh renderer: the same pixels."""
    scene = animated(name, **options)
    size = (48, 48)
    count = min(scene.frame_count, 8)
    with Renderer(size) as renderer:
        sequence = [renderer.render(scene, frame=f) for f in range(count)]
    histories = [range(count // 2, count), range(1, count, 2), range(count - 1, -1, -1)]
    for frames in histories:
        with Renderer(size) as renderer:
            for frame in frames:
                image = renderer.render(scene, frame=frame)
                assert np.array_equal(image, sequence[frame]), (
                    f"{name} {options} frame {frame} after frames {list(frames)}"
                )
    with Renderer(size) as renderer:
        last = count - 1
        assert np.array_equal(renderer.render(scene, frame=last), sequence[last])


def test_the_planner_reuses_captures_inside_a_worker():
    """The reuse the test above relies on being exact does happen: robot_wave's frames 1-4
    skip the mirror's capture when drawn in order after frame 0."""
    with Renderer((48, 48)) as renderer:
        skipped = []
        for frame in range(6):
            renderer.render("robot_wave", frame=frame)
            assert renderer.last_stats is not None
            skipped.append(bool(renderer.last_stats.skipped))
    assert skipped == [False, True, True, True, True, False]


def test_a_killed_batch_resumes_to_the_same_files(tmp_path):
    """SIGKILL a real batch (its whole process group) once its first frame is on disk, with
    23 frames of 30-40 ms each still to come; the rerun, on two processes, renders only
    the missing ones, and the folder ends as an uninterrupted batch's."""
    out_dir = tmp_path / "frames"
    command = [
        sys.executable,
        "-m",
        "mirrorlab.cli",
        "render",
        "robot_wave",
        "--frames",
        "24",
        "--size",
        "512x512",
        "--out-dir",
        str(out_dir),
        "--jobs",
        "1",
    ]
    process = subprocess.Popen(
        command, stdout=subprocess.PIPE, stderr=subprocess.PIPE, start_new_session=True
    )
    try:
        while process.poll() is None and not frames_in(out_dir):
            time.sleep(0.005)  # waiting for the condition: a frame on disk
        assert process.poll() is None, process.communicate()[1].decode()[-2000:]
        os.killpg(process.pid, signal.SIGKILL)
        process.wait()
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
            process.wait()
    assert process.stdout is not None and process.stderr is not None
    process.stdout.close()
    process.stderr.close()
    written = [p for p in frames_in(out_dir) if is_whole_frame(p, (512, 512))]
    assert 1 <= len(written) < 24, f"{len(written)} frames were written before the kill"

    resumed = mirrorlab_command(*command[3:-2], "--jobs", "2")
    assert resumed.returncode == 0, resumed.stderr[-2000:]
    assert f"wrote {24 - len(written)} frames" in resumed.stdout
    assert f"skipped {len(written)} already written whole" in resumed.stdout
    assert not list(out_dir.glob(".*.tmp"))
    paths = frames_in(out_dir)
    assert len(paths) == 24
    job = FrameJob(resolve_scene("robot_wave"), (512, 512))
    try:
        for frame, path in enumerate(paths):
            assert path.read_bytes() == render_frame(job, frame), f"frame {frame} differs"
    finally:
        release_frame_renderer()


def test_a_rerun_skips_whole_frames_and_redoes_broken_or_foreign_ones(tmp_path, capsys):
    out_dir = tmp_path / "frames"
    args = ["render", "robot_wave", "--frames", "6", "--size", "32x32", "--out-dir", str(out_dir)]
    assert main(args) == 0
    first = {p.name: p.read_bytes() for p in frames_in(out_dir)}
    assert len(first) == 6
    (out_dir / "robot_wave_0001.png").unlink()
    broken = out_dir / "robot_wave_0004.png"
    broken.write_bytes(first[broken.name][:200])  # cut short
    capsys.readouterr()
    assert main(args) == 0
    assert "wrote 2 frames" in capsys.readouterr().out
    assert {p.name: p.read_bytes() for p in frames_in(out_dir)} == first
    assert main(args) == 0
    assert "skipped 6, nothing to render" in capsys.readouterr().out
    # the same folder, other settings: nothing of the old frames is kept
    assert main([*args, "--method", "stencil"]) == 0
    assert "replaced 6 made with other settings" in capsys.readouterr().out


def test_a_still_scene_is_one_frame_and_animations_hold_every_frame(tmp_path):
    still = mirrorlab_command(
        "render", "lab20", "--size", "64x64", "--out-dir", str(tmp_path / "still"), "--jobs", "2"
    )
    assert still.returncode == 0, still.stderr[-2000:]
    assert [p.name for p in (tmp_path / "still").glob("*.png")] == ["lab20_0000.png"]
    assert np.array_equal(
        png(tmp_path / "still" / "lab20_0000.png"), mirrorlab.render("lab20", size=SIZE)
    )

    out_dir, gif, webp = tmp_path / "wave", tmp_path / "wave.gif", tmp_path / "wave.webp"
    assert (
        main(
            [
                "render",
                "robot_wave",
                "--frames",
                "8",
                "--size",
                "64x64",
                "--out-dir",
                str(out_dir),
                "--gif",
                str(gif),
                "--webp",
                str(webp),
                "--fps",
                "10",
                "--out",
                str(tmp_path / "last.png"),
            ]
        )
        == 0
    )

    frames = [png(p) for p in frames_in(out_dir)]
    assert np.array_equal(png(tmp_path / "last.png"), frames[-1])
    shown = {kind: shown_frames(path, 100) for kind, path in (("gif", gif), ("webp", webp))}
    # Pillow merges identical neighbours (frames 0-4 stand still) into one longer frame
    assert len(shown["webp"]) == len(shown["gif"]) == 8
    for frame, (expected, lossless, paletted) in enumerate(
        zip(frames, shown["webp"], shown["gif"], strict=True)
    ):
        assert np.array_equal(lossless, expected), f"WebP frame {frame}"
        # 256 colours a frame: close, not exact
        assert np.abs(paletted.astype(int) - expected).mean() < 3.0, f"GIF frame {frame}"


def shown_frames(path: Path, milliseconds: int) -> list[np.ndarray]:
    """The pictures an animation shows, one per ``milliseconds`` of its frames' times."""
    from PIL import GifImagePlugin, Image, WebPImagePlugin

    shown = []
    with Image.open(path) as animation:
        assert isinstance(animation, GifImagePlugin.GifImageFile | WebPImagePlugin.WebPImageFile)
        for index in range(animation.n_frames):
            animation.seek(index)
            picture = np.asarray(animation.convert("RGB"))  # loads it, and its duration
            repeats = animation.info["duration"] / milliseconds
            assert repeats == round(repeats) >= 1
            shown += [picture] * round(repeats)
    return shown


def test_whole_frames_are_complete_pngs_of_the_size(tmp_path):
    from mirrorlab.files import write_bytes_atomic, write_png_atomic

    path = tmp_path / "a.png"
    write_png_atomic(path, np.zeros((24, 32, 3), dtype=np.uint8))
    assert is_whole_frame(path, (32, 24))
    assert not is_whole_frame(path, (24, 32))
    assert not is_whole_frame(tmp_path / "missing.png", (32, 24))
    disguised = tmp_path / "b.png"  # a GIF under a PNG's name
    write_bytes_atomic(disguised, animation_bytes([path], "gif", 10))
    assert not is_whole_frame(disguised, (32, 24))
    path.write_bytes(path.read_bytes()[:-20])  # cut short
    assert not is_whole_frame(path, (32, 24))


# --------------------------------------------------------------------------- bad input


def refused(capsys, args, *words):
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    assert err[0].startswith("mirrorlab render: error: ")
    for word in words:
        assert word in err[0]


@pytest.mark.parametrize(
    "extra, words",
    [
        (["--jobs", "0"], ["--jobs", "from 1 to 1024", "'0'"]),
        (["--jobs", "two"], ["--jobs", "'two'"]),
        (["--fps", "0"], ["--fps"]),
        (["--gif", "/proc/mirrorlab.gif"], ["cannot write /proc/mirrorlab.gif"]),
        (["--webp", "NAME.gif"], ["--webp", "ending in .webp"]),
        (["--gif", "no/such/folder/a.gif"], ["--gif", "does not exist"]),
        (["--stats"], ["--stats", "without --out-dir"]),
    ],
)
def test_bad_batch_options_are_refused_before_anything_is_written(capsys, tmp_path, extra, words):
    out_dir = tmp_path / "frames"
    refused(
        capsys,
        [
            "render",
            "robot_wave",
            "--frames",
            "4",
            "--size",
            "32x32",
            "--out-dir",
            str(out_dir),
            *extra,
        ],
        *words,
    )
    assert not out_dir.exists()


def test_batch_options_need_an_out_dir(capsys, tmp_path):
    for extra in (
        ["--jobs", "2"],
        ["--scheduler", "tcp://127.0.0.1:9"],
        ["--gif", str(tmp_path / "a.gif")],
    ):
        refused(
            capsys,
            ["render", "robot_wave", "--frames", "4", "--out", str(tmp_path / "a.png"), *extra],
            extra[0],
            "give --out-dir",
        )
    assert list(tmp_path.iterdir()) == []


def test_an_out_dir_that_is_a_file(capsys, tmp_path):
    blocker = tmp_path / "frames"
    blocker.write_text("not a folder")
    refused(capsys, ["render", "robot_wave", "--out-dir", str(blocker)], "--out-dir", "is a file")
    refused(
        capsys,
        ["render", "robot_wave", "--out-dir", str(blocker / "deeper")],
        "--out-dir",
        "is a file",
    )
    assert blocker.read_text() == "not a folder"


def test_an_unreachable_scheduler(capsys, tmp_path, monkeypatch):
    monkeypatch.setattr("mirrorlab.jobs.CONNECT_TIMEOUT", "1s")
    out_dir = tmp_path / "frames"
    refused(
        capsys,
        [
            "render",
            "robot_wave",
            "--frames",
            "3",
            "--size",
            "32x32",
            "--out-dir",
            str(out_dir),
            "--scheduler",
            "tcp://127.0.0.1:9",
        ],
        "--scheduler: cannot reach a Dask scheduler at 'tcp://127.0.0.1:9'",
    )
    assert not out_dir.exists()
