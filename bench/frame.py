"""Frame-time benchmark: mirrorlab's two-pass renderer against a minimal PyOpenGL yardstick.

Run from the repository root::

    python bench/frame.py [--size 512x512] [--frames 50] [--warmup 10] [--block 5]
                          [--json PATH] [--save-images DIR]

Everything runs in one process and one headless (EGL) context, so both sides share
the same driver, PyOpenGL configuration and CPU. Three variants are timed:

``mirrorlab``
    ``SceneRenderer.render(scene, framebuffer)`` with the capture forced (its texture
    marked stale before each frame: capture pass and camera pass) followed by
    ``Framebuffer.read()`` into numpy: the real renderer on the shipped ``lab20`` scene.
``minimal``
    The same two passes written directly against PyOpenGL in this file: its own
    framebuffer of the same size, one VBO + EBO + VAO per mesh (loaded with
    ``mirrorlab.scene.mesh.load_mesh``) plus one for the mirror quad, one shader
    program (lit parts, textured base, mirror quad chosen by a uniform), the same
    world matrices (``mirrorlab.scene.robot.scene_parts``), pass 1 = orthographic
    capture copied with
    ``glCopyTexImage2D``, pass 2 = perspective view plus the mirror textured with the
    capture, then ``glReadPixels`` into numpy. Per-part uniforms are worked out once.
    None of mirrorlab's passes, renderer or GL resource classes is used.
``mirrorlab, capture skipped``
    ``SceneRenderer.render(scene, framebuffer)`` without forcing the capture: nothing
    changed since the last capture, so the planner runs only the camera pass. This
    is what the frame plan saves.

Every frame ends with a readback to numpy, which waits for the GL to finish, so a
frame's wall time is the whole frame. After a warm-up the variants are timed in
alternating blocks (the order rotates every round) until each has ``--frames``
samples. The ratio of ``mirrorlab`` to ``minimal`` is the median over the rounds of
the ratio of their block medians (:func:`mirrorlab.benchmarks.scale.paired_ratio`).
The last frames of ``mirrorlab`` and ``minimal`` are compared pixel by pixel to show
that both draw the same picture.
"""

from __future__ import annotations

import argparse
import gc
import json
import os
import platform
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from importlib.util import find_spec
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np
import OpenGL
from PIL import Image

from mirrorlab.benchmarks.scale import paired_ratio
from mirrorlab.gl.context import check_gl_errors, offscreen_context
from mirrorlab.gl.opengl import GL  # after mirrorlab.gl.context chose the platform
from mirrorlab.gl.resources import Framebuffer
from mirrorlab.renderer import SceneRenderer
from mirrorlab.scene.backgrounds import load_picture
from mirrorlab.scene.loader import load_scene
from mirrorlab.scene.mesh import TextureSource, load_mesh
from mirrorlab.scene.model import Camera, PlanarReflector, Scene
from mirrorlab.scene.robot import scene_parts

VERTEX_SHADER = """#version 330
layout(location = 0) in vec3 position;
layout(location = 1) in vec3 normal;
layout(location = 2) in vec2 uv;

uniform mat4 model;
uniform mat4 view_projection;
uniform mat3 normal_matrix;

out vec3 world_normal;
out vec2 surface_uv;

void main() {
    world_normal = normal_matrix * normal;
    surface_uv = uv;
    gl_Position = view_projection * model * vec4(position, 1.0);
}
"""

# Branch-free on purpose: an if/else version with a texture fetch in each branch made
# this yardstick's frames about 20% slower on llvmpipe (which shades pixels in SIMD
# batches with masked branches). Here: one fetch per fragment, then selects.
FRAGMENT_SHADER = """#version 330
in vec3 world_normal;
in vec2 surface_uv;

uniform int mode;            // 0: lit colour, 1: lit colour * texture, 2: mirror
uniform sampler2D image;     // the part's texture, or the capture for the mirror
uniform vec3 color;
uniform vec3 light_direction;
uniform float ambient;
uniform float diffuse;
uniform vec3 backing_color;

out vec4 frag_color;

void main() {
    vec3 texel = texture(image, surface_uv).rgb;
    float lambert = max(dot(normalize(world_normal), light_direction), 0.0);
    vec3 lit = (mode == 1 ? color * texel : color) * (ambient + diffuse * lambert);
    vec3 mirror = gl_FrontFacing ? texel : backing_color;
    frag_color = vec4(mode == 2 ? mirror : lit, 1.0);
}
"""

