"""The ray tracer works in bands of rows: the picture is the same whatever the band
size, and the memory it takes beyond the result is one band's, not the image's."""

from __future__ import annotations

import tracemalloc

import numpy as np
import pytest

import mirrorlab
from mirrorlab.raytrace import trace_scene


@pytest.mark.parametrize(("size", "supersample"), [((37, 23), 1), ((20, 15), 2)])
def test_bands_give_the_picture_of_one_band(size, supersample):
    scene = mirrorlab.load_scene("two_mirrors")
    whole = trace_scene(scene, size, supersample, tile_rays=10**9)
    banded = trace_scene(scene, size, supersample, tile_rays=64)  # 2 rows a band
    assert np.array_equal(whole.to_uint8(), banded.to_uint8())
    assert np.array_equal(whole.image, banded.image)
    assert np.array_equal(whole.reflective_mask, banded.reflective_mask)
    assert whole.reflector is not None and banded.reflector is not None
    assert np.array_equal(whole.reflector, banded.reflector)
    assert banded.image.shape == (size[1], size[0], 3)


def test_memory_beyond_the_result_is_one_bands():
    scene = mirrorlab.load_scene("lab20")
    trace_scene(scene, (16, 16))  # meshes and pictures read once, outside the count

    def peak(side: int, tile_rays: int) -> int:
        tracemalloc.start()
        try:
            trace_scene(scene, (side, side), tile_rays=tile_rays)
            return tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()

    def result_bytes(side: int) -> int:
        return side * side * (3 * 4 + 3 + 1 + 2)  # float32 RGB, uint8 RGB, mask, reflector

    # Four times the pixels: in 2048-ray bands the peak grows by the result's growth
    # alone (and a little); traced whole, by the per-ray work, several times more.
    banded = peak(320, 2048) - peak(160, 2048)
    whole = peak(320, 10**9) - peak(160, 10**9)
    grown = result_bytes(320) - result_bytes(160)
    assert banded < grown + 1e6, f"banded peak grew {banded / 1e6:.2f} MB, result {grown / 1e6:.2f}"
    assert whole > 5 * grown, f"whole-image peak grew only {whole / 1e6:.2f} MB"


def test_to_uint8_of_a_float_image_rounds_as_gl_does():
    from mirrorlab.raytrace import RayImage

    image = np.array([[[0.0, 0.5 / 255, 1.5 / 255], [2.0, -1.0, 254.5 / 255]]])
    got = RayImage(image, np.zeros((1, 2), bool)).to_uint8()
    assert got.tolist() == [[[0, 0, 2], [255, 0, 254]]]
