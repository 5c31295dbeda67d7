"""The scene as data: camera, background, lights, objects, reflectors and animation.

Every class here is a frozen dataclass of plain values (floats, tuples, paths), so a
scene compares by value, can be written back to TOML (:mod:`mirrorlab.scene.loader`)
and is changed by making a new one (:func:`dataclasses.replace`, or the ``with_*``
helpers). Files named by a scene (meshes, textures, cube faces) are absolute paths.

World units; y is up; angles in degrees; colours linear RGB in [0, 1]. Numpy only: no
OpenGL is imported here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from functools import cached_property
from pathlib import Path
from typing import ClassVar, Literal

import numpy as np

from mirrorlab import math3d

Vec3 = tuple[float, float, float]

CAPTURE_MODES = ("copy", "fbo")
"""How a planar capture reaches its texture: ``glCopyTexImage2D`` (the lab) or drawn
straight into it through a framebuffer."""

DEFAULT_PLAIN_COLOR: Vec3 = (0.6, 0.6, 0.62)
"""Albedo of a reflector drawn as a plain, lit surface (bounce depth used up)."""
DEFAULT_BACKING: Vec3 = (0.33, 0.3, 0.27)
"""Unlit colour of a planar mirror's back face."""


NEAR_MARGIN = 1e-4
"""How far (a share of ``near``) a camera's clipping near plane lies before ``near``."""


@dataclass(frozen=True)
class Camera:
    """A perspective viewer. ``fovy`` is the vertical field of view in degrees; ``near``
    and ``far`` are the clip distances in world units."""

    eye: Vec3 = (12.0, 5.0, 9.0)
    target: Vec3 = (-3.5, 1.0, -2.0)
    up: Vec3 = (0.0, 1.0, 0.0)
    fovy: float = 45.0
    near: float = 0.1
    far: float = 100.0

    def view(self) -> np.ndarray:
        """World-to-eye ``(4, 4)``; ValueError when the eye is its target."""
        return math3d.look_at(self.eye, self.target, self.up)

    def projection(self, aspect: float) -> np.ndarray:
        """``(4, 4)`` perspective for a width / height ``aspect``.

        Its near plane lies :data:`NEAR_MARGIN` of ``near`` closer to the eye than
        ``near``: a surface exactly at the near distance (a viewer placed exactly
        ``near`` from a mirror) is then in front of the plane by far more than float
        rounding, so it is drawn, and traced, the same way every time."""
        return math3d.perspective(self.fovy, aspect, *self.depth_range)

    @property
    def depth_range(self) -> tuple[float, float]:
        """The (near, far) clip distances of :meth:`projection`: near moved in by
        :data:`NEAR_MARGIN`."""
        return (self.near * (1.0 - NEAR_MARGIN), self.far)


@dataclass(frozen=True)
class Transform:
    """Placement of an object: scaled by ``scale`` ``(3,)``, turned by ``rotation``
    (degrees about x, then y, then z) and moved to ``position``."""

    position: Vec3 = (0.0, 0.0, 0.0)
    rotation: Vec3 = (0.0, 0.0, 0.0)
    scale: Vec3 = (1.0, 1.0, 1.0)

    def matrix(self) -> np.ndarray:
        """Object frame to world, ``(4, 4)``, read-only (worked out once: a moving part's
        frames keep the transforms of the parts that stay)."""
        return self._matrix

    @cached_property
    def _matrix(self) -> np.ndarray:
        rx, ry, rz = self.rotation
        turn = (
            math3d.rotate(rz, (0, 0, 1))
            @ math3d.rotate(ry, (0, 1, 0))
            @ math3d.rotate(rx, (1, 0, 0))
        )
        matrix = math3d.translate(self.position) @ turn @ math3d.scale(self.scale)
        matrix.flags.writeable = False
        return matrix


@dataclass(frozen=True)
class Light:
    """A directional light: ``direction`` points from the scene towards it."""

    direction: Vec3 = (0.45, 0.8, 0.4)
    intensity: float = 0.7
    color: Vec3 = (1.0, 1.0, 1.0)


BackgroundKind = Literal["color", "sky", "cube_faces", "sphere_map"]