MODE_LIT, MODE_TEXTURED, MODE_MIRROR = 0, 1, 2
IDENTITY = np.eye(4, dtype=np.float32)


# --------------------------------------------------------------------------------------
# The minimal hand-written renderer (the yardstick)
# --------------------------------------------------------------------------------------


class Part(NamedTuple):
    """One draw of a scene part: its mesh's VAO and uniforms, ready to upload."""

    vao: int
    index_count: int
    model: np.ndarray  # (4, 4) float32, row-major
    normal_matrix: np.ndarray  # (3, 3) float32, row-major
    color: tuple[float, float, float]
    texture: int  # GL texture name, 0 for none


def compile_program(vertex: str, fragment: str) -> int:
    """Compile and link a program from GLSL sources; RuntimeError with the log on failure."""
    program = GL.glCreateProgram()
    for source, kind in ((vertex, GL.GL_VERTEX_SHADER), (fragment, GL.GL_FRAGMENT_SHADER)):
        shader = GL.glCreateShader(kind)
        GL.glShaderSource(shader, source)
        GL.glCompileShader(shader)
        if not GL.glGetShaderiv(shader, GL.GL_COMPILE_STATUS):
            raise RuntimeError(f"shader did not compile: {GL.glGetShaderInfoLog(shader)!r}")
        GL.glAttachShader(program, shader)
        GL.glDeleteShader(shader)  # freed once the program is deleted
    GL.glLinkProgram(program)
    if not GL.glGetProgramiv(program, GL.GL_LINK_STATUS):
        raise RuntimeError(f"program did not link: {GL.glGetProgramInfoLog(program)!r}")
    return int(program)


def upload_mesh(vertices: np.ndarray, indices: np.ndarray) -> tuple[int, list[int]]:
    """A VAO over an interleaved (x, y, z, nx, ny, nz, u, v) VBO and a uint32 EBO.

    Returns the VAO and its two buffer names."""
    vertices = np.ascontiguousarray(vertices, dtype=np.float32)
    indices = np.ascontiguousarray(indices, dtype=np.uint32)
    vao = int(GL.glGenVertexArrays(1))
    buffers = [int(b) for b in GL.glGenBuffers(2)]
    GL.glBindVertexArray(vao)
    GL.glBindBuffer(GL.GL_ARRAY_BUFFER, buffers[0])
    GL.glBufferData(GL.GL_ARRAY_BUFFER, vertices.nbytes, vertices, GL.GL_STATIC_DRAW)
    GL.glBindBuffer(GL.GL_ELEMENT_ARRAY_BUFFER, buffers[1])
    GL.glBufferData(GL.GL_ELEMENT_ARRAY_BUFFER, indices.nbytes, indices, GL.GL_STATIC_DRAW)
    for location, (size, offset) in enumerate(((3, 0), (3, 12), (2, 24))):
        GL.glEnableVertexAttribArray(location)
        GL.glVertexAttribPointer(location, size, GL.GL_FLOAT, GL.GL_FALSE, 32, GL.GLvoidp(offset))
    GL.glBindVertexArray(0)
    return vao, buffers


def make_texture(width: int, height: int, pixels: np.ndarray | None) -> int:
    """An RGB8 texture: mipmapped and repeating from ``pixels`` (row 0 at the bottom), or
    blank, level 0 only and clamped when ``pixels`` is None (the capture target)."""
    texture = int(GL.glGenTextures(1))
    GL.glBindTexture(GL.GL_TEXTURE_2D, texture)
    GL.glPixelStorei(GL.GL_UNPACK_ALIGNMENT, 1)
    GL.glTexImage2D(
        GL.GL_TEXTURE_2D, 0, GL.GL_RGB8, width, height, 0, GL.GL_RGB, GL.GL_UNSIGNED_BYTE, pixels
    )
    wrap = GL.GL_CLAMP_TO_EDGE if pixels is None else GL.GL_REPEAT
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_WRAP_S, wrap)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_WRAP_T, wrap)
    GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAG_FILTER, GL.GL_LINEAR)
    if pixels is None:
        GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MIN_FILTER, GL.GL_LINEAR)
        GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAX_LEVEL, 0)
    else:
        GL.glGenerateMipmap(GL.GL_TEXTURE_2D)
        GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MIN_FILTER, GL.GL_LINEAR_MIPMAP_LINEAR)
    return texture


