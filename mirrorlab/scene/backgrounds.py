"""What lies beyond the objects, as a function of direction: the procedural sky, a
picture used as a sphere map, six cube-face pictures, or a plain colour.

:func:`environment_of` turns a scene's :class:`~mirrorlab.scene.model.Background` into an
:data:`~mirrorlab.envmap.EnvFunction` that the map bakers, the sky pass and the ray
tracer all use, so every technique and the ground truth see the same surroundings.
World units, y up. Numpy only.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import lru_cache
from pathlib import Path

import numpy as np

from mirrorlab.envmap import EnvFunction, cube_map, sphere_map
from mirrorlab.scene.model import Background

CUBE_FACE_FILES = ("px", "nx", "py", "ny", "pz", "nz")
"""File stems of a cube map's six faces, in GL order +X, -X, +Y, -Y, +Z, -Z."""

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
    """The procedural sky: sky, sun, coloured balloons, hills along the horizon and a soft
    checkered ground. ``directions`` ``(n, 3)`` (normalised here), world, y up; returns
    ``(n, 3)`` float64 RGB in [0, 1].

    Every feature has soft edges (a few hundredths of a radian) so that one ray per
    pixel and a filtered texture lookup see the same colours.
    """
    d = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
    d = d / np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-12)
    x, y, z = d[:, 0], d[:, 1], d[:, 2]
    elevation = np.arcsin(np.clip(y, -1.0, 1.0))
    azimuth = np.arctan2(z, x)
    k = np.sqrt(np.clip(y, 0.0, 1.0))[:, None]  # pale at the horizon, deep at the zenith
    color = (1 - k) * np.array([0.86, 0.88, 0.92]) + k * np.array([0.22, 0.42, 0.82])
    sun = np.exp(-((np.arccos(np.clip(d @ SUN_DIRECTION, -1, 1)) / 0.09) ** 2))[:, None]
    color = color * (1 - sun) + sun * np.array([1.0, 0.96, 0.8])
    for direction, balloon, radius in _BALLOONS:
        axis = np.asarray(direction) / np.linalg.norm(direction)
        angle = np.arccos(np.clip(d @ axis, -1.0, 1.0))
        a = (1.0 - _smoothstep(radius * 0.75, radius, angle))[:, None]
        color = color * (1 - a) + a * np.asarray(balloon)
    hill_top = 0.1 + 0.06 * np.sin(3 * azimuth) + 0.035 * np.sin(7 * azimuth + 1.0)
    hill = (1.0 - _smoothstep(-0.015, 0.015, elevation - hill_top))[:, None]
    hue = azimuth[:, None] + np.array([0.0, 2.1, 4.2])
    hill_color = 0.3 + 0.18 * np.cos(hue) + 0.1 * (elevation[:, None] / 0.2)
    color = color * (1 - hill) + hill * hill_color
    t = 1.0 / np.maximum(-y, 1e-3)  # the ground: a soft checker on the plane y = -1
    gx, gz = x * t, z * t
    checker = 0.5 + 0.5 * np.tanh(3.0 * np.sin(np.pi * gx / 2.0) * np.sin(np.pi * gz / 2.0))
    ground = checker[:, None] * np.array([0.62, 0.55, 0.42]) + (1 - checker[:, None]) * np.array(
        [0.25, 0.32, 0.2]
    )
    haze = _smoothstep(0.0, 0.35, -y)[:, None]
    ground = haze * ground + (1 - haze) * np.array([0.5, 0.52, 0.5])
    below = _smoothstep(0.01, -0.01, elevation)[:, None]
    color = color * (1 - below) + below * ground
    return np.clip(color, 0.0, 1.0)


