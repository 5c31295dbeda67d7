"""What every lab's judge shares: task results, the student's errors mapped to tasks, the
whole-frame comparison, and the student | reference | difference picture. Numpy only;
it reads :class:`~.evidence.Evidence`, which only the trusted process made."""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from mirrorlab.labs import LabSpec, Task
from mirrorlab.labs.trusted.evidence import Evidence
from mirrorlab.labs.trusted.variants import Variant

TOLERANCE = 24
"""Whole-picture comparisons: a pixel differs when one of its channels is more than this
many levels (of 255) from every pixel in the other picture's 3 x 3 neighbourhood, both
ways (so an edge a driver puts half a pixel over passes, and a thin line drawn or missing
does not)."""
ALLOWED_SHARE = 0.0005
"""A picture passes with at most this share of its pixels differing (32 of 256 x 256)."""
ALLOWED_MIN = 16
OVERLAY_LEVELS = 6
"""The whole frame, at every scale and orientation. A pixel's *residual* is how far its
channels lie outside the range of the reference's 5 x 5 neighbourhood around it
(:data:`OVERLAY_REACH`): above (the most any channel is above the neighbourhood's
largest) and below, 0 within it, so an edge or a detail drawn up to 2 pixels over, or
blurred that far, has none. Any window of
:data:`WINDOWS`, anywhere in the frame, whose mean residual above (or below) is at least
this many levels marks its pixels with a residual of that kind: they count as differing
pixels. So a mark a person can read is caught however faint per pixel, however thin or
sparse: a patch offset by 6 levels, a line of 6 along a row, column or diagonal (12 at
other angles), hatching on every other column at 12, dots on every other pixel of every
other row at 24; while no change of under 6 levels anywhere (rounding, another driver's
noise, a uniform offset) ever is."""
WINDOWS = tuple(("square", n) for n in (2, 4, 8, 16, 32)) + tuple(
    (kind, n) for kind in ("row", "column", "diagonal", "antidiagonal") for n in (4, 8, 16, 32)
)
"""The windows :data:`OVERLAY_LEVELS` is judged over: squares of 2 to 32 pixels a side and
strips 4 to 32 pixels long along rows, columns and both diagonals."""


@dataclass(frozen=True)
class TaskResult:
    """One task's verdict: ``hint`` says what to fix when it failed (and may say something
    useful when it passed)."""

    task: Task
    passed: bool
    hint: str = ""


@dataclass
class Context:
    """What a judge knows besides the two runs: the student's ``variant`` and the other
    variants of the class (``others``, by student), whose numbers a copied file carries."""

    variant: Variant
    others: dict[str, Variant] = field(default_factory=dict)
    matched: str = ""
    """Set by a judge: the student (or ``default``) whose variant's numbers the file
    carries instead of its own, for the teacher's report."""

    def differing_others(self) -> dict[str, Variant]:
        return {name: v for name, v in self.others.items() if not v.same_numbers(self.variant)}


Verdicts = dict[str, tuple[bool, str]]


GL_ERROR_NAMES = {
    1280: "GL_INVALID_ENUM",
    1281: "GL_INVALID_VALUE",
    1282: "GL_INVALID_OPERATION",
    1283: "GL_STACK_OVERFLOW",
    1284: "GL_STACK_UNDERFLOW",
    1285: "GL_OUT_OF_MEMORY",
}
GL_ERROR = re.compile(
    r"GLError: GLError\(err = (\d+), description = (['\"])(.*?)(?:\2|$)"
    r"(?:, baseOperation = (\w*))?"
)


def plain_message(message: str) -> str:
    """A student's error as a person reads it: PyOpenGL's ``GLError(err = 1282, ...)``
    becomes the call and what it broke (the checker names the precondition where it can),
    with GL's name for the error."""
    found = GL_ERROR.search(message)
    if not found:
        return message
    code, description, call = int(found.group(1)), found.group(3), found.group(4)
    detail = re.fullmatch(r"[a-z ]+ \((.*?)\)?", description)
    text = detail.group(1) if detail else f"{call or 'a call'}: {description}"
    return f"{text} ({GL_ERROR_NAMES.get(code, f'GL error {code}')})"


def error_line(error: dict[str, Any]) -> str:
    """An error as the student should read it: where in their file, then what."""
    line = f"line {error['line']}" if error.get("line") else ""
    code = str(error.get("code") or "")
    where = f"{line}: {code}" if line and code else line
    message = plain_message(str(error.get("message", "")))
    return f"{where} -> {message}" if where else message


