"""A run prepared before its file is read, in the checker's GL process: the runner
started in the sandbox, a context of its own and the lab's session (:class:`PreparedRun`).

A cold check prepares its run as it starts, the runner first, so that the runner loads
while the GL process loads OpenGL; the warm checker's process (:mod:`.warm`) prepares the
next run while it waits for the next save. Either way each run gets a new runner in a new
box and a new context, which nothing of any other run has touched.
"""

from __future__ import annotations

import json
from typing import Any

from mirrorlab.labs.trusted.runner import Runner, start_runner
from mirrorlab.labs.trusted.sandbox import Limits
from mirrorlab.labs.trusted.variants import Variant


def job_variant(job: dict[str, Any]) -> Variant:
    """The variant a job names."""
    plain = job["variant"]
    return Variant(job["lab"], dict(plain["values"]), plain["id"], plain.get("student", ""))


def _job_key(job: dict[str, Any]) -> str:
    """What a prepared run depends on: all of a job but its file, name and folder."""
    return json.dumps({k: v for k, v in job.items() if k not in ("file", "name", "out")})


class PreparedRun:
    """What one run of a job needs before its file is read: the lab, its runner started
    in the sandbox (with ``source`` in its box, or waiting for the file to come with the
    session), then a context of its own, its target and the lab's session for the job's
    variant and size. The runner starts first, so it loads while this process loads
    OpenGL. :meth:`release` ends what no run took and releases the context (with every
    GL object a run made in it)."""

    def __init__(self, job: dict[str, Any], source: bytes | None = None) -> None:
        from mirrorlab.labs import load_lab

        self.key = _job_key(job)
        self.spec = load_lab(job["lab"], job["package"], job["import_root"])
        self.limits = Limits(**job["limits"])
        self.size = (int(job["size"][0]), int(job["size"][1]))
        self.runner: Runner | None = start_runner(self.spec, self.limits, job.get("owner"), source)
        self.context: Any = None
        try:
            from mirrorlab.gl.context import offscreen_context
            from mirrorlab.gl.resources import Framebuffer
            from mirrorlab.labs.trusted.session import open_session

            self.context = offscreen_context()
            target = Framebuffer(self.context.resources, *self.size)
            target.bind()
            self.session = open_session(self.spec.name, self.size, job_variant(job))
        except BaseException:
            self.release()
            raise

    @property
    def resources(self) -> Any:
        """The context's registry of GL objects (released with it)."""
        return self.context.resources

    def fits(self, job: dict[str, Any]) -> bool:
        """Whether this was prepared for a job like ``job`` (same lab, variant, size,
        limits and asker)."""
        return _job_key(job) == self.key

    def take_runner(self) -> Runner | None:
        """The runner, handed to the run that uses it (which then ends it)."""
        runner, self.runner = self.runner, None
        return runner

    def release(self) -> None:
        if self.runner is not None:
            self.runner.release()
            self.runner = None
        if self.context is not None:
            self.context.release()
            self.context = None


def prepare_like(job: dict[str, Any]) -> PreparedRun | None:
    """A run prepared for a job like ``job``; None when it cannot be made (the next job
    then says why, made afresh)."""
    try:
        return PreparedRun(job)
    except Exception:
        return None
