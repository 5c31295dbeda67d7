"""Running a student's file where it can harm nothing: its own process, a time limit, a
memory limit, a process limit, its own scratch folder and no way to write outside it.

How, in order of preference (:func:`sandbox_mode` says which applies):

- ``bwrap``: bubblewrap (Debian ``bubblewrap``) mounts the whole file system read-only,
  gives the run an empty ``/tmp`` of its own, binds only the submission's box writable,
  and unshares the network, the process ids, IPC and the host name. Run as root, the
  student's process then drops to a user id of its own (``setpriv``), so that the process
  limit counts its processes alone; folders the interpreter lives in that other users may
  not enter (such as ``/root``) are replaced by an empty folder holding only the
  interpreter.
- ``user`` (root, no working bubblewrap): the same limits, the process running under a
  user id of its own, which may write only in its box (and world-writable places).
- Without bubblewrap and without root there is no way to keep the code from writing where
  the user may, and :func:`run_sandboxed` refuses (:class:`SandboxError`).

Limits (:class:`Limits`): CPU seconds (RLIMIT_CPU: an endless loop ends there, however
busy the machine), wall-clock seconds (for code that waits forever; the whole process tree
is killed then), address space (RLIMIT_AS), threads and processes (RLIMIT_NPROC), file
size and open files. Run as root, a run that starts more than :data:`MAX_PROCESSES`
processes (a fork bomb) is stopped at once.
"""

from __future__ import annotations

import json
import os
import resource
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path
from typing import Any

from mirrorlab.paths import REPO_DIR

UID_BASE = 200_000
"""Sandboxed processes run as UID_BASE + the id of the process that started them, so that
two gradings running at once never share a user id (nor its process limit)."""

MAX_PROCESSES = 8
"""Processes a run may have at once (a lab's harness needs one; threads are not counted)."""

MAX_RUN_JSON = 4 << 20
MAX_OBSERVATIONS = 64 << 20


class SandboxError(RuntimeError):
    """No safe way to run untrusted code here; the message says what to install."""


@dataclass(frozen=True)
class Limits:
    """What one submission may use: ``cpu_seconds`` of CPU time, ``seconds`` of wall-clock
    time, ``memory_mb`` of address space, ``processes`` (RLIMIT_NPROC: threads count too),
    ``file_mb`` per file written."""

    cpu_seconds: int = 20
    seconds: float = 120.0
    memory_mb: int = 1536
    processes: int = 64
    file_mb: int = 64


@dataclass
class SandboxResult:
    """How a sandboxed run ended: ``status`` is ``ok`` (the harness wrote its files),
    ``timeout``, ``memory`` or ``crashed``; ``detail`` one line for a person."""

    status: str
    detail: str
    seconds: float
    returncode: int | None
    out_dir: Path
    mode: str


def _bwrap_works() -> bool:
    bwrap = shutil.which("bwrap")
    if bwrap is None:
        return False
    try:
        done = subprocess.run([bwrap, "--ro-bind", "/", "/", "--dev", "/dev", "--unshare-pid",
                               "--unshare-net", "--die-with-parent", "true"],
                              capture_output=True, timeout=30)
    except (OSError, subprocess.TimeoutExpired):
        return False
    return done.returncode == 0


@lru_cache(maxsize=1)
def sandbox_mode() -> str:
    """``bwrap``, ``user`` or ``none`` (see the module's text); MIRRORLAB_SANDBOX may ask
    for ``user`` (to test it) but never for less than this machine can do."""
    root = os.geteuid() == 0
    wanted = os.environ.get("MIRRORLAB_SANDBOX", "")
    if wanted == "user" and root:
        return "user"
    if _bwrap_works():
        return "bwrap"
    return "user" if root else "none"


def sandbox_uid() -> int:
    return UID_BASE + os.getpid()


def _hidden_ancestor(path: Path) -> Path | None:
    """The highest folder above ``path`` that other users may not enter, if any."""
    hidden = None
    for parent in reversed(path.parents):
        try:
            if not os.stat(parent).st_mode & 0o001:
                return parent
        except OSError:
            return hidden
    return hidden


