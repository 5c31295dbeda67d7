"""The OpenGL layer: contexts, resource wrappers and the calls layer the renderer records
through (:mod:`mirrorlab.gl.calls`). It knows no reflection technique.

Importing this package selects PyOpenGL's platform (see :mod:`mirrorlab.gl.context`)
before anything imports OpenGL.
"""

from mirrorlab.gl import context as context
