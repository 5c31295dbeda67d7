"""Accuracy as a budget (:mod:`mirrorlab.budget`), numpy only: the scene keys, the
candidates derived from the registry, the features on scenes whose answers are known, the
choice against brute force over its own predictions, steady choices, the time budget's
knapsack, the calibration file, and the benchmark's figures on a hand-made table."""

from __future__ import annotations

import contextlib
import itertools
import json
import math
from dataclasses import replace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mirrorlab.budget.bench import Run, SceneResult, Table, analyse
from mirrorlab.budget.candidates import candidates_for, error_family
from mirrorlab.budget.chooser import (
    BudgetChooser,
    Prediction,
    _best_within,
    _frontier,
    choose_frames,
)
from mirrorlab.budget.features import candidate_features, view_features
from mirrorlab.budget.measure import Score
from mirrorlab.budget.model import (
    BASE_BASIS,
    COST_BASIS,
    ERROR_BASIS,
    Calibration,
    CalibrationError,
    CostModel,
    ErrorModel,
    calibration_from_json,
    load_calibration,
    nnls,
)
from mirrorlab.options import OptionError, apply_options
from mirrorlab.plan import reflector_footprint
from mirrorlab.scene.loader import SceneError, load_scene, loads
from mirrorlab.scene.model import Budget, Camera, MeshObject, PlanarReflector, Scene, Transform
from mirrorlab.techniques import Technique, register, technique, techniques, unregister
from mirrorlab.views import camera_view
from tests.scenekit import BOX_MESH, planar_reflector

# --------------------------------------------------------------------------- scene keys


def test_budget_keys_round_trip_through_the_file():
    for table, budget in (
        ("max_error = 0.05", Budget(max_error=0.05)),
        ('max_error = "mae=3"', Budget(max_error=3.0, metric="mae")),
        ('max_error = "flip=0.1"', Budget(max_error=0.1)),
        ("max_ms = 12.5", Budget(max_ms=12.5)),
    ):
        scene = loads(f'name = "b"\n[budget]\n{table}\n')
        assert scene.budget == budget
        assert loads(scene.to_toml()).budget == budget


@pytest.mark.parametrize(
    "table, message",
    [
        ("max_error = 0", r"budget\.max_error: expected a mean FLIP"),
        ("max_error = 1.5", r"budget\.max_error: expected a mean FLIP"),
        ('max_error = "mae=300"', r"budget\.max_error: .*mae=N"),
        ('max_error = "mse=3"', r"budget\.max_error: .*got 'mse=3'"),
        ("max_error = true", r"budget\.max_error: expected .* got the boolean true"),
        ("max_ms = -1", r"budget\.max_ms: expected a number greater than 0"),
        ("max_error = 0.1\nmax_ms = 3", r"budget\.max_ms: give one of max_error and max_ms"),
        ("margin = 2", r"budget\.margin: unknown key"),
        ("", r"budget: expected max_error"),
    ],
)
def test_a_bad_budget_is_one_line_naming_the_key(table, message):
    with pytest.raises(SceneError, match=message) as caught:
        loads(f'name = "b"\n[budget]\n{table}\n', "b.toml")
    assert "\n" not in str(caught.value) and str(caught.value).startswith("b.toml: ")


@pytest.mark.parametrize(
    "allow, message",
    [
        ('["stencil", "cube"]', r"reflectors\[0\]\.allow\[1\]: expected one of .*got 'cube'"),
        ('["stencil", "stencil"]', r"reflectors\[0\]\.allow\[1\]: 'stencil' is listed twice"),
        ("[]", r"reflectors\[0\]\.allow: expected at least one of"),
        ('"stencil"', r"reflectors\[0\]\.allow: expected an array"),
    ],
)
def test_a_bad_allow_list_is_one_line_naming_the_key(allow, message):
    text = (
        'name = "b"\n[[reflectors]]\ntechnique = "reflected"\n'
        "corners = [[0, -1, -1], [0, 1, -1], [0, 1, 1], [0, -1, 1]]\n"
        f"allow = {allow}\n"
    )
    with pytest.raises(SceneError, match=message):
        loads(text, "b.toml")


