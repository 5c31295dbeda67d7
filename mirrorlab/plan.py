"""Which passes a frame needs, and why: simulate only the effects the scene calls for.

Pure numpy/python; the renderer runs what this decides.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mirrorlab import math3d
from mirrorlab.scene.robot import Camera, LabScene

METHODS = ("ortho", "reflected", "stencil")
"""The rasterised mirror techniques: the lab's fixed orthographic capture, a per-frame
reflected-camera capture sampled projectively, and a stencil-masked reflected redraw."""


CAPTURE_MODES = ("copy", "fbo")
"""How a capture reaches its texture: ``glCopyTexImage2D`` (the lab) or drawn straight
into it through a framebuffer."""


@dataclass(frozen=True)
class PlannedPass:
    """One pass of a frame: ``name``, whether it runs, and the ``reason`` in words."""

    name: str
    runs: bool
    reason: str


@dataclass(frozen=True)
class CaptureState:
    """What the environment texture currently holds: the scene revision, the size it was
    captured at and, for a viewer-dependent capture, the viewer; None for never captured."""

    revision: int | None = None
    size: tuple[int, int] | None = None
    viewer: Camera | None = None


def check_method(method: str) -> str:
    """``method`` if it names a technique in :data:`METHODS`, else ValueError listing them."""
    if method not in METHODS:
        raise ValueError(f"method must be one of {', '.join(METHODS)}, got {method!r}")
    return method


def mirror_faces_viewer(scene: LabScene, camera: Camera) -> bool:
    """True when the viewer is strictly on the reflecting side of the mirror's plane."""
    mirror = scene.mirror
    offset = np.asarray(camera.eye, dtype=np.float64) - mirror.center
    return bool(offset @ mirror.normal > 0.0)


def mirror_in_view(scene: LabScene, camera: Camera, aspect: float) -> bool:
    """False when all four mirror corners lie outside one and the same side of the
    viewer's view volume (so no part of the mirror can be on screen); conservative."""
    clip = math3d.transform_points(camera.projection(aspect) @ camera.view(),
                                   scene.mirror.corners)
    x, y, z, w = clip[:, 0], clip[:, 1], clip[:, 2], clip[:, 3]
    outside = (x < -w, x > w, y < -w, y > w, z < -w, z > w)
    return not any(bool(np.all(side)) for side in outside)


def _reflection_skip(scene: LabScene, camera: Camera, size: tuple[int, int]) -> str | None:
    if not mirror_faces_viewer(scene, camera):
        return "viewer is behind or in the mirror's plane"
    if not mirror_in_view(scene, camera, size[0] / size[1]):
        return "the mirror is out of view"
    return None


def plan_frame(scene: LabScene, camera: Camera, size: tuple[int, int],
               captured: CaptureState, force_capture: bool = False,
               method: str = "ortho") -> list[PlannedPass]:
    """The ordered passes for one frame of ``size`` (width, height) pixels.

    - ``ortho``: the capture does not depend on the viewer, so it is redone
      only when the scene or the frame size changed since ``captured``, and
      skipped while the mirror is out of view or seen from behind.
    - ``reflected``: the capture follows the viewer; it is redone when the
      viewer, the scene or the size changed, with the same skips.
    - ``stencil``: no capture; the reflection pass runs when the mirror's
      front can be seen.
    """
    check_method(method)
    skip = _reflection_skip(scene, camera, size)
    camera_pass = PlannedPass("camera", True, "the frame itself")
    if method == "stencil":
        reflection = (PlannedPass("stencil-reflection", False, skip) if skip else
                      PlannedPass("stencil-reflection", True, "the mirror's front is in view"))
        return [camera_pass, reflection]
    name = "capture" if method == "ortho" else "reflected-capture"
    if force_capture:
        return [PlannedPass(name, True, "capture forced (e.g. for a benchmark)"), camera_pass]
    if skip:
        return [PlannedPass(name, False, skip), camera_pass]
    if captured.revision is None:
        capture = PlannedPass(name, True, "environment texture is still blank")
    elif captured.size != tuple(size):
        capture = PlannedPass(name, True, f"frame size changed to {size[0]}x{size[1]}")
    elif captured.revision != scene.graph.revision:
        capture = PlannedPass(name, True, "the scene changed since the last capture")
    elif method == "reflected" and captured.viewer != camera:
        capture = PlannedPass(name, True, "the viewer moved since the last capture")
    else:
        capture = PlannedPass(name, False, "nothing changed since the last capture")
    return [capture, camera_pass]
