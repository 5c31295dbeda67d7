"""Bad input, one test per kind: each gets one line naming what is wrong, exit status 2,
and no output file appears or changes. Run through :func:`mirrorlab.cli.main` in this
(EGL) process; what needs a process of its own (a read-only file system, missing
libraries, Ctrl-C) is in test_faults.py."""

from __future__ import annotations

import hashlib
import os
import shutil
import struct
import zlib
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from mirrorlab.cli import main
from mirrorlab.data import data_path
from mirrorlab.scene.backgrounds import CUBE_FACE_FILES
from mirrorlab.techniques import technique_names

MODELS = data_path("models")


class Outputs:
    """An output that exists before the command (it must not change) and one that does
    not (it must not appear), in a folder of its own."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        self.existing = folder / "existing.png"
        Image.new("RGB", (3, 2), (1, 2, 3)).save(self.existing)
        self.digest = self._digest()
        self.fresh = folder / "fresh.png"

    def _digest(self) -> str:
        return hashlib.sha256(self.existing.read_bytes()).hexdigest()

    def assert_untouched(self) -> None:
        assert self._digest() == self.digest, "the existing output changed"
        assert not self.fresh.exists(), "a new output appeared"
        left = sorted(p.name for p in self.folder.iterdir() if p.name != "existing.png")
        assert left == [], f"files left behind: {left}"


@pytest.fixture
def outputs(tmp_path):
    folder = tmp_path / "out"
    folder.mkdir()
    return Outputs(folder)


def refused(capsys, args: list[str], *words: str) -> str:
    """Run ``mirrorlab ARGS``: exit 2 and one line on stderr holding ``words``."""
    code = main(args)
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert code == 2, f"exit {code}: {err}"
    assert len(lines) == 1, f"expected one line, got: {err}"
    assert lines[0].startswith("mirrorlab "), lines[0]
    for word in words:
        assert word in lines[0], f"{word!r} not in {lines[0]!r}"
    assert "Traceback" not in err and "Warning" not in err
    return lines[0]


def render_args(outputs: Outputs, *extra: str) -> list[str]:
    return ["render", "--size", "24x24", "--out", str(outputs.existing), *extra]


def scene_file(folder: Path, *, texture: str | None = None, mesh: str | None = None) -> Path:
    """A scene with one mesh object (a cube from the shipped models unless ``mesh``),
    textured with ``texture`` if given."""
    lines = ['name = "bad"', "[[objects]]", f'mesh = "{mesh or MODELS / "base.obj"}"']
    if texture:
        lines.append(f'texture = "{texture}"')
    path = folder / "bad.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


# --------------------------------------------------------------------------- outputs


def test_out_and_save_env_on_one_file(capsys, outputs):
    refused(
        capsys,
        render_args(outputs, "--save-env", str(outputs.existing)),
        "--save-env",
        "also the file of --out",
    )
    outputs.assert_untouched()


def test_out_dir_frames_on_the_out_file(capsys, outputs):
    refused(
        capsys,
        [
            "render",
            "robot_wave",
            "--size",
            "24x24",
            "--frames",
            "2",
            "--out",
            str(outputs.folder / "robot_wave_0001.png"),
            "--out-dir",
            str(outputs.folder),
        ],
        "also the file of --out",
    )
    outputs.assert_untouched()


def test_output_in_a_missing_folder(capsys, outputs):
    refused(
        capsys,
        ["render", "--size", "24x24", "--out", str(outputs.folder / "no" / "x.png")],
        "--out",
        "does not exist",
    )
    outputs.assert_untouched()


@pytest.mark.parametrize("option", ["--out", "--save-env"])
def test_a_write_the_system_refuses(capsys, outputs, option):
    # /proc takes no new files, whoever asks: the same message and exit status as a
    # read-only file system or a folder without permission (see test_faults.py).
    refused(
        capsys,
        render_args(outputs, option, "/proc/mirrorlab.png")
        if option == "--save-env"
        else ["render", "--out", "/proc/mirrorlab.png"],
        "cannot write /proc/mirrorlab.png: ",
    )
    outputs.assert_untouched()


def test_output_that_is_a_folder_or_under_a_file(capsys, outputs, tmp_path):
    folder = tmp_path / "folder.png"
    folder.mkdir()
    refused(capsys, ["render", "--out", str(folder)], "is a directory")
    refused(
        capsys, render_args(outputs, "--save-env", str(outputs.existing / "x.png")), "is a file"
    )
    refused(
        capsys, render_args(outputs, "--out-dir", str(outputs.existing)), "--out-dir", "is a file"
    )
    outputs.assert_untouched()


# --------------------------------------------------------------------------- sizes


@pytest.mark.parametrize(
    "size", ["0x0", "-5x5", "64x-1", "wide", "axb", "64", "9000x10", "8193x8193"]
)
def test_bad_render_sizes(capsys, outputs, size):
    refused(
        capsys,
        ["render", "--size", size, "--out", str(outputs.existing)],
        "--size",
        "expected WIDTHxHEIGHT",
    )
    outputs.assert_untouched()


@pytest.mark.parametrize("size", ["0x0", "-1x5", "x", "10000x10000"])
def test_bad_window_sizes(capsys, outputs, size):
    # Refused before a window (or a display) is needed.
    refused(capsys, ["demo", "--size", size, "--screenshot", str(outputs.existing)], "--size")
    outputs.assert_untouched()


@pytest.fixture(scope="module")
def huge_faces(tmp_path_factory):
    """Six 8192 x 8192 cube faces (1-bit PNGs, small files): more than llvmpipe can
    allocate for one cube map. The GL storage is made from the first face's header
    before any face is decoded, so the refusal comes at once."""
    folder = tmp_path_factory.mktemp("huge_faces")
    Image.new("1", (8192, 8192), 1).save(folder / "px.png")
    for stem in CUBE_FACE_FILES[1:]:
        shutil.copy(folder / "px.png", folder / f"{stem}.png")
    return folder


def test_cube_faces_beyond_what_the_gl_can_allocate(capsys, outputs, huge_faces):
    refused(
        capsys,
        render_args(outputs, "--cube-faces", str(huge_faces)),
        "OpenGL ran out of memory in pass 'background'",
        "smaller",
    )
    outputs.assert_untouched()
    # The same folder as a static cube map's source: the same refusal, in its pass.
    refused(
        capsys,
        render_args(
            outputs,
            "chrome_sphere",
            "--method",
            "cube",
            "--set",
            f'reflectors[0].source="{huge_faces}"',
        ),
        "OpenGL ran out of memory in pass",
        "smaller",
    )
    outputs.assert_untouched()


def test_a_texture_beyond_gl_max_texture_size(capsys, outputs, tmp_path):
    wide = tmp_path / "wide.png"
    Image.new("RGB", (16385, 1), (200, 10, 10)).save(wide)  # llvmpipe's limit: 16384
    scene = scene_file(tmp_path, texture=str(wide))
    refused(
        capsys,
        render_args(outputs, str(scene)),
        f"picture {wide}",
        "16385x1",
        "GL_MAX_TEXTURE_SIZE",
    )
    outputs.assert_untouched()


# --------------------------------------------------------------------------- pictures


def png_chunk(kind: bytes, data: bytes) -> bytes:
    return (
        struct.pack(">I", len(data))
        + kind
        + data
        + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    )


def bad_picture(folder: Path, kind: str) -> Path:
    path = folder / f"{kind}.png"
    if kind == "empty":
        path.write_bytes(b"")
    elif kind == "not-a-picture":
        path.write_text("these are words, not pixels\n")
    elif kind == "corrupt":
        good = folder / "good.png"
        Image.fromarray(np.random.default_rng(1).integers(0, 255, (64, 64, 3), np.uint8)).save(good)
        path.write_bytes(good.read_bytes()[:400])
    elif kind == "huge":  # a header that claims 100000 x 100000 pixels
        header = struct.pack(">IIBBBBB", 100_000, 100_000, 8, 2, 0, 0, 0)
        path.write_bytes(
            b"\x89PNG\r\n\x1a\n"
            + png_chunk(b"IHDR", header)
            + png_chunk(b"IDAT", zlib.compress(b"\0" * 64))
            + png_chunk(b"IEND", b"")
        )
    return path


PICTURE_PROBLEMS = {
    "empty": "empty (0 bytes)",
    "not-a-picture": "cannot be read as an image",
    "corrupt": "cannot be read as an image",
    "huge": "100000x100000, too large",
}


@pytest.mark.parametrize("kind", sorted(PICTURE_PROBLEMS))
def test_bad_picture_as_a_texture(capsys, outputs, tmp_path, kind):
    picture = bad_picture(tmp_path, kind)
    scene = scene_file(tmp_path, texture=str(picture))
    refused(capsys, render_args(outputs, str(scene)), f"picture {picture}", PICTURE_PROBLEMS[kind])
    outputs.assert_untouched()


@pytest.mark.parametrize("kind", ["corrupt", "huge"])
def test_bad_picture_among_cube_faces(capsys, outputs, tmp_path, kind):
    folder = tmp_path / "faces"
    folder.mkdir()
    for stem in CUBE_FACE_FILES:
        Image.new("RGB", (8, 8), (90, 90, 200)).save(folder / f"{stem}.png")
    bad_picture(tmp_path, kind).replace(folder / "py.png")
    refused(
        capsys,
        render_args(outputs, "--cube-faces", str(folder)),
        f"picture {folder / 'py.png'}",
        PICTURE_PROBLEMS[kind],
    )
    outputs.assert_untouched()


def test_cube_faces_of_mismatched_sizes(capsys, outputs, tmp_path):
    folder = tmp_path / "faces"
    folder.mkdir()
    for stem in CUBE_FACE_FILES:
        side = 16 if stem == "nz" else 8
        Image.new("RGB", (side, side), (90, 90, 200)).save(folder / f"{stem}.png")
    refused(
        capsys,
        render_args(outputs, "--cube-faces", str(folder)),
        "nz.png is 16x16",
        "expected 8x8 like px.png",
    )
    Image.new("RGB", (8, 9)).save(folder / "nz.png")
    refused(
        capsys,
        render_args(outputs, "--cube-faces", str(folder)),
        "nz.png is 8x9",
        "expected a square",
    )
    outputs.assert_untouched()


# --------------------------------------------------------------------------- meshes


def bad_mesh(folder: Path, kind: str) -> Path:
    path = folder / (f"{kind}.ply" if kind in ("corrupt", "huge") else f"{kind}.obj")
    if kind == "empty":
        path.write_bytes(b"")
    elif kind == "no-triangles":
        path.write_text("# only words here\nv 0 0 0\n")
    elif kind == "corrupt":  # a binary PLY whose data stops short
        path.write_bytes(
            b"ply\nformat binary_little_endian 1.0\nelement vertex 3\n"
            b"property float x\nproperty float y\nproperty float z\n"
            b"element face 1\nproperty list uchar int vertex_indices\n"
            b"end_header\n" + b"\0" * 10
        )
    elif kind == "non-finite":
        path.write_text("v 0 0 0\nv 1 0 nan\nv 0 1 0\nf 1 2 3\n")
    elif kind == "far":
        path.write_text("v 0 0 0\nv 1e30 0 0\nv 0 1 0\nf 1 2 3\n")
    elif kind == "huge":  # 300 MB of nothing (a sparse file: no disk used)
        with open(path, "wb") as stream:
            stream.truncate(300 * 2**20)
    return path


MESH_PROBLEMS = {
    "empty": "empty (0 bytes)",
    "no-triangles": "expected triangles, found none",
    "corrupt": "trimesh could not read it",
    "non-finite": "vertex 2 is not finite",
    "far": "too far for OpenGL's 32-bit floats",
    "huge": "300 MB, too large",
}


@pytest.mark.parametrize("kind", sorted(MESH_PROBLEMS))
def test_bad_mesh(capsys, outputs, tmp_path, kind):
    mesh = bad_mesh(tmp_path, kind)
    scene = scene_file(tmp_path, mesh=str(mesh))
    refused(capsys, render_args(outputs, str(scene)), f"mesh file {mesh}", MESH_PROBLEMS[kind])
    outputs.assert_untouched()


# --------------------------------------------------------------------------- numbers


@pytest.mark.parametrize(
    ("args", "words"),
    [
        (["--camera", "nan,5,9"], ("--camera", "expected finite numbers")),
        (["--camera", "inf,5,9"], ("--camera", "expected finite numbers")),
        (
            ["--camera", "1e308,5,9"],
            ("--camera", "camera.eye[0]", "1e+308 is too large", "overflows"),
        ),
        (["--camera", "1e150,5,9"], ("--camera", "camera.eye[0]", "1e+150 is too large")),
        (["--target", "5,-1e40,0"], ("--target", "camera.target[1]", "too large")),
        (["--angles", "0,nan,0"], ("--angles", "expected finite numbers")),
        (["--angles", "0,1e300,0"], ("--angles", "angles[1]", "too large")),
        (["--fovy", "inf"], ("--fovy", "expected finite numbers")),
        (["--set", "camera.eye=[nan, 1, 1]"], ("--set", "camera.eye[0]", "finite")),
        (
            ["--set", "camera.eye=[1e400, 1, 1]"],
            ("--set", "camera.eye[0]", "got inf", "overflows to inf"),
        ),
    ],
)
def test_non_finite_and_overflowing_values(capsys, outputs, args, words):
    refused(capsys, render_args(outputs, *args), *words)
    outputs.assert_untouched()


def test_non_finite_values_in_a_scene_file(capsys, outputs, tmp_path):
    scene = tmp_path / "nan.toml"
    scene.write_text('[[objects]]\ntype = "robot"\nangles = [0.0, nan, 0.0]\n')
    refused(
        capsys,
        render_args(outputs, str(scene)),
        "objects[0].angles[1]",
        "expected a finite number, got nan",
    )
    outputs.assert_untouched()


# --------------------------------------------------------------------------- not errors


@pytest.mark.parametrize("method", technique_names("planar"))
@pytest.mark.parametrize("eye", ["-7,1,-2", "-7,3,5", "-9,1,-2", "-12,4,6"])
def test_a_camera_on_or_behind_the_mirror_plane_renders(capsys, tmp_path, method, eye):
    # On the plane x = -7 (inside the glass or beside it) and behind it: no reflection to
    # draw, and nothing wrong either.
    out = tmp_path / "ok.png"
    code = main(
        [
            "render",
            "--size",
            "24x24",
            "--method",
            method,
            "--camera",
            eye,
            "--target",
            "0,1,0",
            "--out",
            str(out),
        ]
    )
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert captured.err == ""
    with Image.open(out) as image:
        pixels = np.asarray(image.convert("RGB"))
    assert pixels.shape == (24, 24, 3) and pixels.std() > 0  # a picture, not a blank


def test_nothing_is_left_behind_when_a_render_succeeds(capsys, outputs):
    assert main(render_args(outputs, "--save-env", str(outputs.fresh))) == 0
    capsys.readouterr()
    assert sorted(p.name for p in outputs.folder.iterdir()) == ["existing.png", "fresh.png"]
    assert os.path.getsize(outputs.fresh) > 0
