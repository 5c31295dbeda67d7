"""The shipped techniques' capture cameras: where each technique that shows the scene
looks from, for one reflector seen in one view (a :data:`mirrorlab.plan.CaptureCamera`
each, named by its registry entry's ``capture_camera``). The camera math itself is in
:mod:`mirrorlab.views`; these choose the cameras, the part of each target that is ever
read (its scissor) and what of the cameras the texture depends on (its key). Numpy only.

A technique of another kind names a function of its own (in its own module), with the
same signature; the planner calls it, not knowing which technique it serves.
"""

from __future__ import annotations

import numpy as np

from mirrorlab import math3d
from mirrorlab.footprint import Footprint
from mirrorlab.plan import (
    CaptureCameras,
    CaptureContext,
    Rectangle,
    glass_scissor,
    intersect,
    reflector_footprint,
)
from mirrorlab.scene.model import CurvedReflector, PlanarReflector, Reflector
from mirrorlab.views import (
    View,
    Warp,
    cube_face_views,
    mirrored_eye,
    ortho_capture_view,
    reflected_capture_view,
    stencil_view,
)


def _reach(view: View, reflector: PlanarReflector, context: CaptureContext) -> float | None:
    """How far the world seen in ``reflector`` from ``view`` extends (None for a view
    without an eye: the camera keeps ``view``'s far plane)."""
    eye = mirrored_eye(view, reflector)
    return None if eye is None else context.reach(eye)


def ortho_camera(
    reflector: Reflector,
    view: View,
    footprint: Footprint | None,
    scissor: Rectangle | None,
    context: CaptureContext,
) -> CaptureCameras:
    """The ``ortho`` technique (the lab's pass 1): an orthographic camera on the mirror
    looking out along its normal (:func:`~mirrorlab.views.ortho_capture_view`). It does
    not follow the viewer: its texture depends on the texture's size alone."""
    assert isinstance(reflector, PlanarReflector)
    size = context.texture_size(reflector, view, footprint)
    return CaptureCameras((ortho_capture_view(reflector, size),), (None,), size)


def reflected_camera(
    reflector: Reflector,
    view: View,
    footprint: Footprint | None,
    scissor: Rectangle | None,
    context: CaptureContext,
) -> CaptureCameras | None:
    """The ``reflected`` technique: the viewer's mirror image, its near plane on the glass
    (:func:`~mirrorlab.views.reflected_capture_view`), scissored to the glass (only the
    glass is ever sampled). None where the viewer is behind the mirror's plane, and in a
    warped view, which has no mirror image (:class:`~mirrorlab.views.Warp`)."""
    assert isinstance(reflector, PlanarReflector)
    if view.warp is not None:
        return None
    size = context.texture_size(reflector, view, footprint)
    camera = reflected_capture_view(view, reflector, size, _reach(view, reflector, context))
    if camera is None:
        return None
    glass = glass_scissor(reflector, camera) if context.use_plan else None
    return CaptureCameras((camera,), (glass,), camera.key)


def stencil_camera(
    reflector: Reflector,
    view: View,
    footprint: Footprint | None,
    scissor: Rectangle | None,
    context: CaptureContext,
) -> CaptureCameras | None:
    """The ``stencil`` technique (inline): the world seen in the mirror, drawn straight
    into ``view``'s target (:func:`~mirrorlab.views.stencil_view`), scissored to where
    the glass shows within ``view``'s own scissor. It makes no texture, so no key. None
    in a warped view, which has no mirror image."""
    assert isinstance(reflector, PlanarReflector)
    if view.warp is not None:
        return None
    glass = (footprint or reflector_footprint(reflector, view)).bounds
    inner = intersect(scissor, glass) if glass is not None and context.use_plan else scissor
    world = stencil_view(view, reflector, _reach(view, reflector, context))
    return CaptureCameras((world,), (inner,), None)


def cube_camera(
    reflector: Reflector,
    view: View,
    footprint: Footprint | None,
    scissor: Rectangle | None,
    context: CaptureContext,
) -> CaptureCameras:
    """The ``cube-live`` technique: six 90-degree faces from the reflector's centre
    (:func:`~mirrorlab.views.cube_face_views`), their clip distances holding the whole
    scene. It does not follow the viewer; what it shows leaves out its own parallax
    correction's sizes."""
    assert isinstance(reflector, CurvedReflector)
    faces = cube_face_views(reflector, context.depth_range(reflector))
    return CaptureCameras(
        tuple(faces), (None,) * len(faces), (reflector.map_size,), context.own_content(reflector)
    )


