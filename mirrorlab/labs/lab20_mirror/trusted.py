"""Lab 20's trusted side: its session (the robot on its base at the variant's pose, the
mirror's frame, the viewer, the texture shader), its kit call ``lab.draw_scene`` as the
executor runs it, what the checker observes after the frames (the ENVIRONMENT texture,
METAL) and the calls it leaves out. OpenGL is imported on first use."""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

import numpy as np

from mirrorlab import math3d
from mirrorlab.labs.lab20_mirror.variant import lab20_geometry
from mirrorlab.labs.trusted.evidence import Evidence
from mirrorlab.labs.trusted.session import (
    LabBase,
    LabSetupError,
    compile_program,
    lazy_gl,
    picture,
    read_texture_2d,
    texture_parameters,
    uniform,
)
from mirrorlab.labs.trusted.state import GL_TEXTURE_2D
from mirrorlab.labs.trusted.variants import Variant
from mirrorlab.scene.graph import SceneGraph
from mirrorlab.scene.robot import build_robot

if TYPE_CHECKING:
    from mirrorlab.labs.trusted.call_executor import Executor
    from mirrorlab.labs.trusted.lab_run import LabRun


def left_out() -> dict[str, str]:
    """Calls of the allow-list (:data:`~mirrorlab.labs.trusted.calls.GL_SPECS`) this lab's
    handout does not need, with why."""
    from mirrorlab.labs.trusted import calls

    return {name: "lab 20 makes no texture coordinates by texgen" for name in calls.TEXGEN}


def channels() -> tuple[str, ...]:
    """The ways of :data:`~mirrorlab.labs.trusted.calls.CHANNELS` from a file's numbers to
    the frame this lab's handout teaches: the mirror quad (its corners and texture
    coordinates, filled) and the copy of the capture."""
    return ("immediate_mode", "texture_coordinates", "copies")


class Lab20(LabBase):
    """Lab 20, the multipass mirror: the robot on its base at the variant's pose, a dark
    frame behind the variant's mirror, the viewer, and ``textureShader`` (sampler
    uniform ``texSampler``) for the mirror quad."""

    name = "lab20"
    EYE = (12.0, 5.0, 9.0)
    TARGET = (-3.5, 1.0, -2.0)
    FOVY, NEAR, FAR = 45.0, 0.1, 100.0
    BACKGROUND = (0.16, 0.18, 0.22)
    NODES = ("base", "shoulder", "lower_arm", "elbow", "upper_arm", "hand")

    def __init__(self, size: tuple[int, int], variant: Variant) -> None:
        super().__init__(size, variant)
        self.geometry = lab20_geometry(variant)
        self.textureShader = compile_program("kit_texture.vert", "kit_texture.frag")
        self.texSampler = uniform(self.textureShader, "texSampler")
        self.graph = SceneGraph(build_robot())
        for joint, angle in zip(
            ("base", "lower_arm", "upper_arm"), self.geometry["angles"], strict=True
        ):
            self.graph.set_angle(joint, angle)
        lazy_gl().glClearColor(*self.BACKGROUND, 1.0)

    def student_values(self) -> dict[str, Any]:
        return {
            **super().student_values(),
            "textureShader": self.textureShader,
            "texSampler": self.texSampler,
            "robot_nodes": list(self.NODES),
        }

    def programs(self) -> set[int]:
        return {self.textureShader}

    def frame_model(self) -> np.ndarray:
        """The mirror frame's model: the shipped 8.6 x 8.6 frame (8 x 8 glass and a 0.3
        border) scaled to the variant's mirror, just behind its plane."""
        g = self.geometry
        scale = np.diag(
            [1.0, (g["y1"] - g["y0"] + 0.6) / 8.6, (g["z1"] - g["z0"] + 0.6) / 8.6, 1.0]
        )
        return math3d.translate((g["x"] - 0.175, g["y0"] - 0.3, (g["z0"] + g["z1"]) / 2)) @ scale

    def draw_scene(self, textures: dict[str, int | None]) -> list[int]:
        """The robot, each node wearing ``textures[node]``, and the mirror's frame, lit,
        under the current matrices. Never the mirror."""
        parts = []
        for node in self.graph.nodes():
            if node.mesh:
                parts.append((node.mesh, node.world_matrix(), node.color, textures.get(node.name)))
        parts.append(("mirror_frame", self.frame_model(), (0.35, 0.27, 0.2), None))
        return self.draw_parts(parts)


