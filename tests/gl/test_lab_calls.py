"""Every call the labs allow, in every form the OpenGL specification gives it, runs in the
executor (fed messages directly in a headless context): the integer and short forms, the
vector forms, every allowed function present. Numbers out of any range are the student's
error in one line; and a fuzz of each call's arguments and of the pipe's messages gets a
reply or one line, never an internal error."""

from __future__ import annotations

import importlib
import json
import os
import re
import struct
import time

import numpy as np
import pytest
from hypothesis import HealthCheck, example, given, settings
from hypothesis import strategies as st

from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import Framebuffer
from mirrorlab.labs import unregister
from mirrorlab.labs.trusted import calls as C
from mirrorlab.labs.trusted.call_executor import Executor, Stop
from mirrorlab.labs.trusted.pipe import PipeBudget, PipeClosed, PipeError, TrustedChannel
from mirrorlab.labs.trusted.session import open_session
from mirrorlab.labs.trusted.variants import default_variant
from tests.gl.conftest import module_context
from tests.labs.mutants import solution

SIZE = (32, 32)


gl_context = pytest.fixture(scope="module", name="gl_context")(module_context)

FORMS = {
    # family: the forms of the OpenGL 4.6 compatibility specification (sizes x types [v])
    "glVertex": [f"glVertex{n}{t}{v}" for n in "234" for t in "sifd" for v in ("", "v")],
    "glTexCoord": [f"glTexCoord{n}{t}{v}" for n in "1234" for t in "sifd" for v in ("", "v")],
    "glMultiTexCoord": [
        f"glMultiTexCoord{n}{t}{v}" for n in "1234" for t in "sifd" for v in ("", "v")
    ],
    "glColor": [
        f"glColor{n}{t}{v}"
        for n in "34"
        for t in ("b", "s", "i", "f", "d", "ub", "us", "ui")
        for v in ("", "v")
    ],
    "glNormal": [f"glNormal3{t}{v}" for t in "bsifd" for v in ("", "v")],
    "glTranslate": ["glTranslatef", "glTranslated"],
    "glRotate": ["glRotatef", "glRotated"],
    "glScale": ["glScalef", "glScaled"],
    "glLoadMatrix": ["glLoadMatrixf", "glLoadMatrixd"],
    "glMultMatrix": ["glMultMatrixf", "glMultMatrixd"],
    "glTexParameter": [
        "glTexParameteri",
        "glTexParameterf",
        "glTexParameteriv",
        "glTexParameterfv",
    ],
    "glTexEnv": ["glTexEnvi", "glTexEnvf", "glTexEnviv", "glTexEnvfv"],
    "glTexGen": [f"glTexGen{t}{v}" for t in "ifd" for v in ("", "v")],
    "glGetTexGen": ["glGetTexGeniv", "glGetTexGenfv", "glGetTexGendv"],
    "glGetTexParameter": ["glGetTexParameteriv", "glGetTexParameterfv"],
    "glGetTexLevelParameter": ["glGetTexLevelParameteriv", "glGetTexLevelParameterfv"],
    "glPixelStore": ["glPixelStorei", "glPixelStoref"],
    "glClearDepth": ["glClearDepth", "glClearDepthf"],
    "glDepthRange": ["glDepthRange", "glDepthRangef"],
    "glUniform": [
        f"glUniform{n}{t}{v}" for n in "1234" for t in ("i", "f", "ui") for v in ("", "v")
    ],
    "glGet": ["glGetBooleanv", "glGetIntegerv", "glGetFloatv", "glGetDoublev"],
}


def family(name: str) -> str:
    """The family of call form ``name`` (``glVertex`` for glVertex3sv), by the longest
    family name it starts with."""
    found = [f for f in FORMS if re.fullmatch(re.escape(f) + r"[0-9]?[a-z]*v?", name)]
    return max(found, key=len) if found else ""


@pytest.fixture(scope="module")
def quad_lab():
    """The test folder's quad lab, which opens every channel (registered while the module
    runs: lab-parametrised tests elsewhere take the shipped labs)."""
    spec = importlib.import_module("tests.labs.fourth_lab").SPEC
    yield spec
    unregister(spec.name)


@pytest.fixture
def target(registry):
    framebuffer = Framebuffer(registry, *SIZE)
    framebuffer.bind()
    return framebuffer


def send(ex: Executor, name: str, args: list, op: str = "gl", arrays=()) -> dict:
    reply, _ = ex.call({"op": op, "fn": name, "args": args, "line": 3}, list(arrays))
    return reply