def image_sampler(image: np.ndarray) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """Bilinear, clamped lookup into ``image`` ``(h, w, 3)`` uint8 (row 0 at the top, t = 1
    there, as a GL texture shows it): ``sample(s, t)`` with ``(n,)`` arrays returns
    ``(n, 3)`` float64 in [0, 1]."""
    rows = np.asarray(image, dtype=np.float64)[::-1] / 255.0  # row 0 at t = 0
    height, width = rows.shape[:2]

    def sample(s: np.ndarray, t: np.ndarray) -> np.ndarray:
        x = np.clip(np.asarray(s) * width - 0.5, 0.0, width - 1.0)
        y = np.clip(np.asarray(t) * height - 0.5, 0.0, height - 1.0)
        x0 = np.clip(np.floor(x).astype(np.int64), 0, max(width - 2, 0))
        y0 = np.clip(np.floor(y).astype(np.int64), 0, max(height - 2, 0))
        x1, y1 = np.minimum(x0 + 1, width - 1), np.minimum(y0 + 1, height - 1)
        fx, fy = (x - x0)[:, None], (y - y0)[:, None]
        top = rows[y0, x0] * (1 - fx) + rows[y0, x1] * fx
        bottom = rows[y1, x0] * (1 - fx) + rows[y1, x1] * fx
        return top * (1 - fy) + bottom * fy

    return sample


def sphere_image_environment(image: np.ndarray, view: np.ndarray) -> EnvFunction:
    """The surroundings that ``image`` shows when used as a sphere map seen with ``view``
    ``(4, 4)`` (world to eye): direction ``r`` looks up the image at ``sphere_map(R r)``,
    with ``R`` the view's rotation. A sphere map baked from this for that view is the
    image again, and every other technique sees the same surroundings."""
    rotation = np.asarray(view, dtype=np.float64)[:3, :3]
    sample = image_sampler(image)

    def environment(directions: np.ndarray) -> np.ndarray:
        d = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
        s, t = sphere_map(d @ rotation.T)
        return sample(np.asarray(s).reshape(-1), np.asarray(t).reshape(-1))

    return environment


def cube_faces_environment(faces: np.ndarray) -> EnvFunction:
    """The surroundings six cube faces ``(6, n, n, 3)`` uint8 show (rows as
    :func:`load_cube_faces` gives them): each direction's face and texel bilinearly."""
    samplers = [image_sampler(face) for face in faces]

    def environment(directions: np.ndarray) -> np.ndarray:
        d = np.asarray(directions, dtype=np.float64).reshape(-1, 3)
        face, s, t = cube_map(d)
        colors = np.zeros((len(d), 3))
        for index in range(6):
            mine = face == index
            if mine.any():
                colors[mine] = samplers[index](s[mine], t[mine])
        return colors

    return environment


MAX_PICTURE_PIXELS = 16384 * 16384
"""Largest picture read, in pixels (a 16384 x 16384 picture is 768 MB as RGB); a larger
one is refused from its header, before anything is decoded."""