SESSION = Lab20


def kit_calls() -> dict[str, Any]:
    """The lab object's own calls, each ``handler(executor, args)``."""
    return {"draw_scene": draw_scene}


def draw_scene(executor: Executor, args: list[Any]) -> None:
    textures: dict[str, int | None] = {}
    shown: dict[str, Any] = {}
    given = args[0].get("textures") if args and isinstance(args[0], dict) else None
    if not isinstance(given, dict):
        raise LabSetupError("lab.draw_scene(robot): the robot's graph is missing")
    nodes = getattr(executor.session, "NODES", ())
    for node, value in list(given.items())[:16]:
        if node not in nodes:
            continue
        if value is None or isinstance(value, dict):
            textures[node] = None
            shown[node] = None if value is None else {"other": str(value.get("other", ""))[:40]}
        else:
            textures[node] = (
                executor.owned_texture(value, f"robot[{node!r}].texture", GL_TEXTURE_2D) or None
            )
            shown[node] = textures[node]
    bound = executor.record_draw(
        "draw_scene", lambda: executor.lab.draw_scene(textures), textures=shown
    )
    executor.after_kit_draw(bound)


def observe(run: LabRun) -> None:
    """What the checker observes after the frames (into ``run.evidence``)."""
    GL = lazy_gl()
    evidence, tracker = run.evidence, run.executor.tracker
    assert isinstance(run.session, Lab20)
    pictures = {t.name for t in tracker.textures.values() if t.picture}
    environment = find_environment(evidence, run.session, pictures)
    metal = next((t.name for t in tracker.textures.values() if t.picture == "metal"), 0)
    evidence.state["environment"], evidence.state["metal"] = environment, metal
    evidence.state["texture_shader"] = run.session.textureShader
    evidence.state["texture_sampler"] = run.session.texSampler
    if environment and GL.glIsTexture(environment):
        evidence.arrays["capture"] = read_texture_2d(environment)
        evidence.state["environment_parameters"] = texture_parameters(environment)
    if metal and GL.glIsTexture(metal):
        now = read_texture_2d(metal)
        original = picture("metal")
        evidence.state["metal_intact"] = bool(
            now.shape == original.shape and np.array_equal(now, original)
        )


def find_environment(evidence: Evidence, session: LabBase, pictures: set[int]) -> int:
    """Lab 20's ENVIRONMENT texture, as the calls show it: the texture the mirror quad
    sampled in the last frame (bound on the unit the texture shader's sampler reads),
    unless that is a picture such as METAL; else the texture create_mirror() copied
    into, unless that is a picture; else the blank texture of the frame's size that the
    set-up made."""
    for event in reversed(evidence.events("draw", who="primitive", within="render_mirror")):
        unit = event.get("sampler")
        if isinstance(unit, int) and 0 <= unit < 8:
            bound = event["state"]["units"].get(str(unit), {}).get("2d")
            if bound and bound["value"] and int(bound["value"]) not in pictures:
                return int(bound["value"])
    for event in reversed(evidence.events("copy", within="create_mirror")):
        if int(event["texture"]) not in pictures:
            return int(event["texture"])
    for event in evidence.events("upload", frame=None):
        if (
            not event.get("data")
            and (event.get("width"), event.get("height")) == (session.width, session.height)
            and int(event["texture"]) not in pictures
        ):
            return int(event["texture"])
    return 0