@dataclass(frozen=True)
class Background:
    """What lies beyond every object: a plain ``color``; the procedural ``sky``; six
    pictures in the folder ``path`` (``cube_faces``); or the picture ``path`` used as a
    sphere map (``sphere_map``: the textbook's way), seen with the orientation of
    ``sphere_map_camera``. The colour is also what a capture is cleared to."""

    kind: BackgroundKind = "color"
    color: Vec3 = (0.16, 0.18, 0.22)
    path: Path | None = None
    sphere_map_camera: Camera | None = None

    @property
    def is_environment(self) -> bool:
        """True when the background varies with direction (drawn as a sky, reflected by
        environment maps); False for a plain colour."""
        return self.kind != "color"


@dataclass(frozen=True)
class MeshObject:
    """A lit mesh from any file trimesh reads, ``color`` multiplied by ``texture`` (a
    picture) when there is one. Left None, each comes from a glTF file's own material
    (its base colour factor and base colour texture), else white and no texture."""

    name: str
    mesh: Path
    transform: Transform = Transform()
    color: Vec3 | None = None
    texture: Path | None = None


@dataclass(frozen=True)
class RobotObject:
    """The lab's robot arm (:mod:`mirrorlab.scene.robot`): base, lower-arm and upper-arm
    joint ``angles`` in degrees, the whole arm placed by ``transform``."""

    name: str = "robot"
    angles: Vec3 = (-35.0, 30.0, -75.0)
    transform: Transform = Transform()


SceneObject = MeshObject | RobotObject


@dataclass(frozen=True)
class OrthoCapture:
    """The orthographic capture camera of an ``ortho`` mirror (the lab's pass 1):
    ``extents`` are glOrtho's (left, right, bottom, top, near, far)."""

    eye: Vec3
    target: Vec3
    up: Vec3
    extents: tuple[float, float, float, float, float, float]

    def view(self) -> np.ndarray:
        return math3d.look_at(self.eye, self.target, self.up)

    def projection(self) -> np.ndarray:
        return math3d.ortho(*self.extents)


FOOTPRINT_TEXTURE = "footprint"
"""The ``texture_size`` that sizes a capture to the mirror's footprint in the view it is
seen in (rounded up to :data:`FOOTPRINT_STEP` pixels), for a technique whose capture
camera is its own (``ortho``): its capture does not follow the viewer, only its size
does."""
FOOTPRINT_STEP = 16
"""A footprint-sized capture's sides are multiples of this many pixels: a viewer moving
a little keeps the capture's size, and the capture."""


SSR_NO_PROBE = "none"
"""The ``probe`` of :class:`ScreenSpace` that falls back to nothing: a ray the screen
holds no answer for shows the background's colour (to measure what a probe earns)."""


@dataclass(frozen=True)
class ScreenSpace:
    """How screen-space reflections (technique ``ssr``) march and where they fall back
    (:mod:`mirrorlab.screen_space` holds the march's numpy reference and the defaults'
    reasons).

    ``probe`` names the technique a ray the screen holds no answer for is looked up in
    (any curved technique: ``cube-live``, ``cube``, ``latlong``, ...; or
    :data:`SSR_NO_PROBE`); ``stride`` is the pixels between the march's samples along the
    ray's longer screen axis; ``steps`` the most samples a ray takes; ``thickness`` how
    far behind the surface seen at a pixel a ray may pass and still meet it, as a share
    of that surface's distance from the eye; ``max_distance`` how far a ray is followed
    in world units (0: until it leaves the view); ``refine`` the halvings that narrow a
    hit down; ``edge_fade`` the share of the screen's smaller side over which hits near
    its edges blend into the probe."""

    probe: str = "cube-live"
    stride: float = 1.0
    steps: int = 256
    thickness: float = 0.02
    max_distance: float = 0.0
    refine: int = 4
    edge_fade: float = 0.03


