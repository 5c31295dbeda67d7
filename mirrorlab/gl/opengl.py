"""PyOpenGL's ``GL`` namespace, imported only after :mod:`mirrorlab.gl.context` has chosen
the platform. Modules that call GL directly import it from here (``from
mirrorlab.gl.opengl import GL``), so import order can never pick the wrong platform."""

from mirrorlab.gl import context as _context  # noqa: F401  (sets PYOPENGL_PLATFORM first)

from OpenGL import GL  # isort: skip

__all__ = ["GL"]
