"""One-shot headless rendering of the lab scene: context, renderer, frame, readback."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mirrorlab.scene.robot import (
    DEFAULT_ANGLES,
    DEFAULT_CAMERA,
    DEFAULT_TARGET,
    Camera,
    build_lab_scene,
)


@dataclass(frozen=True)
class HeadlessFrame:
    """``image`` ``(h, w, 3)`` uint8 final frame; ``environment`` ``(h, w, 3)`` uint8
    capture; both with row 0 at the top. ``passes`` names the passes that ran."""

    image: np.ndarray
    environment: np.ndarray
    passes: list[str]
    gl_renderer: str


def check_size(size: Sequence[int]) -> tuple[int, int]:
    """Validate a (width, height) pair of positive ints; ValueError naming the value."""
    if len(size) != 2:
        raise ValueError(f"size must be (width, height), got {size!r}")
    width, height = (int(v) for v in size)
    if width < 1 or height < 1 or width != size[0] or height != size[1]:
        raise ValueError(f"size must be two positive whole numbers, got {tuple(size)!r}")
    return width, height


def render_lab_frame(
    size: Sequence[int] = (512, 512),
    angles: Sequence[float] = DEFAULT_ANGLES,
    camera: Sequence[float] = DEFAULT_CAMERA,
    target: Sequence[float] = DEFAULT_TARGET,
) -> HeadlessFrame:
    """Render the lab scene once, headless (EGL), and read back frame and capture."""
    from mirrorlab.gl.context import HeadlessContext, check_gl_errors
    from mirrorlab.gl.resources import Framebuffer
    from mirrorlab.renderer import Renderer

    width, height = check_size(size)
    scene = build_lab_scene(angles)
    viewer = Camera(eye=tuple(float(v) for v in camera), target=tuple(float(v) for v in target))
    viewer.view()  # raises ValueError for a degenerate camera before any GL work
    with HeadlessContext() as context:
        framebuffer = Framebuffer(context.resources, width, height)
        renderer = Renderer(context.resources, scene)
        stats = renderer.render(framebuffer, viewer)
        image = framebuffer.read()
        environment = renderer.read_environment()
        check_gl_errors("rendering the lab scene")
        return HeadlessFrame(image, environment, stats.ran, context.info()["renderer"])
