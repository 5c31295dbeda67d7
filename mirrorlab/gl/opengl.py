"""PyOpenGL's ``GL`` namespace, imported only after :mod:`mirrorlab.gl.context` has chosen
the platform. Modules that use GL import it from here (``from mirrorlab.gl.opengl import
GL``), so import order can never pick the wrong platform. The renderer, its passes and
the resource wrappers take only constants from it and make their calls through
mirrorlab's layer, :mod:`mirrorlab.gl.calls` (``gl`` and ``raw``), which can record them.

``RAW`` holds PyOpenGL's raw entry points of the calls a frame makes around itself
(saving and restoring the state it changes) and of those whose wrappers convert their
arguments in Python (a buffer's upload, matrix and array uniforms, the readback): plain
ctypes calls, without PyOpenGL's argument conversion and per-call error check, cheaper.
Errors still show at the next checked call or pass check
(:func:`mirrorlab.gl.context.check_gl_errors`)."""

from types import SimpleNamespace

from mirrorlab.gl import context as _context  # noqa: F401  (sets PYOPENGL_PLATFORM first)

from OpenGL import GL  # isort: skip
from OpenGL.raw.GL.VERSION import GL_1_0, GL_1_3, GL_1_5, GL_2_0, GL_3_0, GL_3_2  # isort: skip

RAW = SimpleNamespace(
    **{
        name: getattr(module, name)
        for module, names in (
            (
                GL_1_0,
                (
                    "glIsEnabled",
                    "glGetIntegerv",
                    "glGetBooleanv",
                    "glGetFloatv",
                    "glEnable",
                    "glDisable",
                    "glFrontFace",
                    "glCullFace",
                    "glDepthFunc",
                    "glDepthMask",
                    "glStencilMask",
                    "glStencilFunc",
                    "glStencilOp",
                    "glColorMask",
                    "glViewport",
                    "glScissor",
                    "glClearColor",
                    "glReadPixels",
                ),
            ),
            (GL_1_3, ("glActiveTexture",)),
            (GL_1_5, ("glBufferSubData", "glBindBuffer")),
            (
                GL_2_0,
                ("glUseProgram", "glUniformMatrix4fv", "glUniform3fv", "glVertexAttribPointer"),
            ),
            (GL_3_0, ("glBindVertexArray", "glBindFramebuffer")),
            (GL_3_2, ("glDrawElementsInstancedBaseVertex",)),
        )
        for name in names
    }
)

__all__ = ["GL", "RAW"]
