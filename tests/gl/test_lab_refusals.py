"""What a lab's refusal says (issue 45, items 3 and 4): every refused enum by its GL name
and what the call takes; every float argument of every allowed call that is nan or
infinite named, with why it cannot work; degenerate matrices and views named by the
argument that makes them so, refused where GL refuses them and noted in the call trace
where GL carries them out. The checks run before a call reaches GL, so a core context's
emulation (``./dev test-macos``) says the same."""

from __future__ import annotations

import importlib
import re
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import Framebuffer
from mirrorlab.labs import unregister
from mirrorlab.labs.trusted import calls as C
from mirrorlab.labs.trusted.call_executor import Executor
from mirrorlab.labs.trusted.session import open_session
from mirrorlab.labs.trusted.variants import default_variant

SIZE = (64, 64)
EVERY_CALL = {**C.GL_SPECS, **C.GLU_SPECS}
CANDIDATES: tuple[Any, ...] = (
    1,
    0,
    0.5,
    None,
    [],
    "x",
    *([number] * n for number in (0.5, 1) for n in (16, 4, 3, 2, 1)),
)


def valid(check: C.Check) -> Any:
    """A value ``check`` takes (its set's smallest enum, or the first candidate it takes)."""
    enums = getattr(check, "enums", None)
    if enums is not None:
        return min(enums)
    bits = getattr(check, "bits", None)
    if bits is not None:
        return min(bits.names)
    for value in CANDIDATES:
        try:
            check(value, "w")
            return value
        except C.CallError:
            continue
    raise AssertionError(f"no candidate passes {check}")


def refusal(name: str, args: list[Any]) -> C.CallError:
    with pytest.raises(C.CallError) as caught:
        C.check_arguments(name, EVERY_CALL[name], args)
    return caught.value


def test_the_issues_enums_are_named():
    coord = refusal("glTexGeni", [int(GL.GL_TEXTURE_GEN_S), int(GL.GL_TEXTURE_GEN_MODE), 0x2402])
    assert "GL_TEXTURE_GEN_S is a capability" in coord.message
    assert "glTexGeni takes GL_S, GL_T, GL_R or GL_Q" in coord.message
    face = int(GL.GL_TEXTURE_CUBE_MAP_POSITIVE_X) + 6
    target = refusal("glCopyTexImage2D", [face, 0, int(GL.GL_RGB), 0, 0, 128, 128, 0])
    assert "GL_TEXTURE_CUBE_MAP_NEGATIVE_Z + 1 is past the last face" in target.message
    unit = refusal("glActiveTexture", [1])
    assert "the unit number 1 is GL_TEXTURE0 + 1" in unit.message
    cap = refusal("glEnable", [int(GL.GL_S)])
    assert "GL_S is a texture coordinate" in cap.message and "GL_TEXTURE_GEN_S" in cap.message
    assert "0x" not in coord.message + target.message + cap.message


ENUM_ARGUMENTS = [
    (name, index)
    for name, spec in sorted(EVERY_CALL.items())
    for index, check in enumerate(spec.checks)
    if getattr(check, "enums", None) is not None
]
GL_VALUES = sorted({int(v) for v in C._gl_constants()} - {0})


@settings(max_examples=200, deadline=None)
@given(
    st.sampled_from(ENUM_ARGUMENTS),
    st.one_of(st.sampled_from(GL_VALUES), st.integers(0, 0x20000)),
)
def test_every_refused_enum_is_named_with_what_the_call_takes(argument, value):
    """Any value an enum argument refuses: named by its GL name (or as a number, or as a
    step past a run such as the faces), and the call's own choices listed by name."""
    name, index = argument
    spec = EVERY_CALL[name]
    allowed = spec.checks[index].enums
    if value in allowed:
        return
    args = [valid(check) for check in spec.checks]
    args[index] = value
    message = refusal(name, args).message
    said = message.split(": ", 1)[1]
    assert re.search(r"GL_\w+|is a number|is no GL enum", said), message
    assert f"{name} takes " in said, message
    taken = said.split(f"{name} takes ", 1)[1]
    listed = re.findall(r"GL_\w+", taken)
    assert listed and set(listed) <= set(allowed.names.values()), message


def takes_floats(check: C.Check) -> bool:
    """Whether ``check`` takes a float (or a vector of them): nan there is its ValueError."""
    sample = valid(check)
    bad = [{"$f": "nan"}, *sample[1:]] if isinstance(sample, list) and sample else {"$f": "nan"}
    try:
        check(bad, "w")
    except C.CallError as error:
        return error.kind == "ValueError" and "nan" in error.message
    return False