class MinimalRenderer:
    """The lab's two passes in plain PyOpenGL, drawing the same triangles as mirrorlab."""

    UNIFORMS = (
        "model",
        "view_projection",
        "normal_matrix",
        "mode",
        "image",
        "color",
        "light_direction",
        "ambient",
        "diffuse",
        "backing_color",
    )

    def __init__(self, scene: Scene, width: int, height: int) -> None:
        self.scene = scene
        mirror = scene.reflector("mirror")
        assert isinstance(mirror, PlanarReflector), "the minimal renderer draws a flat mirror"
        self.mirror = mirror
        self.width, self.height = width, height
        self.draw_calls = 0  # glDrawElements calls in the last frame
        self.triangles = 0  # triangles submitted in the last frame

        self.program = compile_program(VERTEX_SHADER, FRAGMENT_SHADER)
        self.loc = {
            name: int(GL.glGetUniformLocation(self.program, name)) for name in self.UNIFORMS
        }
        missing = [name for name, loc in self.loc.items() if loc < 0]
        if missing:
            raise RuntimeError(f"minimal program lacks uniforms {missing}")

        self.fbo = int(GL.glGenFramebuffers(1))
        self.renderbuffers = [int(r) for r in GL.glGenRenderbuffers(2)]
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, self.fbo)
        for rb, fmt, attachment in zip(
            self.renderbuffers,
            (GL.GL_RGBA8, GL.GL_DEPTH24_STENCIL8),
            (GL.GL_COLOR_ATTACHMENT0, GL.GL_DEPTH_STENCIL_ATTACHMENT),
            strict=True,
        ):
            GL.glBindRenderbuffer(GL.GL_RENDERBUFFER, rb)
            GL.glRenderbufferStorage(GL.GL_RENDERBUFFER, fmt, width, height)
            GL.glFramebufferRenderbuffer(GL.GL_FRAMEBUFFER, attachment, GL.GL_RENDERBUFFER, rb)
        if GL.glCheckFramebufferStatus(GL.GL_FRAMEBUFFER) != GL.GL_FRAMEBUFFER_COMPLETE:
            raise RuntimeError("minimal framebuffer is incomplete")

        self.meshes: dict[Path, tuple[int, int]] = {}  # mesh file -> (vao, index count)
        self.textures: dict[TextureSource, int] = {}
        self.buffers: list[int] = []
        for part in scene_parts(scene):
            if part.mesh not in self.meshes:
                data = load_mesh(part.mesh)
                vao, buffers = upload_mesh(data.interleaved(), data.indices)
                self.meshes[part.mesh] = (vao, int(data.indices.size))
                self.buffers += buffers
            if part.texture and part.texture not in self.textures:
                assert isinstance(part.texture, Path), "the minimal renderer reads picture files"
                pixels = load_picture(part.texture)
                self.textures[part.texture] = make_texture(
                    pixels.shape[1], pixels.shape[0], np.ascontiguousarray(pixels[::-1])
                )
        self.environment = make_texture(width, height, None)

        mirror = self.mirror
        quad = np.hstack(
            [mirror.corner_array, np.broadcast_to(mirror.normal, (4, 3)), mirror.texcoords()]
        )
        self.quad_vao, buffers = upload_mesh(quad, np.array([0, 1, 2, 0, 2, 3]))
        self.buffers += buffers

        GL.glUseProgram(self.program)
        GL.glUniform1i(self.loc["image"], 0)
        GL.glUniform3f(self.loc["backing_color"], *self.mirror.backing)
        self.parts: list[Part] = []
        for part in scene_parts(scene):
            vao, count = self.meshes[part.mesh]
            self.parts.append(
                Part(
                    vao,
                    count,
                    part.model.astype(np.float32),
                    np.linalg.inv(part.model[:3, :3]).T.astype(np.float32),
                    part.color,
                    self.textures[part.texture] if part.texture else 0,
                )
            )

    def _draw_parts(self, view_projection: np.ndarray) -> None:
        loc = self.loc
        GL.glUniformMatrix4fv(
            loc["view_projection"], 1, GL.GL_TRUE, view_projection.astype(np.float32)
        )
        for part in self.parts:
            GL.glUniformMatrix4fv(loc["model"], 1, GL.GL_TRUE, part.model)
            GL.glUniformMatrix3fv(loc["normal_matrix"], 1, GL.GL_TRUE, part.normal_matrix)
            GL.glUniform3f(loc["color"], *part.color)
            GL.glUniform1i(loc["mode"], MODE_TEXTURED if part.texture else MODE_LIT)
            if part.texture:
                GL.glBindTexture(GL.GL_TEXTURE_2D, part.texture)
            GL.glBindVertexArray(part.vao)
            GL.glDrawElements(GL.GL_TRIANGLES, part.index_count, GL.GL_UNSIGNED_INT, None)
            self.draw_calls += 1
            self.triangles += part.index_count // 3

    def draw(self, camera: Camera) -> None:
        """Both passes into this renderer's framebuffer."""
        scene, loc = self.scene, self.loc
        self.draw_calls = self.triangles = 0
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, self.fbo)
        GL.glViewport(0, 0, self.width, self.height)
        GL.glEnable(GL.GL_DEPTH_TEST)
        GL.glEnable(GL.GL_CULL_FACE)
        GL.glClearColor(*scene.background.color, 1.0)
        GL.glActiveTexture(GL.GL_TEXTURE0)
        GL.glUseProgram(self.program)
        (light,) = scene.lights  # the lab has one white light
        direction = np.asarray(light.direction, dtype=np.float64)
        GL.glUniform3f(loc["light_direction"], *(direction / np.linalg.norm(direction)))
        GL.glUniform1f(loc["ambient"], scene.ambient)
        GL.glUniform1f(loc["diffuse"], light.intensity)

        # Pass 1: the mirror's orthographic view, copied into the environment texture.
        GL.glClear(GL.GL_COLOR_BUFFER_BIT | GL.GL_DEPTH_BUFFER_BIT)
        capture = self.mirror.ortho_capture
        self._draw_parts(capture.projection() @ capture.view())
        GL.glBindTexture(GL.GL_TEXTURE_2D, self.environment)
        GL.glCopyTexImage2D(GL.GL_TEXTURE_2D, 0, GL.GL_RGB, 0, 0, self.width, self.height, 0)

        # Pass 2: the viewer's perspective, the mirror quad showing the capture first (what
        # it hides is then not shaded, as mirrorlab draws it), then the parts.
        GL.glClear(GL.GL_COLOR_BUFFER_BIT | GL.GL_DEPTH_BUFFER_BIT)
        view_projection = camera.projection(self.width / self.height) @ camera.view()
        GL.glUniformMatrix4fv(
            loc["view_projection"], 1, GL.GL_TRUE, view_projection.astype(np.float32)
        )
        GL.glDisable(GL.GL_CULL_FACE)  # the mirror's back face shows its backing
        GL.glUniformMatrix4fv(loc["model"], 1, GL.GL_TRUE, IDENTITY)
        GL.glUniform1i(loc["mode"], MODE_MIRROR)
        GL.glBindTexture(GL.GL_TEXTURE_2D, self.environment)
        GL.glBindVertexArray(self.quad_vao)
        GL.glDrawElements(GL.GL_TRIANGLES, 6, GL.GL_UNSIGNED_INT, None)
        GL.glEnable(GL.GL_CULL_FACE)
        self.draw_calls += 1
        self.triangles += 2
        self._draw_parts(view_projection)

    def read(self) -> np.ndarray:
        """The frame as ``(height, width, 3)`` uint8, row 0 at the top."""
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, self.fbo)
        GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 1)
        data = GL.glReadPixels(0, 0, self.width, self.height, GL.GL_RGB, GL.GL_UNSIGNED_BYTE)
        pixels = np.frombuffer(data, dtype=np.uint8).reshape(self.height, self.width, 3)
        return pixels[::-1].copy()

    def release(self) -> None:
        GL.glDeleteProgram(self.program)
        GL.glDeleteVertexArrays(
            len(self.meshes) + 1, [vao for vao, _ in self.meshes.values()] + [self.quad_vao]
        )
        GL.glDeleteBuffers(len(self.buffers), self.buffers)
        GL.glDeleteTextures([*self.textures.values(), self.environment])
        GL.glDeleteRenderbuffers(2, self.renderbuffers)
        GL.glDeleteFramebuffers(1, [self.fbo])