def _reachable_binds() -> list[str]:
    """bwrap arguments (after the private /tmp) that show the interpreter, the virtual
    environment and mirrorlab to the sandbox, read-only: where a folder above them is
    closed to other users (such as /root), an empty folder replaces it first; each is
    bound again in any case, since it may live under /tmp (a fresh clone there)."""
    needed = sorted({Path(sys.base_prefix).resolve(), Path(sys.prefix).resolve(),
                     REPO_DIR.resolve(), Path(sys.executable).resolve().parent})
    hidden = sorted({h for h in map(_hidden_ancestor, needed) if h is not None})
    arguments: list[str] = []
    for folder in hidden:
        arguments += ["--perms", "0755", "--tmpfs", str(folder)]
    for path in needed:
        arguments += ["--ro-bind", str(path), str(path)]
    return arguments


def _environment(box: Path) -> dict[str, str]:
    keep = {key: os.environ[key] for key in ("PATH", "LANG", "LC_ALL") if key in os.environ}
    return {**keep, "HOME": str(box), "TMPDIR": "/tmp", "PYTHONDONTWRITEBYTECODE": "1",
            "PYTHONNOUSERSITE": "1", "PYOPENGL_PLATFORM": "egl",
            "EGL_PLATFORM": "surfaceless", "MPLCONFIGDIR": str(box / ".matplotlib")}


def _limit(limits: Limits, drop_to: int | None):
    def apply() -> None:
        memory = limits.memory_mb << 20
        resource.setrlimit(resource.RLIMIT_CPU, (limits.cpu_seconds, limits.cpu_seconds + 1))
        for kind, value in ((resource.RLIMIT_AS, memory),
                            (resource.RLIMIT_NPROC, limits.processes),
                            (resource.RLIMIT_FSIZE, limits.file_mb << 20),
                            (resource.RLIMIT_NOFILE, 256), (resource.RLIMIT_CORE, 0)):
            resource.setrlimit(kind, (value, value))
        if drop_to is not None:
            os.setgroups([])
            os.setgid(drop_to)
            os.setuid(drop_to)

    return apply


def uid_processes(uid: int) -> list[int]:
    """The ids of the processes running as ``uid`` now."""
    found = []
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


def run_sandboxed(argv: list[str], box: Path, limits: Limits) -> tuple[int | None, float, str]:
    """Run ``argv`` in the sandbox with ``box`` (a folder) as its only writable place and
    working folder. Returns (exit code, or None when stopped; seconds; why it was stopped:
    ``""``, ``"wall"`` or ``"processes"``). Output goes to ``box/stdout.txt`` and
    ``box/stderr.txt``."""
    mode = sandbox_mode()
    if mode == "none":
        raise SandboxError(
            "cannot run untrusted code safely here: install bubblewrap (Debian package "
            "'bubblewrap'; ./dev setup does) or run the checker as root")
    root = os.geteuid() == 0
    uid = sandbox_uid() if root else os.getuid()
    box = box.resolve()
    if root:
        for path in [box, *box.rglob("*")]:
            os.chown(path, uid, uid)
    env = _environment(box)
    if mode == "bwrap":
        command = ["bwrap", "--ro-bind", "/", "/", "--dev", "/dev", "--proc", "/proc",
                   "--size", str(64 << 20), "--tmpfs", "/tmp", *_reachable_binds(),
                   "--bind", str(box), str(box), "--chdir", str(box),
                   "--unshare-ipc", "--unshare-pid", "--unshare-net", "--unshare-uts",
                   "--unshare-cgroup-try", "--die-with-parent", "--new-session",
                   "--clearenv"]
        for key, value in env.items():
            command += ["--setenv", key, value]
        if root:
            command += ["--cap-add", "CAP_SETUID", "--cap-add", "CAP_SETGID", "--",
                        "setpriv", f"--reuid={uid}", f"--regid={uid}", "--clear-groups",
                        "--inh-caps=-all", "--bounding-set=-all"]
        else:
            command += ["--unshare-user", "--"]
        command += argv
        preexec = _limit(limits, None)
    else:
        command = argv
        preexec = _limit(limits, uid)
    started = time.perf_counter()
    with open(box / "stdout.txt", "wb") as out, open(box / "stderr.txt", "wb") as err:
        process = subprocess.Popen(command, stdin=subprocess.DEVNULL, stdout=out, stderr=err,
                                   cwd=box, env=env, preexec_fn=preexec,
                                   start_new_session=True)
        stopped = ""
        code: int | None = None
        try:
            while True:
                try:
                    code = process.wait(timeout=0.05)
                    break
                except subprocess.TimeoutExpired:
                    pass
                if root and len(uid_processes(uid)) > MAX_PROCESSES:
                    stopped = "processes"
                elif time.perf_counter() - started > limits.seconds:
                    stopped = "wall"
                if stopped:
                    os.killpg(process.pid, signal.SIGKILL)
                    process.wait()
                    code = None
                    break
        finally:
            if root:
                _kill_uid(uid)
    return code, time.perf_counter() - started, stopped


