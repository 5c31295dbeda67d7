"""The judges' picture comparison: each pixel's smallest largest-channel difference to the
other picture's 3 x 3 neighbourhood (edges repeated), as written the plain way, for any
pictures (hypothesis)."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays

from mirrorlab.labs.trusted.judging import _nearest


def nearest_plainly(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    height, width = a.shape[:2]
    best = np.full((height, width), 255, dtype=np.int16)
    for y in range(height):
        for x in range(width):
            for dy in (-1, 0, 1):
                for dx in (-1, 0, 1):
                    other = b[min(max(y + dy, 0), height - 1), min(max(x + dx, 0), width - 1)]
                    step = np.abs(a[y, x].astype(np.int16) - other.astype(np.int16)).max()
                    best[y, x] = min(best[y, x], step)
    return best


@st.composite
def picture_pairs(draw):
    shape = (draw(st.integers(1, 7)), draw(st.integers(1, 7)), 3)
    pixels = arrays(np.uint8, shape, elements=st.integers(0, 255))
    return draw(pixels), draw(pixels)


@settings(max_examples=60, deadline=None)
@given(picture_pairs())
def test_nearest_is_the_plain_definition(pair):
    a, b = pair
    found = _nearest(a, b)
    assert found.dtype == np.int16 and np.array_equal(found, nearest_plainly(a, b))