# --------------------------------------------------------------------------------------
# Timing
# --------------------------------------------------------------------------------------


@dataclass
class Variant:
    """One timed way of producing a frame: ``draw`` issues it, ``read`` reads it back."""

    key: str
    label: str
    draw: Callable[[], object]  # what it returns is not used
    read: Callable[[], np.ndarray]
    last_frame: Callable[[], tuple[int, int]]  # checks the last frame: (draw calls, triangles)
    draw_calls: int = 0
    triangles: int = 0
    blocks: list[list[float]] = field(default_factory=list)  # frame ms, one list a round
    draw_ms: list[float] = field(default_factory=list)
    read_ms: list[float] = field(default_factory=list)
    image: np.ndarray | None = None

    @property
    def total_ms(self) -> list[float]:
        """Every timed frame's wall time in ms."""
        return [ms for block in self.blocks for ms in block]

    def frame(self, record: bool) -> float:
        """Run one frame; returns its wall time in ms (:func:`run_blocks` keeps it in
        :attr:`blocks`) and records its issue and readback times when ``record``."""
        start = time.perf_counter()
        self.draw()
        drawn = time.perf_counter()
        self.image = self.read()
        end = time.perf_counter()
        total = (end - start) * 1e3
        if record:
            self.draw_ms.append((drawn - start) * 1e3)
            self.read_ms.append((end - drawn) * 1e3)
        return total

    def summary(self) -> dict[str, Any]:
        total = np.asarray(self.total_ms)
        p10, median, p90 = np.percentile(total, [10, 50, 90])
        return {
            "label": self.label,
            "frames": len(total),
            "median_ms": float(median),
            "p10_ms": float(p10),
            "p90_ms": float(p90),
            "mean_ms": float(total.mean()),
            "min_ms": float(total.min()),
            "until_readback_median_ms": float(np.median(self.draw_ms)),
            "readback_median_ms": float(np.median(self.read_ms)),
            "triangles_per_frame": self.triangles,
            "draw_calls_per_frame": self.draw_calls,
            "samples_ms": [round(v, 4) for v in self.total_ms],
        }


