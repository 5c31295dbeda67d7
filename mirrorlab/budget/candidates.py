"""What an accuracy budget may choose among for each reflector: its candidates.

A candidate is one configuration of a reflector: a technique with its map size and
parameters, as a set of the reflector's fields (:class:`Candidate`). A reflector's
candidates are the configurations the accuracy sweep measures for its kind
(:func:`mirrorlab.accuracy.lab_techniques` for a planar mirror,
:func:`mirrorlab.accuracy.curved_techniques` for a curved reflector): every registered
technique of its kind, at every texture size the sweep measures, with every capture
mode and parallax correction it measures, and the reflector's own configuration as the
scene gives it. A technique registered later joins them by being registered. A
reflector's ``allow`` list keeps only its techniques.

Numpy only (no OpenGL): the sweep's lists are plain data.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, fields, replace
from typing import Any

from mirrorlab.scene.model import (
    CurvedReflector,
    PlanarReflector,
    Reflector,
    Scene,
)
from mirrorlab.techniques import technique

PLACEMENT_FIELDS = {"name", "corners", "transform", "ortho", "allow"}
"""A reflector's fields that say where it is (and its name): a candidate never sets
them, so one candidate serves the reflector in every pose. (An ``ortho`` capture camera
moves with its mirror; a candidate says only whether the mirror keeps it.)"""

AS_GIVEN = "as given"
"""Said of the candidate that is the reflector as its scene gives it (when the sweep
measures no configuration equal to it)."""


@dataclass(frozen=True)
class Candidate:
    """One configuration of a reflector: ``label`` (the sweep's name for it, with its map
    size: ``reflected-fbo 256``, ``cube-live distance 4+1 256``, ``stencil``), the
    ``technique``, its ``map_size`` (the texture's side in texels; 0 where it has none or
    it follows the view or the footprint) and ``changes``, the reflector fields it sets
    (as ``(name, value)`` pairs); ``drops_ortho``: an ``ortho`` capture camera the scene
    gives is not this candidate's (its technique has a camera of another kind)."""

    label: str
    technique: str
    map_size: int
    changes: tuple[tuple[str, Any], ...]
    drops_ortho: bool = False

    def apply(self, reflector: Reflector) -> Reflector:
        """``reflector`` (as posed this frame, its fields as the scene gives them) drawn
        by this candidate."""
        changes = dict(self.changes)
        if self.drops_ortho:
            changes["ortho"] = None
        return replace(reflector, **changes)


def candidates_for(reflector: Reflector, scene: Scene) -> tuple[Candidate, ...]:
    """Every candidate of ``reflector`` in ``scene``: the sweep's configurations of its
    kind (the live cube map's box and sphere proxies made for ``scene``'s objects, as the
    sweep makes them) and the reflector as given, first; only the techniques of its
    ``allow`` list when it has one. Kept for the reflector's configuration (not its
    place), so a moving reflector's candidates are made once."""
    proxies: tuple[tuple[str, str], ...] = ()
    if isinstance(reflector, CurvedReflector) and technique_takes_parallax():
        proxies = _proxies(scene.objects, reflector)
    from mirrorlab.techniques import techniques

    # the registry's entries are part of the key: a technique registered later joins
    return _candidates(_configuration(reflector), proxies, techniques(reflector.kind))


def technique_takes_parallax() -> bool:
    """Whether any registered curved technique takes a parallax correction."""
    from mirrorlab.techniques import techniques

    return any(entry.parallax for entry in techniques("curved"))


_PLACE = ((0.0, -1.0, -1.0), (0.0, 1.0, -1.0), (0.0, 1.0, 1.0), (0.0, -1.0, 1.0))
"""Where a planar mirror's configuration is put to make its candidates."""


def _configuration(reflector: Reflector) -> Reflector:
    """``reflector`` as a key of its configuration: a planar mirror put at one fixed place
    (so that a moving mirror's candidates are made once); a curved reflector where it is
    (its parallax proxies are checked against where it is)."""
    if isinstance(reflector, PlanarReflector):
        return replace(reflector, name="r", corners=_PLACE, ortho=None)
    return replace(reflector, name="r")


@functools.lru_cache(maxsize=64)
def _proxies(objects: tuple, reflector: CurvedReflector) -> tuple[tuple[str, str], ...]:
    from mirrorlab.accuracy import proxies_for

    return proxies_for(Scene("candidates", objects=objects, reflectors=(reflector,)))


