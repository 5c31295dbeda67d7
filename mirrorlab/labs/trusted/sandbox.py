"""Running a student's file where it can harm nothing and reach nothing: its own process,
limits on time, memory and processes, a scratch folder of its own, no network, and a file
system that holds only what the student side needs.

How, in order of preference (:func:`sandbox_mode` says which applies):

- ``bwrap``: bubblewrap (Debian ``bubblewrap``) builds a new root for the run: ``/usr``
  read-only (the system's libraries), the interpreter's own folder read-only (wherever it
  is: every folder above it is made anew, open, holding nothing else, so an interpreter
  under a closed home works), the student side of the labs (:mod:`mirrorlab.labs.student`)
  and numpy read-only under ``/lab``, the run's scratch (:mod:`.scratch`: at most
  :data:`~.scratch.SCRATCH_MB` MiB and :data:`~.scratch.SCRATCH_FILES` files and folders)
  writable at ``/lab/box`` and ``/tmp``, everything else read-only. No checkout, no venv,
  no other package, no solution, no reference, no other submission, no home. Network,
  process ids, IPC and the host name are unshared. Run as root, the process then drops to
  a user id of its own (``setpriv``).
- ``user`` (root on Linux, no working bubblewrap): the same limits, the process under a
  user id of its own, which may write only in its scratch: where the kernel gives a mount
  namespace every other mount is read-only there (else world-writable places stay open
  to it). The file system stays visible to it (readable files only): the note of
  :func:`unsandboxed_note` says so.
- ``none`` (no bubblewrap, not root on Linux; every macOS and Windows machine): the file
  runs in a process of its own, as the user, over the same pipe, with what limits the
  system has; its scratch is watched. Nothing keeps it from reading or writing what the
  user may.

Only ``bwrap`` is a sandbox. The other two run only when the run's :class:`Limits` say
``unsandboxed`` (a student's own file in ``lab check`` and ``lab run``, the teacher's
solutions, ``lab grade --unsandboxed``); otherwise :class:`Sandboxed` refuses with
:class:`SandboxError`, one line saying how to get bubblewrap (:func:`missing_sandbox`).
The checker's verdicts never depend on the sandbox: the evidence is what the trusted
process executed and observed.

Limits (:class:`Limits`): wall-clock seconds (a watchdog thread ends the process tree
then), everywhere. Where the system has them (POSIX ``resource``): CPU seconds
(RLIMIT_CPU), address space (RLIMIT_AS, not on macOS, which ignores it), threads and
processes (RLIMIT_NPROC), file size and open files. Run as root, a run that starts more
than :data:`MAX_PROCESSES` processes (a fork bomb) is stopped at once. The process starts
in a session of its own (a new process group on Windows) and is ended with its group.
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import sysconfig
import tempfile
import threading
import time
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

from mirrorlab.labs.trusted import scratch

UID_BASE = 200_000
"""Sandboxed processes run as UID_BASE + the id of the process that asked for the run (the
command or grading worker), so that two gradings running at once never share a user id
(nor its process limit)."""

MAX_PROCESSES = 8
"""Processes a run may have at once (the runner needs one; threads are not counted)."""

STUDENT_PACKAGE = Path(__file__).resolve().parent.parent / "student"
"""The student side's folder: the only part of mirrorlab a sandbox sees."""

BOX_PREFIX = "mirrorlab-box-"
SCRATCH_FOLDER = "scratch"
"""The run folder's scratch (:mod:`.scratch`): the one place its program may write."""
STDERR_KEPT = 4000
"""Bytes of a piped run's errors kept (its last ones)."""
SANDBOX_BOX = "/lab/box"
SANDBOX_PACKAGES = "/lab/pkg"
SANDBOX_SITE = "/lab/site"
SANDBOX_LAB_SIDE = "/lab/pkg/lab_side.py"
"""Where the sandbox holds the lab's own student side (its ``student.py``), read-only."""


class SandboxError(RuntimeError):
    """No safe way to run untrusted code here, or the sandbox could not be set up; the
    message is one line saying what to do."""