def test_the_options_set_the_budget_and_refuse_both():
    lab = load_scene("lab20")
    assert apply_options(lab, {"max_error": "mae=2"}).budget == Budget(max_error=2.0, metric="mae")
    assert apply_options(lab, {"max_ms": 9.0}).budget == Budget(max_ms=9.0)
    with pytest.raises(OptionError, match="give one of them"):
        apply_options(lab, {"max_error": 0.1, "max_ms": 9.0})
    with pytest.raises(OptionError, match=r"^--max-error: budget\.max_error"):
        apply_options(lab, {"max_error": -2})


# --------------------------------------------------------------------------- candidates

COPY_MIRROR = Technique(
    "budget-copy-mirror",
    "planar",
    "a test's planar technique: the reflected camera again",
    texture="viewer",
    pass_class="mirrorlab.passes.reflected:ReflectedMirror",
    capture_camera="mirrorlab.captures:reflected_camera",
)
COPY_MAP = Technique(
    "budget-copy-map",
    "curved",
    "a test's curved technique: a static cube map again",
    texture="static",
    pass_class="mirrorlab.passes.envmap:CubeMapped",
    vertex_shader="envmap.vert",
    fragment_shader="envmap_cube.frag",
    sampler="cube_map_texture",
    source="faces",
    view_ray=True,
)


@contextlib.contextmanager
def registered(*entries: Technique):
    for entry in entries:
        register(entry)
    try:
        yield
    finally:
        for entry in entries:
            unregister(entry.name)


def test_every_registered_technique_of_a_kind_is_a_candidate():
    with registered(COPY_MIRROR, COPY_MAP):
        for name in ("lab20", "chrome_sphere"):
            scene = load_scene(name)
            reflector = scene.reflectors[0]
            found = {c.technique for c in candidates_for(reflector, scene)}
            assert found == {t.name for t in techniques(reflector.kind)}
            sized = {c.map_size for c in candidates_for(reflector, scene) if c.map_size}
            assert {64, 128, 256, 512, 1024} <= sized


def test_a_chooser_limited_to_a_map_size_offers_no_larger_map():
    scene = load_scene("chrome_sphere")
    sphere = scene.reflectors[0]
    every = BudgetChooser().candidates(sphere, scene)
    limited = BudgetChooser(largest=256).candidates(sphere, scene)
    assert set(limited) == {c for c in every if c.map_size <= 256}
    assert len(limited) < len(every)


def test_allow_keeps_its_techniques_only():
    scene = load_scene("lab20")
    mirror = replace(scene.reflectors[0], allow=("stencil", "reflected"))
    found = candidates_for(mirror, replace(scene, reflectors=(mirror,)))
    assert {c.technique for c in found} == {"stencil", "reflected"}


@settings(max_examples=25, deadline=None)
@given(
    st.floats(-5, 5),
    st.floats(-5, 5),
    st.floats(-60, 60),
)
def test_a_candidate_changes_a_moved_mirror_but_never_where_it_is(x, y, turn):
    scene = load_scene("lab20")
    mirror = planar_reflector(scene, "mirror").moved(position=(x, y, -2.0), rotation=(0, turn, 0))
    assert isinstance(mirror, PlanarReflector)
    for candidate in candidates_for(mirror, scene):
        drawn = candidate.apply(mirror)
        assert isinstance(drawn, PlanarReflector)
        assert drawn.corners == mirror.corners and drawn.name == mirror.name
        assert drawn.technique == candidate.technique
        if technique(drawn.technique).own_camera:
            assert drawn.ortho == mirror.ortho  # the lab's camera moves with the mirror
        else:
            assert drawn.ortho is None


# --------------------------------------------------------------------------- features


def _mirror_scene(objects=(), eye=(0.0, 0.0, 10.0)) -> Scene:
    mirror = PlanarReflector(
        "mirror", ((0.0, -2.0, -2.0), (0.0, 2.0, -2.0), (0.0, 2.0, 2.0), (0.0, -2.0, 2.0))
    )
    # turned to face +z: corners in the plane z = 0
    mirror = mirror.moved(position=(0.0, 0.0, 0.0), rotation=(0.0, -90.0, 0.0))
    return Scene(
        "t",
        camera=Camera(eye=eye, target=(0.0, 0.0, 0.0), fovy=40.0, near=0.1, far=100.0),
        objects=tuple(objects),
        reflectors=(mirror,),
    )


def _features(scene: Scene, size=(96, 96)):
    reflector = scene.reflectors[0]
    view = camera_view(scene.camera, size)
    found = view_features(scene, reflector, view, reflector_footprint(reflector, view))
    assert found is not None
    by_family = {}
    for candidate in candidates_for(reflector, scene):
        by_family[error_family(candidate.apply(reflector))] = candidate_features(
            found, reflector, candidate
        )
    return found, by_family


