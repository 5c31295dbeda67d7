"""The trusted checker's GL process: one lab file run and observed, its evidence written.

``python -m mirrorlab.labs.trusted.gl_process JOB.json`` opens a headless context, the lab's
session for the job's variant, runs the file through :class:`~.lab_run.LabRun` (the file
itself in the sandbox) and writes ``evidence.json`` and ``arrays.npz`` into the job's
output folder. It is a process of its own so that the command or grading worker that
asked can stop it at a deadline whatever the student's GLSL does to the driver
(:func:`run_job`), and so that its memory is its own.
"""

from __future__ import annotations

import dataclasses
import errno
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import TYPE_CHECKING, Any

from mirrorlab.labs import LabSpec
from mirrorlab.labs.trusted.evidence import Evidence
from mirrorlab.labs.trusted.pipe import wait_readable
from mirrorlab.labs.trusted.sandbox import Limits, SandboxError
from mirrorlab.labs.trusted.variants import Variant

if TYPE_CHECKING:
    from mirrorlab.labs.trusted.prepared import PreparedRun

EXIT_SANDBOX, EXIT_FAILED, EXIT_NO_GL, EXIT_MACHINE = 3, 4, 5, 6
"""The GL process's exit statuses for a job: its sandbox could not start; it failed while
running the file (the file's calls or the checker: :mod:`.failures` tells them apart);
it could not make an OpenGL context; its own machine failed it (a full disk)."""
MEMORY_MB = 3072
"""The GL process's own address-space limit (Mesa's threads reserve much more than they
touch; its resident memory is measured in the tests)."""


DISK_ERRORS = frozenset(
    getattr(errno, name)
    for name in ("ENOSPC", "EDQUOT", "EROFS", "EIO", "EFBIG")
    if hasattr(errno, name)
)
"""The errors of a disk that refuses the checker's own files: the machine's, whatever the
file ran (a full disk, a quota, a read-only or failing one)."""


class CheckerError(RuntimeError):
    """The checker's OpenGL process failed while it ran a file: the file's calls may have
    crashed it, or the checker or the machine failed (:mod:`.failures` tells them
    apart)."""


class MachineError(CheckerError):
    """The checker's machine failed it, whatever the file: its disk is full or will not
    take the check's files. Never a grade."""


def peak_kib() -> int:
    """This process's peak resident memory, KiB: Linux's VmHWM (ru_maxrss there would count
    what the parent held before the exec), else ru_maxrss (bytes on macOS); 0 where the
    system does not say (Windows)."""
    status = Path("/proc/self/status")
    if status.is_file():
        try:
            return int(status.read_text().split("VmHWM:")[1].split()[0])
        except (OSError, IndexError, ValueError):
            return 0
    try:
        import resource
    except ImportError:
        return 0
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
    return peak // 1024 if sys.platform == "darwin" else peak


def execute(job: dict[str, Any], prepared: PreparedRun | None = None) -> Evidence:
    """Run ``job`` in this process (which must not have loaded OpenGL for a window): in
    ``prepared`` (a run prepared for a job like it, its runner still without a file), else
    in a run prepared now, whose runner starts first and loads while this process loads
    OpenGL, makes its context and opens the lab's session."""
    from mirrorlab.labs.trusted.prepared import PreparedRun

    source = Path(job["file"]).read_bytes()
    # GLContextError: no OpenGL here (run_one says so)
    run_in = prepared if prepared is not None else PreparedRun(job, source)
    try:
        from mirrorlab.labs.trusted.lab_run import LabRun

        with LabRun(
            run_in.spec,
            run_in.session,
            source,
            job["name"],
            run_in.limits,
            registry=run_in.resources,
            owner=job.get("owner"),
            runner=run_in.take_runner(),
        ) as run:
            evidence = run.check()
    finally:
        run_in.release()
    evidence.state["checker_peak_kib"] = peak_kib()
    return evidence


def _note(path: Path, text: str) -> None:
    """Why a job failed, for the process that asked (nothing when even that cannot be
    written: the exit status says enough)."""
    try:
        path.write_text(text)
    except OSError:
        pass