def prepared(session=None) -> Executor:
    """An executor inside its first frame (where drawing is allowed) with a 4 x 4 RGB
    texture bound on unit 0 and the lab's program in use (so each call reaches GL, past
    the checks of state)."""
    ex = Executor(session or open_session("lab20", SIZE, default_variant("lab20")))
    ex.begin_frame()
    texture = send(ex, "glGenTextures", [1])["value"]
    assert send(ex, "glBindTexture", [int(GL.GL_TEXTURE_2D), texture])["ok"]
    assert send(
        ex,
        "glTexImage2D",
        [
            int(GL.GL_TEXTURE_2D),
            0,
            int(GL.GL_RGB),
            4,
            4,
            0,
            int(GL.GL_RGB),
            int(GL.GL_UNSIGNED_BYTE),
            None,
        ],
    )["ok"]
    if ex.session.programs():
        assert send(ex, "glUseProgram", [min(ex.session.programs())])["ok"]
    return ex


ENUMS = sorted(
    {
        value
        for item in vars(C).values()
        if isinstance(item, frozenset | dict)
        for value in item
        if type(value) is int
    }
    | {int(GL.GL_TEXTURE_ENV), int(GL.GL_TEXTURE_ENV_MODE), int(GL.GL_TEXTURE_GEN_MODE)}
)
"""Every enum of the allow-list's checks."""


def candidates(kind: str) -> list:
    """Arguments of pack kind ``kind`` to try, the most ordinary first."""
    if kind == "s":
        return ["texSampler"]
    if kind == "p":
        return [{"$a": 0}, None]
    if kind in ("v", "n"):
        lists = [[0] * n for n in (1, 2, 3, 4, 16, 0)]
        return lists if kind == "n" else [[0.0] * len(x) for x in lists]
    if kind == "j":
        return [None]
    numbers = [0, 1, 2, 4, 8, *ENUMS]
    return numbers if kind != "f" else [float(n) for n in numbers]


def arguments(name: str, spec: C.Spec) -> list:
    """Arguments every check of ``spec`` accepts."""
    args = []
    for index, (kind, check) in enumerate(zip(spec.kinds, spec.checks, strict=False)):
        for value in candidates(kind.rstrip("?")):
            try:
                check(value, "x")
            except C.CallError:
                continue
            args.append(value)
            break
        else:
            raise AssertionError(f"{name}: no candidate argument {index + 1} passes its check")
    return args


def test_every_form_of_every_allowed_family_is_allowed():
    allowed = {**C.GL_SPECS, **C.GLU_SPECS}
    families = {family(name) for name in allowed} - {""}
    assert {"glVertex", "glColor", "glTexCoord", "glNormal", "glUniform"} <= families
    for name in sorted(families):
        missing = [form for form in FORMS[name] if form not in allowed]
        assert not missing, f"{name}: the labs allow some forms but not {missing}"


def test_every_allowed_call_runs_in_every_form(target, quad_lab):
    """Each allowed name exists in PyOpenGL (what the sandbox's stand-in offers) and, with
    arguments its checks accept, gets a reply: a value or the student's error, never an
    exception of the checker's own."""
    from OpenGL import GLU

    from mirrorlab.labs.trusted.lab_run import reset_state

    failures = []
    labs = ("lab20", "spheremap", "cubemap", quad_lab.name)  # the quad lab opens every channel
    sessions = {lab: open_session(lab, SIZE, default_variant(lab)) for lab in labs}
    for op, specs, module in (("gl", C.GL_SPECS, GL), ("glu", C.GLU_SPECS, GLU)):
        for name, spec in specs.items():
            assert callable(getattr(module, name, None)), f"PyOpenGL has no {name}"
            # each call in a lab that offers it (every call is offered by one)
            offering = [lab for lab in labs if op == "glu" or name in C.lab_specs(lab)]
            args = arguments(name, spec)
            in_begin = spec.in_begin and name != "glEnd"
            for lab in offering:
                ex = prepared(sessions[lab])
                if in_begin:
                    assert send(ex, "glBegin", [int(GL.GL_TRIANGLES)])["ok"]
                try:
                    reply = send(ex, name, args, op, arrays=[np.zeros(256, np.uint8)])
                except Exception as exc:  # the failure is the point
                    failures.append(f"{name}{tuple(args)}: {type(exc).__name__}: {exc}")
                    break
                finally:
                    if in_begin:
                        send(ex, "glEnd", [])
                    ex.end_open_primitive()  # glBegin's own
                    GL.glUseProgram(0)
                    reset_state()
                if reply["ok"] or reply["type"] == "GLError":
                    break  # allowed arguments, set-up state: only GL's own verdict refuses
                # an argument of a channel this lab closes (the quad lab opens them all)
                assert reply["type"] == "NotImplementedError" and lab != quad_lab.name, reply
                assert "this lab's handout draws nothing with it" in reply["message"], reply
    assert not failures, "\n".join(failures)
    assert int(GL.glGetError()) == GL.GL_NO_ERROR