def test_a_mirror_in_an_empty_scene_reflects_only_the_background():
    found, families = _features(_mirror_scene())
    assert found.objects == 0.0 and found.offscreen == 1.0
    assert all(wrong == 0.0 for wrong, _, _ in families.values())


def test_a_wall_behind_the_viewer_fills_every_reflected_ray():
    wall = MeshObject(
        "wall", BOX_MESH, Transform(position=(0.0, 0.0, 30.0), scale=(200.0, 200.0, 1.0))
    )
    head_on, families = _features(_mirror_scene([wall]))
    assert head_on.objects == 1.0
    assert head_on.offscreen == 1.0  # behind the eye: not on the screen
    assert families["reflected"][0] == 0.0 and families["stencil"][0] == 0.0
    # the orthographic capture looks along the normal: the same wall, shifted (the
    # viewer's rays spread), and more so seen off the normal
    assert families["ortho"][0] == 0.0 and families["ortho"][1] > 1.0
    _, oblique = _features(_mirror_scene([wall], eye=(7.0, 0.0, 7.0)))
    assert oblique["ortho"][1] > 1.5 * families["ortho"][1]


@settings(max_examples=30, deadline=None)
@given(
    st.tuples(st.floats(-20, 20), st.floats(-20, 20), st.floats(0.5, 30)),
    st.tuples(st.floats(-3, 3), st.floats(-3, 3), st.floats(-3, 3)),
)
def test_features_are_finite_shares_from_anywhere_in_front(eye, box):
    scene = _mirror_scene([MeshObject("box", BOX_MESH, Transform(position=box))], eye=eye)
    reflector = scene.reflectors[0]
    view = camera_view(scene.camera, (64, 48))
    footprint = reflector_footprint(reflector, view)
    found = None if footprint.empty else view_features(scene, reflector, view, footprint)
    if found is None:
        return
    vector = found.vector()
    assert np.all(np.isfinite(vector))
    assert 0 <= found.objects <= 1 and 0 <= found.offscreen <= 1 and 0 <= found.grazing <= 1
    for candidate in candidates_for(reflector, scene):
        wrong, shift, texels = candidate_features(found, reflector, candidate)
        assert 0 <= wrong <= 1 + 1e-9 and 0 <= shift <= 64 and math.isfinite(texels)


# --------------------------------------------------------------------------- choosing


def synthetic_calibration(roots: dict[str, float], costs: dict[str, float]) -> Calibration:
    """A calibration whose error models predict a constant error per family (the square of
    ``roots[family]``, bound twice that root) and whose costs are a constant draw per
    cost family (10 ms for the rest)."""
    one = len(ERROR_BASIS)
    models = {
        family: ErrorModel((root,) + (0.0,) * (one - 1), root, 100)
        for family, root in roots.items()
    }
    wide = ErrorModel((0.5,) + (0.0,) * (one - 1), 0.5, 100)
    zero = (0.0,) * len(COST_BASIS)
    return Calibration(
        {"flip": models, "mae": models},
        {"flip": {"any": wide}, "mae": {"any": wide}},
        {name: CostModel((ms, *zero[1:]), zero, 10) for name, ms in costs.items()},
        {"any": CostModel((10.0, *zero[1:]), zero, 10)},
        (1.0,) + (0.0,) * (len(BASE_BASIS) - 1),
    )


def _lab(budget: Budget) -> Scene:
    return replace(load_scene("lab20"), budget=budget)


def test_the_cheapest_within_the_budget_is_chosen_and_else_the_most_accurate():
    calibration = synthetic_calibration(
        {"stencil": 0.05, "reflected": 0.1, "ortho": 0.4},
        {"stencil": 5.0, "reflected copy": 2.0, "reflected fbo": 3.0, "ortho copy": 1.0},
    )
    for limit, expected, met in (
        (0.05, "reflected-copy", True),  # (2 x 0.1)^2 = 0.04 is within
        (0.02, "stencil", True),  # (2 x 0.05)^2 = 0.01
        (1.0, "ortho-copy", True),
        (0.001, "stencil", False),  # nothing is: the most accurate
    ):
        _, frame = BudgetChooser(calibration).choose(_lab(Budget(max_error=limit)), (128, 128))
        choice = frame.choices[0]
        assert choice.chosen is not None and choice.chosen.candidate.label.startswith(expected)
        assert choice.met is met and frame.met is met


