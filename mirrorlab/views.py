"""Views: the ways a pass looks at the scene (the viewer, a mirror's capture camera, a
cube face, the world seen through a stencil mirror), as numpy matrices.

A :class:`View` is everything a pass needs to draw the scene from somewhere: a rigid
world-to-eye ``view``, a ``projection`` (which may flip x, for the world seen in a
mirror), the target ``size``, the eye's world position (None for an orthographic
view) and an optional world-space ``clip_plane``. Numpy only.
"""

from __future__ import annotations

import functools
from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property

import numpy as np

from mirrorlab import culling, math3d
from mirrorlab.envmap import CUBE_FACE_NAMES
from mirrorlab.scene.model import Camera, CurvedReflector, OrthoCapture, PlanarReflector

_FLIP_X = np.diag([-1.0, 1.0, 1.0, 1.0])
_BIAS = np.array([[0.5, 0, 0, 0.5], [0, 0.5, 0, 0.5], [0, 0, 0.5, 0.5], [0, 0, 0, 1.0]])
"""Clip space [-1, 1] to texture space [0, 1]."""

CUBE_FACE_AXES = (
    # (look direction, up) per face in GL order +X, -X, +Y, -Y, +Z, -Z: with these, the
    # target's x and y run along the face's s and t as the cube-map spec's table has them
    # (+X: s along -z, t along -y; ...), so a copy of the target is the face as it is.
    ((1.0, 0.0, 0.0), (0.0, -1.0, 0.0)),
    ((-1.0, 0.0, 0.0), (0.0, -1.0, 0.0)),
    ((0.0, 1.0, 0.0), (0.0, 0.0, 1.0)),
    ((0.0, -1.0, 0.0), (0.0, 0.0, -1.0)),
    ((0.0, 0.0, 1.0), (0.0, -1.0, 0.0)),
    ((0.0, 0.0, -1.0), (0.0, -1.0, 0.0)),
)
CULL_TESTS_KEPT = 8
"""Scissors whose culling test (:meth:`View.cull_test`) a view keeps."""


@dataclass(frozen=True)
class Warp:
    """How a view whose projection is not a matrix places what it draws: a function of
    the vertex stage (a hemisphere's paraboloid, ...), written in GLSL.

    ``shader`` names the package shader file that stands in for ``warp.glsl`` in every
    program that draws the view (:meth:`mirrorlab.passes.base.SharedResources.program`):
    with ``WARP_VERTEX`` defined it gives ``vec4 project(mat4 view_projection, vec4
    point)``, the clip position of an origin-relative point from the view's matrix (it
    may lower ``gl_ClipDistance[0]``, which is on while a warped view is drawn, below
    what ``clip.glsl``'s ``clip_world`` wrote), else
    ``vec3 view_direction(mat3 eye_to_world, vec2 ndc)``, the world direction seen at a
    point of the target (the background's).

    A warped :class:`View` keeps a ``projection``: the matrix its warp's shader takes
    (with :attr:`View.relative_view`), whose clip volume holds everything the view can
    show, so that culling, which tests against it, errs large. A reflector's footprint
    in a warped view is the whole target. A warped view has no clip plane, and no mirror
    image: a reflector whose camera follows the viewer (a reflected or stencil mirror)
    has no camera from it and is drawn plain there.
    """

    shader: str


