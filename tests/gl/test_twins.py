"""A copy of an existing technique under a new name breaks nothing (DESIGN.md, stage 5):
the registry's checks run again in a pytest process of their own with a twin of a planar
and of a curved technique registered (``MIRRORLAB_TEST_TWINS``, :mod:`tests.twins`): the
registry's lists, the scene schema and command line and their messages, the options, the
accuracy sweep's configurations, and, for each twin, the pass contract (planned, drawn,
recorded and replayed) and the renamed-copy frame.

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
    *(
        f"tests/unit/test_techniques.py::{name}"
        for name in (
            "test_a_technique_registered_here_is_in_the_scene_schema",
            "test_a_technique_registered_here_is_on_the_command_line",
            "test_every_list_comes_from_the_registry",
            "test_passes_planner_and_renderer_do_not_dispatch_on_technique_names",
        )
    ),
    *(
        f"tests/unit/test_options.py::{name}"
        for name in (
            "test_method_changes_the_reflectors_of_its_kind_only",
            "test_a_reflectors_source_is_kept_only_where_it_means_the_same",
            "test_leaving_cube_live_drops_the_parallax_correction",
            "test_a_bad_parallax_is_refused_naming_the_flag",
            "test_bad_values_are_refused_in_one_line_naming_the_flag",
        )
    ),
    "tests/unit/test_footprint_texture.py::test_scene_files_and_options_take_footprint_for_ortho_only",
    "tests/unit/test_loader.py::test_other_structural_mistakes_are_named",
    "tests/unit/test_loader.py::test_parallax_belongs_to_live_cube_maps_only",
    *(
        f"tests/unit/test_accuracy.py::{name}"
        for name in (
            "test_planar_configurations_cover_every_capture_mode_and_size_plus_stencil",
            "test_curved_configurations_stop_at_the_largest_map_the_sweep_bakes",
            "test_the_live_cube_map_is_measured_with_each_proxy_and_each_step_count",
            "test_a_scene_gets_the_configurations_of_its_kinds_of_reflector",
        )
    ),
)
"""The registry's own checks (numpy only): its lists, the schema, the command line and
their messages, the options, the sweep's configurations."""
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
