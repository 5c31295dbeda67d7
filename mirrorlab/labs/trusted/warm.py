"""The warm checker: ``lab check --watch`` re-checks a file on every save in a fraction of
a cold check's time, and isolates each run as ``lab grade`` does.

What stays warm, and what is new for every run:

- The checker's GL process (:class:`WarmProcess`, a :class:`~.gl_process.CheckerProcess`
  started with ``--serve --prepare``) stays, with its imports and the lab's meshes and
  pictures read; as a grading worker's kept process does, it runs each job in a context of
  its own. After each job it prepares the next run (:class:`~.prepared.PreparedRun`): a
  new runner in the sandbox, in a new box (a new process, which has run nothing of any student's and
  waits for its session; the file comes with the session), then a new context, its
  target and the lab's session, all made before the next save. The run that used the
  last ones is over by then: its runner and every process of the sandbox's user are
  ended, its box removed and its context released, with every GL object in it.
- This process keeps the judge and the reference evidence (loaded once, a copy given to
  each check, so no check can change what the next is judged against).

Nothing of one run is reachable from the next: not its processes, not its box, not its
GL objects or state, not the Python objects it sent (the checker reads only the calls of
the run at hand). A save while a check runs makes a new check of the newest file: at
once when the running check has taken longer than :data:`CANCEL_AFTER` (the GL process is
stopped and started again, a cold start), else when it ends.
"""

from __future__ import annotations

import copy
import json
import os
import signal
import subprocess
import tempfile
import threading
import time
from pathlib import Path

from mirrorlab.labs import LabSpec
from mirrorlab.labs.trusted.checker import (
    CHECK_SIZE,
    CheckResult,
    check_submission,
    file_reference,
    file_variant,
)
from mirrorlab.labs.trusted.evidence import Evidence
from mirrorlab.labs.trusted.gl_process import CheckerProcess, run_job
from mirrorlab.labs.trusted.judging import Context
from mirrorlab.labs.trusted.sandbox import Limits, sandbox_uid, sweep_stale, uid_processes
from mirrorlab.labs.trusted.variants import Variant

CANCEL_AFTER = 1.0
"""Seconds after which a check that a new save makes stale is stopped rather than waited
for (an honest check takes a fraction of that; a file that loops would hold the next
check until its CPU limit)."""


class WarmProcess(CheckerProcess):
    """A checker process that prepares each next run while it waits. What it writes is
    dropped, as a check's own process's is: the report is the student's whole answer (a
    job's failure comes back in its folder)."""

    SERVE = ("--serve", "--prepare")
    STDERR = subprocess.DEVNULL

    def close(self, ask: bool = True) -> None:
        """End the process: asked to when ``ask`` (between jobs: it then releases its
        prepared run), else, or when it does not end in time, made to; then every
        process of the sandbox's user is ended and what the process left in the
        temporary folder removed."""
        stdin = self.process.stdin
        if ask and self.process.poll() is None and stdin is not None:
            try:
                stdin.close()
                self.process.wait(timeout=10)
            except (OSError, subprocess.TimeoutExpired):
                pass
        super().close()
        _end_sandbox_user()
        sweep_stale(Path(tempfile.gettempdir()))


class Cancelled(Exception):
    """A check stopped because a newer save made it stale (:meth:`WarmChecker.cancel`)."""


