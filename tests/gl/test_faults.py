"""Faults from outside the input, each in a process of its own: a read-only file system
and a folder without permission (through bubblewrap), OpenGL libraries that cannot be
loaded, an OpenGL too old, no display, and Ctrl-C. Each ends with one line on stderr,
its exit status (2 bad input or a refused write, 1 the machine, 130 interrupted), and no
output file written or changed."""

from __future__ import annotations

import hashlib
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import threading
from pathlib import Path

import pytest
from PIL import Image

from mirrorlab.data import data_path
from tests import REPO_DIR

GIVE_UP_S = 120.0
"""Only a limit for a hung process: every wait ends when its condition holds."""
LIBDIR = Path("/usr/lib/x86_64-linux-gnu")

needs_bwrap = pytest.mark.skipif(
    shutil.which("bwrap") is None and not os.environ.get("CI"),
    reason="bubblewrap is not installed (./dev installs it)",
)


def mirrorlab_command(*args: str) -> list[str]:
    return [sys.executable, "-m", "mirrorlab.cli", *args]


def run(command: list[str], env: dict | None = None) -> subprocess.CompletedProcess:
    return subprocess.run(
        command,
        capture_output=True,
        text=True,
        timeout=GIVE_UP_S,
        cwd=REPO_DIR,
        env={**os.environ, **(env or {})},
    )


def sandboxed(
    *args: str, read_only: Path | None = None, hide: tuple[Path, ...] = (), uid: int | None = None
) -> list[str]:
    """``mirrorlab ARGS`` under bubblewrap: the whole file system as it is, but
    ``read_only`` mounted read-only, the files ``hide`` replaced by empty ones, and with
    ``uid`` as a user who is not root."""
    command = ["bwrap", "--bind", "/", "/", "--dev", "/dev", "--proc", "/proc", "--die-with-parent"]
    if read_only is not None:
        command += ["--ro-bind", str(read_only), str(read_only)]
    for path in hide:
        command += ["--ro-bind", "/dev/null", str(path)]
    if uid is not None:
        # Mesa keeps its shader cache under $HOME, which this user may not write to (and
        # says so on stderr): give it a home of its own. In bubblewrap's user namespace the
        # user is the caller outside, who owns the folder: it needs no other user's access
        # (0700), and it is removed after the test.
        home = Path(tempfile.mkdtemp(prefix="mirrorlab-home-"))
        home.chmod(0o700)
        HOMES.append(home)
        command += [
            "--unshare-user",
            "--uid",
            str(uid),
            "--gid",
            str(uid),
            "--setenv",
            "HOME",
            str(home),
            "--setenv",
            "XDG_CACHE_HOME",
            str(home),
        ]
    return command + mirrorlab_command(*args)


HOMES: list[Path] = []


@pytest.fixture(autouse=True)
def remove_homes():
    yield
    while HOMES:
        shutil.rmtree(HOMES.pop(), ignore_errors=True)


def one_line(result: subprocess.CompletedProcess, code: int, *words: str) -> str:
    lines = result.stderr.strip().splitlines()
    assert result.returncode == code, f"exit {result.returncode}: {result.stderr}"
    assert len(lines) == 1, f"expected one line, got: {result.stderr}"
    for word in words:
        assert word in lines[0], f"{word!r} not in {lines[0]!r}"
    return lines[0]


@pytest.fixture
def shared_folder():
    """A folder that a user who is not root can enter (pytest's tmp_path is root's only)."""
    folder = Path(tempfile.mkdtemp(prefix="mirrorlab-faults-"))
    folder.chmod(0o755)
    yield folder
    shutil.rmtree(folder, ignore_errors=True)


def existing_png(folder: Path) -> tuple[Path, str]:
    path = folder / "existing.png"
    Image.new("RGB", (3, 2), (1, 2, 3)).save(path)
    return path, hashlib.sha256(path.read_bytes()).hexdigest()


def digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


# --------------------------------------------------------------------------- writes


@needs_bwrap
def test_save_env_on_a_read_only_file_system_keeps_the_existing_output(shared_folder):
    existing, before = existing_png(shared_folder)
    locked = shared_folder / "locked"
    locked.mkdir()
    result = run(
        sandboxed(
            "render",
            "--size",
            "24x24",
            "--out",
            str(existing),
            "--save-env",
            str(locked / "env.png"),
            read_only=locked,
        )
    )
    one_line(result, 2, f"cannot write {locked / 'env.png'}: Read-only file system")
    assert digest(existing) == before
    assert sorted(p.name for p in shared_folder.iterdir()) == ["existing.png", "locked"]
    assert list(locked.iterdir()) == []


@needs_bwrap
def test_a_folder_without_permission_gives_the_same_line_and_status(shared_folder):
    locked = shared_folder / "locked"
    locked.mkdir()
    locked.chmod(0o555)
    result = run(sandboxed("render", "--size", "24x24", "--out", str(locked / "x.png"), uid=1000))
    one_line(result, 2, f"cannot write {locked / 'x.png'}: Permission denied")
    assert list(locked.iterdir()) == []


@needs_bwrap
def test_unreadable_picture_and_mesh_files(shared_folder):
    picture = shared_folder / "secret.png"
    Image.new("RGB", (4, 4)).save(picture)
    mesh = shared_folder / "secret.obj"
    shutil.copy(data_path("models") / "base.obj", mesh)
    for path in (picture, mesh):
        path.chmod(0o000)
    out = shared_folder / "out.png"
    scene = shared_folder / "scene.toml"
    scene.write_text(
        f'[[objects]]\nmesh = "{data_path("models") / "base.obj"}"\ntexture = "{picture}"\n'
    )
    result = run(sandboxed("render", str(scene), "--size", "24x24", "--out", str(out), uid=1000))
    one_line(result, 2, f"picture {picture}", "Permission denied")
    scene.write_text(f'[[objects]]\nmesh = "{mesh}"\n')
    result = run(sandboxed("render", str(scene), "--size", "24x24", "--out", str(out), uid=1000))
    one_line(result, 2, f"mesh file {mesh}", "Permission denied")
    assert not out.exists()