@dataclass(frozen=True, eq=False)
class View:
    """One way of looking at the scene.

    ``view`` ``(4, 4)`` rigid world-to-eye; ``projection`` ``(4, 4)``; ``size`` (width,
    height) of the target in pixels; ``eye`` ``(3,)`` world position of the viewpoint,
    None for an orthographic view (which looks along ``-z`` of its eye space);
    ``mirrored`` True when ``projection @ view`` turns counter-clockwise triangles
    clockwise (the world seen in a mirror); ``clip_plane`` ``(4,)`` world-space plane
    whose negative side is cut away, or None; ``label`` names the view in plans;
    ``depth_range`` the (near, far) clip distances its projection was made with (an
    oblique near plane then replaced near), None where unknown; ``warp`` how a view whose
    projection is not a matrix places what it draws (:class:`Warp`), None for a
    projection matrix.
    """

    view: np.ndarray
    projection: np.ndarray
    size: tuple[int, int]
    eye: np.ndarray | None
    label: str
    mirrored: bool = False
    clip_plane: np.ndarray | None = None
    depth_range: tuple[float, float] | None = None
    warp: Warp | None = None

    def __post_init__(self) -> None:
        if self.warp is not None and self.clip_plane is not None:
            raise ValueError(f"view {self.label!r}: a warped view takes no clip plane")

    @property
    def orthographic(self) -> bool:
        """Whether the view looks along its ``-z`` from everywhere, with no eye point: its
        projection is orthographic and it is not warped."""
        return self.warp is None and is_orthographic(self.projection)

    # What a view works out is kept, read-only: one view may be drawn in many frames
    # (camera_view gives a still camera's view again).

    @cached_property
    def view_projection(self) -> np.ndarray:
        return math3d.read_only(self.projection @ self.view)

    @cached_property
    def cull_planes(self) -> np.ndarray:
        """``(6, 4)`` or ``(7, 4)``: the view's clip volume (and clip plane) as planes of
        homogeneous world points (:func:`mirrorlab.culling.view_planes`)."""
        return math3d.read_only(culling.view_planes(self.view_projection, self.clip_plane))

    @cached_property
    def _cull_tests(self) -> dict:
        return {}

    def cull_test(self, scissor: tuple[int, int, int, int] | None = None) -> np.ndarray:
        """``(10, k)``: :func:`mirrorlab.culling.plane_test` of :attr:`cull_planes`, and of
        the sides of the pixel rectangle ``scissor`` when given
        (:func:`mirrorlab.culling.scissor_planes`); kept for the last few scissors."""
        tests = self._cull_tests
        held = tests.get(scissor)
        if held is None:
            planes = (
                self.cull_planes
                if scissor is None
                else np.vstack(
                    [
                        self.cull_planes,
                        culling.scissor_planes(self.view_projection, self.size, scissor),
                    ]
                )
            )
            held = math3d.read_only(culling.plane_test(planes))
            if len(tests) >= CULL_TESTS_KEPT:
                del tests[next(iter(tests))]
            tests[scissor] = held
        return held

    @cached_property
    def origin(self) -> np.ndarray:
        """World point ``(3,)`` everything is drawn relative to (camera-relative
        rendering, see :meth:`relative`): the eye, or an orthographic view's camera
        position."""
        if self.eye is not None:
            return math3d.read_only(np.array(self.eye, dtype=np.float64))
        return math3d.read_only(eye_position(self.view))

    @cached_property
    def column_offset(self) -> np.ndarray:
        """``(2, 4, 4)``: :attr:`origin` where a part's model matrix, given by columns (as
        the packed draw's parts buffer holds it, beside its surface matrix), keeps its
        translation, 0 elsewhere: what is taken from a part's columns to make them
        origin-relative."""
        offset = np.zeros((2, 4, 4))
        offset[0, 3, :3] = self.origin
        return math3d.read_only(offset)

    @cached_property
    def relative_view_projection(self) -> np.ndarray:
        """``(4, 4)`` float64: :attr:`view_projection` for points given relative to
        :attr:`origin` (its translation is the eye's own, near zero), so that float32 on
        the GL side never holds a large world position."""
        return math3d.read_only(np.asarray(self.projection, dtype=np.float64) @ self.relative_view)

    @cached_property
    def uniforms(self) -> tuple[np.ndarray, tuple[float, float, float, float] | None]:
        """What a program draws the view with: :attr:`relative_view_projection` as float32
        ``(4, 4)`` (read-only) and the clip plane for origin-relative points
        (:meth:`relative_plane`), None without one; worked out once for a view."""
        matrix = math3d.read_only(self.relative_view_projection.astype(np.float32))
        plane = self.relative_plane(self.clip_plane)
        if plane is None:
            return matrix, None
        a, b, c, d = (float(v) for v in plane)
        return matrix, (a, b, c, d)

    @cached_property
    def relative_view(self) -> np.ndarray:
        """``(4, 4)``: the rigid :attr:`view` for points relative to :attr:`origin`."""
        return math3d.read_only(
            np.asarray(self.view, dtype=np.float64) @ math3d.translate(self.origin)
        )

    @cached_property
    def draw_key(self) -> tuple:
        """Equal for views that draw the same way, exactly (matrices, origin, clip plane,
        size): what a recorded draw of the view is kept by."""
        clip = None if self.clip_plane is None else np.asarray(self.clip_plane).tobytes()
        return (
            np.asarray(self.view).tobytes(),
            np.asarray(self.projection).tobytes(),
            self.origin.tobytes(),
            clip,
            self.size,
            self.warp,
        )

    def relative(self, model: np.ndarray) -> np.ndarray:
        """``model`` ``(4, 4)`` (object to world) composed in float64 with the move to
        :attr:`origin`: object to origin-relative world, ready for float32 upload."""
        return math3d.translate(-self.origin) @ np.asarray(model, dtype=np.float64)

    def relative_plane(self, plane: np.ndarray | None) -> np.ndarray | None:
        """A world plane ``(4,)`` for points relative to :attr:`origin` (None stays None)."""
        if plane is None:
            return None
        plane = np.asarray(plane, dtype=np.float64)
        return np.append(plane[:3], plane[3] + plane[:3] @ self.origin)

    @cached_property
    def forward(self) -> np.ndarray:
        """Unit world direction ``(3,)`` the view looks along."""
        return math3d.read_only(-np.asarray(self.view, dtype=np.float64)[2, :3])

    @cached_property
    def key(self) -> tuple:
        """Equal for views that draw the same picture (for reusing captures)."""
        clip = () if self.clip_plane is None else tuple(_rounded(self.clip_plane))
        return (
            tuple(_rounded(self.view).ravel()),
            tuple(_rounded(self.projection).ravel()),
            self.size,
            clip,
            self.warp,
        )

    @property
    def aspect(self) -> float:
        return self.size[0] / self.size[1]

    def texture_matrix(self) -> np.ndarray:
        """``(4, 4)``: world point to homogeneous texture coordinate of this view's image
        (for projective lookups of a capture drawn with it)."""
        return _BIAS @ self.view_projection


