"""The lab's robot arm as a scene graph: base (METAL texture) -> lower arm -> upper arm ->
hand, each joint a rotation; and the drawable parts of any scene's objects.

The hand sits off-centre, towards the upper arm's +z side, so the robot is not
mirror-symmetric and a flipped reflection shows. World units. Numpy only.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from mirrorlab import math3d
from mirrorlab.data import model_file, texture_file
from mirrorlab.math3d import read_only
from mirrorlab.scene.graph import Node, SceneGraph
from mirrorlab.scene.mesh import MeshTexture, TextureSource, mesh_material
from mirrorlab.scene.model import MeshObject, RobotObject, Scene, SceneObject

JOINT_NAMES = ("base", "lower_arm", "upper_arm")
"""Joint nodes in the order of an ``angles`` triple: base about y, the arms about their z."""

HAND_COLOR = (0.92, 0.08, 0.08)
LOWER_ARM_COLOR = (0.95, 0.62, 0.12)
UPPER_ARM_COLOR = (0.15, 0.42, 0.95)
JOINT_COLOR = (0.72, 0.73, 0.76)
HAND_OFFSET = (0.0, 3.2, 0.45)
"""Hand centre in the upper arm's frame: at its tip, pushed towards +z."""


def build_robot() -> Node:
    """The robot's node tree: world -> base -> lower arm -> upper arm -> hand. Meshes name
    ``models/<mesh>.obj``, textures ``textures/<texture>.png``."""
    world = Node("world")
    base = world.add(
        Node(
            "base",
            offset=math3d.translate((0, -2, 0)),
            joint_axis=(0, 1, 0),
            mesh="base",
            texture="metal",
        )
    )
    base.add(Node("shoulder", mesh="joint", color=JOINT_COLOR))
    lower = base.add(
        Node("lower_arm", joint_axis=(0, 0, 1), mesh="lower_arm", color=LOWER_ARM_COLOR)
    )
    lower.add(Node("elbow", offset=math3d.translate((0, 4, 0)), mesh="joint", color=JOINT_COLOR))
    upper = lower.add(
        Node(
            "upper_arm",
            offset=math3d.translate((0, 4, 0)),
            joint_axis=(0, 0, 1),
            mesh="upper_arm",
            color=UPPER_ARM_COLOR,
        )
    )
    upper.add(Node("hand", offset=math3d.translate(HAND_OFFSET), mesh="hand", color=HAND_COLOR))
    return world


def robot_graph(robot: RobotObject) -> SceneGraph:
    """The robot's graph posed at its angles, its root placed by its transform."""
    graph = SceneGraph(build_robot())
    graph.root.offset = robot.transform.matrix()
    for name, angle in zip(JOINT_NAMES, robot.angles, strict=True):
        graph.set_angle(name, angle)
    return graph


@dataclass(frozen=True, eq=False)
class Part:
    """One drawable mesh in world space: ``model`` ``(4, 4)`` mesh frame to world,
    ``color`` RGB albedo, ``texture`` where its picture comes from (a picture file, or a
    glTF mesh's own texture; see :func:`mirrorlab.scene.mesh.texture_picture`) or None.
    ``name`` is the object's name, with the robot's node after a dot (``robot.hand``)."""

    name: str
    mesh: Path
    model: np.ndarray
    color: tuple[float, float, float]
    texture: TextureSource | None


WHITE = (1.0, 1.0, 1.0)


def mesh_look(item: MeshObject) -> tuple[tuple[float, float, float], TextureSource | None]:
    """A mesh object's colour and texture: the scene's own where it gives them, else its
    glTF file's base colour factor and base colour texture, else white and none."""
    material = mesh_material(item.mesh)
    color = item.color if item.color is not None else (material.base_color or WHITE)
    texture: TextureSource | None = item.texture
    if texture is None and material.base_color_texture is not None:
        texture = MeshTexture(item.mesh)
    return color, texture


@dataclass(frozen=True, eq=False)
class PartLooks:
    """What one object's drawable parts are, whatever its pose: each part's ``names``,
    ``meshes``, ``colors`` and ``textures`` (see :class:`Part`), in drawing order. One
    object is kept for each look (:func:`object_looks`), compared and hashed by identity:
    every pose of an object shares it."""

    names: tuple[str, ...]
    meshes: tuple[Path, ...]
    colors: tuple[tuple[float, float, float], ...]
    textures: tuple[TextureSource | None, ...]

    def __len__(self) -> int:
        return len(self.names)

    def parts(self, models: np.ndarray) -> tuple[Part, ...]:
        """The parts placed by ``models`` ``(k, 4, 4)``, one a part."""
        return tuple(
            Part(name, mesh, model, color, texture)
            for name, mesh, color, texture, model in zip(
                self.names, self.meshes, self.colors, self.textures, models, strict=True
            )
        )


@lru_cache(maxsize=256)
def _looks(
    names: tuple[str, ...],
    meshes: tuple[Path, ...],
    colors: tuple[tuple[float, float, float], ...],
    textures: tuple[TextureSource | None, ...],
) -> PartLooks:
    return PartLooks(names, meshes, colors, textures)


