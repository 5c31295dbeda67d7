"""A fourth lab, defined here in the test folder alone: clear the frame to the variant's
colour and draw one quad. Importing this package registers it, as a shipped lab's package
does; tests/labs/test_new_lab.py finds it in ``lab start``, ``check``, ``release`` and
``grade``."""

from __future__ import annotations

from pathlib import Path

from mirrorlab.labs import LabSpec, Task, register

HOME = Path(__file__).resolve().parent

SPEC = register(
    LabSpec(
        name="quad",
        folder="lab_quad",
        title="The quad lab: a cleared frame and one quad",
        setup=(),
        frame="display",
        functions=("clear_background", "draw_quad", "display"),
        tasks=(
            Task(1, "clear", "clear_background", "the frame cleared to your colour"),
            Task(2, "quad", "draw_quad", "the quad drawn at its corners"),
        ),
        package=__name__,
        home=HOME,
        solution=HOME / "solution.py",
        options={"red": (0.1, 0.3, 0.5, 0.7)},
        defaults={"red": 0.3},
    )
)
