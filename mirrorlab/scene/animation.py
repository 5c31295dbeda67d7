"""Keyframe animation: a scene posed at a frame by linear interpolation of the values its
keyframes set. Numpy only."""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import replace
from typing import TYPE_CHECKING, Any

from mirrorlab.scene.model import PlanarReflector

if TYPE_CHECKING:
    from mirrorlab.scene.model import Keyframe, Scene

CAMERA_FIELDS = ("eye", "target", "up", "fovy")
"""Camera fields a keyframe can set."""
OBJECT_FIELDS = ("position", "rotation", "scale", "angles")
"""Object fields a keyframe can set (``angles``: robots only)."""
REFLECTOR_FIELDS = ("position", "rotation", "scale")
"""Curved reflector fields a keyframe can set."""
PLANAR_FIELDS = ("position", "rotation")
"""Planar mirror fields a keyframe can set: where its centre is and how it is turned from
where its scene file puts it (its corners follow; its size is its corners')."""

Value = float | tuple[float, ...]
"""An animated value: a number (``fovy``) or a vector (``eye``, ``position``...)."""


def interpolate(keys: Sequence[tuple[int, Value]], frame: int) -> Value:
    """The value at ``frame`` from ``(frame, value)`` pairs sorted by frame: linear between
    the two around it, held before the first and after the last. The values of one track
    are all floats or all tuples of floats of one length."""
    if frame <= keys[0][0]:
        return keys[0][1]
    for (f0, v0), (f1, v1) in itertools.pairwise(keys):
        if f0 <= frame <= f1:
            if f1 == f0:
                return v1
            w = (frame - f0) / (f1 - f0)
            if isinstance(v0, tuple) and isinstance(v1, tuple):
                return tuple(a + (b - a) * w for a, b in zip(v0, v1, strict=True))
            if isinstance(v0, tuple) or isinstance(v1, tuple):
                raise TypeError(f"keyframes {f0} and {f1} mix a number and a vector")
            return v0 + (v1 - v0) * w
    return keys[-1][1]


def _track(
    keyframes: tuple[Keyframe, ...], group: str, name: str | None, field: str
) -> list[tuple[int, Value]]:
    keys = []
    for key in keyframes:
        values = getattr(key, group)
        if name is not None:
            values = values.get(name, {})
        if field in values:
            keys.append((key.frame, values[field]))
    return keys


def pose(scene: Scene, frame: int) -> Scene:
    """``scene`` with every animated value set for ``frame`` (see :class:`Keyframe`)."""
    assert scene.animation is not None
    keyframes = scene.animation.keyframes
    camera_changes: dict[str, Any] = {}  # each field's type, as the loader checked
    for field in CAMERA_FIELDS:
        keys = _track(keyframes, "camera", None, field)
        if keys:
            camera_changes[field] = interpolate(keys, frame)
    posed = replace(scene, camera=replace(scene.camera, **camera_changes))
    for group, fields in (("objects", OBJECT_FIELDS), ("reflectors", REFLECTOR_FIELDS)):
        names = {name for key in keyframes for name in getattr(key, group)}
        for name in sorted(names):
            changes = {
                field: interpolate(keys, frame)
                for field in fields
                if (keys := _track(keyframes, group, name, field))
            }
            posed = _apply(posed, group, name, changes)
    return posed


def _apply(scene: Scene, group: str, name: str, changes: dict) -> Scene:

    item = scene.object(name) if group == "objects" else scene.reflector(name)
    if isinstance(item, PlanarReflector):
        moved = item.moved(changes.get("position"), changes.get("rotation"))
        return scene.with_reflector(name, corners=moved.corners, ortho=moved.ortho)
    fields = {}
    transform = item.transform
    for field, value in changes.items():
        if field == "angles":
            fields["angles"] = value
        else:
            transform = replace(transform, **{field: value})
    fields["transform"] = transform
    if group == "objects":
        return scene.with_object(name, **fields)
    return scene.with_reflector(name, **fields)
