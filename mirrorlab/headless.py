"""One-shot headless rendering of the lab scene: context, renderer, frame, readback."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mirrorlab.plan import CAPTURE_MODES
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


RENDER_METHODS = ("ortho", "reflected", "stencil", "raytrace")
"""What :func:`render_lab_frame` can draw with: the rasterised techniques and the ground truth."""


def render_lab_frame(
    size: Sequence[int] = (512, 512),
    angles: Sequence[float] = DEFAULT_ANGLES,
    camera: Sequence[float] = DEFAULT_CAMERA,
    target: Sequence[float] = DEFAULT_TARGET,
    method: str = "ortho",
    capture: str = "copy",
    environment_size: int | None = None,
) -> HeadlessFrame:
    """Render the lab scene once, headless (EGL), and read back frame and capture.

    ``method`` is one of :data:`RENDER_METHODS`; ``capture`` ("copy" or "fbo")
    and ``environment_size`` (square texture side in pixels, None = frame
    size) apply to the capturing methods. ``raytrace`` needs no GL context;
    its ``environment`` is an empty ``(0, 0, 3)`` array, as is stencil's.
    """
    if method not in RENDER_METHODS:
        raise ValueError(f"method must be one of {', '.join(RENDER_METHODS)}, got {method!r}")
    if capture not in CAPTURE_MODES:
        raise ValueError(f"capture must be {' or '.join(CAPTURE_MODES)}, got {capture!r}")
    width, height = check_size(size)
    env_size = None
    if environment_size is not None:
        env_size = check_size((environment_size, environment_size))
    scene = build_lab_scene(angles)
    viewer = Camera(eye=tuple(float(v) for v in camera), target=tuple(float(v) for v in target))
    viewer.view()  # raises ValueError for a degenerate camera before any GL work
    nothing = np.zeros((0, 0, 3), dtype=np.uint8)
    if method == "raytrace":
        from mirrorlab.raytrace import lab_ray_scene

        traced = lab_ray_scene(scene).render(viewer.view(), viewer.projection(width / height),
                                              (width, height))
        return HeadlessFrame(traced.to_uint8(), nothing, ["raytrace"], "mirrorlab.raytrace")

    from mirrorlab.gl.context import HeadlessContext, check_gl_errors
    from mirrorlab.gl.resources import Framebuffer
    from mirrorlab.renderer import Renderer

    with HeadlessContext() as context:
        framebuffer = Framebuffer(context.resources, width, height)
        renderer = Renderer(context.resources, scene, method, capture, env_size)
        stats = renderer.render(framebuffer, viewer)
        image = framebuffer.read()
        environment = renderer.read_environment() if method != "stencil" else nothing
        check_gl_errors("rendering the lab scene")
        return HeadlessFrame(image, environment, stats.ran, context.info()["renderer"])