def run_one(job_file: Path, prepared: PreparedRun | None = None) -> int:
    """Run the job in ``job_file`` (in ``prepared`` when it was prepared for a job like it;
    it is released either way); its evidence (or why not) goes to the job's folder.
    Returns the process's exit status for it: 0, or one of :data:`EXIT_SANDBOX`,
    :data:`EXIT_NO_GL` and :data:`EXIT_MACHINE` (the machine's failures, told before any
    of the file's calls or after all of them), or :data:`EXIT_FAILED` (raised in
    between)."""
    from mirrorlab.errors import GLContextError

    try:
        job = json.loads(job_file.read_text())
    except OSError as exc:
        if prepared is not None:
            prepared.release()
        return EXIT_MACHINE if exc.errno is not None else EXIT_FAILED
    except BaseException:
        if prepared is not None:
            prepared.release()
        raise
    if prepared is not None and not prepared.fits(job):
        prepared.release()
        prepared = None
    out = Path(job["out"])
    try:
        evidence = execute(job, prepared)
    except SandboxError as exc:
        _note(out / "sandbox_error.txt", str(exc))
        return EXIT_SANDBOX
    except GLContextError as exc:
        _note(out / "no_gl.txt", str(exc))
        return EXIT_NO_GL
    except OSError as exc:
        if exc.errno not in DISK_ERRORS:
            raise  # attributed by a second run and a control (failures.py)
        # the file's own failures are evidence; a disk that refuses the checker's is not
        _note(out / "machine_error.txt", f"{exc.strerror or exc} ({exc.filename or 'a file'})")
        return EXIT_MACHINE
    try:
        evidence.save(out, compress=False)
    except OSError as exc:
        _note(out / "machine_error.txt", f"cannot write its evidence: {exc.strerror or exc}")
        return EXIT_MACHINE
    return 0


def serve(prepare: bool = False) -> int:
    """Run the jobs whose files come one a line on stdin, one after another, each in a
    context of its own; after each, its exit status on stdout (whatever else would be
    written there, by Python or a library, goes to stderr). With ``prepare``, the next
    run is prepared as soon as a job's status is written, for a job like the last one
    (:class:`~.prepared.PreparedRun`: a new runner, context and session, which nothing of
    any job has touched). Each student GLSL text is still compiled and probed in a process
    of its own, started when the text arrives. The process is its parent's to stop
    (closing stdin ends it), so an interrupt from the terminal is left to the parent."""
    from mirrorlab.labs.trusted.prepared import prepare_like

    if hasattr(signal, "SIGINT"):
        signal.signal(signal.SIGINT, signal.SIG_IGN)
    reply_fd = os.dup(1)
    os.dup2(2, 1)
    prepared: PreparedRun | None = None
    try:
        for line in sys.stdin:
            job_file = Path(line.strip())
            try:  # read now: the asker removes the job's folder once it has the status
                job = json.loads(job_file.read_text())
            except (OSError, ValueError):
                job = None
            try:
                code = run_one(job_file, prepared)
            except Exception as exc:  # the job's own folder says what failed
                try:
                    job_out = Path(json.loads(job_file.read_text())["out"])
                    _note(job_out / "checker_error.txt", f"{type(exc).__name__}: {exc}")
                except (OSError, ValueError, KeyError):
                    pass
                code = EXIT_FAILED
            prepared = None
            os.write(reply_fd, f"{code}\n".encode())
            if prepare and job is not None:
                prepared = prepare_like(job)
    finally:
        if prepared is not None:
            prepared.release()
    return 0


def main(argv: list[str]) -> int:
    if argv[0] == "--serve":
        return serve(prepare="--prepare" in argv[1:])
    code = run_one(Path(argv[0]))
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)  # the evidence is written: nothing to wait for in the interpreter's end