@functools.lru_cache(maxsize=64)
def _candidates(
    reflector: Reflector, proxies: tuple[tuple[str, str], ...], registered: tuple
) -> tuple[Candidate, ...]:
    from mirrorlab.accuracy import (
        DISTANCE_STEPS,
        ENVMAP_MAX_SIZE,
        FULL_SIZES,
        curved_techniques,
        lab_techniques,
    )
    from mirrorlab.options import apply_options

    if isinstance(reflector, PlanarReflector):
        configurations = lab_techniques(FULL_SIZES)
    else:
        sizes = tuple(size for size in FULL_SIZES if size <= ENVMAP_MAX_SIZE)
        configurations = curved_techniques(sizes, proxies, DISTANCE_STEPS)
    alone = Scene("candidates", reflectors=(reflector,))
    made: list[Candidate] = []
    seen = set()
    for label, options in configurations:
        changed = apply_options(alone, options).reflectors[0]
        candidate = _candidate(label, reflector, changed)
        if candidate.changes in seen:
            continue
        seen.add(candidate.changes)
        made.append(candidate)
    given = _candidate(AS_GIVEN, reflector, reflector)
    if given.changes not in seen:
        made.insert(0, given)
    if reflector.allow:
        made = [c for c in made if c.technique in reflector.allow]
    return tuple(made)


def _candidate(label: str, original: Reflector, changed: Reflector) -> Candidate:
    """The candidate that makes ``original`` into ``changed`` (their fields but the
    placement ones compared), labelled ``label`` and its map size."""
    changes = tuple(
        (f.name, getattr(changed, f.name))
        for f in fields(changed)
        if (
            f.name not in PLACEMENT_FIELDS and getattr(changed, f.name) != getattr(original, f.name)
        )
        or f.name == "technique"
    )
    size = _map_size(changed)
    drops = isinstance(changed, PlanarReflector) and changed.ortho is None and not _keeps(changed)
    if label == AS_GIVEN:
        label = f"{describe(changed)} ({AS_GIVEN})"
    elif size:
        label = f"{label} {size}"
    return Candidate(label, changed.technique, size, changes, drops)


def describe(reflector: Reflector) -> str:
    """A reflector's configuration in the sweep's words: technique (and capture mode,
    parallax correction), then its map size."""
    entry = technique(reflector.technique)
    words = [reflector.technique]
    if isinstance(reflector, PlanarReflector):
        if not entry.draws_inline:
            words[0] += f"-{reflector.capture}"
            size = reflector.texture_size
            words.append(str(size) if size is not None else "view-sized")
        return " ".join(words)
    assert isinstance(reflector, CurvedReflector)
    parallax = reflector.parallax
    if parallax is not None:
        words.append(parallax.kind)
        steps = getattr(parallax, "steps", None)
        if steps is not None:
            words.append(f"{steps}+{getattr(parallax, 'secant', 0)}")
    words.append(str(reflector.map_size))
    return " ".join(words)


def error_family(reflector: Reflector) -> str:
    """The candidates whose error one model predicts (their map size a feature of it):
    the technique, and a live map's parallax correction (a distance search with its
    steps). A capture's mode (copy or fbo) gives the same picture, so it is left out."""
    words = [reflector.technique]
    parallax = getattr(reflector, "parallax", None)
    if parallax is not None:
        words.append(parallax.kind)
        steps = getattr(parallax, "steps", None)
        if steps is not None:
            words.append(f"{steps}+{getattr(parallax, 'secant', 0)}")
    return " ".join(words)


def cost_family(reflector: Reflector) -> str:
    """The candidates whose cost one model predicts: the error family and a planar
    capture's mode."""
    family = error_family(reflector)
    if isinstance(reflector, PlanarReflector) and not technique(reflector.technique).draws_inline:
        return f"{family} {reflector.capture}"
    return family


def _keeps(reflector: PlanarReflector) -> bool:
    return technique(reflector.technique).own_camera


def _map_size(reflector: Reflector) -> int:
    """The side of the reflector's texture in texels (0: none, or one that follows the
    view or its footprint)."""
    entry = technique(reflector.technique)
    if entry.texture == "inline":
        return 0
    if isinstance(reflector, PlanarReflector):
        size = reflector.texture_size
        return size if isinstance(size, int) else 0
    return reflector.map_size