@dataclass(frozen=True)
class PlanarReflector:
    """A flat four-cornered mirror. ``corners`` ``(4, 3)`` run counter-clockwise seen
    from the reflecting side. ``technique`` names a planar technique of
    :mod:`mirrorlab.techniques`;
    ``capture`` one of :data:`CAPTURE_MODES`; ``texture_size`` the capture's square side
    in pixels (None: the size of the view it is seen in, as in the lab; ``"footprint"``,
    for a technique with a camera of its own: the size of the pixel rectangle its glass
    covers in that view, see :data:`FOOTPRINT_TEXTURE`). ``ortho`` is the
    capture camera of the ``ortho`` technique (None: one derived from the corners, see
    :func:`ortho_capture_for`). ``color`` is its plain look when bounces run out;
    ``backing`` the unlit colour of its back.

    A technique that falls back to a map (``ssr``: :class:`ScreenSpace`, its settings in
    ``ssr``) reads that map's settings from ``map_size``, ``source``, ``capture_center``
    (a live map's capture point, from the mirror's centre, in world axes that turn with
    the mirror) and ``parallax``, as a curved reflector's own map has them."""

    name: str
    corners: tuple[Vec3, Vec3, Vec3, Vec3]
    technique: str = "reflected"
    capture: str = "copy"
    texture_size: int | Literal["footprint"] | None = None
    ortho: OrthoCapture | None = None
    color: Vec3 = DEFAULT_PLAIN_COLOR
    backing: Vec3 = DEFAULT_BACKING
    map_size: int = 256
    source: Path | None = None
    capture_center: Vec3 = (0.0, 0.0, 0.0)
    parallax: Parallax | None = None
    ssr: ScreenSpace | None = None

    kind: ClassVar[Literal["planar"]] = "planar"

    @cached_property
    def corner_array(self) -> np.ndarray:
        """``(4, 3)`` float64 corners."""
        return np.asarray(self.corners, dtype=np.float64)

    @cached_property
    def normal(self) -> np.ndarray:
        """Unit normal ``(3,)`` on the reflecting side."""
        c = self.corner_array
        n = np.cross(c[1] - c[0], c[2] - c[0]) + np.cross(c[2] - c[0], c[3] - c[0])
        return n / np.linalg.norm(n)

    @cached_property
    def center(self) -> np.ndarray:
        return self.corner_array.mean(axis=0)

    @cached_property
    def plane(self) -> np.ndarray:
        """``(4,)`` plane, positive on the reflecting side."""
        return math3d.plane_through(self.center, self.normal)

    @cached_property
    def ortho_capture(self) -> OrthoCapture:
        """The ``ortho`` technique's capture camera: :attr:`ortho` or the derived one."""
        return (
            self.ortho
            if self.ortho is not None
            else ortho_capture_for(self.corner_array, self.normal)
        )

    def moved(self, position: Vec3 | None = None, rotation: Vec3 | None = None) -> PlanarReflector:
        """The mirror turned by ``rotation`` (degrees about x, then y, then z, as a
        :class:`Transform`'s) about its centre, then moved so that its centre is at
        ``position`` (default: where it is); its corners, and an ``ortho`` capture camera
        given with it, follow. A keyframe poses a planar mirror this way, from the place
        its scene file gives it."""
        center = self.center
        turn = Transform(rotation=rotation or (0.0, 0.0, 0.0)).matrix()[:3, :3]
        goal = center if position is None else np.asarray(position, dtype=np.float64)

        def place(point) -> Vec3:
            return _vec(goal + turn @ (np.asarray(point, dtype=np.float64) - center))

        corners = tuple(place(c) for c in self.corner_array)
        offset = _vec(turn @ np.asarray(self.capture_center, dtype=np.float64))
        ortho = self.ortho
        if ortho is not None:
            ortho = replace(
                ortho,
                eye=place(ortho.eye),
                target=place(ortho.target),
                up=_vec(turn @ np.asarray(ortho.up, dtype=np.float64)),
            )
        return replace(
            self,
            corners=corners,  # type: ignore[arg-type]
            ortho=ortho,
            capture_center=offset,
        )

    def probe_center(self) -> np.ndarray:
        """World position ``(3,)`` a live probe map of the mirror is captured from: its
        centre moved by :attr:`capture_center`."""
        return self.center + np.asarray(self.capture_center, dtype=np.float64)

    def texcoords(self) -> np.ndarray:
        """``(4, 2)`` texture coordinates of the corners in the ortho capture: where the
        capture camera's extents put each corner (the lab's (0,0), (0,1), (1,1), (1,0))."""
        capture = self.ortho_capture
        clip = math3d.transform_points(capture.projection() @ capture.view(), self.corner_array)
        return (clip[:, :2] / clip[:, 3:4] + 1.0) / 2.0