INTEGER_HALF = re.compile(r"(?<![\w.])1\s*/\s*2(?![\w.])")
"""``1/2`` in GLSL: integer division, 0."""


def glsl_body(source: str, function: str) -> str:
    """The body of GLSL ``function`` as the student's file spells it (the first definition
    found, its comments left out), '' when there is none: for naming a slip whose numbers
    another slip gives too."""
    found = re.search(r"\b\w+\s+" + re.escape(function) + r"\s*\([^)]*\)\s*\{", source)
    if not found:
        return ""
    depth, start = 1, found.end()
    for i in range(start, min(len(source), start + 8000)):
        depth += {"{": 1, "}": -1}.get(source[i], 0)
        if depth == 0:
            return re.sub(r"//[^\n]*|/\*.*?\*/", " ", source[start:i], flags=re.S)
    return ""


def errors_for(evidence: Evidence, task: Task, glsl_functions: tuple[str, ...] = ()) -> str:
    """The error that makes ``task`` fail, if any: its own function's error, a GLSL error
    for a shader task, or an error that stopped the whole file."""
    for error in evidence.errors:
        function, kind = error.get("function"), error.get("kind")
        if function == "<file>":
            return f"the file did not run: {error_line(error)}"
        if kind == "glsl" and task.function in glsl_functions:
            return error_line(error)
        if function == task.function and kind != "glsl":
            what = {"missing": "", "exception": f"{function}() raised at "}.get(str(kind), "")
            return f"{what}{error_line(error)}"
    return ""


def stopped_hint(evidence: Evidence, judged: str) -> str:
    """ "not judged: ..." when an error in a function other than ``judged`` stopped the
    last frame, else ''."""
    stopped = evidence.raised_in()
    return f"not judged: the frame stopped at {stopped}()" if stopped and stopped != judged else ""


def results(
    spec: LabSpec, student: Evidence, verdicts: Verdicts, glsl_functions: tuple[str, ...] = ()
) -> list[TaskResult]:
    """Task results from ``verdicts`` (task id -> (passed, hint)): a run that did not end
    well fails every task with its one line; an error of a task's function takes over its
    verdict; a failed task whose function never finished in a frame that an error stopped
    elsewhere is "not judged" (its evidence is missing, so any other hint would guess)."""
    if student.status != "ok":
        return [TaskResult(task, False, student.detail) for task in spec.tasks]
    found = []
    stopped = student.raised_in()
    for task in spec.tasks:
        passed, hint = verdicts.get(task.id, (False, "not checked"))
        error = errors_for(student, task, glsl_functions)
        if error:
            passed, hint = False, error
        elif (
            not passed
            and stopped
            and stopped != task.function
            and task.function in spec.functions
            and task.function not in spec.setup
            and not finished(student, task.function)
        ):
            hint = (
                f"not judged: the frame stopped at {stopped}() before {task.function}() "
                f"finished; fix that error first"
            )
        elif not passed and stopped and stopped == task.function:
            own = next((e for e in student.errors if e.get("function") == stopped), None)
            if own is not None:
                hint = f"not judged: {stopped}() stopped at {error_line(own)}"
        found.append(TaskResult(task, passed, hint))
    return found


def finished(student: Evidence, function: str) -> bool:
    """Whether ``function`` ran to its end in the last frame."""
    return any(
        e.get("kind") == "leave" and e.get("function") == function and not e.get("raised")
        for e in student.last_frame
    )


# ------------------------------------------------------------------------ pictures
def share_within(
    a: np.ndarray, b: np.ndarray, tolerance: int, mask: np.ndarray | None = None
) -> float:
    """The share of pixels (in ``mask``) whose every channel of ``a`` and ``b`` (uint8 or
    0-255 floats) is within ``tolerance``."""
    diff = np.abs(np.asarray(a, dtype=np.float64) - np.asarray(b, dtype=np.float64)).max(-1)
    if mask is not None:
        diff = diff[mask]
    return float(np.mean(diff <= tolerance)) if diff.size else 0.0


