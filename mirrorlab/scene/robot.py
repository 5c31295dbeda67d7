"""The lab scene: a three-joint robot arm on a METAL base, a rectangular mirror,
the mirror's orthographic capture camera and a default viewer.

World units: the mirror is the 8 x 8 square in the plane x = -7, facing +x;
the robot stands at the origin. The capture numbers are the lab's exactly.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from mirrorlab import math3d
from mirrorlab.scene.graph import Node, SceneGraph

JOINT_NAMES = ("base", "lower_arm", "upper_arm")
"""Joint nodes in the order of an ``angles`` triple: base about y, the arms about their z."""

DEFAULT_ANGLES = (-35.0, 30.0, -75.0)
DEFAULT_CAMERA = (12.0, 5.0, 9.0)
DEFAULT_TARGET = (-3.5, 1.0, -2.0)

# Part colours (linear RGB). The hand sits off-centre, towards the upper arm's
# +z side, so the robot is not mirror-symmetric and a flipped reflection shows.
HAND_COLOR = (0.92, 0.08, 0.08)
LOWER_ARM_COLOR = (0.95, 0.62, 0.12)
UPPER_ARM_COLOR = (0.15, 0.42, 0.95)
JOINT_COLOR = (0.72, 0.73, 0.76)
FRAME_COLOR = (0.35, 0.27, 0.2)
MIRROR_BACKING = (0.33, 0.3, 0.27)
"""Colour of the mirror's back (unlit), seen from behind its plane."""
HAND_OFFSET = (0.0, 3.2, 0.45)
"""Hand centre in the upper arm's frame: at its tip, pushed towards +z."""


@dataclass(frozen=True)
class Mirror:
    """A planar rectangular mirror.

    ``corners`` ``(4, 3)`` world positions, counter-clockwise seen from the
    reflecting side; ``texcoords`` ``(4, 2)`` the environment-texture
    coordinate at each corner.
    """

    corners: np.ndarray
    texcoords: np.ndarray

    @property
    def normal(self) -> np.ndarray:
        """Unit normal ``(3,)`` on the reflecting side."""
        c = self.corners
        n = np.cross(c[1] - c[0], c[2] - c[0])
        return n / np.linalg.norm(n)

    @property
    def center(self) -> np.ndarray:
        return self.corners.mean(axis=0)

    def texcoord_at(self, points: np.ndarray) -> np.ndarray:
        """Interpolated texture coordinates ``(..., 2)`` at points ``(..., 3)`` on the mirror.

        The quad is a parallelogram (corner 0, edges to corners 1 and 3), so
        bilinear interpolation of the corner coordinates is affine in the point.
        """
        c, tc = self.corners, self.texcoords
        edge_a, edge_b = c[3] - c[0], c[1] - c[0]
        rel = np.asarray(points, dtype=np.float64) - c[0]
        a = rel @ edge_a / (edge_a @ edge_a)
        b = rel @ edge_b / (edge_b @ edge_b)
        return tc[0] + a[..., None] * (tc[3] - tc[0]) + b[..., None] * (tc[1] - tc[0])


@dataclass(frozen=True)
class OrthoCapture:
    """The mirror's orthographic capture camera (the lab's pass 1)."""

    extents: tuple[float, float, float, float, float, float] = (-6.0, 2.0, -3.0, 5.0, 0.0, 15.0)
    eye: tuple[float, float, float] = (-7.0, 0.0, 0.0)
    target: tuple[float, float, float] = (0.0, 0.0, 0.0)
    up: tuple[float, float, float] = (0.0, 1.0, 0.0)

    def view(self) -> np.ndarray:
        return math3d.look_at(self.eye, self.target, self.up)

    def projection(self) -> np.ndarray:
        return math3d.ortho(*self.extents)


@dataclass(frozen=True)
class Camera:
    """A perspective viewer. ``fovy`` is the vertical field of view in degrees."""

    eye: tuple[float, float, float] = DEFAULT_CAMERA
    target: tuple[float, float, float] = DEFAULT_TARGET
    up: tuple[float, float, float] = (0.0, 1.0, 0.0)
    fovy: float = 45.0
    near: float = 0.1
    far: float = 100.0

    def view(self) -> np.ndarray:
        return math3d.look_at(self.eye, self.target, self.up)

    def projection(self, aspect: float) -> np.ndarray:
        return math3d.perspective(self.fovy, aspect, self.near, self.far)


