"""The whole frame's rule for faint marks (issue 44 item 4), on the labs' real reference
frames: any mark a person can read (a word, solid, hatched on every other column,
checkered or dotted; lines along rows, columns, diagonals and at other angles; boxes) at
any scale, stride and place is caught at every amplitude down to the tolerance stated in
:data:`~mirrorlab.labs.trusted.judging.OVERLAY_LEVELS`, while what another GPU or the
core-profile emulation does to an honest frame (changes under 6 levels anywhere, the
frame or a part of it drawn up to 2 pixels over, blurred up to 2 pixels) never is."""

from __future__ import annotations

from functools import lru_cache

import numpy as np
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from mirrorlab.labs import find_lab
from mirrorlab.labs.content import reference_folder
from mirrorlab.labs.trusted.evidence import Evidence
from mirrorlab.labs.trusted.judging import (
    OVERLAY_LEVELS,
    _spread,
    allowed_pixels,
    differing,
    overlay_marks,
)

LABS = ("lab20", "spheremap", "cubemap")
FONT = {
    "H": ("101", "101", "111", "101", "101"),
    "A": ("010", "101", "111", "101", "101"),
    "C": ("011", "100", "100", "100", "011"),
    "K": ("101", "110", "100", "110", "101"),
    "E": ("111", "100", "110", "100", "111"),
    "D": ("110", "101", "101", "101", "110"),
    "X": ("101", "101", "010", "101", "101"),
    "O": ("111", "101", "101", "101", "111"),
}
FILLS = {"solid": 1, "hatched": 2, "checkered": 2, "dotted": 4}
"""How a word's strokes are filled, and the share of their pixels the fill leaves out
(1: none; 2: every other one; 4: three of four): the mark is caught from
OVERLAY_LEVELS times this."""


@lru_cache(maxsize=4)
def reference(lab: str) -> np.ndarray:
    frame: np.ndarray = Evidence.load(reference_folder(find_lab(lab))).arrays["frame"]
    return frame


@lru_cache(maxsize=4)
def local_range(lab: str) -> np.ndarray:
    """How much the reference varies within 2 pixels of each pixel, ``(h, w)``."""
    ref = reference(lab).astype(np.int16)
    largest, smallest = ref, ref
    for _ in range(2):
        largest, smallest = _spread(largest, np.maximum), _spread(smallest, np.minimum)
    return np.asarray((largest - smallest).max(axis=-1))


def word_mask(word: str, scale: int, fill: str, phase: int) -> np.ndarray:
    """``word`` in the 3 x 5 font, each font pixel ``scale`` pixels, its strokes filled so."""
    rows, columns = 5 * scale, (4 * len(word) - 1) * scale
    mask = np.zeros((rows, columns), dtype=bool)
    for index, letter in enumerate(word):
        for row, line in enumerate(FONT[letter]):
            for column, bit in enumerate(line):
                if bit == "1":
                    x = (4 * index + column) * scale
                    mask[row * scale : (row + 1) * scale, x : x + scale] = True
    yy, xx = np.mgrid[0:rows, 0:columns] + phase
    keep = {
        "solid": np.ones_like(mask),
        "hatched": xx % 2 == 0,
        "checkered": (xx + yy) % 2 == 0,
        "dotted": (xx % 2 == 0) & (yy % 2 == 0),
    }[fill]
    return mask & keep


def line_mask(length: int, slope: float, direction: str) -> np.ndarray:
    """A line one pixel wide, ``length`` pixels along x (or y), of ``slope``."""
    ys = np.round(np.arange(length) * slope).astype(int)
    mask = np.zeros((ys.max() + 1, length), dtype=bool)
    mask[ys, np.arange(length)] = True
    return mask.T if direction == "vertical" else mask


MARKS = st.one_of(
    st.builds(
        lambda word, scale, fill, phase: ("word", FILLS[fill], word_mask(word, scale, fill, phase)),
        st.text(alphabet="".join(FONT), min_size=3, max_size=6),
        st.integers(2, 6),
        st.sampled_from(sorted(FILLS)),
        st.integers(0, 1),
    ),
    st.builds(
        lambda length, slope, direction: (
            "line",
            1 if slope in (0.0, 1.0) else 2,
            line_mask(length, slope, direction),
        ),
        st.integers(48, 140),
        st.sampled_from([0.0, 1.0, 0.3, 0.5, 0.7]),
        st.sampled_from(["horizontal", "vertical"]),
    ),
    st.builds(
        lambda w, h: ("box", 1, np.ones((h, w), dtype=bool)), st.integers(8, 60), st.integers(8, 40)
    ),
)


