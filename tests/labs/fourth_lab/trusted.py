"""The quad lab's trusted side: a session that draws nothing of its own, no kit calls
beyond the shared ones, nothing observed beyond the frame, every call of the allow-list
offered and every channel from a file's numbers to the frame open (the tests draw every
way the fixed pipeline can through it)."""

from __future__ import annotations

from typing import Any

from mirrorlab.labs.trusted.session import LabBase


class QuadLab(LabBase):
    name = "quad"


SESSION = QuadLab


def left_out() -> dict[str, str]:
    return {}


def channels() -> tuple[str, ...]:
    from mirrorlab.labs.trusted.calls import CHANNELS

    return tuple(CHANNELS)


def kit_calls() -> dict[str, Any]:
    return {}


def observe(run: Any) -> None:
    """The frame is all the judge needs."""