def _tail(path: Path, limit: int = 4000) -> str:
    try:
        with open(path, "rb") as stream:
            stream.seek(max(0, path.stat().st_size - limit))
            return stream.read().decode(errors="replace")
    except OSError:
        return ""


def run_harness(lab: str, file: Path, box: Path, limits: Limits,
                size: tuple[int, int] = (256, 256)) -> SandboxResult:
    """Run the student's ``file`` for ``lab`` through :mod:`mirrorlab.labs.harness` in the
    sandbox, in the new folder ``box`` (the file is copied into ``box/work``)."""
    work, out = box / "work", box / "out"
    work.mkdir(parents=True)
    out.mkdir()
    student = work / "submission.py"
    try:
        shutil.copyfile(file, student)
    except OSError as exc:
        return SandboxResult("crashed", f"cannot read {file}: {exc.strerror}", 0.0, None, out,
                             sandbox_mode())
    argv = [sys.executable, "-I", "-m", "mirrorlab.labs.harness", lab, str(student),
            str(out), "--size", f"{size[0]}x{size[1]}"]
    code, seconds, stopped = run_sandboxed(argv, box, limits)
    mode = sandbox_mode()
    if stopped == "wall":
        return SandboxResult("timeout", f"stopped after {limits.seconds:g} s of waiting (the "
                             f"wall-clock limit)", seconds, None, out, mode)
    if stopped == "processes":
        return SandboxResult("processes", f"stopped when it started more than {MAX_PROCESSES} "
                             f"processes (a fork bomb?)", seconds, None, out, mode)
    if code in (-signal.SIGXCPU, 128 + signal.SIGXCPU):
        return SandboxResult("timeout", f"stopped at the CPU-time limit of "
                             f"{limits.cpu_seconds} s (an endless loop?)", seconds, code, out,
                             mode)
    stderr = _tail(box / "stderr.txt")
    run_json = out / "run.json"
    if code == 0 and run_json.is_file():
        return SandboxResult("ok", "", seconds, code, out, mode)
    last = next((line for line in reversed(stderr.strip().splitlines()) if line.strip()), "")
    if "MemoryError" in stderr or "Cannot allocate memory" in stderr:
        return SandboxResult("memory", f"stopped at the memory limit of {limits.memory_mb} MB",
                             seconds, code, out, mode)
    died = -code if code is not None and code < 0 else (code - 128 if code and code > 128
                                                          else 0)
    if died:
        try:
            name = signal.Signals(died).name
        except ValueError:
            name = f"signal {died}"
        detail = f"the program died ({name})"
    else:
        detail = f"the program stopped with exit status {code}"
    if last:
        detail += f": {last.strip()[:200]}"
    return SandboxResult("crashed", detail, seconds, code, out, mode)


def read_outputs(out: Path) -> tuple[dict[str, Any], dict[str, Any]]:
    """``run.json`` and the arrays of ``observations.npz`` a harness wrote, read as data
    (no pickles; sizes bounded). ValueError when they are missing or malformed."""
    import numpy as np

    run_json, npz = out / "run.json", out / "observations.npz"
    for path, limit in ((run_json, MAX_RUN_JSON), (npz, MAX_OBSERVATIONS)):
        if not path.is_file() or path.stat().st_size > limit:
            raise ValueError(f"the run left no readable {path.name}")
    run = json.loads(run_json.read_text())
    if not isinstance(run, dict):
        raise ValueError("run.json is not an object")
    with np.load(npz, allow_pickle=False) as data:
        arrays = {key: data[key] for key in data.files}
    return run, arrays


def new_box(root: Path | None = None) -> Path:
    """A fresh, empty folder for one run (under ``root``, default the system's temp)."""
    if root is not None:
        root.mkdir(parents=True, exist_ok=True)
    return Path(tempfile.mkdtemp(prefix="mirrorlab-box-", dir=root))
