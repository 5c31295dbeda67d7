"""Scene graph: a tree of nodes with local transforms and cached world matrices.

Each node's local transform is ``offset @ rotate(angle, joint_axis)``: a fixed
placement in the parent's frame followed by an optional joint rotation. World
matrices are computed on demand and cached until an angle above them changes.
Matrices are ``(4, 4)`` float64 (see :mod:`mirrorlab.math3d`).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field

import numpy as np

from mirrorlab import math3d


@dataclass(eq=False)
class Node:
    """One part of the scene.

    ``mesh`` and ``texture`` name assets (``models/<mesh>.obj``,
    ``textures/<texture>.png``); ``color`` is linear RGB in [0, 1], multiplied
    with the texture when there is one. A node with no mesh only carries a
    transform for its children.
    """

    name: str
    offset: np.ndarray = field(default_factory=math3d.identity)
    joint_axis: tuple[float, float, float] | None = None
    mesh: str | None = None
    color: tuple[float, float, float] = (1.0, 1.0, 1.0)
    texture: str | None = None
    children: list[Node] = field(default_factory=list)
    parent: Node | None = field(default=None, repr=False)
    _angle: float = 0.0
    _world: np.ndarray | None = field(default=None, repr=False)

    @property
    def angle(self) -> float:
        """Joint angle in degrees (0 for a node without a joint)."""
        return self._angle

    def local_matrix(self) -> np.ndarray:
        """Transform from this node's frame to its parent's, ``(4, 4)``."""
        if self.joint_axis is None:
            return self.offset
        return self.offset @ math3d.rotate(self._angle, self.joint_axis)

    def world_matrix(self) -> np.ndarray:
        """Transform from this node's frame to the world, ``(4, 4)``; cached."""
        if self._world is None:
            local = self.local_matrix()
            self._world = local if self.parent is None else self.parent.world_matrix() @ local
        return self._world

    def add(self, child: Node) -> Node:
        """Attach ``child`` below this node and return it."""
        child.parent = self
        self.children.append(child)
        child._invalidate()
        return child

    def walk(self) -> Iterator[Node]:
        """This node and all below it, parents before children."""
        yield self
        for child in self.children:
            yield from child.walk()

    def _invalidate(self) -> None:
        for node in self.walk():
            node._world = None


class SceneGraph:
    """A node tree plus a revision counter that grows on every change.

    Passes compare revisions to know whether anything they drew has changed.
    """

    def __init__(self, root: Node) -> None:
        self.root = root
        self.revision = 0
        self._by_name: dict[str, Node] = {}
        for node in root.walk():
            if node.name in self._by_name:
                raise ValueError(f"duplicate scene node name {node.name!r}")
            self._by_name[node.name] = node

    def __getitem__(self, name: str) -> Node:
        try:
            return self._by_name[name]
        except KeyError:
            raise KeyError(
                f"no scene node named {name!r}; nodes are {sorted(self._by_name)}"
            ) from None

    def nodes(self) -> Iterator[Node]:
        """All nodes, parents before children."""
        return self.root.walk()

    def set_angle(self, name: str, angle_deg: float) -> None:
        """Set the joint angle (degrees) of node ``name`` and invalidate what hangs below it."""
        node = self[name]
        if node.joint_axis is None:
            raise ValueError(f"scene node {name!r} has no joint to rotate")
        angle = float(angle_deg)
        if not np.isfinite(angle):
            raise ValueError(f"joint angle for {name!r} must be finite, got {angle_deg!r}")
        if angle != node._angle:
            node._angle = angle
            node._invalidate()
            self.revision += 1
