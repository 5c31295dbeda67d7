"""Lab 20's object in the sandbox (``kit.lab20()``): the robot's scene graph the student
textures, and the calls that reach the checker's drawing. Student side: imports only the
standard library and :mod:`mirrorlab.labs.student`."""

from __future__ import annotations

from typing import Any

from mirrorlab.labs.student.kit_standin import StudentLab
from mirrorlab.labs.student.remote import LabSetupError, Remote


class Node:
    """One node of the robot's scene graph: its ``name`` and the GL ``texture`` it wears
    (None for none)."""

    def __init__(self, name: str) -> None:
        self.name = name
        self.texture: Any = None

    def __repr__(self) -> str:
        return f"Node({self.name!r}, texture={self.texture!r})"


class RobotGraph:
    """The robot's scene graph: ``robot["base"]`` is its base node."""

    def __init__(self, names: list[str]) -> None:
        self._nodes = {name: Node(name) for name in names}

    def __getitem__(self, name: str) -> Node:
        if name not in self._nodes:
            raise KeyError(
                f"the robot has no node {name!r}; its nodes are {', '.join(self._nodes)}"
            )
        return self._nodes[name]

    def nodes(self):
        return iter(self._nodes.values())

    def textures(self) -> dict[str, Any]:
        return {name: _texture(node.texture) for name, node in self._nodes.items()}


def _texture(value: Any) -> Any:
    if value is None:
        return None
    if isinstance(value, bool):
        return {"other": repr(value)}
    try:
        return int(value.__index__())
    except (AttributeError, TypeError, ValueError):
        return {"other": repr(value)[:40]}


class Lab20(StudentLab):
    """Lab 20: the robot, the mirror's frame, the viewer, and ``textureShader`` (sampler
    uniform ``texSampler``) for the mirror quad."""

    def __init__(self, remote: Remote, values: dict[str, Any]) -> None:
        self._node_names = list(values.pop("robot_nodes"))
        super().__init__(remote, values)
        self.robot: RobotGraph | None = None

    def robot_graph(self) -> RobotGraph:
        """The robot's scene graph at the lab's pose, no node textured yet."""
        self.robot = RobotGraph(self._node_names)
        return self.robot

    def draw_scene(self, robot: RobotGraph | None = None) -> None:
        """The robot (with its nodes' textures) and the mirror's frame, lit, under the
        current projection and modelview matrices. Never the mirror."""
        robot = robot if robot is not None else self.robot
        if robot is None:
            raise LabSetupError(
                "draw_scene: there is no scene graph yet; "
                "build_scene_graph() makes it with lab.robot_graph()"
            )
        if not isinstance(robot, RobotGraph):
            raise LabSetupError(
                f"draw_scene: expected the graph lab.robot_graph() made, got {type(robot).__name__}"
            )
        self._call("draw_scene", ["j"], {"textures": robot.textures()})

    def set_viewer(self) -> None:
        """The viewer's projection and camera (the matrices of the camera pass)."""
        self._call("set_viewer", [])


LAB_OBJECT = Lab20