@functools.lru_cache(maxsize=64)
def projective_lookup(source: View, viewer: View) -> np.ndarray:
    """``(4, 4)`` float32, read-only: :meth:`View.texture_matrix` of the capture view
    ``source`` for points given relative to ``viewer``'s origin (composed in float64), the
    texture lookup of a surface ``viewer`` draws with what ``source`` captured; kept for
    the last few pairs (a still viewer's is the same every frame)."""
    lookup = source.texture_matrix() @ math3d.translate(viewer.origin)
    return math3d.read_only(lookup.astype(np.float32))


def _rounded(array: np.ndarray) -> np.ndarray:
    """``array`` rounded to 12 decimals; an entry too large for that (rounding would
    overflow: a needle-thin view's projection) is kept as it is, being a whole number."""
    array = np.asarray(array, dtype=np.float64)
    with np.errstate(over="ignore", invalid="ignore"):
        rounded = np.round(array, 12)
    return np.where(np.isfinite(rounded), rounded, array)


@functools.lru_cache(maxsize=64)
def _camera_matrices(camera: Camera, aspect: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``camera``'s view, projection and eye, worked out once (a still camera is the same
    every frame); read-only, as every caller shares them."""
    matrices = (camera.view(), camera.projection(aspect), np.asarray(camera.eye, dtype=np.float64))
    for matrix in matrices:
        matrix.flags.writeable = False
    return matrices


def camera_view(camera: Camera, size: Sequence[int], label: str = "camera") -> View:
    """The viewer's view of a ``size`` (width, height) target: the same :class:`View`
    object for the same camera, size and label (read-only, with what it works out
    kept), so a still camera's view is worked out once, not every frame."""
    return _camera_view(camera, (int(size[0]), int(size[1])), label)


