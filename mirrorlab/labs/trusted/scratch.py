"""The one place a student's run may write: its scratch space, with a total.

A run's scratch holds ``box/`` (its working folder, where its file lies) and ``tmp/`` (its
``/tmp``, or ``TMPDIR``). Two kinds (:func:`scratch_kind` says which applies here):

- ``tmpfs``: a file system of its own, made in the run's own mount namespace before the
  program starts (:func:`tmpfs_preexec`; where the kernel refuses, the run is started
  again, watched, and so are the process's later runs): at most :data:`SCRATCH_BYTES` and
  :data:`SCRATCH_FILES` files and folders, enforced by the kernel (a write past either
  fails with ``No space left on device``). Nobody else sees it, and it is gone with the
  run's last process: nothing of it is ever removed file by file. Used with bubblewrap
  (as root, a mount namespace; as a user, a user namespace too, in which bubblewrap then
  makes its own) and in the user-id fallback where the kernel gives a mount namespace;
  there every other mount is made read-only in that namespace too, so the scratch is the
  only place the run can write.
- ``watched``: a folder of the host's temporary folder (:func:`measure` looks at it
  :data:`WATCH_SECONDS` apart, and the run is stopped at the first look that finds it
  over either total; what it writes between two looks is the slack), removed by the
  system's own tool (:func:`discard`). Used where there is no mount namespace: macOS,
  Windows, a Linux without bubblewrap or user namespaces.

Nothing here walks a student's tree recursively in Python: :func:`measure` is iterative,
bounded by the totals, and :func:`discard` is ``rm -rf`` (``rd /s /q`` on Windows).
"""

from __future__ import annotations

import ctypes
import os
import re
import shutil
import stat
import subprocess
import sys
import tempfile
from collections.abc import Callable, Mapping
from functools import lru_cache
from pathlib import Path

SCRATCH_MB = 256
SCRATCH_BYTES = SCRATCH_MB << 20
"""The most one run may write: its box and its /tmp together."""
SCRATCH_FILES = 4096
"""The most files and folders (inodes) one run's scratch may hold, its own four (the
scratch, ``box``, ``tmp`` and the student's file) included."""
WATCH_SECONDS = 0.05
"""How often a ``watched`` scratch is measured."""
WATCH_DEPTH = 256
"""A ``watched`` scratch deeper than this many folders stops the run (measuring it would
need more open folders than a process may hold)."""

BOX, TMP = "box", "tmp"

_CLONE_NEWNS, _CLONE_NEWUSER = 0x00020000, 0x10000000
_MS_RDONLY, _MS_NOSUID, _MS_NODEV = 1, 2, 4
_MS_NOEXEC, _MS_REMOUNT, _MS_BIND = 8, 32, 4096
_MS_REC, _MS_PRIVATE = 0x4000, 1 << 18
_MOUNT_FLAGS = {
    "ro": _MS_RDONLY,
    "nosuid": _MS_NOSUID,
    "nodev": _MS_NODEV,
    "noexec": _MS_NOEXEC,
    "noatime": 1024,
    "nodiratime": 2048,
    "relatime": 1 << 21,
}


def scratch_message() -> str:
    """The totals, as the run's one line says them."""
    return f"{SCRATCH_MB} MiB or {SCRATCH_FILES} files and folders"


def tmpfs_options(owner: int | None) -> bytes:
    """The scratch file system's mount options (``owner``: the user id that owns it)."""
    options = f"size={SCRATCH_BYTES},nr_inodes={SCRATCH_FILES},mode=0700"
    if owner is not None:
        options += f",uid={owner},gid={owner}"
    return options.encode()


def _unescape(field: bytes) -> bytes:
    """A mountinfo path with its octal escapes (``\\040`` for a space) undone."""
    return re.sub(rb"\\([0-7]{3})", lambda m: bytes([int(m.group(1), 8)]), field)


def _mounts() -> dict[bytes, int]:
    """This process's mount points and each one's per-mount flags (nosuid, nodev, ...),
    from mountinfo: a bind remount must keep them."""
    found: dict[bytes, int] = {}
    try:
        lines = Path("/proc/self/mountinfo").read_bytes().splitlines()
    except OSError:
        return found
    for line in lines:
        fields = line.split(b" ")
        if len(fields) > 5:
            flags = 0
            for option in fields[5].decode(errors="replace").split(","):
                flags |= _MOUNT_FLAGS.get(option, 0)
            found[_unescape(fields[4])] = flags
    return found


