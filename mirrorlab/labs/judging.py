"""What every lab's judge shares: task results, errors mapped to tasks, image comparisons
and the student | reference | difference picture. Numpy only; reads what a harness run
wrote, never the student's code."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from mirrorlab.labs import LabSpec, Task


@dataclass(frozen=True)
class TaskResult:
    """One task's verdict: ``hint`` names the likely mistake when it failed (and may say
    something useful when it passed)."""

    task: Task
    passed: bool
    hint: str = ""


@dataclass
class Evidence:
    """A run as the judges see it: ``run`` (run.json: errors, calls, state) and
    ``arrays`` (observations.npz), for the student and for the reference solution."""

    run: dict[str, Any]
    arrays: dict[str, np.ndarray]

    @property
    def state(self) -> dict[str, Any]:
        state = self.run.get("state")
        return state if isinstance(state, dict) else {}

    @property
    def errors(self) -> list[dict[str, Any]]:
        errors = self.run.get("errors")
        return [e for e in errors if isinstance(e, dict)] if isinstance(errors, list) else []

    @property
    def calls(self) -> list[str]:
        calls = self.run.get("calls")
        return [c for c in calls if isinstance(c, str)] if isinstance(calls, list) else []

    def image(self, name: str, shape: tuple[int, ...] | None = None) -> np.ndarray | None:
        """The uint8 picture ``name``, or None when missing or not ``(h, w, 3)`` (or
        ``shape``)."""
        value = self.arrays.get(name)
        if not isinstance(value, np.ndarray) or value.dtype != np.uint8 or value.ndim != 3 \
                or value.shape[-1] != 3:
            return None
        if shape is not None and value.shape != shape:
            return None
        return value

    def matrix(self, name: str) -> np.ndarray | None:
        value = self.arrays.get(name)
        if not isinstance(value, np.ndarray) or value.shape != (4, 4) \
                or not np.all(np.isfinite(value)):
            return None
        return value.astype(np.float64)

    def floats(self, name: str, shape: tuple[int, ...]) -> np.ndarray | None:
        value = self.arrays.get(name)
        if not isinstance(value, np.ndarray) or value.shape != shape \
                or value.dtype.kind != "f":
            return None
        return value.astype(np.float64)

    def last_frame_calls(self) -> list[str]:
        """The calls of the last frame the run drew (after its last ``frame N`` mark)."""
        calls = self.calls
        marks = [i for i, c in enumerate(calls) if c.startswith("frame ")]
        return calls[marks[-1] + 1:] if marks else []

    def stopped_by(self) -> str:
        """The function whose error stopped the last frame, or ''."""
        for call in self.last_frame_calls():
            if call.startswith("raise "):
                return call.split(" ", 1)[1]
        return ""

    def stopped_hint(self, judged: str) -> str:
        """"not judged: ..." when an error in a function other than ``judged`` (the one
        under judgement) stopped the last frame, else ''."""
        stopped = self.stopped_by()
        return f"not judged: the frame stopped at {stopped}()" if stopped and \
            stopped != judged else ""

    def displayed_frames(self, reference: Evidence
                         ) -> tuple[tuple[np.ndarray, np.ndarray] | None, str]:
        """This run's last frame and ``reference``'s (each (H, W, 3) uint8, one size) for
        judging display(), with ''; or None with why they cannot be judged: an error outside
        display() stopped the frame, or display() drew none."""
        if hint := self.stopped_hint("display"):
            return None, hint
        frame, ref = self.image("frame"), reference.image("frame")
        if frame is None or ref is None or frame.shape != ref.shape:
            return None, "display() drew no frame"
        return (frame, ref), ""

    def frame_events(self) -> list[dict[str, Any]]:
        events = self.state.get("frame_events")
        return [e for e in events if isinstance(e, dict)] if isinstance(events, list) else []


def error_line(error: dict[str, Any]) -> str:
    """An error as the student should read it: where in their file, then what."""
    line = f"line {error['line']}" if error.get("line") else ""
    code = str(error.get("code") or "")
    where = f"{line}: {code}" if line and code else line
    return f"{where} -> {error.get('message', '')}" if where else str(error.get("message", ""))


def errors_for(evidence: Evidence, spec: LabSpec, task: Task,
               glsl_functions: tuple[str, ...] = ()) -> str:
    """The error message that makes ``task`` fail, if any: its own function's error, a
    GLSL error for a shader task, or an error that stopped the whole file."""
    for error in evidence.errors:
        function = error.get("function")
        kind = error.get("kind")
        if function in ("<file>",):
            return f"the file did not run: {error_line(error)}"
        if kind == "glsl" and task.function in glsl_functions:
            return error_line(error)
        if function == task.function and kind != "glsl":
            what = {"missing": "", "exception": f"{function}() raised at "}.get(str(kind), "")
            return f"{what}{error_line(error)}"
    return ""


def share_within(a: np.ndarray, b: np.ndarray, tolerance: int,
                 mask: np.ndarray | None = None) -> float:
    """The share of pixels (in ``mask``) whose every channel of ``a`` and ``b`` (uint8 or
    0-255 floats) is within ``tolerance``."""
    diff = np.abs(np.asarray(a, dtype=np.float64) - np.asarray(b, dtype=np.float64)).max(-1)
    if mask is not None:
        diff = diff[mask]
    return float(np.mean(diff <= tolerance)) if diff.size else 0.0


def difference_picture(student: np.ndarray, reference: np.ndarray) -> np.ndarray:
    """``|student - reference|`` amplified four times, ``(h, w, 3)`` uint8."""
    diff = np.abs(student.astype(np.int16) - reference.astype(np.int16)) * 4
    return np.clip(diff, 0, 255).astype(np.uint8)


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


def picture(rows: list[tuple[np.ndarray | None, np.ndarray | None]],
            size: tuple[int, int]) -> np.ndarray:
    """Rows of student | reference | difference, each cell ``size`` (h, w), separated by
    4 px, under a line of titles."""
    from PIL import Image, ImageDraw

    h, w = size
    gap = 4
    out = np.full((HEADER + len(rows) * (h + gap) - gap, 3 * w + 2 * gap, 3), 255,
                  dtype=np.uint8)
    titles = Image.fromarray(out[:HEADER])
    draw = ImageDraw.Draw(titles)
    for j, title in enumerate(("student", "reference", "difference x4")):
        draw.text((j * (w + gap) + 4, 2), title, fill=(40, 40, 40))
    out[:HEADER] = np.asarray(titles)
    for i, (student, reference) in enumerate(rows):
        ok_s = student is not None and student.shape == (h, w, 3)
        ok_r = reference is not None and reference.shape == (h, w, 3)
        cells = [student if ok_s else blank((h, w)), reference if ok_r else blank((h, w)),
                 difference_picture(student, reference) if ok_s and ok_r  # type: ignore[arg-type]
                 else blank((h, w))]
        for j, cell in enumerate(cells):
            y, x = HEADER + i * (h + gap), j * (w + gap)
            out[y:y + h, x:x + w] = cell
    return out


Judge = Callable[[LabSpec, Evidence, Evidence], list[TaskResult]]


def results_with_errors(spec: LabSpec, student: Evidence,
                        verdicts: dict[str, tuple[bool, str]],
                        glsl_functions: tuple[str, ...] = ()) -> list[TaskResult]:
    """Task results from ``verdicts`` (task id -> (passed, hint)), with an error of the
    task's function taking over its verdict and hint."""
    results = []
    for task in spec.tasks:
        passed, hint = verdicts.get(task.id, (False, "not checked"))
        error = errors_for(student, spec, task, glsl_functions)
        if error:
            passed, hint = False, error
        results.append(TaskResult(task, passed, hint))
    return results