def _resampled_faces(
    reflector: CurvedReflector, size: int, context: CaptureContext
) -> CaptureCameras:
    """Six 90-degree faces from the reflector's centre, as :func:`cube_camera`'s, ``size``
    texels a side, for a 2D map resampled from them."""
    faces = cube_face_views(reflector, context.depth_range(reflector), size)
    return CaptureCameras(
        tuple(faces), (None,) * len(faces), (reflector.map_size,), context.own_content(reflector)
    )


def octahedral_cube_camera(
    reflector: Reflector,
    view: View,
    footprint: Footprint | None,
    scissor: Rectangle | None,
    context: CaptureContext,
) -> CaptureCameras:
    """The ``octahedral-live`` technique: the six faces a live cube map of the same size
    captures, resampled into the octahedral map. An octahedral map of ``n``^2 texels
    has its finest texels (around ``+z``) as fine as a cube's of ``n`` at a face's
    centre, so coarser faces would blur them."""
    assert isinstance(reflector, CurvedReflector)
    return _resampled_faces(reflector, reflector.map_size, context)


def paraboloid_size(map_size: int) -> int:
    """The faces of the cube capture a dual-paraboloid map of two ``map_size``^2 halves is
    converted from: half its size (at least 4), whose texels at a face's centre match
    the paraboloid's finest, at each half's centre."""
    return max(4, (int(map_size) + 1) // 2)


def paraboloid_cube_camera(
    reflector: Reflector,
    view: View,
    footprint: Footprint | None,
    scissor: Rectangle | None,
    context: CaptureContext,
) -> CaptureCameras:
    """The ``paraboloid-live`` technique: six faces of :func:`paraboloid_size`, converted
    into the two halves of the map."""
    assert isinstance(reflector, CurvedReflector)
    return _resampled_faces(reflector, paraboloid_size(reflector.map_size), context)


PARABOLOID_WARP = Warp("warp_paraboloid.glsl")
"""The vertex-stage paraboloid of a hemisphere capture (``shaders/warp_paraboloid.glsl``)."""
PARABOLOID_SIDES = (
    # (look direction, up) of the front and the back side (mirrorlab.envmap.paraboloid_map)
    ((0.0, 0.0, 1.0), (0.0, 1.0, 0.0)),
    ((0.0, 0.0, -1.0), (0.0, 1.0, 0.0)),
)


def paraboloid_views(reflector: CurvedReflector, far: float) -> tuple[View, View]:
    """The two hemisphere views of a vertex-warped dual-paraboloid capture from the
    reflector's centre (front along ``+z``, back along ``-z``, both ``+y`` up, as
    :func:`mirrorlab.envmap.paraboloid_map` has them), each ``map_size`` texels square,
    warped by :data:`PARABOLOID_WARP`: a view's matrix takes points to its eye space
    divided by ``far`` (so the warp's depth runs from the centre to ``far``), whose box
    ``[-far, far]^3`` around the centre is what culling tests against."""
    center = reflector.center()
    size = (reflector.map_size, reflector.map_size)
    scale = math3d.read_only(np.diag([1.0 / far, 1.0 / far, 1.0 / far, 1.0]))
    views = []
    for name, (direction, up) in zip(("front", "back"), PARABOLOID_SIDES, strict=True):
        views.append(
            View(
                view=math3d.look_at(center, center + np.asarray(direction), up),
                projection=scale,
                size=size,
                eye=center,
                label=f"{reflector.name} paraboloid {name}",
                depth_range=(0.0, float(far)),
                warp=PARABOLOID_WARP,
            )
        )
    return views[0], views[1]


def paraboloid_camera(
    reflector: Reflector,
    view: View,
    footprint: Footprint | None,
    scissor: Rectangle | None,
    context: CaptureContext,
) -> CaptureCameras:
    """The ``paraboloid-warped`` technique: the two hemispheres drawn straight into their
    halves of the map by the vertex-stage paraboloid (:func:`paraboloid_views`), seeing
    as far as a live cube map's faces. It does not follow the viewer."""
    assert isinstance(reflector, CurvedReflector)
    sides = paraboloid_views(reflector, context.depth_range(reflector)[1])
    return CaptureCameras(
        sides, (None, None), (reflector.map_size,), context.own_content(reflector)
    )