@dataclass(frozen=True)
class Limits:
    """What one submission may use: ``cpu_seconds`` of CPU time, ``seconds`` of wall-clock
    time, ``memory_mb`` of address space, ``processes`` (RLIMIT_NPROC: threads count too),
    ``file_mb`` per file written; ``unsandboxed``: whether the run may go ahead without a
    sandbox (see the module's text) where this machine has none."""

    cpu_seconds: int = 20
    seconds: float = 120.0
    memory_mb: int = 1536
    processes: int = 64
    file_mb: int = 64
    unsandboxed: bool = False


def _bwrap_works() -> bool:
    bwrap = shutil.which("bwrap")
    if bwrap is None:
        return False
    try:
        done = subprocess.run(
            [
                bwrap,
                "--ro-bind",
                "/",
                "/",
                "--dev",
                "/dev",
                "--unshare-pid",
                "--unshare-net",
                "--die-with-parent",
                "true",
            ],
            capture_output=True,
            timeout=30,
        )
    except (OSError, subprocess.TimeoutExpired):
        return False
    return done.returncode == 0


def _is_root() -> bool:
    return hasattr(os, "geteuid") and os.geteuid() == 0


@lru_cache(maxsize=1)
def sandbox_mode() -> str:
    """``bwrap``, ``user`` or ``none`` (see the module's text). MIRRORLAB_SANDBOX may ask
    for ``user`` (as root) or ``none`` instead of bubblewrap, to test them; neither is a
    sandbox, so a run still needs ``Limits.unsandboxed`` to use them."""
    root = _is_root()
    wanted = os.environ.get("MIRRORLAB_SANDBOX", "")
    if wanted == "user" and root:
        return "user"
    if wanted == "none":
        return "none"
    if _bwrap_works():
        return "bwrap"
    return "user" if root and sys.platform.startswith("linux") else "none"


def sandboxed() -> bool:
    """Whether a run here is sandboxed (bubblewrap works)."""
    return sandbox_mode() == "bwrap"


UNSANDBOXED_FLAG = "--unsandboxed"
"""The ``lab grade`` option that runs submissions without a sandbox, knowingly."""


def _missing() -> tuple[str, str]:
    """Why there is no sandbox here, and how to get one."""
    wanted = os.environ.get("MIRRORLAB_SANDBOX", "")
    if wanted in ("user", "none") and sandbox_mode() == wanted:
        return f"MIRRORLAB_SANDBOX={wanted} turns the sandbox off", "unset it"
    if not sys.platform.startswith("linux"):
        return (
            f"bubblewrap, the sandbox, exists only on Linux (this is {sys.platform})",
            "grade on a Linux machine with bubblewrap (apt-get install bubblewrap)",
        )
    if shutil.which("bwrap"):
        return (
            "bubblewrap cannot make a sandbox here (are user namespaces disabled?)",
            "allow unprivileged user namespaces (sysctl kernel.unprivileged_userns_clone=1)",
        )
    return (
        "no sandbox: bubblewrap is not installed",
        "install it (Debian/Ubuntu: apt-get install bubblewrap; Fedora: dnf install bubblewrap)",
    )


def unsandboxed_reason() -> str:
    """Why there is no sandbox here, in a few words ('' where bubblewrap works)."""
    return "" if sandbox_mode() == "bwrap" else _missing()[0]


def missing_sandbox() -> str:
    """One line: why there is no sandbox here and how to get one (or take the risk)."""
    why, get = _missing()
    return (
        f"{why}; {get}, or give {UNSANDBOXED_FLAG} to run every submission as a "
        f"process of yours, able to read and write what you can"
    )


def unsandboxed_how() -> str:
    """How a file runs here without a sandbox (the ``user`` or ``none`` mode)."""
    return {
        "user": "as a user id of its own, the file system in its view",
        "none": "as you, in a process of its own",
    }.get(sandbox_mode(), "sandboxed")


def unsandboxed_note() -> str:
    """One line for a student's own check run without a sandbox."""
    return (
        f"note: not sandboxed ({_missing()[0]}): the file runs {unsandboxed_how()}; "
        f"fine for your own file"
    )


def sandbox_uid(owner: int | None = None) -> int:
    """The user id of the runs that process ``owner`` (default this one) asks for."""
    return UID_BASE + (os.getpid() if owner is None else owner)


