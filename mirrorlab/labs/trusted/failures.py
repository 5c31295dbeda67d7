"""Whose failure it is: a grade is never made from the checker's own.

The trusted checker's OpenGL process can fail while it runs a file. The failure is the
file's when the file's calls make it fail (they crash the driver, they exhaust the
checker's memory); it is the checker's or the machine's otherwise (no OpenGL, a full disk,
a process killed from outside, a bug of mirrorlab's). The file is never asked: the
trusted side tells them apart by what it sees itself (:func:`run_attributed`):

- failures the checker reports before any of the file's calls or after all of them
  (:class:`~mirrorlab.errors.GLContextError`: no OpenGL context; :class:`.MachineError`:
  the check's files cannot be written; :class:`.SandboxError`) are the machine's, at once;
- a process that dies or raises while it runs the file's calls is run again, in a fresh
  process: a second run that passes is the verdict (the first failure was not the file's);
- when it fails again, a control runs the same way, in a fresh process: the untouched
  starter of the same lab and variant (package data; nothing of the student's). When the
  control fails too, the checker fails here whatever the file: CheckerError (not graded).
  When the control runs, the checker works and this file's calls make it fail: the file
  is judged, every task failing with one line that says so.

So a file can make itself fail, never make itself "not graded"; and a machine that fails
every run grades nobody.
"""

from __future__ import annotations

from collections.abc import Callable

from mirrorlab.labs import LabSpec
from mirrorlab.labs.trusted.evidence import Evidence
from mirrorlab.labs.trusted.gl_process import CheckerError, MachineError, run_job
from mirrorlab.labs.trusted.sandbox import Limits
from mirrorlab.labs.trusted.variants import Variant

Runner = Callable[[LabSpec, bytes, str, Variant, Limits, tuple[int, int], bool], Evidence]


def control_source(spec: LabSpec, variant: Variant) -> bytes:
    """The control file: the lab's untouched starter with ``variant``'s numbers."""
    from mirrorlab.labs.content import starter

    return starter(spec, variant).encode()


def run_attributed(
    spec: LabSpec,
    source: bytes,
    file_name: str,
    variant: Variant,
    limits: Limits,
    size: tuple[int, int],
    keep: bool = False,
    run: Runner = run_job,
) -> Evidence:
    """``run`` (:func:`~.gl_process.run_job`) of the file, its checker's failures told
    apart from its own (see the module's text): the evidence to judge, or the machine's
    failure raised (GLContextError, MachineError, SandboxError, or CheckerError when the
    control fails too)."""
    try:
        return run(spec, source, file_name, variant, limits, size, keep)
    except MachineError:
        raise
    except CheckerError:
        pass
    try:  # again, in a process of its own
        return run(spec, source, file_name, variant, limits, size, False)
    except MachineError:
        raise
    except CheckerError as again:
        failure = str(again)
    try:
        run(spec, control_source(spec, variant), "starter.py", variant, limits, size, False)
    except CheckerError as control:
        raise CheckerError(
            f"{failure}; the lab's untouched starter failed there too ({control}): the "
            f"checker itself fails on this machine"
        ) from None
    return Evidence(
        spec.name,
        "crashed",
        f"the file's calls made the checker's OpenGL process fail, twice ({failure}), "
        f"while the lab's untouched starter runs there",
        variant=variant.plain(),
    )