def parse_size(text: str) -> tuple[int, int]:
    parts = text.lower().split("x")
    if len(parts) == 2 and all(p.isdigit() and 0 < int(p) <= 8192 for p in parts):
        return int(parts[0]), int(parts[1])
    raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT (1 to 8192 each), got {text!r}")


def positive_int(text: str) -> int:
    value = int(text)
    if value < 1:
        raise argparse.ArgumentTypeError(f"expected a positive integer, got {text!r}")
    return value


def non_negative_int(text: str) -> int:
    value = int(text)
    if value < 0:
        raise argparse.ArgumentTypeError(f"expected 0 or more, got {text!r}")
    return value


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        description="Time mirrorlab's two-pass frame against a minimal PyOpenGL version."
    )
    parser.add_argument(
        "--size", type=parse_size, default=(512, 512), help="frame WIDTHxHEIGHT (default 512x512)"
    )
    parser.add_argument(
        "--frames",
        type=positive_int,
        default=50,
        help="timed frames per variant (default %(default)s)",
    )
    parser.add_argument(
        "--warmup",
        type=non_negative_int,
        default=10,
        help="untimed frames per variant first (default %(default)s)",
    )
    parser.add_argument(
        "--block",
        type=positive_int,
        default=5,
        help="frames per variant before switching (default %(default)s)",
    )
    parser.add_argument("--json", type=Path, metavar="PATH", help="also write results as JSON")
    parser.add_argument(
        "--save-images",
        type=Path,
        metavar="DIR",
        help="write the last mirrorlab and minimal frames (and their "
        "difference, x8) as PNGs into DIR",
    )
    return parser


