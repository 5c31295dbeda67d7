"""Functions the executor tests send to worker processes (importable there)."""

from __future__ import annotations

import os
from pathlib import Path


def square(value: int) -> int:
    return value * value


def fail(value: int) -> int:
    raise ValueError(f"no good: {value}")


def die_once(marker: str, value: int) -> int:
    """Kill the worker process the first time (``marker`` does not exist yet); return
    ``value`` the next time."""
    path = Path(marker)
    if not path.exists():
        path.write_text(str(os.getpid()))
        os._exit(3)
    return value


def count_calls(folder: str, key: str) -> str:
    """Leave one file per call in ``folder``; returns ``key``."""
    Path(folder, f"{key}-{os.getpid()}-{len(list(Path(folder).iterdir()))}").touch()
    return key


def process_id(_: int) -> int:
    return os.getpid()
