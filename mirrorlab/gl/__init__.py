"""The OpenGL layer: contexts and resource wrappers. It knows no reflection technique.

Importing this package selects PyOpenGL's platform (see :mod:`mirrorlab.gl.context`)
before anything imports OpenGL.
"""

from mirrorlab.gl import context as context
