"""The meshes in models/: loadable, lit the right way round, textured where needed."""

from pathlib import Path

import numpy as np
import pytest

from mirrorlab.data import data_path
from mirrorlab.scene.loader import load_scene
from mirrorlab.scene.mesh import load_mesh, vertex_normals
from mirrorlab.scene.robot import model_file, scene_parts

MODELS = sorted((data_path("models")).glob("*.obj"))


def test_every_model_file_is_tested_and_the_scenes_use_only_them():
    used = {
        part.mesh.resolve()
        for name in ("lab20", "sphere", "cone", "mirror_and_sphere")
        for part in scene_parts(load_scene(name))
    }
    used |= {
        r.mesh.resolve()
        for name in ("sphere", "cone", "mirror_and_sphere")
        for r in load_scene(name).reflectors
        if r.kind == "curved"
    }
    assert used <= {m.resolve() for m in MODELS}
    assert len(MODELS) >= 9


@pytest.mark.parametrize("path", MODELS, ids=lambda p: Path(p).stem)
def test_model_loads_with_outward_ccw_triangles(path):
    mesh = load_mesh(path)
    assert mesh.positions.dtype == np.float32 and mesh.indices.dtype == np.uint32
    assert mesh.interleaved().shape == (len(mesh.positions), 8)
    tris = mesh.positions[mesh.indices].astype(np.float64)
    winding = np.cross(tris[:, 1] - tris[:, 0], tris[:, 2] - tris[:, 0])
    normals = mesh.normals[mesh.indices].mean(axis=1)
    # back-face culling relies on this: the winding agrees with the shading normal
    assert np.all(np.einsum("ij,ij->i", winding, normals) > 0)
    assert np.allclose(np.linalg.norm(mesh.normals, axis=1), 1, atol=1e-5)


def test_textured_base_has_texture_coordinates():
    uvs = load_mesh(model_file("base")).uvs
    assert uvs.min() >= 0 and uvs.max() > 0.9


def test_the_robot_draws_a_few_hundred_triangles():
    robot = [p for p in scene_parts(load_scene("lab20")) if p.name.startswith("robot.")]
    assert len(robot) == 6
    total = sum(load_mesh(p.mesh).triangle_count for p in robot)
    assert 300 <= total <= 600


def test_vertex_normals_never_nan_for_degenerate_triangles():
    positions = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [5, 5, 5]], float)
    normals = vertex_normals(positions, np.array([[0, 1, 2]]))
    assert np.all(np.isfinite(normals))
    assert np.allclose(normals[3], (0, 1, 0))  # in no triangle: the fallback


def test_missing_and_broken_mesh_files_name_the_file(tmp_path):
    with pytest.raises(FileNotFoundError, match=r"nothere\.obj"):
        load_mesh(tmp_path / "nothere.obj")
    bad = tmp_path / "empty.obj"
    bad.write_text("# no faces\nv 0 0 0\n")
    with pytest.raises(ValueError, match=r"empty\.obj"):
        load_mesh(bad)
