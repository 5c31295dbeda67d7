"""The trusted checker's GL process: one lab file run and observed, its evidence written.

``python -m mirrorlab.labs.trusted.execute JOB.json`` opens a headless context, the lab's
session for the job's variant, runs the file through :class:`~.run.LabRun` (the file
itself in the sandbox) and writes ``evidence.json`` and ``arrays.npz`` into the job's
output folder. It is a process of its own so that the command or grading worker that
asked can stop it at a deadline whatever the student's GLSL does to the driver
(:func:`run_job`), and so that its memory is its own.
"""

from __future__ import annotations

import json
import os
import resource
import signal
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

from mirrorlab.labs.trusted.evidence import Evidence
from mirrorlab.labs.trusted.sandbox import Limits, SandboxError
from mirrorlab.labs.trusted.variants import Variant

EXIT_SANDBOX = 3
MEMORY_MB = 3072
"""The GL process's own address-space limit (Mesa's threads reserve much more than they
touch; its resident memory is measured in the tests)."""


class CheckerError(RuntimeError):
    """The checker's own process failed: a fault of the machine or of mirrorlab."""


def peak_kib() -> int:
    """This process's peak resident memory (VmHWM), KiB."""
    try:
        status = Path("/proc/self/status").read_text()
        return int(status.split("VmHWM:")[1].split()[0])
    except (OSError, IndexError, ValueError):
        return 0


def execute(job: dict[str, Any]) -> Evidence:
    """Run ``job`` in this process (which must not have loaded OpenGL for a window)."""
    from mirrorlab.gl.context import HeadlessContext, use_platform

    use_platform("egl")
    from mirrorlab.gl.resources import Framebuffer
    from mirrorlab.labs import find_lab
    from mirrorlab.labs.trusted.kit import open_session
    from mirrorlab.labs.trusted.run import LabRun

    spec = find_lab(job["lab"])
    size = (int(job["size"][0]), int(job["size"][1]))
    variant = Variant(spec.name, dict(job["variant"]["values"]), job["variant"]["id"],
                      job["variant"].get("student", ""))
    limits = Limits(**job["limits"])
    source = Path(job["file"]).read_bytes()
    context = HeadlessContext()
    try:
        target = Framebuffer(context.resources, *size)
        target.bind()
        session = open_session(spec.name, size, variant)
        with LabRun(spec, session, source, job["name"], limits,
                    registry=context.resources, owner=job.get("owner")) as run:
            evidence = run.check()
    finally:
        context.release()
    evidence.state["checker_peak_kib"] = peak_kib()
    return evidence


def main(argv: list[str]) -> int:
    job = json.loads(Path(argv[0]).read_text())
    out = Path(job["out"])
    try:
        evidence = execute(job)
    except SandboxError as exc:
        (out / "sandbox_error.txt").write_text(str(exc))
        return EXIT_SANDBOX
    evidence.save(out)
    return 0


def _child_setup() -> None:
    """The GL process's own memory limit, and its end when the process that asked for it
    dies (a killed grading worker leaves no checker running)."""
    memory = MEMORY_MB << 20
    resource.setrlimit(resource.RLIMIT_AS, (memory, memory))
    try:
        import ctypes

        ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
    except (OSError, AttributeError):
        pass


def run_job(lab: str, source: bytes, file_name: str, variant: Variant, limits: Limits,
            size: tuple[int, int]) -> Evidence:
    """Run ``source`` (the student's file, called ``file_name``) through ``lab`` for
    ``variant`` in a checker process of its own, which is stopped if it outlives the
    run's own limits; SandboxError when the sandbox cannot start, CheckerError when the
    checker's process fails."""
    from mirrorlab.labs.trusted.sandbox import sweep_stale

    sweep_stale(Path(tempfile.gettempdir()))
    with tempfile.TemporaryDirectory(prefix=f"mirrorlab-check-{os.getpid()}-") as folder:
        base = Path(folder)
        (base / "source.py").write_bytes(source)
        out = base / "out"
        out.mkdir()
        job = {"lab": lab, "file": str(base / "source.py"), "name": file_name,
               "variant": variant.plain(), "size": list(size), "out": str(out),
               "owner": os.getpid(),
               "limits": {"cpu_seconds": limits.cpu_seconds, "seconds": limits.seconds,
                          "memory_mb": limits.memory_mb, "processes": limits.processes,
                          "file_mb": limits.file_mb}}
        (base / "job.json").write_text(json.dumps(job))
        env = {**os.environ, "PYOPENGL_PLATFORM": "egl", "EGL_PLATFORM": "surfaceless"}
        try:
            done = subprocess.run(
                [sys.executable, "-m", "mirrorlab.labs.trusted.execute",
                 str(base / "job.json")], capture_output=True, text=True, env=env,
                timeout=limits.seconds + 60, preexec_fn=_child_setup)
        except subprocess.TimeoutExpired:
            return Evidence(lab, "timeout", f"stopped after {limits.seconds + 60:g} s: the "
                            f"calls took too long to draw", variant=variant.plain())
        if done.returncode == EXIT_SANDBOX:
            raise SandboxError((out / "sandbox_error.txt").read_text().strip())
        if done.returncode != 0:
            lines = [line for line in done.stderr.strip().splitlines() if line.strip()]
            last = lines[-1] if lines else f"exit status {done.returncode}"
            if done.returncode < 0:
                last = f"it died ({-done.returncode}); {last}"
            raise CheckerError(f"the checker's OpenGL process failed: {last[:300]}")
        return Evidence.load(out)


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
