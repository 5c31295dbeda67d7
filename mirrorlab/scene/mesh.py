"""Meshes: trimesh files turned into flat numpy arrays ready for a vertex buffer, and the
look a glTF file gives its mesh (base colour and base colour texture)."""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np

MAX_MESH_BYTES = 256 * 2**20
"""Largest mesh file read."""
MAX_COORDINATE = 1e6
"""Largest vertex coordinate magnitude (as :data:`mirrorlab.scene.loader.MAX_MAGNITUDE`)."""
GLTF_SUFFIXES = (".glb", ".gltf")
"""Mesh files whose material is read (glTF's ``pbrMetallicRoughness``)."""


class MeshFileError(ValueError):
    """A mesh file mirrorlab read but cannot use; the message names the file."""


@dataclass(frozen=True, eq=False)
class MeshMaterial:
    """The look a mesh file gives its mesh: ``base_color`` RGB in [0, 1] (glTF's
    ``baseColorFactor``, alpha dropped) and ``base_color_texture`` ``(h, w, 3)`` uint8,
    row 0 at the top (its ``baseColorTexture``), each None when the file has none. Only
    glTF files (.glb, .gltf) have one here; a scene's own ``color`` and ``texture`` win."""

    base_color: tuple[float, float, float] | None = None
    base_color_texture: np.ndarray | None = None


@dataclass(frozen=True)
class MeshTexture:
    """The base colour texture of the glTF file ``mesh``, as a part's texture source (a
    picture file's is its Path)."""

    mesh: Path


TextureSource = Path | MeshTexture
"""Where a part's texture comes from: a picture file, or a glTF file's own texture."""


@dataclass(frozen=True)
class MeshData:
    """Triangle mesh as arrays.

    positions ``(n, 3)`` float32 in the part's own frame (scene units),
    normals ``(n, 3)`` float32 unit length, uvs ``(n, 2)`` float32 texture
    coordinates (zeros where the file has none), indices ``(m, 3)`` uint32
    counter-clockwise seen from outside; ``material`` what the file says the mesh looks
    like (see :class:`MeshMaterial`).
    """

    positions: np.ndarray
    normals: np.ndarray
    uvs: np.ndarray
    indices: np.ndarray
    material: MeshMaterial = field(default_factory=MeshMaterial)

    @property
    def triangle_count(self) -> int:
        return int(self.indices.shape[0])

    def interleaved(self) -> np.ndarray:
        """``(n, 8)`` float32 rows of x, y, z, nx, ny, nz, u, v."""
        return np.ascontiguousarray(
            np.hstack([self.positions, self.normals, self.uvs]), dtype=np.float32
        )


def vertex_normals(positions: np.ndarray, indices: np.ndarray) -> np.ndarray:
    """Area-weighted vertex normals ``(n, 3)`` of a triangle mesh.

    Vertices that belong to no triangle, or only to degenerate ones, get
    (0, 1, 0) rather than NaN.
    """
    p = np.asarray(positions, dtype=np.float64)
    tris = p[indices]
    face_normals = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    sums = np.zeros_like(p)
    for corner in range(3):
        np.add.at(sums, indices[:, corner], face_normals)
    lengths = np.linalg.norm(sums, axis=1, keepdims=True)
    fallback = np.array([0.0, 1.0, 0.0])
    return np.where(lengths > 1e-20, sums / np.maximum(lengths, 1e-300), fallback)


def load_mesh(path: str | Path) -> MeshData:
    """Load a mesh file (OBJ, GLB, PLY, ... whatever trimesh reads) as :class:`MeshData`.

    The file's vertex order is kept, so texture seams stay split. Raises
    ValueError naming the file when it holds no triangles.
    """
    import trimesh

    path = Path(path)
    if not path.is_file():
        raise FileNotFoundError(f"mesh file {path} does not exist")
    size = path.stat().st_size
    if size == 0:
        raise ValueError(f"mesh file {path} is empty (0 bytes)")
    if size > MAX_MESH_BYTES:
        raise ValueError(
            f"mesh file {path} is {size / 2**20:,.0f} MB, too large: expected "
            f"at most {MAX_MESH_BYTES // 2**20} MB"
        )
    material = MeshMaterial()
    try:
        with warnings.catch_warnings():
            # trimesh's texture merge warns (an all-NaN median) on some files it then
            # reads correctly; the warning says nothing to a mirrorlab user.
            warnings.filterwarnings("ignore", category=RuntimeWarning, module="trimesh")
            if path.suffix.lower() in GLTF_SUFFIXES:
                mesh, material = _load_gltf(path)
            else:
                mesh = trimesh.load_mesh(path, process=False, maintain_order=True)
    except MeshFileError:
        raise
    except Exception as exc:
        raise ValueError(f"mesh file {path}: trimesh could not read it ({exc})") from exc
    positions = np.asarray(mesh.vertices, dtype=np.float64)
    indices = np.asarray(mesh.faces, dtype=np.int64)
    if indices.size == 0:
        raise ValueError(f"mesh file {path}: expected triangles, found none")
    if not np.all(np.isfinite(positions)):
        row = int(np.flatnonzero(~np.isfinite(positions).all(axis=1))[0])
        raise ValueError(
            f"mesh file {path}: vertex {row + 1} is not finite ({positions[row].tolist()})"
        )
    if np.abs(positions).max() > MAX_COORDINATE:
        row = int(np.flatnonzero((np.abs(positions) > MAX_COORDINATE).any(axis=1))[0])
        raise ValueError(
            f"mesh file {path}: vertex {row + 1} ({positions[row].tolist()}) "
            f"lies beyond {MAX_COORDINATE:g}, too far for OpenGL's 32-bit floats"
        )
    uv = getattr(mesh.visual, "uv", None)
    uvs = np.zeros((len(positions), 2)) if uv is None else np.asarray(uv, dtype=np.float64)
    return MeshData(
        positions=positions.astype(np.float32),
        normals=vertex_normals(positions, indices).astype(np.float32),
        uvs=uvs.astype(np.float32),
        indices=indices.astype(np.uint32),
        material=material,
    )


