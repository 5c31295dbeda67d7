"""Every channel from a file's numbers to the frame, closed by construction (issue 44): the
executor fed messages directly in a headless context (no sandbox). Each channel a lab's
handout does not teach is refused whatever picture it tries to carry; uploads take only
None or zeros at every target, level and unit; what a copy takes from outside the
framebuffer is zeros; auto-made mipmaps are made and recorded as made from level 0; a read of any
format the executor accepts works; and the trusted side's own drawing and reading give the
same pixels whatever state a file left (a property, over generated leftover state)."""

from __future__ import annotations

import importlib
from typing import Any

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from OpenGL.error import GLError

from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import Framebuffer, read_pixels
from mirrorlab.labs import find_lab, unregister
from mirrorlab.labs.content import reference_folder
from mirrorlab.labs.trusted import calls as C
from mirrorlab.labs.trusted import legacy
from mirrorlab.labs.trusted.call_executor import Executor
from mirrorlab.labs.trusted.evidence import Evidence
from mirrorlab.labs.trusted.lab_run import reset_state
from mirrorlab.labs.trusted.session import (
    read_cube_faces,
    read_level,
    read_texture_2d,
    texture_parameters,
)
from mirrorlab.labs.trusted.variants import Variant, default_variant
from tests.gl.conftest import module_context
from tests.gl.test_lab_calls import solution_glsl

SIZE = (64, 64)
LABS = ("lab20", "spheremap", "cubemap")
gl_context = pytest.fixture(scope="module", name="gl_context")(module_context)


@pytest.fixture(scope="module")
def quad_lab():
    """The test folder's quad lab, which opens every channel (registered while the module
    runs: lab-parametrised tests elsewhere take the shipped labs)."""
    spec = importlib.import_module("tests.labs.fourth_lab").SPEC
    yield spec
    unregister(spec.name)


@pytest.fixture(scope="module")
def sessions(gl_context, quad_lab):
    """One session of each lab (the sphere-map lab's texgen on unit 2) and a target."""
    from mirrorlab.labs.trusted.session import open_session

    target = Framebuffer(gl_context.resources, *SIZE)
    target.bind()
    variants = {lab: default_variant(lab) for lab in LABS}
    variants["spheremap"] = Variant("spheremap", {**variants["spheremap"].values, "unit": 2})
    found = {lab: open_session(lab, SIZE, variants[lab]) for lab in LABS}
    found[quad_lab.name] = open_session(quad_lab.name, SIZE, default_variant(quad_lab.name))
    yield target, found
    target.release()


@pytest.fixture
def lab(sessions):
    """``lab(name)``: a new executor of that lab in its first frame, on the target."""
    target, found = sessions

    def make(name: str) -> Executor:
        target.bind()
        reset_state()
        ex = Executor(found[name])
        ex.begin_frame()
        return ex

    yield make
    reset_state()
    GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, 0)


def send(ex: Executor, name: str, *args: Any, arrays=(), op: str = "gl") -> dict[str, Any]:
    reply, _ = ex.call({"op": op, "fn": name, "args": list(args), "line": 9}, list(arrays))
    return reply


def reference_bytes(lab: str, count: int) -> np.ndarray:
    """The first ``count`` bytes of ``lab``'s shipped reference frame, rows bottom first as
    GL reads them (the picture a forgery would carry), never all zeros."""
    frame = Evidence.load(reference_folder(find_lab(lab))).arrays["frame"][::-1]
    data = np.resize(np.ascontiguousarray(frame).reshape(-1), count)
    assert data.any()
    return data


def texture(ex: Executor, target: int = GL.GL_TEXTURE_2D) -> int:
    name = send(ex, "glGenTextures", 1)["value"]
    assert send(ex, "glBindTexture", int(target), name)["ok"]
    return int(name)


