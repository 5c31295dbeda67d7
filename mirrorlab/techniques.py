"""Every reflection technique by name: what kind of reflector it serves, what its texture
depends on, and where its pass lives. Imports no OpenGL, so a command line can list the
names cheaply; the renderer imports a technique's pass module only when a scene uses it.

A technique is one pass module in :mod:`mirrorlab.passes` with a class that follows
:class:`mirrorlab.passes.base.ReflectorPass` (update its texture, draw, release), its
shaders, a numpy reference (:mod:`mirrorlab.envmap`, :mod:`mirrorlab.views`) and one
entry here. The planner (:mod:`mirrorlab.plan`) reads the entry's ``texture`` to decide
when the texture must be made again.
"""

from __future__ import annotations

import importlib
from dataclasses import dataclass
from typing import Literal

from mirrorlab.scene.model import CURVED_TECHNIQUES, PLANAR_TECHNIQUES

TextureKind = Literal["static", "baked", "fixed", "viewer", "inline"]
"""What a technique's texture depends on:

- ``static``: nothing but the background or a picture: made once.
- ``baked``: the background and the view's rotation (sphere maps live in eye space):
  baked again when the view turns.
- ``fixed``: the scene, from a camera of the reflector's own (the lab's orthographic
  capture, a live cube map's six faces): captured again when the scene changes.
- ``viewer``: the scene from the viewer's mirror image: captured again when the scene
  or the viewer changes.
- ``inline``: no texture: the reflection is drawn straight into the view (stencil).
"""


@dataclass(frozen=True)
class Technique:
    """``name``; ``kind`` of reflector (``planar`` or ``curved``); ``texture`` (see
    :data:`TextureKind`); ``pass_class`` as ``module:Class``; ``summary`` for help texts;
    ``gl_version`` the OpenGL (major, minor) its pass needs (every pass's shaders are GLSL
    3.30; ``sphere-texgen`` also needs the compatibility profile's texgen)."""

    name: str
    kind: Literal["planar", "curved"]
    texture: TextureKind
    pass_class: str
    summary: str
    gl_version: tuple[int, int] = (3, 3)

    @property
    def captures_scene(self) -> bool:
        """True when its texture shows the scene (and so other reflectors, one bounce less)."""
        return self.texture in ("fixed", "viewer", "inline")

    def load(self) -> type:
        """The pass class (imports its module, and with it OpenGL)."""
        module, name = self.pass_class.split(":")
        return getattr(importlib.import_module(module), name)


RENDERER_GL_VERSION = (3, 3)
"""What the renderer's own shaders (the lit scene, the sky) need: GLSL 3.30."""

TECHNIQUES: dict[str, Technique] = {t.name: t for t in (
    Technique("ortho", "planar", "fixed", "mirrorlab.passes.ortho:OrthoMirror",
              "the lab: an orthographic capture from the mirror, copied into a texture"),
    Technique("reflected", "planar", "viewer", "mirrorlab.passes.reflected:ReflectedMirror",
              "the viewer's mirror image renders the scene, sampled projectively"),
    Technique("stencil", "planar", "inline", "mirrorlab.passes.stencil:StencilMirror",
              "the mirrored scene drawn straight into the frame through a stencil mask"),
    Technique("sphere", "curved", "baked", "mirrorlab.passes.envmap:SphereMapped",
              "sphere map, looked up per fragment"),
    Technique("sphere-vertex", "curved", "baked", "mirrorlab.passes.envmap:SphereMapped",
              "sphere map, coordinates per vertex in a shader"),
    Technique("sphere-texgen", "curved", "baked", "mirrorlab.passes.envmap:SphereMapped",
              "sphere map by fixed-function GL_SPHERE_MAP texgen, per vertex"),
    Technique("normal", "curved", "baked", "mirrorlab.passes.envmap:SphereMapped",
              "'demo style': the sphere map indexed by the eye-space normal"),
    Technique("cube", "curved", "static", "mirrorlab.passes.envmap:CubeMapped",
              "static cube map, from six pictures or baked from the background"),
    Technique("cube-live", "curved", "fixed", "mirrorlab.passes.cube_live:LiveCubeMapped",
              "cube map captured live from the reflector's centre, six passes; its "
              "lookups optionally corrected for parallax (box, sphere, distance search)"),
    Technique("latlong", "curved", "static", "mirrorlab.passes.envmap:LatlongMapped",
              "Blinn-Newell latitude-longitude map, per fragment"),
)}

assert tuple(n for n, t in TECHNIQUES.items() if t.kind == "planar") == PLANAR_TECHNIQUES
assert tuple(n for n, t in TECHNIQUES.items() if t.kind == "curved") == (
    "sphere", "sphere-vertex", "sphere-texgen", "normal", "cube", "cube-live", "latlong")
assert set(TECHNIQUES) == set(PLANAR_TECHNIQUES + CURVED_TECHNIQUES)


def technique(name: str) -> Technique:
    """The technique called ``name``; ValueError listing the names otherwise."""
    try:
        return TECHNIQUES[name]
    except KeyError:
        raise ValueError(f"unknown technique {name!r}; expected one of "
                         f"{', '.join(TECHNIQUES)}") from None
