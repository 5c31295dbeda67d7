"""A glTF file's own material: its base colour factor and base colour texture are used when
the scene gives no colour or texture of its own, by the rasteriser and the ray tracer alike.
The GLB files are made here with trimesh, as a user's exporter would make them."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import mirrorlab
from mirrorlab.api import raytrace
from mirrorlab.scene.model import MeshObject
from tests.imagecheck import assert_images_close

SIZE = (96, 96)
QUADRANTS = {
    "top_left": (230, 20, 20),
    "top_right": (20, 200, 40),
    "bottom_left": (30, 40, 220),
    "bottom_right": (235, 215, 30),
}
"""The test picture: a colour per quadrant, so a flip in either direction shows."""
FACTOR = (0.2, 0.6, 0.1)


def quadrant_picture(side: int = 8) -> np.ndarray:
    half = side // 2
    picture = np.zeros((side, side, 3), dtype=np.uint8)
    picture[:half, :half] = QUADRANTS["top_left"]
    picture[:half, half:] = QUADRANTS["top_right"]
    picture[half:, :half] = QUADRANTS["bottom_left"]
    picture[half:, half:] = QUADRANTS["bottom_right"]
    return picture


def write_quad_glb(
    path: Path, texture: np.ndarray | None = None, factor: tuple[float, float, float] | None = None
) -> Path:
    """A 2 x 2 square in the z = 0 plane facing +z, texture coordinates (0, 0) at its lower
    left, with a PBR material of ``texture`` and/or ``factor``; written by trimesh."""
    import trimesh
    from PIL import Image

    vertices = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], dtype=float)
    faces = np.array([[0, 1, 2], [0, 2, 3]])
    uv = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], dtype=float)
    material = trimesh.visual.material.PBRMaterial(
        baseColorFactor=[*(factor or (1.0, 1.0, 1.0)), 1.0],
        baseColorTexture=None if texture is None else Image.fromarray(texture),
    )
    mesh = trimesh.Trimesh(
        vertices,
        faces,
        process=False,
        visual=trimesh.visual.TextureVisuals(uv=uv, material=material),
    )
    mesh.export(path)
    return path


def scene_file(folder: Path, mesh: Path, extra: str = "") -> Path:
    """The square seen head-on, lit straight on (ambient 0.3 + 0.7: full brightness)."""
    path = folder / f"{mesh.stem}.toml"
    path.write_text(f"""
name = "{mesh.stem}"
ambient = 0.3

[camera]
eye = [0.0, 0.0, 5.0]
target = [0.0, 0.0, 0.0]
fovy = 30.0

[background]
color = [0.0, 0.0, 0.0]

[[lights]]
direction = [0.0, 0.0, 1.0]
intensity = 0.7

[[objects]]
mesh = "{mesh.name}"
{extra}
""")
    return path


@pytest.fixture(scope="module")
def renderer():
    with mirrorlab.Renderer(size=SIZE) as kept:
        yield kept


def quadrant_means(image: np.ndarray) -> dict[str, np.ndarray]:
    """Mean colour of a 6 x 6 patch at the middle of each quadrant of the square (which
    covers the centre of the frame)."""
    height, width = image.shape[:2]
    middle_x, middle_y = width // 2, height // 2
    spots = {
        "top_left": (-1, -1),
        "top_right": (1, -1),
        "bottom_left": (-1, 1),
        "bottom_right": (1, 1),
    }
    out = {}
    for name, (dx, dy) in spots.items():
        x, y = middle_x + dx * 12, middle_y + dy * 12
        out[name] = image[y - 3 : y + 3, x - 3 : x + 3].reshape(-1, 3).mean(axis=0)
    return out


def test_a_glb_texture_is_used_when_the_scene_gives_none(tmp_path, renderer):
    glb = write_quad_glb(tmp_path / "textured.glb", texture=quadrant_picture())
    scene = mirrorlab.load_scene(scene_file(tmp_path, glb))
    quad = scene.objects[0]
    assert isinstance(quad, MeshObject) and quad.color is None and quad.texture is None
    drawn = renderer.render(scene)
    traced = raytrace(scene, size=SIZE)
    for image in (drawn, traced):
        for name, mean in quadrant_means(image).items():
            assert np.abs(mean - QUADRANTS[name]).max() <= 6, (name, mean)
    assert_images_close("gltf_texture_raster_vs_trace", drawn, traced, 12, 0.97, 3.0)


def test_a_glb_base_colour_is_used_and_the_scene_colour_wins(tmp_path, renderer):
    glb = write_quad_glb(tmp_path / "green.glb", factor=FACTOR)
    plain = mirrorlab.load_scene(scene_file(tmp_path, glb))
    drawn = renderer.render(plain)
    traced = raytrace(plain, size=SIZE)
    expected = np.round(np.array(FACTOR) * 255)
    for image in (drawn, traced):
        centre = image[40:56, 40:56].reshape(-1, 3).mean(axis=0)
        assert np.abs(centre - expected).max() <= 3, centre
    assert_images_close("gltf_colour_raster_vs_trace", drawn, traced, 12, 0.97, 3.0)

    own = mirrorlab.load_scene(scene_file(tmp_path, glb, "color = [1.0, 0.0, 1.0]"))
    centre = renderer.render(own)[40:56, 40:56].reshape(-1, 3).mean(axis=0)
    assert np.abs(centre - [255, 0, 255]).max() <= 3, centre


def test_the_scene_texture_wins_and_the_glb_factor_tints_it(tmp_path, renderer):
    from PIL import Image

    glb = write_quad_glb(tmp_path / "both.glb", texture=quadrant_picture(), factor=(1, 1, 1))
    Image.fromarray(np.full((4, 4, 3), 200, dtype=np.uint8)).save(tmp_path / "grey.png")
    scene = mirrorlab.load_scene(scene_file(tmp_path, glb, 'texture = "grey.png"'))
    drawn = renderer.render(scene)
    for mean in quadrant_means(drawn).values():
        assert np.abs(mean - 200).max() <= 3, mean


def test_a_scene_without_colour_saves_without_one(tmp_path):
    glb = write_quad_glb(tmp_path / "saved.glb", factor=FACTOR)
    scene = mirrorlab.load_scene(scene_file(tmp_path, glb))
    assert "color" not in scene.to_toml().split("[[objects]]")[1]
    again = tmp_path / "again.toml"
    again.write_text(scene.to_toml())
    quad = mirrorlab.load_scene(again).objects[0]
    assert isinstance(quad, MeshObject) and quad.color is None