# ------------------------------------------------------------------ the list is closed
def test_every_call_switch_and_mode_is_a_channels_or_carries_no_number(quad_lab):
    """The closure, not a list: a call, a glEnable switch, a glBegin mode or a matrix mode
    added to the allow-list must be classed as a channel's or as carrying no number of the
    file's to a pixel, or this fails."""
    in_channels = {name for channel in C.CHANNELS.values() for name in channel.calls}
    assert len(in_channels) == sum(len(c.calls) for c in C.CHANNELS.values())  # one each
    assert set(C.GL_SPECS) == in_channels | C.NEUTRAL
    assert not in_channels & C.NEUTRAL
    caps = {cap for channel in C.CHANNELS.values() for cap in channel.caps}
    assert C.CAPS == caps | C.NEUTRAL_CAPS and not caps & C.NEUTRAL_CAPS
    assert C.BEGIN_MODES == {m for c in C.CHANNELS.values() for m in c.modes}
    matrix_modes = {m for c in C.CHANNELS.values() for m in c.matrix_modes}
    assert C.MATRIX_MODES == matrix_modes | C.enums("GL_MODELVIEW", "GL_PROJECTION")
    # what every handout uses carries no number to a pixel
    assert {"glColorMask", "glDepthMask", "glClearColor", "glViewport", "glTexImage2D"} <= C.NEUTRAL
    taught = {lab: C.lab_channels(lab) for lab in LABS}
    assert taught == {
        "lab20": {"immediate_mode", "texture_coordinates", "copies"},
        "spheremap": {"texgen"},
        "cubemap": {"copies"},
    }
    assert C.lab_channels(quad_lab.name) == set(C.CHANNELS)


def closed_cases() -> list[tuple[str, str]]:
    return [
        (lab, name)
        for lab in LABS
        for name in C.CHANNELS
        if name not in {"immediate_mode", "texture_coordinates", "copies"} or lab != "lab20"
        if not (lab == "spheremap" and name == "texgen")
        and not (lab == "cubemap" and name == "copies")
    ]


@pytest.mark.parametrize(("lab_name", "channel"), closed_cases())
def test_a_closed_channel_carries_no_picture(lab, lab_name, channel):
    """Every call, switch, mode and matrix mode of a channel the lab's handout does not
    teach is refused in one line, whatever it carries (here, the reference frame's
    numbers), and leaves GL as it was."""
    ex = lab(lab_name)
    found = C.CHANNELS[channel]
    picture = reference_bytes(lab_name, 64).astype(float) / 255
    tries: list[tuple[str, list[Any]]] = [
        (name, [float(v) for v in picture[: len(C.GL_SPECS[name].kinds)]]) for name in found.calls
    ]
    tries += [("glBegin", [mode]) for mode in found.modes]
    tries += [("glEnable", [cap]) for cap in found.caps]
    tries += [("glMatrixMode", [mode]) for mode in found.matrix_modes]
    assert tries, channel
    before = np.asarray(GL.glGetIntegerv(GL.GL_VIEWPORT)).tolist()
    for name, args in tries:
        reply = send(ex, name, *args)
        assert not reply["ok"] and reply["type"] == "NotImplementedError", (name, reply)
        assert (
            "this lab's handout draws nothing with it" in reply["message"]
            or f"{name} is not one of the OpenGL calls this lab offers: " in reply["message"]
        ), reply
        assert "\n" not in reply["message"]
    assert ex.tracker.primitive is None and not legacy.gl().glIsEnabled(GL.GL_BLEND)
    assert np.asarray(GL.glGetIntegerv(GL.GL_VIEWPORT)).tolist() == before
    assert int(GL.glGetError()) == GL.GL_NO_ERROR
    # switching a closed switch off is harmless, and allowed
    for cap in found.caps:
        assert send(ex, "glDisable", cap)["ok"]


# ------------------------------------------------------------------ uploads and copies
IMAGE_TARGETS = sorted(C.IMAGE_TARGETS)


