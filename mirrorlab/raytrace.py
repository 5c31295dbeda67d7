"""Ground truth: a small ray tracer over the same triangles the rasteriser draws.

One primary ray per pixel centre, and a reflected ray wherever a ray meets a
reflective surface, up to the scene's ``max_bounces`` (a reflector met when the
bounces are used up shows as a plain lit surface, as the rasteriser draws it), traced
with trimesh's ray casting (which uses embreex by itself when it is installed).
Shading repeats the rasteriser's model in numpy:
``albedo * (ambient + sum of light * max(n . l, 0))`` with the vertex normal
interpolated across the triangle and the texture sampled with its mipmaps.

It shares no code with the GL passes: the scene (:class:`~mirrorlab.scene.model.Scene`,
its meshes and the camera's matrices) is the only common ground, so it stays an
independent check of every rasterised technique. :func:`trace_scene` traces any scene.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mirrorlab import math3d
from mirrorlab.scene.backgrounds import environment_of, load_picture
from mirrorlab.scene.mesh import load_mesh
from mirrorlab.scene.model import CurvedReflector, PlanarReflector, Scene

Environment = Callable[[np.ndarray], np.ndarray]
"""``env(directions (n, 3) unit, world) -> (n, 3)`` RGB in [0, 1] for rays that escape."""

_EPSILON = 1e-4  # scene units; pushes secondary rays off the surface they leave


@dataclass
class RaySurface:
    """One triangle mesh in world space.

    ``vertices`` ``(n, 3)`` and ``normals`` ``(n, 3)`` world space, ``uvs``
    ``(n, 2)``, ``faces`` ``(m, 3)`` counter-clockwise seen from the front,
    ``color`` the albedo RGB in [0, 1], ``texture`` ``(h, w, 3)`` uint8 with
    row 0 at the top (t = 1) or None. A ``reflective`` surface is a perfect
    mirror with smooth (interpolated) normals, lit in ``color`` when the bounces are
    used up; ``backing`` is the unlit colour of its back face, or None when both faces
    reflect.
    """

    vertices: np.ndarray
    normals: np.ndarray
    uvs: np.ndarray
    faces: np.ndarray
    color: Sequence[float] = (1.0, 1.0, 1.0)
    texture: np.ndarray | None = None
    reflective: bool = False
    backing: Sequence[float] | None = None


@dataclass(frozen=True)
class RayImage:
    """``image`` ``(h, w, 3)`` float (float32 from :func:`trace_scene`) in [0, 1], row 0
    at the top; ``reflective_mask``
    ``(h, w)`` bool, True where the pixel's primary ray met the front of a reflective
    surface (the region every reflection technique is judged on); ``reflector`` ``(h, w)``
    int, the index in the scene's reflectors of the pixel's first hit (-1: none), when
    traced by :func:`trace_scene`."""

    image: np.ndarray
    reflective_mask: np.ndarray
    reflector: np.ndarray | None = None
    pixels: np.ndarray | None = None
    """The image as uint8, when it was made from the float64 colours as they were traced."""

    def to_uint8(self) -> np.ndarray:
        """The image as ``(h, w, 3)`` uint8, rounded as GL's unorm conversion rounds."""
        if self.pixels is not None:
            return self.pixels
        out = np.empty(self.image.shape, dtype=np.uint8)
        for top in range(0, len(out), 256):  # in bands: no full-size float temporaries
            out[top:top + 256] = _to_uint8(self.image[top:top + 256])
        return out


def _to_uint8(colors: np.ndarray) -> np.ndarray:
    return np.round(np.clip(colors, 0.0, 1.0) * 255.0).astype(np.uint8)


