"""Writing output files safely: each through a temporary file and a rename, and the files
of one command all together or none (:class:`Outputs`), so that a failure never leaves
a partial file or clobbers an existing one."""

from __future__ import annotations

import io
import os
import shutil
import tempfile
import uuid
from pathlib import Path

import numpy as np

from mirrorlab.errors import WriteError


class OutputError(ValueError):
    """An output path that cannot be used: ``option`` names where it came from."""

    def __init__(self, option: str, problem: str) -> None:
        self.option = option
        super().__init__(f"{option}: {problem}")


def check_output(
    option: str, text: str | Path, suffix: str = ".png", make_folder: bool = False
) -> Path:
    """``text`` as an output path ending in ``suffix`` in a folder that exists (or, with
    ``make_folder``, can be made) and takes a new file; OutputError naming ``option``
    for a bad name or a missing folder, :class:`~mirrorlab.errors.WriteError` (``cannot
    write PATH: REASON``) when the system refuses to write there. Checked before any
    work is done, so a command fails at once rather than after rendering."""
    path = Path(text)
    if path.suffix.lower() != suffix:
        raise OutputError(option, f"expected a file name ending in {suffix}, got {str(text)!r}")
    if path.is_dir():
        raise OutputError(option, f"{str(text)!r} is a directory, expected a {suffix} file name")
    folder = path.absolute().parent
    existing = next(p for p in (folder, *folder.parents) if p.exists())
    if not existing.is_dir():
        raise OutputError(option, f"{existing} is a file, so {str(text)!r} cannot be written")
    if existing != folder and not make_folder:
        raise OutputError(option, f"folder {path.parent} does not exist; make it first")
    check_writable(existing, path)
    return path


def check_folder(option: str, text: str | Path) -> Path:
    """``text`` as an output folder: one that exists or can be made, and takes new files."""
    folder = Path(text)
    existing = next(p for p in (folder.absolute(), *folder.absolute().parents) if p.exists())
    if not existing.is_dir():
        raise OutputError(option, f"{existing} is a file, expected a folder")
    check_writable(existing, folder)
    return folder


def check_writable(folder: Path, path: Path) -> None:
    """WriteError for ``path`` when ``folder`` does not take a new file (read-only file
    system, permissions, a pseudo file system): tried by making and removing one."""
    try:
        with tempfile.TemporaryFile(dir=folder, prefix=".mirrorlab-check."):
            pass
    except OSError as exc:
        raise WriteError(path, _reason(exc)) from None


def _reason(error: OSError) -> str:
    return error.strerror or str(error)


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
    """Write ``data`` beside ``path`` under a temporary name; returns that name.
    WriteError naming ``path`` when the system refuses."""
    name = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        handle, name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
        with os.fdopen(handle, "wb") as stream:
            stream.write(data)
        os.chmod(name, 0o666 & ~_umask())  # mkstemp makes 0600; give the usual mode
    except BaseException as exc:
        if name is not None:
            Path(name).unlink(missing_ok=True)
        if isinstance(exc, OSError):
            raise WriteError(path, _reason(exc)) from None
        raise
    return Path(name)


def _keep_old(path: Path) -> Path | None:
    """A second name for ``path``'s current file (a hard link, or a copy where links are
    not allowed), to put back if a later output fails; None when there is no file."""
    if not path.is_file():
        return None
    backup = path.with_name(f".{path.name}.{uuid.uuid4().hex[:12]}.old")
    try:
        os.link(path, backup)
    except OSError:
        try:
            shutil.copy2(path, backup)
        except OSError as exc:
            backup.unlink(missing_ok=True)
            raise WriteError(path, _reason(exc)) from None
    return backup


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

    def add(self, path: str | Path, data: bytes) -> None:
        path = Path(path)
        if any(path.resolve() == done.resolve() for done, _ in self._staged):
            raise OutputError(
                str(path), "two outputs would be written to this one file; give each its own name"
            )
        self._staged.append((path, _stage(path, data)))

    def add_png(self, path: Path, image: np.ndarray) -> None:
        self.add(path, png_bytes(image))

    def commit(self) -> None:
        """Rename every staged file into place. If any rename fails (or is interrupted),
        the ones already done are undone: the old files come back, new ones go."""
        done: list[tuple[Path, Path | None]] = []
        try:
            for path, staged in self._staged:
                backup = _keep_old(path)
                try:
                    os.replace(staged, path)
                except OSError as exc:
                    if backup is not None:
                        backup.unlink(missing_ok=True)
                    raise WriteError(path, _reason(exc)) from None
                done.append((path, backup))
        except BaseException:
            for path, backup in reversed(done):
                if backup is not None:
                    os.replace(backup, path)
                else:
                    path.unlink(missing_ok=True)
            raise
        finally:
            self.discard()
        for _, backup in done:
            if backup is not None:
                backup.unlink(missing_ok=True)

    def discard(self) -> None:
        for _, staged in self._staged:
            staged.unlink(missing_ok=True)
        self._staged.clear()
