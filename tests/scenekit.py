"""Scenes made for tests from other scenes: the same scene moved or scaled as a whole,
small builders for the kinds of scene the plan and the truth are checked on, and look-ups
that check a scene's reflector, object or robot is there and of the kind a test needs."""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import replace

import numpy as np

from mirrorlab.data import data_path
from mirrorlab.scene.model import (
    BoxProxy,
    Camera,
    CurvedReflector,
    MeshObject,
    OrthoCapture,
    PlanarReflector,
    Reflector,
    RobotObject,
    Scene,
    SphereProxy,
    Transform,
    Vec3,
)

MAP_TEXTURES = ("static", "baked", "fixed")
"""The texture kinds of the curved techniques that look the reflection up in a map (made
once, baked for the view, or captured), whose lookup coordinates tests read back."""


def map_technique_names() -> tuple[str, ...]:
    """The curved techniques whose reflection is a map lookup (:data:`MAP_TEXTURES`), from
    the registry; a technique drawn from the view's own frame (``screen``) is not one."""
    from mirrorlab.techniques import techniques

    return tuple(t.name for t in techniques("curved") if t.texture in MAP_TEXTURES)


SPHERE_MESH = data_path("models") / "env_sphere.obj"
BOX_MESH = data_path("models") / "hand.obj"
PANEL_MESH = data_path("models") / "panel.obj"


def vec3(values: Iterable[float]) -> Vec3:
    """Three floats from any three numbers."""
    x, y, z = (float(v) for v in values)
    return (x, y, z)


def _affine(point, scale: float, offset) -> tuple[float, float, float]:
    x, y, z = np.asarray(point, dtype=np.float64) * scale + np.asarray(offset, dtype=float)
    return (float(x), float(y), float(z))


def transformed(scene: Scene, scale: float = 1.0, offset=(0.0, 0.0, 0.0)) -> Scene:
    """``scene`` with every position scaled by ``scale`` about the origin, then moved by
    ``offset`` ``(3,)``: camera (and its near and far), objects, reflectors, an ortho
    capture and parallax proxies alike. Lights are directions and stay."""

    def point(p):
        return _affine(p, scale, offset)

    camera = scene.camera
    camera = replace(
        camera,
        eye=point(camera.eye),
        target=point(camera.target),
        near=camera.near * scale,
        far=camera.far * scale,
    )
    objects = []
    for item in scene.objects:
        transform = item.transform
        objects.append(
            replace(
                item,
                transform=replace(
                    transform,
                    position=point(transform.position),
                    scale=vec3(float(s) * scale for s in transform.scale),
                ),
            )
        )
    reflectors: list[Reflector] = []
    for reflector in scene.reflectors:
        if isinstance(reflector, PlanarReflector):
            ortho = reflector.ortho
            if ortho is not None:
                left, right, bottom, top, near, far = ortho.extents
                ortho = OrthoCapture(
                    eye=point(ortho.eye),
                    target=point(ortho.target),
                    up=ortho.up,
                    extents=(
                        left * scale,
                        right * scale,
                        bottom * scale,
                        top * scale,
                        near * scale,
                        far * scale,
                    ),
                )
            reflectors.append(
                replace(reflector, corners=tuple(point(c) for c in reflector.corners), ortho=ortho)
            )
            continue
        assert isinstance(reflector, CurvedReflector)
        transform = reflector.transform
        parallax = reflector.parallax
        if isinstance(parallax, BoxProxy):
            parallax = BoxProxy(point(parallax.min), point(parallax.max))
        elif isinstance(parallax, SphereProxy):
            parallax = SphereProxy(parallax.radius * scale)
        reflectors.append(
            replace(
                reflector,
                parallax=parallax,
                transform=replace(
                    transform,
                    position=point(transform.position),
                    scale=vec3(float(s) * scale for s in transform.scale),
                ),
            )
        )
    return replace(
        scene, camera=camera, objects=tuple(objects), reflectors=tuple(reflectors), animation=None
    )


def quad(center, normal, up, width: float, height: float) -> tuple:
    """Four corners of a ``width`` x ``height`` rectangle at ``center`` facing ``normal``,
    its height along ``up`` (as a scene file's center/normal/width/height/up)."""
    center = np.asarray(center, dtype=float)
    normal = np.asarray(normal, dtype=float)
    normal = normal / np.linalg.norm(normal)
    up = np.asarray(up, dtype=float)
    up = up - (up @ normal) * normal
    up = up / np.linalg.norm(up)
    right = np.cross(normal, up)
    w, h = width / 2.0, height / 2.0
    corners = (
        center - w * right - h * up,
        center - w * right + h * up,
        center + w * right + h * up,
        center + w * right - h * up,
    )
    return tuple(tuple(float(v) for v in c) for c in corners)


def mirror(
    name: str,
    center,
    normal,
    width: float,
    height: float,
    technique: str,
    up=(0.0, 1.0, 0.0),
    **fields,
) -> PlanarReflector:
    return PlanarReflector(
        name=name, corners=quad(center, normal, up, width, height), technique=technique, **fields
    )


def ball(name: str, center, radius: float, technique: str, **fields) -> CurvedReflector:
    return CurvedReflector(
        name=name,
        mesh=SPHERE_MESH,
        technique=technique,
        transform=Transform(position=vec3(center), scale=(radius, radius, radius)),
        **fields,
    )


def block(name: str, center, size: float, color) -> MeshObject:
    """A box (the hand's mesh, a unit-ish cube) of side about ``size``."""
    return MeshObject(
        name=name,
        mesh=BOX_MESH,
        color=color,
        transform=Transform(position=vec3(center), scale=(size, size, size)),
    )


def looking(eye, target, up=(0.0, 1.0, 0.0), **fields) -> Camera:
    return Camera(
        eye=vec3(eye),
        target=vec3(target),
        up=vec3(up),
        **fields,
    )


def planar_reflector(scene: Scene, name: str) -> PlanarReflector:
    """``scene``'s reflector ``name``, checked to be a flat mirror."""
    reflector = scene.reflector(name)
    assert isinstance(reflector, PlanarReflector), f"{name!r} is not a planar mirror"
    return reflector


def curved_reflector(scene: Scene, name: str) -> CurvedReflector:
    """``scene``'s reflector ``name``, checked to be a curved reflector."""
    reflector = scene.reflector(name)
    assert isinstance(reflector, CurvedReflector), f"{name!r} is not a curved reflector"
    return reflector


def scene_robot(scene: Scene) -> RobotObject:
    """``scene``'s robot, checked to be there."""
    assert scene.robot is not None, f"scene {scene.name!r} has no robot"
    return scene.robot


def mesh_object(scene: Scene, name: str) -> MeshObject:
    """``scene``'s object ``name``, checked to be a mesh (not the robot)."""
    item = scene.object(name)
    assert isinstance(item, MeshObject), f"{name!r} is not a mesh object"
    return item