ORTHO_DEPTH = 15.0
"""How far in front of the glass a derived orthographic capture sees (the lab's far)."""


def ortho_capture_for(corners: np.ndarray, normal: np.ndarray) -> OrthoCapture:
    """An orthographic camera on the mirror's plane looking out along ``normal`` whose
    box is exactly the mirror: the lab's capture generalised to any mirror."""
    center = corners.mean(axis=0)
    height_axis = corners[1] - corners[0]
    up = height_axis / np.linalg.norm(height_axis)
    view = math3d.look_at(center, center + normal, up)
    local = math3d.transform_points(view, corners)[:, :2]
    left, bottom = local.min(axis=0)
    right, top = local.max(axis=0)
    return OrthoCapture(
        eye=_vec(center),
        target=_vec(center + normal),
        up=_vec(up),
        extents=(float(left), float(right), float(bottom), float(top), 0.0, ORTHO_DEPTH),
    )


PARALLAX_PROXIES = ("box", "sphere", "distance")
"""How a ``cube-live`` lookup can correct for surroundings that are not far away (see
:mod:`mirrorlab.parallax`)."""


@dataclass(frozen=True)
class BoxProxy:
    """The surroundings as an axis-aligned box (a room): world corners ``min`` and ``max``."""

    min: Vec3
    max: Vec3

    kind = "box"


@dataclass(frozen=True)
class SphereProxy:
    """The surroundings as a sphere of ``radius`` (world units) around the capture centre."""

    radius: float

    kind = "sphere"


@dataclass(frozen=True)
class DistanceSearch:
    """The capture also keeps each texel's distance; the lookup searches the reflected
    ray in ``steps`` linear steps, with ``secant`` secant steps at each crossing of the
    stored surface, which counts as a hit when the ray lies within ``thickness`` of it
    (relative to the distance; else the ray passed behind an object; with no secant
    steps every crossing is a hit)."""

    steps: int = 8
    secant: int = 2
    thickness: float = 0.1

    kind = "distance"


Parallax = BoxProxy | SphereProxy | DistanceSearch


@dataclass(frozen=True)
class CurvedReflector:
    """An environment-mapped mesh. ``technique`` names a curved technique of
    :mod:`mirrorlab.techniques`;
    ``map_size`` the map's side in texels; ``source`` a picture used as the sphere map
    as it is, or a folder of six cube faces for ``cube`` (None: baked from the
    background); ``capture_center`` the point, in the mesh's own frame, a live cube
    map is captured from; ``parallax`` (``cube-live`` only) how its lookups correct for
    nearby surroundings (None: everything is taken as infinitely far away); ``ssr`` the
    settings of screen-space reflections (technique ``ssr``; None: the defaults), whose
    probe map is this reflector's own (``map_size``, ``source``, ``capture_center``,
    ``parallax``)."""

    name: str
    mesh: Path
    transform: Transform = Transform()
    technique: str = "cube-live"
    map_size: int = 256
    source: Path | None = None
    capture_center: Vec3 = (0.0, 0.0, 0.0)
    color: Vec3 = DEFAULT_PLAIN_COLOR
    parallax: Parallax | None = None
    ssr: ScreenSpace | None = None

    kind: ClassVar[Literal["curved"]] = "curved"

    def model_matrix(self) -> np.ndarray:
        return self.transform.matrix()

    def center(self) -> np.ndarray:
        """World position ``(3,)`` of :attr:`capture_center`."""
        return math3d.transform_points(self.model_matrix(), np.asarray(self.capture_center))[:3]


Reflector = PlanarReflector | CurvedReflector


