"""The value probe's judging, numpy only (mirrorlab/labs/trusted/probe.py, formulas.py and
each lab's glsl.py): the inputs a seed draws cover each function's whole domain and its
hard cases; the ways a formula is written agree with each other and with mirrorlab's own
implementation (mirrorlab.envmap) on every input of the domain; every variant made from a
formula, given back as a student's values, is named by one that gives the same numbers;
a discard or a value missing anywhere fails; and the issue's slips are in the family."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mirrorlab.envmap import cube_map, reflect, sphere_map
from mirrorlab.labs.trusted import formulas as F
from mirrorlab.labs.trusted import probe

FUNCTIONS = {f.name: (lab, f) for lab in ("spheremap", "cubemap") for f in probe.lab_functions(lab)}
SEEDS = st.integers(0, 2**63 - 1)


def drawn(name: str, seed: int) -> tuple[probe.GlslFunction, dict[str, np.ndarray], probe.Drawn]:
    _, function = FUNCTIONS[name]
    inputs = probe.draw_inputs(function, seed)
    return function, {k: v.astype(np.float64) for k, v in inputs.values.items()}, inputs


def student(function, inputs, drawn_inputs, values: np.ndarray, written=None) -> probe.Probed:
    out = np.zeros((drawn_inputs.count, 4))
    out[:, : values.shape[1]] = values
    out[:, 3] = 1.0 if written is None else written
    return probe.Probed(
        function,
        inputs,
        out,
        out[:, 3] == 1.0,
        drawn_inputs.block.astype(np.int64),
        drawn_inputs.blocks,
    )


def test_the_labs_declare_their_functions_in_the_handouts_order():
    assert list(FUNCTIONS) == ["reflect_eye", "sphere_map_st", "cube_face", "cube_face_st"]


@settings(max_examples=10)
@given(seed=SEEDS)
def test_the_written_forms_agree_with_mirrorlabs_own_formulas_on_the_domain(seed):
    function, inputs, d = drawn("reflect_eye", seed)
    assert np.abs(function.expected(inputs) - reflect(inputs["u"], inputs["n"])).max() < 1e-6
    function, inputs, d = drawn("sphere_map_st", seed)
    judged = np.array([d.blocks[b][1] for b in d.block]) == probe.EXACT
    expected = np.stack(sphere_map(inputs["r"]), -1)
    for form in function.forms:
        assert np.abs(F.evaluate(form, inputs)[judged] - expected[judged]).max() < 1e-5
    for name in ("cube_face", "cube_face_st"):
        function, inputs, d = drawn(name, seed)
        face, s, t = cube_map(inputs["r"])
        if name == "cube_face":
            assert probe.right_rows(student(function, inputs, d, face[:, None] * 1.0)).all()
            continue
        on_own_face = inputs["face"][:, 0] == face  # an edge's other face: its own (s, t)
        for form in function.forms:
            values = F.evaluate(form, inputs)
            assert np.abs(values[on_own_face] - np.stack([s, t], -1)[on_own_face]).max() < 1e-9


def test_the_domains_hold_the_hard_cases():
    _, inputs, d = drawn("reflect_eye", 7)
    dots = (inputs["u"] * inputs["n"]).sum(-1)
    assert (dots < -0.5).sum() > 50 and (dots > 0.5).sum() > 50
    assert np.abs(dots).min() < 1e-6 and np.isclose(dots, -1).any() and np.isclose(dots, 1).any()
    _, inputs, d = drawn("sphere_map_st", 7)
    r = inputs["r"]
    assert (1 + r[:, 2] < 2e-4).any() and np.isclose(r[:, 2], 1).any()
    assert [rule for _, rule in d.blocks].count(probe.ANY) == 1  # (0, 0, -1) itself
    lengths = np.linalg.norm(r, axis=-1)
    assert (lengths < 0.6).any() and (lengths > 2).any()  # diagnostic, never judged
    _, inputs, d = drawn("cube_face_st", 7)
    assert sorted(set(inputs["face"][:, 0].astype(int))) == list(range(6))
    size = np.sort(np.abs(inputs["r"]), -1)
    assert (size[:, 2] == size[:, 1]).sum() >= 24  # edges, on both of their faces
    assert ((size[:, 2] == size[:, 1]) & (size[:, 1] == size[:, 0])).sum() >= 8


def test_every_seed_draws_other_inputs():
    a = probe.draw_inputs(FUNCTIONS["reflect_eye"][1], 1).values["u"]
    b = probe.draw_inputs(FUNCTIONS["reflect_eye"][1], 2).values["u"]
    assert a.shape == b.shape and not np.array_equal(a, b)


@pytest.mark.parametrize("name", sorted(FUNCTIONS))
def test_every_variant_given_back_is_named_by_one_with_the_same_numbers(name):
    function, inputs, d = drawn(name, 2024)
    candidates = probe._candidates(function, inputs)
    assert len(candidates) >= 25
    judged = np.array([d.blocks[b][1] for b in d.block]) != probe.ANY
    named = 0
    stride = max(1, len(candidates) // 40)  # a spread of them: the check is quadratic
    for candidate in candidates[::stride]:
        values, words = candidate.values, candidate.words
        p = student(function, inputs, d, values)
        ok = probe.right_rows(p)
        if ok.all():
            continue  # a variant the domain cannot tell from the formula: right
        hint = probe.name_mistake(p, ok, candidates=candidates)
        if "does not know" in hint or "NaN" in hint or "general inputs" in hint:
            continue  # infinite or undefined on part of the domain: named by symptom
        named += 1
        same = probe._matches(values, candidates)[:, judged].mean(-1) > 0.9
        readings = [candidates[i].words for i in np.flatnonzero(same)]
        assert any(hint.startswith(f"{name}: {w}") for w in readings) or (
            "same value" in hint or "unchanged" in hint or "on the " in hint
        ), (words, hint)
    assert named >= len(candidates[::stride]) // 2


@pytest.mark.parametrize(
    "name, words",
    [
        ("reflect_eye", "u where the formula has n"),
        ("reflect_eye", "the factor 2 missing"),
        ("reflect_eye", "n.u clamped to 0 or more"),
        ("reflect_eye", "r points the wrong way"),
        ("sphere_map_st", "without its square root"),
        ("sphere_map_st", "1/2 applied twice"),
        ("sphere_map_st", "squared without its parentheses"),
        ("sphere_map_st", "h not normalised"),
        ("sphere_map_st", "s and t swapped"),
        ("sphere_map_st", "the term 1 missing"),
        ("cube_face", "the comparisons are chained"),
        ("cube_face", "largest signed component"),
        ("cube_face", "numbered +X, +Y, +Z"),
        ("cube_face_st", "every face takes ma of the +X face"),
        ("cube_face_st", "on the -X face (face 1), ma: abs() missing"),
        ("cube_face_st", "sc and tc swapped"),
        ("cube_face_st", "divided by the length of r"),
    ],
)
def test_the_issues_slips_are_in_the_family(name, words):
    function, inputs, _ = drawn(name, 3)
    assert any(words in c.words for c in probe._candidates(function, inputs))


@pytest.mark.parametrize("name", sorted(FUNCTIONS))
def test_right_values_pass_and_a_discard_or_a_constant_fails(name):
    function, inputs, d = drawn(name, 99)
    right = function.expected(inputs)
    rules = np.array([d.blocks[b][1] for b in d.block])
    right[rules == probe.ANY] = 0.0  # the singular input: any value is right
    assert probe.right_rows(student(function, inputs, d, right)).all()
    written = np.ones(d.count)
    written[d.count // 2] = 0.0  # one fragment discarded
    p = student(function, inputs, d, right, written)
    ok = probe.right_rows(p)
    assert not ok.all() and "wrote no value for 1 of the" in probe.name_mistake(p, ok)
    constant = np.repeat(right[:1], d.count, axis=0)
    p = student(function, inputs, d, constant)
    ok = probe.right_rows(p)
    assert not ok.all() and "the same value" in probe.name_mistake(p, ok)
    nan = right.copy()
    nan[0] = np.nan
    p = student(function, inputs, d, nan)
    assert not probe.right_rows(p).all()


def test_a_cube_edge_accepts_either_of_its_faces():
    function, inputs, d = drawn("cube_face", 5)
    faces = np.array(
        [
            tied[-1]
            for tied in __import__(
                "mirrorlab.labs.lab_cubemap.glsl", fromlist=["tied_faces"]
            ).tied_faces(inputs["r"])
        ],
        float,
    )[:, None]
    assert probe.right_rows(student(function, inputs, d, faces)).all()