# --------------------------------------------------------------------------- the machine


@needs_bwrap
def test_missing_egl_library_names_the_debian_packages(tmp_path):
    out = tmp_path / "x.png"
    # no display either: both ways out are named
    command = sandboxed(
        "render", "--size", "24x24", "--out", str(out), hide=(LIBDIR / "libEGL.so.1",)
    )
    result = run([*command[:1], "--unsetenv", "DISPLAY", *command[1:]])
    one_line(
        result,
        1,
        "libEGL.so.1 cannot be loaded and there is no display",
        "install the Debian packages libegl1 libegl-mesa0 libgl1-mesa-dri",
        "'xvfb-run -a') to render in a hidden window",
    )
    # EGL forced: the library itself is named
    result = run(
        sandboxed("render", "--size", "24x24", "--out", str(out), hide=(LIBDIR / "libEGL.so.1",)),
        env={"MIRRORLAB_GL_BACKEND": "egl"},
    )
    one_line(
        result,
        1,
        "cannot load the OpenGL library libEGL.so.1",
        "install the Debian packages libegl1 libegl-mesa0 libgl1-mesa-dri",
    )
    assert not out.exists()


@needs_bwrap
def test_missing_glx_library_names_the_debian_packages(tmp_path):
    result = run(
        sandboxed("demo", "--max-frames", "1", hide=(LIBDIR / "libGL.so.1",)),
        env={"DISPLAY": ":99"},
    )
    one_line(
        result,
        1,
        "cannot load the OpenGL library libGL.so.1",
        "libgl1 libglx-mesa0 libgl1-mesa-dri",
    )


def test_no_display_points_to_render():
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    result = subprocess.run(
        mirrorlab_command("demo", "--max-frames", "1"),
        capture_output=True,
        text=True,
        timeout=GIVE_UP_S,
        cwd=REPO_DIR,
        env=env,
    )
    one_line(result, 1, "no display", "xvfb-run", "mirrorlab render")


def test_an_opengl_too_old_names_the_technique_and_the_version(tmp_path):
    out = tmp_path / "x.png"
    result = run(
        mirrorlab_command("render", "--size", "24x24", "--method", "stencil", "--out", str(out)),
        env={"MESA_GL_VERSION_OVERRIDE": "3.0"},
    )
    one_line(result, 1, "technique 'stencil' needs OpenGL 3.3", "OpenGL 3.0")
    result = run(
        mirrorlab_command("render", "no_mirror", "--size", "24x24", "--out", str(out)),
        env={"MESA_GL_VERSION_OVERRIDE": "3.0"},
    )
    one_line(result, 1, "mirrorlab's renderer (GLSL 3.30) needs OpenGL 3.3")
    assert not out.exists()


# --------------------------------------------------------------------------- Ctrl-C


def _default_sigint() -> None:
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def interrupt_when(command: list[str], started: str) -> subprocess.CompletedProcess:
    """Run ``command``, send it SIGINT (Ctrl-C) once ``started`` shows on its stderr (its
    progress bar), and return what it did."""
    # A command started in the background of a non-interactive shell inherits SIGINT
    # ignored, and Python then never turns SIGINT into KeyboardInterrupt: the child gets
    # the default action back, whatever started pytest (a render ran to its end so).
    process = subprocess.Popen(
        command,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        cwd=REPO_DIR,
        preexec_fn=_default_sigint,
    )
    seen = bytearray()
    ready = threading.Event()

    def read() -> None:
        while chunk := process.stderr.read1(4096):  # type: ignore[union-attr]
            seen.extend(chunk)
            if started.encode() in seen:
                ready.set()
        ready.set()

    reader = threading.Thread(target=read, daemon=True)
    reader.start()
    try:
        assert ready.wait(GIVE_UP_S), f"{started!r} never showed"
        assert process.poll() is None, f"it ended first: {seen.decode(errors='replace')}"
        process.send_signal(signal.SIGINT)
        stdout = process.stdout.read()  # type: ignore[union-attr]
        code = process.wait(GIVE_UP_S)
        reader.join(GIVE_UP_S)
    finally:
        if process.poll() is None:
            process.kill()
            process.wait()
    return subprocess.CompletedProcess(
        command, code, stdout.decode(), seen.decode(errors="replace")
    )


def last_line(text: str) -> str:
    return [part for part in text.replace("\r", "\n").splitlines() if part.strip()][-1]


def test_ctrl_c_during_a_render(tmp_path):
    out = tmp_path / "x.png"
    result = interrupt_when(
        mirrorlab_command("render", "--raytrace", "--size", "2048x2048", "--out", str(out)),
        "ray tracing",
    )
    assert result.returncode == 130, result.stderr[-2000:]
    assert last_line(result.stderr) == "mirrorlab render: interrupted"
    assert "Traceback" not in result.stderr and "KeyboardInterrupt" not in result.stderr
    assert not out.exists() and list(tmp_path.iterdir()) == []


def test_ctrl_c_during_the_accuracy_sweep(tmp_path):
    result = interrupt_when(
        mirrorlab_command("bench", "accuracy", "--quick", "--out-dir", str(tmp_path)), "accuracy"
    )
    assert result.returncode == 130, result.stderr[-2000:]
    assert last_line(result.stderr) == "mirrorlab bench: interrupted"
    assert "Traceback" not in result.stderr and "KeyboardInterrupt" not in result.stderr
    assert list(tmp_path.iterdir()) == []
