"""The cube-map lab's GLSL functions as the value probe judges them
(:mod:`mirrorlab.labs.trusted.probe`): each one's domain (directions of any length, with
the axes, the face edges and corners where two or three faces tie, and components of zero
as hard cases), the OpenGL table in the handout's notation and the ways it is written,
and, for the face, the family of other ways to pick one. Numpy only."""

from __future__ import annotations

import itertools

import numpy as np

from mirrorlab.labs.trusted import formulas as F
from mirrorlab.labs.trusted.probe import Block, GlslFunction, unit_vectors

FACES = tuple(
    f"{sign}{axis} face (face {2 * i + j})"
    for i, axis in enumerate("XYZ")
    for j, sign in enumerate("+-")
)
r = F.var("r")
rx, ry, rz = F.comp(r, "x"), F.comp(r, "y"), F.comp(r, "z")
ONE, TWO = F.const(1), F.const(2)


def _table(name: str, *entries: F.Expr) -> F.Expr:
    return F.named(name, F.select("face", entries, FACES))


SC = _table("sc", F.neg(rz), rz, rx, rx, rx, F.neg(rx))
TC = _table("tc", F.neg(ry), F.neg(ry), rz, F.neg(rz), F.neg(ry), F.neg(ry))
MA = _table("ma", rx, rx, ry, ry, rz, rz)
MA_SIZE = _table("ma", *(F.call("abs", c) for c in (rx, rx, ry, ry, rz, rz)))


def _st(sc: F.Expr, tc: F.Expr, size: F.Expr) -> F.Expr:
    return F.vec(
        F.div(F.add(F.div(sc, size), ONE), TWO),
        F.div(F.add(F.div(tc, size), ONE), TWO),
    )


TABLE = _st(SC, TC, F.call("abs", MA))
"""s = (sc / |ma| + 1) / 2, t = (tc / |ma| + 1) / 2, sc, tc and ma by the handout's table."""
TABLE_OF_SIZES = _st(SC, TC, MA_SIZE)
"""The same with |ma| in the table, as a solution writes it (a slip on one face's row)."""


def _directions(rng: np.random.Generator) -> list[tuple[str, np.ndarray]]:
    """Directions of the cube map's domain, by kind: any length from 1/4 to 4."""
    general = unit_vectors(rng, 384) * np.exp(rng.uniform(np.log(0.25), np.log(4.0), (384, 1)))
    axes = np.concatenate([np.eye(3), -np.eye(3)])
    axes = np.concatenate([axes, 3.0 * axes])
    edges = []
    for i, j in itertools.combinations(range(3), 2):
        k = 3 - i - j
        for si, sj in itertools.product((1.0, -1.0), repeat=2):
            for _ in range(2):
                v = np.zeros(3)
                size = rng.uniform(0.5, 3.0)
                v[i], v[j] = si * size, sj * size
                v[k] = rng.uniform(-0.9, 0.9) * size
                edges.append(v)
    corners = np.array(list(itertools.product((1.0, -1.0), repeat=3))) * rng.uniform(
        0.5, 3.0, (8, 1)
    )
    near = unit_vectors(rng, 24)
    lead = np.argmax(np.abs(near), -1)
    second = (lead + 1 + (rng.uniform(size=24) > 0.5)) % 3
    rows = np.arange(24)
    near[rows, second] = np.sign(near[rows, second] + 1e-9) * np.abs(near[rows, lead]) * (1 - 2e-3)
    zeros = unit_vectors(rng, 12)
    zeros[np.arange(12), np.arange(12) % 3] = 0.0
    return [
        ("general directions", general),
        ("the axes", axes),
        ("face edges (two components of the same size)", np.array(edges)),
        ("corners (three components of the same size)", corners),
        ("near a face edge", near),
        ("a component of 0", zeros),
    ]


def tied_faces(directions: np.ndarray) -> list[list[int]]:
    """Per direction ``(n, 3)``, the faces it may pick: each axis of the largest size
    (two or three at an edge or corner), with its sign."""
    size = np.abs(directions)
    largest = size.max(-1, keepdims=True)
    return [
        [2 * a + int(d[a] < 0) for a in range(3) if s[a] == m[0]]
        for d, s, m in zip(directions, size, largest, strict=True)
    ]


def face_domain(rng: np.random.Generator) -> list[Block]:
    return [Block(kind, {"r": d}) for kind, d in _directions(rng)]


def st_domain(rng: np.random.Generator) -> list[Block]:
    """Each direction with each face it may pick (an edge's direction on both faces)."""
    blocks = []
    for kind, directions in _directions(rng):
        rows, faces = [], []
        for direction, tied in zip(directions, tied_faces(directions), strict=True):
            for face in tied:
                rows.append(direction)
                faces.append([float(face)])
        blocks.append(Block(kind, {"r": np.array(rows), "face": np.array(faces)}))
    return blocks


