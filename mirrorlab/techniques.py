"""Every technique by name, in one registry: what kind of reflector it serves (or whether
it draws the whole frame, as the ray tracer does), what its texture depends on, where its
pass lives, its shaders and sampler, and the flags its pass and the planner read. Every
list of techniques is derived from here: the scene schema (:mod:`mirrorlab.scene.loader`),
the command line's choices and help (:mod:`mirrorlab.cli`, :mod:`mirrorlab.options`), the
plan (:mod:`mirrorlab.plan`) and the renderer's passes. Imports no OpenGL and nothing of
the scene, so a command line can list the names cheaply; the renderer imports a
technique's pass module only when a scene uses it.

A new technique is one pass module in :mod:`mirrorlab.passes` with a class that follows
:class:`mirrorlab.passes.base.ReflectorPass` (update its texture, draw, release), its
shaders, a numpy reference (:mod:`mirrorlab.envmap`, :mod:`mirrorlab.views`) and one
:func:`register` call (the shipped ones are registered below).
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal

TechniqueKind = Literal["planar", "curved", "frame"]
"""``planar``: a flat mirror's technique; ``curved``: an environment-mapped mesh's;
``frame``: draws the whole frame itself, instead of the rasteriser (the ray tracer)."""

TextureKind = Literal["static", "baked", "fixed", "viewer", "inline"]
"""What a reflector technique's texture depends on:

- ``static``: nothing but the background or a picture: made once.
- ``baked``: the background and the view's rotation (sphere maps live in eye space):
  baked again when the view turns.
- ``fixed``: the scene, from a camera of the reflector's own (the lab's orthographic
  capture, a live cube map's six faces): captured again when the scene changes.
- ``viewer``: the scene from the viewer's mirror image: captured again when the scene
  or the viewer changes.
- ``inline``: no texture: the reflection is drawn straight into the view (stencil).
"""

CaptureCamera = Literal["ortho", "reflected", "cube"]
"""Where a capturing technique's camera is (:mod:`mirrorlab.views`): the mirror's own
orthographic camera, the viewer's mirror image, or six faces from the reflector's centre."""


@dataclass(frozen=True)
class Technique:
    """One technique.

    ``name``; ``kind`` (see :data:`TechniqueKind`); ``summary`` for help texts;
    ``texture`` (see :data:`TextureKind`; None for a frame technique); ``pass_class`` as
    ``module:Class`` (reflector techniques) or ``draw_frame`` as ``module:function``
    (frame techniques: ``function(scene, size, progress) -> (h, w, 3) uint8``);
    ``vertex_shader``, ``fragment_shader`` and ``sampler`` (the uniform its map is bound
    to) of its program; ``constants``: int uniforms its pass sets before each draw (a
    program may be shared by several techniques); ``capture_camera`` (see
    :data:`CaptureCamera`) for a capturing technique; ``source`` what a reflector's
    ``source`` key names for it (a ``picture`` used as its map, a folder of six cube
    ``faces``; None: it takes none); ``view_ray``: its
    lookup follows the world-space view ray (``eye_world``, ``view_direction``);
    ``map_size_uniform``: its shader is told its map's size; ``parallax``: it takes a
    ``parallax`` table; ``own_camera``: planar, an ``ortho`` table sets its camera;
    ``gl_version`` the OpenGL (major, minor) its pass needs.
    """

    name: str
    kind: TechniqueKind
    summary: str
    texture: TextureKind | None = None
    pass_class: str = ""
    draw_frame: str = ""
    vertex_shader: str = ""
    fragment_shader: str = ""
    sampler: str = ""
    constants: tuple[tuple[str, int], ...] = ()
    capture_camera: CaptureCamera | None = None
    source: Literal["picture", "faces"] | None = None
    view_ray: bool = False
    map_size_uniform: bool = False
    parallax: bool = False
    own_camera: bool = False
    gl_version: tuple[int, int] = (3, 3)

    @property
    def captures_scene(self) -> bool:
        """True when its texture shows the scene (and so other reflectors, one bounce less)."""
        return self.texture in ("fixed", "viewer", "inline")

    @property
    def draws_inline(self) -> bool:
        """True when its reflection is drawn straight into the view (no texture)."""
        return self.texture == "inline"

    def load(self) -> type:
        """The pass class (imports its module, and with it OpenGL)."""
        return _load(self.pass_class, f"technique {self.name!r}'s pass_class")

    def frame_function(self) -> Callable[..., Any]:
        """A frame technique's drawing function (imports its module)."""
        return _load(self.draw_frame, f"technique {self.name!r}'s draw_frame")


def _load(spec: str, what: str) -> Any:
    module, sep, name = spec.partition(":")
    if not sep:
        raise ValueError(f"{what} must be 'module:name', got {spec!r}")
    return getattr(importlib.import_module(module), name)


RENDERER_GL_VERSION = (3, 3)
"""What the renderer's own shaders (the lit scene, the sky) need: GLSL 3.30."""

_REGISTRY: dict[str, Technique] = {}


def register(entry: Technique) -> Technique:
    """Add ``entry`` to the registry (ValueError when the name is taken, or an entry lacks
    what its kind needs); returns it. Every list of techniques includes it from then on."""
    if entry.name in _REGISTRY:
        raise ValueError(f"technique {entry.name!r} is already registered")
    if entry.kind == "frame":
        if not entry.draw_frame:
            raise ValueError(f"frame technique {entry.name!r} needs a draw_frame")
    elif entry.texture is None or not entry.pass_class:
        raise ValueError(f"technique {entry.name!r} needs a texture kind and a pass_class")
    _REGISTRY[entry.name] = entry
    return entry