@pytest.mark.parametrize("lab_name", LABS)
def test_uploads_carry_no_pixels_at_any_target_level_or_unit(lab, lab_name):
    """glTexImage2D and glTexSubImage2D take None or zeros, on every unit, target and
    level: the reference frame's bytes never reach GL."""
    ex = lab(lab_name)
    data = reference_bytes(lab_name, 8 * 8 * 4)
    for unit in (0, 4, 7):
        send(ex, "glActiveTexture", int(GL.GL_TEXTURE0) + unit)
        plane = texture(ex)
        cube = texture(ex, GL.GL_TEXTURE_CUBE_MAP)
        for image_target in IMAGE_TARGETS:
            bound = plane if image_target == GL.GL_TEXTURE_2D else cube
            for level in (0, 2):
                upload = (image_target, level, int(GL.GL_RGBA), 8, 8, 0, int(GL.GL_RGBA))
                reply = send(
                    ex,
                    "glTexImage2D",
                    *upload,
                    int(GL.GL_UNSIGNED_BYTE),
                    {"$a": 0},
                    arrays=[data],
                )
                assert reply["type"] == "ValueError", reply
                assert "no pixels of a file's own" in reply["message"]
                images = ex.tracker.textures[bound].images.values()
                assert all(image.source == "blank" for image in images)
                blank = send(
                    ex,
                    "glTexImage2D",
                    *upload,
                    int(GL.GL_UNSIGNED_BYTE),
                    {"$a": 0},
                    arrays=[np.zeros(data.size, np.uint8)],
                )
                assert blank["ok"], blank
                sub = (image_target, level, 0, 0, 8, 8, int(GL.GL_RGBA), int(GL.GL_UNSIGNED_BYTE))
                reply = send(ex, "glTexSubImage2D", *sub, {"$a": 0}, arrays=[data])
                assert reply["type"] == "ValueError", reply
                assert read_level(image_target, level).any() == np.False_
        send(ex, "glDeleteTextures", [plane, cube])
    send(ex, "glActiveTexture", int(GL.GL_TEXTURE0))


def test_a_blank_texture_is_zeros_whatever_gl_held_before(lab):
    """None is uploaded as zeros: GL's own None leaves a texture's memory undefined, which
    may hold what an earlier texture (another file's, a reference's) had."""
    ex = lab("lab20")
    picture = reference_bytes("lab20", 64 * 64 * 4).reshape(64, 64, 4)
    for _ in range(4):  # the checker's own textures, freed: their memory goes back
        own = int(GL.glGenTextures(1))
        GL.glBindTexture(GL.GL_TEXTURE_2D, own)
        GL.glTexImage2D(
            GL.GL_TEXTURE_2D, 0, GL.GL_RGBA8, 64, 64, 0, GL.GL_RGBA, GL.GL_UNSIGNED_BYTE, picture
        )
        GL.glDeleteTextures([own])
    name = texture(ex)
    image = (int(GL.GL_TEXTURE_2D), 0, int(GL.GL_RGBA), 64, 64, 0, int(GL.GL_RGBA))
    assert send(ex, "glTexImage2D", *image, int(GL.GL_UNSIGNED_BYTE), None)["ok"]
    assert not read_texture_2d(name).any()


@pytest.mark.parametrize(
    "rectangle",
    [(-8, 0, 64, 64), (0, -8, 16, 16), (8, 0, 64, 64), (60, 60, 8, 2), (-4, -4, 72, 70)],
)
def test_what_a_copy_takes_from_outside_the_framebuffer_is_zeros(lab, rectangle):
    """GL's pixels outside the framebuffer are undefined (memory of anything's): the texels
    a copy takes from there are zeros; the rest is the frame's."""
    ex = lab("lab20")
    send(ex, "glClearColor", 1.0, 1.0, 1.0, 1.0)
    send(ex, "glClear", int(GL.GL_COLOR_BUFFER_BIT))
    name = texture(ex)
    x, y, width, height = rectangle
    assert send(ex, "glCopyTexImage2D", int(GL.GL_TEXTURE_2D), 0, int(GL.GL_RGB), *rectangle, 0)[
        "ok"
    ]
    image = read_texture_2d(name)[::-1]  # rows from the bottom, as the framebuffer's
    ys, xs = np.mgrid[0:height, 0:width]
    inside = (xs + x >= 0) & (xs + x < SIZE[0]) & (ys + y >= 0) & (ys + y < SIZE[1])
    assert image.shape == (height, width, 3)
    assert (image[inside] == 255).all() and not image[~inside].any()
    assert ex.tracker.textures[name].images[(0, 0)].source == "copy"


