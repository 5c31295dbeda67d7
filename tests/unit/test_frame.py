"""Frames show as pictures in Jupyter: IPython's own display formatter (what a notebook
kernel runs on a cell's last value) finds a PNG in a Frame, and the PNG holds the pixels."""

from __future__ import annotations

import io

import numpy as np
import pytest
from PIL import Image

import mirrorlab
from mirrorlab.frame import Frame


def picture(height: int = 6, width: int = 5, channels: int = 3) -> np.ndarray:
    rng = np.random.default_rng(19)
    return rng.integers(0, 256, (height, width, channels), dtype=np.uint8)


def decoded(png: bytes) -> np.ndarray:
    with Image.open(io.BytesIO(png)) as image:
        return np.asarray(image)


def test_ipython_displays_a_frame_as_its_png():
    from IPython.core.formatters import DisplayFormatter

    image = picture()
    data, _ = DisplayFormatter().format(mirrorlab.show(image))
    assert "image/png" in data
    assert np.array_equal(decoded(data["image/png"]), image)


@pytest.mark.parametrize("channels", [3, 4])
def test_the_png_holds_the_pixels(channels):
    image = picture(channels=channels)
    png = Frame(image)._repr_png_()
    assert png is not None
    assert np.array_equal(decoded(png), image)


@pytest.mark.parametrize(
    "array",
    [
        np.zeros((4, 4)),
        np.zeros((4, 4, 3), np.float32),
        np.zeros((0, 4, 3), np.uint8),
        np.zeros((4, 4, 2), np.uint8),
    ],
)
def test_what_is_no_picture_shows_as_an_array(array):
    from IPython.core.formatters import DisplayFormatter

    frame = Frame(array)
    assert frame._repr_png_() is None
    data, _ = DisplayFormatter().format(frame)
    assert "image/png" not in data and data["text/plain"].startswith("Frame(")
    with pytest.raises(ValueError, match="a picture is"):
        frame.png()


def test_a_frame_is_the_array_it_wraps():
    image = picture()
    frame = mirrorlab.show(image)
    assert isinstance(frame, np.ndarray) and frame.shape == image.shape
    assert np.array_equal(frame, image) and frame.dtype == np.uint8
    assert type(frame - image) is np.ndarray  # arithmetic gives plain arrays
    assert isinstance(frame.mean(), float)
    assert type(frame[1:3]) is Frame  # a crop is still a picture


def test_save_writes_the_png(tmp_path):
    image = picture()
    path = mirrorlab.show(image).save(tmp_path / "frame.png")
    assert np.array_equal(np.asarray(Image.open(path)), image)
    assert [p.name for p in tmp_path.iterdir()] == ["frame.png"]
