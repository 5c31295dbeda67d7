"""The part meshes in models/: loadable, lit the right way round, textured where needed."""

import numpy as np
import pytest

from mirrorlab.scene.mesh import load_mesh, load_model, vertex_normals
from mirrorlab.scene.robot import build_lab_scene

MESHES = sorted({n.mesh for n in build_lab_scene().graph.nodes() if n.mesh})


@pytest.mark.parametrize("name", MESHES)
def test_model_loads_with_outward_ccw_triangles(name):
    mesh = load_model(name)
    assert mesh.positions.dtype == np.float32 and mesh.indices.dtype == np.uint32
    assert mesh.interleaved().shape == (len(mesh.positions), 8)
    tris = mesh.positions[mesh.indices].astype(np.float64)
    winding = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    normals = mesh.normals[mesh.indices].mean(axis=1)
    # back-face culling relies on this: the winding agrees with the shading normal
    assert np.all(np.einsum("ij,ij->i", winding, normals) > 0)
    assert np.allclose(np.linalg.norm(mesh.normals, axis=1), 1, atol=1e-5)


def test_textured_base_has_texture_coordinates():
    uvs = load_model("base").uvs
    assert uvs.min() >= 0 and uvs.max() > 0.9


def test_scene_draws_a_few_hundred_triangles():
    total = sum(load_model(n.mesh).triangle_count
                for n in build_lab_scene().graph.nodes() if n.mesh)
    assert 300 <= total <= 600


def test_vertex_normals_never_nan_for_degenerate_triangles():
    positions = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [5, 5, 5]], float)
    normals = vertex_normals(positions, np.array([[0, 1, 2]]))
    assert np.all(np.isfinite(normals))


def test_missing_and_broken_mesh_files_name_the_file(tmp_path):
    with pytest.raises(FileNotFoundError, match=r"nothere\.obj"):
        load_mesh(tmp_path / "nothere.obj")
    bad = tmp_path / "empty.obj"
    bad.write_text("# no faces\nv 0 0 0\n")
    with pytest.raises(ValueError, match=r"empty\.obj"):
        load_mesh(bad)