def tmpfs_preexec(
    scratch: Path,
    files: Mapping[str, bytes],
    owner: int | None,
    user_namespace: bool,
    read_only_host: bool = False,
) -> Callable[[], None]:
    """What the run's first process does before its program (in the child, after the
    fork): a mount namespace of its own (with ``user_namespace``, a user namespace too,
    mapping this user to itself), the scratch tmpfs mounted on the folder ``scratch``
    (owned by ``owner``, else by this user) with ``box/`` holding ``files`` and ``tmp/``;
    with ``read_only_host``, every other mount made read-only in that namespace. Raises
    OSError when the kernel refuses (see :func:`tmpfs_works`). Everything it needs is
    prepared here, so the child only makes system calls."""
    libc = ctypes.CDLL(None, use_errno=True)
    unshare, mount = libc.unshare, libc.mount
    mount.argtypes = [ctypes.c_char_p, ctypes.c_char_p, ctypes.c_char_p, ctypes.c_ulong]
    mount.argtypes += [ctypes.c_char_p]
    uid, gid = os.getuid(), os.getgid()
    target = os.fsencode(scratch)
    options = tmpfs_options(owner)
    placed = [(os.fsencode(scratch / BOX / name), data) for name, data in files.items()]
    folders = [os.fsencode(scratch / BOX), os.fsencode(scratch / TMP)]
    others = [(p, f) for p, f in _mounts().items() if p != target] if read_only_host else []
    workdir = os.fsencode(scratch / BOX)

    def fail(what: str) -> None:
        number = ctypes.get_errno()
        raise OSError(number, f"{what}: {os.strerror(number)}")

    def write(path: str, text: str) -> None:
        descriptor = os.open(path, os.O_WRONLY)
        try:
            os.write(descriptor, text.encode())
        finally:
            os.close(descriptor)

    def prepare() -> None:  # pragma: no cover - runs in the child before it starts
        if unshare(_CLONE_NEWNS | (_CLONE_NEWUSER if user_namespace else 0)) != 0:
            fail("unshare")
        if user_namespace:
            write("/proc/self/setgroups", "deny")
            write("/proc/self/uid_map", f"{uid} {uid} 1")
            write("/proc/self/gid_map", f"{gid} {gid} 1")
        if mount(None, b"/", None, _MS_REC | _MS_PRIVATE, None) != 0:
            fail("mount --make-rprivate /")
        if mount(b"tmpfs", target, b"tmpfs", _MS_NOSUID | _MS_NODEV, options) != 0:
            fail("mount tmpfs")
        for folder in folders:
            os.mkdir(folder, 0o700)
            if owner is not None:
                os.chown(folder, owner, owner)
        for path, data in placed:
            descriptor = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
            try:
                view = memoryview(data)
                while view:
                    view = view[os.write(descriptor, view) :]
            finally:
                os.close(descriptor)
            if owner is not None:
                os.chown(path, owner, owner)
        for point, flags in others:
            # best effort per mount (a few pseudo file systems refuse a remount); the
            # ones a file could write to (/, /tmp, /dev/shm, /var/tmp) are plain mounts
            mount(None, point, None, _MS_REMOUNT | _MS_BIND | _MS_RDONLY | flags, None)
        os.chdir(workdir)  # the folder the run starts in, now on the scratch

    return prepare


def _probe(user_namespace: bool, owner: int | None, read_only_host: bool) -> bool:
    folder = Path(tempfile.mkdtemp(prefix="mirrorlab-probe-"))
    try:
        (folder / "scratch").mkdir()
        prepare = tmpfs_preexec(
            folder / "scratch", {"probe": b"1"}, owner, user_namespace, read_only_host
        )
        program = shutil.which("true") or sys.executable
        done = subprocess.run(
            [program] if program != sys.executable else [program, "-I", "-S", "-c", ""],
            preexec_fn=prepare,
            capture_output=True,
            timeout=30,
        )
        return done.returncode == 0 and not any((folder / "scratch").iterdir())
    except (OSError, subprocess.SubprocessError):
        return False
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def eligible(mode: str) -> bool:
    """Whether a run in sandbox ``mode`` (``bwrap``, ``user``, ``none``) may have a tmpfs
    scratch: on Linux, with bubblewrap (as root a mount namespace; as a user a user
    namespace too) or as root in the user-id fallback. ``none`` never does (macOS,
    Windows and a Linux without bubblewrap are alike: a watched folder)."""
    if not sys.platform.startswith("linux") or mode == "none":
        return False
    return mode == "bwrap" or os.geteuid() == 0


_refused: set[str] = set()
"""The modes whose tmpfs scratch the kernel refused in this process (then watched)."""


def refuse(mode: str) -> None:
    """Note that the kernel refused a tmpfs scratch in ``mode``: this process's later runs
    in it are watched."""
    _refused.add(mode)


def scratch_kind(mode: str) -> str:
    """``tmpfs`` or ``watched`` for a run in sandbox ``mode`` (see the module's text):
    ``tmpfs`` where it is :func:`eligible` and was not refused (the run that finds it
    refused is started again, watched: :func:`refuse`)."""
    return "tmpfs" if eligible(mode) and mode not in _refused else "watched"


