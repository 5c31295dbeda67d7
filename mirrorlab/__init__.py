"""mirrorlab: the CS370 multipass mirror, and environment mapping, measured.

Importing this package loads neither OpenGL nor glfw; :func:`render` does,
when called.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from mirrorlab.scene.robot import DEFAULT_ANGLES, DEFAULT_CAMERA, DEFAULT_TARGET

__all__ = ["DEFAULT_ANGLES", "DEFAULT_CAMERA", "DEFAULT_TARGET", "render"]
__version__ = "0.1.0"


def render(
    size: Sequence[int] = (512, 512),
    angles: Sequence[float] = DEFAULT_ANGLES,
    camera: Sequence[float] = DEFAULT_CAMERA,
    target: Sequence[float] = DEFAULT_TARGET,
    method: str = "ortho",
    capture: str = "copy",
    environment_size: int | None = None,
) -> np.ndarray:
    """Render the lab scene headless and return the frame.

    Parameters
    ----------
    size : (width, height) in pixels.
    angles : base, lower-arm and upper-arm joint angles in degrees.
    camera, target : viewer position and the point it looks at, world units.
    method : ``"ortho"`` (the lab's capture), ``"reflected"``, ``"stencil"`` or
        ``"raytrace"`` (the ground truth, no GL).
    capture : ``"copy"`` (glCopyTexImage2D) or ``"fbo"`` (drawn into the texture).
    environment_size : side of the square environment texture in pixels; None
        makes it the frame's size.

    Returns
    -------
    ``(height, width, 3)`` uint8 RGB image, row 0 at the top.
    """
    from mirrorlab.headless import render_lab_frame

    return render_lab_frame(size, angles, camera, target, method, capture,
                            environment_size).image