def interpreter() -> Path:
    """The real Python interpreter behind this one (a venv's python is a link to it)."""
    return Path(getattr(sys, "_base_executable", "") or sys.executable).resolve()


def _within(path: Path, folder: Path) -> bool:
    return path == folder or folder in path.parents


class _Root:
    """bwrap arguments that build the sandbox's file system."""

    def __init__(self) -> None:
        self.arguments: list[str] = []
        self.made: set[Path] = {Path("/")}
        self.bound: list[Path] = []
        self.fresh: list[Path] = []  # empty file systems of the sandbox's own (its /tmp)

    def reachable(self, path: Path) -> bool:
        """Whether ``path`` shows the host's folder in the sandbox (a fresh file system
        shows none: what lies below its top must be made or bound)."""
        return path in self.made or any(_within(path, b) for b in self.bound if b not in self.fresh)

    def parents(self, destination: Path) -> None:
        """Every folder above ``destination`` made anew, mode 0755 (bwrap would make them
        0700, which a dropped user cannot enter)."""
        for parent in reversed(destination.parents):
            if not self.reachable(parent):
                self.arguments += ["--perms", "0755", "--dir", str(parent)]
                self.made.add(parent)

    def bind(self, source: Path, destination: Path | None = None, writable: bool = False) -> None:
        destination = destination or source
        if destination != source or not self.reachable(destination):
            self.parents(destination)
            self.arguments += ["--bind" if writable else "--ro-bind", str(source), str(destination)]
            self.bound.append(destination)

    def hide(self, folder: Path) -> None:
        """An empty folder in place of ``folder`` where the sandbox would see it: within
        a folder bound from the host (a fresh file system such as its /tmp shows none of
        the host's, and a folder made there would only give away the host's path)."""
        if folder.is_dir() and any(_within(folder, b) for b in self.bound if b not in self.fresh):
            self.arguments += ["--tmpfs", str(folder)]


def _site_folders() -> list[Path]:
    """Folders of installed packages the sandbox may otherwise see."""
    found = {
        Path(p).resolve()
        for p in sys.path
        if p and Path(p).name in ("site-packages", "dist-packages")
    }
    for key in ("purelib", "platlib"):
        for scheme_vars in ({}, {"base": sys.base_prefix, "platbase": sys.base_prefix}):
            try:
                found.add(Path(sysconfig.get_path(key, vars=scheme_vars)).resolve())
            except (KeyError, ValueError):
                continue
    found.update(
        Path(p)
        for p in (
            "/usr/lib/python3/dist-packages",
            f"/usr/local/lib/python3.{sys.version_info.minor}/dist-packages",
        )
    )
    return sorted(found)


def numpy_folders() -> list[Path]:
    """numpy's package folder (and its bundled libraries), which the student side may
    use; none when this interpreter has no numpy."""
    try:
        import numpy
    except ImportError:  # pragma: no cover - a dependency of mirrorlab
        return []
    folder = Path(numpy.__file__).resolve().parent
    libs = folder.parent / "numpy.libs"
    return [folder, *([libs] if libs.is_dir() else [])]


