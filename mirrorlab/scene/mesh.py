"""Meshes: trimesh files turned into flat numpy arrays ready for a vertex buffer."""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

MAX_MESH_BYTES = 256 * 2**20
"""Largest mesh file read."""
MAX_COORDINATE = 1e6
"""Largest vertex coordinate magnitude (as :data:`mirrorlab.scene.loader.MAX_MAGNITUDE`)."""


@dataclass(frozen=True)
class MeshData:
    """Triangle mesh as arrays.

    positions ``(n, 3)`` float32 in the part's own frame (scene units),
    normals ``(n, 3)`` float32 unit length, uvs ``(n, 2)`` float32 texture
    coordinates (zeros where the file has none), indices ``(m, 3)`` uint32
    counter-clockwise seen from outside.
    """

    positions: np.ndarray
    normals: np.ndarray
    uvs: np.ndarray
    indices: np.ndarray

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
        raise ValueError(f"mesh file {path} is {size / 2**20:,.0f} MB, too large: expected "
                         f"at most {MAX_MESH_BYTES // 2**20} MB")
    try:
        with warnings.catch_warnings():
            # trimesh's texture merge warns (an all-NaN median) on some files it then
            # reads correctly; the warning says nothing to a mirrorlab user.
            warnings.filterwarnings("ignore", category=RuntimeWarning, module="trimesh")
            mesh = trimesh.load_mesh(path, process=False, maintain_order=True)
    except Exception as exc:
        raise ValueError(f"mesh file {path}: trimesh could not read it ({exc})") from exc
    positions = np.asarray(mesh.vertices, dtype=np.float64)
    indices = np.asarray(mesh.faces, dtype=np.int64)
    if indices.size == 0:
        raise ValueError(f"mesh file {path}: expected triangles, found none")
    if not np.all(np.isfinite(positions)):
        row = int(np.flatnonzero(~np.isfinite(positions).all(axis=1))[0])
        raise ValueError(f"mesh file {path}: vertex {row + 1} is not finite "
                         f"({positions[row].tolist()})")
    if np.abs(positions).max() > MAX_COORDINATE:
        row = int(np.flatnonzero((np.abs(positions) > MAX_COORDINATE).any(axis=1))[0])
        raise ValueError(f"mesh file {path}: vertex {row + 1} ({positions[row].tolist()}) "
                         f"lies beyond {MAX_COORDINATE:g}, too far for OpenGL's 32-bit floats")
    uv = getattr(mesh.visual, "uv", None)
    uvs = np.zeros((len(positions), 2)) if uv is None else np.asarray(uv, dtype=np.float64)
    return MeshData(
        positions=positions.astype(np.float32),
        normals=vertex_normals(positions, indices).astype(np.float32),
        uvs=uvs.astype(np.float32),
        indices=indices.astype(np.uint32),
    )
