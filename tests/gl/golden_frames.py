"""The frames every shipped scene must keep, pixel for pixel: each scene file drawn as a
sequence of frames by one renderer (so captures are made, reused, replayed and made
again as a program drawing it would see them), every frame of an animated scene, and
every technique on the scenes built for them.

A sequence's frames are kept side by side in one PNG,
``tests/gl/golden/shipped/<name>.png`` (``SIZE`` each, left to right), made from the
renderer as it was before the renderer's drawing was reworked for scale (issue 22) by
``python tools/make_golden.py``; ``tests/gl/test_shipped_goldens.py`` compares them
exactly.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, replace
from pathlib import Path
from typing import Any

import numpy as np

import mirrorlab
from mirrorlab.data import scenes_dir
from mirrorlab.options import apply_options
from mirrorlab.scene.model import Scene
from mirrorlab.techniques import technique_names, techniques
from tests.scenekit import vec3
from tests.twins import original

SIZE = (96, 96)
"""Width, height of every frame."""
FOLDER = Path(__file__).resolve().parent / "golden" / "shipped"


def orbited(scene: Scene, degrees: float) -> Scene:
    """``scene`` with its camera turned ``degrees`` about its target (the vertical axis)."""
    camera = scene.camera
    eye, target = np.asarray(camera.eye, dtype=np.float64), np.asarray(camera.target)
    angle = np.radians(degrees)
    x, y, z = eye - target
    turned = (x * np.cos(angle) - z * np.sin(angle), y, x * np.sin(angle) + z * np.cos(angle))
    eye_tuple = vec3(target + np.asarray(turned))
    return replace(scene, camera=replace(camera, eye=eye_tuple))


def still_sequence(scene: Scene) -> list[Scene]:
    """A still scene's frames: as it is twice (the second frame reuses every capture),
    the camera turned 10 degrees twice (captures that follow the viewer run again, then
    are reused), then something moved: the robot's base (or the first object) while the
    camera stays turned."""
    turned = orbited(scene, 10.0)
    if turned.robot is not None:
        base, lower, upper = turned.robot.angles
        moved = turned.with_angles((base + 25.0, lower, upper))
    elif turned.objects:
        first = turned.objects[0]
        position = vec3(
            float(v) + d for v, d in zip(first.transform.position, (0.3, 0.2, -0.2), strict=True)
        )
        moved = turned.with_object(
            first.name, transform=replace(first.transform, position=position)
        )
    else:
        moved = orbited(scene, -12.0)
    return [scene, scene, turned, turned, moved]


@dataclass(frozen=True)
class Sequence:
    """One golden PNG: ``name``, and the frames drawn in order by one renderer, each a
    scene and its animation frame."""

    name: str
    frames: tuple[tuple[Scene, int], ...]
    golden: str = ""
    """The PNG's name when it is not ``name``: a copy of a technique under another name
    (:mod:`tests.twins`) draws its original's golden frames."""

    @property
    def path(self) -> Path:
        return FOLDER / f"{self.golden or self.name}.png"


TECHNIQUE_VARIANTS: tuple[tuple[str, dict[str, Any]], ...] = (
    ("lab20", {"method": "reflected"}),
    ("lab20", {"method": "stencil"}),
    ("lab20", {"capture": "fbo"}),
    ("lab20", {"env_size": 48}),
    ("lab20", {"method": "reflected", "env_size": 40}),
    *(
        ("chrome_sphere", {"method": method, "map_size": 64})
        for method in technique_names("curved")
    ),
    # a technique for both kinds of reflector on the lab's planar mirror too
    *(("lab20", {"method": t.name}) for t in techniques("planar") if t.kind == "both"),
    ("two_mirrors", {"method": "stencil"}),
    ("mirror_and_sphere", {"max_bounces": 3}),
)
"""Shipped scenes with options that put every technique and capture mode on screen (every
curved technique of the registry on the chrome sphere, and a technique for both kinds on
the lab's mirror: a new one needs its golden PNG made, ``python tools/make_golden.py``)."""


def _label(options: dict[str, Any]) -> str:
    return "_".join(f"{key}-{value}" for key, value in options.items())


def sequences() -> Iterator[Sequence]:
    """Every golden sequence: each shipped scene file, then :data:`TECHNIQUE_VARIANTS`."""
    for path in sorted(scenes_dir().glob("*.toml")):
        scene = mirrorlab.load_scene(path.stem)
        if scene.animation is not None:
            frames = tuple((scene, f) for f in range(scene.frame_count))
        else:
            frames = tuple((frame, 0) for frame in still_sequence(scene))
        yield Sequence(path.stem, frames)
    for name, options in TECHNIQUE_VARIANTS:
        scene = apply_options(mirrorlab.load_scene(name), options)
        frames = tuple((frame, 0) for frame in still_sequence(scene))
        golden = ""
        if "method" in options and original(options["method"]) != options["method"]:
            golden = f"{name}__{_label({**options, 'method': original(options['method'])})}"
        yield Sequence(f"{name}__{_label(options)}", frames, golden)


def draw_sequence(renderer, sequence: Sequence, **render_options) -> np.ndarray:
    """The sequence's frames drawn in order by ``renderer`` (a
    :class:`mirrorlab.renderer.SceneRenderer`), side by side: ``(h, w * frames, 3)``
    uint8."""
    from tests.gl.frames import draw

    return np.concatenate(
        [
            draw(renderer, scene.at_frame(frame), SIZE, **render_options)[0]
            for scene, frame in sequence.frames
        ],
        axis=1,
    )
