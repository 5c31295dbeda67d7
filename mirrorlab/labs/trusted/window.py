"""``mirrorlab lab run``: a student's file in a window that belongs to the trusted process.

The window and its GL context are this process's. Each run of the file has a context of
its own (a hidden one, beside the window's) with the lab's session and a target of the
window's size, as a check has; the file itself runs in the sandbox exactly as for a
check (:class:`~.lab_run.LabRun`), its calls executed in that context frame after frame:
the lab's set-up functions once, then ``display()`` every frame, each frame shown in the
window as it is drawn. Esc (a key callback: a tap is seen however slow the frame), the
window's close button or ``max_frames`` ends it. With ``watch``, every save of the file
ends its run and starts a new one in the same window: a new sandbox, a new context and a
new session, nothing of the last run kept. Errors are printed one line each, as the
checker words them.
"""

from __future__ import annotations

import sys
from pathlib import Path
from typing import Any

import numpy as np

from mirrorlab.labs import LabSpec, find_lab
from mirrorlab.labs.trusted.sandbox import Limits, sandboxed, unsandboxed_note

WINDOW_LIMITS = Limits(cpu_seconds=600, seconds=86_400.0, unsandboxed=True)
"""A window runs until it is closed: the student's process may spend 10 minutes of CPU
(their own file: without a sandbox where there is none)."""
WAIT_SECONDS = 0.05
"""How long the window waits for events between looks at the file, once a run is over."""


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


class _Keys:
    """The window's keys as glfw reports them to its callback: a press of Esc is kept
    until the loop looks, so a tap during a slow frame still ends the run."""

    def __init__(self, glfw: Any, window: Any) -> None:
        self.glfw = glfw
        self.escape = False
        glfw.set_key_callback(window, self.on_key)

    def on_key(self, window: Any, key: int, scancode: int, action: int, mods: int) -> None:
        if key == self.glfw.KEY_ESCAPE and action == self.glfw.PRESS:
            self.escape = True


class _Screen:
    """The window's side: a frame drawn by a run (in its own context) copied into a
    texture of the window's context and onto the window."""

    def __init__(self, context: Any, size: tuple[int, int]) -> None:
        from mirrorlab.gl.resources import Texture2D, TextureFramebuffer

        self.context, self.size = context, size
        self.texture = Texture2D.blank(context.resources, *size)
        self.source = TextureFramebuffer(context.resources, self.texture)
        self.frame: np.ndarray | None = None

    def show(self, frame: np.ndarray | None = None) -> None:
        """Show ``frame`` (``(h, w, 3)`` uint8, row 0 at the top), or the last one again."""
        from mirrorlab.gl.opengl import GL

        self.context.make_current()
        width, height = self.size
        if frame is not None:
            self.frame = frame
            self.texture.bind(0)
            GL.glPixelStorei(GL.GL_UNPACK_ALIGNMENT, 1)
            GL.glTexSubImage2D(
                GL.GL_TEXTURE_2D,
                0,
                0,
                0,
                width,
                height,
                GL.GL_RGB,
                GL.GL_UNSIGNED_BYTE,
                np.ascontiguousarray(frame[::-1]),
            )
        GL.glBindFramebuffer(GL.GL_READ_FRAMEBUFFER, self.source.name)
        GL.glBindFramebuffer(GL.GL_DRAW_FRAMEBUFFER, 0)
        if self.frame is None:
            GL.glClearColor(0.0, 0.0, 0.0, 1.0)
            GL.glClear(GL.GL_COLOR_BUFFER_BIT)
        else:
            GL.glBlitFramebuffer(
                0, 0, width, height, 0, 0, width, height, GL.GL_COLOR_BUFFER_BIT, GL.GL_NEAREST
            )
        self.context.swap_buffers()


