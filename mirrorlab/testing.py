"""Headless render tests of your own reflections: a pytest plugin.

Installing mirrorlab registers it with pytest (entry point ``pytest11``), which gives
every test the :func:`renderer` fixture: one headless OpenGL context for the whole test
session, 256 x 256 frames unless a test asks for another size. Compare pictures with
:func:`assert_image_close`; on failure it writes the actual, expected and difference
images and names the folder::

    from mirrorlab.testing import assert_image_close

    def test_my_mirror(renderer):
        image = renderer.render("scenes/my_room.toml", method="stencil")
        assert_image_close(image, "tests/expected/my_room.png", tolerance=8)

Failure images go to ``mirrorlab-failures/`` in the working folder (the environment
variable ``MIRRORLAB_FAILURES`` names another). Importing this module loads no OpenGL.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from mirrorlab.api import Renderer

RENDER_SIZE = (256, 256)


@pytest.fixture(scope="session")
def renderer() -> Iterator[Renderer]:
    """A :class:`mirrorlab.Renderer` kept open for the whole test session."""
    with Renderer(RENDER_SIZE) as shared:
        yield shared


def _as_image(value: np.ndarray | str | Path, what: str) -> np.ndarray:
    if isinstance(value, str | Path):
        from mirrorlab.scene.backgrounds import load_picture

        return load_picture(value)
    image = np.asarray(value)
    if image.ndim != 3 or image.shape[2] != 3:
        raise ValueError(f"{what} must be an (h, w, 3) image, got shape {image.shape}")
    return image


def failure_folder() -> Path:
    return Path(os.environ.get("MIRRORLAB_FAILURES", "mirrorlab-failures"))


def difference_image(actual: np.ndarray, expected: np.ndarray) -> np.ndarray:
    """``|actual - expected|`` amplified four times for the eye, ``(h, w, 3)`` uint8."""
    diff = np.abs(actual.astype(np.int16) - expected.astype(np.int16)) * 4
    return np.clip(diff, 0, 255).astype(np.uint8)


def save_images(name: str, **images: np.ndarray) -> Path:
    """Write ``images`` as ``<failure folder>/<name>_<key>.png``; returns the folder."""
    from PIL import Image

    folder = failure_folder()
    folder.mkdir(parents=True, exist_ok=True)
    for key, image in images.items():
        Image.fromarray(np.asarray(image, dtype=np.uint8)).save(folder / f"{name}_{key}.png")
    return folder


def _test_name() -> str:
    current = os.environ.get("PYTEST_CURRENT_TEST", "image").split(" ")[0]
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", current.split("::")[-1]) or "image"


def assert_image_close(actual: np.ndarray | str | Path, expected: np.ndarray | str | Path,
                       tolerance: int = 2, fraction: float = 1.0,
                       max_mean: float | None = None, name: str | None = None) -> None:
    """Assert that two ``(h, w, 3)`` uint8 images (or PNG files) agree: at least
    ``fraction`` of the pixels have every channel within ``tolerance`` (0-255 scale), and,
    when given, the mean absolute channel difference is at most ``max_mean``.

    On failure the actual, expected and difference images are written (see
    :func:`failure_folder`) as ``NAME_actual.png`` and so on, ``name`` defaulting to the
    running test's name, and the AssertionError says where.
    """
    actual_image = _as_image(actual, "actual")
    expected_image = _as_image(expected, "expected")
    label = name or _test_name()
    if actual_image.shape != expected_image.shape:
        raise AssertionError(f"{label}: image shape {actual_image.shape} differs from the "
                             f"expected {expected_image.shape}")
    diff = np.abs(actual_image.astype(np.int16) - expected_image.astype(np.int16))
    within = float(np.mean(diff.max(axis=-1) <= tolerance))
    mean = float(diff.mean())
    if within < fraction or (max_mean is not None and mean > max_mean):
        folder = save_images(label, actual=actual_image, expected=expected_image,
                             diff=difference_image(actual_image, expected_image))
        bound = "" if max_mean is None else f" (max {max_mean})"
        raise AssertionError(
            f"{label}: {within:.4%} of pixels within {tolerance}/255 (need {fraction:.2%}), "
            f"mean difference {mean:.3f}/255{bound}; images in {folder}/{label}_*.png")
