"""Every technique by name, in one registry: what kind of reflector it serves (or whether
it draws the whole frame, as the ray tracer does), what its texture depends on, where its
pass lives, its shaders and sampler, and the flags its pass and the planner read. Every
list of techniques is derived from here: the scene schema (:mod:`mirrorlab.scene.loader`),
the command line's choices and help (:mod:`mirrorlab.cli`, :mod:`mirrorlab.options`), the
plan (:mod:`mirrorlab.plan`) and the renderer's passes. Imports no OpenGL and nothing of
the scene, so a command line can list the names cheaply; the renderer imports a
technique's pass module only when a scene uses it.

A new technique is one pass module in :mod:`mirrorlab.passes` with a class that follows
:class:`mirrorlab.passes.base.ReflectorPass` (update its texture, draw, say which texture
it shows, release), its shaders, a numpy reference (:mod:`mirrorlab.envmap`,
:mod:`mirrorlab.views`), its capture camera when it shows the scene (a
:data:`mirrorlab.plan.CaptureCamera` function: the shipped ones are in
:mod:`mirrorlab.captures`) and one :func:`register` call (the shipped ones are registered
below). Its entry says all the planner and the renderer need: its cameras come from its
``capture_camera``, whether its view nests in the draw (an ``inline`` texture) or is
captured into a texture from its ``texture`` kind, and whether it draws before or after
the view's objects from ``draws_after_objects``. Neither the planner nor the renderer
names a technique.

The replay rule: a frame planned as the last one was is drawn again from the last
frame's recorded GL calls (:class:`mirrorlab.renderer.RecordedFrame`), which hold the
arguments as they were given. So a pass must not change an array it handed GL in a
recorded frame afterwards, while that frame may be replayed: hand GL fresh or read-only
arrays (a buffer the GL fills, or the renderer fills before a replay, is the exception:
the replay then draws what it holds). ``tests/gl/test_pass_contract.py`` checks this
for every registered technique.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Literal

if TYPE_CHECKING:
    from mirrorlab.plan import CaptureCamera
    from mirrorlab.scene.model import Reflector

TechniqueKind = Literal["planar", "curved", "both", "frame"]
"""``planar``: a flat mirror's technique; ``curved``: an environment-mapped mesh's;
``both``: either's (a reflector of either kind may take it: screen-space reflections);
``frame``: draws the whole frame itself, instead of the rasteriser (the ray tracer)."""

REFLECTOR_KINDS = ("planar", "curved")
"""The kinds of reflector a scene holds (a ``both`` technique serves each)."""

TextureKind = Literal["static", "baked", "fixed", "viewer", "inline", "screen"]
"""What a reflector technique's texture depends on:

- ``static``: nothing but the background or a picture: made once.
- ``baked``: the background and the view's rotation (sphere maps live in eye space):
  baked again when the view turns.
- ``fixed``: the scene, from a camera of the reflector's own (the lab's orthographic
  capture, a live cube map's six faces): captured again when the scene changes.
- ``viewer``: the scene from the viewer's mirror image: captured again when the scene
  or the viewer changes.
- ``inline``: no texture: the reflection is drawn straight into the view (stencil).
- ``screen``: the view's own frame, its colour and depth as the view's target holds them
  when the reflector is drawn (after the objects: ``draws_after_objects``), copied by
  the pass at each draw (:class:`mirrorlab.passes.view_frame.ViewFrame`): never held
  from one view or frame to the next, so never reused and never planned as a pass of
  its own; a replayed frame makes the copy again (it is one of the frame's recorded
  calls), so it reads what that frame drew. What such a technique cannot find on the
  screen comes from its ``probe``.