def test_auto_made_mipmaps_are_made_and_known_as_made_from_level_0(lab):
    """GL_GENERATE_MIPMAP: a write to level 0 remakes the levels below (in GL, and by the
    emulation on a core context), and the record says each was made from level 0; writing
    level 0 again blank leaves no level holding the earlier picture."""
    ex = lab("lab20")
    assert send(ex, "draw_scene", {"textures": {}}, op="kit")["ok"]
    name = texture(ex)
    send(ex, "glTexParameteri", int(GL.GL_TEXTURE_2D), int(GL.GL_GENERATE_MIPMAP), 1)
    assert send(ex, "glCopyTexImage2D", int(GL.GL_TEXTURE_2D), 0, int(GL.GL_RGB), 0, 0, 64, 64, 0)[
        "ok"
    ]
    record = ex.tracker.textures[name]
    assert [record.images[(0, level)].source for level in range(7)] == ["copy"] + ["mipmap"] * 6
    GL.glBindTexture(GL.GL_TEXTURE_2D, name)
    assert read_level(GL.GL_TEXTURE_2D, 1).any() and read_level(GL.GL_TEXTURE_2D, 6).any()
    image = (int(GL.GL_TEXTURE_2D), 0, int(GL.GL_RGB), 64, 64, 0, int(GL.GL_RGB))
    assert send(ex, "glTexImage2D", *image, int(GL.GL_UNSIGNED_BYTE), None)["ok"]
    assert [record.images[(0, level)].source for level in range(7)] == ["blank"] + ["mipmap"] * 6
    for level in range(7):
        assert not read_level(GL.GL_TEXTURE_2D, level).any(), level


# ------------------------------------------------------------------ reads of any format
@pytest.mark.parametrize("internal", sorted(C.INTERNAL_FORMATS))
def test_a_read_of_any_accepted_format_works(lab, internal):
    """Whatever format a copy or an upload gave a texture, the checker's reads of it work:
    a depth copy reads as grey, the others as GL reads them back."""
    ex = lab("cubemap")
    assert send(ex, "set_viewer", op="kit")["ok"]
    assert send(ex, "draw_scene", op="kit")["ok"]
    send(ex, "glActiveTexture", int(GL.GL_TEXTURE1))
    plane = texture(ex)
    copy = send(ex, "glCopyTexImage2D", int(GL.GL_TEXTURE_2D), 0, internal, 0, 0, 64, 64, 0)
    cube = texture(ex, GL.GL_TEXTURE_CUBE_MAP)
    for face in range(6):
        target = int(GL.GL_TEXTURE_CUBE_MAP_POSITIVE_X) + face
        send(ex, "glCopyTexImage2D", target, 0, internal, 0, 0, 16, 16, 0)
    send(ex, "glActiveTexture", int(GL.GL_TEXTURE0))
    reset_state()
    image = read_texture_2d(plane)
    faces = read_cube_faces(cube)
    assert texture_parameters(plane)["width"] in (0, 64)
    assert int(GL.glGetError()) == GL.GL_NO_ERROR
    if copy["ok"]:
        assert image.shape == (64, 64, 3) and image.dtype == np.uint8
        assert faces is not None and faces.shape == (6, 16, 16, 3)
        depth = internal in (
            GL.GL_DEPTH_COMPONENT,
            GL.GL_DEPTH_COMPONENT16,
            GL.GL_DEPTH_COMPONENT24,
        )
        if depth:  # the depths of the scene: grey, not black
            assert np.ptp(image[..., 0]) > 0 and (image[..., 0] == image[..., 2]).all()
    else:
        assert copy["type"] == "GLError" and "\n" not in copy["message"], copy