def child_options(
    memory_mb: int,
    cpu_seconds: int | None = None,
    cores: bool = True,
    die_with_parent: bool = False,
) -> dict[str, Any]:
    """Popen's arguments that limit a trusted helper process (the checker's GL process, the
    GLSL check's): where the system has ``resource``, its address space (``memory_mb``), its
    CPU seconds (``cpu_seconds``, None: no limit) and, without ``cores``, no core file; with
    ``die_with_parent``, on Linux, its end when the process that started it dies (a killed
    grading worker leaves no checker running). A limit the system refuses (macOS refuses
    some RLIMIT_AS values) is left out. Empty where a child can run no code before it
    starts (Windows): its caller's wall-clock limit alone applies there."""
    if os.name != "posix":
        return {}

    def setup() -> None:  # pragma: no cover - runs in the child before it starts
        try:
            import resource
        except ImportError:
            resource = None  # type: ignore[assignment]
        if resource is not None:
            memory = memory_mb << 20
            wanted = [(resource.RLIMIT_AS, memory, memory)]
            if cpu_seconds is not None:
                wanted.append((resource.RLIMIT_CPU, cpu_seconds, cpu_seconds))
            if not cores:
                wanted.append((resource.RLIMIT_CORE, 0, 0))
            for kind, soft, hard in wanted:
                try:
                    resource.setrlimit(kind, (soft, hard))
                except (ValueError, OSError):
                    pass
        if die_with_parent and sys.platform.startswith("linux"):
            try:
                import ctypes

                ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
            except (OSError, AttributeError):
                pass

    return {"preexec_fn": setup}


def gl_process_environment() -> dict[str, str]:
    """The GL process's environment: its offscreen backend pinned to the one chosen here
    (the process sets its own PyOpenGL platform from it)."""
    from mirrorlab.gl.context import BACKEND_VARIABLE, choose

    backend = choose("offscreen", new_process=True).backend
    environ = {k: v for k, v in os.environ.items() if k != "PYOPENGL_PLATFORM"}
    surfaceless = {"EGL_PLATFORM": "surfaceless"} if backend == "egl" else {}
    return {**environ, BACKEND_VARIABLE: backend, **surfaceless}


class CheckerProcess:
    """A trusted GL process kept for many jobs, one at a time (a grading worker's): it
    saves each job the start of a process, its imports and its meshes. A job that
    outlives its deadline, or a process that dies, ends the process; the next job starts
    a new one, as does every :data:`JOBS_PER_PROCESS`-th."""

    SERVE: tuple[str, ...] = ("--serve",)
    """How the process is started (:func:`main`'s arguments)."""
    STDERR: int | None = None
    """Where what the process writes goes (None: this process's stderr)."""

    def __init__(self) -> None:
        self.process = subprocess.Popen(
            [sys.executable, "-m", "mirrorlab.labs.trusted.gl_process", *self.SERVE],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=self.STDERR,
            env=gl_process_environment(),
            **child_options(MEMORY_MB, die_with_parent=True),
        )
        assert self.process.stdout is not None
        self.reply_read = self.process.stdout.fileno()
        self.jobs = 0

    def alive(self) -> bool:
        return self.process.poll() is None and self.jobs < JOBS_PER_PROCESS

    def run(self, job_file: Path, timeout: float) -> int | None:
        """The job's exit status, or None when it did not end in ``timeout`` seconds (the
        process is then ended); CheckerError when the process died meanwhile."""
        self.jobs += 1
        try:
            assert self.process.stdin is not None
            self.process.stdin.write(f"{job_file}\n".encode())
            self.process.stdin.flush()
        except (BrokenPipeError, OSError):
            self.close()
            raise CheckerError("the checker's OpenGL process had ended before the job") from None
        ready = wait_readable(self.reply_read, timeout)
        line = os.read(self.reply_read, 64) if ready else b""
        if not line:
            died = self.process.poll() is not None
            self.close()
            if died:
                code = self.process.returncode
                how = f"signal {-code}" if code < 0 else f"exit status {code}"
                raise CheckerError(f"the checker's OpenGL process died ({how})")
            return None
        return int(line.split()[0])

    def close(self) -> None:
        if self.process.poll() is None:
            self.process.kill()
        self.process.wait()
        for stream in (self.process.stdin, self.process.stdout):
            if stream is not None:
                try:
                    stream.close()
                except OSError:
                    pass


JOBS_PER_PROCESS = 64
_kept: CheckerProcess | None = None


def kept_process() -> CheckerProcess:
    """This process's checker process (made, or made again, as needed)."""
    global _kept
    if _kept is None or not _kept.alive():
        if _kept is not None:
            _kept.close()
        _kept = CheckerProcess()
    return _kept


