"""The sphere-map lab's object in the sandbox (``kit.spheremap()``). Student side:
imports only the standard library and :mod:`mirrorlab.labs.student`."""

from __future__ import annotations

from mirrorlab.labs.student.kit_standin import StudentLab
from mirrorlab.labs.student.remote import checked_number


class SphereMapLab(StudentLab):
    """The cone in front of the launch picture, drawn by your shader functions or by
    fixed-function texgen."""

    def set_viewer(self, aspect: float | None = None) -> None:
        """The viewer's projection (for ``aspect``, default the frame's) and camera."""
        self._call(
            "set_viewer",
            ["j"],
            None if aspect is None else checked_number(aspect, "f", "lab.set_viewer(aspect)"),
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


LAB_OBJECT = SphereMapLab