@settings(max_examples=50, deadline=None)
@given(
    lab=st.sampled_from(LABS),
    mark=MARKS,
    place=st.tuples(st.floats(0, 1), st.floats(0, 1)),
    extra=st.floats(0, 40),
    brighter=st.booleans(),
)
def test_a_readable_mark_is_caught_down_to_the_stated_tolerance(lab, mark, place, extra, brighter):
    """Any mark of any pattern, scale and place: its amplitude the stated tolerance for its
    pattern (OVERLAY_LEVELS times the share its fill leaves out) above how much the
    reference itself varies where it lies, and more."""
    _, sparseness, mask = mark
    ref = reference(lab)
    height, width = mask.shape
    assume(height + 4 <= ref.shape[0] and width + 4 <= ref.shape[1])
    assume(int(mask.sum()) > allowed_pixels(ref.shape))  # up to 32 pixels pass (0.05%)
    y = 2 + int(place[0] * (ref.shape[0] - height - 4))
    x = 2 + int(place[1] * (ref.shape[1] - width - 4))
    box = (slice(y, y + height), slice(x, x + width))
    varies = int(local_range(lab)[box][mask].max())
    amplitude = OVERLAY_LEVELS * sparseness + varies + extra
    values = ref[box].astype(np.int16)[mask]
    room = 255 - int(values.max()) if brighter else int(values.min())
    assume(room >= amplitude)  # the mark must fit in 0..255 where it lies
    marked = ref.astype(np.int16)
    sign = 1 if brighter else -1
    marked[box][mask] += int(np.ceil(amplitude)) * sign
    marked = marked.astype(np.uint8)
    caught = differing(marked, ref) | overlay_marks(marked, ref)
    assert int(caught.sum()) > allowed_pixels(ref.shape), (int(mask.sum()), int(caught.sum()))
    assert int(caught[box][mask].sum()) * 2 >= int(mask.sum())


def shifted(image: np.ndarray, dy: int, dx: int) -> np.ndarray:
    """``image`` drawn ``dy``, ``dx`` pixels over, its edges repeated."""
    height, width = image.shape[:2]
    ys = np.clip(np.arange(height) - dy, 0, height - 1)
    xs = np.clip(np.arange(width) - dx, 0, width - 1)
    return image[ys][:, xs]


def blurred(image: np.ndarray, radius: int) -> np.ndarray:
    padded = np.pad(image.astype(np.float64), ((radius,) * 2, (radius,) * 2, (0, 0)), "edge")
    total = np.zeros(image.shape)
    for dy in range(2 * radius + 1):
        for dx in range(2 * radius + 1):
            total += padded[dy : dy + image.shape[0], dx : dx + image.shape[1]]
    return np.round(total / (2 * radius + 1) ** 2).astype(np.uint8)


@settings(max_examples=40, deadline=None)
@given(
    lab=st.sampled_from(LABS),
    seed=st.integers(0, 2**32 - 1),
    noise=st.integers(0, OVERLAY_LEVELS - 1),
    kind=st.sampled_from(["random", "offset", "stripes", "rows"]),
    move=st.tuples(st.integers(-2, 2), st.integers(-2, 2)),
    part=st.booleans(),
    blur=st.integers(0, 2),
)
def test_what_another_gpu_does_to_an_honest_frame_is_never_a_mark(
    lab, seed, noise, kind, move, part, blur
):
    """Changes under the tolerance anywhere (random, a uniform offset, stripes of one
    sign), on the frame or a part of it drawn up to 2 pixels over, or blurred up to 2
    pixels (2 in all): no pixel is marked."""
    assume(max(abs(move[0]), abs(move[1])) + blur <= 2)
    ref = reference(lab)
    rng = np.random.default_rng(seed)
    honest = shifted(ref, *move)
    if part:  # only a part moved (an object a pixel or two over), the rest in place
        honest = np.where(np.arange(ref.shape[1])[None, :, None] < ref.shape[1] // 2, honest, ref)
    if blur:
        honest = blurred(honest, blur)
    offset = {
        "random": rng.integers(-noise, noise + 1, ref.shape),
        "offset": np.full(ref.shape, rng.choice([-noise, noise])),
        "stripes": np.where(np.arange(ref.shape[1])[None, :, None] % 2 == 0, noise, 0)
        + np.zeros(ref.shape, dtype=int),
        "rows": np.where(np.arange(ref.shape[0])[:, None, None] % 3 == 0, -noise, 0)
        + np.zeros(ref.shape, dtype=int),
    }[kind]
    honest = np.clip(honest.astype(np.int16) + offset, 0, 255).astype(np.uint8)
    assert int(overlay_marks(honest, ref).sum()) == 0
