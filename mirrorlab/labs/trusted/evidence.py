"""What one run of a lab file showed, as the trusted side observed it, and nothing else.

Everything in an :class:`Evidence` was made by the trusted process: the calls it executed
(per frame, in order, each with the student's line and the lab function running), the
state at every draw and copy, the textures' contents and where they came from, the
pictures it read back, its own checks of the student's GLSL. The runner's own reports are
the errors the student's code raised (a claim that can only cost the student marks).
Saved as ``evidence.json`` and ``arrays.npz`` (no pickles) for the reference runs' cache
and the shipped reference data.
"""

from __future__ import annotations

import json
import zipfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

MAX_JSON = 16 << 20
MAX_ARRAYS = 64 << 20
MAX_UNPACKED = 256 << 20
"""Evidence files may come from a student's folder (a released reference): their sizes,
packed and unpacked, are checked before they are read."""


@dataclass
class Evidence:
    """One run: ``status`` (``ok``, ``timeout``, ``memory``, ``processes``, ``crashed``,
    ``stopped``) and ``detail`` (one line when not ok), the student's ``errors``, the
    executor's refused calls (``call_errors``), the events of each frame (``frames``)
    and of the set-up (``setup``), the ``textures``, the lab's own observations
    (``state``), the pictures (``arrays``) and the file's ``source``."""

    lab: str
    status: str = "ok"
    detail: str = ""
    errors: list[dict[str, Any]] = field(default_factory=list)
    call_errors: list[dict[str, Any]] = field(default_factory=list)
    frames: list[dict[str, Any]] = field(default_factory=list)
    setup: list[dict[str, Any]] = field(default_factory=list)
    textures: dict[str, dict[str, Any]] = field(default_factory=dict)
    state: dict[str, Any] = field(default_factory=dict)
    arrays: dict[str, np.ndarray] = field(default_factory=dict)
    variant: dict[str, Any] = field(default_factory=dict)
    source: str = ""

    # ---------------------------------------------------------------- reading
    def image(self, name: str, shape: tuple[int, ...] | None = None) -> np.ndarray | None:
        """The uint8 picture ``name``, or None when missing or not ``(h, w, 3)`` (or
        ``shape``)."""
        value = self.arrays.get(name)
        if (
            not isinstance(value, np.ndarray)
            or value.dtype != np.uint8
            or value.ndim != 3
            or value.shape[-1] != 3
        ):
            return None
        if shape is not None and value.shape != shape:
            return None
        return value

    def floats(self, name: str, shape: tuple[int, ...]) -> np.ndarray | None:
        value = self.arrays.get(name)
        if not isinstance(value, np.ndarray) or value.shape != shape or value.dtype.kind != "f":
            return None
        return value.astype(np.float64)

    def line_text(self, line: int) -> str:
        """Line ``line`` of the student's file, stripped ('' when there is none)."""
        lines = self.source.splitlines()
        return lines[line - 1].strip()[:200] if 0 < line <= len(lines) else ""

    def at(self, line: int) -> str:
        """ "line N (code)" for a hint, or '' for line 0."""
        if not line:
            return ""
        code = self.line_text(line)
        return f"line {line} ({code})" if code else f"line {line}"

    @property
    def last_frame(self) -> list[dict[str, Any]]:
        return self.frames[-1]["events"] if self.frames else []

    def events(
        self, kind: str, frame: int | None = -1, who: str | None = None, within: str | None = None
    ) -> list[dict[str, Any]]:
        """Events of ``kind`` in frame ``frame`` (-1: the last; None: the set-up), drawn by
        ``who``, while lab function ``within`` ran."""
        source = (
            self.setup if frame is None else (self.frames[frame]["events"] if self.frames else [])
        )
        return [
            e
            for e in source
            if e.get("kind") == kind
            and (who is None or e.get("who") == who)
            and (within is None or within in (e.get("steps") or []))
        ]

    def called(self, function: str, frame: int | None = -1) -> bool:
        """Whether lab function ``function`` ran in frame ``frame`` (None: any time)."""
        if frame is None:
            return any(
                e.get("kind") == "enter" and e.get("function") == function
                for e in [*self.setup, *(x for f in self.frames for x in f["events"])]
            )
        return any(
            e.get("kind") == "enter" and e.get("function") == function
            for e in (self.frames[frame]["events"] if self.frames else [])
        )

    def raised_in(self, frame: int = -1) -> str:
        """The function whose error stopped frame ``frame`` (the innermost), or ''."""
        for event in self.frames[frame]["events"] if self.frames else []:
            if event.get("kind") == "leave" and event.get("raised"):
                return str(event.get("function", ""))
        return ""

    def texture(self, name: int | None) -> dict[str, Any] | None:
        return self.textures.get(str(name)) if name else None

    # ---------------------------------------------------------------- files
    def save(self, folder: Path, compress: bool = True) -> None:
        """``folder/evidence.json`` and ``folder/arrays.npz`` (zip-compressed, or not when
        it is read back at once)."""
        folder.mkdir(parents=True, exist_ok=True)
        plain = {
            key: getattr(self, key)
            for key in (
                "lab",
                "status",
                "detail",
                "errors",
                "call_errors",
                "textures",
                "state",
                "variant",
                "source",
            )
        }
        # events that share a state snapshot (the state did not change between them)
        # refer to one copy of it in "states"
        states: list[dict[str, Any]] = []
        index: dict[int, int] = {}

        def packed(events: list[dict[str, Any]]) -> list[dict[str, Any]]:
            out = []
            for event in events:
                state = event.get("state")
                if isinstance(state, dict):
                    if id(state) not in index:
                        index[id(state)] = len(states)
                        states.append(state)
                    event = {**event, "state": {"$state": index[id(state)]}}
                out.append(event)
            return out

        plain["setup"] = packed(self.setup)
        plain["frames"] = [
            {**frame, "events": packed(frame.get("events", []))} for frame in self.frames
        ]
        plain["states"] = states
        with open(folder / "evidence.json", "w") as stream:  # streamed, never whole
            json.dump(plain, stream, default=_json_value)
        if compress:
            np.savez_compressed(folder / "arrays.npz", **self.arrays)  # type: ignore[arg-type]
        else:
            np.savez(folder / "arrays.npz", **self.arrays)  # type: ignore[arg-type]

    @classmethod
    def load(cls, folder: Path) -> Evidence:
        """The evidence saved in ``folder`` (as data: no pickles, sizes bounded);
        ValueError when it is missing or malformed."""
        folder = Path(folder)
        text_path, arrays_path = folder / "evidence.json", folder / "arrays.npz"
        for path, limit in ((text_path, MAX_JSON), (arrays_path, MAX_ARRAYS)):
            if not path.is_file() or path.stat().st_size > limit:
                raise ValueError(f"no readable {path.name} in {folder}")
        try:
            with zipfile.ZipFile(arrays_path) as archive:
                unpacked = sum(member.file_size for member in archive.infolist())
            if unpacked > MAX_UNPACKED:
                raise ValueError(f"its arrays unpack to {unpacked >> 20} MiB")
            plain = json.loads(text_path.read_text())
            with np.load(arrays_path, allow_pickle=False) as data:
                arrays = {key: data[key] for key in data.files}
        except (OSError, ValueError, UnicodeDecodeError, zipfile.BadZipFile) as exc:
            raise ValueError(f"unreadable evidence in {folder}: {exc}") from None
        if not isinstance(plain, dict) or not isinstance(plain.get("lab"), str):
            raise ValueError(f"unreadable evidence in {folder}")
        evidence = cls(plain["lab"], arrays=arrays)
        for key in (
            "status",
            "detail",
            "errors",
            "call_errors",
            "frames",
            "setup",
            "textures",
            "state",
            "variant",
            "source",
        ):
            if key in plain and isinstance(plain[key], type(getattr(evidence, key))):
                setattr(evidence, key, plain[key])
        states = plain.get("states")
        states = states if isinstance(states, list) else []
        for events in [
            evidence.setup,
            *(f.get("events") for f in evidence.frames if isinstance(f, dict)),
        ]:
            for event in events if isinstance(events, list) else []:
                ref = event.get("state") if isinstance(event, dict) else None
                if isinstance(ref, dict) and set(ref) == {"$state"}:
                    i = ref["$state"]
                    event["state"] = states[i] if type(i) is int and 0 <= i < len(states) else {}
        return evidence


def _json_value(value: Any) -> Any:
    """What JSON cannot write as it is (numpy arrays and numbers, tuples) as what it can."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, tuple):
        return list(value)
    raise TypeError(f"cannot write {type(value).__name__} to evidence.json")