def unregister(name: str) -> None:
    """Remove the technique ``name`` (for tests that register one of their own)."""
    _REGISTRY.pop(name, None)


def techniques(kind: TechniqueKind | None = None) -> tuple[Technique, ...]:
    """Every registered technique (of ``kind``), in the order they were registered."""
    return tuple(t for t in _REGISTRY.values() if kind is None or t.kind == kind)


def technique_names(kind: TechniqueKind | None = None) -> tuple[str, ...]:
    """The names of :func:`techniques` ``(kind)``."""
    return tuple(t.name for t in techniques(kind))


def technique(name: str) -> Technique:
    """The technique called ``name``; ValueError listing the names otherwise."""
    try:
        return _REGISTRY[name]
    except KeyError:
        raise ValueError(
            f"unknown technique {name!r}; expected one of {', '.join(_REGISTRY)}"
        ) from None


def frame_technique(name: object) -> Technique | None:
    """The frame technique called ``name`` (a value given as ``method``), or None."""
    entry = _REGISTRY.get(name) if isinstance(name, str) else None
    return entry if entry is not None and entry.kind == "frame" else None


def names_where(test: Callable[[Technique], bool]) -> tuple[str, ...]:
    """The names of the techniques ``test`` is true of (for messages: "applies to ...")."""
    return tuple(t.name for t in _REGISTRY.values() if test(t))


_SPHERE: dict[str, Any] = dict(
    vertex_shader="envmap.vert",
    fragment_shader="envmap_sphere.frag",
    sampler="sphere_map_texture",
    source="picture",
)
for _entry in (
    Technique(
        "ortho",
        "planar",
        "the lab: an orthographic capture from the mirror, copied into a texture",
        texture="fixed",
        pass_class="mirrorlab.passes.ortho:OrthoMirror",
        capture_camera="ortho",
        own_camera=True,
    ),
    Technique(
        "reflected",
        "planar",
        "the viewer's mirror image renders the scene, sampled projectively",
        texture="viewer",
        pass_class="mirrorlab.passes.reflected:ReflectedMirror",
        capture_camera="reflected",
    ),
    Technique(
        "stencil",
        "planar",
        "the mirrored scene drawn straight into the frame through a stencil mask",
        texture="inline",
        pass_class="mirrorlab.passes.stencil:StencilMirror",
    ),
    Technique(
        "sphere",
        "curved",
        "sphere map, looked up per fragment",
        texture="baked",
        pass_class="mirrorlab.passes.envmap:SphereMapped",
        constants=(("per_vertex", 0), ("texgen", 0)),
        **_SPHERE,
    ),
    Technique(
        "sphere-vertex",
        "curved",
        "sphere map, coordinates per vertex in a shader",
        texture="baked",
        pass_class="mirrorlab.passes.envmap:SphereMapped",
        constants=(("per_vertex", 1), ("texgen", 0)),
        **_SPHERE,
    ),
    Technique(
        "sphere-texgen",
        "curved",
        "sphere map by the textbook's GL_SPHERE_MAP texgen, its formula per vertex in a shader",
        texture="baked",
        pass_class="mirrorlab.passes.envmap:SphereMapped",
        constants=(("per_vertex", 1), ("texgen", 1)),
        **_SPHERE,
    ),
    Technique(
        "cube",
        "curved",
        "static cube map, from six pictures or baked from the background",
        texture="static",
        pass_class="mirrorlab.passes.envmap:CubeMapped",
        vertex_shader="envmap.vert",
        fragment_shader="envmap_cube.frag",
        sampler="cube_map_texture",
        source="faces",
        view_ray=True,
    ),
    Technique(
        "cube-live",
        "curved",
        "cube map captured live from the reflector's centre, six "
        "passes; its lookups optionally corrected for parallax (box, sphere, distance "
        "search)",
        texture="fixed",
        pass_class="mirrorlab.passes.cube_live:LiveCubeMapped",
        vertex_shader="envmap.vert",
        fragment_shader="envmap_cube.frag",
        sampler="cube_map_texture",
        capture_camera="cube",
        view_ray=True,
        parallax=True,
    ),
    Technique(
        "latlong",
        "curved",
        "Blinn-Newell latitude-longitude map, per fragment",
        texture="static",
        pass_class="mirrorlab.passes.envmap:LatlongMapped",
        vertex_shader="envmap.vert",
        fragment_shader="envmap_latlong.frag",
        sampler="latlong_texture",
        view_ray=True,
    ),
    Technique(
        "normal",
        "curved",
        "'demo style': the sphere map indexed by the eye-space normal",
        texture="baked",
        pass_class="mirrorlab.passes.envmap:SphereMapped",
        vertex_shader="envmap.vert",
        fragment_shader="envmap_normal.frag",
        sampler="normal_map_texture",
        source="picture",
        map_size_uniform=True,
    ),
    Technique(
        "raytrace",
        "frame",
        "the ray-traced ground truth instead of OpenGL (slow)",
        draw_frame="mirrorlab.raytrace:trace_frame",
    ),
):
    register(_entry)
