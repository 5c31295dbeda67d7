"""The sphere-map lab's GLSL functions as the value probe judges them
(:mod:`mirrorlab.labs.trusted.probe`): each one's domain (its general inputs and hard
cases), its formula in the handout's notation and the ways it is written, from which the
variants a hint names are made (:mod:`mirrorlab.labs.trusted.formulas`). Numpy only."""

from __future__ import annotations

import numpy as np

from mirrorlab.labs.trusted import formulas as F
from mirrorlab.labs.trusted.probe import ANY, DIAGNOSTIC, Block, GlslFunction, unit_vectors

u, n, r = F.var("u"), F.var("n"), F.var("r")
rx, ry, rz = F.comp(r, "x"), F.comp(r, "y"), F.comp(r, "z")
HALF = F.const(0.5, "1/2")

REFLECT = F.sub(u, F.mul(F.const(2), F.call("dot", n, u), n))
"""r = u - 2 (n.u) n, as the handout writes it."""

M = F.named(
    "m",
    F.mul(
        F.const(2),
        F.call(
            "sqrt",
            F.add(
                F.call("square", rx), F.call("square", ry), F.call("square", F.add(rz, F.const(1)))
            ),
        ),
    ),
)
HOFF = F.vec(F.add(F.div(rx, M), HALF), F.add(F.div(ry, M), HALF))
"""s = rx / m + 1/2, t = ry / m + 1/2 with m = 2 sqrt(rx^2 + ry^2 + (rz + 1)^2)."""


def _halfway(of: F.Expr) -> F.Expr:
    """s, t from the unit halfway vector between ``of`` and the viewer: normalize(of +
    (0, 0, 1)).xy / 2 + 1/2."""
    h = F.named("h", F.add(of, F.vec(F.const(0), F.const(0), F.const(1))))
    unit = F.call("normalize", h)
    return F.vec(
        F.add(F.div(F.comp(unit, "x"), F.const(2)), HALF),
        F.add(F.div(F.comp(unit, "y"), F.const(2)), HALF),
    )


HALFWAY = _halfway(r)
HALFWAY_OF_UNIT_R = _halfway(F.call("normalize", r))
"""The same (s, t) through the halfway vector, and with r normalised first: the written
forms whose slips (the halfway vector not normalised) the handout's form has no node for."""


def reflect_domain(rng: np.random.Generator) -> list[Block]:
    """Unit u and n over the whole sphere, and the hard cases: n.u = 0, n = -u and n = u,
    u and n along the axes."""
    count = 384
    general = {"u": unit_vectors(rng, count), "n": unit_vectors(rng, count)}
    grazing_u = unit_vectors(rng, 16)
    other = unit_vectors(rng, 16)
    grazing_n = np.cross(grazing_u, other)
    grazing_n /= np.linalg.norm(grazing_n, axis=-1, keepdims=True)
    head_on = unit_vectors(rng, 16)
    axes = np.concatenate([np.eye(3), -np.eye(3)])
    pairs = np.array([(a, b) for a in axes for b in axes])
    return [
        Block("general directions", general),
        Block("grazing directions (n.u = 0)", {"u": grazing_u, "n": grazing_n}),
        Block(
            "head-on directions (n = -u, n = u)",
            {"u": head_on, "n": np.concatenate([-head_on[:8], head_on[8:]])},
        ),
        Block("u and n along the axes", {"u": pairs[:, 0], "n": pairs[:, 1]}),
    ]


def sphere_domain(rng: np.random.Generator) -> list[Block]:
    """Unit r over the whole sphere; the centre r = (0, 0, 1); the rim, r near (0, 0, -1)
    (rz + 1 from 1e-1 down to 1e-4); the axes and the circle rz = 0; the singular direction
    (0, 0, -1) itself (any value); and r of lengths 0.5 and 2.5 (outside the domain, only
    to name a mistake)."""
    general = unit_vectors(rng, 448)
    general = general[general[:, 2] > -1 + 1e-4][:384]
    gaps = np.repeat([1e-1, 1e-2, 1e-3, 1e-4], 6)
    angles = rng.uniform(0, 2 * np.pi, size=gaps.size)
    z = -1 + gaps
    side = np.sqrt(1 - z * z)
    rim = np.stack([side * np.cos(angles), side * np.sin(angles), z], -1)
    around = rng.uniform(0, 2 * np.pi, size=8)
    equator = np.concatenate(
        [
            np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0]], float),
            np.stack([np.cos(around), np.sin(around), np.zeros(8)], -1),
        ]
    )
    away = unit_vectors(rng, 64)
    away = away[away[:, 2] > -0.7][:32]
    return [
        Block("general directions", {"r": general}),
        Block("the centre, r = (0, 0, 1)", {"r": np.array([[0.0, 0.0, 1.0]])}),
        Block("the rim, r close to (0, 0, -1)", {"r": rim}),
        Block("the axes and the circle rz = 0", {"r": equator}),
        Block("the singular direction r = (0, 0, -1)", {"r": np.array([[0.0, 0.0, -1.0]])}, ANY),
        Block(
            "r not of unit length",
            {"r": np.concatenate([0.5 * away, 2.5 * away])},
            DIAGNOSTIC,
        ),
    ]


FUNCTIONS = (
    GlslFunction(
        name="reflect_eye",
        variable="SPHERE_MAP_GLSL",
        parameters=("u", "n"),
        widths=(3, 3),
        result="r",
        kind="direction",
        handout="r = u - 2 (n.u) n",
        domain=reflect_domain,
        forms=(REFLECT,),
    ),
    GlslFunction(
        name="sphere_map_st",
        variable="SPHERE_MAP_GLSL",
        parameters=("r",),
        widths=(3,),
        result="st",
        kind="coordinates",
        handout="s = rx / m + 1/2, t = ry / m + 1/2, m = 2 sqrt(rx^2 + ry^2 + (rz + 1)^2)",
        domain=sphere_domain,
        forms=(HOFF, HALFWAY, HALFWAY_OF_UNIT_R),
    ),
)
"""The functions of ``SPHERE_MAP_GLSL`` the checker judges, in the handout's order."""
