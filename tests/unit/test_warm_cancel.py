"""A stale check stopped by :meth:`WarmChecker.cancel`: ``cancel`` ends the GL process
from the watch's monitor thread, closing the pipes the check thread may be reading at that
moment, so whatever the check thread then raises is the stop, not the watch's error."""

from __future__ import annotations

import threading
from typing import Any

import pytest

from mirrorlab.labs.trusted import warm
from mirrorlab.labs.trusted.gl_process import CheckerError


def checker_without_a_process() -> warm.WarmChecker:
    """A warm checker's state as its check thread sees it, with no GL process started."""
    checker = object.__new__(warm.WarmChecker)
    checker._lock = threading.Lock()
    checker._cancelled = False
    checker.process = None
    return checker


RUN: tuple[Any, ...] = (None, b"", "mine.py", None, None, (8, 8), True)
"""``_run``'s arguments: none is read before the faked ``run_job``."""

ERRORS = [
    CheckerError("the checker's OpenGL process died (signal 9)"),
    OSError(9, "Bad file descriptor"),  # the reply pipe closed under a read
    ValueError("I/O operation on closed file"),
]


@pytest.mark.parametrize("error", ERRORS, ids=lambda e: type(e).__name__)
def test_after_a_cancel_any_error_of_the_run_is_the_cancellation(monkeypatch, error):
    checker = checker_without_a_process()

    def run_job(*args, **kwargs):
        checker._cancelled = True  # cancel() from the monitor thread, mid-run
        raise error

    monkeypatch.setattr(warm, "run_job", run_job)
    with pytest.raises(warm.Cancelled):
        checker._run(*RUN)


@pytest.mark.parametrize("error", ERRORS, ids=lambda e: type(e).__name__)
def test_without_a_cancel_the_runs_error_is_its_own(monkeypatch, error):
    def run_job(*args, **kwargs):
        raise error

    monkeypatch.setattr(warm, "run_job", run_job)
    with pytest.raises(type(error)):
        checker_without_a_process()._run(*RUN)