def bwrap_arguments(space: Path, lab_side: Path | None = None) -> list[str]:
    """The bwrap command line before the program: the sandbox's file system (see the
    module's text), the run's scratch ``space`` (:mod:`.scratch`) writable at :data:`SANDBOX_BOX`
    (its ``box/``) and ``/tmp`` (its ``tmp/``), the lab's ``student.py`` (``lab_side``)
    read-only at :data:`SANDBOX_LAB_SIDE`. Everything else is read-only: bubblewrap's own
    root and ``/dev`` (file systems of the sandbox's owner, without a total) are made so
    once the sandbox is built, so the scratch is the only place a file may write."""
    root = _Root()
    root.bind(Path("/usr"))
    for link in ("bin", "sbin", "lib", "lib64", "lib32", "libx32"):
        path = Path("/", link)
        if path.is_symlink():
            root.arguments += ["--symlink", os.readlink(path), str(path)]
            root.made.add(path)
        elif path.is_dir():
            root.bind(path)
    root.arguments += [
        "--ro-bind-try",
        "/etc/ld.so.cache",
        "/etc/ld.so.cache",
        "--proc",
        "/proc",
        "--dev",
        "/dev",
        "--bind",
        str(space / scratch.TMP),
        "/tmp",
    ]
    root.made.update(Path(p) for p in ("/etc", "/etc/ld.so.cache", "/proc", "/dev", "/tmp"))
    root.bound += [Path("/tmp")]
    root.fresh += [Path("/tmp")]
    base = Path(sys.base_prefix).resolve()
    root.bind(base)
    executable = interpreter()
    if not root.reachable(executable):
        root.bind(executable.parent)
    for folder in _site_folders():
        root.hide(folder)
    root.hide(STUDENT_PACKAGE.parent.parent)  # mirrorlab itself, were it under those
    root.bind(STUDENT_PACKAGE, Path(SANDBOX_PACKAGES, "labstudent"))
    if lab_side is not None:
        root.bind(lab_side.resolve(), Path(SANDBOX_LAB_SIDE))
    for folder in numpy_folders():
        root.bind(folder, Path(SANDBOX_SITE, folder.name))
    root.bind(space / scratch.BOX, Path(SANDBOX_BOX), writable=True)
    hidden = [root.arguments[i + 1] for i, a in enumerate(root.arguments) if a == "--tmpfs"]
    for made in [*hidden, "/dev", "/"]:
        root.arguments += ["--remount-ro", made]
    return [shutil.which("bwrap") or "bwrap", *root.arguments, "--chdir", SANDBOX_BOX]


def _environment(home: str, temporary: str) -> dict[str, str]:
    return {
        "PATH": "/usr/bin:/bin",
        "LANG": "C.UTF-8",
        "HOME": home,
        "TMPDIR": temporary,
        "PYTHONDONTWRITEBYTECODE": "1",
        "PYTHONNOUSERSITE": "1",
        "PYTHONHASHSEED": "0",
    }


def _limit(
    limits: Limits, drop_to: int | None, processes: bool = True
) -> Callable[[], None] | None:
    """What the child runs before the program on POSIX: the limits of ``resource`` that
    this system has (RLIMIT_NPROC only with ``processes``: it counts every process of the
    user), then the drop to user ``drop_to``, then on Linux its death with this process
    (PR_SET_PDEATHSIG). Without a drop, a limit the system refuses
    is left out (macOS refuses some RLIMIT_AS values). None where there is no
    ``resource`` (Windows): the wall-clock limit alone applies there."""
    try:
        import resource
    except ImportError:
        resource = None  # type: ignore[assignment]
    prctl = None
    if sys.platform.startswith("linux"):
        import ctypes

        prctl = ctypes.CDLL(None, use_errno=True).prctl
    if resource is None and drop_to is None and prctl is None:
        return None
    memory, files = limits.memory_mb << 20, limits.file_mb << 20
    wanted = [
        ("RLIMIT_CPU", limits.cpu_seconds, limits.cpu_seconds + 1),
        ("RLIMIT_AS", memory, memory),
        ("RLIMIT_FSIZE", files, files),
        ("RLIMIT_NOFILE", 256, 256),
        ("RLIMIT_CORE", 0, 0),
    ]
    if processes:
        wanted.append(("RLIMIT_NPROC", limits.processes, limits.processes))

    def apply() -> None:
        for name, soft, hard in wanted if resource is not None else []:
            kind = getattr(resource, name, None)
            if kind is None:
                continue
            try:
                resource.setrlimit(kind, (soft, hard))
            except (ValueError, OSError):
                if drop_to is not None:
                    raise
        if drop_to is not None:
            os.setgroups([])
            os.setgid(drop_to)
            os.setuid(drop_to)
        if prctl is not None:  # killed with this process (after the drop, which resets it)
            prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG

    return apply


def uid_processes(uid: int) -> list[int]:
    """The ids of the processes running as ``uid`` now (Linux's /proc; none elsewhere)."""
    found: list[int] = []
    if not Path("/proc/self").is_dir():
        return found
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit():
            try:
                if entry.stat().st_uid == uid:
                    found.append(int(entry.name))
            except OSError:
                continue
    return found


