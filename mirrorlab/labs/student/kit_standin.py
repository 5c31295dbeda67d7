"""The stand-in for ``mirrorlab.labs.kit`` in the sandbox: ``kit.lab20()`` and the others
return the lab's object, whose drawing calls (the robot, the cone, the sphere) the
checker runs in its own context. The object holds the numbers a student may read (the
frame's size, the texture shader's name); the lab's answers are not among them."""

from __future__ import annotations

from types import ModuleType
from typing import Any

from .remote import LabSetupError, Remote, StudentShaderError, _number


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


class _Lab:
    def __init__(self, remote: Remote, values: dict[str, Any]) -> None:
        self._remote = remote
        for key, value in values.items():
            setattr(self, key, tuple(value) if isinstance(value, list) else value)

    def _call(self, name: str, kinds: list[str], *args: Any) -> Any:
        return self._remote.call("kit", name, kinds, args)

    def load_picture_texture(self, texture_id: int, name: str) -> None:
        """Fill texture ``texture_id`` with the lab's picture ``name`` (mipmapped,
        repeating), on texture unit 0."""
        self._call("load_picture_texture", ["i", "s"], texture_id, name)


class Lab20(_Lab):
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


class SphereMapLab(_Lab):
    """The cone in front of the launch picture, drawn by your shader functions or by
    fixed-function texgen."""

    def set_viewer(self, aspect: float | None = None) -> None:
        """The viewer's projection (for ``aspect``, default the frame's) and camera."""
        self._call(
            "set_viewer",
            ["j"],
            None if aspect is None else _number(aspect, "f", "lab.set_viewer(aspect)"),
        )

    def draw_backdrop(self) -> None:
        """The launch picture on its board behind the cone."""
        self._call("draw_backdrop", [])

    def draw_cone_shader(self, glsl: str, texture: int) -> None:
        """The cone drawn by the lab's shader calling your ``reflect_eye`` and
        ``sphere_map_st`` (from ``glsl``), sampling ``texture`` on unit 1."""
        self._call("draw_cone_shader", ["s", "i"], glsl, texture)

    def draw_cone_fixed_function(self) -> None:
        """The cone with no shader, its texture coordinates made by texgen, textured by
        the picture bound on the lab's texgen unit."""
        self._call("draw_cone_fixed_function", [])


class CubeMapLab(_Lab):
    """A chrome sphere among coloured objects, drawn through your face selection from the
    cube map you capture."""

    def set_viewer(self) -> None:
        """The viewer's projection and camera."""
        self._call("set_viewer", [])

    def draw_scene(self) -> None:
        """The pedestal, the objects and the picture behind them. Never the sphere."""
        self._call("draw_scene", [])

    def draw_sphere(self, glsl: str, cube_texture: int) -> None:
        """The chrome sphere, drawn by the lab's shader calling your ``cube_face`` and
        ``cube_face_st`` (from ``glsl``), sampling ``cube_texture`` on unit 1."""
        self._call("draw_sphere", ["s", "i"], glsl, cube_texture)


LAB_CLASSES = {"lab20": Lab20, "spheremap": SphereMapLab, "cubemap": CubeMapLab}


def build_kit(remote: Remote, description: dict) -> ModuleType:
    """The ``mirrorlab.labs.kit`` module of this run: its lab object made once."""
    lab = description["lab"]
    session = LAB_CLASSES[lab](remote, dict(description["kit"]))
    module = ModuleType("mirrorlab.labs.kit")

    def opener(name: str):
        def open_lab() -> _Lab:
            if name != lab:
                raise LabSetupError(
                    f"this file is run as the {lab} lab, but it asks for kit.{name}()"
                )
            return session

        open_lab.__name__ = name
        return open_lab

    for name in LAB_CLASSES:
        setattr(module, name, opener(name))
    for name, value in (
        ("LabSetupError", LabSetupError),
        ("StudentShaderError", StudentShaderError),
        ("ENV_UNIT", 1),
    ):
        setattr(module, name, value)
    return module