def lab_mirror() -> Mirror:
    """The lab's mirror quad with texture coordinates matching the capture.

    s follows world z from -6 to 2 and t follows world y from -3 to 5, which
    is where the capture camera's ortho extents put them.
    """
    corners = np.array(
        [(-7.0, -3.0, -6.0), (-7.0, 5.0, -6.0), (-7.0, 5.0, 2.0), (-7.0, -3.0, 2.0)]
    )
    texcoords = np.array([(0.0, 0.0), (0.0, 1.0), (1.0, 1.0), (1.0, 0.0)])
    return Mirror(corners=corners, texcoords=texcoords)


def build_robot() -> Node:
    """The robot's node tree: world -> base -> lower arm -> upper arm -> hand."""
    world = Node("world")
    base = world.add(
        Node("base", offset=math3d.translate((0, -2, 0)), joint_axis=(0, 1, 0),
             mesh="base", texture="metal")
    )
    base.add(Node("shoulder", mesh="joint", color=JOINT_COLOR))
    lower = base.add(Node("lower_arm", joint_axis=(0, 0, 1), mesh="lower_arm",
                          color=LOWER_ARM_COLOR))
    lower.add(Node("elbow", offset=math3d.translate((0, 4, 0)), mesh="joint",
                   color=JOINT_COLOR))
    upper = lower.add(Node("upper_arm", offset=math3d.translate((0, 4, 0)),
                           joint_axis=(0, 0, 1), mesh="upper_arm", color=UPPER_ARM_COLOR))
    upper.add(Node("hand", offset=math3d.translate(HAND_OFFSET), mesh="hand",
                   color=HAND_COLOR))
    return world


def build_world() -> Node:
    """The robot plus the mirror's frame: a dark slab just behind the mirror plane,
    0.3 wider on every side, so the mirror's edge shows. It lies behind the capture
    camera, so it never appears in the capture."""
    world = build_robot()
    world.add(Node("mirror_frame", offset=math3d.translate((-7.175, -3.3, -2.0)),
                   mesh="mirror_frame", color=FRAME_COLOR))
    return world


@dataclass
class LabScene:
    """Everything the lab renders: robot graph, mirror, capture camera, light.

    ``light_direction`` ``(3,)`` points from the scene towards a directional
    light; ``ambient`` and ``diffuse`` are its weights; colours are RGB in [0, 1].
    """

    graph: SceneGraph
    mirror: Mirror = field(default_factory=lab_mirror)
    capture: OrthoCapture = field(default_factory=OrthoCapture)
    light_direction: tuple[float, float, float] = (0.45, 0.8, 0.4)
    ambient: float = 0.3
    diffuse: float = 0.7
    background: tuple[float, float, float] = (0.16, 0.18, 0.22)
    mirror_backing: tuple[float, float, float] = MIRROR_BACKING

    @property
    def angles(self) -> tuple[float, float, float]:
        a, b, c = (self.graph[name].angle for name in JOINT_NAMES)
        return (a, b, c)

    def set_angles(self, angles: Sequence[float]) -> None:
        """Set the base, lower-arm and upper-arm joint angles in degrees."""
        if len(angles) != len(JOINT_NAMES):
            raise ValueError(
                f"angles must be {len(JOINT_NAMES)} numbers (base, lower, upper), got {angles!r}"
            )
        for name, angle in zip(JOINT_NAMES, angles, strict=True):
            self.graph.set_angle(name, angle)

    def hand_center(self) -> np.ndarray:
        """World position ``(3,)`` of the hand's centre (the off-centre red marker)."""
        return self.graph["hand"].world_matrix()[:3, 3].copy()


def build_lab_scene(angles: Sequence[float] = DEFAULT_ANGLES) -> LabScene:
    """The lab scene with the robot posed at ``angles`` (degrees)."""
    scene = LabScene(graph=SceneGraph(build_world()))
    scene.set_angles(angles)
    return scene
