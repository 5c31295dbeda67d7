"""Many files of one lab checked by one warm checker (:mod:`mirrorlab.labs.trusted.warm`),
one after another, as ``lab check --watch`` checks a student's saves: one GL process, and
for each file a new runner in a new box, a new context and a new session, the reference
copied. That shares between two files what a grading worker's kept process shares (the
process), and no more; it saves each file a process's start-up. And :class:`Watch`: ``lab
check --watch`` itself, driven by saves and Ctrl-C."""

from __future__ import annotations

import os
import queue
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterable
from pathlib import Path
from typing import Any

from mirrorlab.labs import LabSpec, find_lab
from mirrorlab.labs.trusted.checker import CheckResult, report_lines
from mirrorlab.labs.trusted.evidence import Evidence
from mirrorlab.labs.trusted.sandbox import Limits
from mirrorlab.labs.trusted.variants import Variant
from mirrorlab.labs.trusted.warm import WarmChecker
from tests.labs.conftest import LIMITS, SOLUTIONS


def check_files(
    lab: str, paths: Iterable[Path], limits=LIMITS, solutions: Path | None = SOLUTIONS
) -> dict[str, CheckResult]:
    """Each file checked, by its stem (references made from ``solutions``)."""
    spec = find_lab(lab)
    found: dict[str, CheckResult] = {}
    with WarmChecker(spec, limits, solutions) as checker:
        for path in paths:
            check = checker.check(path)
            assert check is not None, path
            found[path.stem] = check
    return found


def check_folder(lab: str, folder: Path, limits=LIMITS) -> dict[str, list[tuple[str, bool, str]]]:
    """Each ``.py`` file of ``folder`` checked, as ``lab grade``'s rows: by stem, (task id,
    passed, hint) per task."""
    checks = check_files(lab, sorted(folder.glob("*.py")), limits)
    return {
        stem: [(r.task.id, r.passed, r.hint) for r in check.results]
        for stem, check in checks.items()
    }


class TracingChecker(WarmChecker):
    """A warm checker that keeps the evidence each file's check judged (by the file's
    bytes: a check may also run the lab's starter, to tell the checker's failures from the
    file's), for tests that read the calls a file executed."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.runs: dict[bytes, Evidence] = {}

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
        evidence = super()._run(spec, source, file_name, variant, limits, size, keep)
        self.runs[source] = evidence
        return evidence


def check_folder_with_calls(
    lab: str, folder: Path, limits=LIMITS
) -> dict[str, tuple[list[tuple[str, bool, str]], list[str]]]:
    """Each ``.py`` file of ``folder`` checked by one warm checker (references made from
    the solutions), by stem: its rows as :func:`check_folder` gives them, and the text of
    every call the file executed (as the call trace names it: :mod:`.trace_hints`)."""
    from mirrorlab.labs.trusted.trace_hints import Roles, Trace

    spec = find_lab(lab)
    declared = spec.module("judge").JUDGE
    found = {}
    checker = TracingChecker(spec, limits, SOLUTIONS)
    with checker:
        for path in sorted(folder.glob("*.py")):
            source = path.read_bytes()
            check = checker.check(path, source)
            assert check is not None, path
            evidence = checker.runs.pop(source)
            roles = Roles(evidence, declared.roles, declared.programs, declared.uniforms)
            made = [
                c.text for c in Trace(evidence, roles).calls if c.kind != "function" and not c.error
            ]
            found[path.stem] = ([(r.task.id, r.passed, r.hint) for r in check.results], made)
    return found


def report(lab: str, check: CheckResult) -> str:
    """The check as ``lab check`` prints it."""
    return "\n".join(report_lines(find_lab(lab), check))


GIVE_UP_S = 240.0
"""Only a hung watch stops a wait this long: every wait ends on what it waits for."""


class Watch:
    """``mirrorlab lab check lab20 FILE --watch`` in a process of its own (Ctrl-C reaches
    it as a terminal's would), its output read as it comes; ``command`` runs another
    mirrorlab (an installed one) with ``env``."""

    def __init__(
        self,
        folder: Path,
        name: str = "mine.py",
        command: tuple[str, ...] = (sys.executable, "-m", "mirrorlab.cli"),
        env: dict[str, str] | None = None,
    ) -> None:
        self.process = subprocess.Popen(
            [*command, "lab", "check", "lab20", *([name] if name else []), "--watch"],
            cwd=folder,
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
        )
        self.lines: queue.Queue[str] = queue.Queue()
        self.seen: list[str] = []
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self) -> None:
        assert self.process.stdout is not None
        for line in self.process.stdout:
            self.lines.put(line)

    def until(self, text: str) -> list[str]:
        """The lines up to the next one holding ``text``."""
        got: list[str] = []
        deadline = time.monotonic() + GIVE_UP_S
        while True:
            try:
                line = self.lines.get(timeout=min(max(deadline - time.monotonic(), 0.01), 1.0))
            except queue.Empty:
                ended = self.process.poll() is not None and not self.reader.is_alive()
                if ended or time.monotonic() >= deadline:
                    assert self.process.stderr is not None
                    errors = self.process.stderr.read() if ended else "(still running)"
                    raise AssertionError(
                        f"no {text!r} after {got}; exit {self.process.poll()}, stderr: {errors}"
                    ) from None
                continue
            got.append(line)
            self.seen.append(line)
            if text in line:
                return got

    def report(self) -> str:
        return "".join(self.until("checked at "))

    def checkers(self) -> list[int]:
        """The watch's checker processes (its children running the GL process)."""
        found = []
        for entry in Path("/proc").iterdir():
            if not entry.name.isdigit():
                continue
            try:
                status = (entry / "status").read_text()
                command = (entry / "cmdline").read_bytes()
            except OSError:
                continue
            parent = int(status.split("PPid:")[1].split()[0])
            if parent == self.process.pid and b"gl_process" in command:
                found.append(int(entry.name))
        return found

    def __enter__(self) -> Watch:
        return self

    def __exit__(self, *exc: object) -> None:
        if self.process.poll() is None:  # a failed test: the watch is stopped all the same
            self.process.send_signal(signal.SIGINT)
            try:
                self.process.communicate(timeout=GIVE_UP_S)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.communicate()

    def interrupt(self) -> tuple[int, str, str]:
        """Ctrl-C: (exit status, everything it printed, its stderr)."""
        self.process.send_signal(signal.SIGINT)
        self.process.wait(timeout=GIVE_UP_S)
        self.reader.join(timeout=GIVE_UP_S)
        while not self.lines.empty():
            self.seen.append(self.lines.get())
        assert self.process.stderr is not None
        return self.process.returncode, "".join(self.seen), self.process.stderr.read()


def save_by_rename(path: Path, text: str) -> None:
    """As vim and JetBrains editors save: a new file renamed over the old."""
    staging = path.with_name(f".{path.name}.swp")
    staging.write_text(text)
    os.replace(staging, path)
