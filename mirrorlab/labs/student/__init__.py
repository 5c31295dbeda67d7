"""The student side of a lab run: what runs in the sandbox with the student's file.

It holds no OpenGL and no answers. :mod:`.runner` executes the student's file with
stand-ins for ``OpenGL.GL``, ``OpenGL.GLU`` and ``mirrorlab.labs.kit`` (:mod:`.gl`,
:mod:`.kit_standin`) whose every call goes over a pipe (:mod:`.wire`) to the trusted checker,
which validates it, executes it in its own GL context and replies. This package imports
only the standard library (numpy when the sandbox offers it) and its own modules, never
the rest of mirrorlab: the sandbox binds this folder alone.
"""
