"""The pytest plugin as a user meets it: a test file of their own, run by pytest in a folder
of its own. The first run fails in a few lines saying how to make the expected image;
``--mirrorlab-update`` makes it; a changed picture fails naming the actual, expected and
difference images (no traceback); ``--mirrorlab-update`` takes the new picture."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
from PIL import Image

USER_TEST = """
from mirrorlab.testing import assert_image_close


def test_my_mirror(renderer):
    image = renderer.render("lab20", size=(64, 48), method="{method}")
    assert_image_close(image, "expected/my_mirror.png", tolerance=4, fraction=0.99)
"""


def run_pytest(folder: Path, *args: str) -> subprocess.CompletedProcess:
    """pytest on the user's file, with the environment a user has (tests/imagecheck.py
    points MIRRORLAB_FAILURES at tests/_failures in this process)."""
    env = {k: v for k, v in os.environ.items() if k != "MIRRORLAB_FAILURES"}
    return subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "test_mine.py", *args],
        cwd=folder,
        capture_output=True,
        text=True,
        timeout=300,
        env=env,
    )


def failure_section(output: str) -> list[str]:
    """The lines pytest printed for the failing test, between its header and the summary."""
    lines = output.splitlines()
    start = next(
        i for i, line in enumerate(lines) if "test_my_mirror" in line and line.startswith("_")
    )
    end = next(i for i, line in enumerate(lines) if i > start and line.startswith("="))
    return [line for line in lines[start + 1 : end] if line.strip()]


def test_the_plugin_makes_checks_and_updates_expected_images(tmp_path):
    (tmp_path / "test_mine.py").write_text(USER_TEST.format(method="ortho"))
    expected = tmp_path / "expected" / "my_mirror.png"

    first = run_pytest(tmp_path)
    assert first.returncode == 1, first.stdout
    section = failure_section(first.stdout)
    assert len(section) <= 3, section
    assert section[0].startswith(
        "test_mine.py:7: test_my_mirror: no expected image "
        "expected/my_mirror.png; run pytest --mirrorlab-update"
    )
    assert "Traceback" not in first.stdout and "def test_my_mirror" not in first.stdout
    assert not expected.exists()

    made = run_pytest(tmp_path, "--mirrorlab-update")
    assert made.returncode == 0, made.stdout
    assert "expected/my_mirror.png (new)" in made.stdout
    picture = np.asarray(Image.open(expected))
    assert picture.shape == (48, 64, 3) and picture.std() > 10

    again = run_pytest(tmp_path)
    assert again.returncode == 0, again.stdout
    assert "expected images written" not in again.stdout

    (tmp_path / "test_mine.py").write_text(USER_TEST.format(method="stencil"))
    changed = run_pytest(tmp_path)
    assert changed.returncode == 1, changed.stdout
    section = failure_section(changed.stdout)
    assert len(section) == 4, section  # the summary line, then the three images
    assert section[0].startswith("test_mine.py:7: test_my_mirror: ")
    assert "of pixels within 4/255 against expected/my_mirror.png (need 99.00%)" in section[0]
    failures = tmp_path / "mirrorlab-failures"
    for line, key in zip(section[1:], ("actual", "expected", "diff"), strict=True):
        assert line.split() == [f"{key}:", f"mirrorlab-failures/test_my_mirror_{key}.png"]
        assert (failures / f"test_my_mirror_{key}.png").is_file()
    assert "Traceback" not in changed.stdout
    assert np.array_equal(np.asarray(Image.open(expected)), picture), "a failure rewrote it"

    updated = run_pytest(tmp_path, "--mirrorlab-update")
    assert updated.returncode == 0, updated.stdout
    assert "expected/my_mirror.png (replaced:" in updated.stdout
    now = np.asarray(Image.open(expected))
    assert np.array_equal(now, np.asarray(Image.open(failures / "test_my_mirror_actual.png")))
    assert run_pytest(tmp_path).returncode == 0