def sample_bilinear(texture: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Bilinear lookup with repeat wrap, like GL_LINEAR on one level.

    ``texture`` ``(h, w, 3)`` with values 0..255 (uint8 or float) and row 0 at
    t = 1; ``uv`` ``(n, 2)``; returns ``(n, 3)`` float64 in [0, 1].
    """
    height, width = texture.shape[:2]
    gl_rows = np.asarray(texture, dtype=np.float64)[::-1] / 255.0  # row 0 now at t = 0
    x = uv[:, 0] * width - 0.5
    y = uv[:, 1] * height - 0.5
    x0, y0 = np.floor(x), np.floor(y)
    fx, fy = (x - x0)[:, None], (y - y0)[:, None]
    x0, y0 = x0.astype(np.int64), y0.astype(np.int64)
    xa, xb = x0 % width, (x0 + 1) % width
    ya, yb = y0 % height, (y0 + 1) % height
    top = gl_rows[ya, xa] * (1 - fx) + gl_rows[ya, xb] * fx
    bottom = gl_rows[yb, xa] * (1 - fx) + gl_rows[yb, xb] * fx
    return top * (1 - fy) + bottom * fy


def mesh_surface(mesh: Path, model: np.ndarray, **appearance) -> RaySurface:
    """The mesh file ``mesh`` moved to world space by ``model`` ``(4, 4)`` (normals by its
    inverse transpose); ``appearance`` gives the other :class:`RaySurface` fields."""
    data = load_mesh(mesh)
    return RaySurface(
        vertices=math3d.transform_points(model, data.positions.astype(np.float64))[:, :3],
        normals=data.normals.astype(np.float64) @ math3d.normal_matrix(model).T,
        uvs=data.uvs.astype(np.float64),
        faces=data.indices.astype(np.int64),
        **appearance,
    )


class RayScene:
    """Surfaces, directional lights and what escaping rays see.

    ``lights`` are ``(direction (3,) towards the light, colour (3,) times intensity)``
    pairs; ``background`` is a constant RGB or an :data:`Environment` function of the
    ray direction.
    """

    def __init__(self, surfaces: Sequence[RaySurface],
                 lights: Sequence[tuple[Sequence[float], Sequence[float]]],
                 ambient: float, background: Sequence[float] | Environment) -> None:
        import trimesh

        if not surfaces:
            raise ValueError("a ray scene needs at least one surface")
        self.surfaces = list(surfaces)
        self.lights = [(np.asarray(d, dtype=np.float64) / np.linalg.norm(d),
                        np.asarray(c, dtype=np.float64)) for d, c in lights]
        self.ambient = float(ambient)
        self.background = background
        offsets = np.cumsum([0] + [len(s.vertices) for s in self.surfaces])
        vertices = np.vstack([s.vertices for s in self.surfaces])
        faces = np.vstack([s.faces + off for s, off in zip(self.surfaces, offsets, strict=False)])
        self._face_surface = np.concatenate(
            [np.full(len(s.faces), i) for i, s in enumerate(self.surfaces)])
        self._normals = np.vstack([s.normals for s in self.surfaces])
        self._uvs = np.vstack([s.uvs for s in self.surfaces])
        self._mesh = trimesh.Trimesh(vertices=vertices, faces=faces, process=False)
        self._triangles = vertices[faces]
        self._faces = faces
        self._mip_chains: dict[int, MipChain] = {}
        self._face_normals = np.cross(self._triangles[:, 1] - self._triangles[:, 0],
                                      self._triangles[:, 2] - self._triangles[:, 0])

    def _escape(self, directions: np.ndarray) -> np.ndarray:
        if callable(self.background):
            return np.asarray(self.background(directions), dtype=np.float64)
        return np.broadcast_to(np.asarray(self.background, dtype=np.float64),
                               directions.shape).copy()

    def trace(self, origins: np.ndarray, directions: np.ndarray,
              bounces: int = 1) -> tuple[np.ndarray, np.ndarray]:
        """Colour ``(n, 3)`` seen along each ray, and ``(n,)`` bool: the ray's first hit is
        the front of a reflective surface. ``directions`` ``(n, 3)`` unit;
        ``bounces`` is how many reflections are followed (beyond that a mirror is a
        plain lit surface). Textures are read at level 0 (no footprint is known)."""
        hits = self._resolve(np.asarray(origins, dtype=np.float64),
                             np.asarray(directions, dtype=np.float64), bounces)
        return self._shade(hits, np.zeros(len(hits.surface))), hits.on_mirror

    def _resolve(self, origins: np.ndarray, directions: np.ndarray, bounces: int) -> _Hits:
        """Follow each ray through up to ``bounces`` reflections to the surface it ends on."""
        hits = _Hits.escaping(directions)
        if len(origins) == 0:
            return hits
        faces, rays, points = self._mesh.ray.intersects_id(
            origins, directions, multiple_hits=False, return_locations=True)
        if len(rays) == 0:
            return hits
        faces, rays = np.asarray(faces), np.asarray(rays)
        barycentric = _barycentric(self._triangles[faces], points)
        corners = self._faces[faces]
        normals = np.einsum("nk,nkd->nd", barycentric, self._normals[corners])
        normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-300)
        front = np.einsum("nd,nd->n", self._face_normals[faces], directions[rays]) < 0.0
        surface_ids = self._face_surface[faces]
        hits.surface[rays] = surface_ids
        hits.first[rays] = surface_ids
        hits.uv[rays] = np.einsum("nk,nkd->nd", barycentric, self._uvs[corners])
        hits.normal[rays] = normals
        mirrors = np.array([s.reflective for s in self.surfaces])[surface_ids]
        backed = np.array([s.backing is not None for s in self.surfaces])[surface_ids]
        hits.backing[rays[mirrors & backed & ~front]] = True
        hits.on_mirror[rays[mirrors & front]] = True
        reflecting = mirrors & (front | ~backed)
        if not reflecting.any():
            return hits
        if bounces <= 0:  # bounces used up: the mirror is a plain surface
            hits.plain[rays[reflecting]] = True
            return hits
        rays, points, normals = rays[reflecting], points[reflecting], normals[reflecting]
        incoming = directions[rays]
        # A mirror reflects about its normal turned towards the incoming ray.
        facing = np.where((np.einsum("nd,nd->n", normals, incoming) > 0)[:, None],
                          -normals, normals)
        reflected = incoming - 2.0 * np.einsum("nd,nd->n", incoming, facing)[:, None] * facing
        reflected /= np.linalg.norm(reflected, axis=1, keepdims=True)
        onward = self._resolve(points + _EPSILON * facing, reflected, bounces - 1)
        for name in ("surface", "uv", "normal", "direction", "backing", "plain"):
            getattr(hits, name)[rays] = getattr(onward, name)
        return hits

    def _shade(self, hits: _Hits, lod: np.ndarray) -> np.ndarray:
        """Colours ``(n, 3)`` of resolved hits; ``lod`` ``(n,)`` is log2 of the texel footprint."""
        colors = np.zeros((len(hits.surface), 3))
        escaped = hits.surface < 0
        colors[escaped] = self._escape(hits.direction[escaped])
        for index, surface in enumerate(self.surfaces):
            mine = hits.surface == index
            if surface.reflective:
                backing = mine & hits.backing
                if backing.any():
                    colors[backing] = np.asarray(surface.backing, dtype=np.float64)
                mine = mine & hits.plain
            if not mine.any():
                continue
            albedo = np.broadcast_to(np.asarray(surface.color, dtype=np.float64),
                                     (int(mine.sum()), 3))
            if surface.texture is not None and not surface.reflective:
                albedo = albedo * self._mipmaps(index).sample(hits.uv[mine], lod[mine])
            light = np.full((int(mine.sum()), 3), self.ambient)
            for direction, color in self.lights:
                light += np.maximum(hits.normal[mine] @ direction, 0.0)[:, None] * color
            colors[mine] = albedo * light
        return np.clip(colors, 0.0, 1.0)

    def _mipmaps(self, index: int) -> MipChain:
        chain = self._mip_chains.get(index)
        if chain is None:
            chain = self._mip_chains[index] = MipChain(self.surfaces[index].texture)
        return chain

    def render(self, view: np.ndarray, projection: np.ndarray, size: Sequence[int],
               bounces: int = 1, rows: tuple[int, int] | None = None) -> RayImage:
        """Trace one ray through each pixel centre of a ``size`` (width, height) image seen
        through ``projection @ view`` (both ``(4, 4)``, the rasteriser's matrices); only
        the image rows ``rows`` = (first, end) when given (first even, so that each 2 x 2
        pixel quad lies in the band), and the result has those rows only.

        Rays start on the near plane, so nothing nearer than it shows, as in GL.
        Textures are filtered like GL_LINEAR_MIPMAP_LINEAR, with the level chosen
        from the texture-coordinate differences between neighbouring pixels
        (as a GPU does across a 2 x 2 quad).
        """
        width, full_height = (int(v) for v in size)
        first, end = rows if rows is not None else (0, full_height)
        if first % 2 or not 0 <= first < end <= full_height:
            raise ValueError(f"rows must be (even first, end) within 0..{full_height}, "
                             f"got {rows}")
        height = end - first
        columns = (np.arange(width) + 0.5) / width * 2.0 - 1.0
        rows_ndc = 1.0 - (np.arange(first, end) + 0.5) / full_height * 2.0
        ndc_x, ndc_y = np.meshgrid(columns, rows_ndc)
        inverse = np.linalg.inv(np.asarray(projection, dtype=np.float64)
                                @ np.asarray(view, dtype=np.float64))
        flat = np.stack([ndc_x.ravel(), ndc_y.ravel()], axis=1)
        near = _unproject(inverse, flat, -1.0)
        far = _unproject(inverse, flat, 1.0)
        directions = far - near
        directions /= np.linalg.norm(directions, axis=1, keepdims=True)
        hits = self._resolve(near, directions, bounces)
        lod = self._pixel_lod(hits, width, height)
        colors = self._shade(hits, lod.ravel())
        return RayImage(colors.reshape(height, width, 3), hits.on_mirror.reshape(height, width),
                        hits.first.reshape(height, width))

    def _pixel_lod(self, hits: _Hits, width: int, height: int) -> np.ndarray:
        """``(height, width)`` mip level per pixel from texel-space differences to the other
        pixel of its 2 x 2 quad in x and in y (0 where the neighbour lies on another part)."""
        lod = np.zeros((height, width))
        surface = hits.surface.reshape(height, width)
        uv = hits.uv.reshape(height, width, 2)
        sizes = np.ones((height, width, 2))
        for index, part in enumerate(self.surfaces):
            if part.texture is not None:
                sizes[surface == index] = (part.texture.shape[1], part.texture.shape[0])
        texels = uv * sizes
        partner_x = np.arange(width) ^ 1
        partner_y = np.arange(height) ^ 1
        partner_x[partner_x >= width] = width - 1
        partner_y[partner_y >= height] = height - 1
        dx = texels[:, partner_x] - texels
        dy = texels[partner_y] - texels
        dx[surface[:, partner_x] != surface] = 0.0
        dy[surface[partner_y] != surface] = 0.0
        rho = np.maximum(np.linalg.norm(dx, axis=2), np.linalg.norm(dy, axis=2))
        lod[rho > 1.0] = np.log2(rho[rho > 1.0])
        return lod


@dataclass
class _Hits:
    """Where each ray's path ends: ``surface`` index (-1 escaped), ``uv`` and ``normal`` there,
    the last ``direction`` travelled, whether it ended on a mirror's ``backing``, on a
    mirror with no bounces left (``plain``), and whether the first hit was a mirror's
    front (``on_mirror``)."""

    surface: np.ndarray
    uv: np.ndarray
    normal: np.ndarray
    direction: np.ndarray
    backing: np.ndarray
    plain: np.ndarray
    on_mirror: np.ndarray
    first: np.ndarray

    @classmethod
    def escaping(cls, directions: np.ndarray) -> _Hits:
        count = len(directions)
        return cls(np.full(count, -1), np.zeros((count, 2)), np.zeros((count, 3)),
                   directions.copy(), np.zeros(count, dtype=bool), np.zeros(count, dtype=bool),
                   np.zeros(count, dtype=bool), np.full(count, -1))


class MipChain:
    """A texture's mipmap levels, each the 2 x 2 box average of the one above (as
    ``glGenerateMipmap`` makes them), sampled like GL_LINEAR_MIPMAP_LINEAR."""

    def __init__(self, texture: np.ndarray) -> None:
        level = np.asarray(texture, dtype=np.float64)
        self.levels = [level]
        while min(level.shape[:2]) > 1:
            h, w = level.shape[0] // 2 * 2, level.shape[1] // 2 * 2
            level = level[:h, :w].reshape(h // 2, 2, w // 2, 2, 3).mean(axis=(1, 3))
            self.levels.append(level)

    def sample(self, uv: np.ndarray, lod: np.ndarray) -> np.ndarray:
        """``(n, 3)`` colours in [0, 1] at ``uv`` ``(n, 2)`` and mip level ``lod`` ``(n,)``."""
        lod = np.clip(lod, 0.0, len(self.levels) - 1)
        lower = np.floor(lod).astype(np.int64)
        blend = (lod - lower)[:, None]
        colors = np.zeros((len(uv), 3))
        for level in np.unique(lower):
            pick = lower == level
            upper = min(level + 1, len(self.levels) - 1)
            a = sample_bilinear(self.levels[level], uv[pick])
            b = sample_bilinear(self.levels[upper], uv[pick])
            colors[pick] = a * (1 - blend[pick]) + b * blend[pick]
        return colors


def _unproject(inverse: np.ndarray, ndc_xy: np.ndarray, ndc_z: float) -> np.ndarray:
    points = np.hstack([ndc_xy, np.full((len(ndc_xy), 1), ndc_z), np.ones((len(ndc_xy), 1))])
    world = points @ inverse.T
    return world[:, :3] / world[:, 3:4]


def _barycentric(triangles: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Barycentric weights ``(n, 3)`` of ``points`` ``(n, 3)`` in ``triangles`` ``(n, 3, 3)``."""
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    v0, v1, v2 = b - a, c - a, points - a
    d00 = np.einsum("nd,nd->n", v0, v0)
    d01 = np.einsum("nd,nd->n", v0, v1)
    d11 = np.einsum("nd,nd->n", v1, v1)
    d20 = np.einsum("nd,nd->n", v2, v0)
    d21 = np.einsum("nd,nd->n", v2, v1)
    denominator = d00 * d11 - d01 * d01
    safe = np.where(np.abs(denominator) > 1e-300, denominator, 1.0)
    v = (d11 * d20 - d01 * d21) / safe
    w = (d00 * d21 - d01 * d20) / safe
    return np.stack([1.0 - v - w, v, w], axis=1)


def ray_scene(scene: Scene) -> RayScene:
    """The tracer's model of ``scene``: every object's parts, each planar mirror as a
    reflective quad with its backing, each curved reflector as a perfect mirror (both
    faces reflect), the lights, and the background for rays that escape."""
    from mirrorlab.scene.robot import scene_parts

    surfaces = [mesh_surface(part.mesh, part.model, color=part.color,
                             texture=load_picture(part.texture) if part.texture else None)
                for part in scene_parts(scene)]
    for reflector in scene.reflectors:
        if isinstance(reflector, PlanarReflector):
            surfaces.append(RaySurface(
                vertices=reflector.corner_array.copy(),
                normals=np.broadcast_to(reflector.normal, (4, 3)).copy(),
                uvs=reflector.texcoords(), faces=np.array([[0, 1, 2], [0, 2, 3]]),
                color=reflector.color, reflective=True, backing=reflector.backing))
        else:
            assert isinstance(reflector, CurvedReflector)
            surfaces.append(mesh_surface(reflector.mesh, reflector.model_matrix(),
                                         color=reflector.color, reflective=True))
    lights = [(light.direction, np.asarray(light.color) * light.intensity)
              for light in scene.lights]
    background = (scene.background.color if not scene.background.is_environment
                  else environment_of(scene.background))
    return RayScene(surfaces, lights, scene.ambient, background)


TILE_RAYS = 1 << 17
"""Rays traced at once: the tracer's working memory grows with this, not the image."""


def trace_scene(scene: Scene, size: Sequence[int], supersample: int = 1,
                camera_view: np.ndarray | None = None,
                projection: np.ndarray | None = None, progress: bool = False,
                tile_rays: int = TILE_RAYS) -> RayImage:
    """Ray-traced image and reflective mask of ``scene`` seen by its camera (or the given
    ``camera_view`` and ``projection``) at ``size`` (width, height), following
    ``scene.max_bounces`` reflections.

    With ``supersample`` k > 1, k x k rays per pixel are traced and averaged (a box
    filter over the pixel, which is what a mipmapped texture lookup approximates, while
    one ray per pixel aliases wherever a reflection compresses what it shows); a pixel's
    mask is then True only when all its k x k rays meet a reflector's front.

    The image is traced in bands of rows, about ``tile_rays`` rays each, so the memory
    it takes is the result's (about 17 bytes a pixel) and one band's, at any size;
    ``progress`` shows a tqdm bar of the bands on stderr.
    """
    width, height = (int(v) for v in size)
    k = int(supersample)
    if k < 1:
        raise ValueError(f"supersample must be a positive whole number, got {supersample!r}")
    view = scene.camera.view() if camera_view is None else camera_view
    proj = scene.camera.projection(width / height) if projection is None else projection
    rays = ray_scene(scene)
    first_reflector = len(rays.surfaces) - len(scene.reflectors)
    band = max(2, tile_rays // (k * k * width) // 2 * 2)  # image rows a band, even
    image = np.empty((height, width, 3), dtype=np.float32)
    pixels = np.empty((height, width, 3), dtype=np.uint8)
    mask = np.empty((height, width), dtype=bool)
    reflector = np.empty((height, width), dtype=np.int16)
    from tqdm import tqdm

    starts = range(0, height, band)
    with tqdm(total=len(starts), desc="ray tracing", unit="band", disable=not progress,
              leave=False, file=sys.stderr, mininterval=0.5) as bar:
        for top in starts:
            _trace_band(rays, view, proj, scene.max_bounces, (width, height), k, top,
                        min(top + band, height), first_reflector,
                        (image, pixels, mask, reflector))
            bar.update()
    return RayImage(image, mask, reflector, pixels)


def _trace_band(rays: RayScene, view: np.ndarray, proj: np.ndarray, bounces: int,
                size: tuple[int, int], k: int, top: int, bottom: int, first_reflector: int,
                into: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]) -> None:
    """Trace image rows ``top`` to ``bottom`` (k x k rays a pixel) into the result arrays."""
    image, pixels, mask, reflector = into
    width, height = size
    traced = rays.render(view, proj, (k * width, k * height), bounces=bounces,
                         rows=(k * top, k * bottom))
    assert traced.reflector is not None
    rows = bottom - top
    surface = traced.reflector.reshape(rows, k, width, k)[:, k // 2, :, k // 2]
    reflector[top:bottom] = np.where(surface >= first_reflector, surface - first_reflector, -1)
    colors = traced.image.reshape(rows, k, width, k, 3).mean(axis=(1, 3))
    image[top:bottom] = colors
    pixels[top:bottom] = _to_uint8(colors)
    mask[top:bottom] = traced.reflective_mask.reshape(rows, k, width, k).all(axis=(1, 3))


def trace_frame(scene: Scene, size: Sequence[int], progress: bool = False) -> np.ndarray:
    """The ``raytrace`` technique (:mod:`mirrorlab.techniques`): ``scene``'s ground truth at
    ``size`` as ``(h, w, 3)`` uint8."""
    return trace_scene(scene, size, progress=progress).to_uint8()
