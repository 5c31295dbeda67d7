"""The quad lab's object in the sandbox (``kit.quad()``): the frame's size alone."""

from __future__ import annotations

from mirrorlab.labs.student.kit_standin import StudentLab


class QuadLab(StudentLab):
    """The frame's ``width`` and ``height``; the lab gives no drawing of its own."""


LAB_OBJECT = QuadLab