@functools.lru_cache(maxsize=64)
def _camera_view(camera: Camera, size: tuple[int, int], label: str) -> View:
    view, projection, eye = _camera_matrices(camera, size[0] / size[1])
    return View(
        view=view,
        projection=projection,
        size=size,
        eye=eye,
        label=label,
        depth_range=camera.depth_range,
    )


def eye_position(view: np.ndarray) -> np.ndarray:
    """The eye's world position ``(3,)`` of a rigid world-to-eye ``view`` ``(4, 4)``."""
    view = np.asarray(view, dtype=np.float64)
    return -view[:3, :3].T @ view[:3, 3]


def is_orthographic(projection: np.ndarray) -> bool:
    """Whether ``projection``'s last row is (0, 0, 0, 1), within ``np.allclose``'s
    default tolerances (written out: allclose cost more than planning a view)."""
    x, y, z, w = (float(v) for v in np.asarray(projection)[3])
    return max(abs(x), abs(y), abs(z)) <= 1e-8 and abs(w - 1.0) <= 1e-8 + 1e-5


@functools.lru_cache(maxsize=64)
def mirrored_eye(view: View, reflector: PlanarReflector) -> np.ndarray | None:
    """``view``'s eye ``(3,)`` reflected in ``reflector``'s plane (read-only; None for a
    view without an eye), kept for the last few: a still viewer's is the same every
    frame."""
    if view.eye is None:
        return None
    reflection = math3d.reflection_matrix(reflector.plane)
    return math3d.read_only(math3d.transform_points(reflection, view.eye)[:3])


def _mirror_of(view: View, reflector: PlanarReflector) -> tuple[np.ndarray, np.ndarray | None]:
    """The rigid view of ``view`` reflected in ``reflector``'s plane (``F @ view @ R``, F
    flipping the eye's x so the matrix stays a rotation) and the reflected eye."""
    mirrored = _FLIP_X @ view.view @ math3d.reflection_matrix(reflector.plane)
    return mirrored, mirrored_eye(view, reflector)


def _reaching(
    projection: np.ndarray, view: View, far: float | None
) -> tuple[np.ndarray, tuple[float, float] | None]:
    """``projection`` (of a view derived from ``view``) with its far plane moved to ``far``
    (a perspective one, when ``far`` is given; its near is ``view``'s), and the range."""
    if far is None or view.depth_range is None or is_orthographic(projection):
        return projection, view.depth_range
    near = min(view.depth_range[0], 0.5 * far)
    return math3d.with_depth_range(projection, near, far), (near, far)


def reflected_capture_view(
    view: View,
    reflector: PlanarReflector,
    size: tuple[int, int] | None = None,
    far: float | None = None,
) -> View | None:
    """The capture camera of a ``reflected`` mirror for ``view``: the view reflected in the
    mirror's plane, its far plane at ``far`` (default: ``view``'s) and its near plane moved
    onto the glass (Lengyel's oblique projection), drawn at ``size`` (default:
    ``view``'s). Its :meth:`View.texture_matrix` maps a point on the glass to where
    ``view`` sees it. None when the viewer is in or behind the mirror's plane, where no
    such camera exists (nothing of the glass's front is seen). The same (read-only)
    :class:`View` object for the same view, mirror, size and far plane: a still viewer's
    capture camera is worked out once.
    """
    return _reflected_capture_view(
        view,
        reflector,
        None if size is None else (int(size[0]), int(size[1])),
        None if far is None else float(far),
    )