"""

CAMERA_TEXTURES = ("fixed", "viewer", "inline")
"""The texture kinds that show the scene, whose techniques need a ``capture_camera``."""


@dataclass(frozen=True)
class Technique:
    """One technique.

    ``name``; ``kind`` (see :data:`TechniqueKind`); ``summary`` for help texts;
    ``texture`` (see :data:`TextureKind`; None for a frame technique); ``pass_class`` as
    ``module:Class`` (reflector techniques) or ``draw_frame`` as ``module:function``
    (frame techniques: ``function(scene, size, progress) -> (h, w, 3) uint8``);
    ``vertex_shader``, ``fragment_shader`` and ``sampler`` (the uniform its map is bound
    to) of its program; ``constants``: int uniforms its pass sets before each draw (a
    program may be shared by several techniques); ``capture_camera``, for a technique
    whose texture shows the scene (:data:`CAMERA_TEXTURES`), as ``module:function``: its
    :data:`mirrorlab.plan.CaptureCamera` (the planner captures its cameras into the
    texture, or, ``inline``, nests the first one's plan in the draw);
    ``draws_after_objects``: its own draw (its map, capture or nested view) comes after
    the view's objects, not before them as by default (the stencil mirror marks only the
    glass the objects leave showing); ``source`` what a reflector's
    ``source`` key names for it (a sphere-map ``picture`` used as its map, a folder of
    six cube ``faces``, a square ``octahedral`` picture, a ``paraboloid`` picture of two
    discs side by side; None: it takes none; a technique changed to one whose source is
    of another kind drops the reflector's); ``view_ray``: its
    lookup follows the world-space view ray (``eye_world``, ``view_direction``);
    ``map_size_uniform``: its shader is told its map's size; ``parallax``: it takes a
    ``parallax`` table; ``own_camera``: planar, an ``ortho`` table sets its camera;
    ``gl_version`` the OpenGL (major, minor) its pass needs; ``probe``, as
    ``module:function``: a :data:`ProbeFunction` giving the reflector as another
    technique (its probe) draws it, whose draw the planner plans too and hands the pass
    as :attr:`mirrorlab.plan.ReflectorDraw.fallback` (screen-space reflections fall back
    to it where the screen holds no answer).
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
    capture_camera: str = ""
    draws_after_objects: bool = False
    source: Literal["picture", "faces", "octahedral", "paraboloid"] | None = None
    view_ray: bool = False
    map_size_uniform: bool = False
    parallax: bool = False
    own_camera: bool = False
    gl_version: tuple[int, int] = (3, 3)
    probe: str = ""

    def serves(self, kind: str) -> bool:
        """Whether a reflector of ``kind`` (``planar`` or ``curved``) may take it (or, for
        ``frame``, whether it is a frame technique)."""
        return self.kind == kind or (self.kind == "both" and kind in REFLECTOR_KINDS)

    @property
    def draws_inline(self) -> bool:
        """True when its reflection is drawn straight into the view (no texture): its
        camera's view plan nests in its draw."""
        return self.texture == "inline"

    def load(self) -> type:
        """The pass class (imports its module, and with it OpenGL)."""
        return _load(self.pass_class, self.name, "pass_class")

    def frame_function(self) -> Callable[..., Any]:
        """A frame technique's drawing function (imports its module)."""
        return _load(self.draw_frame, self.name, "draw_frame")

    def capture_function(self) -> CaptureCamera:
        """Its capture camera (imports its module)."""
        return _load(self.capture_camera, self.name, "capture_camera")

    def probe_function(self) -> ProbeFunction:
        """Its probe (imports its module)."""
        return _load(self.probe, self.name, "probe")


ProbeFunction = Callable[["Reflector"], "Reflector | None"]
"""A technique's probe (its entry's ``probe``): ``reflector -> reflector or None``, the
reflector as the technique it falls back to draws it (a reflector of a curved technique,
with the map that technique needs), None where it has none. Numpy only."""


_LOADED: dict[str, Any] = {}
"""What each ``module:name`` spec named, once loaded (the planner asks every frame)."""


def _load(spec: str, technique: str, field: str) -> Any:
    """The object ``spec`` (``module:name``, technique ``technique``'s ``field``) names."""
    found = _LOADED.get(spec)
    if found is None:
        module, sep, name = spec.partition(":")
        if not sep:
            raise ValueError(
                f"technique {technique!r}'s {field} must be 'module:name', got {spec!r}"
            )
        found = _LOADED[spec] = getattr(importlib.import_module(module), name)
    return found


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
    elif entry.texture in CAMERA_TEXTURES and not entry.capture_camera:
        raise ValueError(
            f"technique {entry.name!r} shows the scene ({entry.texture}): it needs a capture_camera"
        )
    elif entry.texture == "screen" and not entry.draws_after_objects:
        raise ValueError(
            f"technique {entry.name!r} reads the view's own frame (screen): it must draw "
            "after the view's objects (draws_after_objects)"
        )
    _REGISTRY[entry.name] = entry
    return entry


def unregister(name: str) -> None:
    """Remove the technique ``name`` (for tests that register one of their own)."""
    _REGISTRY.pop(name, None)


def techniques(kind: TechniqueKind | None = None) -> tuple[Technique, ...]:
    """Every registered technique (that serves ``kind``: a ``both`` technique is among
    the ``planar`` and the ``curved`` ones), in the order they were registered."""
    return tuple(t for t in _REGISTRY.values() if kind is None or t.serves(kind))


def technique_names(kind: TechniqueKind | None = None) -> tuple[str, ...]:
    """The names of :func:`techniques` ``(kind)``."""
    return tuple(t.name for t in techniques(kind))


def reflector_technique_names() -> tuple[str, ...]:
    """Every technique a reflector may take (of either kind), each once."""
    return tuple(t.name for t in _REGISTRY.values() if t.kind != "frame")


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
        capture_camera="mirrorlab.captures:ortho_camera",
        own_camera=True,
    ),
    Technique(
        "reflected",
        "planar",
        "the viewer's mirror image renders the scene, sampled projectively",
        texture="viewer",
        pass_class="mirrorlab.passes.reflected:ReflectedMirror",
        capture_camera="mirrorlab.captures:reflected_camera",
    ),
    Technique(
        "stencil",
        "planar",
        "the mirrored scene drawn straight into the frame through a stencil mask",
        texture="inline",
        pass_class="mirrorlab.passes.stencil:StencilMirror",
        capture_camera="mirrorlab.captures:stencil_camera",
        draws_after_objects=True,
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
        capture_camera="mirrorlab.captures:cube_camera",
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
        "octahedral",
        "curved",
        "static octahedral map: the whole sphere in one square, its levels padded across "
        "the folds; baked from the background or a square octahedral picture",
        texture="static",
        pass_class="mirrorlab.passes.octahedral:OctahedralMapped",
        vertex_shader="envmap.vert",
        fragment_shader="envmap_octahedral.frag",
        sampler="octahedral_texture",
        source="octahedral",
        view_ray=True,
    ),
    Technique(
        "octahedral-live",
        "curved",
        "live cube capture resampled into an octahedral map (as EEVEE and DDGI store "
        "probes); its lookups optionally corrected for parallax as cube-live's",
        texture="fixed",
        pass_class="mirrorlab.passes.octahedral:LiveOctahedralMapped",
        vertex_shader="envmap.vert",
        fragment_shader="envmap_octahedral.frag",
        sampler="octahedral_texture",
        capture_camera="mirrorlab.captures:octahedral_cube_camera",
        view_ray=True,
        parallax=True,
    ),
    Technique(
        "paraboloid",
        "curved",
        "static dual-paraboloid map: two hemispheres in two squares; baked from the "
        "background or a dual-paraboloid picture",
        texture="static",
        pass_class="mirrorlab.passes.paraboloid:ParaboloidMapped",
        vertex_shader="envmap.vert",
        fragment_shader="envmap_paraboloid.frag",
        sampler="paraboloid_texture",
        source="paraboloid",
        view_ray=True,
    ),
    Technique(
        "paraboloid-live",
        "curved",
        "live cube capture converted into a dual-paraboloid map (as GTA V does); its "
        "lookups optionally corrected for parallax as cube-live's",
        texture="fixed",
        pass_class="mirrorlab.passes.paraboloid:LiveParaboloidMapped",
        vertex_shader="envmap.vert",
        fragment_shader="envmap_paraboloid.frag",
        sampler="paraboloid_texture",
        capture_camera="mirrorlab.captures:paraboloid_cube_camera",
        view_ray=True,
        parallax=True,
    ),
    Technique(
        "paraboloid-warped",
        "curved",
        "dual-paraboloid map captured live in two passes, the paraboloid applied per "
        "vertex (large triangles come out straight where they should curve)",
        texture="fixed",
        pass_class="mirrorlab.passes.paraboloid:WarpedParaboloidMapped",
        vertex_shader="envmap.vert",
        fragment_shader="envmap_paraboloid.frag",
        sampler="paraboloid_texture",
        capture_camera="mirrorlab.captures:paraboloid_camera",
        view_ray=True,
    ),
    Technique(
        "ssr",
        "both",
        "screen-space reflections: the reflected ray marched through the view's own "
        "depth (McGuire-Mara DDA), its misses from a probe (any map technique)",
        texture="screen",
        pass_class="mirrorlab.passes.ssr:ScreenSpaceReflections",
        vertex_shader="envmap.vert",
        fragment_shader="ssr_march.frag",
        sampler="frame_color",
        draws_after_objects=True,
        view_ray=True,
        parallax=True,
        probe="mirrorlab.screen_space:probe_reflector",
    ),
    Technique(
        "raytrace",
        "frame",
        "the ray-traced ground truth instead of OpenGL (slow)",
        draw_frame="mirrorlab.raytrace:trace_frame",
    ),
):
    register(_entry)