# ------------------------------------------------------------------ no state inherited
def _own_textures(session: Any) -> dict[str, int]:
    """A 2D texture holding a lab picture, a blank one and a cube map of copies, made
    with the checker's own calls (as a file's would be)."""
    metal, blank, cube = (int(t) for t in GL.glGenTextures(3))
    session.load_picture_texture(metal, "metal")
    GL.glBindTexture(GL.GL_TEXTURE_2D, blank)
    GL.glTexImage2D(GL.GL_TEXTURE_2D, 0, GL.GL_RGB, 4, 4, 0, GL.GL_RGB, GL.GL_UNSIGNED_BYTE, None)
    GL.glBindTexture(GL.GL_TEXTURE_CUBE_MAP, cube)
    for face in range(6):
        GL.glTexImage2D(
            GL.GL_TEXTURE_CUBE_MAP_POSITIVE_X + face,
            0,
            GL.GL_RGB,
            8,
            8,
            0,
            GL.GL_RGB,
            GL.GL_UNSIGNED_BYTE,
            np.full(8 * 8 * 3, 40 * face, np.uint8),
        )
    for pname in (GL.GL_TEXTURE_MIN_FILTER, GL.GL_TEXTURE_MAG_FILTER):
        GL.glTexParameteri(GL.GL_TEXTURE_CUBE_MAP, pname, GL.GL_LINEAR)
    return {"metal": metal, "blank": blank, "cube": cube}


UNIT_CAPS = (GL.GL_TEXTURE_2D, GL.GL_TEXTURE_CUBE_MAP, *(GL.GL_TEXTURE_GEN_S + i for i in range(4)))
LEFTOVER = st.one_of(
    st.tuples(st.just("push"), st.sampled_from(sorted(C.MATRIX_MODES)), st.integers(0, 40)),
    st.tuples(st.just("mode"), st.sampled_from(sorted(C.MATRIX_MODES))),
    st.tuples(st.just("unit"), st.integers(0, 7)),
    st.tuples(st.just("cap"), st.sampled_from(sorted(C.CAPS)), st.integers(0, 7), st.booleans()),
    st.tuples(
        st.just("bind"),
        st.integers(0, 7),
        st.sampled_from(["metal", "blank", "cube"]),
    ),
    st.tuples(st.just("texenv"), st.integers(0, 7), st.sampled_from(sorted(C.TEXENV_MODES))),
    st.tuples(
        st.just("texgen"),
        st.integers(0, 7),
        st.sampled_from(sorted(C.TEXGEN_COORDS)),
        st.sampled_from([GL.GL_EYE_LINEAR, GL.GL_OBJECT_LINEAR]),
        st.floats(-3, 3),
    ),
    st.tuples(st.just("texture_matrix"), st.integers(0, 7), st.floats(-3, 3)),
    st.tuples(st.just("texcoord"), st.integers(0, 7), st.floats(0.2, 4)),
    st.tuples(st.just("colour"), st.floats(0, 1), st.floats(0, 1)),
    st.tuples(
        st.just("pixel_store"), st.sampled_from(sorted(C.STORE_PARAMS)), st.sampled_from([1, 2, 8])
    ),
    st.tuples(
        st.just("masks"), st.booleans(), st.booleans(), st.sampled_from(sorted(C.DEPTH_FUNCS))
    ),
    st.tuples(
        st.just("blend"),
        st.sampled_from(sorted(C.BLEND_FACTORS)),
        st.sampled_from(sorted(C.BLEND_FACTORS)),
    ),
    st.tuples(
        st.just("raster"),
        st.sampled_from(sorted(C.POLYGON_MODES)),
        st.sampled_from(sorted(C.FACES)),
        st.sampled_from(sorted(C.WINDINGS)),
    ),
    st.tuples(
        st.just("scissor"),
        st.integers(0, 60),
        st.integers(0, 60),
        st.integers(0, 8),
        st.integers(0, 8),
    ),
    st.tuples(st.just("program"), st.booleans()),
)
"""One piece of state a file could leave, set straight in GL (or the emulation), whether
or not its lab's calls would let a file set it: the trusted side must not depend on any."""