def _kill_uid(uid: int) -> None:
    """SIGKILL every process still running as ``uid`` (a sandbox's own user id) until none
    is left (they may still be forking while the first ones die)."""
    for _ in range(500):
        pids = uid_processes(uid)
        if not pids:
            return
        for pid in pids:
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                continue
        time.sleep(0.01)


def _others_may_run(path: Path) -> bool:
    try:
        return all(os.stat(p).st_mode & 0o001 for p in path.parents) and bool(
            os.stat(path).st_mode & 0o001
        )
    except OSError:
        return False


def user_interpreter() -> Path:
    """An interpreter another user may run (for the ``user`` mode)."""
    for candidate in (interpreter(), Path("/usr/bin/python3")):
        if candidate.is_file() and _others_may_run(candidate):
            return candidate
    raise SandboxError(
        "no Python interpreter that another user may run: install Debian's "
        "python3, or bubblewrap (Debian package 'bubblewrap')"
    )


class Sandboxed:
    """``argv`` running in the sandbox (started at once), with ``box`` (a folder of
    :func:`new_box`) as its run folder. The one place it may write is its scratch
    (:mod:`.scratch`): ``box/scratch``, made with ``box/`` (its working folder, holding
    ``files``: name -> bytes) and ``tmp/`` (its temporary folder) at the start, at most
    :data:`~.scratch.SCRATCH_MB` MiB and :data:`~.scratch.SCRATCH_FILES` files and
    folders. With ``pipe``, its stdin and stdout are pipes to this process
    (``process.stdin`` and ``process.stdout``) and its errors are kept in memory (the last
    4000 bytes: :meth:`stderr_tail`); else its stdin is empty and its output and errors go
    to ``box/stdout.txt`` and ``box/stderr.txt``. A watchdog thread kills the run at the
    wall-clock limit, when it starts too many processes, or (a ``watched`` scratch) when
    its scratch holds more than the totals; :meth:`wait` ends it and says why."""

    def __init__(
        self,
        argv: list[str],
        box: Path,
        limits: Limits,
        pipe: bool = False,
        owner: int | None = None,
        lab_side: Path | None = None,
        files: Mapping[str, bytes] | None = None,
    ) -> None:
        mode = sandbox_mode()
        if mode != "bwrap" and not limits.unsandboxed:
            raise SandboxError(missing_sandbox())
        self.mode, self.limits, self.box = mode, limits, box.resolve()
        root = mode != "none" and _is_root()
        self.uid = sandbox_uid(owner) if root else -1
        self.root = root
        self.scratch = self.box / SCRATCH_FOLDER
        self.scratch.mkdir(mode=0o700)
        self.kind = scratch.scratch_kind(mode)
        files = dict(files or {})
        drop_to = self.uid if root else None
        made: Callable[[], None] | None = None
        if self.kind == "tmpfs":
            made = scratch.tmpfs_preexec(
                self.scratch,
                files,
                drop_to,
                user_namespace=mode == "bwrap" and not root,
                read_only_host=mode == "user",
            )
        else:
            scratch.prepare_watched(self.scratch, files, drop_to)
        if mode == "user":  # the dropped user reaches its scratch and the run's own files
            self.box.chmod(0o711)
            self.scratch.chmod(0o711)
        if mode == "bwrap":
            env = _environment(SANDBOX_BOX, "/tmp")
            command = [
                *bwrap_arguments(self.scratch, lab_side),
                "--unshare-ipc",
                "--unshare-pid",
                "--unshare-net",
                "--unshare-uts",
                "--unshare-cgroup-try",
                "--die-with-parent",
                "--new-session",
                "--clearenv",
            ]
            for key, value in env.items():
                command += ["--setenv", key, value]
            if root:
                command += [
                    "--cap-add",
                    "CAP_SETUID",
                    "--cap-add",
                    "CAP_SETGID",
                    "--",
                    "setpriv",
                    f"--reuid={self.uid}",
                    f"--regid={self.uid}",
                    "--clear-groups",
                    "--inh-caps=-all",
                    "--bounding-set=-all",
                ]
            else:
                command += ["--unshare-user", "--"]
            command += argv
            limit = _limit(limits, None)
        elif mode == "user":
            env = _environment(str(self.scratch / scratch.BOX), str(self.scratch / scratch.TMP))
            command = argv
            limit = _limit(limits, self.uid)
        else:
            env = _environment(str(self.scratch / scratch.BOX), str(self.scratch / scratch.TMP))
            if sys.platform == "win32":  # what Python and Windows need to start at all
                env = {
                    **env,
                    "PATH": os.environ.get("PATH", ""),
                    **{k: os.environ[k] for k in ("SYSTEMROOT", "TEMP", "TMP") if k in os.environ},
                }
            command = argv
            limit = _limit(limits, None, processes=False)
        self.started = time.perf_counter()
        self.stopped = ""
        self._done = threading.Event()
        self._errors = bytearray()
        try:
            self.process = self._start(command, env, pipe, made, limit)
        except subprocess.SubprocessError as exc:
            if self.kind != "tmpfs":
                raise SandboxError(f"the run could not start ({mode} mode): {exc}") from None
            # the kernel refused the run's own file system: watched, from now on
            scratch.refuse(mode)
            self.kind = "watched"
            scratch.prepare_watched(self.scratch, files, drop_to)
            try:
                self.process = self._start(command, env, pipe, None, limit)
            except subprocess.SubprocessError as again:
                raise SandboxError(f"the run could not start ({mode} mode): {again}") from None
        self._drain: threading.Thread | None = None
        if pipe:
            self._drain = threading.Thread(target=self._keep_errors, daemon=True)
            self._drain.start()
        self._watchdog = threading.Thread(target=self._watch, daemon=True)
        self._watchdog.start()

    def _start(
        self,
        command: list[str],
        env: dict[str, str],
        pipe: bool,
        made: Callable[[], None] | None,
        limit: Callable[[], None] | None,
    ) -> subprocess.Popen:
        """The run's process, in a session (POSIX) or process group (Windows) of its own to
        be ended as one; ``made`` (the tmpfs scratch) then ``limit`` run in it first."""
        group: dict[str, Any]
        if sys.platform == "win32":
            group = {"creationflags": subprocess.CREATE_NEW_PROCESS_GROUP}
        else:
            group = {"start_new_session": True, "preexec_fn": _chain(made, limit)}
        workdir = self.box if made is not None else self.scratch / scratch.BOX
        with (
            open(os.devnull if pipe else self.box / "stderr.txt", "wb") as err,
            open(os.devnull if pipe else self.box / "stdout.txt", "wb") as out,
        ):
            return subprocess.Popen(
                command,
                stdin=subprocess.PIPE if pipe else subprocess.DEVNULL,
                stdout=subprocess.PIPE if pipe else out,
                stderr=subprocess.PIPE if pipe else err,
                cwd=workdir,
                env=env,
                **group,
            )

    def place(self, name: str) -> str:
        """Where the program sees ``name`` of its working folder (one of ``files``)."""
        if self.mode == "bwrap":
            return f"{SANDBOX_BOX}/{name}"
        return str(self.scratch / scratch.BOX / name)

    def _keep_errors(self) -> None:
        stream = self.process.stderr
        assert stream is not None
        while True:
            try:
                chunk = os.read(stream.fileno(), 1 << 16)
            except OSError:
                break
            if not chunk:
                break
            self._errors += chunk
            del self._errors[: max(0, len(self._errors) - STDERR_KEPT)]

    def stderr_tail(self) -> str:
        """The last bytes of what the program wrote to its errors, as text ('' if none);
        with ``pipe``, once :meth:`wait` has returned."""
        if self._drain is None:
            return tail(self.box / "stderr.txt")
        return bytes(self._errors).decode(errors="replace")

    def _watch(self) -> None:
        watched = self.kind == "watched"
        while not self._done.wait(scratch.WATCH_SECONDS):
            if self.process.poll() is not None:
                return
            if self.root and len(uid_processes(self.uid)) > MAX_PROCESSES:
                self.kill("processes")
            elif time.perf_counter() - self.started > self.limits.seconds:
                self.kill("wall")
            elif watched and scratch.over(self.scratch):
                self.kill("scratch")

    def kill(self, why: str = "checker") -> None:
        """Stop the run now (``why`` is kept for :meth:`wait`)."""
        if not self.stopped:
            self.stopped = why
        if self.process.poll() is not None and not hasattr(os, "killpg"):
            return
        try:
            if hasattr(os, "killpg"):
                os.killpg(self.process.pid, signal.SIGKILL)
            else:  # Windows: the process and what it started
                subprocess.run(
                    ["taskkill", "/F", "/T", "/PID", str(self.process.pid)],
                    capture_output=True,
                    timeout=30,
                )
                self.process.kill()
        except (OSError, subprocess.TimeoutExpired):
            pass

    def wait(self, timeout: float | None = None) -> tuple[int | None, float, str]:
        """(exit code, or None when stopped; seconds; why it was stopped: ``""``,
        ``"wall"``, ``"processes"``, ``"scratch"`` or ``"checker"``). Kills what is
        left."""
        try:
            code: int | None = self.process.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            self.kill()
            code = self.process.wait()
        self._done.set()
        self._watchdog.join()
        if self._drain is not None:
            self._drain.join(timeout=10)
        if self.root:
            _kill_uid(self.uid)
        if self.stopped in ("wall", "processes", "scratch"):
            code = None
        return code, time.perf_counter() - self.started, self.stopped