def test_integer_forms_draw_where_the_float_forms_do(target, quad_lab):
    """glVertex3i and glVertex2s put the vertex where glVertex3f does; glColor3ub's and
    glColor3us's colours are GL's normalised ones (in the quad lab, which offers colours)."""
    ex = prepared(open_session(quad_lab.name, SIZE, default_variant(quad_lab.name)))
    send(ex, "glBegin", [int(GL.GL_TRIANGLES)])
    for name, args in (
        ("glColor3ub", [255, 0, 51]),
        ("glVertex3i", [1, -2, 3]),
        ("glColor3usv", [[0, 65535, 0]]),
        ("glVertex2s", [-4, 5]),
        ("glColor4b", [127, 0, -128, 127]),
        ("glVertex4iv", [[1, 2, 3, 1]]),
    ):
        assert send(ex, name, args)["ok"], name
    primitive = ex.tracker.primitive
    assert primitive is not None
    assert [v[0] for v in primitive.vertices] == [[1, -2, 3, 1.0], [-4, 5, 0.0, 1.0], [1, 2, 3, 1]]
    assert [v[2] for v in primitive.vertices] == [
        [1.0, 0.0, 0.2, 1.0],
        [0.0, 1.0, 0.0, 1.0],
        [1.0, 0.0, -1.0, 1.0],
    ]
    assert send(ex, "glEnd", [])["ok"]
    reply = send(ex, "glVertex3s", [0, 1 << 15, 0])
    assert reply["type"] == "GLError" and "outside -32768..32767" in reply["message"]


@pytest.mark.parametrize(
    ("op", "name", "args", "words"),
    [
        ("gl", "glVertex3f", [10**400, 0, 0], "an integer of 401 digits"),
        ("gl", "glOrtho", [-(10**400), 1, 0, 1, 0, 1], "is out of range"),
        ("gl", "glLoadMatrixf", [[10**400] * 16], "is out of range"),
        ("gl", "glClearColor", [float("nan"), 0, 0, 1], "finite numbers"),
        ("gl", "glMatrixMode", [10**400], "an integer of 401 digits"),
        ("gl", "glClear", [10**400], "an integer of 401 digits"),
        ("gl", "glViewport", [0, 0, 10**400, 1], "an integer of 401 digits"),
        ("kit", "set_viewer", [10**400], "is out of range"),
        ("kit", "set_viewer", [float("inf")], "finite numbers"),
    ],
)
def test_numbers_out_of_range_are_the_students_error_in_one_line(target, op, name, args, words):
    ex = Executor(open_session("lab20", SIZE, default_variant("lab20")))
    reply = send(ex, name, args, op)
    assert not reply["ok"] and words in reply["message"], reply
    assert "\n" not in reply["message"] and len(reply["message"]) < 200, reply


# ---------------------------------------------------------------------------- the fuzz
NUMBERS = st.one_of(
    st.integers(),
    st.integers(-(10**500), 10**500),
    st.floats(),
    st.sampled_from([0, 1, -1, 0x0DE1, 0x1907, 0x8513, 0x84C0, 2**32, 2**31, -(2**31) - 1]),
)
ROBOT = st.builds(
    lambda nodes: {"textures": nodes},
    st.dictionaries(
        st.sampled_from(["base", "hand", "upper_arm", "x" * 300]),
        st.one_of(NUMBERS, st.none(), st.fixed_dictionaries({"other": NUMBERS})),
        max_size=3,
    ),
)
"""lab.draw_scene's robot, its nodes' textures fuzzed."""


def solution_glsl(lab: str) -> str:
    """The GLSL of ``lab``'s solution (its ``..._GLSL`` string)."""
    found = re.search(r'_GLSL = """(.*?)"""', solution(lab), re.S)
    assert found is not None
    return found.group(1)