def _nearest(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """For each pixel of ``a``, the smallest largest-channel difference to a pixel of ``b``
    in its 3 x 3 neighbourhood, ``(h, w)``."""
    height, width = a.shape[:2]
    # channels first: numpy reduces a short last axis an element at a time, about ten
    # times slower than these whole-plane maxima
    planes = np.ascontiguousarray(np.moveaxis(a, -1, 0), dtype=np.int16)
    padded = np.pad(
        np.ascontiguousarray(np.moveaxis(b, -1, 0), dtype=np.int16),
        ((0, 0), (1, 1), (1, 1)),
        mode="edge",
    )
    best = np.full((height, width), 255, dtype=np.int16)
    difference = np.empty(planes.shape, dtype=np.int16)
    for dy in range(3):
        for dx in range(3):
            np.subtract(planes, padded[:, dy : dy + height, dx : dx + width], out=difference)
            np.abs(difference, out=difference)
            np.minimum(best, difference.max(axis=0), out=best)
    return best


def differing(student: np.ndarray, reference: np.ndarray, tolerance: int = TOLERANCE) -> np.ndarray:
    """The pixels where ``student`` and ``reference`` (``(h, w, 3)`` uint8, one size)
    differ (see :data:`TOLERANCE`), ``(h, w)`` bool."""
    return (_nearest(student, reference) > tolerance) | (_nearest(reference, student) > tolerance)


def _spread(image: np.ndarray, pick: Any) -> np.ndarray:
    """Per channel, ``pick`` (np.maximum or np.minimum) of each pixel's 3 x 3
    neighbourhood of ``image`` (``(h, w, c)`` int16)."""
    height, width = image.shape[:2]
    padded = np.pad(image, ((1, 1), (1, 1), (0, 0)), mode="edge")
    out = image.copy()
    for dy in range(3):
        for dx in range(3):
            out = pick(out, padded[dy : dy + height, dx : dx + width])
    return out


OVERLAY_REACH = 2
"""How far (pixels) around a pixel the reference's range is taken for its residual: an
edge or a detail drawn up to this far over, or blurred over this far (another GPU's
filtering, a mipmap level more), makes none."""


def residual(picture: np.ndarray, other: np.ndarray, reach: int = OVERLAY_REACH) -> np.ndarray:
    """How far each channel of ``picture`` lies outside the range of ``other``'s
    neighbourhood ``reach`` pixels around it (``(h, w, 3)`` uint8 each), ``(h, w, 3)``
    int16: positive above the largest, negative below the smallest, 0 within."""
    a, b = picture.astype(np.int16), other.astype(np.int16)
    largest, smallest = b, b
    for _ in range(reach):
        largest, smallest = _spread(largest, np.maximum), _spread(smallest, np.minimum)
    above = np.maximum(a - largest, 0)
    below = np.maximum(smallest - a, 0)
    return (above - below).astype(np.int16)


def _shifted(values: np.ndarray, dy: int, dx: int) -> np.ndarray:
    """``values`` moved so that entry (y, x) holds values[y + dy, x + dx] (zeros past the
    edges; ``dy`` and ``dx`` may be negative)."""
    out = np.zeros_like(values)
    height, width = values.shape[:2]
    if abs(dy) >= height or abs(dx) >= width:
        return out
    source_y, target_y = (
        (slice(dy, height), slice(0, height - dy)) if dy >= 0 else (slice(0, dy), slice(-dy, None))
    )
    source_x, target_x = (
        (slice(dx, width), slice(0, width - dx)) if dx >= 0 else (slice(0, dx), slice(-dx, None))
    )
    out[target_y, target_x] = values[source_y, source_x]
    return out


DIRECTIONS = {"row": (0, 1), "column": (1, 0), "diagonal": (1, 1), "antidiagonal": (1, -1)}


def _steps(kind: str, n: int) -> list[tuple[int, int]]:
    """The doubling steps that sum a window of ``kind`` and size ``n`` (a power of two)
    from its first pixel: each adds the sum so far moved by (dy, dx)."""
    steps: list[tuple[int, int]] = []
    size = 1
    while size < n:
        if kind == "square":
            steps += [(0, size), (size, 0)]
        else:
            dy, dx = DIRECTIONS[kind]
            steps.append((dy * size, dx * size))
        size *= 2
    return steps


def _marked(offset: np.ndarray, levels: float) -> np.ndarray:
    """The pixels of ``offset`` (``(h, w)``, >= 0) lying in a window of :data:`WINDOWS`
    whose mean is at least ``levels``, where the offset itself is not 0, ``(h, w)`` bool."""
    marks = np.zeros(offset.shape, dtype=bool)
    if offset.max(initial=0) < levels:
        return marks  # no window's mean reaches what no pixel does
    for kind in ("square", *DIRECTIONS):
        total = offset.astype(np.int32)
        done: list[tuple[int, int]] = []
        for n in sorted(n for k, n in WINDOWS if k == kind):
            for step in _steps(kind, n)[len(done) :]:
                total = total + _shifted(total, *step)
                done.append(step)
            flagged = total >= levels * (n * n if kind == "square" else n)
            if flagged.any():
                for dy, dx in reversed(done):  # each window's flag over its pixels
                    flagged = flagged | _shifted(flagged, -dy, -dx)
                marks |= flagged
    return marks & (offset > 0)


def overlay_marks(
    student: np.ndarray, reference: np.ndarray, levels: float = OVERLAY_LEVELS
) -> np.ndarray:
    """The pixels of a mark on ``student`` against ``reference`` (``(h, w, 3)`` uint8),
    at every scale and orientation of :data:`WINDOWS` (see :data:`OVERLAY_LEVELS`; the
    residual above and the residual below, each its largest over the channels),
    ``(h, w)`` bool."""
    values = residual(student, reference)
    above = np.maximum(values, 0).max(axis=-1)
    below = np.maximum(-values, 0).max(axis=-1)
    return _marked(above, levels) | _marked(below, levels)


COLOUR_FORMATS = frozenset(
    {3, 4, 0x1907, 0x1908, 0x8051, 0x8058, 0x8054, 0x805B, 0x881B, 0x881A, 0x8815, 0x8814}
)
"""Internal formats that keep a picture's red, green and blue as they are (GL_RGB,
GL_RGBA, 3, 4 and their 8-, 16-bit and float sizes)."""
FORMAT_NAMES = {
    1: "1 (one channel)",
    2: "2 (two channels)",
    0x1902: "GL_DEPTH_COMPONENT",
    0x81A5: "GL_DEPTH_COMPONENT16",
    0x81A6: "GL_DEPTH_COMPONENT24",
    0x1906: "GL_ALPHA",
    0x1903: "GL_RED",
    0x8229: "GL_R8",
    0x822B: "GL_RG8",
    0x1909: "GL_LUMINANCE",
    0x8040: "GL_LUMINANCE8",
    0x190A: "GL_LUMINANCE_ALPHA",
    0x8C41: "GL_SRGB8",
    0x8C43: "GL_SRGB8_ALPHA8",
}


def copy_format_slip(copy: dict[str, Any]) -> str:
    """What a ``copy`` event's internal format does to the picture when it is not one of
    :data:`COLOUR_FORMATS`, '' when it keeps the colours."""
    found = copy.get("internalformat")
    if not isinstance(found, int) or found in COLOUR_FORMATS or found == 0:
        return ""
    name = FORMAT_NAMES.get(found, f"{found:#x}")
    if "DEPTH" in name:
        what = "a depth texture: it copies the depth buffer, not the picture"
    elif "SRGB" in name:
        what = "an sRGB texture: the picture reads back darker"
    else:
        what = "a texture of fewer channels than the picture's red, green and blue"
    return f"copies as {name}, {what}; copy as GL_RGB"


def allowed_pixels(shape: tuple[int, ...]) -> int:
    return max(ALLOWED_MIN, int(ALLOWED_SHARE * shape[0] * shape[1]))


def triangles_mask(
    clip: list[np.ndarray],
    triangles: list[tuple[int, int, int]],
    size: tuple[int, int],
    grow: float = 2.0,
) -> np.ndarray:
    """The pixels of a ``size`` (w, h) frame covered by ``triangles`` of points in clip
    coordinates (``(4,)`` each; points behind the eye are left out), ``grow`` pixels
    wider, ``(h, w)`` bool."""
    width, height = size
    mask = np.zeros((height, width), dtype=bool)
    yy, xx = np.mgrid[0:height, 0:width] + 0.5
    screen: list[tuple[float, float] | None] = []
    for point in clip:
        if point[3] <= 1e-6:
            screen.append(None)
            continue
        ndc = point[:2] / point[3]
        screen.append(((ndc[0] + 1) / 2 * width, (1 - ndc[1]) / 2 * height))
    for a, b, c in triangles:
        found = [screen[i] for i in (a, b, c)]
        corners = [p for p in found if p is not None]
        if len(corners) < 3:
            continue
        inside = np.ones_like(mask)
        area = (corners[1][0] - corners[0][0]) * (corners[2][1] - corners[0][1]) - (
            corners[1][1] - corners[0][1]
        ) * (corners[2][0] - corners[0][0])
        if abs(area) < 1e-9:
            continue
        sign = 1.0 if area > 0 else -1.0
        for (x0, y0), (x1, y1) in zip(corners, corners[1:] + corners[:1], strict=True):
            inside &= sign * ((x1 - x0) * (yy - y0) - (y1 - y0) * (xx - x0)) >= -grow * np.hypot(
                x1 - x0, y1 - y0
            )
        mask |= inside
    return mask


def where(mask: np.ndarray) -> str:
    """Where the true pixels of ``mask`` lie, for a person: the box holding most of them,
    in pixels from the picture's top-left corner."""
    ys, xs = np.nonzero(mask)
    if not len(xs):
        return "nowhere"
    x0, x1 = (int(v) for v in np.percentile(xs, (5, 95)))
    y0, y1 = (int(v) for v in np.percentile(ys, (5, 95)))
    return f"most of them between x {x0}-{x1} and y {y0}-{y1} from the top left"


def same_picture(student: np.ndarray | None, reference: np.ndarray | None) -> bool:
    """Whether two pictures agree as a whole (see :data:`TOLERANCE`)."""
    if student is None or reference is None or student.shape != reference.shape:
        return False
    return int(differing(student, reference).sum()) <= allowed_pixels(student.shape)


def judge_frame(
    verdicts: Verdicts,
    student: Evidence,
    reference: Evidence,
    regions: dict[str, np.ndarray | None],
    frame_task: str,
    owner: dict[str, tuple[str, str]],
    allowed: np.ndarray | None = None,
) -> Verdicts:
    """The final frame compared with the reference frame as a whole, after the per-task
    verdicts: pixels that differ beyond :data:`TOLERANCE` and the pixels of a faint mark
    (:func:`overlay_marks`) both count. A frame that differs in more pixels than allowed
    must be explained by a failed task whose region (``regions[task]``, a mask; None for
    the whole frame) holds the differing pixels; otherwise the task that owns
    them (``owner``: a region's name -> (task id, what it is)) fails saying where, or
    ``frame_task`` fails with the count. ``allowed``: pixels whose faint mark is a
    difference the handout accepts (a mask), not counted."""
    frame, ref = student.image("frame"), reference.image("frame")
    if frame is None or ref is None or frame.shape != ref.shape:
        return verdicts
    verdicts = dict(verdicts)
    marks = overlay_marks(frame, ref)
    if allowed is not None and allowed.shape == marks.shape:
        marks &= ~allowed
    mask = differing(frame, ref) | marks
    limit = allowed_pixels(frame.shape)
    if int(mask.sum()) <= limit:
        return verdicts
    explained = np.zeros_like(mask)
    frame_failed = False
    for task, (passed, _) in verdicts.items():
        if not passed:
            region = regions.get(task)
            if region is None and task == frame_task:
                frame_failed = True  # its own finding: an overlay is still named
            elif region is None:
                return verdicts
            else:
                explained |= region
    left = mask & ~explained
    count = int(left.sum())
    if count <= limit:
        return verdicts
    if frame_failed:
        faint = int((left & marks).sum())
        if faint * 2 >= count:
            verdicts[frame_task] = (
                False,
                f"{verdicts[frame_task][1]}; and {faint} of the frame's pixels are a faint "
                f"mark over it: an overlay? (see the picture), {where(left & marks)}",
            )
        return verdicts
    for name, (task, what) in owner.items():
        region = regions.get(name)
        if (
            region is not None
            and verdicts.get(task, (False, ""))[0]
            and int((left & region).sum()) * 2 >= count
        ):
            verdicts[task] = (
                False,
                f"{what} differs from the reference in "
                f"{int((left & region).sum())} pixels, "
                f"{where(left & region)} (see the picture)",
            )
            return verdicts
    passed, hint = verdicts.get(frame_task, (True, ""))
    faint = int((left & marks).sum())
    what = (
        f" ({faint} of them by a faint mark over the frame: an overlay?)"
        if faint * 2 >= count
        else ""
    )
    message = (
        f"the frame differs from the reference in {count} pixels{what} (see the "
        f"picture), {where(left)}"
    )
    verdicts[frame_task] = (False, f"{hint}; {message}" if not passed and hint else message)
    return verdicts


def difference_picture(
    student: np.ndarray, reference: np.ndarray, marked: bool = False
) -> np.ndarray:
    """``|student - reference|`` amplified four times, ``(h, w, 3)`` uint8; with ``marked``
    the pixels that differ as a whole-picture comparison counts them (beyond the tolerance,
    or in a faint mark) are red."""
    diff = np.abs(student.astype(np.int16) - reference.astype(np.int16)) * 4
    out = np.clip(diff, 0, 255).astype(np.uint8)
    if marked:
        out[differing(student, reference) | overlay_marks(student, reference)] = (255, 0, 0)
    return out


def blank(shape: tuple[int, int]) -> np.ndarray:
    """A grey 'nothing here' picture of ``shape`` (h, w) with a dark cross."""
    image = np.full((*shape, 3), 96, dtype=np.uint8)
    h, w = shape
    for i in range(min(h, w)):
        image[int(i * h / min(h, w)), int(i * w / min(h, w))] = 40
        image[int(i * h / min(h, w)), w - 1 - int(i * w / min(h, w))] = 40
    return image


HEADER = 16
"""Pixels above the picture's cells for their titles."""


def picture(
    rows: list[tuple[np.ndarray | None, np.ndarray | None]], size: tuple[int, int]
) -> np.ndarray:
    """Rows of student | reference | difference, each cell ``size`` (h, w), separated by
    4 px, under a line of titles; in the first row (the frame) the differing pixels are
    red."""
    from PIL import Image, ImageDraw

    h, w = size
    gap = 4
    out = np.full((HEADER + len(rows) * (h + gap) - gap, 3 * w + 2 * gap, 3), 255, dtype=np.uint8)
    titles = Image.fromarray(out[:HEADER])
    draw = ImageDraw.Draw(titles)
    for j, title in enumerate(("student", "reference", "difference x4 (red: differs)")):
        draw.text((j * (w + gap) + 4, 2), title, fill=(40, 40, 40))
    out[:HEADER] = np.asarray(titles)
    for i, (student, reference) in enumerate(rows):
        ok_s = student is not None and student.shape == (h, w, 3)
        ok_r = reference is not None and reference.shape == (h, w, 3)
        cells = [
            student if ok_s else blank((h, w)),
            reference if ok_r else blank((h, w)),
            difference_picture(student, reference, marked=i == 0)  # type: ignore[arg-type]
            if ok_s and ok_r
            else blank((h, w)),
        ]
        for j, cell in enumerate(cells):
            y, x = HEADER + i * (h + gap), j * (w + gap)
            out[y : y + h, x : x + w] = cell  # type: ignore[assignment]
    return out


# ---------------------------------------------------------------- the calls, for hints
def fmt(values: Any) -> str:
    """Numbers as a person writes them: ``-6, 2, -3``."""
    return ", ".join(
        f"{v:g}" for v in np.round(np.asarray(values, dtype=np.float64), 3).reshape(-1) + 0.0
    )


def wrong_clear_colour(
    clear: dict[str, Any], background: tuple[float, ...], student: Evidence
) -> str:
    """'(r, g, b) (glClearColor at line N)' when a ``clear`` event cleared to another colour
    than ``background``, else ''."""
    color = clear.get("color", {})
    value = color.get("value", (0, 0, 0, 1))
    if np.allclose(value[:3], background, atol=0.02):
        return ""
    line = color.get("line", 0)
    return f"({fmt(value[:3])})" + (f" (glClearColor at {student.at(line)})" if line else "")


def matrix(values: Any) -> np.ndarray | None:
    array = np.asarray(values, dtype=np.float64) if values is not None else None
    if array is None or array.shape != (4, 4) or not np.all(np.isfinite(array)):
        return None
    return array


def matrix_ops(event: dict[str, Any], mode: int) -> list[dict[str, Any]]:
    ops = (event.get("state") or {}).get("matrix_ops", {}).get(str(mode))
    return [o for o in ops if isinstance(o, dict)] if isinstance(ops, list) else []


MATRIX_NAMES = {0x1700: "GL_MODELVIEW", 0x1701: "GL_PROJECTION", 0x1702: "GL_TEXTURE"}


def misplaced_calls(student: Evidence, within: str, wanted: dict[str, int]) -> str:
    """A hint when, in the last frame's ``within``, a call that belongs on one matrix
    (``wanted``: call name -> matrix mode) was applied to another."""
    for event in student.events("matrix", within=within):
        target, mode = wanted.get(event["op"]), int(event.get("mode") or 0)
        if target is not None and target != mode:
            set_by = event.get("mode_line", 0)
            since = f", set at line {set_by}" if set_by else ""
            return (
                f"{event['op']} at {student.at(event['line'])} was applied to the "
                f"{MATRIX_NAMES.get(mode, '?')[3:].lower()} matrix (the matrix mode was "
                f"{MATRIX_NAMES.get(mode, '?')}{since}): call "
                f"glMatrixMode({MATRIX_NAMES[target]}) before it"
            )
    return ""


def stacked_ops(event: dict[str, Any], student: Evidence, mode: int, first: str) -> str:
    """A hint when, at ``event``, the ``mode`` matrix was not started afresh before the
    call ``first`` (it multiplied onto what an earlier call left)."""
    ops = matrix_ops(event, mode)
    starts = (
        "glLoadIdentity",
        "glLoadMatrixf",
        "glLoadMatrixd",
        "glLoadTransposeMatrixf",
        "glLoadTransposeMatrixd",
    )
    names = [o["op"] for o in ops]
    if first not in names:
        return ""
    before = ops[: names.index(first)]
    if any(o["op"] in starts for o in before):
        return ""
    if before:
        earlier = before[0]
        what = (
            "the viewer's matrix (lab.set_viewer)"
            if earlier["op"] == "lab.set_viewer"
            else f"{earlier['op']} at line {earlier['line']}"
        )
        return (
            f"{first} at {student.at(ops[names.index(first)]['line'])} multiplied onto "
            f"{what}: call glLoadIdentity() before it"
        )
    return ""


def viewer_camera(
    student: Evidence,
    draw: dict[str, Any],
    lab: Any,
    aspect: float | None = None,
    what: str = "the scene",
) -> tuple[bool, str]:
    """A hint when ``draw`` (the camera pass's) was not drawn with the viewer's matrices
    and over the whole frame (or the part ``aspect`` says)."""
    state = draw.get("state") or {}
    viewport = draw.get("viewport") or [0, 0, 0, 0]
    frame = student.image("frame")
    size = (frame.shape[1], frame.shape[0]) if frame is not None else (256, 256)
    if aspect is None and viewport != [0, 0, size[0], size[1]]:
        line = (state.get("viewport") or {}).get("line", 0)
        by = f" (glViewport at {student.at(line)})" if line else ""
        return False, (
            f"{what} is drawn in glViewport({fmt(viewport)}){by}; the frame is "
            f"{size[0]} x {size[1]}: glViewport(0, 0, WIDTH, HEIGHT)"
        )
    projection, modelview = matrix(draw.get("projection")), matrix(draw.get("modelview"))
    want_p, want_v = lab.viewer_for(size, aspect)
    if projection is None or modelview is None:
        return False, "the camera pass's matrices could not be read"
    if not np.allclose(projection @ modelview, want_p @ want_v, atol=1e-4):
        call = "lab.set_viewer()" if aspect is None else "lab.set_viewer(aspect)"
        if np.allclose(modelview, want_v, atol=1e-4) and projection[3, 2] != 0:
            shown, wanted = (p[1, 1] / p[0, 0] for p in (projection, want_p))
            fovy, want_fovy = (
                float(np.degrees(2 * np.arctan(1 / p[1, 1]))) for p in (projection, want_p)
            )
            if abs(shown - wanted) > 1e-3:
                return False, (
                    f"{what} is drawn with a projection of aspect {shown:.2f}; "
                    f"this view needs {wanted:.2f}: {call} with it"
                )
            if abs(fovy - want_fovy) > 0.05:
                return False, (
                    f"{what} is drawn with a field of view of {fovy:.0f} degrees; "
                    f"the viewer's is {want_fovy:.0f}: {call}"
                )
        return False, (
            f"{what} is not drawn from the viewer: its projection and camera are "
            f"not {call}'s (set it just before drawing)"
        )
    return True, ""