def load_picture(path: str | Path) -> np.ndarray:
    """A picture file as ``(h, w, 3)`` uint8, row 0 at the top; ValueError naming the file
    when it cannot be read (missing, unreadable, empty, corrupt, not an image) or holds
    more than :data:`MAX_PICTURE_PIXELS` pixels."""
    import warnings

    from PIL import Image

    path = Path(path)
    if path.is_file() and path.stat().st_size == 0:
        raise ValueError(f"picture {path} is empty (0 bytes)")
    try:
        with warnings.catch_warnings():
            # Pillow's decompression-bomb guard: the size is checked here instead.
            warnings.simplefilter("ignore", Image.DecompressionBombWarning)
            Image.MAX_IMAGE_PIXELS = None
            with Image.open(path) as image:
                width, height = image.size
                if width * height > MAX_PICTURE_PIXELS:
                    raise ValueError(
                        f"picture {path} is {width}x{height}, too large: "
                        f"expected at most {MAX_PICTURE_PIXELS:,} pixels "
                        f"(16384x16384)"
                    )
                if width < 1 or height < 1:
                    raise ValueError(f"picture {path} is {width}x{height}: it has no pixels")
                return np.asarray(image.convert("RGB"))
    except ValueError as exc:
        if str(exc).startswith(f"picture {path}"):
            raise
        raise ValueError(f"picture {path} cannot be read as an image ({exc})") from None
    except (OSError, SyntaxError, EOFError, MemoryError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else exc
        raise ValueError(f"picture {path} cannot be read as an image ({reason})") from None


def load_cube_faces(folder: str | Path) -> np.ndarray:
    """The six images ``folder/{px,nx,py,ny,pz,nz}.png`` as cube faces ``(6, n, n, 3)``
    uint8 in mirrorlab's image convention (row 0 holds t = 1; see :mod:`mirrorlab.envmap`).

    The files are upright pictures, as skybox images usually are: a file's top row
    is its face's t = 0 edge, the edge the OpenGL cube-map table puts towards +y on
    the four side faces (towards +z on +Y, -z on -Y). ValueError naming the file
    when one is missing, unreadable, not square or not the size of the others.
    """
    folder = Path(folder)
    stamps = tuple(
        (folder / f"{stem}.png").stat().st_mtime_ns if (folder / f"{stem}.png").is_file() else None
        for stem in CUBE_FACE_FILES
    )
    return _load_cube_faces(folder.resolve(), stamps)


def cube_face_size(folder: str | Path) -> int:
    """The side of the cube faces in ``folder``, from ``px.png``'s header alone (nothing is
    decoded), so that a texture too large for the GL is found before six pictures are
    read; :func:`load_cube_faces` checks the faces fully. ValueError naming the file."""
    from PIL import Image

    path = Path(folder) / f"{CUBE_FACE_FILES[0]}.png"
    try:
        with Image.open(path) as image:
            return int(image.size[0])
    except (OSError, ValueError, SyntaxError) as exc:
        reason = exc.strerror if isinstance(exc, OSError) and exc.strerror else exc
        raise ValueError(f"picture {path} cannot be read as an image ({reason})") from None


@lru_cache(maxsize=8)
def _load_cube_faces(folder: Path, stamps: tuple) -> np.ndarray:
    """:func:`load_cube_faces`, remembered per folder and the files' modification times."""
    faces: list[np.ndarray] = []
    for stem in CUBE_FACE_FILES:
        path = folder / f"{stem}.png"
        if not path.is_file():
            raise ValueError(
                f"cube face {path} is missing; a cube map needs "
                f"{', '.join(s + '.png' for s in CUBE_FACE_FILES)}"
            )
        pixels = load_picture(path)
        if pixels.shape[0] != pixels.shape[1]:
            raise ValueError(
                f"cube face {path} is {pixels.shape[1]}x{pixels.shape[0]}, expected a square"
            )
        if faces and pixels.shape != faces[0].shape:
            raise ValueError(
                f"cube face {path} is {pixels.shape[1]}x{pixels.shape[0]}, "
                f"expected {faces[0].shape[1]}x{faces[0].shape[0]} like "
                f"{CUBE_FACE_FILES[0]}.png"
            )
        faces.append(pixels[::-1])  # upright file -> row 0 at t = 1
    stacked = np.ascontiguousarray(np.stack(faces))
    stacked.setflags(write=False)
    return stacked


@lru_cache(maxsize=16)
def environment_of(background: Background) -> EnvFunction:
    """The background as a function of direction (remembered per background: one function
    object per background, so bakes keyed by it are shared)."""
    if background.kind == "sky":
        return sky_environment
    if background.kind == "cube_faces":
        assert background.path is not None
        return cube_faces_environment(load_cube_faces(background.path))
    if background.kind == "sphere_map":
        assert background.path is not None and background.sphere_map_camera is not None
        return sphere_image_environment(
            load_picture(background.path), background.sphere_map_camera.view()
        )
    color = np.asarray(background.color, dtype=np.float64)

    def plain(directions: np.ndarray) -> np.ndarray:
        return np.broadcast_to(color, np.asarray(directions).reshape(-1, 3).shape).copy()

    return plain