FLOAT_ARGUMENTS = [
    (name, index)
    for name, spec in sorted(EVERY_CALL.items())
    for index, check in enumerate(spec.checks)
    if takes_floats(check)
]


@pytest.mark.parametrize("bad", ["nan", "inf", "-inf"])
def test_every_float_argument_that_is_not_finite_is_named(bad):
    """nan and infinity, as the student side sends them (JSON carries neither), in every
    float argument of every allowed call: a ValueError naming the argument by PyOpenGL's
    name, with what it would make."""
    assert len(FLOAT_ARGUMENTS) > 100
    for name, index in FLOAT_ARGUMENTS:
        spec = EVERY_CALL[name]
        args = [valid(check) for check in spec.checks]
        sample = args[index]
        args[index] = [{"$f": bad}, *sample[1:]] if isinstance(sample, list) else {"$f": bad}
        error = refusal(name, args)
        names = C.arg_names(name)
        assert error.kind == "ValueError", (name, error.message)
        assert f"argument {index + 1}" in error.message, (name, error.message)
        if index < len(names):
            assert f"({names[index]})" in error.message, (name, error.message)
        assert "would be undefined" in error.message and "finite" in error.message


@pytest.fixture(scope="module")
def quad_lab():
    """The test folder's quad lab, which opens every channel (lines and points for
    glLineWidth; registered while the module runs: lab-parametrised tests elsewhere take
    the shipped labs)."""
    spec = importlib.import_module("tests.labs.fourth_lab").SPEC
    yield spec
    unregister(spec.name)


@pytest.fixture
def executor(registry, quad_lab) -> Executor:
    target = Framebuffer(registry, *SIZE)
    target.bind()
    return Executor(open_session(quad_lab.name, SIZE, default_variant(quad_lab.name)))


def run(ex: Executor, op: str, name: str, *args: Any) -> dict[str, Any]:
    reply, _ = ex.call({"op": op, "fn": name, "args": list(args), "line": 3}, [])
    return reply


@pytest.mark.parametrize(
    "op, name, args, words",
    [
        ("gl", "glOrtho", [1, 1, -1, 1, 0, 10], "left = right = 1: the box has no width"),
        ("gl", "glOrtho", [-1, 1, 2, 2, 0, 10], "bottom = top = 2"),
        ("gl", "glOrtho", [-1, 1, -1, 1, 3, 3], "zNear = zFar = 3"),
        ("gl", "glFrustum", [-1, 1, -1, 1, 0, 10], "zNear = 0: a perspective box"),
        ("glu", "gluOrtho2D", [0, 0, -1, 1], "left = right = 0"),
        ("gl", "glLineWidth", [0.0], "width = 0"),
    ],
)
def test_degenerate_boxes_are_refused_naming_the_argument(executor, op, name, args, words):
    reply = run(executor, op, name, *args)
    assert not reply["ok"] and reply["type"] == "GLError" and words in reply["message"], reply
    assert int(GL.glGetError()) == GL.GL_NO_ERROR


@pytest.mark.parametrize(
    "name, args, words",
    [
        ("gluLookAt", [0, 0, 0, 0, 0, 0, 0, 1, 0], "eye and center are both (0, 0, 0)"),
        ("gluLookAt", [0, 0, 0, 0, 1, 0, 0, 1, 0], "up (0, 1, 0) is parallel to the view"),
        ("gluLookAt", [0, 0, 5, 0, 0, 0, 0, 0, 0], "up = (0, 0, 0)"),
        ("gluPerspective", [0, 1, 0.1, 10], "fovy = 0"),
        ("gluPerspective", [60, 1, 2, 2], "zNear = zFar = 2"),
        ("gluPerspective", [60, 0, 0.1, 10], "aspect = 0"),
        ("glScalef", [1, 0, 1], "y = 0: a scale of 0 flattens"),
        ("glRotatef", [30, 0, 0, 0], "the axis (0, 0, 0) has no direction"),
        ("glLoadMatrixf", [[0.0] * 16], "the matrix is singular"),
        ("glViewport", [0, 0, 0, 64], "0 pixels wide"),
    ],
)
def test_degenerate_matrices_run_as_gl_runs_them_and_are_noted(executor, name, args, words):
    """What GL carries out although it cannot work: the call runs (as it would in
    PyOpenGL) and the call trace notes why, for the hint of the task it spoils."""
    reply = run(executor, "glu" if name.startswith("glu") else "gl", name, *args)
    assert reply["ok"], reply
    traced = [e for e in executor.tracker.events if e.get("kind") == "call"][-1]
    assert words in traced.get("note", ""), traced
