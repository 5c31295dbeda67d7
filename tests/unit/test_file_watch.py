"""The file watch of ``lab check --watch`` and ``lab run --watch``: a save is seen whatever
way the editor writes it (in place, a new file renamed over the old, the old removed
first)."""

from __future__ import annotations

import os
import threading
import time
from collections.abc import Callable
from pathlib import Path

from mirrorlab.labs.trusted.watch import FileWatch

POLL = 0.01


def later(seconds: float, action: Callable[[], object]) -> threading.Thread:
    def run() -> None:
        time.sleep(seconds)
        action()

    thread = threading.Thread(target=run)
    thread.start()
    return thread


def test_a_save_in_place_is_seen(tmp_path: Path):
    path = tmp_path / "mine.py"
    path.write_text("a = 1\n")
    watch = FileWatch(path, POLL)
    seen = watch.settled()
    writer = later(0.05, lambda: path.write_text("a = 2 # a longer line\n"))
    changed = watch.changed_from(seen)
    writer.join()
    assert changed is not None and changed != seen
    assert path.read_text() == "a = 2 # a longer line\n"


def test_a_save_by_rename_is_seen_even_with_the_same_size_and_time(tmp_path: Path):
    path = tmp_path / "mine.py"
    path.write_text("a = 1\n")
    watch = FileWatch(path, POLL)
    seen = watch.settled()
    status = path.stat()

    def save() -> None:  # vim's way: a new file, renamed over the old
        staging = tmp_path / ".mine.py.swp"
        staging.write_text("a = 2\n")
        os.utime(staging, ns=(status.st_atime_ns, status.st_mtime_ns))
        os.replace(staging, path)

    writer = later(0.05, save)
    changed = watch.changed_from(seen)
    writer.join()
    assert changed is not None and changed != seen  # a new inode
    assert path.read_text() == "a = 2\n"


def test_a_file_removed_is_reported_gone_then_seen_again(tmp_path: Path):
    path = tmp_path / "mine.py"
    path.write_text("a = 1\n")
    watch = FileWatch(path, POLL)
    seen = watch.settled()
    remover = later(0.05, path.unlink)
    assert watch.changed_from(seen) is None  # gone
    remover.join()
    writer = later(0.05, lambda: path.write_text("a = 3\n"))
    back = watch.changed_from(None)
    writer.join()
    assert back is not None and path.read_text() == "a = 3\n"
