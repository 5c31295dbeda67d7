"""A copy of an existing technique under a new name breaks nothing (DESIGN.md, stage 5):
the registry's checks run again in a pytest process of their own with a twin of a planar
and of a curved technique registered (``MIRRORLAB_TEST_TWINS``, :mod:`tests.twins`): the
registry's lists, the scene schema and command line, the options, the accuracy sweep's
configurations, and, for each twin, the pass contract and the renamed-copy frame.

The whole suite runs the same way by hand (docs/developing.md, "Tests")."""

from __future__ import annotations

import os
import subprocess
import sys

from mirrorlab.techniques import CAMERA_TEXTURES, Technique, techniques
from tests import REPO_DIR
from tests.gl.test_registry import scene_for
from tests.twins import VARIABLE, twin_of

CHECKS = (
    "tests/unit/test_techniques.py",
    "tests/unit/test_options.py",
    "tests/unit/test_accuracy.py",
)
"""The registry's own checks, run whole (numpy only)."""
PASS_CONTRACT = (
    "tests/gl/test_pass_contract.py::"
    "test_a_recorded_frames_arrays_stay_as_they_were_and_its_replays_are_fresh_frames"
)
RENAMED_COPY = "tests/gl/test_registry.py::test_a_renamed_copy_of_a_technique_draws_the_same_frame"


def originals() -> list[Technique]:
    """One technique of each kind of reflector to copy: the first that shows the scene
    (a capture camera, a texture the planner reuses), else the first of its kind."""
    chosen = []
    for kind in ("planar", "curved"):
        entries = [t for t in techniques() if t.kind == kind]
        showing = [t for t in entries if t.texture in CAMERA_TEXTURES]
        chosen.append((showing or entries)[0])
    return chosen


def test_a_twin_of_a_planar_and_a_curved_technique_breaks_none_of_the_registry_checks():
    chosen = originals()
    selected = [*CHECKS]
    for entry in chosen:  # the GL checks parametrized by technique, for the twins only
        twin = twin_of(entry)
        selected += [
            f"{PASS_CONTRACT}[{twin.name}]",
            f"{RENAMED_COPY}[{scene_for(twin)}-{twin.name}]",
        ]
    result = subprocess.run(
        [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", *selected],
        capture_output=True,
        text=True,
        cwd=REPO_DIR,
        env={**os.environ, VARIABLE: ",".join(entry.name for entry in chosen)},
    )
    assert result.returncode == 0, result.stdout[-3000:] + result.stderr[-2000:]
    # every node ran (one that matches nothing stops pytest with exit 4) and passed
    summary = result.stdout.strip().splitlines()[-1]
    assert " passed" in summary and "skipped" not in summary, summary
