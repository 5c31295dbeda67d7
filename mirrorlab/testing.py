"""Headless render tests of your own reflections: a pytest plugin.

Installing mirrorlab registers it with pytest (entry point ``pytest11``), which gives
every test the :func:`renderer` fixture: one headless OpenGL context for the whole test
session, 256 x 256 frames unless a test asks for another size. Compare pictures with
:func:`assert_image_close`::

    from mirrorlab.testing import assert_image_close

    def test_my_mirror(renderer):
        image = renderer.render("scenes/my_room.toml", method="stencil")
        assert_image_close(image, "tests/expected/my_room.png", tolerance=8)

``pytest --mirrorlab-update`` writes the expected images that are missing or no longer
match (from what the tests rendered), and those tests pass; the summary lists them. On a
failure the actual, expected and difference images are written to ``mirrorlab-failures/``
in the working folder (the environment variable ``MIRRORLAB_FAILURES`` names another),
and pytest reports a few lines naming them instead of a traceback. Importing this module
loads no OpenGL.
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterator
from pathlib import Path
from typing import ClassVar

import numpy as np
import pytest

from mirrorlab.api import Renderer

RENDER_SIZE = (256, 256)
UPDATE_OPTION = "--mirrorlab-update"


class ImageMismatch(AssertionError):
    """Two images disagree (or the expected one is missing): ``summary`` says how, and
    ``images`` names the files written for a look (``actual``, ``expected``, ``diff``)."""

    def __init__(self, summary: str, images: dict[str, Path]) -> None:
        self.summary, self.images = summary, dict(images)
        named = "".join(f"\n  {key + ':':<9} {path}" for key, path in self.images.items())
        super().__init__(summary + named)


class _Session:
    """What the plugin knows of this pytest run: whether to update, and what it wrote."""

    update: ClassVar[bool] = False
    written: ClassVar[list[tuple[Path, str]]] = []


def pytest_addoption(parser: pytest.Parser) -> None:
    group = parser.getgroup("mirrorlab", "mirrorlab render tests")
    group.addoption(
        UPDATE_OPTION,
        action="store_true",
        default=False,
        help="write the expected images that are missing or no longer match "
        "(assert_image_close with a file as the expected image), from what "
        "the tests rendered; those tests pass",
    )


def pytest_configure(config: pytest.Config) -> None:
    _Session.update = bool(config.getoption(UPDATE_OPTION, default=False))
    _Session.written = []


def pytest_unconfigure(config: pytest.Config) -> None:
    _Session.update = False


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo):
    """An :class:`ImageMismatch` is reported as its message and the test's line, not a
    traceback: the pictures say more than the stack."""
    report = yield
    excinfo = call.excinfo
    if report.failed and excinfo is not None and isinstance(excinfo.value, ImageMismatch):
        where = str(item.nodeid)
        for entry in excinfo.traceback:
            if Path(entry.path) == Path(item.path):
                where = f"{item.nodeid.split('::')[0]}:{entry.lineno + 1}"
        report.longrepr = f"{where}: {excinfo.value}"
    return report


def pytest_terminal_summary(terminalreporter, exitstatus: int, config: pytest.Config) -> None:
    if _Session.written:
        terminalreporter.section("mirrorlab: expected images written")
        for path, why in _Session.written:
            terminalreporter.write_line(f"{path} ({why})")


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
    from mirrorlab.files import write_png_atomic

    folder = failure_folder()
    folder.mkdir(parents=True, exist_ok=True)
    for key, image in images.items():
        write_png_atomic(folder / f"{name}_{key}.png", np.asarray(image, dtype=np.uint8))
    return folder


def _test_name() -> str:
    current = os.environ.get("PYTEST_CURRENT_TEST", "image").split(" ")[0]
    return re.sub(r"[^A-Za-z0-9_.-]+", "_", current.split("::")[-1]) or "image"


def _update(path: Path, image: np.ndarray, why: str) -> None:
    from mirrorlab.files import write_png_atomic

    path.parent.mkdir(parents=True, exist_ok=True)
    write_png_atomic(path, image)
    _Session.written.append((path, why))


def assert_image_close(
    actual: np.ndarray | str | Path,
    expected: np.ndarray | str | Path,
    tolerance: int = 2,
    fraction: float = 1.0,
    max_mean: float | None = None,
    name: str | None = None,
) -> None:
    """Assert that two ``(h, w, 3)`` uint8 images (or PNG files) agree: at least
    ``fraction`` of the pixels have every channel within ``tolerance`` (0-255 scale), and,
    when given, the mean absolute channel difference is at most ``max_mean``.

    When ``expected`` is a file that is missing, or that does not match while pytest runs
    with ``--mirrorlab-update``, the actual image is written there instead (and the
    assertion passes only in that update run). On failure the actual, expected and
    difference images are written (see :func:`failure_folder`) as ``NAME_actual.png`` and
    so on, ``name`` defaulting to the running test's name, and :class:`ImageMismatch`
    names them.
    """
    actual_image = _as_image(actual, "actual")
    label = name or _test_name()
    expected_file = Path(expected) if isinstance(expected, str | Path) else None
    if expected_file is not None and not expected_file.exists():
        if _Session.update:
            _update(expected_file, actual_image, "new")
            return
        folder = save_images(label, actual=actual_image)
        raise ImageMismatch(
            f"{label}: no expected image {expected_file}; run pytest "
            f"{UPDATE_OPTION} to write it from this run",
            {"actual": folder / f"{label}_actual.png"},
        )
    expected_image = _as_image(expected, "expected")
    if actual_image.shape != expected_image.shape:
        if _Session.update and expected_file is not None:
            _update(expected_file, actual_image, "replaced: another size")
            return
        folder = save_images(label, actual=actual_image, expected=expected_image)
        raise ImageMismatch(
            f"{label}: image shape {actual_image.shape} differs from the "
            f"expected {expected_image.shape}",
            {key: folder / f"{label}_{key}.png" for key in ("actual", "expected")},
        )
    diff = np.abs(actual_image.astype(np.int16) - expected_image.astype(np.int16))
    within = float(np.mean(diff.max(axis=-1) <= tolerance))
    mean = float(diff.mean())
    if within < fraction or (max_mean is not None and mean > max_mean):
        bound = "" if max_mean is None else f" (max {max_mean})"
        against = f" against {expected_file}" if expected_file is not None else ""
        summary = (
            f"{label}: {within:.4%} of pixels within {tolerance}/255{against} (need "
            f"{fraction:.2%}), mean difference {mean:.3f}/255{bound}"
        )
        if _Session.update and expected_file is not None:
            _update(
                expected_file,
                actual_image,
                f"replaced: {within:.2%} of pixels were within {tolerance}/255",
            )
            return
        folder = save_images(
            label,
            actual=actual_image,
            expected=expected_image,
            diff=difference_image(actual_image, expected_image),
        )
        raise ImageMismatch(
            summary, {key: folder / f"{label}_{key}.png" for key in ("actual", "expected", "diff")}
        )