@dataclass(frozen=True)
class Keyframe:
    """Values set at ``frame``: ``camera`` maps camera fields to values; ``objects`` and
    ``reflectors`` map a name to its fields (position, rotation, scale; angles for a
    robot; a planar mirror's position and rotation, see :meth:`PlanarReflector.moved`).
    A field moves linearly between the keyframes that set it and holds its value before
    the first and after the last."""

    frame: int
    camera: dict = field(default_factory=dict)
    objects: dict = field(default_factory=dict)
    reflectors: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Animation:
    """``frames`` frames (numbered from 0) posed by ``keyframes``, in frame order."""

    frames: int
    keyframes: tuple[Keyframe, ...]


@dataclass(frozen=True)
class Scene:
    """A whole scene: what the renderer, the planner, the ray tracer and the demo need.

    ``max_bounces`` is how deep reflections of reflections go (0 draws reflectors as
    plain surfaces; 1 shows each reflector with the scene and the others plain). ``source``
    is the file the scene was read from (not compared)."""

    name: str
    camera: Camera = Camera()
    background: Background = Background()
    ambient: float = 0.3
    lights: tuple[Light, ...] = (Light(),)
    objects: tuple[SceneObject, ...] = ()
    reflectors: tuple[Reflector, ...] = ()
    max_bounces: int = 1
    animation: Animation | None = None
    description: str = ""
    source: Path | None = field(default=None, compare=False)

    # ----------------------------------------------------------------- look-ups

    def object(self, name: str) -> SceneObject:
        for item in self.objects:
            if item.name == name:
                return item
        raise KeyError(
            f"scene {self.name!r} has no object {name!r}; objects are "
            f"{', '.join(o.name for o in self.objects) or 'none'}"
        )

    def reflector(self, name: str) -> Reflector:
        for item in self.reflectors:
            if item.name == name:
                return item
        raise KeyError(
            f"scene {self.name!r} has no reflector {name!r}; reflectors are "
            f"{', '.join(r.name for r in self.reflectors) or 'none'}"
        )

    @property
    def robot(self) -> RobotObject | None:
        """The first robot of the scene, or None."""
        return next((o for o in self.objects if isinstance(o, RobotObject)), None)

    def content_key(self) -> tuple:
        """Everything a capture shows but the viewer: equal keys, equal captures."""
        return (
            self.background,
            self.ambient,
            self.lights,
            self.objects,
            self.reflectors,
            self.max_bounces,
        )

    @property
    def frame_count(self) -> int:
        """Frames in the animation (1 for a still scene)."""
        return self.animation.frames if self.animation else 1

    # ----------------------------------------------------------------- changes

    def with_object(self, name: str, **changes) -> Scene:
        """The scene with object ``name``'s fields replaced."""
        self.object(name)
        return replace(
            self,
            objects=tuple(replace(o, **changes) if o.name == name else o for o in self.objects),
        )

    def with_reflector(self, name: str, **changes) -> Scene:
        """The scene with reflector ``name``'s fields replaced."""
        self.reflector(name)
        return replace(
            self,
            reflectors=tuple(
                replace(r, **changes) if r.name == name else r for r in self.reflectors
            ),
        )

    def with_angles(self, angles) -> Scene:
        """The scene with its robot posed at ``angles`` (base, lower, upper degrees)."""
        robot = self.robot
        if robot is None:
            raise ValueError(f"scene {self.name!r} has no robot to pose")
        values = tuple(float(a) for a in angles)
        if len(values) != 3 or not all(math.isfinite(v) for v in values):
            raise ValueError(
                f"angles must be 3 finite numbers (base, lower, upper), got {angles!r}"
            )
        return self.with_object(robot.name, angles=values)

    def to_toml(self) -> str:
        """The scene as a scene file's text; reading it back gives an equal scene (file
        names are written relative to the scene's own file, see
        :func:`mirrorlab.scene.loader.dumps`)."""
        from mirrorlab.scene.loader import dumps

        return dumps(self)

    def at_frame(self, frame: int) -> Scene:
        """The scene posed for animation frame ``frame`` (the scene itself when still)."""
        if self.animation is None:
            return self
        if not 0 <= frame < self.animation.frames:
            raise ValueError(
                f"frame {frame} is outside the animation's 0...{self.animation.frames - 1}"
            )
        from mirrorlab.scene.animation import pose

        return pose(self, frame)


def _vec(values) -> Vec3:
    x, y, z = (float(v) for v in values)
    return (x, y, z)