@lru_cache(maxsize=4)
def tmpfs_works(mode: str) -> bool:
    """Whether a run in sandbox ``mode`` gets its tmpfs scratch here, tried with a process
    that does nothing (``mirrorlab info`` asks; a run finds out as it starts)."""
    if not eligible(mode):
        return False
    root = os.geteuid() == 0
    return _probe(user_namespace=not root, owner=None, read_only_host=False)


def prepare_watched(scratch: Path, files: Mapping[str, bytes], owner: int | None) -> None:
    """A ``watched`` scratch on the host: ``box/`` holding ``files`` and ``tmp/``, owned by
    ``owner`` (when given)."""
    for folder in (scratch, scratch / BOX, scratch / TMP):
        folder.mkdir(mode=0o700, exist_ok=True)
    for name, data in files.items():
        (scratch / BOX / name).write_bytes(data)
    if owner is not None:
        for path in (scratch, scratch / BOX, scratch / TMP, *(scratch / BOX / n for n in files)):
            os.chown(path, owner, owner)


def measure(
    scratch: Path, max_bytes: int = SCRATCH_BYTES, max_entries: int = SCRATCH_FILES
) -> tuple[int, int, bool]:
    """(bytes on disk, files and folders, whether it is deeper than :data:`WATCH_DEPTH`)
    of a ``watched`` scratch, stopping early once either total is passed. Iterative, and
    folder by folder through open descriptors where the system has them (POSIX), so no
    path grows with the depth; links are counted, never followed; a file with several
    names counts once."""
    total, entries, seen = 0, 0, set()
    by_descriptor = os.open in os.supports_dir_fd and os.scandir in os.supports_fd
    if by_descriptor:
        flags = os.O_RDONLY | getattr(os, "O_DIRECTORY", 0) | getattr(os, "O_NOFOLLOW", 0)
        try:
            root = os.open(scratch, flags)
        except OSError:
            return 0, 0, False
        stack: list[tuple[int, int]] = [(root, 0)]
        try:
            while stack:
                descriptor, depth = stack.pop()
                try:
                    with os.scandir(descriptor) as listing:
                        names = [(e.name, e.is_dir(follow_symlinks=False)) for e in listing]
                    for name, folder in names:
                        entries += 1
                        info = os.stat(name, dir_fd=descriptor, follow_symlinks=False)
                        if (info.st_dev, info.st_ino) not in seen:
                            seen.add((info.st_dev, info.st_ino))
                            total += _on_disk(info)
                        if total > max_bytes or entries > max_entries:
                            return total, entries, False
                        if folder:
                            if depth + 1 > WATCH_DEPTH:
                                return total, entries, True
                            stack.append((os.open(name, flags, dir_fd=descriptor), depth + 1))
                except OSError:
                    pass
                finally:
                    os.close(descriptor)
        finally:
            for descriptor, _ in stack:
                os.close(descriptor)
        return total, entries, False
    paths: list[tuple[Path, int]] = [(scratch, 0)]
    while paths:
        folder_path, depth = paths.pop()
        try:
            with os.scandir(folder_path) as listing:
                for entry in listing:
                    entries += 1
                    info = entry.stat(follow_symlinks=False)
                    total += _on_disk(info)
                    if total > max_bytes or entries > max_entries:
                        return total, entries, False
                    if entry.is_dir(follow_symlinks=False):
                        if depth + 1 > WATCH_DEPTH:
                            return total, entries, True
                        paths.append((Path(entry.path), depth + 1))
        except OSError:
            continue
    return total, entries, False


def _on_disk(info: os.stat_result) -> int:
    """The bytes a file takes: its blocks where the system says (a sparse file's holes
    take none), else its size."""
    blocks = getattr(info, "st_blocks", None)
    if blocks is not None and stat.S_ISREG(info.st_mode):
        return max(int(blocks) * 512, 0)
    return int(info.st_size) if stat.S_ISREG(info.st_mode) else 0


def over(scratch: Path) -> bool:
    """Whether a ``watched`` scratch holds more than the totals allow (or is deeper than
    can be measured)."""
    total, entries, deep = measure(scratch)
    return deep or total > SCRATCH_BYTES or entries > SCRATCH_FILES


def discard(path: Path) -> bool:
    """Remove ``path`` and all below it with the system's own tool (``rm -rf``; ``rd /s
    /q`` on Windows), however deep; True when it is gone. Never raises."""
    if not os.path.lexists(path):
        return True
    if sys.platform == "win32":
        commands = [["cmd", "/d", "/c", "rd", "/s", "/q", str(path)]]
    else:
        remove = [shutil.which("rm") or "/bin/rm", "-rf", "--", str(path)]
        # a folder the run closed to its owner (mode 000) is opened first, then removed
        commands = [remove, [shutil.which("chmod") or "/bin/chmod", "-R", "u+rwx", str(path)]]
        commands.append(remove)
    for command in commands:
        try:
            subprocess.run(command, capture_output=True, timeout=120)
        except (OSError, subprocess.SubprocessError):
            return False
        if not os.path.lexists(path):
            return True
    return False