def log(message: str) -> None:
    print(f"[bench] {message}", file=sys.stderr, flush=True)


def expect(condition: bool, message: str) -> None:
    if not condition:
        raise RuntimeError(message)


def run_blocks(variants: list[Variant], frames: int, block: int) -> None:
    """Alternate blocks of ``block`` frames per variant, rotating the order each round."""
    rounds = -(-frames // block)
    for round_index in range(rounds):
        count = min(block, frames - round_index * block)
        shift = round_index % len(variants)
        parts = []
        for variant in variants[shift:] + variants[:shift]:
            gc.collect()
            times = [variant.frame(record=True) for _ in range(count)]
            variant.blocks.append(times)
            variant.draw_calls, variant.triangles = variant.last_frame()
            check_gl_errors(f"a block of {variant.key}")
            parts.append(f"{variant.key} {np.median(times):6.2f}")
        log(
            f"round {round_index + 1:>2}/{rounds}: {count} frames each, block median ms: "
            + ", ".join(parts)
        )


def write_json_atomic(path: Path, payload: dict[str, Any]) -> None:
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(handle, "w") as stream:
            json.dump(payload, stream, indent=2)
            stream.write("\n")
        os.replace(temp, path)
    except BaseException:
        Path(temp).unlink(missing_ok=True)
        raise


def save_images(directory: Path, mine: np.ndarray, minimal: np.ndarray) -> list[Path]:
    directory.mkdir(parents=True, exist_ok=True)
    diff = np.abs(mine.astype(np.int16) - minimal.astype(np.int16))
    amplified = np.clip(diff * 8, 0, 255).astype(np.uint8)
    paths = []
    for name, image in (("mirrorlab", mine), ("minimal", minimal), ("diff_x8", amplified)):
        path = directory / f"{name}.png"
        Image.fromarray(image).save(path)
        paths.append(path)
    return paths


def markdown_table(rows: list[dict[str, Any]]) -> str:
    header = (
        "| variant | median ms | p10 ms | p90 ms | until readback ms | readback ms "
        "| triangles | draw calls |"
    )
    lines = [header, "|---|---:|---:|---:|---:|---:|---:|---:|"]
    for row in rows:
        lines.append(
            f"| {row['label']} | {row['median_ms']:.2f} | {row['p10_ms']:.2f} "
            f"| {row['p90_ms']:.2f} | {row['until_readback_median_ms']:.2f} "
            f"| {row['readback_median_ms']:.2f} | {row['triangles_per_frame']} "
            f"| {row['draw_calls_per_frame']} |"
        )
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    width, height = args.size
    scene = load_scene("lab20")
    camera = scene.camera

    with offscreen_context() as context:
        info = context.info()
        framebuffer = Framebuffer(context.resources, width, height)
        renderer = SceneRenderer(context.resources)
        minimal = MinimalRenderer(scene, width, height)
        check_gl_errors("setting up both renderers")
        part_triangles = sum(int(minimal.meshes[part.mesh][1]) // 3 for part in scene_parts(scene))

        def mirrorlab_frame(expected: list[str]) -> Callable[[], tuple[int, int]]:
            """Checks that mirrorlab's last frame ran ``expected`` passes; the camera pass
            draws the mirror quad too."""

            def last_frame() -> tuple[int, int]:
                stats = renderer.last_frame
                if stats is None or stats.ran != expected:
                    raise RuntimeError(
                        f"mirrorlab ran passes {stats and stats.ran}, expected {expected}"
                    )
                return stats.draw_calls, part_triangles * len(expected) + 2

            return last_frame

        def forced() -> None:
            renderer.state.clear()  # the capture's texture counts as stale: capture again
            renderer.render(scene, framebuffer)

        full = Variant(
            "mirrorlab",
            "mirrorlab (capture + camera)",
            forced,
            framebuffer.read,
            mirrorlab_frame(["capture:mirror", "camera"]),
        )
        small = Variant(
            "minimal",
            "minimal PyOpenGL (capture + camera)",
            lambda: minimal.draw(camera),
            minimal.read,
            lambda: (minimal.draw_calls, minimal.triangles),
        )
        skipped = Variant(
            "skipped",
            "mirrorlab, capture skipped (camera only)",
            lambda: renderer.render(scene, framebuffer),
            framebuffer.read,
            mirrorlab_frame(["camera"]),
        )
        variants = [full, small, skipped]

        log(
            f"{info['renderer']}; {width}x{height}; warm-up {args.warmup} frames each, then "
            f"{args.frames} timed frames each in blocks of {args.block}"
        )
        for variant in variants:
            for _ in range(args.warmup):
                variant.frame(record=False)
        check_gl_errors("the warm-up")
        run_blocks(variants, args.frames, args.block)

        expect(
            full.triangles == small.triangles,
            f"unfair comparison: mirrorlab draws {full.triangles} triangles a frame, "
            f"minimal {small.triangles}",
        )
        assert full.image is not None and small.image is not None and skipped.image is not None
        diff = np.abs(full.image.astype(np.int16) - small.image.astype(np.int16))
        skipped_same = bool(np.array_equal(full.image, skipped.image))
        saved = save_images(args.save_images, full.image, small.image) if args.save_images else []
        minimal.release()

    rows = [variant.summary() for variant in variants]
    ratio = paired_ratio(full.blocks, small.blocks)
    saving = rows[0]["median_ms"] - rows[2]["median_ms"]
    cpus, usable = os.cpu_count(), len(os.sched_getaffinity(0))
    accelerate = find_spec("OpenGL_accelerate") is not None
    image_check = {
        "mean_abs_diff": float(diff.mean()),
        "max_abs_diff": int(diff.max()),
        "pixels_differing": int(np.any(diff > 0, axis=2).sum()),
        "pixels": width * height,
        "capture_skipped_frame_identical": skipped_same,
    }

    print(f"## mirrorlab frame benchmark, {width}x{height}\n")
    print(f"- GL: {info['renderer']} ({info['version']})")
    print(
        f"- CPUs: {cpus} ({usable} usable by this process); "
        f"LP_NUM_THREADS={os.environ.get('LP_NUM_THREADS', 'unset')}"
    )
    print(
        f"- Python {platform.python_version()}, PyOpenGL {OpenGL.__version__} "
        f"(ERROR_CHECKING={OpenGL.ERROR_CHECKING}, OpenGL_accelerate "
        f"{'installed' if accelerate else 'not installed'}), numpy {np.__version__}"
    )
    print(
        f"- {args.frames} timed frames per variant after {args.warmup} warm-up frames, "
        f"interleaved in blocks of {args.block}; every frame includes readback to numpy\n"
    )
    print(markdown_table(rows))
    print(
        "\n'until readback' is the time spent issuing the frame (render() or the minimal "
        "draw), 'readback' the\nread to numpy, which also waits for any rasterisation "
        "still pending.\n"
    )
    print(
        f"- mirrorlab / minimal (the median of the rounds' ratios of block medians): "
        f"**{ratio:.2f}x**"
    )
    print(
        f"- skipping the unchanged capture saves {saving:.2f} ms "
        f"({saving / rows[0]['median_ms']:.0%}) of mirrorlab's frame"
    )
    print(
        f"- image check, mirrorlab vs minimal: mean |diff| = {image_check['mean_abs_diff']:.4f}"
        f" per channel, max {image_check['max_abs_diff']}, "
        f"{image_check['pixels_differing']} of {image_check['pixels']} pixels differ; "
        f"capture-skipped frame identical to full frame: {'yes' if skipped_same else 'NO'}"
    )
    for path in saved:
        print(f"- wrote {path}")

    if args.json:
        write_json_atomic(
            args.json,
            {
                "size": [width, height],
                "frames": args.frames,
                "warmup": args.warmup,
                "block": args.block,
                "gl_renderer": info["renderer"],
                "gl_version": info["version"],
                "cpu_count": cpus,
                "cpus_usable": usable,
                "python": platform.python_version(),
                "pyopengl": OpenGL.__version__,
                "pyopengl_error_checking": bool(OpenGL.ERROR_CHECKING),
                "opengl_accelerate": accelerate,
                "variants": {variant.key: row for variant, row in zip(variants, rows, strict=True)},
                "ratio_mirrorlab_over_minimal": ratio,
                "capture_skip_saving_ms": saving,
                "image_check": image_check,
            },
        )
        print(f"- wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