def run_job(
    spec: LabSpec,
    source: bytes,
    file_name: str,
    variant: Variant,
    limits: Limits,
    size: tuple[int, int],
    keep: bool = False,
    process: CheckerProcess | None = None,
) -> Evidence:
    """Run ``source`` (the student's file, called ``file_name``) through ``spec``'s lab for
    ``variant`` in a checker process of its own (with ``keep``, this process's kept one:
    see :class:`CheckerProcess`; or ``process``, the caller's), which is stopped if it
    outlives the run's own limits. Raises SandboxError when the sandbox cannot start,
    GLContextError (render's one line) when no OpenGL context can be made, MachineError
    when the machine fails the check (a full disk), CheckerError when the checker's
    process fails otherwise."""
    from mirrorlab.labs.trusted.sandbox import sweep_stale

    sweep_stale(Path(tempfile.gettempdir()))
    try:
        folder = tempfile.mkdtemp(prefix=f"mirrorlab-check-{os.getpid()}-")
    except OSError as exc:
        raise MachineError(
            f"cannot make the check's folder in {tempfile.gettempdir()}: {exc.strerror or exc}"
        ) from None
    try:
        return _run_in(Path(folder), spec, source, file_name, variant, limits, size, keep, process)
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def _run_in(
    base: Path,
    spec: LabSpec,
    source: bytes,
    file_name: str,
    variant: Variant,
    limits: Limits,
    size: tuple[int, int],
    keep: bool,
    process: CheckerProcess | None = None,
) -> Evidence:
    """:func:`run_job` in its folder ``base`` (the checker's own files only)."""
    from mirrorlab.errors import GLContextError

    out = base / "out"
    try:
        (base / "source.py").write_bytes(source)
        out.mkdir()
        job = {
            "lab": spec.name,
            "package": spec.package,
            "import_root": str(spec.import_root),
            "file": str(base / "source.py"),
            "name": file_name,
            "variant": variant.plain(),
            "size": list(size),
            "out": str(out),
            "owner": os.getpid(),
            "limits": dataclasses.asdict(limits),
        }
        job_file = base / "job.json"
        job_file.write_text(json.dumps(job))
    except OSError as exc:
        raise MachineError(
            f"cannot write the check's files in {base.parent}: {exc.strerror or exc}"
        ) from None
    deadline = limits.seconds + 60
    stderr = ""
    if process is not None or keep:
        code = (process or kept_process()).run(job_file, deadline)
    else:
        try:
            done = subprocess.run(
                [sys.executable, "-m", "mirrorlab.labs.trusted.gl_process", str(job_file)],
                capture_output=True,
                text=True,
                env=gl_process_environment(),
                timeout=deadline,
                **child_options(MEMORY_MB, die_with_parent=True),
            )
            code, stderr = done.returncode, done.stderr
        except subprocess.TimeoutExpired:
            code = None
    if code is None:
        return Evidence(
            spec.name,
            "timeout",
            f"stopped after {deadline:g} s: the calls took too long to draw",
            variant=variant.plain(),
        )

    def said(name: str, otherwise: str) -> str:
        try:
            return (out / name).read_text().strip()[:300] or otherwise
        except OSError:
            return otherwise

    if code == EXIT_SANDBOX:
        raise SandboxError(said("sandbox_error.txt", "the sandbox could not start"))
    if code == EXIT_NO_GL:
        raise GLContextError(said("no_gl.txt", "no OpenGL context for the checker"))
    if code == EXIT_MACHINE:
        raise MachineError(
            f"the checker's OpenGL process failed: {said('machine_error.txt', 'its disk')}"
        )
    if code != 0:
        lines = [line for line in stderr.strip().splitlines() if line.strip()]
        last = said("checker_error.txt", lines[-1] if lines else f"exit status {code}")
        if code < 0:
            last = f"it died ({-code}); {last}"
        raise CheckerError(f"the checker's OpenGL process failed: {last[:300]}")
    try:
        return Evidence.load(out)
    except ValueError as exc:
        raise MachineError(f"the checker's evidence could not be read back: {exc}") from None


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
