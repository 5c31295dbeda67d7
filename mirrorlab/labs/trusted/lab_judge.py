"""A lab's judge, declared: every lab's reasoning in one place.

A lab's ``judge.py`` declares a :class:`LabJudge`: its tasks (:class:`TaskRule`: the
student functions each judges and the checks its verdict rests on), the textures' and
programs' names the student knows (``roles``), the lab's numbers (``numbers``: what a
variant's values make, for naming a copy) and the regions of the frame each task owns.
:func:`judge` runs it. A task's verdict comes from its checks, each a fact the evidence
shows compared with the reference solution's run of the student's own variant (the
matrices a draw used, the state when a copy was made, a texture's parameters, the order
of the frame's draws, a picture), so any form the handouts allow that does the same
passes. Its hint is, in this order: the error its functions raised (:func:`.judging.results`),
a function of it the frame never calls, the first divergence of the student's calls from
the solution's in its functions (:mod:`.trace_hints`), the first of its ``explain``
checks that finds something, then what its failing check found; and never a call the
file already makes (:meth:`.trace_hints.Hints.guard`).

Numpy only.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mirrorlab.labs import LabSpec
from mirrorlab.labs.trusted.evidence import Evidence
from mirrorlab.labs.trusted.judging import (
    Context,
    TaskResult,
    Verdicts,
    copy_format_slip,
    differing,
    judge_frame,
    matrix,
    results,
    same_picture,
    stopped_hint,
    triangles_mask,
    where,
)
from mirrorlab.labs.trusted.trace_hints import (
    Hints,
    fmt,
    ordinal,
    relation_2d,
)
from mirrorlab.labs.trusted.variants import Variant

GL_COLOR_BUFFER_BIT, GL_DEPTH_BUFFER_BIT = 0x4000, 0x0100
GL_MODELVIEW, GL_PROJECTION = 0x1700, 0x1701
GL_CLAMP = 0x2900
FILTERS = {
    0x2600: "GL_NEAREST",
    0x2601: "GL_LINEAR",
    0x2700: "GL_NEAREST_MIPMAP_NEAREST",
    0x2701: "GL_LINEAR_MIPMAP_NEAREST",
    0x2702: "GL_NEAREST_MIPMAP_LINEAR",
    0x2703: "GL_LINEAR_MIPMAP_LINEAR",
}
MIPMAP_FILTERS = frozenset(range(0x2700, 0x2704))
WRAPS = {
    0x2900: "GL_CLAMP",
    0x812F: "GL_CLAMP_TO_EDGE",
    0x812D: "GL_CLAMP_TO_BORDER",
    0x2901: "GL_REPEAT",
    0x8370: "GL_MIRRORED_REPEAT",
}
PARAMETERS = {
    0x2801: ("GL_TEXTURE_MIN_FILTER", 0x2702),
    0x2800: ("GL_TEXTURE_MAG_FILTER", 0x2601),
    0x2802: ("GL_TEXTURE_WRAP_S", 0x2901),
    0x2803: ("GL_TEXTURE_WRAP_T", 0x2901),
    0x8072: ("GL_TEXTURE_WRAP_R", 0x2901),
}
"""A texture's parameters the checks compare: name, GL's default."""
SAME_WRAP = {GL_CLAMP: 0x812F}
"""GL_CLAMP as the handouts allow it: GL_CLAMP_TO_EDGE."""
AXES = {(1, 0, 0): "+X", (-1, 0, 0): "-X", (0, 1, 0): "+Y", (0, -1, 0): "-Y", (0, 0, 1): "+Z"}
AXES[(0, 0, -1)] = "-Z"
BEGIN_NAMES = {0: "GL_POINTS", 1: "GL_LINES", 2: "GL_LINE_LOOP", 3: "GL_LINE_STRIP"}


# --------------------------------------------------------------------------- events
@dataclass(frozen=True)
class Events:
    """The events of a frame a check reads: of ``kind`` (``draw``, ``copy``, ``clear``,
    ``leave``), drawn by ``who`` (a kit call's name or ``primitive``), while lab function
    ``within`` ran and ``outside`` did not; ``function`` for ``leave`` and ``enter``."""

    kind: str
    who: str | None = None
    within: str | None = None
    outside: str | None = None
    function: str | None = None
    at_least: int = 0
    """Primitives only: with at least this many vertices."""
    last: bool = False
    """Only the last of them (a function the file also calls elsewhere draws more)."""

    def find(self, evidence: Evidence) -> list[dict[str, Any]]:
        found = [
            e
            for e in evidence.events(self.kind, who=self.who, within=self.within)
            if (self.outside is None or self.outside not in (e.get("steps") or []))
            and (self.function is None or e.get("function") == self.function)
            and len(e.get("vertices") or []) >= self.at_least
        ]
        return found[-1:] if self.last else found

    def said(self) -> str:
        what = {
            "draw": f"lab.{self.who}" if self.who and self.who != "primitive" else "glBegin/glEnd",
            "copy": "a copy (glCopyTexImage2D)",
            "clear": "glClear",
        }.get(self.kind, self.kind)
        return what + (f" in {self.within}()" if self.within else "")


@dataclass(frozen=True)
class Finding:
    """What a failing check found: ``hint``; ``slots``, the kinds of state it is about
    (for choosing the divergence that explains it); ``final`` when the hint stands as it is
    (a copy of another variant, a picture judged once another task passes); ``about``, the
    function whose calls it is about when that is not the task's own (then its slots choose
    nothing among the task's functions' divergences)."""

    hint: str
    slots: frozenset[str] = frozenset()
    final: bool = False
    about: str | None = None


@dataclass
class Run:
    """One judging: the two runs, the variant's context, the lab's numbers (``numbers``,
    and every other variant's in ``others``), the trace hints and the verdicts so far."""

    spec: LabSpec
    declared: LabJudge
    student: Evidence
    reference: Evidence
    context: Context
    hints: Hints
    numbers: dict[str, Any]
    others: dict[str, dict[str, Any]]
    passed: dict[str, bool] = field(default_factory=dict)

    @property
    def size(self) -> tuple[int, int]:
        frame = self.reference.image("frame")
        return (frame.shape[1], frame.shape[0]) if frame is not None else (256, 256)

    def task_name(self, task_id: str) -> str:
        return self.spec.task_name(task_id)

    def role(self, texture: Any, evidence: Evidence | None = None) -> str:
        evidence = evidence or self.student
        for key, name in self.declared.roles.items():
            if texture and evidence.state.get(key) == texture:
                return name
        return f"texture {texture}" if texture else "no texture"

    def at(self, line: int) -> str:
        return self.student.at(line) or "the lab's own code"


Check = Callable[[Run], "Finding | None"]


# ---------------------------------------------------------------------- the checks
@dataclass(frozen=True)
class Happens:
    """``events`` happen in the last frame (as often as in the solution's with ``count``)."""

    events: Events
    what: str
    count: bool = False

    def __call__(self, run: Run) -> Finding | None:
        mine, theirs = self.events.find(run.student), self.events.find(run.reference)
        if not mine and theirs:
            return Finding(
                f"{self.what} never happens: no {self.events.said()}",
                _slots(self.events),
                about=self.events.within,
            )
        if self.count and len(mine) != len(theirs):
            return Finding(
                f"{self.events.said()} happens {len(mine)} times; the solution's {len(theirs)}",
                _slots(self.events),
            )
        return None


def _slots(events: Events) -> frozenset[str]:
    return frozenset({"framebuffer"} if events.kind in ("draw", "clear") else {"image"})


def _pairs(events: Events, run: Run) -> list[tuple[dict[str, Any], dict[str, Any]]] | Finding:
    mine, theirs = events.find(run.student), events.find(run.reference)
    if len(mine) != len(theirs):
        if not mine:
            return Finding(f"no {events.said()} in the last frame", _slots(events))
        return Finding(
            f"{events.said()} happens {len(mine)} times in a frame; the solution's {len(theirs)}",
            _slots(events),
        )
    return list(zip(mine, theirs, strict=True))


@dataclass(frozen=True)
class SameView:
    """The draws ``events`` use the solution's matrices: the same picture on screen (x and y
    of projection @ modelview); with ``keep`` and ``cut``, any near and far planes that
    keep what lies at those distances along the view (and leave out what lies at ``cut``),
    else the same depth too. ``what`` names the view in a hint."""

    events: Events
    what: str
    keep: tuple[float, ...] = ()
    cut: tuple[float, ...] = ()

    def __call__(self, run: Run) -> Finding | None:
        pairs = _pairs(self.events, run)
        if isinstance(pairs, Finding):
            return pairs
        for index, (mine, theirs) in enumerate(pairs):
            p, m = matrix(mine.get("projection")), matrix(mine.get("modelview"))
            rp, rm = matrix(theirs.get("projection")), matrix(theirs.get("modelview"))
            if p is None or m is None or rp is None or rm is None:
                return Finding(f"{self.what}: its matrices are not numbers", frozenset({"matrix"}))
            if not self.same(p, m, rp, rm):
                which = f" ({ordinal(index)} of {len(pairs)})" if len(pairs) > 1 else ""
                other = next(
                    (
                        j
                        for j, (_, want) in enumerate(pairs)
                        if j != index
                        and (wp := matrix(want.get("projection"))) is not None
                        and (wm := matrix(want.get("modelview"))) is not None
                        and self.same(p, m, wp, wm)
                    ),
                    None,
                )
                if other is not None:
                    return Finding(
                        f"{self.what} in the wrong order: the {ordinal(index)} is the "
                        f"solution's {ordinal(other)}" + _set_by(mine, run),
                        frozenset({"matrix"}),
                    )
                return Finding(
                    f"{self.what}{which}: {explain_view(p, m, rp, rm, self.keep, self.cut)}"
                    + _set_by(mine, run),
                    frozenset({"matrix", "matrix_mode"}),
                )
        return None

    def same(self, p: np.ndarray, m: np.ndarray, rp: np.ndarray, rm: np.ndarray) -> bool:
        clip, want = p @ m, rp @ rm
        scale = max(1.0, float(np.abs(want).max()))
        if not self.keep and not self.cut:
            return bool(np.allclose(clip, want, atol=1e-4 * scale))
        if not np.allclose(clip[[0, 1, 3]], want[[0, 1, 3]], atol=1e-4 * scale):
            return False
        return depth_ok(clip, rm, self.keep, self.cut)


def depth_ok(
    clip: np.ndarray, view: np.ndarray, keep: tuple[float, ...], cut: tuple[float, ...]
) -> bool:
    """Whether ``clip`` keeps the points ``keep`` away along ``view``'s direction between its
    near and far planes, and the points ``cut`` away outside them."""
    to_world = np.linalg.inv(view)

    def inside(distance: float) -> bool:
        point = to_world @ np.array([0.0, 0.0, -distance, 1.0])
        x = clip @ point
        return bool(x[3] > 1e-9 and abs(x[2] / x[3]) <= 1.0)

    return all(inside(d) for d in keep) and not any(inside(d) for d in cut)


def projection_of(p: np.ndarray) -> dict[str, Any]:
    """What a projection matrix is: ``kind`` (none, orthographic, perspective, other) and its
    numbers (glOrtho's extents; gluPerspective's fovy, aspect, near, far)."""
    if np.allclose(p, np.eye(4), atol=1e-6):
        return {"kind": "none"}
    if (
        np.allclose(p[3], (0, 0, 0, 1), atol=1e-6)
        and min(abs(p[0, 0]), abs(p[1, 1]), abs(p[2, 2])) > 1e-12
    ):
        width, height, depth = 2 / p[0, 0], 2 / p[1, 1], -2 / p[2, 2]
        mid = (-p[0, 3] * width, -p[1, 3] * height, -p[2, 3] * depth)
        extents = (
            (mid[0] - width) / 2,
            (mid[0] + width) / 2,
            (mid[1] - height) / 2,
            (mid[1] + height) / 2,
            (mid[2] - depth) / 2,
            (mid[2] + depth) / 2,
        )
        return {"kind": "orthographic", "extents": extents}
    if (
        np.allclose(p[3], (0, 0, -1, 0), atol=1e-6)
        and abs(p[1, 1]) > 1e-12
        and abs(p[0, 0]) > 1e-12
    ):
        a, b = p[2, 2], p[2, 3]
        near, far = (
            (float(b / (a - 1)), float(b / (a + 1))) if abs(a * a - 1) > 1e-12 else (0.0, 0.0)
        )
        return {
            "kind": "perspective",
            "fovy": float(np.degrees(2 * np.arctan(1 / p[1, 1]))),
            "aspect": float(p[1, 1] / p[0, 0]),
            "near": near,
            "far": far,
        }
    return {"kind": "other"}


def camera_of(m: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """Eye, view direction and up of a rigid modelview ``m`` (None when it is not rigid)."""
    rotation = m[:3, :3]
    if not np.allclose(rotation @ rotation.T, np.eye(3), atol=1e-4):
        return None
    return -rotation.T @ m[:3, 3], -rotation[2], rotation[1]


def _towards(direction: np.ndarray) -> str:
    for axis, name in AXES.items():
        if np.dot(direction, axis) > 0.999:
            return f" (towards {name})"
    return ""


def explain_view(
    p: np.ndarray,
    m: np.ndarray,
    rp: np.ndarray,
    rm: np.ndarray,
    keep: tuple[float, ...],
    cut: tuple[float, ...],
) -> str:
    """How the matrices ``p``, ``m`` differ from the solution's ``rp``, ``rm``, in the words
    of the calls that make them: the kind of projection, its extents, field of view, aspect,
    near and far planes; the camera's eye, direction and up."""
    mine, theirs = projection_of(p), projection_of(rp)
    parts = []
    if mine["kind"] != theirs["kind"]:
        parts.append(
            "no projection is set (the projection matrix is the identity)"
            if mine["kind"] == "none"
            else f"the projection is {mine['kind']}; the solution's is {theirs['kind']}"
        )
    elif mine["kind"] == "orthographic":
        a, b = mine["extents"], theirs["extents"]
        if not np.allclose(a[:4], b[:4], atol=1e-3):
            parts.append(
                f"the orthographic box's left, right, bottom, top are {fmt(np.round(a[:4], 3))} "
                f"(the solution's: {fmt(np.round(b[:4], 3))})"
            )
        elif (keep or cut) and np.allclose(m, rm, atol=1e-4) and not depth_ok(p @ m, rm, keep, cut):
            parts.append(
                f"the near and far planes {fmt(np.round(a[4:], 3))} cut what the view must "
                f"show or show what it must not (the solution's: {fmt(np.round(b[4:], 3))})"
            )
    elif mine["kind"] == "perspective":
        if abs(mine["fovy"] - theirs["fovy"]) > 0.05:
            parts.append(
                f"field of view {mine['fovy']:.0f} degrees (the solution's: {theirs['fovy']:.0f})"
            )
        elif abs(mine["aspect"] - theirs["aspect"]) > 1e-3:
            parts.append(f"aspect {mine['aspect']:.2f} (the solution's: {theirs['aspect']:.2f})")
        elif keep and not 0 < mine["near"] < min(keep):
            parts.append(
                f"the near plane {mine['near']:.4g} is beyond what lies {min(keep):g} away, "
                f"so it is lost (the solution's near plane: {theirs['near']:.4g})"
            )
        elif keep and mine["far"] < max(keep):
            parts.append(
                f"the far plane {mine['far']:.4g} stops short of what lies {max(keep):g} away "
                f"(the solution's far plane: {theirs['far']:.4g})"
            )
        elif not keep:
            parts.append(
                f"near and far {mine['near']:.4g}, {mine['far']:.4g} (the solution's: "
                f"{theirs['near']:.4g}, {theirs['far']:.4g})"
            )
    if not np.allclose(m, rm, atol=1e-4):
        camera, want = camera_of(m), camera_of(rm)
        if camera is None or want is None:
            if np.allclose(m, rm @ rm, atol=1e-4):
                parts.append("the camera's matrix is applied twice (it multiplies onto itself)")
            else:
                parts.append("the camera's matrix is not a rigid camera (it scales or shears)")
        else:
            eye, forward, up = camera
            w_eye, w_forward, w_up = want
            if np.allclose(m, rm @ rm, atol=1e-4):
                parts.append("the camera's matrix is applied twice (it multiplies onto itself)")
            elif np.dot(forward, w_forward) < 0.999:
                parts.append(
                    f"the camera looks along ({fmt(np.round(forward, 3))}){_towards(forward)}; "
                    f"the solution's along ({fmt(np.round(w_forward, 3))}){_towards(w_forward)}"
                )
            elif not np.allclose(eye, w_eye, atol=1e-3):
                parts.append(
                    f"the camera sits at ({fmt(np.round(eye, 3))}); the solution's at "
                    f"({fmt(np.round(w_eye, 3))})"
                )
            elif np.dot(up, w_up) < 0.999:
                parts.append(
                    f"the camera's up is ({fmt(np.round(up, 3))}); the solution's is "
                    f"({fmt(np.round(w_up, 3))})"
                )
    return "; ".join(parts) or "its matrices differ from the solution's"


def _set_by(event: dict[str, Any], run: Run) -> str:
    """' (set by glOrtho at line 59, gluLookAt at line 62)': the calls that made the
    matrices at ``event``."""
    ops = (event.get("state") or {}).get("matrix_ops") or {}
    made = []
    for mode in (str(GL_PROJECTION), str(GL_MODELVIEW)):
        for op in ops.get(mode) or []:
            if isinstance(op, dict) and op.get("line") and op.get("op") != "glLoadIdentity":
                made.append(f"{op['op']} at line {op['line']}")
    return f" (set by {', '.join(made[:4])})" if made else ""


@dataclass(frozen=True)
class SameViewport:
    """The draws ``events`` use the solution's viewport."""

    events: Events
    what: str

    def __call__(self, run: Run) -> Finding | None:
        pairs = _pairs(self.events, run)
        if isinstance(pairs, Finding):
            return pairs
        for mine, theirs in pairs:
            if mine.get("viewport") != theirs.get("viewport"):
                setting = (mine.get("state") or {}).get("viewport") or {}
                line = setting.get("line", 0)
                by = (
                    f" (glViewport at {run.at(line)}"
                    + (f", in {setting.get('function')}()" if setting.get("function") else "")
                    + ")"
                    if line
                    else ""
                )
                box, want = mine.get("viewport") or [0] * 4, theirs.get("viewport") or [0] * 4
                return Finding(
                    f"{self.what} is drawn in the viewport ({fmt(box)}){by}; the solution's is "
                    f"({fmt(want)})",
                    frozenset({"viewport"}),
                )
        return None


@dataclass(frozen=True)
class SameClears:
    """Before each of the draws ``events`` (since the one before it, in the function that
    draws), the framebuffer is cleared as the solution's is: the same buffers, to the same
    colour."""

    events: Events
    what: str

    def __call__(self, run: Run) -> Finding | None:
        pairs = _pairs(self.events, run)
        if isinstance(pairs, Finding):
            return pairs
        for index, (mine, theirs) in enumerate(pairs):
            a, b = (
                _clears_before(run.student, mine, self.events),
                _clears_before(run.reference, theirs, self.events),
            )
            which = f"the {ordinal(index)} " if len(pairs) > 1 else ""
            if b["mask"] & ~a["mask"]:
                lacking = []
                if b["mask"] & GL_COLOR_BUFFER_BIT and not a["mask"] & GL_COLOR_BUFFER_BIT:
                    lacking.append("the colour")
                if b["mask"] & GL_DEPTH_BUFFER_BIT and not a["mask"] & GL_DEPTH_BUFFER_BIT:
                    lacking.append("the depth buffer")
                last = f" (glClear at {run.at(a['line'])} clears less)" if a["line"] else ""
                return Finding(
                    f"{' and '.join(lacking)} is not cleared before {which}{self.what}{last}: "
                    f"it keeps what was drawn before it",
                    frozenset({"framebuffer"}),
                )
            if b["mask"] & GL_COLOR_BUFFER_BIT and not np.allclose(
                a["color"][:3], b["color"][:3], atol=0.02
            ):
                by = (
                    f" (glClearColor at {run.at(a['color_line'])}"
                    + (f", in {a['color_function']}()" if a["color_function"] else "")
                    + ")"
                    if a["color_line"]
                    else ""
                )
                return Finding(
                    f"{which}{self.what} is cleared to ({fmt(np.round(a['color'][:3], 3))}){by}; "
                    f"the solution clears to ({fmt(np.round(b['color'][:3], 3))})",
                    frozenset({"clear_color"}),
                )
        return None


def _clears_before(evidence: Evidence, event: dict[str, Any], selected: Events) -> dict[str, Any]:
    """The clears between the draw ``event`` and the draw of ``selected`` before it (or the
    frame's start): their buffers, the colour and where it was set."""
    events = evidence.last_frame
    index = next((i for i, e in enumerate(events) if e is event), 0)
    earlier = [e for e in selected.find(evidence) if events.index(e) < index] if index else []
    start = events.index(earlier[-1]) if earlier else 0
    mask, color, line, color_line, function = 0, (0.0, 0.0, 0.0), 0, 0, ""
    for e in events[start:index]:
        if e.get("kind") == "clear" and not e.get("scissor"):
            mask |= int(e.get("mask") or 0)
            setting = e.get("color") or {}
            color = tuple(setting.get("value") or (0, 0, 0, 0))
            color_line, function = setting.get("line", 0), setting.get("function", "")
            line = e.get("line", 0)
    return {
        "mask": mask,
        "color": color,
        "line": line,
        "color_line": color_line,
        "color_function": function,
    }


@dataclass(frozen=True)
class SamePicture:
    """The picture ``array`` (an array of the evidence), or the one the first of ``events``
    copied, matches the solution's (see :func:`.judging.same_picture`); ``after``: tasks it
    is judged once they pass; ``what`` names it."""

    what: str
    array: str = ""
    events: Events | None = None
    after: tuple[str, ...] = ()
    columns: Callable[[Run], slice] | None = None

    def pictures(self, run: Run) -> tuple[np.ndarray | None, np.ndarray | None]:
        if self.events is not None:
            mine, theirs = self.events.find(run.student), self.events.find(run.reference)
            if not mine or not theirs:
                return None, None
            return run.student.image(mine[0].get("picture", "")), run.reference.image(
                theirs[0].get("picture", "")
            )
        a, b = run.student.arrays.get(self.array), run.reference.arrays.get(self.array)
        return (a if isinstance(a, np.ndarray) else None), (
            b if isinstance(b, np.ndarray) else None
        )

    def __call__(self, run: Run) -> Finding | None:
        mine, theirs = self.pictures(run)
        if theirs is None:
            return None
        if mine is None or mine.dtype != np.uint8 or mine.shape != theirs.shape:
            return Finding(f"{self.what} is missing", frozenset({"framebuffer", "image"}))
        if self.columns is not None:
            cols = self.columns(run)
            mine, theirs = mine[:, cols], theirs[:, cols]
        if mine.ndim == 4:
            bad = [i for i in range(len(mine)) if not same_picture(mine[i], theirs[i])]
            if not bad:
                return None
            worst = max(bad, key=lambda i: int(differing(mine[i], theirs[i]).sum()))
            mask = differing(mine[worst], theirs[worst])
            found = (
                f"{self.what}: {len(bad)} of {len(mine)} differ from the solution's; the "
                f"{ordinal(worst)} in {int(mask.sum())} texels, {where(mask)}"
            )
        elif same_picture(mine, theirs):
            return None
        else:
            mask = differing(mine, theirs)
            found = (
                f"{self.what} differs from the solution's in {int(mask.sum())} pixels, "
                f"{where(mask)}"
            )
        for task in self.after:
            if not run.passed.get(task, True):
                return Finding(f"{self.what} is judged once {run.task_name(task)} passes")
        return Finding(found, frozenset({"framebuffer", "image"}))


@dataclass(frozen=True)
class SameCopies:
    """The copies ``events`` take what the solution's take: into the texture of the same
    role, the same face and level, the same part of the framebuffer, a format that keeps the
    picture's colours (:func:`.judging.copy_format_slip`)."""

    events: Events

    def __call__(self, run: Run) -> Finding | None:
        pairs = _pairs(self.events, run)
        if isinstance(pairs, Finding):
            return pairs
        for mine, theirs in pairs:
            at = run.at(mine.get("line", 0))
            role, want = (
                run.role(mine.get("texture")),
                run.role(theirs.get("texture"), run.reference),
            )
            if role != want:
                return Finding(
                    f"the copy at {at} went into {role} (bound on unit {mine.get('unit')} at "
                    f"that moment), not {want}",
                    frozenset({"binding", "unit", "image"}),
                )
            for key, words in (
                ("target", "the face (target)"),
                ("level", "the level"),
            ):
                if mine.get(key) != theirs.get(key):
                    return Finding(
                        f"the copy at {at} fills {words} {mine.get(key):#x} "
                        if key == "target"
                        else f"the copy at {at} fills level {mine.get(key)}; the solution's "
                        f"level {theirs.get(key)}",
                        frozenset({"image"}),
                    )
            if (mine.get("x"), mine.get("y"), mine.get("offset")) != (
                theirs.get("x"),
                theirs.get("y"),
                theirs.get("offset"),
            ):
                return Finding(
                    f"the copy at {at} starts at ({mine.get('x')}, {mine.get('y')}) of the "
                    f"framebuffer: the solution copies from ({theirs.get('x')}, "
                    f"{theirs.get('y')})",
                    frozenset({"image"}),
                )
            if (mine.get("width"), mine.get("height")) != (
                theirs.get("width"),
                theirs.get("height"),
            ):
                return Finding(
                    f"the copy at {at} takes {mine.get('width')} x {mine.get('height')} "
                    f"pixels; the solution's {theirs.get('width')} x {theirs.get('height')}",
                    frozenset({"image"}),
                )
            if slip := copy_format_slip(mine):
                return Finding(f"the copy at {at} {slip}", frozenset({"image"}))
        return None


@dataclass(frozen=True)
class SameOrder:
    """The frame's draws, clears and copies while ``within`` ran come in the solution's
    order (consecutive clears taken as one; a lab function called from ``within`` as one
    step, its own order its task's)."""

    within: str

    def signature(self, evidence: Evidence) -> list[tuple[Any, ...]]:
        found: list[tuple[Any, ...]] = []
        for event in evidence.last_frame:
            steps = event.get("steps") or []
            if event.get("kind") not in ("draw", "copy", "clear") or self.within not in steps:
                continue
            if (
                event.get("kind") == "draw"
                and event.get("who") == "primitive"
                and len(event.get("vertices") or []) < 3
            ):
                continue
            inner = steps[steps.index(self.within) + 1 :]
            if inner:
                label: tuple[Any, ...] = ("function", inner[0], self.within)
                if not found or found[-1] != label:
                    found.append(label)
                continue
            label = (event["kind"], event.get("who"), event.get("function"))
            if found and event["kind"] == "clear" and found[-1][0] == "clear":
                found[-1] = label
                continue
            found.append(label)
        return found

    def __call__(self, run: Run) -> Finding | None:
        mine, theirs = self.signature(run.student), self.signature(run.reference)
        if mine == theirs:
            return None

        def said(label: tuple[Any, ...]) -> str:
            kind, who, function = label
            if kind == "function":
                return f"{who}()"
            if kind == "draw":
                return f"lab.{who}" if who != "primitive" else f"the glBegin/glEnd of {function}()"
            return f"the {kind} in {function}()"

        for a, b in zip(mine, theirs, strict=False):
            if a != b:
                return Finding(
                    f"in the wrong order: the solution's frame has {said(b)} where yours has "
                    f"{said(a)}",
                    frozenset({"framebuffer"}),
                )
        return Finding(
            f"the frame draws {len(mine)} things in {self.within}(); the solution's {len(theirs)}",
            frozenset({"framebuffer"}),
        )


@dataclass(frozen=True)
class CopiesAfterDraws:
    """Each of the copies ``copies`` comes after the same draw of ``draws`` (and before
    the next) as the solution's: it takes what was drawn for it."""

    copies: Events
    draws: Events

    def places(self, evidence: Evidence) -> list[int]:
        index = {id(e): i for i, e in enumerate(evidence.last_frame)}
        drawn = [index[id(d)] for d in self.draws.find(evidence)]
        return [sum(1 for d in drawn if d < index[id(c)]) for c in self.copies.find(evidence)]

    def __call__(self, run: Run) -> Finding | None:
        mine, theirs = self.places(run.student), self.places(run.reference)
        for i, (a, b) in enumerate(zip(mine, theirs, strict=False)):
            if a != b:
                copy = self.copies.find(run.student)[i]
                return Finding(
                    f"in the wrong order: the copy at {run.at(copy.get('line', 0))} comes "
                    f"after {a} of the draws ({self.draws.said()}); the solution's after {b}: "
                    f"a copy takes only what was drawn before it",
                    frozenset({"framebuffer", "image"}),
                )
        return None


@dataclass(frozen=True)
class SameTexture:
    """The texture of evidence key ``texture`` (its role) ends with the solution's filters
    and wrapping (GL_CLAMP allowed for GL_CLAMP_TO_EDGE) and mipmaps only where the
    solution's has them."""

    texture: str
    parameters: tuple[int, ...] = (0x2801, 0x2800, 0x2802, 0x2803)

    def __call__(self, run: Run) -> Finding | None:
        mine = run.student.texture(run.student.state.get(self.texture))
        theirs = run.reference.texture(run.reference.state.get(self.texture))
        name = self.role(run)
        if theirs is None:
            return None
        if mine is None:
            return Finding(f"{name} is not a texture the lab shows", frozenset({"binding"}))
        for pname in self.parameters:
            label, default = PARAMETERS[pname]
            have, line = _parameter(mine, pname, default)
            want, _ = _parameter(theirs, pname, default)
            if SAME_WRAP.get(have, have) == SAME_WRAP.get(want, want):
                continue
            set_at = f" (line {line})" if line else " (GL's default: never set)"
            names = FILTERS if "FILTER" in label else WRAPS
            found = (
                f"{name}'s {label} is {names.get(have, hex(have))}{set_at}; the solution's is "
                f"{names.get(want, hex(want))}"
            )
            if have in MIPMAP_FILTERS and want not in MIPMAP_FILTERS:
                found += (
                    ": a mipmap filter wants mipmaps, which a copy into level 0 never makes, "
                    "so the texture is incomplete and shows black"
                )
            elif have in (0x2901, 0x8370) and want not in (0x2901, 0x8370):
                found += ": repeating blends the opposite edge in at the border"
            return Finding(found, frozenset({"texparam"}))
        if _levels(mine) and not _levels(theirs):
            line = (mine.get("mipmaps") or {}).get("line", 0)
            return Finding(
                f"{name} has mipmaps (glGenerateMipmap{f' at line {line}' if line else ''}) "
                f"that later copies into level 0 never update; the solution's has level 0 only",
                frozenset({"mipmaps"}),
            )
        return None

    def role(self, run: Run) -> str:
        return run.declared.roles.get(self.texture, self.texture)


def _parameter(record: dict[str, Any], pname: int, default: int) -> tuple[int, int]:
    setting = (record.get("params") or {}).get(str(pname))
    if isinstance(setting, dict) and isinstance(setting.get("value"), int | float):
        return int(setting["value"]), int(setting.get("line") or 0)
    return default, 0


def _levels(record: dict[str, Any]) -> bool:
    return any(isinstance(i, list) and len(i) == 3 and i[1] > 0 for i in record.get("images") or [])


@dataclass(frozen=True)
class SameArgument:
    """The kit call of ``events`` was given what the solution's was at ``path`` (keys into
    its recorded arguments), a texture by its role; ``label`` is how the file writes it."""

    events: Events
    path: tuple[str, ...]
    label: str

    def __call__(self, run: Run) -> Finding | None:
        mine, theirs = self.events.find(run.student), self.events.find(run.reference)
        if not theirs:
            return None
        if not mine:
            stopped = run.student.raised_in()
            if stopped:
                return Finding(f"not judged: the frame stopped at {stopped}()", final=True)
            return Finding(f"no {self.events.said()} in the last frame", frozenset({"framebuffer"}))

        def value(event: dict[str, Any], evidence: Evidence) -> str:
            found: Any = event
            for key in self.path:
                found = found.get(key) if isinstance(found, dict) else None
            if isinstance(found, dict):
                return f"another value ({found.get('other', '?')})"
            return run.role(found, evidence) if found else "no texture"

        have, want = value(mine[-1], run.student), value(theirs[-1], run.reference)
        if have == want:
            return None
        return Finding(
            f"{self.label} is {have} when {self.events.said()} at "
            f"{run.at(mine[-1].get('line', 0))} "
            f"draws; the solution gives it {want}",
            frozenset(),
        )


@dataclass(frozen=True)
class SameSampling:
    """The draws ``events`` use the solution's program, and the texture its sampler reads
    (the one bound on the unit the sampler uniform names) has the same role."""

    events: Events
    program: str
    sampler: str

    def __call__(self, run: Run) -> Finding | None:
        pairs = _pairs(self.events, run)
        if isinstance(pairs, Finding):
            return pairs
        mine, theirs = pairs[-1]
        state = mine.get("state") or {}
        program = state.get("program") or {}
        if program.get("value") != run.student.state.get(self.program):
            line = program.get("line", 0)
            by = f" (glUseProgram at {run.at(line)})" if line else ""
            return Finding(
                f"{self.events.said()} draws without {self.program_name(run)}: the program in use "
                f"is {program.get('value') or 'none'}{by}; the solution uses "
                f"{self.program_name(run)}",
                frozenset({"program"}),
            )
        unit, want_unit = mine.get("sampler"), theirs.get("sampler")
        have = _bound(state, unit, run, run.student)
        want = _bound(theirs.get("state") or {}, want_unit, run, run.reference)
        if have == want:
            return None
        units = [
            int(u)
            for u, entry in (state.get("units") or {}).items()
            if run.role((entry.get("2d") or {}).get("value")) == want
        ]
        set_at = mine.get("sampler_set")
        if not set_at:
            said = f"the sampler uniform {self.sampler} is never set, so it reads unit {unit}"
        else:
            said = (
                f"{self.sampler} reads unit {unit} (glUniform1i at {run.at(set_at.get('line', 0))})"
            )
        where_bound = (
            f"{want} is bound on unit {', '.join(map(str, units))}"
            if units
            else f"{want} is bound on no unit"
        )
        return Finding(
            f"{said}, which holds {have}; {where_bound} when it draws",
            frozenset({"uniform", "binding", "unit"}),
        )

    def program_name(self, run: Run) -> str:
        return run.declared.programs.get(self.program, self.program)


def _bound(state: dict[str, Any], unit: Any, run: Run, evidence: Evidence) -> str:
    entry = (state.get("units") or {}).get(str(unit)) or {}
    return run.role((entry.get("2d") or {}).get("value"), evidence)


@dataclass(frozen=True)
class SamePrimitive:
    """The primitive of ``events`` (the last) covers the solution's: its vertices lie on the
    solution's polygon (in the solution's model space) and cover it, and its texture
    coordinates are the solution's at every point; ``what`` names it, ``corners`` is the
    numbers' key of its corners (for naming a copy)."""

    events: Events
    what: str
    corners: str = ""

    def __call__(self, run: Run) -> Finding | None:
        mine, theirs = self.events.find(run.student), self.events.find(run.reference)
        if not theirs:
            return None
        if not mine:
            return Finding(f"no {self.what} is drawn (glBegin ... glEnd)", frozenset({"primitive"}))
        a, b = mine[-1], theirs[-1]
        at = run.at(a.get("begin_line", 0))
        if a.get("mode") not in (4, 5, 6, 7, 8, 9):
            return Finding(
                f"{self.what} at {at} is drawn as "
                f"{BEGIN_NAMES.get(int(a.get('mode') or 0), 'lines')}: it "
                f"must fill its area (the solution's: a polygon)",
                frozenset({"primitive"}),
            )
        m, rm = matrix(a.get("modelview")), matrix(b.get("modelview"))
        if m is None or rm is None:
            return Finding(f"{self.what}: its matrices are not numbers", frozenset({"matrix"}))
        to_model = np.linalg.inv(rm) @ m
        points = _points(a, to_model)
        want = _points(b, np.eye(4))
        texcoords = np.array([v[1][0][:2] for v in a["vertices"]], dtype=np.float64)
        want_tc = np.array([v[1][0][:2] for v in b["vertices"]], dtype=np.float64)
        copied = self.copied(run, points)
        if copied:
            return copied
        corners = _unique(want)
        listed = ", ".join(f"({fmt(np.round(c, 3))})" for c in corners)
        normal, offset = _plane(want)
        offsets = points @ normal - offset
        if not np.allclose(offsets, 0, atol=1e-3):
            axis = _axis_name(normal)
            if np.allclose(offsets, offsets[0], atol=1e-3) and axis:
                level = float(points[0] @ normal * np.sign(normal.sum()))
                return Finding(
                    f"{self.what} at {at} lies in the plane {axis} = {level:g}; the solution's "
                    f"in {axis} = {float(offset * np.sign(normal.sum())):g} (its corners: "
                    f"{listed})",
                    frozenset({"vertex"}),
                )
            return Finding(
                f"{self.what} at {at} is not flat in the solution's plane (its corners: {listed})",
                frozenset({"vertex"}),
            )
        for point in points:
            nearest = corners[int(np.argmin(np.linalg.norm(corners - point, axis=1)))]
            if not _inside(point, want, int(b.get("mode", 7))) or (
                len(points) <= 4 and not np.allclose(point, nearest, atol=1e-3)
            ):
                return Finding(
                    f"the vertex ({fmt(np.round(point, 3))}) is not a corner of the solution's "
                    f"{self.what}; the nearest corner is ({fmt(np.round(nearest, 3))}) "
                    f"(corners: {listed})",
                    frozenset({"vertex"}),
                )
        if not _covers(points, int(a.get("mode", 7)), want, int(b.get("mode", 7))):
            return Finding(
                f"{self.what} does not cover the solution's: its corners are {listed}",
                frozenset({"vertex"}),
            )
        fit = _affine(want, want_tc)
        expected = np.array([fit(p) for p in points])
        if np.allclose(texcoords, expected, atol=1e-3):
            return None
        pattern = relation_2d(texcoords, expected)
        if pattern:
            return Finding(
                f"{self.what}'s texture coordinates are {pattern}", frozenset({"texcoord"})
            )
        for point, have, should in zip(points, texcoords, expected, strict=True):
            if not np.allclose(have, should, atol=1e-3):
                return Finding(
                    f"the texture coordinates ({fmt(np.round(have, 3))}) at the corner "
                    f"({fmt(np.round(point, 3))}) should be ({fmt(np.round(should, 3))}): "
                    f"{_affine_words(want, want_tc)}",
                    frozenset({"texcoord"}),
                )
        return None

    def copied(self, run: Run, points: np.ndarray) -> Finding | None:
        if not self.corners:
            return None
        mine = np.asarray(run.numbers.get(self.corners), dtype=np.float64)
        for name, numbers in run.others.items():
            theirs = np.asarray(numbers.get(self.corners), dtype=np.float64)
            if theirs.shape != mine.shape or np.allclose(theirs, mine):
                continue
            if all(np.min(np.linalg.norm(theirs - p, axis=1)) < 1e-3 for p in points):
                run.context.matched = run.context.matched or name
                listed = ", ".join(f"({fmt(c)})" for c in mine)
                return Finding(
                    f"this {self.what} is {another(name)}, not yours: yours has the corners "
                    f"{listed}",
                    final=True,
                )
        return None


def another(name: str) -> str:
    """Whose numbers a copied file carries, as its hint says it."""
    return (
        "for the lab's own numbers (the default variant)"
        if name == "default"
        else "for another student's variant (their numbers)"
    )


def _points(event: dict[str, Any], transform: np.ndarray) -> np.ndarray:
    found = []
    for vertex in event.get("vertices") or []:
        w = transform @ np.asarray(vertex[0], dtype=np.float64)
        found.append(w[:3] / w[3] if abs(w[3]) > 1e-12 else w[:3])
    return np.array(found)


def _unique(points: np.ndarray) -> np.ndarray:
    kept: list[np.ndarray] = []
    for p in points:
        if not any(np.allclose(p, k, atol=1e-6) for k in kept):
            kept.append(p)
    return np.array(kept)


def _plane(points: np.ndarray) -> tuple[np.ndarray, float]:
    centre = points.mean(0)
    _, _, vt = np.linalg.svd(points - centre)
    normal = vt[-1]
    return normal, float(centre @ normal)


def _axis_name(normal: np.ndarray) -> str:
    for i, axis in enumerate("xyz"):
        if abs(abs(normal[i]) - 1) < 1e-6:
            return axis
    return ""


def _triangles(mode: int, count: int) -> list[tuple[int, int, int]]:
    if mode == 7:
        return [t for i in range(0, count - 3, 4) for t in ((i, i + 1, i + 2), (i, i + 2, i + 3))]
    if mode in (9, 6):
        return [(0, i, i + 1) for i in range(1, count - 1)]
    if mode == 4:
        return [(i, i + 1, i + 2) for i in range(0, count - 2, 3)]
    if mode in (5, 8):
        return [(i, i + 1, i + 2) for i in range(count - 2)]
    return []


def _in_plane_2d(points: np.ndarray, basis: np.ndarray) -> np.ndarray:
    return (points - basis[0]) @ basis[1:].T


def _inside(point: np.ndarray, polygon: np.ndarray, mode: int) -> bool:
    basis = _basis(polygon)
    flat = _in_plane_2d(polygon, basis)
    q = _in_plane_2d(point[None], basis)[0]
    return any(
        _in_triangle(q, flat[a], flat[b], flat[c], 1e-3)
        for a, b, c in _triangles(mode, len(polygon))
    )


def _basis(points: np.ndarray) -> np.ndarray:
    centre = points.mean(0)
    _, _, vt = np.linalg.svd(points - centre)
    return np.array([centre, vt[0], vt[1]])


def _covers(points: np.ndarray, mode: int, polygon: np.ndarray, polygon_mode: int) -> bool:
    """Whether the student's primitive (``points`` drawn as ``mode``) covers the solution's
    ``polygon`` (sampled on a grid of its own triangles)."""
    basis = _basis(polygon)
    flat, mine = _in_plane_2d(polygon, basis), _in_plane_2d(points, basis)
    triangles = _triangles(mode, len(points))
    for a, b, c in _triangles(polygon_mode, len(polygon)):
        for u in np.linspace(0.05, 0.85, 8):
            for v in np.linspace(0.05, 0.9 - u, 6):
                q = flat[a] + u * (flat[b] - flat[a]) + v * (flat[c] - flat[a])
                if not any(
                    _in_triangle(q, mine[x], mine[y], mine[z], 1e-6) for x, y, z in triangles
                ):
                    return False
    return True


def _in_triangle(q: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray, eps: float) -> bool:
    def cross(o: np.ndarray, p: np.ndarray, r: np.ndarray) -> float:
        return float((p[0] - o[0]) * (r[1] - o[1]) - (p[1] - o[1]) * (r[0] - o[0]))

    d1, d2, d3 = cross(a, b, q), cross(b, c, q), cross(c, a, q)
    negative = d1 < -eps or d2 < -eps or d3 < -eps
    positive = d1 > eps or d2 > eps or d3 > eps
    return not (negative and positive)


def _affine(points: np.ndarray, values: np.ndarray) -> Callable[[np.ndarray], np.ndarray]:
    """The affine map of position to texture coordinates the solution's primitive follows."""
    design = np.hstack([points, np.ones((len(points), 1))])
    solution, *_ = np.linalg.lstsq(design, values, rcond=None)
    return lambda p: np.append(p, 1.0) @ solution


def _affine_words(points: np.ndarray, values: np.ndarray) -> str:
    """``s = (z + 6) / 8, t = (y + 3) / 8``: how the solution's texture coordinates follow
    the position, where each follows one axis."""
    moving = [axis for axis in range(3) if np.ptp(points[:, axis]) > 1e-9]
    design = np.hstack([points[:, moving], np.ones((len(points), 1))])
    fitted, *_ = np.linalg.lstsq(design, values, rcond=None)
    solution = np.zeros((4, values.shape[1]))
    solution[moving] = fitted[:-1]
    solution[3] = fitted[-1]
    words = []
    for column, name in enumerate("st"):
        coefficients = solution[:3, column]
        axis = int(np.argmax(np.abs(coefficients)))
        if np.sum(np.abs(coefficients) > 1e-6) != 1:
            return "they follow the position as the solution's do"
        scale = 1 / coefficients[axis]
        start = -solution[3, column] * scale
        shift = (
            f"({'xyz'[axis]} + {-start:g})"
            if start < 0
            else f"({'xyz'[axis]} - {start:g})"
            if start
            else "xyz"[axis]
        )
        words.append(f"{name} = {shift} / {scale:g}")
    return ", ".join(words)


@dataclass(frozen=True)
class SameSeen:
    """What the kit saw when the draw of ``events`` ran (its ``seen`` record: texgen modes
    and switches, the texture bound on its unit) is the solution's; ``labels`` words each
    key, a texture by its role."""

    events: Events
    labels: dict[str, str]

    def __call__(self, run: Run) -> Finding | None:
        pairs = _pairs(self.events, run)
        if isinstance(pairs, Finding):
            return pairs
        mine, theirs = pairs[-1]
        seen, want = mine.get("seen") or {}, theirs.get("seen") or {}
        for key, label in self.labels.items():
            have, should = seen.get(key), want.get(key)
            if key == "texture":
                have, should = run.role(have), run.role(should, run.reference)
            if have != should:
                unit = seen.get("unit", 0)
                return Finding(
                    f"{label} on texture unit {unit} is {_worded(have)} when {self.events.said()} "
                    f"at {run.at(mine.get('line', 0))} draws; the solution's is {_worded(should)}",
                    frozenset({"texgen", "enable", "binding", "unit"}),
                )
        return None


TEXGEN_NAMES = {
    0x2400: "GL_EYE_LINEAR",
    0x2401: "GL_OBJECT_LINEAR",
    0x2402: "GL_SPHERE_MAP",
    0x8511: "GL_NORMAL_MAP",
    0x8512: "GL_REFLECTION_MAP",
}


def _worded(value: Any) -> str:
    if value is True:
        return "on"
    if value is False:
        return "off"
    if isinstance(value, int) and value in TEXGEN_NAMES:
        return TEXGEN_NAMES[value]
    return str(value)


@dataclass(frozen=True)
class SameUnits:
    """At ``events`` (the last), every texture unit has the solution's ``switches`` on and
    off and its texgen modes (``texgen``): nothing switched on or set on a unit the solution
    leaves alone (a file that sets up every variant's unit fails here)."""

    events: Events
    what: str
    switches: tuple[str, ...] = ()
    texgen: tuple[str, ...] = ()

    def __call__(self, run: Run) -> Finding | None:
        mine, theirs = self.events.find(run.student), self.events.find(run.reference)
        if not mine or not theirs:
            return None
        a = (mine[-1].get("state") or {}).get("units") or {}
        b = (theirs[-1].get("state") or {}).get("units") or {}
        for unit in sorted({*a, *b}, key=int):
            for switch in self.switches:
                have, want = switch in (a.get(unit) or {}), switch in (b.get(unit) or {})
                if have != want:
                    line = ((a.get(unit) or {}).get(switch) or {}).get("line", 0)
                    by = f" (glEnable at {run.at(line)})" if line else ""
                    return Finding(
                        f"{switch} is {'on' if have else 'off'} on texture unit {unit}{by} "
                        f"{self.what}; the solution's is {'on' if want else 'off'} there",
                        frozenset({"enable"}),
                    )
            for coordinate in self.texgen:
                key = f"texgen_{coordinate}"
                have = ((a.get(unit) or {}).get(key) or {}).get("value", 0x2400)
                want = ((b.get(unit) or {}).get(key) or {}).get("value", 0x2400)
                if have != want:
                    line = ((a.get(unit) or {}).get(key) or {}).get("line", 0)
                    by = f" (glTexGen at {run.at(line)})" if line else " (GL's default)"
                    return Finding(
                        f"texgen for {coordinate} on texture unit {unit} is {_worded(have)}{by} "
                        f"{self.what}; the solution's is {_worded(want)}",
                        frozenset({"texgen"}),
                    )
        return None


@dataclass(frozen=True)
class SameDraws:
    """The kit's draws while ``within`` ran are the solution's: the same ones, as often, each
    in the same viewport (which half of the window, say)."""

    within: str
    who: tuple[str, ...]

    def __call__(self, run: Run) -> Finding | None:
        def draws(evidence: Evidence) -> list[dict[str, Any]]:
            return [
                e for e in evidence.events("draw", within=self.within) if e.get("who") in self.who
            ]

        mine, theirs = draws(run.student), draws(run.reference)
        for a, b in zip(mine, theirs, strict=False):
            if a.get("who") != b.get("who"):
                return Finding(
                    f"lab.{a.get('who')} at {run.at(a.get('line', 0))} draws in the viewport "
                    f"({fmt(a.get('viewport') or [])}), where the solution draws "
                    f"lab.{b.get('who')}",
                    frozenset({"viewport", "framebuffer"}),
                )
            if a.get("viewport") != b.get("viewport"):
                return Finding(
                    f"lab.{a.get('who')} at {run.at(a.get('line', 0))} draws in the viewport "
                    f"({fmt(a.get('viewport') or [])}); the solution draws it in "
                    f"({fmt(b.get('viewport') or [])})",
                    frozenset({"viewport"}),
                )
        if len(mine) > len(theirs):
            extra = mine[len(theirs)]
            return Finding(
                f"lab.{extra.get('who')} at {run.at(extra.get('line', 0))} draws once more than "
                "the "
                f"solution does (in the viewport ({fmt(extra.get('viewport') or [])}))",
                frozenset({"framebuffer"}),
            )
        if len(mine) < len(theirs):
            lost = theirs[len(mine)]
            return Finding(
                f"lab.{lost.get('who')} is not drawn in the viewport "
                f"({fmt(lost.get('viewport') or [])})",
                frozenset({"framebuffer"}),
            )
        return None


@dataclass(frozen=True)
class SameMipmaps:
    """The draw ``events`` samples ``texture`` (its ``sampling`` record) as the solution's
    does, or with a mipmap filter once mipmaps are made from this frame's pictures (what the
    handout allows)."""

    events: Events
    texture: str

    def __call__(self, run: Run) -> Finding | None:
        pairs = _pairs(self.events, run)
        if isinstance(pairs, Finding):
            return pairs
        mine, _ = pairs[-1]
        params = mine.get("sampling") or {}
        minify = (params.get(str(0x2801)) or {}).get("value")
        if minify not in MIPMAP_FILTERS:
            return None
        line = (params.get(str(0x2801)) or {}).get("line", 0)
        name = run.declared.roles.get(self.texture, self.texture)
        if not mine.get("mipmaps"):
            return Finding(
                f"{name}'s minifying filter is {FILTERS[minify]} ({run.at(line)}), which wants "
                f"mipmaps it does not have, so it shows black",
                frozenset({"texparam", "mipmaps"}),
            )
        if not mine.get("mipmaps_fresh"):
            made = (mine.get("mipmaps") or {}).get("line", 0)
            return Finding(
                f"the draw samples mipmaps made before this frame's pictures: glGenerateMipmap at "
                f"{run.at(made)} runs before the copies, so the mipmaps show an older picture",
                frozenset({"mipmaps"}),
            )
        return None


@dataclass(frozen=True)
class CopyOf:
    """A file made for another variant: what ``observe`` reads from the student's run
    equals what another variant's numbers make (``numbers(variant)[key]``) and not this
    variant's. ``words`` names it ({whose} and this variant's numbers ``{mine}``)."""

    observe: Callable[[Run], Any]
    key: str
    words: str

    def __call__(self, run: Run) -> Finding | None:
        seen = self.observe(run)
        if seen is None:
            return None
        mine = run.numbers.get(self.key)
        if _equal(seen, mine):
            return None
        for name, numbers in run.others.items():
            if _equal(seen, numbers.get(self.key)):
                run.context.matched = run.context.matched or name
                return Finding(self.words.format(whose=another(name), mine=_said(mine)), final=True)
        return None


@dataclass(frozen=True)
class OneVariant:
    """A file that sets up the state of several variants at once (``observe`` reads, as a
    set, what each variant's ``numbers[key]`` names one of: the texgen units, say): more than
    this variant's is a file shared between variants; the hint names the extra ones and the
    copy check the first other student they serve."""

    observe: Callable[[Run], set[Any]]
    key: str
    words: str

    def __call__(self, run: Run) -> Finding | None:
        seen = self.observe(run)
        mine = run.numbers.get(self.key)
        extra = seen - {mine}
        if not extra or mine not in seen:
            return None
        for name, numbers in run.others.items():
            if numbers.get(self.key) in extra:
                run.context.matched = run.context.matched or name
                break
        return Finding(
            self.words.format(extra=", ".join(map(str, sorted(extra))), mine=mine), final=True
        )


def _equal(a: Any, b: Any) -> bool:
    if a is None or b is None:
        return False
    try:
        x, y = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
        return bool(x.shape == y.shape and np.allclose(x, y, atol=1e-3))
    except (TypeError, ValueError):
        return a == b


def _said(value: Any) -> str:
    if isinstance(value, tuple | list | np.ndarray):
        return (
            "("
            + ", ".join(
                fmt([v]) if isinstance(v, int | float) else str(v)
                for v in np.asarray(value, dtype=object).reshape(-1)
            )
            + ")"
        )
    return str(value)


@dataclass(frozen=True)
class Glsl:
    """A GLSL task: ``check(student)`` gives (passed, hint) from the values the student's
    functions write (the value probe's; the lab's judge keeps it)."""

    check: Callable[[Evidence], tuple[bool, str]]

    def __call__(self, run: Run) -> Finding | None:
        passed, hint = self.check(run.student)
        return None if passed else Finding(hint, final=True)


@dataclass(frozen=True)
class Stopped:
    """'not judged' when an error in another function stopped the frame."""

    function: str

    def __call__(self, run: Run) -> Finding | None:
        hint = stopped_hint(run.student, self.function)
        return Finding(hint, final=True) if hint else None


# ------------------------------------------------------------------- the declaration
@dataclass(frozen=True)
class TaskRule:
    """One task as a lab's judge declares it: its ``id``, the student ``functions`` it judges
    (its hints look there first: never called, the calls' divergences), ``checks`` (all must
    hold), ``explain`` (checks read only for a failed task's hint), ``families`` (the calls
    of its functions it judges; None: all) and ``region`` (the frame's pixels it owns)."""

    id: str
    functions: tuple[str, ...]
    checks: tuple[Check, ...]
    explain: tuple[Check, ...] = ()
    families: frozenset[str] | None = None
    region: str | None = None
    after: tuple[str, ...] = ()
    """Tasks whose failure this one's is judged after ("judged once task N passes")."""
    after_first: bool = False
    """Say "judged once" before the divergences of its functions (they are the other
    task's to name)."""


@dataclass(frozen=True)
class LabJudge:
    """A lab's judge, declared: its tasks, the textures' and programs' names (``roles``:
    evidence key -> what the file calls it), the lab's numbers for a variant (``numbers``),
    the regions of the frame (``regions(run)``: name -> mask), which region's differences
    a task owns (``owner``) and the task the whole frame falls to (``frame_task``), the
    GLSL functions its shader tasks judge and the rows of its check picture."""

    lab: str
    tasks: tuple[TaskRule, ...]
    roles: dict[str, str]
    frame_task: str
    programs: dict[str, str] = field(default_factory=dict)
    uniforms: dict[str, str] = field(default_factory=dict)
    numbers: Callable[[Variant], dict[str, Any]] = lambda variant: {}
    regions: Callable[[Run], dict[str, np.ndarray | None]] = lambda run: {}
    owner: dict[str, tuple[str, str]] = field(default_factory=dict)
    glsl_functions: tuple[str, ...] = ()
    frame: Callable[[Run], tuple[Evidence, Evidence]] | None = None
    """The runs the whole frame is compared as (the cube-map lab blurs a mipmapped sphere)."""
    allowed: Callable[[Run], np.ndarray | None] = lambda run: None
    """The frame's pixels whose faint mark is a difference the handout accepts (a mask; lab
    20's GL_CLAMP rim around the mirror), not counted by the whole frame's rule."""


def judge(
    declared: LabJudge, spec: LabSpec, student: Evidence, reference: Evidence, context: Context
) -> list[TaskResult]:
    """Every task's verdict and hint (see the module's text)."""
    run = Run(
        spec,
        declared,
        student,
        reference,
        context,
        Hints(student, reference, declared.roles, spec.setup, declared.programs, declared.uniforms),
        declared.numbers(context.variant),
        {name: declared.numbers(v) for name, v in context.differing_others().items()},
    )
    findings: dict[str, Finding | None] = {}
    for rule in declared.tasks:
        found = next((f for check in rule.checks if (f := check(run)) is not None), None)
        findings[rule.id] = found
        run.passed[rule.id] = found is None
    verdicts: Verdicts = {}
    for rule in declared.tasks:
        found = findings[rule.id]
        verdicts[rule.id] = (True, "") if found is None else (False, hint(run, rule, found))
    regions = declared.regions(run)
    judged, against = declared.frame(run) if declared.frame is not None else (student, reference)
    verdicts = judge_frame(
        verdicts,
        judged,
        against,
        {**{r.id: regions.get(r.region) if r.region else None for r in declared.tasks}, **regions},
        declared.frame_task,
        declared.owner,
        declared.allowed(run),
    )
    frame_hint = verdicts.get(declared.frame_task, (True, ""))
    if not frame_hint[0] and findings.get(declared.frame_task) is None:
        # the whole frame differs and no task explains it: the first divergence of any
        # lab function names what made it so
        first = next((d for f in spec.functions for d in run.hints.divergences(f)), None)
        if first is not None:
            verdicts[declared.frame_task] = (False, f"{first.text}; {frame_hint[1]}")
    return [
        r if r.passed else TaskResult(r.task, False, run.hints.guard(r.hint))
        for r in results(spec, student, verdicts, declared.glsl_functions)
    ]


def hint(run: Run, rule: TaskRule, found: Finding) -> str:
    """A failed task's hint (see the module's text)."""
    if found.final:
        return found.hint
    for function in rule.functions:
        never = run.hints.never_called(function)
        if never:
            return never
    failed = [task for task in rule.after if not run.passed.get(task, True)]
    if failed and rule.after_first:
        return f"judged once {run.task_name(failed[0])} passes"
    divergences = [d for f in rule.functions for d in run.hints.divergences(f, rule.families)]
    slots = found.slots if found.about in (None, *rule.functions) else frozenset()
    chosen = next((d for d in divergences if d.slots & slots), None) or next(
        iter(divergences), None
    )
    if chosen is not None:
        same_line = chosen.student is not None and f"line {chosen.student.line} (" in found.hint
        said = (
            chosen.text
            if same_line or found.hint in chosen.text
            else f"{chosen.text}; {found.hint}"
        )
        return run.hints.guard(said)
    for task in rule.after:
        # its own functions make the solution's calls: the failure comes from that task
        if not run.passed.get(task, True):
            return f"judged once {run.task_name(task)} passes"
    for check in rule.explain:
        explained = check(run)
        if explained is not None:
            return run.hints.guard(explained.hint)
    return run.hints.guard(found.hint)


# ----------------------------------------------------------------------- regions
def polygon_region(
    corners: np.ndarray, clip: np.ndarray, size: tuple[int, int], grow: float = 2.0
) -> np.ndarray:
    """The pixels of a ``size`` (w, h) frame inside the convex polygon ``corners`` ``(n, 3)``
    seen through ``clip`` (projection @ view), ``grow`` pixels wider, ``(h, w)`` bool."""
    points = [clip @ np.append(c, 1.0) for c in corners]
    return triangles_mask(points, [(0, i, i + 1) for i in range(1, len(points) - 1)], size, grow)


def convex_rim(
    corners: np.ndarray, clip: np.ndarray, size: tuple[int, int], reach: float
) -> np.ndarray:
    """The pixels of a ``size`` (w, h) frame within ``reach`` pixels either side of the
    outline of the convex polygon ``corners`` ``(n, 3)`` seen through ``clip`` (projection
    @ view; every corner in front of the eye), ``(h, w)`` bool."""
    width, height = size
    points = [clip @ np.append(c, 1.0) for c in corners]
    if any(p[3] <= 1e-6 for p in points):
        return np.zeros((height, width), dtype=bool)
    screen = [((p[0] / p[3] + 1) / 2 * width, (1 - p[1] / p[3]) / 2 * height) for p in points]
    yy, xx = np.mgrid[0:height, 0:width] + 0.5
    area = sum(
        x0 * y1 - x1 * y0
        for (x0, y0), (x1, y1) in zip(screen, screen[1:] + screen[:1], strict=True)
    )
    sign = 1.0 if area > 0 else -1.0
    outer = np.ones((height, width), dtype=bool)
    inner = np.ones((height, width), dtype=bool)
    for (x0, y0), (x1, y1) in zip(screen, screen[1:] + screen[:1], strict=True):
        length = float(np.hypot(x1 - x0, y1 - y0))
        distance = sign * ((x1 - x0) * (yy - y0) - (y1 - y0) * (xx - x0))
        outer &= distance >= -reach * length
        inner &= distance >= reach * length
    return outer & ~inner


def drawn_region(draw: dict[str, Any], size: tuple[int, int]) -> np.ndarray:
    """The pixels a primitive the student drew covers (2 px wider), ``(h, w)`` bool."""
    projection, modelview = matrix(draw.get("projection")), matrix(draw.get("modelview"))
    if projection is None or modelview is None:
        return np.zeros((size[1], size[0]), dtype=bool)
    clip = [
        projection @ modelview @ np.asarray(v[0], dtype=np.float64)
        for v in draw.get("vertices") or []
    ]
    return triangles_mask(clip, _triangles(int(draw.get("mode", 0)), len(clip)), size)