@settings(max_examples=40, deadline=None)
@given(
    st.lists(st.floats(0.0, 0.8), min_size=3, max_size=3),
    st.lists(st.floats(0.1, 20.0), min_size=4, max_size=4),
    st.floats(0.001, 0.9),
)
def test_the_first_choice_is_brute_force_over_the_predictions(roots, costs, limit):
    calibration = synthetic_calibration(
        dict(zip(("stencil", "reflected", "ortho"), roots, strict=True)),
        dict(zip(("stencil", "reflected copy", "reflected fbo", "ortho copy"), costs, strict=True)),
    )
    _, frame = BudgetChooser(calibration).choose(_lab(Budget(max_error=limit)), (96, 96))
    choice = frame.choices[0]
    within = [p for p in choice.predictions if p.bound <= limit]
    assert choice.chosen is not None
    if within:
        assert choice.chosen.cost == min(p.cost for p in within)
        assert choice.chosen.bound <= limit and choice.met
    else:
        assert choice.chosen.bound == min(p.bound for p in choice.predictions)
        assert not choice.met


def test_a_still_scene_keeps_its_first_choice_and_is_not_predicted_again():
    scene = _lab(Budget(max_error=0.03))
    chosen = choose_frames(scene, range(6), (96, 96))
    labels = {c.choices[0].candidate_label for _, c in chosen.values()}
    assert len(labels) == 1
    assert all(frame.repeated for _, frame in list(chosen.values())[1:])
    assert len({id(scene.reflectors) for scene, _ in chosen.values()}) == 1


def test_a_cheaper_candidate_must_save_enough_to_take_over():
    # the reflected capture runs again only when the viewer moves: 1 ms a frame while
    # still, 1 ms + its capture once the viewer moves; stencil 2 ms whatever
    for capture, kept in ((1.05, True), (3.0, False)):
        calibration = synthetic_calibration(
            {"stencil": 0.05, "reflected": 0.05, "ortho": 0.5},
            {"stencil": 2.0, "reflected fbo": 5.0, "ortho copy": 5.0},
        )
        zero = (0.0,) * (len(COST_BASIS) - 1)
        costs = dict(calibration.costs)
        costs["reflected copy"] = CostModel((1.0, *zero), (capture, *zero), 10)
        chooser = BudgetChooser(replace(calibration, costs=costs))
        scene = _lab(Budget(max_error=0.02))
        _, first = chooser.choose(scene, (96, 96))
        assert first.choices[0].candidate_label.startswith("reflected-copy")
        moved = replace(scene, camera=replace(scene.camera, eye=(12.0, 8.0, 9.0)))
        _, second = chooser.choose(moved, (96, 96))
        assert second.predicted
        label = second.choices[0].candidate_label
        assert label.startswith("reflected-copy" if kept else "stencil"), (capture, label)


def _prediction(cost: float, error: float) -> Prediction:
    from mirrorlab.budget.candidates import Candidate

    return Prediction(Candidate(f"{cost}-{error}", "stencil", 0, ()), error, error, cost)


@settings(max_examples=60, deadline=None)
@given(
    st.lists(
        st.lists(st.tuples(st.floats(0.1, 10), st.floats(0, 1)), min_size=1, max_size=5),
        min_size=1,
        max_size=3,
    ),
    st.floats(0.1, 30),
)
def test_the_time_budget_finds_the_best_combination_that_fits(options, room):
    predictions = [[_prediction(c, e) for c, e in reflector] for reflector in options]
    weights = np.full(len(options), 1.0 / len(options))
    found = _best_within([_frontier(p) for p in predictions], weights, room)
    best = None
    for combination in itertools.product(*predictions):
        if sum(p.cost for p in combination) <= room:
            value = sum(w * p.error for w, p in zip(weights, combination, strict=True))
            best = value if best is None else min(best, value)
    if best is None:
        assert found is None
    else:
        assert found is not None and sum(p.cost for p in found) <= room
        value = sum(w * p.error for w, p in zip(weights, found, strict=True))
        assert value == pytest.approx(best, abs=1e-12)


