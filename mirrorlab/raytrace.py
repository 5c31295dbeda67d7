"""Ground truth: a small ray tracer over the same triangles the rasteriser draws.

One primary ray per pixel centre, and a reflected ray wherever a ray meets a
reflective surface, up to the scene's ``max_bounces`` (a reflector met when the
bounces are used up shows as a plain lit surface, as the rasteriser draws it), traced
with trimesh's ray casting (which uses embreex by itself when it is installed).
Shading repeats the rasteriser's model in numpy:
``albedo * (ambient + sum of light * max(n . l, 0))`` with the vertex normal
interpolated across the triangle and the texture sampled with its mipmaps.

It draws the picture the rasteriser draws, by the same definition (docs/accuracy.md):

- **Near and far planes.** Primary rays start on the camera's near plane; a primary
  ray whose first surface lies beyond the far plane sees the background, as GL clips
  it. Reflections see the whole scene, whatever the far plane (the rasteriser's
  reflection views reach as far as the scene extends).
- **Back faces.** Every surface but a planar mirror is seen from its front only: a ray
  meeting a back face passes through it, as back-face culling lets the rasteriser's
  view through. So the inside of a curved reflector shows the world beyond it, not
  a reflection; a planar mirror's back shows its backing colour.
- **Offsets.** A ray leaving a surface starts a few hundred float32 ULPs off it along
  its normal, in the frame the intersector works in (Wachter and Binder, "A Fast and
  Robust Method for Avoiding Self-Intersection", Ray Tracing Gems ch. 6): the offset
  scales with the hit's magnitude, so the truth holds at any scale.
- **Mip selection.** Each ray carries ray differentials (Igehy 1999): the rays through
  the neighbouring pixel of its 2 x 2 quad in x and in y, transferred to every surface
  it meets and reflected with it (a curved mirror's normal turning spreads them). The
  texture's level of detail is chosen from them where the ray ends, as a GPU chooses
  it from the differences across its quad, for every pixel and at every bounce.

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
from numpy.typing import ArrayLike

from mirrorlab import math3d
from mirrorlab.scene.backgrounds import environment_of
from mirrorlab.scene.mesh import load_mesh, texture_picture
from mirrorlab.scene.model import CurvedReflector, PlanarReflector, Scene

Environment = Callable[[np.ndarray], np.ndarray]
"""``env(directions (n, 3) unit, world) -> (n, 3)`` RGB in [0, 1] for rays that escape."""

_ULP_ORIGIN = 1.0 / 32.0
_FLOAT_SCALE = 1.0 / 65536.0
_INT_SCALE = 256.0
"""Wachter and Binder's constants (Ray Tracing Gems ch. 6): below |p| = 1/32 a fixed
offset of 1/65536 along the normal, above it 256 float32 ULPs of each coordinate."""
_FRAME_SIZE = 100.0
"""The intersector's float32 frame: the mesh's bounding box moved to the origin and
scaled so its diagonal is 100 (as trimesh hands it to embree); offsets are made there."""
_MAX_PASSES = 16
"""Back faces a ray may pass through before it is taken to escape."""


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
            out[top : top + 256] = _to_uint8(self.image[top : top + 256])
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

    def __init__(
        self,
        surfaces: Sequence[RaySurface],
        lights: Sequence[tuple[ArrayLike, ArrayLike]],
        ambient: float,
        background: Sequence[float] | Environment,
    ) -> None:
        import trimesh

        if not surfaces:
            raise ValueError("a ray scene needs at least one surface")
        self.surfaces = list(surfaces)
        self.lights = [
            (np.asarray(d, dtype=np.float64) / np.linalg.norm(d), np.asarray(c, dtype=np.float64))
            for d, c in lights
        ]
        self.ambient = float(ambient)
        self.background = background
        offsets = np.cumsum([0] + [len(s.vertices) for s in self.surfaces])
        vertices = np.vstack([s.vertices for s in self.surfaces])
        faces = np.vstack([s.faces + off for s, off in zip(self.surfaces, offsets, strict=False)])
        self._face_surface = np.concatenate(
            [np.full(len(s.faces), i) for i, s in enumerate(self.surfaces)]
        )
        self._normals = np.vstack([s.normals for s in self.surfaces])
        self._uvs = np.vstack([s.uvs for s in self.surfaces])
        self._mesh = trimesh.Trimesh(vertices=vertices, faces=faces, process=False)
        self._triangles = vertices[faces]
        self._faces = faces
        self._mip_chains: dict[int, MipChain] = {}
        self._face_normals = np.cross(
            self._triangles[:, 1] - self._triangles[:, 0],
            self._triangles[:, 2] - self._triangles[:, 0],
        )
        self._reflective = np.array([s.reflective for s in self.surfaces])
        self._backed = np.array([s.backing is not None for s in self.surfaces])
        self._texture_sizes = np.array(
            [
                (0.0, 0.0)
                if s.texture is None or s.reflective
                else (s.texture.shape[1], s.texture.shape[0])
                for s in self.surfaces
            ],
            dtype=np.float64,
        )
        low, high = vertices.min(axis=0), vertices.max(axis=0)
        self._frame_origin = low
        self._frame_scale = _FRAME_SIZE / max(float(np.linalg.norm(high - low)), 1e-300)

    def _escape(self, directions: np.ndarray) -> np.ndarray:
        if callable(self.background):
            return np.asarray(self.background(directions), dtype=np.float64)
        return np.broadcast_to(
            np.asarray(self.background, dtype=np.float64), directions.shape
        ).copy()

    def offset_points(self, points: np.ndarray, normals: np.ndarray) -> np.ndarray:
        """``points`` ``(n, 3)`` moved off their surface along ``normals`` ``(n, 3)``
        (unit, pointing where the next ray goes) by Wachter and Binder's integer-ULP
        offset, made in the intersector's float32 frame: far enough that the next ray
        cannot meet the surface it leaves again, at any scale or distance from the
        origin, and no farther."""
        q = ((points - self._frame_origin) * self._frame_scale).astype(np.float32)
        n = np.asarray(normals, dtype=np.float32)
        steps = (_INT_SCALE * n).astype(np.int32)
        bits = q.view(np.int32)
        moved = (bits + np.where(q < 0, -steps, steps)).view(np.float32)
        near_zero = np.abs(q) < _ULP_ORIGIN
        offset = np.where(near_zero, q + np.float32(_FLOAT_SCALE) * n, moved)
        return offset.astype(np.float64) / self._frame_scale + self._frame_origin

    def trace(
        self, origins: np.ndarray, directions: np.ndarray, bounces: int = 1
    ) -> tuple[np.ndarray, np.ndarray]:
        """Colour ``(n, 3)`` seen along each ray, and ``(n,)`` bool: the ray's first hit is
        the front of a reflective surface. ``directions`` ``(n, 3)`` unit;
        ``bounces`` is how many reflections are followed (beyond that a mirror is a
        plain lit surface). Textures are read at level 0 (no footprint is known)."""
        hits = self._resolve(
            np.asarray(origins, dtype=np.float64), np.asarray(directions, dtype=np.float64), bounces
        )
        return self._shade(hits, np.zeros(len(hits.surface))), hits.on_mirror

    def _first_visible(
        self,
        origins: np.ndarray,
        directions: np.ndarray,
        spreads: np.ndarray | None,
        beyond: Callable[[np.ndarray], np.ndarray] | None,
    ) -> _Visible:
        """Each ray's first surface seen from its front (or a planar mirror's backing),
        passing through back faces; ``spreads`` ``(n, 4, 3)`` are its differentials,
        carried to that surface; ``beyond`` marks hit points past the far plane (those
        rays see nothing)."""
        count = len(origins)
        seen = _Visible.none(count, spreads)
        pending = np.arange(count)
        origins = origins.copy()
        spreads = None if spreads is None else spreads.copy()
        for _ in range(_MAX_PASSES):
            if len(pending) == 0:
                break
            faces, rays, points = self._mesh.ray.intersects_id(
                origins[pending], directions[pending], multiple_hits=False, return_locations=True
            )
            if len(rays) == 0:
                break
            faces, local = np.asarray(faces), np.asarray(rays)
            rays = pending[local]
            surface_ids = self._face_surface[faces]
            face_normals = self._face_normals[faces]
            incoming = directions[rays]
            front = np.einsum("nd,nd->n", face_normals, incoming) < 0.0
            backed = self._backed[surface_ids]
            if spreads is not None:
                spreads[rays] = _transfer(
                    spreads[rays], points - origins[rays], incoming, face_normals
                )
            stops = front | backed
            if beyond is not None:
                clipped = stops & beyond(points)
                stops &= ~clipped  # past the far plane: these rays see the background
            done = rays[stops]
            seen.face[done] = faces[stops]
            seen.point[done] = points[stops]
            seen.front[done] = front[stops]
            through = ~front & ~backed
            if beyond is not None:
                through &= ~beyond(points)
            # Culled back faces: go on from just past them.
            unit_normals = face_normals[through] / np.linalg.norm(
                face_normals[through], axis=1, keepdims=True
            )
            origins[rays[through]] = self.offset_points(points[through], -unit_normals)
            pending = rays[through]
        if spreads is not None:
            seen.spreads = spreads
        return seen

    def _resolve(
        self,
        origins: np.ndarray,
        directions: np.ndarray,
        bounces: int,
        spreads: np.ndarray | None = None,
        beyond: Callable[[np.ndarray], np.ndarray] | None = None,
    ) -> _Hits:
        """Follow each ray through up to ``bounces`` reflections to the surface it ends on;
        with ``spreads`` (its ray differentials ``(n, 4, 3)``) the texel footprint there
        too. ``beyond`` (primary rays only) marks points past the far plane."""
        hits = _Hits.escaping(directions)
        if len(origins) == 0:
            return hits
        seen = self._first_visible(origins, directions, spreads, beyond)
        rays = np.nonzero(seen.face >= 0)[0]
        if len(rays) == 0:
            return hits
        faces, points, front = seen.face[rays], seen.point[rays], seen.front[rays]
        barycentric = _barycentric(self._triangles[faces], points)
        corners = self._faces[faces]
        raw_normals = np.einsum("nk,nkd->nd", barycentric, self._normals[corners])
        lengths = np.maximum(np.linalg.norm(raw_normals, axis=1, keepdims=True), 1e-300)
        normals = raw_normals / lengths
        surface_ids = self._face_surface[faces]
        hits.surface[rays] = surface_ids
        hits.first[rays] = surface_ids
        hits.uv[rays] = np.einsum("nk,nkd->nd", barycentric, self._uvs[corners])
        hits.normal[rays] = normals
        mirrors = self._reflective[surface_ids]
        hits.backing[rays[~front]] = True  # a planar mirror's back: its backing colour
        hits.on_mirror[rays[mirrors & front]] = True
        reflecting = mirrors & front
        derivatives = None
        if seen.spreads is not None:
            derivatives = _surface_derivatives(self._triangles[faces], seen.spreads[rays])
            hits.texels[rays] = self._texel_footprint(surface_ids, corners, derivatives)
        if not reflecting.any():
            return hits
        if bounces <= 0:  # bounces used up: the mirror is a plain surface
            hits.plain[rays[reflecting]] = True
            return hits
        incoming = directions[rays[reflecting]]
        normal = normals[reflecting]
        # A mirror reflects about its normal turned towards the incoming ray.
        towards = np.where(np.einsum("nd,nd->n", normal, incoming) > 0, -1.0, 1.0)[:, None]
        facing = normal * towards
        along = np.einsum("nd,nd->n", incoming, facing)[:, None]
        reflected = incoming - 2.0 * along * facing
        reflected /= np.linalg.norm(reflected, axis=1, keepdims=True)
        onward_spreads = None
        if seen.spreads is not None and derivatives is not None:
            onward_spreads = _reflect_spreads(
                seen.spreads[rays[reflecting]],
                incoming,
                facing,
                along,
                derivatives[reflecting],
                self._normals[corners[reflecting]],
                towards,
                lengths[reflecting],
            )
        face_normals = self._face_normals[faces[reflecting]]
        leave = face_normals / np.linalg.norm(face_normals, axis=1, keepdims=True)
        reflected, onward_spreads = self.onward(
            surface_ids[reflecting], leave, reflected, onward_spreads
        )
        starts = self.offset_points(points[reflecting], leave)  # front faces: leave outward
        onward = self._resolve(starts, reflected, bounces - 1, onward_spreads)
        chosen = rays[reflecting]
        for name in ("surface", "uv", "normal", "direction", "backing", "plain", "texels"):
            getattr(hits, name)[chosen] = getattr(onward, name)
        return hits

    def onward(
        self,
        surface_ids: np.ndarray,
        outward: np.ndarray,
        reflected: np.ndarray,
        spreads: np.ndarray | None,
    ) -> tuple[np.ndarray, np.ndarray | None]:
        """Where rays go on from the reflective surfaces ``surface_ids`` ``(n,)`` they met
        (``outward`` ``(n, 3)``: the faces' unit normals): the mirror reflections
        ``reflected`` ``(n, 3)`` with their differentials ``spreads``, as they are. A
        model of another kind of reflector (a test's) changes them here."""
        return reflected, spreads

    def _texel_footprint(
        self, surface_ids: np.ndarray, corners: np.ndarray, derivatives: np.ndarray
    ) -> np.ndarray:
        """``(n,)``: how many texels of its texture the ray's pixel step covers at its hit
        (GL's rho: the longer of the x and y steps), from the barycentric derivatives
        ``(n, 2, 2)`` (``d(u, v)/d(x, y)`` of the hit's triangle coordinates)."""
        texels = np.zeros(len(surface_ids))
        uv = self._uvs[corners]  # (n, 3, 2)
        edges = np.stack([uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]], axis=1)  # (n, 2, 2)
        steps = np.einsum("nak,nab->nbk", edges, derivatives)  # uv change per x, per y
        sizes = self._texture_sizes[surface_ids]  # (n, 2) width, height (0: untextured)
        lengths = np.linalg.norm(steps * sizes[:, None, :], axis=2)  # (n, 2)
        texels[:] = lengths.max(axis=1)
        return texels

    def _shade(self, hits: _Hits, lod: np.ndarray) -> np.ndarray:
        """Colours ``(n, 3)`` of resolved hits; ``lod`` ``(n,)`` is log2 of the texel footprint."""
        colors = np.zeros((len(hits.surface), 3))
        escaped = hits.surface < 0
        colors[escaped] = self._escape(hits.direction[escaped])
        for index, surface in enumerate(self.surfaces):
            mine = hits.surface == index
            backing = mine & hits.backing
            if backing.any() and surface.backing is not None:
                colors[backing] = np.asarray(surface.backing, dtype=np.float64)
            mine = mine & ~hits.backing
            if surface.reflective:
                mine = mine & hits.plain
            if not mine.any():
                continue
            albedo = np.broadcast_to(
                np.asarray(surface.color, dtype=np.float64), (int(mine.sum()), 3)
            )
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
            texture = self.surfaces[index].texture
            assert texture is not None  # asked for textured surfaces only
            chain = self._mip_chains[index] = MipChain(texture)
        return chain

    def render(
        self,
        view: np.ndarray,
        projection: np.ndarray,
        size: Sequence[int],
        bounces: int = 1,
        rows: tuple[int, int] | None = None,
    ) -> RayImage:
        """Trace one ray through each pixel centre of a ``size`` (width, height) image seen
        through ``projection @ view`` (both ``(4, 4)``, the rasteriser's matrices); only
        the image rows ``rows`` = (first, end) when given (first even, so that each 2 x 2
        pixel quad lies in the band), and the result has those rows only.

        Rays start on the near plane, so nothing nearer than it shows, and a first hit
        past the far plane shows the background, as in GL. Textures are filtered like
        GL_LINEAR_MIPMAP_LINEAR, the level chosen from each ray's differentials: the rays
        through the other pixel of its 2 x 2 quad in x and in y, followed with it.
        """
        width, full_height = (int(v) for v in size)
        first, end = rows if rows is not None else (0, full_height)
        if first % 2 or not 0 <= first < end <= full_height:
            raise ValueError(f"rows must be (even first, end) within 0..{full_height}, got {rows}")
        height = end - first
        matrix = np.asarray(projection, dtype=np.float64) @ np.asarray(view, dtype=np.float64)
        inverse = np.linalg.inv(matrix)

        def rays(columns: np.ndarray, image_rows: np.ndarray):
            ndc_x = (columns + 0.5) / width * 2.0 - 1.0
            ndc_y = 1.0 - (image_rows + 0.5) / full_height * 2.0
            grid_x, grid_y = np.meshgrid(ndc_x, ndc_y)
            flat = np.stack([grid_x.ravel(), grid_y.ravel()], axis=1)
            near = _unproject(inverse, flat, -1.0)
            directions = _unproject(inverse, flat, 1.0) - near
            return near, directions / np.linalg.norm(directions, axis=1, keepdims=True)

        columns, image_rows = np.arange(width), np.arange(first, end)
        near, directions = rays(columns, image_rows)
        # The other pixel of each 2 x 2 quad (past the edge for an odd size, as a GPU's
        # helper pixel is), for the differentials.
        near_x, directions_x = rays(columns ^ 1, image_rows)
        near_y, directions_y = rays(columns, image_rows ^ 1)
        spreads = np.stack(
            [near_x - near, directions_x - directions, near_y - near, directions_y - directions],
            axis=1,
        )

        def beyond(points: np.ndarray) -> np.ndarray:
            clip = np.column_stack([points, np.ones(len(points))]) @ matrix.T
            with np.errstate(divide="ignore", invalid="ignore"):
                return clip[:, 2] > clip[:, 3]

        hits = self._resolve(near, directions, bounces, spreads, beyond)
        lod = np.log2(np.maximum(hits.texels, 1.0))
        colors = self._shade(hits, lod)
        return RayImage(
            colors.reshape(height, width, 3),
            hits.on_mirror.reshape(height, width),
            hits.first.reshape(height, width),
        )


def _transfer(
    spreads: np.ndarray, travelled: np.ndarray, directions: np.ndarray, normals: np.ndarray
) -> np.ndarray:
    """Ray differentials ``(n, 4, 3)`` (d origin / dx, d direction / dx, the same for y)
    carried along unit ``directions`` ``(n, 3)`` by ``travelled`` ``(n, 3)`` onto the
    plane with normal ``normals`` ``(n, 3)`` (Igehy's transfer): the origins' change
    becomes the change of the hit point on that plane."""
    distance = np.linalg.norm(travelled, axis=1)[:, None]
    out = spreads.copy()
    denominator = np.einsum("nd,nd->n", directions, normals)[:, None]
    safe = np.where(np.abs(denominator) > 1e-300, denominator, 1e-300)
    for origin, direction in ((0, 1), (2, 3)):
        moved = spreads[:, origin] + distance * spreads[:, direction]
        along = np.einsum("nd,nd->n", moved, normals)[:, None] / safe
        out[:, origin] = moved - along * directions
    return out


def _surface_derivatives(triangles: np.ndarray, spreads: np.ndarray) -> np.ndarray:
    """``(n, 2, 2)``: the change of a hit's triangle coordinates (u along B - A, v along
    C - A) per pixel step in x (column 0) and in y (column 1), from its transferred
    differentials ``(n, 4, 3)``."""
    a, b, c = triangles[:, 0], triangles[:, 1], triangles[:, 2]
    e1, e2 = b - a, c - a
    g11 = np.einsum("nd,nd->n", e1, e1)
    g12 = np.einsum("nd,nd->n", e1, e2)
    g22 = np.einsum("nd,nd->n", e2, e2)
    det = g11 * g22 - g12 * g12
    det = np.where(np.abs(det) > 1e-300, det, 1e-300)
    out = np.empty((len(triangles), 2, 2))
    for column, origin in enumerate((0, 2)):
        step = spreads[:, origin]
        r1 = np.einsum("nd,nd->n", e1, step)
        r2 = np.einsum("nd,nd->n", e2, step)
        out[:, 0, column] = (g22 * r1 - g12 * r2) / det
        out[:, 1, column] = (g11 * r2 - g12 * r1) / det
    return out


def _reflect_spreads(
    spreads: np.ndarray,
    incoming: np.ndarray,
    facing: np.ndarray,
    along: np.ndarray,
    derivatives: np.ndarray,
    corner_normals: np.ndarray,
    towards: np.ndarray,
    lengths: np.ndarray,
) -> np.ndarray:
    """The differentials ``(n, 4, 3)`` of the reflected rays: the hit point's change stays
    the origin's, the direction's change is ``dD - 2 ((dD.n) n + (D.n) dn)``, ``dn`` the
    change of the interpolated unit normal across the triangle (zero on a flat mirror:
    the corners' normals agree)."""
    out = spreads.copy()
    edges = np.stack(
        [corner_normals[:, 1] - corner_normals[:, 0], corner_normals[:, 2] - corner_normals[:, 0]],
        axis=1,
    )  # (n, 2, 3)
    for column, (origin, direction) in enumerate(((0, 1), (2, 3))):
        raw = np.einsum("nk,nkd->nd", derivatives[:, :, column], edges)
        raw_change = raw / lengths
        change = (
            raw_change
            - np.einsum("nd,nd->n", raw_change, facing * towards)[:, None] * facing * towards
        ) * towards
        d_direction = spreads[:, direction]
        out[:, direction] = d_direction - 2.0 * (
            np.einsum("nd,nd->n", d_direction, facing)[:, None] * facing + along * change
        )
        out[:, origin] = spreads[:, origin]
    return out


@dataclass
class _Visible:
    """Each ray's first visible surface: its ``face`` (-1: none), the hit ``point``, whether
    it met the face's ``front``, and the ray differentials carried there."""

    face: np.ndarray
    point: np.ndarray
    front: np.ndarray
    spreads: np.ndarray | None

    @classmethod
    def none(cls, count: int, spreads: np.ndarray | None) -> _Visible:
        return cls(np.full(count, -1), np.zeros((count, 3)), np.zeros(count, dtype=bool), None)


@dataclass
class _Hits:
    """Where each ray's path ends: ``surface`` index (-1 escaped), ``uv`` and ``normal`` there,
    the last ``direction`` travelled, whether it ended on a mirror's ``backing``, on a
    mirror with no bounces left (``plain``), whether the first hit was a mirror's front
    (``on_mirror``), and the texel footprint there (``texels``, from ray differentials)."""

    surface: np.ndarray
    uv: np.ndarray
    normal: np.ndarray
    direction: np.ndarray
    backing: np.ndarray
    plain: np.ndarray
    on_mirror: np.ndarray
    first: np.ndarray
    texels: np.ndarray

    @classmethod
    def escaping(cls, directions: np.ndarray) -> _Hits:
        count = len(directions)
        return cls(
            np.full(count, -1),
            np.zeros((count, 2)),
            np.zeros((count, 3)),
            directions.copy(),
            np.zeros(count, dtype=bool),
            np.zeros(count, dtype=bool),
            np.zeros(count, dtype=bool),
            np.full(count, -1),
            np.zeros(count),
        )


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


def ray_scene(scene: Scene, model: type[RayScene] | None = None) -> RayScene:
    """The tracer's model of ``scene``: every object's parts, each planar mirror as a
    reflective quad with its backing, each curved reflector as a perfect mirror seen
    from outside (rays pass through its back faces), the lights, and the background for
    rays that escape; a ``model`` (a :class:`RayScene` subclass) in place of RayScene."""
    from mirrorlab.scene.robot import scene_parts

    surfaces = [
        mesh_surface(
            part.mesh,
            part.model,
            color=part.color,
            texture=texture_picture(part.texture) if part.texture else None,
        )
        for part in scene_parts(scene)
    ]
    for reflector in scene.reflectors:
        if isinstance(reflector, PlanarReflector):
            surfaces.append(
                RaySurface(
                    vertices=reflector.corner_array.copy(),
                    normals=np.broadcast_to(reflector.normal, (4, 3)).copy(),
                    uvs=reflector.texcoords(),
                    faces=np.array([[0, 1, 2], [0, 2, 3]]),
                    color=reflector.color,
                    reflective=True,
                    backing=reflector.backing,
                )
            )
        else:
            assert isinstance(reflector, CurvedReflector)
            surfaces.append(
                mesh_surface(
                    reflector.mesh, reflector.model_matrix(), color=reflector.color, reflective=True
                )
            )
    lights = [
        (light.direction, np.asarray(light.color) * light.intensity) for light in scene.lights
    ]
    background = (
        scene.background.color
        if not scene.background.is_environment
        else environment_of(scene.background)
    )
    return (model or RayScene)(surfaces, lights, scene.ambient, background)


TILE_RAYS = 1 << 17
"""Rays traced at once: the tracer's working memory grows with this, not the image."""


def trace_scene(
    scene: Scene,
    size: Sequence[int],
    supersample: int = 1,
    camera_view: np.ndarray | None = None,
    projection: np.ndarray | None = None,
    progress: bool = False,
    tile_rays: int = TILE_RAYS,
    model: type[RayScene] | None = None,
) -> RayImage:
    """Ray-traced image and reflective mask of ``scene`` seen by its camera (or the given
    ``camera_view`` and ``projection``) at ``size`` (width, height), following
    ``scene.max_bounces`` reflections.

    With ``supersample`` k > 1, k x k rays per pixel are traced and averaged (a box
    filter over the pixel, which is what a mipmapped texture lookup approximates, while
    one ray per pixel aliases wherever a reflection compresses what it shows); a pixel's
    mask is then True only when all its k x k rays meet a reflector's front.

    The image is traced in bands of rows, about ``tile_rays`` rays each, so the memory
    it takes is the result's (about 17 bytes a pixel) and one band's, at any size;
    ``progress`` shows a tqdm bar of the bands on stderr. ``model`` is the
    :class:`RayScene` class traced with (see :func:`ray_scene`).
    """
    width, height = (int(v) for v in size)
    k = int(supersample)
    if k < 1:
        raise ValueError(f"supersample must be a positive whole number, got {supersample!r}")
    view = scene.camera.view() if camera_view is None else camera_view
    proj = scene.camera.projection(width / height) if projection is None else projection
    rays = ray_scene(scene, model)
    first_reflector = len(rays.surfaces) - len(scene.reflectors)
    band = max(2, tile_rays // (k * k * width) // 2 * 2)  # image rows a band, even
    image = np.empty((height, width, 3), dtype=np.float32)
    pixels = np.empty((height, width, 3), dtype=np.uint8)
    mask = np.empty((height, width), dtype=bool)
    reflector = np.empty((height, width), dtype=np.int16)
    from tqdm import tqdm

    starts = range(0, height, band)
    with tqdm(
        total=len(starts),
        desc="ray tracing",
        unit="band",
        disable=not progress,
        leave=False,
        file=sys.stderr,
        mininterval=0.5,
    ) as bar:
        for top in starts:
            _trace_band(
                rays,
                view,
                proj,
                scene.max_bounces,
                (width, height),
                k,
                top,
                min(top + band, height),
                first_reflector,
                (image, pixels, mask, reflector),
            )
            bar.update()
    return RayImage(image, mask, reflector, pixels)


def _trace_band(
    rays: RayScene,
    view: np.ndarray,
    proj: np.ndarray,
    bounces: int,
    size: tuple[int, int],
    k: int,
    top: int,
    bottom: int,
    first_reflector: int,
    into: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
) -> None:
    """Trace image rows ``top`` to ``bottom`` (k x k rays a pixel) into the result arrays."""
    image, pixels, mask, reflector = into
    width, height = size
    traced = rays.render(
        view, proj, (k * width, k * height), bounces=bounces, rows=(k * top, k * bottom)
    )
    assert traced.reflector is not None
    rows = bottom - top
    surface = traced.reflector.reshape(rows, k, width, k)[:, k // 2, :, k // 2]
    reflector[top:bottom] = np.where(surface >= first_reflector, surface - first_reflector, -1)
    colors = traced.image.reshape(rows, k, width, k, 3).mean(axis=(1, 3))
    image[top:bottom] = colors
    pixels[top:bottom] = _to_uint8(colors)
    mask[top:bottom] = traced.reflective_mask.reshape(rows, k, width, k).all(axis=(1, 3))


@dataclass(frozen=True)
class ReflectionHits:
    """Where the reflected ray of each pixel of a view goes, for judging screen-space
    reflections: which surfaces the view itself shows.

    ``reflector`` ``(h, w)`` int: the index in the scene's reflectors of the reflector
    whose front the pixel's primary ray meets (-1: none, or its back); ``point`` ``(h,
    w, 3)`` the world point the reflected ray meets first (NaN where it escapes or the
    pixel shows no reflector); ``escaped`` ``(h, w)`` bool: the reflected ray meets
    nothing; ``on_screen``: the point lies within the view (its sides, near and far
    planes); ``visible``: on screen, and the first surface the viewer sees along the
    line of sight to it (nothing nearer in the way, and not a surface seen from behind).
    Row 0 at the top."""

    reflector: np.ndarray
    point: np.ndarray
    escaped: np.ndarray
    on_screen: np.ndarray
    visible: np.ndarray


def reflection_hits(scene: Scene, size: Sequence[int], tolerance: float = 1e-4) -> ReflectionHits:
    """:class:`ReflectionHits` of ``scene`` seen by its camera at ``size`` (width, height):
    one primary ray per pixel centre, as :func:`trace_scene` traces them, its reflection
    off the reflector it meets (about the interpolated normal turned towards it, from
    just off the surface), and a ray from the eye towards each point met. A point is
    visible when that ray's first surface lies within ``tolerance`` (a share of the
    distance) of it. Perspective cameras."""
    width, height = (int(v) for v in size)
    rays = ray_scene(scene)
    first_reflector = len(rays.surfaces) - len(scene.reflectors)
    camera = scene.camera
    view = camera.view()
    projection = camera.projection(width / height)
    matrix = projection @ view
    inverse = np.linalg.inv(matrix)
    x = (np.arange(width) + 0.5) / width * 2.0 - 1.0
    y = 1.0 - (np.arange(height) + 0.5) / height * 2.0
    grid_x, grid_y = np.meshgrid(x, y)
    flat = np.stack([grid_x.ravel(), grid_y.ravel()], axis=1)
    near = _unproject(inverse, flat, -1.0)
    directions = _unproject(inverse, flat, 1.0) - near
    directions /= np.linalg.norm(directions, axis=1, keepdims=True)

    def beyond(points: np.ndarray) -> np.ndarray:
        clip = np.column_stack([points, np.ones(len(points))]) @ matrix.T
        return clip[:, 2] > clip[:, 3]

    count = width * height
    seen = rays._first_visible(near, directions, None, beyond)
    surface = np.where(seen.face >= 0, rays._face_surface[np.maximum(seen.face, 0)], -1)
    mirror = (seen.face >= 0) & seen.front & (surface >= first_reflector)
    mirror &= rays._reflective[np.maximum(surface, 0)]
    reflector = np.where(mirror, surface - first_reflector, -1)
    point = np.full((count, 3), np.nan)
    escaped = np.zeros(count, dtype=bool)
    chosen = np.flatnonzero(mirror)
    if len(chosen):
        faces = seen.face[chosen]
        corners = rays._faces[faces]
        weights = _barycentric(rays._triangles[faces], seen.point[chosen])
        normals = np.einsum("nk,nkd->nd", weights, rays._normals[corners])
        normals /= np.maximum(np.linalg.norm(normals, axis=1, keepdims=True), 1e-300)
        incoming = directions[chosen]
        towards = np.where(np.einsum("nd,nd->n", normals, incoming) > 0, -1.0, 1.0)[:, None]
        facing = normals * towards
        reflected = incoming - 2.0 * np.einsum("nd,nd->n", incoming, facing)[:, None] * facing
        reflected /= np.linalg.norm(reflected, axis=1, keepdims=True)
        face_normals = rays._face_normals[faces]
        leave = face_normals / np.linalg.norm(face_normals, axis=1, keepdims=True)
        met = rays._first_visible(
            rays.offset_points(seen.point[chosen], leave), reflected, None, None
        )
        hit = met.face >= 0
        point[chosen[hit]] = met.point[hit]
        escaped[chosen[~hit]] = True
    found = np.flatnonzero(np.isfinite(point[:, 0]))
    on_screen = np.zeros(count, dtype=bool)
    visible = np.zeros(count, dtype=bool)
    if len(found):
        targets = point[found]
        clip = np.column_stack([targets, np.ones(len(found))]) @ matrix.T
        w = clip[:, 3]
        inside = w > 0
        ndc = clip[:, :3] / np.where(inside, w, 1.0)[:, None]
        inside &= (np.abs(ndc) <= 1.0).all(axis=1)
        on_screen[found] = inside
        eye = np.asarray(camera.eye, dtype=np.float64)
        offset = targets - eye
        distance = np.linalg.norm(offset, axis=1)
        look = offset / np.maximum(distance, 1e-300)[:, None]
        forward = -view[2, :3]
        start = camera.depth_range[0] / np.maximum(look @ forward, 1e-12)
        sight = rays._first_visible(eye + look * start[:, None], look, None, None)
        reached = np.where(sight.face >= 0, np.linalg.norm(sight.point - eye, axis=1), np.inf)
        visible[found] = inside & (np.abs(reached - distance) <= tolerance * distance)
    shape = (height, width)
    return ReflectionHits(
        reflector.reshape(shape),
        point.reshape(height, width, 3),
        escaped.reshape(shape),
        on_screen.reshape(shape),
        visible.reshape(shape),
    )


def trace_frame(scene: Scene, size: Sequence[int], progress: bool = False) -> np.ndarray:
    """The ``raytrace`` technique (:mod:`mirrorlab.techniques`): ``scene``'s ground truth at
    ``size`` as ``(h, w, 3)`` uint8."""
    return trace_scene(scene, size, progress=progress).to_uint8()
