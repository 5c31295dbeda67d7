"""Stand-ins for ``OpenGL``, ``OpenGL.GL``, ``OpenGL.GLU`` and ``OpenGL.error`` in the
sandbox: every name PyOpenGL exports, the constants with their values, and a function for
each call; the calls the labs offer go to the checker, the others raise."""

from __future__ import annotations

import ctypes
from types import ModuleType
from typing import Any

from .remote import GLError, Remote

CTYPES = {
    "GLbitfield": ctypes.c_uint,
    "GLboolean": ctypes.c_ubyte,
    "GLbyte": ctypes.c_byte,
    "GLchar": ctypes.c_char,
    "GLclampd": ctypes.c_double,
    "GLclampf": ctypes.c_float,
    "GLdouble": ctypes.c_double,
    "GLenum": ctypes.c_uint,
    "GLfloat": ctypes.c_float,
    "GLint": ctypes.c_int,
    "GLshort": ctypes.c_short,
    "GLsizei": ctypes.c_int,
    "GLubyte": ctypes.c_ubyte,
    "GLuint": ctypes.c_uint,
    "GLushort": ctypes.c_ushort,
    "GLvoid": None,
    "GLvoidp": ctypes.c_void_p,
}


class NullFunctionError(GLError):
    """A call this OpenGL does not offer (PyOpenGL's name for it)."""


def _offered(remote: Remote, op: str, name: str, kinds: list[str]):
    def call(*args: Any) -> Any:
        return remote.call(op, name, kinds, args)

    call.__name__ = call.__qualname__ = name
    call.__doc__ = f"{name}: run by the lab's checker"
    return call


def _unavailable(name: str, why: str = ""):
    def call(*args: Any) -> Any:
        raise NotImplementedError(why or f"{name} is not one of the OpenGL calls the labs offer")

    call.__name__ = call.__qualname__ = name
    return call


def _module(
    name: str,
    constants: dict[str, int],
    functions: list[str],
    offered: dict[str, list[str]],
    remote: Remote,
    op: str,
    refused: dict[str, str] | None = None,
) -> ModuleType:
    module = ModuleType(name)
    names = []
    for constant, value in constants.items():
        setattr(module, constant, value)
        names.append(constant)
    for function in functions:
        kinds = offered.get(function)
        setattr(
            module,
            function,
            _offered(remote, op, function, kinds)
            if kinds is not None
            else _unavailable(function, (refused or {}).get(function, "")),
        )
        names.append(function)
    module.__dict__["__all__"] = names
    return module


def build_modules(remote: Remote, description: dict) -> dict[str, ModuleType]:
    """The modules to put in ``sys.modules`` for the student's file."""
    gl = _module(
        "OpenGL.GL",
        description["gl_constants"],
        description["gl_functions"],
        description["gl_offered"],
        remote,
        "gl",
        description.get("gl_refused"),
    )
    for type_name, ctype in CTYPES.items():
        setattr(gl, type_name, ctype)
        gl.__dict__["__all__"].append(type_name)
    glu = _module(
        "OpenGL.GLU",
        description["glu_constants"],
        description["glu_functions"],
        description["glu_offered"],
        remote,
        "glu",
    )
    error = ModuleType("OpenGL.error")
    for name, value in (
        ("Error", Exception),
        ("GLError", GLError),
        ("NullFunctionError", NullFunctionError),
    ):
        setattr(error, name, value)
    gl.__dict__["GLError"] = GLError
    package = ModuleType("OpenGL")
    package.__path__ = []  # a package: "import OpenGL.GL" finds its submodules in sys.modules
    package.__dict__.update(GL=gl, GLU=glu, error=error, ERROR_CHECKING=True)
    return {"OpenGL": package, "OpenGL.GL": gl, "OpenGL.GLU": glu, "OpenGL.error": error}
