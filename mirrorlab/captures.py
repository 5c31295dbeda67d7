"""The shipped techniques' capture cameras: where each technique that shows the scene
looks from, for one reflector seen in one view (a :data:`mirrorlab.plan.CaptureCamera`
each, named by its registry entry's ``capture_camera``). The camera math itself is in
:mod:`mirrorlab.views`; these choose the cameras, the part of each target that is ever
read (its scissor) and what of the cameras the texture depends on (its key). Numpy only.

A technique of another kind names a function of its own (in its own module), with the
same signature; the planner calls it, not knowing which technique it serves.
"""

from __future__ import annotations

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
    glass is ever sampled). None where the viewer is behind the mirror's plane."""
    assert isinstance(reflector, PlanarReflector)
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
) -> CaptureCameras:
    """The ``stencil`` technique (inline): the world seen in the mirror, drawn straight
    into ``view``'s target (:func:`~mirrorlab.views.stencil_view`), scissored to where
    the glass shows within ``view``'s own scissor. It makes no texture, so no key."""
    assert isinstance(reflector, PlanarReflector)
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
