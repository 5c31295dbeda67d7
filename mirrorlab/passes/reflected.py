"""The reflected-camera capture: each frame, the scene seen by the viewer's mirror image,
with an oblique near plane on the mirror, into the ENVIRONMENT texture. The camera pass
then samples it through the same camera (projective texture coordinates)."""

from __future__ import annotations

import numpy as np

from mirrorlab import math3d
from mirrorlab.gl.resources import RenderTarget
from mirrorlab.passes.capture import EnvironmentCapture, clear_to_background
from mirrorlab.passes.scene_draw import SceneDrawer
from mirrorlab.scene.robot import Camera, LabScene, Mirror

# Clip space [-1, 1] to texture space [0, 1].
_BIAS = np.array([[0.5, 0, 0, 0.5], [0, 0.5, 0, 0.5], [0, 0, 0.5, 0.5], [0, 0, 0, 1.0]])


def mirror_plane(mirror: Mirror) -> np.ndarray:
    """The mirror's plane ``(4,)``, positive on its reflecting side."""
    return math3d.plane_through(mirror.center, mirror.normal)


def reflected_view(camera: Camera, plane: np.ndarray) -> np.ndarray:
    """``(4, 4)`` view matrix of ``camera`` reflected in ``plane``.

    Eye, target and up are reflected and a look-at view is built from them,
    so the matrix stays a proper rotation (determinant +1) and triangles keep
    their winding; the picture comes out left-right flipped, which the
    projective lookup undoes.
    """
    reflect = math3d.reflection_matrix(plane)
    eye = math3d.transform_points(reflect, np.asarray(camera.eye, dtype=np.float64))[:3]
    target = math3d.transform_points(reflect, np.asarray(camera.target, dtype=np.float64))[:3]
    up = reflect[:3, :3] @ np.asarray(camera.up, dtype=np.float64)
    return math3d.look_at(eye, target, up)


def reflected_view_projection(camera: Camera, mirror: Mirror, aspect: float) -> np.ndarray:
    """``(4, 4)`` projection @ view of the reflected camera, its near plane on the mirror.

    Lengyel's oblique projection clips everything on the mirror's back side,
    which the reflected eye would otherwise see in front of the glass.
    """
    plane = mirror_plane(mirror)
    view = reflected_view(camera, plane)
    plane_in_eye = plane @ np.linalg.inv(view)
    return math3d.oblique_projection(camera.projection(aspect), plane_in_eye) @ view


class ReflectedCapturePass:
    """Renders the scene from the reflected camera into the environment texture and keeps
    the ``(4, 4)`` matrix that maps a world point on the mirror to its texture coordinate
    (homogeneous: divide s and t by the fourth component)."""

    name = "reflected-capture"

    def __init__(self, scene: LabScene, drawer: SceneDrawer,
                 capture: EnvironmentCapture) -> None:
        self.scene = scene
        self.drawer = drawer
        self.capture = capture
        self.texture_matrix = np.eye(4)

    def run(self, frame_target: RenderTarget, camera: Camera) -> int:
        """Returns the number of draw calls. The capture uses the frame's aspect ratio
        whatever the texture's size, so texels stretch rather than the view."""
        scene = self.scene
        width, height = frame_target.size
        view_projection = reflected_view_projection(camera, scene.mirror, width / height)
        target = self.capture.begin(frame_target)
        clear_to_background(scene.background)
        draws = self.drawer.draw(view_projection)
        self.capture.finish(target)
        self.texture_matrix = _BIAS @ view_projection
        return draws
