"""The labs' pictures and meshes as the checker draws them: each picture's mipmap levels,
made on the CPU, are texel for texel what Mesa's own ``glGenerateMipmap`` makes of level
0 (the oracle); and the asset cache gives back what trimesh and Pillow read, making an
entry once and again when it cannot be read."""

from __future__ import annotations

import numpy as np
import pytest

from mirrorlab.gl.opengl import GL
from mirrorlab.labs.trusted import assets, session


def gl_levels(level0: np.ndarray, count: int) -> list[np.ndarray]:
    """``count`` levels of a texture made from ``level0`` (GL's row order) by
    ``glGenerateMipmap``, read back."""
    texture = int(GL.glGenTextures(1))
    try:
        GL.glBindTexture(GL.GL_TEXTURE_2D, texture)
        GL.glPixelStorei(GL.GL_UNPACK_ALIGNMENT, 1)
        GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 1)
        height, width = level0.shape[:2]
        GL.glTexImage2D(
            GL.GL_TEXTURE_2D,
            0,
            GL.GL_RGB8,
            width,
            height,
            0,
            GL.GL_RGB,
            GL.GL_UNSIGNED_BYTE,
            level0,
        )
        GL.glGenerateMipmap(GL.GL_TEXTURE_2D)
        levels = []
        for number in range(count):
            data = GL.glGetTexImage(GL.GL_TEXTURE_2D, number, GL.GL_RGB, GL.GL_UNSIGNED_BYTE)
            size = max(width >> number, 1)
            levels.append(np.frombuffer(data, np.uint8).reshape(size, size, 3))
        return levels
    finally:
        GL.glPixelStorei(GL.GL_UNPACK_ALIGNMENT, 4)
        GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 4)
        GL.glBindTexture(GL.GL_TEXTURE_2D, 0)
        GL.glDeleteTextures([texture])


@pytest.mark.parametrize("name", session.PICTURES)
def test_a_pictures_mipmaps_are_mesas_own(gl_context, name):
    levels = session.picture_levels(name)
    assert len(levels) == int(np.log2(levels[0].shape[0])) + 1
    assert all(not level.flags.writeable for level in levels)
    for number, (mine, mesas) in enumerate(
        zip(levels, gl_levels(levels[0], len(levels)), strict=True)
    ):
        assert np.array_equal(mine, mesas), (name, number)


def test_a_picture_of_another_shape_is_left_to_gl():
    assert session.mipmap_levels(np.zeros((4, 8, 3), np.uint8)) is None
    assert session.mipmap_levels(np.zeros((6, 6, 3), np.uint8)) is None
    assert len(session.mipmap_levels(np.zeros((8, 8, 3), np.uint8)) or []) == 4


def test_the_asset_cache_gives_back_what_was_read_and_remakes_a_broken_entry(tmp_path, monkeypatch):
    from mirrorlab.data import model_file
    from mirrorlab.scene.mesh import load_mesh

    monkeypatch.setenv("MIRRORLAB_CACHE", str(tmp_path))
    made = []

    def read():
        made.append(1)
        data = load_mesh(model_file("hand"))
        return {"vertices": data.interleaved(), "indices": data.indices.reshape(-1)}

    sources = [model_file("hand")]
    first = assets.cached_arrays("mesh", "hand", sources, ("trimesh",), read)
    again = assets.cached_arrays("mesh", "hand", sources, ("trimesh",), read)
    assert made == [1]
    for key in ("vertices", "indices"):
        assert np.array_equal(first[key], again[key]) and first[key].dtype == again[key].dtype
    (entry,) = (tmp_path / assets.FOLDER).glob("mesh-hand-*.npz")
    entry.write_bytes(b"not an npz")
    remade = assets.cached_arrays("mesh", "hand", sources, ("trimesh",), read)
    assert made == [1, 1] and np.array_equal(remade["indices"], first["indices"])
    assert not list((tmp_path / assets.FOLDER).glob("*.tmp"))
