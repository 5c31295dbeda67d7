"""The equal-texel-budget study's numpy half (:mod:`mirrorlab.texel_budget`): each map's
texels cover the sphere once, their solid-angle ratios are the known ones (the cube's
3 sqrt 3, the paraboloid's 4, the equal-area sphere map's 1), a lookup lands on the
texel it names, and the octahedral map's coarsest texel matches the cube's at 0.87 of
its texels."""

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mirrorlab import envmap
from mirrorlab import texel_budget as tb

small_settings = settings(max_examples=25, deadline=None)


@pytest.mark.parametrize("kind", tb.MAPS)
def test_a_budget_gives_the_largest_map_within_it(kind):
    for budget in (6 * 16 * 16, 6 * 100 * 100 + 7, 5000):
        layout = tb.layout_for_budget(kind, budget)
        assert layout.texels <= budget
        assert tb.Layout(kind, layout.size + 1).texels > budget
    with pytest.raises(ValueError, match="unknown map"):
        tb.layout_for_budget("dodecahedral", 1000)
    with pytest.raises(ValueError, match="too small"):
        tb.layout_for_budget(kind, 10)


@pytest.mark.parametrize(
    ("kind", "size", "ratio", "tolerance"),
    [
        ("cube", 64, 3 * np.sqrt(3), 0.2),  # face centre against face corner: 3 sqrt 3
        ("octahedral", 130, 5.2, 0.2),
        ("paraboloid", 90, 4.0, 0.15),  # rim against centre: (1 + 1)^2
        ("sphere", 128, 1.0, 1e-6),  # the sphere map is equal-area
    ],
)
def test_solid_angle_ratios_and_the_whole_sphere(kind, size, ratio, tolerance):
    layout = tb.Layout(kind, size)
    angles = tb.texel_solid_angles(layout)
    assert np.all(angles > 0)
    assert angles.max() / angles.min() == pytest.approx(ratio, abs=tolerance)
    if kind in ("cube", "octahedral"):  # every texel inside: the sphere, once
        assert angles.sum() == pytest.approx(4 * np.pi, rel=1e-3)
    else:  # the rim's texels, partly outside the disc, are left out
        assert 0.95 * 4 * np.pi < angles.sum() < 4 * np.pi


def test_latitude_longitude_texels_shrink_towards_the_poles():
    angles = tb.texel_solid_angles(tb.Layout("latlong", 32))
    assert angles.sum() == pytest.approx(4 * np.pi, rel=1e-3)
    # a pole row's texel against the equator's: sin(pi / 64) / sin(pi / 2 - pi / 64)
    assert angles.max() / angles.min() == pytest.approx(1 / np.tan(np.pi / 64), rel=0.01)


def test_the_octahedral_map_matches_the_cubes_coarsest_texel_at_087_of_its_texels():
    """The cube's coarsest texel is at a face's centre, (2/n)^2 sr; the octahedral map's,
    c / m^2 for an interior of m texels, with c about 20.78: the same at m^2 = 0.866 x
    6 n^2 (the issue's 0.87, computed on its own grid)."""
    n = 48
    cube = tb.largest_texel(tb.Layout("cube", n))
    assert cube == pytest.approx((2 / n) ** 2, rel=3e-3)  # a little less: the texel is curved
    matched = tb.matching_budget("octahedral", cube, low=100, high=130)
    assert (
        tb.largest_texel(matched)
        <= cube
        < tb.largest_texel(tb.Layout("octahedral", matched.size - 1))
    )
    interior = (matched.size - 2) ** 2
    assert interior / (6 * n * n) == pytest.approx(0.866, abs=0.01)


@pytest.mark.parametrize("kind", tb.MAPS)
@small_settings
@given(seed=st.integers(0, 2**32 - 1))
def test_a_nearest_lookup_lands_on_the_texel_it_names(kind, seed):
    """The direction a lookup gives back is its texel's centre, which looks up the same
    texel: a nearest lookup of it gives it back. (Not at a disc's rim: a texel there
    whose centre lies past the rim stands for a direction of the other side, or, in a
    sphere map, for the rim's one direction.)"""
    layout = tb.layout_for_budget(kind, 6 * 12 * 12)
    r = tb.uniform_directions(200, seed)
    once = tb.nearest_lookup(layout, r)
    assert np.all(np.isfinite(once))
    assert np.allclose(np.linalg.norm(once, axis=-1), 1)
    again = tb.nearest_lookup(layout, once)
    inside = np.ones(len(r), dtype=bool)
    if kind in ("paraboloid", "sphere"):
        n = layout.size
        i, j, _ = tb._positions(layout, r)
        centre = np.hypot((np.floor(i) + 0.5) / n - 0.5, (np.floor(j) + 0.5) / n - 0.5)
        radius = 0.5 / envmap.PARABOLOID_EXTENT if kind == "paraboloid" else 0.5
        inside = centre < radius
        assert inside.mean() > 0.8
    assert np.allclose(again[inside], once[inside], atol=1e-9)
    assert np.all(np.degrees(np.arccos(np.clip(np.sum(again * once, -1), -1, 1))) < 45)


@pytest.mark.parametrize("kind", tb.MAPS)
def test_errors_halve_as_the_edge_doubles_and_bilinear_beats_nearest(kind):
    spread = tb.uniform_directions(20_000)
    small = tb.lookup_error(tb.layout_for_budget(kind, 6 * 16 * 16), spread)
    large = tb.lookup_error(tb.layout_for_budget(kind, 6 * 32 * 32), spread)
    assert large.mean == pytest.approx(small.mean / 2, rel=0.12)
    assert small.bilinear_mean < small.mean and large.bilinear_mean < large.mean
    assert small.mean <= small.p95 <= small.worst
