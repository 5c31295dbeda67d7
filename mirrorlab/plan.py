"""Which passes a frame needs, and why: simulate only the effects the scene calls for.

Pure numpy/python; the renderer runs what this decides.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mirrorlab.scene.robot import Camera, LabScene


@dataclass(frozen=True)
class PlannedPass:
    """One pass of a frame: ``name``, whether it runs, and the ``reason`` in words."""

    name: str
    runs: bool
    reason: str


@dataclass(frozen=True)
class CaptureState:
    """What the environment texture currently holds: the scene revision and the size
    it was captured at, or None for never captured."""

    revision: int | None = None
    size: tuple[int, int] | None = None


def mirror_faces_viewer(scene: LabScene, camera: Camera) -> bool:
    """True when the viewer is strictly on the reflecting side of the mirror's plane."""
    mirror = scene.mirror
    offset = np.asarray(camera.eye, dtype=np.float64) - mirror.center
    return bool(offset @ mirror.normal > 0.0)


def plan_frame(scene: LabScene, camera: Camera, size: tuple[int, int],
               captured: CaptureState, force_capture: bool = False) -> list[PlannedPass]:
    """The ordered passes for one frame of ``size`` (width, height) pixels.

    The orthographic capture does not depend on the viewer, so it is redone
    only when the scene or the frame size changed since ``captured``, and
    skipped while the viewer sees the mirror's back.
    """
    if force_capture:
        capture = PlannedPass("capture", True, "capture forced (e.g. for a benchmark)")
    elif not mirror_faces_viewer(scene, camera):
        capture = PlannedPass("capture", False, "viewer is behind the mirror's plane")
    elif captured.revision is None:
        capture = PlannedPass("capture", True, "environment texture is still blank")
    elif captured.size != tuple(size):
        capture = PlannedPass("capture", True, f"frame size changed to {size[0]}x{size[1]}")
    elif captured.revision != scene.graph.revision:
        capture = PlannedPass("capture", True, "the scene changed since the last capture")
    else:
        capture = PlannedPass("capture", False, "nothing changed since the last capture")
    camera_pass = PlannedPass("camera", True, "the frame itself")
    return [capture, camera_pass]