def right_face(inputs: dict[str, np.ndarray]) -> np.ndarray:
    """The face of the largest component's size (+X before +Y before +Z at a tie)
    ``(n, 1)``."""
    return np.array([[tied[0]] for tied in tied_faces(inputs["r"])], dtype=np.float64)


def accepts_face(values: np.ndarray, inputs: dict[str, np.ndarray]) -> np.ndarray:
    """Per row: the face given is one the direction may pick."""
    given = values[:, 0]
    ok = np.isfinite(given) & (np.abs(given - np.round(given)) < 1e-3)
    faces = np.where(ok, np.round(given), -1).astype(np.int64)
    return np.array(
        [
            ok_ and face in tied
            for ok_, face, tied in zip(ok, faces, tied_faces(inputs["r"]), strict=True)
        ]
    )


def face_family(inputs: dict[str, np.ndarray]) -> list[tuple[np.ndarray, str]]:
    """Other ways to pick the face, each an axis rule, a sign rule and a numbering: by the
    largest signed component or the smallest size, by comparisons chained (|rx| >= |ry|
    >= |rz| for x, in every order) or made against one other axis only; the sign
    reversed or ignored; the faces numbered +X, +Y, +Z, -X, -Y, -Z."""
    d = inputs["r"]
    size = np.abs(d)
    count = d.shape[0]
    axis_rules: list[tuple[np.ndarray, str]] = [
        (np.argmax(size, -1), ""),
        (
            np.argmax(d, -1),
            "the face is picked by the largest signed component, not the "
            "largest size (compare abs(r.x), abs(r.y), abs(r.z))",
        ),
        (np.argmin(size, -1), "the face is picked by the smallest size, not the largest"),
    ]
    for i, j, k in itertools.permutations(range(3)):
        names = "xyz"
        chained = np.where(
            (size[:, i] >= size[:, j]) & (size[:, j] >= size[:, k]),
            i,
            np.where(size[:, j] >= size[:, k], j, k),
        )
        axis_rules.append(
            (
                chained,
                f"the comparisons are chained: |r{names[i]}| >= |r{names[j]}| >= "
                f"|r{names[k]}| picks {names[i]} only when |r{names[j]}| also beats "
                f"|r{names[k]}|; {names[i]} needs to beat each of the others",
            )
        )
        one = np.where(size[:, i] >= size[:, j], i, np.where(size[:, j] >= size[:, k], j, k))
        axis_rules.append(
            (
                one,
                f"r{names[i]} is compared with r{names[j]} only: it must beat both "
                f"|r{names[j]}| and |r{names[k]}|",
            )
        )
    rows = np.arange(count)
    sign_rules = [
        (lambda a: d[rows, a] < 0, ""),
        (
            lambda a: d[rows, a] >= 0,
            "the right axis but the opposite sign: a positive "
            "component picks the POSITIVE face (0, 2, 4)",
        ),
        (
            lambda a: np.zeros(count, bool),
            "the sign is left out: a negative component picks the NEGATIVE face (1, 3, 5)",
        ),
    ]
    numberings = [
        (lambda a, negative: 2 * a + negative, ""),
        (
            lambda a, negative: a + 3 * negative,
            "the faces are numbered +X, +Y, +Z, -X, -Y, "
            "-Z; OpenGL's order is +X, -X, +Y, -Y, +Z, -Z (0 to 5)",
        ),
    ]
    found = []
    for (axis, axis_words), (sign, sign_words), (number, number_words) in itertools.product(
        axis_rules, sign_rules, numberings
    ):
        words = "; ".join(w for w in (axis_words, sign_words, number_words) if w)
        if words:
            negative = sign(axis).astype(np.int64)
            found.append((number(axis, negative).astype(np.float64)[:, None], words))
    return found


def face_cases(inputs: dict[str, np.ndarray]) -> tuple[np.ndarray, tuple[str, ...]]:
    return inputs["face"].reshape(-1).round().astype(np.int64), FACES


FUNCTIONS = (
    GlslFunction(
        name="cube_face",
        variable="CUBE_MAP_GLSL",
        parameters=("r",),
        widths=(3,),
        result="face",
        kind="face",
        handout="the face of the axis of r's largest size, with its sign (0 +X, 1 -X, ... 5 -Z)",
        domain=face_domain,
        family=face_family,
        right=right_face,
        accepts=accepts_face,
    ),
    GlslFunction(
        name="cube_face_st",
        variable="CUBE_MAP_GLSL",
        parameters=("r", "face"),
        widths=(3, 1),
        result="st",
        kind="coordinates",
        handout="s = (sc / |ma| + 1) / 2, t = (tc / |ma| + 1) / 2 with the table's sc, tc, ma",
        domain=st_domain,
        forms=(TABLE, TABLE_OF_SIZES),
        cases=face_cases,
    ),
)
"""The functions of ``CUBE_MAP_GLSL`` the checker judges, in the handout's order."""