def _chain(*steps: Callable[[], None] | None) -> Callable[[], None] | None:
    """One function running each of ``steps`` that is given, in order (None: none)."""
    given = [step for step in steps if step is not None]
    if not given:
        return None

    def run() -> None:  # pragma: no cover - runs in the child before it starts
        for step in given:
            step()

    return run


def run_sandboxed(argv: list[str], box: Path, limits: Limits) -> tuple[int | None, float, str]:
    """Run ``argv`` in the sandbox to its end (see :class:`Sandboxed`)."""
    return Sandboxed(argv, box, limits).wait()


def tail(path: Path, limit: int = 4000) -> str:
    """The last ``limit`` bytes of a file the sandbox wrote, as text ('' if none)."""
    try:
        with open(path, "rb") as stream:
            stream.seek(max(0, path.stat().st_size - limit))
            return stream.read().decode(errors="replace")
    except OSError:
        return ""


STALE_PREFIXES = (BOX_PREFIX, "mirrorlab-check-")
"""Temporary folders named ``PREFIX<pid>-...`` that a killed process may leave."""


def _stale(folder: Path, prefix: str) -> bool:
    """Whether a folder was left by a process that has died (a killed worker)."""
    try:
        pid = int(folder.name[len(prefix) :].split("-")[0])
    except ValueError:
        return False
    return pid != os.getpid() and not _alive(pid)