def test_a_time_budget_chooses_the_most_accurate_that_fits():
    calibration = synthetic_calibration(
        {"stencil": 0.01, "reflected": 0.1, "ortho": 0.4},
        {"stencil": 8.0, "reflected copy": 3.0, "reflected fbo": 3.5, "ortho copy": 1.0},
    )
    for limit, expected in ((20.0, "stencil"), (5.0, "reflected-copy"), (2.5, "ortho-copy")):
        _, frame = BudgetChooser(calibration).choose(_lab(Budget(max_ms=limit)), (96, 96))
        chosen = frame.choices[0].chosen
        assert chosen is not None and chosen.candidate.label.startswith(expected), limit
    _, frame = BudgetChooser(calibration).choose(_lab(Budget(max_ms=0.5)), (96, 96))
    assert not frame.met  # nothing fits: the cheapest, and it says so


def test_every_shipped_scene_is_chosen_for_by_the_shipped_calibration():
    from mirrorlab.scene.loader import shipped_scene_names

    for name in shipped_scene_names():
        scene = replace(load_scene(name), budget=Budget(max_error=0.05))
        chosen, frame = BudgetChooser().choose(scene, (64, 64))
        assert len(frame.choices) == len(scene.reflectors)
        for reflector, choice in zip(chosen.reflectors, frame.choices, strict=True):
            if choice.chosen is not None:
                assert reflector.technique == choice.chosen.candidate.technique
                assert math.isfinite(choice.chosen.bound) and choice.chosen.cost >= 0


# --------------------------------------------------------------------------- calibration


def test_nnls_matches_least_squares_where_that_is_positive_and_clips_otherwise():
    rng = np.random.default_rng(3)
    a = rng.uniform(0, 1, (50, 3))
    x = np.array([1.0, 2.0, 0.5])
    assert np.allclose(nnls(a, a @ x), x)
    target = a @ np.array([1.0, -2.0, 0.5])
    found = nnls(a, target)
    assert np.all(found >= 0) and found[1] == 0.0


def test_the_shipped_calibration_loads_and_a_bad_one_is_named(tmp_path):
    shipped = load_calibration()
    assert "any" in shipped.kind_errors["flip"] and "any" in shipped.kind_costs
    text = shipped.to_json()
    assert calibration_from_json(text).errors.keys() == shipped.errors.keys()
    bad = json.loads(text)
    bad["version"] = 99
    with pytest.raises(CalibrationError, match="version 99"):
        calibration_from_json(json.dumps(bad), "mine.json")
    del bad["version"]
    with pytest.raises(CalibrationError, match=r"^mine\.json:"):
        calibration_from_json(json.dumps({"errors": 3}), "mine.json")
    with pytest.raises(CalibrationError, match="cannot read it"):
        load_calibration(str(tmp_path / "missing.json"))


# --------------------------------------------------------------------------- the bench's figures


def test_the_benchmarks_oracle_and_best_fixed_choice_by_hand():
    from mirrorlab.budget.candidates import Candidate

    a = Candidate("a", "stencil", 0, (("technique", "stencil"),))
    b = Candidate("b", "reflected", 0, (("technique", "reflected"),))
    # two frames; a: 1 ms, error 0.01 then 0.20; b: 4 ms, error 0.02 both times
    table = Table(
        candidates=[[a, b]],
        errors=[[[Score(0.01, 0, 9), Score(0.2, 0, 9)], [Score(0.02, 0, 9), Score(0.02, 0, 9)]]],
        extra=[np.array([[1.0, 1.0], [4.0, 4.0]])],
        given=np.array([10.0, 10.0]),
        visible=np.array([[True, True]]),
        pixels=np.array([[9, 9]]),
    )
    budget = Budget(max_error=0.05)
    run = Run(
        budget,
        frames=[],
        plan_ms=np.array([0.5, 0.5]),
        chosen=[[a], [b]],
        errors=[[Score(0.01, 0, 9)], [Score(0.02, 0, 9)]],
    )
    figures = analyse(SceneResult("t", ["m"], table, [run], 0.0), run)
    assert figures["held_share"] == 1.0
    assert figures["worst_overrun"] == pytest.approx(0.4)
    assert figures["oracle_ms"] == pytest.approx(11.0 + 14.0)
    assert figures["planner_ms"] == pytest.approx(11.0 + 14.0 + 1.0)
    assert figures["best_fixed"] == ["b"] and figures["best_fixed_ms"] == pytest.approx(28.0)
    assert figures["cost_vs_oracle"] == pytest.approx(26.0 / 25.0)
    assert figures["cost_vs_best_fixed"] == pytest.approx(26.0 / 28.0)
    assert figures["switches"] == 1