def _load_gltf(path: Path):
    """A glTF file's geometry as one trimesh mesh (its nodes' transforms applied), and its
    :class:`MeshMaterial`. A file of several primitives gets their shared base colour when
    they all have the same one and no texture; otherwise no material (one mesh is drawn
    with one look)."""
    import trimesh

    geometries = trimesh.load_scene(path, process=False, maintain_order=True).dump(
        concatenate=False
    )
    geometries = [g for g in geometries if isinstance(g, trimesh.Trimesh)]
    if not geometries:
        raise MeshFileError(f"mesh file {path}: expected triangles, found none")
    if len(geometries) == 1:
        mesh = geometries[0]
        return mesh, _material_of(path, mesh)
    materials = [_material_of(path, g) for g in geometries]
    colors = {m.base_color for m in materials}
    shared = len(colors) == 1 and all(m.base_color_texture is None for m in materials)
    mesh = trimesh.util.concatenate(geometries)
    return mesh, MeshMaterial(base_color=colors.pop()) if shared else MeshMaterial()


def _material_of(path: Path, mesh) -> MeshMaterial:
    """The base colour and base colour texture of one trimesh mesh's PBR material."""
    from trimesh.visual.material import PBRMaterial

    from mirrorlab.scene.backgrounds import MAX_PICTURE_PIXELS

    material = getattr(mesh.visual, "material", None)
    if not isinstance(material, PBRMaterial):
        return MeshMaterial()
    color = None
    if material.baseColorFactor is not None:
        factor = np.asarray(material.baseColorFactor, dtype=np.float64).ravel()[:3]
        if factor.dtype.kind in "ui" or factor.max() > 1.0:  # trimesh keeps 0-255 values
            factor = factor / 255.0
        red, green, blue = (float(c) for c in np.clip(factor, 0.0, 1.0))
        color = (red, green, blue)
    texture = None
    image = material.baseColorTexture
    if image is not None and getattr(mesh.visual, "uv", None) is not None:
        width, height = image.size
        if width * height > MAX_PICTURE_PIXELS:
            raise MeshFileError(
                f"mesh file {path}: its base colour texture is {width}x{height}, "
                f"too large: expected at most {MAX_PICTURE_PIXELS:,} pixels"
            )
        texture = np.ascontiguousarray(np.asarray(image.convert("RGB"), dtype=np.uint8))
        texture.flags.writeable = False
    return MeshMaterial(base_color=color, base_color_texture=texture)


@lru_cache(maxsize=64)
def _cached_material(path: Path, stamp: tuple[int, int]) -> MeshMaterial:
    return load_mesh(path).material


def mesh_material(path: Path) -> MeshMaterial:
    """The :class:`MeshMaterial` of the mesh file ``path`` (read once per version of the
    file); an empty one for files other than glTF, which are not read here."""
    if Path(path).suffix.lower() not in GLTF_SUFFIXES:
        return MeshMaterial()
    stat = Path(path).stat()
    return _cached_material(Path(path), (stat.st_mtime_ns, stat.st_size))


def texture_picture(source: TextureSource) -> np.ndarray:
    """The picture of a part's texture ``source``, ``(h, w, 3)`` uint8, row 0 at the top:
    a picture file, or a glTF file's base colour texture."""
    if isinstance(source, MeshTexture):
        picture = mesh_material(source.mesh).base_color_texture
        if picture is None:
            raise ValueError(f"mesh file {source.mesh} has no base colour texture")
        return picture
    from mirrorlab.scene.backgrounds import load_picture

    return load_picture(source)
