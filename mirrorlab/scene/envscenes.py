"""The built-in environment-mapping scenes, in numpy: no OpenGL here.

- ``cone``: the textbook's sphere-mapping experiment (Guha 13.6): a reflective
  rocket cone hanging in front of a picture of a rocket launch; the picture is
  also the cone's sphere map, so moving the cone changes what it reflects.
- ``sphere``: a reflective sphere inside a procedural sky (:func:`sky_environment`)
  with a few lit objects around it, which only a live cube map (or the ray
  tracer) shows in the reflection.

The environment-mapped object (the :class:`Reflector`) is kept out of the scene
graph, like the lab's mirror, so the ordinary scene drawer never draws it.
World units; y is up.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from mirrorlab import math3d
from mirrorlab.scene.graph import Node, SceneGraph
from mirrorlab.scene.mesh import load_texture
from mirrorlab.scene.robot import Camera

Environment = Callable[[np.ndarray], np.ndarray]
"""``env(directions (n, 3) unit, world) -> (n, 3)`` float RGB in [0, 1]: what lies
infinitely far away in each direction."""

ENV_SCENES = ("cone", "sphere")
"""The built-in scenes by name."""

ENVMAP_METHODS = ("sphere", "sphere-vertex", "sphere-texgen", "cube", "cube-live", "latlong",
                  "normal")
"""Every environment-mapping technique by name: ``sphere`` (sphere map per fragment),
``sphere-vertex`` (per vertex, in a shader), ``sphere-texgen`` (fixed-function
GL_SPHERE_MAP texgen, per vertex), ``cube`` (static cube map baked from the
environment), ``cube-live`` (six captures from the reflector's centre), ``latlong``
(Blinn-Newell latitude-longitude map, per fragment), ``normal`` ("demo style": the
map indexed by the eye-space normal's x and y)."""

CONE_CAMERA = Camera(eye=(0.0, 1.0, 7.0), target=(0.0, 0.6, 0.0), fovy=45.0, near=0.5,
                     far=60.0)
SPHERE_CAMERA = Camera(eye=(1.3, 2.0, 7.4), target=(0.0, 0.1, 0.0), fovy=38.0, near=0.2,
                       far=60.0)
CONE_HEIGHT = 2.4
CONE_TILT = 50.0
"""Degrees the cone is turned about x, from apex-up towards the viewer: like a nose cone
flying at the camera, its normals then face every way around and it reflects the whole
picture."""
CONE_LIMITS = (-2.0, 1.8)
"""Lowest and highest y of the cone's base in the cone scene (the demo's arrow keys)."""


@dataclass
class Reflector:
    """The environment-mapped object: ``mesh`` names ``models/<mesh>.obj``; the mesh is
    scaled uniformly by ``scale``, turned by ``rotation`` ``(4, 4)`` and moved to
    ``position`` ``(3,)`` (world units). ``local_center`` ``(3,)`` is the point, in the
    mesh's own frame, from which a live cube map is captured."""

    mesh: str
    position: np.ndarray
    scale: float = 1.0
    rotation: np.ndarray = field(default_factory=math3d.identity)
    local_center: np.ndarray = field(default_factory=lambda: np.zeros(3))

    def model_matrix(self) -> np.ndarray:
        """Mesh frame to world, ``(4, 4)``."""
        return (math3d.translate(self.position) @ self.rotation
                @ math3d.scale((self.scale,) * 3))

    def center(self) -> np.ndarray:
        """World position ``(3,)`` of :attr:`local_center` (the cube-capture point)."""
        return math3d.transform_points(self.model_matrix(), self.local_center)[:3]


@dataclass
class EnvScene:
    """An environment-mapping scene.

    ``graph`` holds the lit objects (drawn by the scene drawer, never the
    reflector); ``environment`` is the distant surroundings as a function of
    direction; ``camera`` the default viewer. ``sphere_texture``, when set,
    names a picture in ``textures/`` used as the sphere map exactly as it is
    (the textbook's way); otherwise sphere maps are baked from ``environment``
    for the current view. Light as in :class:`mirrorlab.scene.robot.LabScene`.
    """

    name: str
    graph: SceneGraph
    reflector: Reflector
    environment: Environment
    camera: Camera
    light_direction: tuple[float, float, float] = (0.45, 0.8, 0.4)
    ambient: float = 0.3
    diffuse: float = 0.7
    sphere_texture: str | None = None
    _moves: int = 0

    @property
    def revision(self) -> int:
        """Grows whenever the graph changes or the reflector moves."""
        return self.graph.revision + self._moves

    def move_reflector(self, offset: Sequence[float]) -> None:
        """Move the reflector by ``offset`` ``(3,)`` world units."""
        delta = np.asarray(offset, dtype=np.float64)
        if delta.shape != (3,) or not np.all(np.isfinite(delta)):
            raise ValueError(f"reflector offset must be 3 finite numbers, got {offset!r}")
        if np.any(delta != 0.0):
            self.reflector.position = self.reflector.position + delta
            self._moves += 1


# ---------------------------------------------------------------------------------------
# the procedural sky of the sphere scene

SUN_DIRECTION = np.array([0.45, 0.55, -0.70]) / np.linalg.norm([0.45, 0.55, -0.70])
_BALLOONS = (  # direction, colour, angular radius (rad): markers that show orientation
    ((1.0, 0.35, 0.2), (0.95, 0.15, 0.12), 0.16),
    ((-0.3, 0.45, 1.0), (0.15, 0.8, 0.25), 0.14),
    ((-1.0, 0.2, -0.45), (0.2, 0.3, 0.95), 0.15),
    ((0.1, 0.95, 0.1), (0.95, 0.85, 0.15), 0.2),
    ((0.2, -0.35, 1.0), (0.85, 0.2, 0.85), 0.15),
)


def _smoothstep(edge0: float, edge1: float, x: np.ndarray) -> np.ndarray:
    t = np.clip((x - edge0) / (edge1 - edge0), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def sky_environment(directions: np.ndarray) -> np.ndarray:
    """The sphere scene's surroundings: sky, sun, coloured balloons, hills along the
    horizon and a soft checkered ground. ``directions`` ``(n, 3)`` (normalised here),
    world, y up; returns ``(n, 3)`` float64 RGB in [0, 1].

    Every feature has soft edges (a few hundredths of a radian) so that one ray per
    pixel and a filtered texture lookup see the same colours.
    """
    d = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
    d = d / np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-12)
    x, y, z = d[:, 0], d[:, 1], d[:, 2]
    elevation = np.arcsin(np.clip(y, -1.0, 1.0))
    azimuth = np.arctan2(z, x)
    # sky: pale at the horizon, deep blue at the zenith
    k = np.sqrt(np.clip(y, 0.0, 1.0))[:, None]
    color = (1 - k) * np.array([0.86, 0.88, 0.92]) + k * np.array([0.22, 0.42, 0.82])
    sun = np.exp(-((np.arccos(np.clip(d @ SUN_DIRECTION, -1, 1)) / 0.09) ** 2))[:, None]
    color = color * (1 - sun) + sun * np.array([1.0, 0.96, 0.8])
    for direction, balloon, radius in _BALLOONS:
        axis = np.asarray(direction) / np.linalg.norm(direction)
        angle = np.arccos(np.clip(d @ axis, -1.0, 1.0))
        a = (1.0 - _smoothstep(radius * 0.75, radius, angle))[:, None]
        color = color * (1 - a) + a * np.asarray(balloon)
    # hills: height varies with azimuth, colour cycles with azimuth
    hill_top = 0.1 + 0.06 * np.sin(3 * azimuth) + 0.035 * np.sin(7 * azimuth + 1.0)
    hill = (1.0 - _smoothstep(-0.015, 0.015, elevation - hill_top))[:, None]
    hue = azimuth[:, None] + np.array([0.0, 2.1, 4.2])
    hill_color = 0.3 + 0.18 * np.cos(hue) + 0.1 * (elevation[:, None] / 0.2)
    color = color * (1 - hill) + hill * hill_color
    # ground: a soft checker on the plane y = -1, fading into haze at the horizon
    t = 1.0 / np.maximum(-y, 1e-3)
    gx, gz = x * t, z * t
    checker = 0.5 + 0.5 * np.tanh(3.0 * np.sin(np.pi * gx / 2.0) * np.sin(np.pi * gz / 2.0))
    ground = (checker[:, None] * np.array([0.62, 0.55, 0.42])
              + (1 - checker[:, None]) * np.array([0.25, 0.32, 0.2]))
    haze = _smoothstep(0.0, 0.35, -y)[:, None]
    ground = haze * ground + (1 - haze) * np.array([0.5, 0.52, 0.5])
    below = _smoothstep(0.01, -0.01, elevation)[:, None]
    color = color * (1 - below) + below * ground
    return np.clip(color, 0.0, 1.0)


# ---------------------------------------------------------------------------------------
# the textbook's launch picture as the cone scene's surroundings


def image_sampler(image: np.ndarray) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """Bilinear, clamped lookup into ``image`` ``(h, w, 3)`` uint8 (row 0 at the top, t = 1
    there, as a GL texture shows it): ``sample(s, t)`` with ``(n,)`` arrays returns ``(n, 3)``
    float64 in [0, 1]."""
    rows = np.asarray(image, dtype=np.float64)[::-1] / 255.0  # row 0 at t = 0
    height, width = rows.shape[:2]

    def sample(s: np.ndarray, t: np.ndarray) -> np.ndarray:
        x = np.clip(np.asarray(s) * width - 0.5, 0.0, width - 1.0)
        y = np.clip(np.asarray(t) * height - 0.5, 0.0, height - 1.0)
        x0 = np.minimum(np.floor(x).astype(np.int64), width - 2)
        y0 = np.minimum(np.floor(y).astype(np.int64), height - 2)
        fx, fy = (x - x0)[:, None], (y - y0)[:, None]
        top = rows[y0, x0] * (1 - fx) + rows[y0, x0 + 1] * fx
        bottom = rows[y0 + 1, x0] * (1 - fx) + rows[y0 + 1, x0 + 1] * fx
        return top * (1 - fy) + bottom * fy

    return sample


def sphere_image_environment(image: np.ndarray, view: np.ndarray) -> Environment:
    """The surroundings that ``image`` shows when used as a sphere map seen with ``view``
    ``(4, 4)`` (world to eye): direction ``r`` looks up the image at ``sphere_map(R r)``,
    with ``R`` the view's rotation. With this, a sphere map baked from the environment for
    that view is the image again, and every other technique sees the same surroundings."""
    from mirrorlab.envmap import sphere_map

    rotation = np.asarray(view, dtype=np.float64)[:3, :3]
    sample = image_sampler(image)

    def environment(directions: np.ndarray) -> np.ndarray:
        d = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
        s, t = sphere_map(d @ rotation.T)
        return sample(np.asarray(s).reshape(-1), np.asarray(t).reshape(-1))

    return environment


# ---------------------------------------------------------------------------------------
# the scenes


def build_cone_scene(cone_height: float = 1.0) -> EnvScene:
    """The textbook experiment: the launch picture on a 16 x 16 backdrop at z = -8 filling
    the default view, and a reflective cone (base radius 1, height 2.4) pointing at the
    viewer and up (tilted :data:`CONE_TILT` from apex-up), the centre of its base at
    (0, ``cone_height``, 0). The picture is the cone's sphere map.

    The light shines straight at the backdrop, so with ambient + diffuse = 1 the picture
    shows with its own colours.
    """
    root = Node("world")
    root.add(Node("backdrop", offset=math3d.translate((0.0, 0.0, -8.0)), mesh="backdrop",
                  texture="launch"))
    reflector = Reflector(mesh="cone", position=np.array([0.0, float(cone_height), 0.0]),
                          rotation=math3d.rotate(CONE_TILT, (1.0, 0.0, 0.0)),
                          local_center=np.array([0.0, CONE_HEIGHT / 4.0, 0.0]))
    environment = sphere_image_environment(load_texture("launch"), CONE_CAMERA.view())
    return EnvScene(name="cone", graph=SceneGraph(root), reflector=reflector,
                    environment=environment, camera=CONE_CAMERA, light_direction=(0, 0, 1),
                    sphere_texture="launch")


SPHERE_OBJECTS = (
    # name, mesh, colour, texture, position, rotation (deg about y)
    ("pedestal", "base", (1.0, 1.0, 1.0), "metal", (0.0, -1.25, 0.0), 0.0),
    ("red_block", "hand", (0.9, 0.12, 0.1), None, (2.1, 0.1, 0.9), 30.0),
    ("blue_ball", "joint", (0.15, 0.35, 0.95), None, (-1.9, 0.9, 1.3), 0.0),
    ("yellow_pillar", "lower_arm", (0.95, 0.75, 0.15), None, (0.6, -1.25, -2.6), 20.0),
    ("green_block", "upper_arm", (0.2, 0.75, 0.3), None, (-2.4, -1.25, -1.0), -35.0),
)
"""The lit objects around the reflective sphere (radius 1 at the origin)."""


def build_sphere_scene(objects: bool = True) -> EnvScene:
    """A reflective sphere of radius 1 at the origin in :func:`sky_environment`, on a
    metal pedestal with four coloured objects around it (``objects=False`` leaves them
    all out, so that only the distant surroundings are reflected)."""
    root = Node("world")
    if objects:
        for name, mesh, color, texture, position, turn in SPHERE_OBJECTS:
            root.add(Node(name, offset=math3d.translate(position) @ math3d.rotate(turn, (0, 1, 0)),
                          mesh=mesh, color=color, texture=texture))
    reflector = Reflector(mesh="env_sphere", position=np.zeros(3))
    return EnvScene(name="sphere", graph=SceneGraph(root), reflector=reflector,
                    environment=sky_environment, camera=SPHERE_CAMERA,
                    light_direction=tuple(float(v) for v in SUN_DIRECTION))  # type: ignore[arg-type]


CUBE_FACE_FILES = ("px", "nx", "py", "ny", "pz", "nz")
"""File stems of a cube map's six faces, in GL order +X, -X, +Y, -Y, +Z, -Z."""


def load_cube_faces(folder: str | Path) -> np.ndarray:
    """The six images ``folder/{px,nx,py,ny,pz,nz}.png`` as cube faces ``(6, n, n, 3)`` uint8
    in mirrorlab's image convention (row 0 holds t = 1; see :mod:`mirrorlab.envmap`).

    The files are upright pictures, as skybox images usually are: a file's top row
    is its face's t = 0 edge, the edge the OpenGL cube-map table puts towards +y on
    the four side faces (towards +z on +Y, -z on -Y). ValueError naming the file
    when one is missing, unreadable, not square or not the size of the others.
    """
    from PIL import Image

    folder = Path(folder)
    faces = []
    for stem in CUBE_FACE_FILES:
        path = folder / f"{stem}.png"
        if not path.is_file():
            raise ValueError(f"cube face {path} is missing; a cube map needs "
                             f"{', '.join(s + '.png' for s in CUBE_FACE_FILES)}")
        try:
            with Image.open(path) as image:
                pixels = np.asarray(image.convert("RGB"))
        except OSError as exc:
            raise ValueError(f"cube face {path} cannot be read as an image ({exc})") from None
        if pixels.shape[0] != pixels.shape[1]:
            raise ValueError(f"cube face {path} is {pixels.shape[1]}x{pixels.shape[0]}, "
                             f"expected a square")
        if faces and pixels.shape != faces[0].shape:
            raise ValueError(f"cube face {path} is {pixels.shape[1]}x{pixels.shape[0]}, "
                             f"expected {faces[0].shape[1]}x{faces[0].shape[0]} like "
                             f"{CUBE_FACE_FILES[0]}.png")
        faces.append(pixels[::-1])  # upright file -> row 0 at t = 1
    return np.ascontiguousarray(np.stack(faces))


def check_method(method: str) -> str:
    """``method`` if it names a technique; ValueError naming it and the choices otherwise."""
    if method not in ENVMAP_METHODS:
        raise ValueError(f"unknown environment-map method {method!r}; expected one of "
                         f"{', '.join(ENVMAP_METHODS)}")
    return method


def build_env_scene(name: str) -> EnvScene:
    """The built-in scene ``name`` (one of :data:`ENV_SCENES`); ValueError otherwise."""
    if name == "cone":
        return build_cone_scene()
    if name == "sphere":
        return build_sphere_scene()
    raise ValueError(f"unknown environment-mapping scene {name!r}; expected one of "
                     f"{', '.join(ENV_SCENES)}")
