"""Watching a student's file for saves: ``lab check --watch`` and ``lab run --watch``.

A save is seen by looking at the file's status every :data:`POLL_SECONDS` (:class:`FileWatch`):
its inode, size and modification and change times, by path. That needs no library and
no service of the system, works the same on every operating system and file system
(network and container folders included, where change notifications are often
missing), and costs a ``stat`` call 40 times a second. Looking by path follows the
editors that save by writing a new file and renaming it over the old one (vim, JetBrains,
VS Code's "atomic" saves), and those that remove the file first: while the path is
missing, the watch waits for it. A change counts once the status has held still for one
look, so a file written in two steps is read whole; what a half-written read gave would
be checked again at once, since the status moved after it.
"""

from __future__ import annotations

import os
import signal
import sys
import threading
import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from datetime import datetime
from pathlib import Path

from mirrorlab.labs import LabSpec
from mirrorlab.labs.trusted.checker import CheckError, file_report
from mirrorlab.labs.trusted.gl_process import CheckerError
from mirrorlab.labs.trusted.sandbox import Limits
from mirrorlab.labs.trusted.warm import WarmChecker

POLL_SECONDS = 0.025
"""How often a watched file's status is looked at."""

Signature = tuple[int, int, int, int, int]


class FileWatch:
    """The saves of the file ``path`` (see the module's text)."""

    def __init__(self, path: Path, poll: float = POLL_SECONDS) -> None:
        self.path, self.poll = path, poll

    def signature(self) -> Signature | None:
        """The file's status now (device, inode, size, modification and change times in
        ns), None while it is missing."""
        try:
            status = os.stat(self.path)
        except OSError:
            return None
        return (
            status.st_dev,
            status.st_ino,
            status.st_size,
            status.st_mtime_ns,
            status.st_ctime_ns,
        )

    def settled(self) -> Signature:
        """The file's status once the file is there and its status has held still for
        one look."""
        last = self.signature()
        while True:
            time.sleep(self.poll)
            now = self.signature()
            if now is not None and now == last:
                return now
            last = now

    def changed_from(self, seen: Signature | None) -> Signature | None:
        """Wait until the file's status differs from ``seen``: None when that is because
        the file is gone, else its status once it holds still."""
        while True:
            now = self.signature()
            if now != seen:
                return None if now is None else self.settled()
            time.sleep(self.poll)


def _read(path: Path) -> bytes | None:
    try:
        return path.read_bytes()
    except OSError:
        return None


def watch_check(
    spec: LabSpec,
    path: Path,
    out: Path,
    limits: Limits,
    solutions: Path | None = None,
) -> int:
    """``mirrorlab lab check --watch``: check ``path`` now and again after every save with
    the warm checker (:mod:`.warm`), printing each report as ``lab check`` does and writing
    its picture to ``out``; until Ctrl-C, which ends it with status 0 and nothing left
    behind. A save during a check has the newest file checked next (the stale report is
    not printed). A bad ``variant.json`` or a failed run of the checker is one line, and
    the watch goes on."""
    from mirrorlab.files import write_png_atomic

    watch = FileWatch(path)
    stop = threading.Event()
    checking: list[Signature | None] = [None]
    print(f"watching {path}: each save is checked (Ctrl-C to stop)", flush=True)
    terminate = _terminate_as_interrupt()
    checker = WarmChecker(spec, limits, solutions)

    def cancel_stale() -> None:  # a check made stale by a save, when it runs long
        while not stop.wait(watch.poll):
            current = checking[0]
            if current is not None and watch.signature() not in (current, None):
                checker.cancel()

    monitor = threading.Thread(target=cancel_stale, name="mirrorlab-watch", daemon=True)
    monitor.start()
    try:
        reported: bytes | None = None
        missing = False
        seen = watch.signature()
        while True:
            source = _read(path) if seen is not None else None
            if source is None:
                if not missing:
                    print(f"{path} is gone; waiting for it to come back", flush=True)
                missing = True
                seen = watch.changed_from(None)
                continue
            missing = False
            if source != reported:
                checking[0] = seen
                started = time.perf_counter()
                try:
                    check = checker.check(path, source)
                except (ValueError, CheckError, CheckerError) as exc:
                    print(f"mirrorlab lab check: error: {exc}", file=sys.stderr, flush=True)
                    check, reported = None, source
                finally:
                    checking[0] = None
                if check is not None and watch.signature() == seen:
                    seconds = time.perf_counter() - started
                    print("\n".join(file_report(spec, path, check)))
                    write_png_atomic(out, check.picture)
                    print(f"picture (student | reference | difference): {out}")
                    stamp = datetime.now().strftime("%H:%M:%S")
                    print(
                        f"checked at {stamp} in {seconds:.2f} s; watching for the next save "
                        f"(Ctrl-C to stop)",
                        flush=True,
                    )
                    reported = source
                elif reported != source:  # saved meanwhile (or stopped): the newest next
                    seen = watch.settled()
                    continue
            seen = watch.changed_from(seen)
    except KeyboardInterrupt:
        print(f"\nstopped watching {path}", flush=True)
    finally:
        with _no_interrupts():
            stop.set()
            monitor.join()
            checker.close()
            terminate()
    return 0


def _terminate_as_interrupt() -> Callable[[], None]:
    """SIGTERM ends the watch as Ctrl-C does, cleaning up (``kill`` would leave the
    checker's prepared box); returns what puts the old handler back."""
    if threading.current_thread() is not threading.main_thread() or not hasattr(signal, "SIGTERM"):
        return lambda: None

    def interrupt(number: int, frame: object) -> None:
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, interrupt)

    def restore() -> None:
        signal.signal(signal.SIGTERM, previous)

    return restore


@contextmanager
def _no_interrupts() -> Iterator[None]:
    """Ctrl-C ignored while the watch cleans up (a second one would leave its processes
    and folders behind)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)
