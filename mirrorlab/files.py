"""Writing output files safely: each through a temporary file and a rename, and the files
of one command all together or none (:class:`Outputs`), so that a failure never leaves
a partial file or clobbers an existing one."""

from __future__ import annotations

import io
import os
import tempfile
from pathlib import Path

import numpy as np


class OutputError(ValueError):
    """An output path that cannot be used: ``option`` names where it came from."""

    def __init__(self, option: str, problem: str) -> None:
        self.option = option
        super().__init__(f"{option}: {problem}")


def check_output(option: str, text: str | Path, suffix: str = ".png") -> Path:
    """``text`` as an output path ending in ``suffix`` whose folder exists or can be made;
    OutputError naming ``option`` otherwise."""
    path = Path(text)
    if path.suffix.lower() != suffix:
        raise OutputError(option, f"expected a file name ending in {suffix}, got {str(text)!r}")
    if path.is_dir():
        raise OutputError(option, f"{str(text)!r} is a directory, expected a {suffix} file name")
    existing = next(p for p in path.absolute().parents if p.exists())
    if not existing.is_dir():
        raise OutputError(option, f"{existing} is a file, so {str(text)!r} cannot be written")
    return path


def png_bytes(image: np.ndarray) -> bytes:
    """``image`` ``(h, w, 3)`` uint8 as PNG file bytes."""
    from PIL import Image

    with io.BytesIO() as buffer:
        Image.fromarray(np.asarray(image, dtype=np.uint8)).save(buffer, format="PNG")
        return buffer.getvalue()


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _stage(path: Path, data: bytes) -> Path:
    """Write ``data`` beside ``path`` under a temporary name; returns that name."""
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(handle, "wb") as stream:
            stream.write(data)
        os.chmod(name, 0o666 & ~_umask())  # mkstemp makes 0600; give the usual mode
    except BaseException:
        Path(name).unlink(missing_ok=True)
        raise
    return Path(name)


def write_bytes_atomic(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a temporary file and a rename."""
    with Outputs() as outputs:
        outputs.add(path, data)


def write_png_atomic(path: Path, image: np.ndarray) -> None:
    """Write ``image`` ``(h, w, 3)`` uint8 to ``path`` as a PNG, atomically."""
    write_bytes_atomic(path, png_bytes(image))


class Outputs:
    """The files of one command, committed together: :meth:`add` writes each beside its
    destination under a temporary name; leaving the ``with`` block without an error
    renames them all into place, with one removes them all. Two outputs to one path
    are refused (one would silently replace the other)."""

    def __init__(self) -> None:
        self._staged: list[tuple[Path, Path]] = []

    def __enter__(self) -> Outputs:
        return self

    def __exit__(self, kind, error, trace) -> None:
        if kind is None:
            self.commit()
        else:
            self.discard()

    def add(self, path: Path, data: bytes) -> None:
        path = Path(path)
        if any(path.resolve() == done.resolve() for done, _ in self._staged):
            raise OutputError(str(path), "two outputs would be written to this one file")
        self._staged.append((path, _stage(path, data)))

    def add_png(self, path: Path, image: np.ndarray) -> None:
        self.add(path, png_bytes(image))

    def commit(self) -> None:
        try:
            for path, staged in self._staged:
                os.replace(staged, path)
        finally:
            self.discard()

    def discard(self) -> None:
        for _, staged in self._staged:
            staged.unlink(missing_ok=True)
        self._staged.clear()
