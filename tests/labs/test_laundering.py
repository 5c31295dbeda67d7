"""Evidence nobody can launder (issue 39, round two): the forgeries of tests/labs/
launderings.py each fail at least one task, with the hint that names what they did; the
whole-frame rule sees a faint overlay in patches and lets noise and half-pixel edges
pass; taint follows pixels through clears, masks, scissors and copies."""

from __future__ import annotations

import numpy as np
import pytest

from mirrorlab.labs import find_lab, lab_names
from mirrorlab.labs.content import reference_folder
from mirrorlab.labs.trusted import calls as C
from mirrorlab.labs.trusted.evidence import Evidence
from mirrorlab.labs.trusted.grading import grade_folder
from mirrorlab.labs.trusted.judging import allowed_pixels, differing, faint_patches
from mirrorlab.labs.trusted.state import Tracker
from tests.labs.conftest import LIMITS, SOLUTIONS
from tests.labs.launderings import launderings


@pytest.mark.parametrize("lab", sorted(lab_names()))
def test_laundered_evidence_fails_with_its_hint(lab, tmp_path):
    found = launderings()[lab]
    folder = tmp_path / "class"
    folder.mkdir()
    for name, (source, _) in found.items():
        (folder / f"{name}.py").write_text(source)
    grades, _ = grade_folder(
        find_lab(lab), folder, 2, None, "pool", LIMITS, progress=False, solutions=SOLUTIONS
    )
    by_student = {g.student: g.tasks for g in grades}
    assert sorted(by_student) == sorted(found)
    for name, (_, phrase) in found.items():
        tasks = by_student[name]
        failed = [hint for _, passed, hint in tasks if not passed]
        assert failed, f"{name} passed every task"
        assert any(phrase in hint for hint in failed), (name, phrase, failed)
        assert all("\n" not in hint and "Traceback" not in hint for _, _, hint in tasks)


def test_no_lab_offers_a_way_to_read_what_was_drawn():
    for lab in lab_names():
        offered = C.lab_specs(lab)
        for name in C.REFUSED:
            assert name not in offered, (lab, name)
            assert C.refused_text(lab, name).startswith(
                f"{name} is not one of the OpenGL calls this lab offers: "
            )
    assert "glCopyTexImage2D" not in C.lab_specs("spheremap")
    assert "glCopyTexImage2D" in C.lab_specs("lab20")
    assert "glUniform1i" in C.lab_specs("lab20") and "glUniform1i" not in C.lab_specs("cubemap")


def _reference(lab: str) -> np.ndarray:
    return Evidence.load(reference_folder(find_lab(lab))).arrays["frame"]


def _blend(frame: np.ndarray, box: tuple[int, int, int, int], colour, alpha: float) -> np.ndarray:
    out = frame.astype(np.float64)
    x0, y0, x1, y1 = box
    out[y0:y1, x0:x1] = out[y0:y1, x0:x1] * (1 - alpha) + np.asarray(colour) * alpha
    return np.round(out).astype(np.uint8)


@pytest.mark.parametrize("lab", sorted(lab_names()))
def test_a_faint_overlay_shows_in_patches_and_noise_does_not(lab):
    reference = _reference(lab)
    marked = reference
    for box, colour in (
        ((0, 30, 256, 54), (255, 255, 255)),
        ((20, 70, 36, 230), (255, 255, 255)),
        ((150, 130, 230, 210), (255, 0, 0)),
    ):
        marked = _blend(marked, box, colour, 0.085)
    # under the per-pixel tolerance, as the issue found
    assert int(np.abs(marked.astype(int) - reference).max()) <= 24
    assert int(differing(marked, reference).sum()) <= allowed_pixels(reference.shape)
    assert int(faint_patches(marked, reference).sum()) > 10 * allowed_pixels(reference.shape)
    # noise of a few levels, everywhere
    rng = np.random.default_rng(7)
    noisy = np.clip(reference.astype(int) + rng.integers(-3, 4, reference.shape), 0, 255)
    assert int(faint_patches(noisy.astype(np.uint8), reference).sum()) == 0
    # a uniform offset of a few levels over the whole frame (another driver's rounding)
    shifted = np.clip(reference.astype(int) + 4, 0, 255).astype(np.uint8)
    assert int(faint_patches(shifted, reference).sum()) == 0
    # everything drawn one pixel over: edges, not patches
    moved = np.roll(reference, 1, axis=1)
    assert int(faint_patches(moved, reference).sum()) <= allowed_pixels(reference.shape)


def test_taint_follows_pixels():
    tracker = Tracker()
    assert tracker.framebuffer_taint == ""
    tracker.taint("texture 3 holds uploaded pixels", (0, 0, 64, 64), (64, 64))
    assert tracker.framebuffer_taint
    tracker.untaint((0, 0, 32, 64))  # a scissored clear: half the frame
    assert tracker.framebuffer_taint and tracker.taint_in((0, 0, 32, 64)) == ""
    assert tracker.taint_in((30, 0, 8, 8)) and tracker.taint_in((-5, -5, 1000, 1000))
    tracker.untaint((32, 0, 32, 64))
    assert tracker.framebuffer_taint == "" and tracker.taint_in((0, 0, 64, 64)) == ""


def test_one_file_for_every_variant_gets_a_refusal_for_each_student(tmp_path):
    """The issue's file, shared by students of different variants: before, each got 8/8;
    now each is refused at the first call that draws in set-up."""
    source, phrase = launderings()["lab20"]["measure_variant_at_setup"]
    folder = tmp_path / "class"
    folder.mkdir()
    for student in ("Ada_Lovelace", "Ben_Ng"):
        (folder / f"{student}.py").write_text(source)
    grades, _ = grade_folder(
        find_lab("lab20"),
        folder,
        2,
        None,
        "pool",
        LIMITS,
        progress=False,
        key=b"a course key of the test, 32 bytes",
        solutions=SOLUTIONS,
    )
    assert len({g.variant for g in grades}) == 2
    for grade in grades:
        hints = [hint for _, passed, hint in grade.tasks if not passed]
        assert hints and any(phrase in hint for hint in hints), (grade.student, hints)
