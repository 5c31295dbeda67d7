"""The errors mirrorlab reports to a user in one line, and what each means for the exit
status of a command. Imports nothing heavy (no OpenGL), so the command line can catch
them all before deciding which platform to load.

- bad input (exit 2): ``ValueError`` and its kinds here and elsewhere (a scene file, an
  option, an output path), :class:`WriteError` (the system refused a write),
  :class:`MissingExtraError` (an option needs an optional dependency not installed),
  :class:`GLLimitError` (larger than the GL allows) and :class:`GLOutOfMemoryError`;
- the machine (exit 1): :class:`GLContextError` (no display, no GL libraries, an OpenGL
  too old), :class:`GLPassError` (any other GL error, naming the pass) and
  :class:`BatchError` (jobs failed on their workers).
"""

from __future__ import annotations

DEBIAN_GL_PACKAGES = "libegl-mesa0 libgl1-mesa-dri"
"""What Debian needs for headless OpenGL (Mesa's EGL and its llvmpipe driver)."""


class GLContextError(RuntimeError):
    """A context could not be created or made current, or cannot do what is asked; the
    message says what to install or do."""


class GLVersionError(GLContextError):
    """The context's OpenGL is older than a technique needs."""


class GLBackendError(GLContextError, ValueError):
    """MIRRORLAB_GL_BACKEND or MIRRORLAB_GL_CORE (or the matching keyword) holds a value
    it does not allow: bad input, as the message names the variable and the values."""


class BatchError(RuntimeError):
    """Jobs sent to workers failed where they ran (frames of a batch render, truths of the
    accuracy sweep); the message names the first (and, for frames, how many: the frames
    that worked stay written)."""


class BenchmarkError(RuntimeError):
    """A benchmark could not time what it stands for (pyrender's worker ended, a variant
    ran other passes than it should); the message says which."""


class GLPassError(RuntimeError):
    """An OpenGL error raised while a pass ran: ``pass_name`` (``capture:mirror``,
    ``camera``...), the GL error ``code`` and the call or driver message."""

    def __init__(self, pass_name: str, code: int, detail: str) -> None:
        self.pass_name, self.code, self.detail = pass_name, code, detail
        super().__init__(
            f"OpenGL error {GL_ERROR_NAMES.get(code, hex(code))} in pass {pass_name!r}: {detail}"
        )


class GLOutOfMemoryError(GLPassError, ValueError):
    """GL_OUT_OF_MEMORY: what was asked for (a texture, a framebuffer) is too large for
    this GL; a smaller size is the fix, so it counts as bad input."""

    def __init__(self, pass_name: str, code: int, detail: str) -> None:
        super().__init__(pass_name, code, detail)
        self.args = (
            f"OpenGL ran out of memory in pass {pass_name!r} ({detail}); use "
            f"smaller sizes (--size, --env-size, --map-size, smaller pictures)",
        )


class MissingExtraError(ValueError):
    """An option needs an optional dependency that is not installed: ``OPTION: needs
    WHAT, which is not installed; install it with: pip install 'mirrorlab[EXTRA]'``."""

    def __init__(self, option: str, what: str, extra: str) -> None:
        self.option, self.what, self.extra = option, what, extra
        super().__init__(
            f"{option}: needs {what}, which is not installed; install it "
            f"with: pip install 'mirrorlab[{extra}]'"
        )


class GLLimitError(ValueError):
    """A size beyond what this GL allows (GL_MAX_TEXTURE_SIZE and the like)."""


class WriteError(Exception):
    """The system refused to write ``path``: ``cannot write PATH: REASON``."""

    def __init__(self, path: object, reason: str) -> None:
        self.path, self.reason = path, reason
        super().__init__(f"cannot write {path}: {reason}")


GL_ERROR_NAMES = {
    0x0500: "GL_INVALID_ENUM",
    0x0501: "GL_INVALID_VALUE",
    0x0502: "GL_INVALID_OPERATION",
    0x0503: "GL_STACK_OVERFLOW",
    0x0504: "GL_STACK_UNDERFLOW",
    0x0505: "GL_OUT_OF_MEMORY",
    0x0506: "GL_INVALID_FRAMEBUFFER_OPERATION",
}
GL_OUT_OF_MEMORY = 0x0505


def pass_error(pass_name: str, code: int, detail: str) -> GLPassError:
    """The error to raise for GL error ``code`` in ``pass_name``."""
    kind = GLOutOfMemoryError if code == GL_OUT_OF_MEMORY else GLPassError
    return kind(pass_name, code, detail)