def run_window(
    lab: str,
    file: str | None,
    size: tuple[int, int],
    max_frames: int,
    screenshot: Path | None,
    solutions: Any = None,
    watch: bool = False,
) -> int:
    """Run the file (default: the lab file of the current folder, as ``lab check`` takes
    it) in a window; 0 when its last run ran without error. With ``watch``, run it again
    after every save until the window is closed."""
    from mirrorlab.gl.context import prepare, window_context

    prepare("window")
    import glfw

    from mirrorlab.files import write_png_atomic
    from mirrorlab.labs.trusted.checker import folder_file

    spec = find_lab(lab)
    path = Path(file) if file else folder_file(spec, Path.cwd())
    if not path.is_file():
        raise FileNotFoundError(f"FILE: {str(path)!r} is not a file")
    if not sandboxed():
        print(f"mirrorlab lab run: {unsandboxed_note()}", file=sys.stderr)
    context = window_context(size[0], size[1], f"mirrorlab lab {spec.name} - {path.name}")
    try:
        keys = _Keys(glfw, context.window)
        screen = _Screen(context, context.framebuffer_size())
        watcher = None
        if watch:
            from mirrorlab.labs.trusted.watch import FileWatch

            watcher = FileWatch(path)
        seen = watcher.signature() if watcher is not None else None
        while True:
            status, end = _run_once(spec, path, screen, keys, max_frames, watcher, seen)
            if watcher is None or end == "closed":
                break
            if end == "over" and not _wait_for_save(glfw, screen, keys, watcher, seen):
                break
            seen = watcher.settled()
            print(f"{path} saved: running it again", file=sys.stderr, flush=True)
        if screenshot is not None and screen.frame is not None:
            write_png_atomic(screenshot, screen.frame)
            print(f"wrote {screenshot}")
        return status
    finally:
        context.release()


def _closing(screen: _Screen, keys: _Keys) -> bool:
    import glfw

    glfw.poll_events()
    return keys.escape or screen.context.should_close()


def _wait_for_save(glfw: Any, screen: _Screen, keys: _Keys, watcher: Any, seen: Any) -> bool:
    """Keep the last frame shown until the file differs from ``seen`` (True) or the window
    is closed."""
    while True:
        glfw.wait_events_timeout(WAIT_SECONDS)
        if keys.escape or screen.context.should_close():
            return False
        now = watcher.signature()
        if now is not None and now != seen:
            return True
        screen.show()


def _run_once(
    spec: LabSpec,
    path: Path,
    screen: _Screen,
    keys: _Keys,
    max_frames: int,
    watcher: Any,
    seen: Any,
) -> tuple[int, str]:
    """One run of the file as it is now, in a context of its own, shown on ``screen``
    until it ends, ``max_frames`` are drawn, the window closes or (with ``watcher``) the
    file changes from ``seen``. Returns the exit status and how it ended: ``closed`` (the
    window), ``changed`` (the file) or ``over``."""
    from mirrorlab.gl.context import offscreen_context
    from mirrorlab.gl.resources import Framebuffer
    from mirrorlab.labs.trusted.call_executor import RunLimits
    from mirrorlab.labs.trusted.checker import file_variant
    from mirrorlab.labs.trusted.lab_run import LabRun
    from mirrorlab.labs.trusted.pipe import PipeBudget
    from mirrorlab.labs.trusted.session import open_session

    source, variant = path.read_bytes(), file_variant(spec, path)
    width, height = screen.size
    end = "over"
    context = offscreen_context()
    try:
        target = Framebuffer(context.resources, width, height)
        target.bind()
        session = open_session(spec.name, (width, height), variant)
        run = LabRun(
            spec,
            session,
            source,
            path.name,
            WINDOW_LIMITS,
            RunLimits(calls=1 << 62, gl_seconds=1e12),
            PipeBudget(total_bytes=1 << 40),
            registry=context.resources,
        )
        try:
            run.start()
            if not run.ended and run.load():
                for function in spec.setup:
                    run.call(function)
                frames = 0
                while not run.ended:
                    if _closing(screen, keys):
                        end = "closed"
                        break
                    if watcher is not None and watcher.signature() not in (seen, None):
                        end = "changed"
                        break
                    context.make_current()
                    target.bind()
                    run.executor.begin_frame(keep=2)
                    if not run.call(spec.frame):
                        break
                    frames += 1
                    frame = run.executor.session_frame()
                    screen.show(frame)
                    context.make_current()
                    if max_frames and frames >= max_frames:
                        break
            context.make_current()
            run.finish()
        finally:
            context.make_current()
            run.release()
        evidence = run.collect()
    finally:
        context.make_current()
        context.release()
        screen.context.make_current()
    for error in evidence.errors:
        print(format_error(spec, error), file=sys.stderr)
    if evidence.status != "ok":
        print(f"the run was stopped: {evidence.detail}", file=sys.stderr)
    return (1 if evidence.errors or evidence.status != "ok" else 0), end