def leave(step: tuple[Any, ...], session: Any, textures: dict[str, int]) -> None:
    """Set ``step``'s state, as a file's calls would have (errors GL gives are GL's)."""
    FF = legacy.gl()
    kind, *args = step
    try:
        if kind == "push":
            FF.glMatrixMode(args[0])
            for _ in range(args[1]):
                FF.glPushMatrix()
                FF.glScalef(1.5, 0.5, 2.0)
        elif kind == "mode":
            FF.glMatrixMode(args[0])
        elif kind == "unit":
            GL.glActiveTexture(GL.GL_TEXTURE0 + args[0])
        elif kind == "cap":
            GL.glActiveTexture(GL.GL_TEXTURE0 + args[1])
            (FF.glEnable if args[2] else FF.glDisable)(args[0])
        elif kind == "bind":
            GL.glActiveTexture(GL.GL_TEXTURE0 + args[0])
            target = GL.GL_TEXTURE_CUBE_MAP if args[1] == "cube" else GL.GL_TEXTURE_2D
            GL.glBindTexture(target, textures[args[1]])
        elif kind == "texenv":
            GL.glActiveTexture(GL.GL_TEXTURE0 + args[0])
            FF.glTexEnvi(GL.GL_TEXTURE_ENV, GL.GL_TEXTURE_ENV_MODE, args[1])
        elif kind == "texgen":
            GL.glActiveTexture(GL.GL_TEXTURE0 + args[0])
            FF.glTexGeni(args[1], GL.GL_TEXTURE_GEN_MODE, args[2])
            plane = np.array([args[3], 0.5, -args[3], 0.25])
            for pname in (GL.GL_EYE_PLANE, GL.GL_OBJECT_PLANE):
                FF.glTexGenfv(args[1], pname, plane)
        elif kind == "texture_matrix":
            GL.glActiveTexture(GL.GL_TEXTURE0 + args[0])
            FF.glMatrixMode(GL.GL_TEXTURE)
            FF.glLoadIdentity()
            FF.glScalef(args[1], 1.0 / max(abs(args[1]), 0.25), 1.0)
        elif kind == "texcoord":
            FF.glMultiTexCoord4f(GL.GL_TEXTURE0 + args[0], 0.3, 0.6, 0.0, args[1])
        elif kind == "colour":
            FF.glColor4f(args[0], args[1], 1.0 - args[0], args[1])
        elif kind == "pixel_store":
            GL.glPixelStorei(args[0], args[1])
        elif kind == "masks":
            GL.glColorMask(args[0], not args[0], args[1], True)
            GL.glDepthMask(args[1])
            GL.glDepthFunc(args[2])
        elif kind == "blend":
            GL.glEnable(GL.GL_BLEND)
            GL.glBlendFunc(args[0], args[1])
        elif kind == "raster":
            FF.glPolygonMode(GL.GL_FRONT_AND_BACK, args[0])
            GL.glEnable(GL.GL_CULL_FACE)
            GL.glCullFace(args[1])
            GL.glFrontFace(args[2])
        elif kind == "scissor":
            GL.glEnable(GL.GL_SCISSOR_TEST)
            GL.glScissor(*args)
        elif kind == "program":
            GL.glUseProgram(max(session.programs()) if args[0] and session.programs() else 0)
    except (GLError, C.CallError):  # GL refused it (a full stack ...), as a file's call
        pass
    while GL.glGetError() != GL.GL_NO_ERROR:
        pass