class WarmChecker:
    """Checks of one lab's files, one after another, with the GL process, the prepared
    run, the judge and the references kept warm (see the module's text). Use as a context
    manager; :meth:`check` from one thread, :meth:`cancel` from any."""

    def __init__(
        self,
        spec: LabSpec,
        limits: Limits,
        solutions: Path | None = None,
        size: tuple[int, int] = CHECK_SIZE,
    ) -> None:
        self.spec, self.limits, self.solutions, self.size = spec, limits, solutions, size
        self._references: dict[str, Evidence] = {}
        self._lock = threading.Lock()
        self._started: float | None = None
        self._cancelled = False
        self._busy = False
        """Whether the process may be in a job (a check left by an exception leaves it so)."""
        self.process: WarmProcess | None = WarmProcess()  # it loads while the judge does
        try:
            self.judge = spec.module("judge")
        except BaseException:
            self.close()
            raise

    def __enter__(self) -> WarmChecker:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def reference(self, variant: Variant, path: Path) -> Evidence:
        """A copy of the reference evidence the file ``path`` of ``variant`` is judged
        against (:func:`~.checker.file_reference`: loaded or made once)."""
        key = json.dumps([variant.plain(), str(path.parent.resolve())], sort_keys=True)
        if key not in self._references:
            self._references[key] = file_reference(
                self.spec, variant, self.solutions, self.limits, path, self.size
            )
        return copy.deepcopy(self._references[key])

    def check(self, path: Path, source: bytes | None = None) -> CheckResult | None:
        """Check the file ``path`` (its content ``source`` when read already) as ``lab
        check`` does; None when :meth:`cancel` stopped it."""
        source = path.read_bytes() if source is None else source
        variant = file_variant(self.spec, path)
        reference = self.reference(variant, path)
        with self._lock:
            if self.process is None or not self.process.alive():
                if self.process is not None:
                    self.process.close()
                self.process = WarmProcess()
            self._started, self._cancelled, self._busy = time.monotonic(), False, True
        try:
            result = check_submission(
                self.spec,
                source,
                reference,
                Context(variant),
                str(path),
                path.name,
                self.limits,
                self.size,
                keep=True,
                run=self._run,
            )
            self._busy = False
        except Cancelled:
            self._busy = False
            return None
        finally:
            with self._lock:
                self._started = None
        return result

    def _run(
        self,
        spec: LabSpec,
        source: bytes,
        file_name: str,
        variant: Variant,
        limits: Limits,
        size: tuple[int, int],
        keep: bool,
    ) -> Evidence:
        """:func:`~.gl_process.run_job` in the warm process (``keep``; the checker's own
        failures are run again in a process of their own, :mod:`.failures`); Cancelled
        when :meth:`cancel` stopped it."""
        if self._cancelled:
            raise Cancelled
        try:
            return run_job(
                spec,
                source,
                file_name,
                variant,
                limits,
                size,
                process=self.process if keep else None,
            )
        except Exception:
            # cancel() ends the GL process from another thread, closing its pipes while
            # this one may be waiting on them: whatever that raises here (CheckerError,
            # or OSError/ValueError from a closed descriptor) is the cancellation
            if self._cancelled:
                raise Cancelled from None
            raise

    def cancel(self, after: float = CANCEL_AFTER) -> bool:
        """Stop the check in progress if it has run ``after`` seconds or more (its GL
        process is ended; the next check starts another); whether it was stopped."""
        with self._lock:
            if self._started is None or time.monotonic() - self._started < after:
                return False
            self._cancelled = True
            if self.process is not None:
                self.process.close(ask=False)
            return True

    def close(self) -> None:
        """End the GL process (asked to, when it is between jobs: see
        :meth:`WarmProcess.close`)."""
        with self._lock:
            process, self.process = self.process, None
        if process is not None:
            process.close(ask=not self._busy)


def _end_sandbox_user() -> None:
    """Run as root, the sandbox runs as a user of its own (:func:`~.sandbox.sandbox_uid`
    of this process): end every process of that user, as the end of each run does, when
    the GL process that would have done so was ended instead."""
    if not (hasattr(os, "geteuid") and os.geteuid() == 0):
        return
    for _ in range(100):
        pids = uid_processes(sandbox_uid())
        if not pids:
            return
        for pid in pids:
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:
                pass
        time.sleep(0.01)


__all__ = [
    "CANCEL_AFTER",
    "WarmChecker",
    "WarmProcess",
]
