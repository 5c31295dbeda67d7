"""The cube-map lab's object in the sandbox (``kit.cubemap()``). Student side: imports
only the standard library and :mod:`mirrorlab.labs.student`."""

from __future__ import annotations

from mirrorlab.labs.student.kit_standin import StudentLab


class CubeMapLab(StudentLab):
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


LAB_OBJECT = CubeMapLab
