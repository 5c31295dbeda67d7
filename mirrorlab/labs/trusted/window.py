"""``mirrorlab lab run``: a student's file in a window that belongs to the trusted process.

The window, its GL context and the lab's session are this process's; the student's file
runs in the sandbox exactly as for a check (:class:`~.lab_run.LabRun`), its calls executed
here frame after frame: the lab's set-up functions once, then ``display()`` every frame
until Esc, the window's close button or ``max_frames``. Errors are printed one line each,
as the checker words them.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

from mirrorlab.labs import LabSpec, find_lab
from mirrorlab.labs.trusted.sandbox import Limits, sandboxed, unsandboxed_note

WINDOW_LIMITS = Limits(cpu_seconds=600, seconds=86_400.0, unsandboxed=True)
"""A window runs until it is closed: the student's process may spend 10 minutes of CPU
(their own file: without a sandbox where there is none)."""


def format_error(spec: LabSpec, error: dict[str, Any]) -> str:
    """One line for an error: the task it belongs to, the student's line and the message."""
    function = str(error.get("function", ""))
    tasks = [t for t in spec.tasks if t.function == function]
    where = f"in {function}()" if not function.startswith("<") else "while loading the file"
    if tasks:
        where += f" ({tasks[0].name}: {tasks[0].title})"
    line = f", line {error['line']}" if error.get("line") else ""
    code = f": {error['code']}" if error.get("code") else ""
    return f"{where}{line}{code} -> {error.get('message', '')}"


def run_window(
    lab: str,
    file: str | None,
    size: tuple[int, int],
    max_frames: int,
    screenshot: Path | None,
    solutions: Any = None,
) -> int:
    """Run the file (default: the lab's starter) in a window; 0 when it ran without error."""
    from mirrorlab.gl.context import prepare, window_context

    prepare("window")
    import glfw

    from mirrorlab.files import write_png_atomic
    from mirrorlab.gl.opengl import GL
    from mirrorlab.labs.content import starter
    from mirrorlab.labs.trusted.call_executor import RunLimits
    from mirrorlab.labs.trusted.checker import file_variant
    from mirrorlab.labs.trusted.lab_run import LabRun
    from mirrorlab.labs.trusted.pipe import PipeBudget
    from mirrorlab.labs.trusted.session import open_session
    from mirrorlab.labs.trusted.variants import default_variant

    spec = find_lab(lab)
    if file:
        path = Path(file)
        if not path.is_file():
            raise FileNotFoundError(f"FILE: {str(path)!r} is not a file")
        source, name, variant = path.read_bytes(), path.name, file_variant(spec, path)
    else:
        variant = default_variant(spec.name)
        source, name = starter(spec, variant).encode(), "starter.py"
    if not sandboxed():
        print(f"mirrorlab lab run: {unsandboxed_note()}", file=sys.stderr)
    context = window_context(size[0], size[1], f"mirrorlab lab {spec.name} - {name}")
    try:
        width, height = context.framebuffer_size()
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, 0)
        session = open_session(spec.name, (width, height), variant)
        run = LabRun(
            spec,
            session,
            source,
            name,
            WINDOW_LIMITS,
            RunLimits(calls=1 << 62, gl_seconds=1e12),
            PipeBudget(total_bytes=1 << 40),
            registry=context.resources,
        )
        last = None
        try:
            run.start()
            if not run.ended and run.load():
                for function in spec.setup:
                    run.call(function)
                frames = 0
                while not run.ended and not context.should_close():
                    glfw.poll_events()
                    if glfw.get_key(context.window, glfw.KEY_ESCAPE) == glfw.PRESS:
                        break
                    GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, 0)
                    run.executor.begin_frame(keep=2)
                    if not run.call(spec.frame):
                        break
                    frames += 1
                    if screenshot is not None:
                        GL.glReadBuffer(GL.GL_BACK)
                        last = run.executor.session_frame()
                    context.swap_buffers()
                    if max_frames and frames >= max_frames:
                        break
            run.finish()
        finally:
            run.release()
        evidence = run.collect()
        for error in evidence.errors:
            print(format_error(spec, error), file=sys.stderr)
        if evidence.status != "ok":
            print(f"the run was stopped: {evidence.detail}", file=sys.stderr)
        if screenshot is not None and last is not None:
            write_png_atomic(screenshot, last)
            print(f"wrote {screenshot}")
        return 1 if evidence.errors or evidence.status != "ok" else 0
    finally:
        context.release()
