"""The name a lab's starter imports: ``from mirrorlab.labs import kit``.

A lab's file runs under ``mirrorlab lab run`` or ``mirrorlab lab check``, in the sandbox,
where this name is the student side's stand-in (:mod:`mirrorlab.labs.student.kit_standin`),
whose ``kit.lab20()`` returns the lab's object. Anywhere else (``python starter.py``) there is
no lab session, and these say so in one line.
"""

from __future__ import annotations

from typing import Any


class LabSetupError(RuntimeError):
    """No lab session is open; one line."""


class StudentShaderError(LabSetupError):
    """The student's GLSL did not compile (raised in the sandbox)."""


ENV_UNIT = 1
"""The texture unit the labs keep their environment texture on."""


def _no_session() -> LabSetupError:
    return LabSetupError(
        "no lab session is open: run this file with 'mirrorlab lab run LAB "
        "FILE' or check it with 'mirrorlab lab check LAB FILE'"
    )


def __getattr__(name: str) -> Any:
    """``kit.<lab>()`` for every registered lab (:func:`mirrorlab.labs.lab_names`)."""
    from mirrorlab.labs import lab_names

    if name not in lab_names():
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

    def open_lab() -> Any:
        raise _no_session()

    open_lab.__name__ = name
    return open_lab