def taught(session: Any, textures: dict[str, int]) -> None:
    """What the handout has the file set for the kit's drawing: the viewport and the
    viewer, and for the texgen cone its unit's texture and s and t by sphere map."""
    GL.glViewport(0, 0, *SIZE)
    session.set_viewer()
    unit = getattr(session, "texgen_unit", None)
    if unit is not None:
        FF = legacy.gl()
        GL.glActiveTexture(GL.GL_TEXTURE0 + unit)
        GL.glBindTexture(GL.GL_TEXTURE_2D, textures["metal"])
        for coord, cap in ((GL.GL_S, GL.GL_TEXTURE_GEN_S), (GL.GL_T, GL.GL_TEXTURE_GEN_T)):
            FF.glTexGeni(coord, GL.GL_TEXTURE_GEN_MODE, GL.GL_SPHERE_MAP)
            FF.glEnable(cap)


GLSL = {lab: solution_glsl(lab) for lab in ("spheremap", "cubemap")}
"""The solutions' GLSL (the kit's shader draws take a file's)."""


def kit_draws(lab_name: str, session: Any, textures: dict[str, int]) -> list[Any]:
    """The trusted side's draws for ``lab_name``, each a function."""
    if lab_name == "lab20":
        return [lambda: session.draw_scene({"base": textures["metal"]})]
    if lab_name == "spheremap":
        return [
            session.draw_backdrop,
            lambda: session.draw_cone_shader(GLSL["spheremap"], textures["metal"]),
            session.draw_cone_fixed_function,
        ]
    return [session.draw_scene, lambda: session.draw_sphere(GLSL["cubemap"], textures["cube"])]


def render_after(lab_name: str, sessions: Any, steps: list[tuple[Any, ...]]) -> list[np.ndarray]:
    """Each of the kit's draws into a cleared target after ``steps`` and what the handout
    sets, then the checker's reads of the file's textures after ``steps``."""
    target, found = sessions
    session = found[lab_name]
    textures = _own_textures(session)
    pictures = []
    try:
        for index in range(len(kit_draws(lab_name, session, textures)) + 1):
            target.bind()
            reset_state()
            GL.glClearColor(0.1, 0.2, 0.3, 1.0)
            GL.glClear(GL.GL_COLOR_BUFFER_BIT | GL.GL_DEPTH_BUFFER_BIT)
            for step in steps:
                leave(step, session, textures)
            taught(session, textures)
            draws = kit_draws(lab_name, session, textures)
            if index < len(draws):
                draws[index]()
                assert int(GL.glGetError()) == GL.GL_NO_ERROR
                target.bind()
                pictures.append(read_pixels(*SIZE))
            else:
                pictures.append(read_texture_2d(textures["metal"]))
                cube = read_cube_faces(textures["cube"])
                assert cube is not None
                pictures.append(cube)
    finally:
        reset_state()
        GL.glDeleteTextures(list(textures.values()))
    return pictures


@settings(
    max_examples=30,
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow],
)
@given(lab_name=st.sampled_from(LABS), steps=st.lists(LEFTOVER, min_size=1, max_size=12))
def test_the_trusted_side_inherits_no_state_a_file_left(sessions, lab_name, steps):
    """The kit's draws and the checker's reads give the same pixels after any state a file
    left (stacks full, every unit's switches, bindings, texture environments, texgen and
    texture matrices, current coordinates and colour, pixel store, masks, blending,
    culling, scissor, program) as after none: they set what they depend on themselves."""
    clean = render_after(lab_name, sessions, [])
    after = render_after(lab_name, sessions, steps)
    assert len(clean) == len(after)
    for index, (a, b) in enumerate(zip(clean, after, strict=True)):
        assert a.shape == b.shape and np.array_equal(a, b), (index, steps)