def object_looks(item: SceneObject) -> PartLooks:
    """The :class:`PartLooks` of one object (the same object for equal looks)."""
    if isinstance(item, MeshObject):
        color, texture = mesh_look(item)
        return _looks((item.name,), (item.mesh,), (tuple(color),), (texture,))
    return robot_looks(item.name)


def object_models(item: SceneObject) -> np.ndarray:
    """Where one object's parts are: their models ``(k, 4, 4)`` (read-only), in the order of
    :func:`object_looks`."""
    if isinstance(item, MeshObject):
        return item.transform.matrix()[None]
    return robot_models(item)


@lru_cache(maxsize=256)
def object_parts(item: SceneObject) -> tuple[Part, ...]:
    """The drawable parts of one object (remembered: objects are values)."""
    return object_looks(item).parts(object_models(item))


@lru_cache(maxsize=1)
def _robot_nodes() -> tuple[tuple[Node, int, int], ...]:
    """The robot's nodes, parents first (the order of :meth:`SceneGraph.nodes`), each with
    its parent's position (-1: the root) and its joint's in an ``angles`` triple (-1:
    none). Only read: the nodes' offsets, axes and looks."""
    nodes = tuple(build_robot().walk())
    return tuple(
        (
            node,
            nodes.index(node.parent) if node.parent is not None else -1,
            JOINT_NAMES.index(node.name) if node.name in JOINT_NAMES else -1,
        )
        for node in nodes
    )


@lru_cache(maxsize=1)
def _unit_axes() -> tuple[tuple[float, float, float], ...]:
    """Each joint's unit axis, in the order of ``angles``, as :func:`math3d.rotate` makes
    it (the same division, so the same bits)."""
    axes = {node.name: node.joint_axis for node, _, _ in _robot_nodes()}
    units = []
    for name in JOINT_NAMES:
        axis = np.asarray(axes[name], dtype=np.float64)
        x, y, z = (float(v) for v in axis / np.linalg.norm(axis))
        units.append((x, y, z))
    return tuple(units)


def _joint_rotations(angles) -> np.ndarray:
    """The three joints' rotations ``(3, 4, 4)``: :func:`math3d.rotate` of each angle about
    its joint's axis, to the last bit (the same entries, :func:`math3d.rotation_entries`)."""
    entries: list[float] = []
    for angle, (x, y, z) in zip(angles, _unit_axes(), strict=True):
        (a, b, c), (d, e, f), (g, h, i) = math3d.rotation_entries(angle, x, y, z)
        entries += (a, b, c, 0.0, d, e, f, 0.0, g, h, i, 0.0, 0.0, 0.0, 0.0, 1.0)
    return np.array(entries).reshape(-1, 4, 4)


@lru_cache(maxsize=1)
def _robot_steps() -> tuple[tuple[tuple[int, int, np.ndarray], ...], list[int]]:
    """How each node below the robot's root is placed, parents first: (its parent's
    position, 0 for the root; its joint's in ``angles``, -1 for none; its offset); and
    the positions, among those nodes, of the ones with a mesh."""
    nodes = _robot_nodes()
    steps = tuple((parent, joint, node.offset) for node, parent, joint in nodes[1:])
    return steps, [i for i, (node, _, _) in enumerate(nodes[1:]) if node.mesh]


@lru_cache(maxsize=256)
def robot_looks(name: str) -> PartLooks:
    """The looks of the parts of a robot called ``name``."""
    drawn = [(node, node.mesh) for node, _, _ in _robot_nodes() if node.mesh]
    return PartLooks(
        tuple(f"{name}.{node.name}" for node, _ in drawn),
        tuple(model_file(mesh) for _, mesh in drawn),
        tuple(node.color for node, _ in drawn),
        tuple(texture_file(node.texture) if node.texture else None for node, _ in drawn),
    )


def robot_models(robot: RobotObject) -> np.ndarray:
    """The models ``(k, 4, 4)`` (read-only) of the robot's drawable parts posed at its
    angles: those of :func:`robot_graph`'s nodes to the last bit (the same products in
    the same order), without building a graph."""
    for name, angle in zip(JOINT_NAMES, robot.angles, strict=True):
        if not math.isfinite(angle):
            raise ValueError(f"joint angle for {name!r} must be finite, got {angle!r}")
    rotations = _joint_rotations(robot.angles)
    steps, drawn = _robot_steps()
    worlds = np.empty((len(steps), 4, 4))  # of the nodes below the root
    root = robot.transform.matrix()
    for node, (parent, joint, offset) in enumerate(steps):
        np.matmul(
            root if parent == 0 else worlds[parent - 1],
            offset if joint < 0 else offset @ rotations[joint],
            out=worlds[node],
        )
    return read_only(worlds if len(drawn) == len(steps) else worlds[drawn])


def robot_parts(robot: RobotObject) -> tuple[Part, ...]:
    """The robot's drawable parts posed at its angles (:func:`robot_models`)."""
    return robot_looks(robot.name).parts(robot_models(robot))


def scene_parts(scene: Scene) -> tuple[Part, ...]:
    """Every drawable part of the scene's objects (never its reflectors)."""
    return tuple(part for item in scene.objects for part in object_parts(item))


def hand_center(robot: RobotObject) -> np.ndarray:
    """World position ``(3,)`` of the robot's hand centre (the off-centre red marker)."""
    return robot_graph(robot)["hand"].world_matrix()[:3, 3].copy()