def _alive(pid: int) -> bool:
    """Whether process ``pid`` exists (one we may not see counts as alive). On Windows,
    os.kill(pid, 0) would end it: the process is asked for its exit code instead."""
    if sys.platform == "win32":
        import _winapi

        try:
            handle = _winapi.OpenProcess(0x1000, False, pid)  # QUERY_LIMITED_INFORMATION
        except PermissionError:
            return True
        except OSError:
            return False
        try:
            return _winapi.GetExitCodeProcess(handle) == 259  # STILL_ACTIVE
        finally:
            _winapi.CloseHandle(handle)
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        return True
    return True


def sweep_stale(parent: Path) -> None:
    """Remove the boxes and check folders that dead processes left in ``parent`` (with the
    system's own tool, however deep a tree a run left there: :func:`~.scratch.discard`)."""
    for prefix in STALE_PREFIXES:
        for folder in parent.glob(f"{prefix}*"):
            if folder.is_dir() and _stale(folder, prefix):
                scratch.discard(folder)


def remove_box(box: Path) -> None:
    """Remove a run folder of :func:`new_box` after its run (see :func:`sweep_stale`)."""
    scratch.discard(box)


def new_box(root: Path | None = None) -> Path:
    """A fresh, empty folder for one run (under ``root``, default the system's temp),
    mode 0700; what dead processes left there is removed first."""
    parent = root if root is not None else Path(tempfile.gettempdir())
    parent.mkdir(parents=True, exist_ok=True)
    sweep_stale(parent)
    return Path(tempfile.mkdtemp(prefix=f"{BOX_PREFIX}{os.getpid()}-", dir=parent))
