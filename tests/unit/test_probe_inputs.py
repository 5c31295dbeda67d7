"""The value probe's chosen inputs (mirrorlab/labs/trusted/probe.py) tell every pair of
its known formulas apart, by far more than the probe's tolerance: on all inputs, and for
the cube map on each face's own inputs (except a slip that is the right formula on that
face, such as a signed major axis on a positive face)."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from mirrorlab.labs.trusted import probe


@pytest.mark.parametrize("function", sorted(probe.FORMULAS))
def test_every_pair_of_formulas_differs(function):
    # sphere_map_st's "right" and "normalised" (both the function) differ on the inputs of
    # length other than 1 only
    formulas = probe.FORMULAS[function]()
    for (a, va), (b, vb) in itertools.combinations(formulas.items(), 2):
        gap = float(np.abs(va - vb).max())
        assert gap > 10 * probe.TOLERANCE, (a, b, gap)
        assert np.all(np.isfinite(va)) and np.all(np.isfinite(vb))


def test_cube_faces_each_tell_the_slips_apart():
    formulas = probe.FORMULAS["cube_face_st"]()
    assert sorted(set(probe.CUBE_FACE.tolist())) == list(range(6))
    for face in range(6):
        on = probe.CUBE_FACE == face
        for (a, va), (b, vb) in itertools.combinations(formulas.items(), 2):
            gap = float(np.abs(va[on] - vb[on]).max())
            if {a, b} == {"right", "signed_major"} and face % 2 == 0:
                assert gap == 0.0
                continue
            assert gap > 10 * probe.TOLERANCE, (face, a, b, gap)


def test_reflect_inputs_have_both_signs_of_n_dot_u():
    d = (probe.REFLECT_U * probe.REFLECT_N).sum(-1)
    assert np.all(d[:16] <= -0.2) and np.all(d[16:] >= 0.2)


def test_slip_names_the_formula_values_follow():
    for function, formulas in ((f, probe.FORMULAS[f]()) for f in probe.FORMULAS):
        for name, predicted in formulas.items():
            values = np.zeros((predicted.shape[0], 4))
            values[:, : predicted.shape[1]] = predicted
            expected = "right" if name in probe.RIGHT[function] else name
            assert probe.slip(function, values) == expected
    assert probe.slip("reflect_eye", None) == ""
    nan = np.full((probe.REFLECT_U.shape[0], 4), np.nan)
    assert probe.slip("reflect_eye", nan) == ""