GLSL = [solution_glsl(lab) for lab in ("spheremap", "cubemap")]
"""The labs' honest GLSL (each compiled once a process), for the kit's shader calls."""
JSON = st.recursive(
    st.one_of(
        st.none(),
        st.booleans(),
        NUMBERS,
        st.text(max_size=20),
        ROBOT,
        st.sampled_from(["metal", "launch", "texSampler", *GLSL, GLSL[0] + "oops"]),
    ),
    lambda inner: st.one_of(
        st.lists(inner, max_size=18), st.dictionaries(st.text(max_size=4), inner, max_size=3)
    ),
    max_leaves=40,
)
NAMES = [
    *sorted({**C.GL_SPECS, **C.GLU_SPECS}),
    "glDrawPixels",
    "draw_scene",
    "set_viewer",
    "load_picture_texture",
    "draw_backdrop",
    "draw_cone_shader",
    "draw_cone_fixed_function",
    "draw_sphere",
    "",
    "glEnd",
    "x" * 5000,
    "gl Clear",
]


@pytest.fixture(scope="module")
def fuzz_target(gl_context):
    """One session of each lab and a target for the whole fuzz (a new executor for each
    example)."""
    framebuffer = Framebuffer(gl_context.resources, *SIZE)
    framebuffer.bind()
    sessions = {
        lab: open_session(lab, SIZE, default_variant(lab))
        for lab in ("lab20", "spheremap", "cubemap")
    }
    GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, 0)
    yield framebuffer, sessions
    framebuffer.release()


@settings(
    max_examples=100, deadline=None, suppress_health_check=[HealthCheck.function_scoped_fixture]
)
@given(
    lab=st.sampled_from(["lab20", "spheremap", "cubemap"]),
    calls=st.lists(
        st.one_of(
            st.tuples(
                st.sampled_from(["gl", "glu", "kit", "other"]),
                st.sampled_from(NAMES),
                st.lists(JSON, max_size=10),
            ),
            st.tuples(
                st.just("kit"),
                st.sampled_from(
                    [
                        "draw_backdrop",
                        "draw_cone_shader",
                        "draw_cone_fixed_function",
                        "draw_sphere",
                        "set_viewer",
                    ]
                ),
                st.lists(st.one_of(st.sampled_from(GLSL), st.integers(-1, 4), NUMBERS), max_size=3),
            ),
        ),
        min_size=1,
        max_size=6,
    ),
)
def test_fuzzed_calls_get_a_reply_or_one_line(fuzz_target, lab, calls):
    from mirrorlab.labs.trusted.lab_run import reset_state

    framebuffer, sessions = fuzz_target
    framebuffer.bind()
    try:
        ex = Executor(sessions[lab])
        ex.begin_frame()
        for op, name, args in calls:
            try:
                reply = send(ex, name, args, op, arrays=[np.zeros(64, np.uint8)])
            except Stop as exc:
                assert "\n" not in str(exc)
                break
            assert reply["ok"] or (
                isinstance(reply["message"], str)
                and "\n" not in reply["message"]
                and len(reply["message"]) < 400
            ), reply
            json.dumps(reply)  # what goes back is plain data
        ex.end_open_primitive()
    finally:
        reset_state()
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, 0)
    assert int(GL.glGetError()) == GL.GL_NO_ERROR


@settings(max_examples=200, deadline=None)
@example(data=b'{"op":"","arrays":[[[],null,null]]}')  # a list as a dtype: found by this fuzz
@given(
    data=st.one_of(
        st.binary(max_size=64),
        st.builds(lambda header: json.dumps(header).encode(), JSON),
        st.builds(
            lambda header, tail: json.dumps(header).encode() + tail,
            st.fixed_dictionaries(
                {"op": st.text(max_size=5)},
                optional={"fn": st.text(max_size=8), "args": JSON, "arrays": JSON},
            ),
            st.binary(max_size=32),
        ),
    )
)
def test_fuzzed_pipe_messages_are_read_as_data_or_refused_in_one_line(data):
    read_fd, write_fd = os.pipe()
    back_read, back_write = os.pipe()
    channel = TrustedChannel(
        read_fd, back_write, PipeBudget(message_bytes=1 << 16, total_bytes=1 << 20)
    )
    try:
        os.write(write_fd, struct.pack(">I", len(data)) + data + bytes(64))
        os.close(write_fd)  # what was not sent never comes: the read ends, closed
        try:
            header, arrays = channel.receive(time.monotonic() + 60)
        except PipeError as exc:
            assert "\n" not in str(exc) and len(str(exc)) < 200
            return
        except PipeClosed:
            return
        assert isinstance(header, dict) and isinstance(header["op"], str)
        assert all(isinstance(a, np.ndarray) for a in arrays)
    finally:
        os.close(back_read)
        channel.close()