@functools.lru_cache(maxsize=64)
def _reflected_capture_view(
    view: View, reflector: PlanarReflector, size: tuple[int, int] | None, far: float | None
) -> View | None:
    plane = reflector.plane
    rigid, eye = _mirror_of(view, reflector)
    # Flip clip-space x back as well: the capture keeps view's winding, and x runs the
    # other way across the image, which the projective lookup undoes.
    projection, depth_range = _reaching(_FLIP_X @ view.projection @ _FLIP_X, view, far)
    plane_in_eye = plane @ np.linalg.inv(rigid)
    try:
        projection = math3d.oblique_projection(projection, plane_in_eye)
    except ValueError:
        return None
    if not np.all(np.isfinite(projection)):
        return None
    return View(
        view=rigid,
        projection=projection,
        size=size or view.size,
        eye=eye,
        label=f"{reflector.name} seen from {view.label}",
        mirrored=view.mirrored,
        depth_range=depth_range,
    )


def stencil_view(view: View, reflector: PlanarReflector, far: float | None = None) -> View:
    """The world seen in a stencil mirror from ``view``: drawn straight into ``view``'s
    target through ``view_projection @ reflection`` (its far plane at ``far``, default
    ``view``'s), clipped by the mirror's plane. The same (read-only) :class:`View` object
    for the same view, mirror and far plane, as :func:`reflected_capture_view`."""
    return _stencil_view(view, reflector, None if far is None else float(far))


@functools.lru_cache(maxsize=64)
def _stencil_view(view: View, reflector: PlanarReflector, far: float | None) -> View:
    rigid, eye = _mirror_of(view, reflector)
    projection, depth_range = _reaching(view.projection @ _FLIP_X, view, far)
    return View(
        view=rigid,
        projection=projection,
        size=view.size,
        eye=eye,
        label=f"{reflector.name} (stencil) in {view.label}",
        mirrored=not view.mirrored,
        clip_plane=reflector.plane,
        depth_range=depth_range,
    )


@functools.lru_cache(maxsize=64)
def _ortho_matrices(capture: OrthoCapture) -> tuple[np.ndarray, np.ndarray]:
    """An ortho capture camera's view and projection, worked out once (read-only)."""
    matrices = (capture.view(), capture.projection())
    for matrix in matrices:
        matrix.flags.writeable = False
    return matrices


def ortho_capture_view(reflector: PlanarReflector, size: tuple[int, int]) -> View:
    """The ``ortho`` technique's capture camera (the lab's pass 1) on a ``size`` target
    (one :class:`View` object for the same capture, size and name, as
    :func:`camera_view`)."""
    return _ortho_capture_view(
        reflector.ortho_capture, (int(size[0]), int(size[1])), reflector.name
    )


@functools.lru_cache(maxsize=64)
def _ortho_capture_view(capture: OrthoCapture, size: tuple[int, int], name: str) -> View:
    view, projection = _ortho_matrices(capture)
    return View(
        view=view, projection=projection, size=size, eye=None, label=f"{name} ortho capture"
    )


def cube_face_views(
    reflector: CurvedReflector, depth_range: tuple[float, float], size: int | None = None
) -> list[View]:
    """The six 90-degree views of a live cube map from the reflector's capture centre,
    with clip distances ``depth_range`` (near, far; see
    :func:`mirrorlab.bounds.cube_depth_range`), ``size`` texels a side (default: the
    reflector's map size)."""
    center = reflector.center()
    near, far = depth_range
    projection = math3d.perspective(90.0, 1.0, near, far)
    edge = reflector.map_size if size is None else int(size)
    face_size = (edge, edge)
    views = []
    for name, (direction, up) in zip(CUBE_FACE_NAMES, CUBE_FACE_AXES, strict=True):
        view = math3d.look_at(center, center + np.asarray(direction), up)
        views.append(
            View(
                view=view,
                projection=projection,
                size=face_size,
                eye=center,
                label=f"{reflector.name} cube {name}",
                depth_range=(float(near), float(far)),
            )
        )
    return views
