"""mirrorlab's GL layer (:mod:`mirrorlab.gl.calls`) records the renderer's calls as its own
state: nothing in ``mirrorlab/gl/`` replaces an attribute of another module, PyOpenGL's
functions are the same objects before, during and after a recorded frame, and a GL call
made outside the layer while a frame records is neither recorded nor wrapped."""

from __future__ import annotations

import ast
import threading
from pathlib import Path
from types import SimpleNamespace

import pytest
from OpenGL import GL as PYOPENGL_GL

import mirrorlab
from mirrorlab.gl.calls import Call, GLCalls, forget_cached_state, gl, raw, recording
from mirrorlab.gl.opengl import GL, RAW
from mirrorlab.gl.resources import Framebuffer, Program
from mirrorlab.renderer import SceneRenderer

GL_PACKAGE = Path(mirrorlab.__file__).parent / "gl"


def _imported_names(tree: ast.Module) -> set[str]:
    names: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            names.update((alias.asname or alias.name).split(".")[0] for alias in node.names)
    return names


def _replacements(path: Path) -> list[str]:
    """Where the module at ``path`` sets or deletes an attribute of something it imported,
    or calls ``setattr``/``delattr`` at all (``file:line: what``)."""
    tree = ast.parse(path.read_text(), str(path))
    imported = _imported_names(tree)
    found = []
    for node in ast.walk(tree):
        if not isinstance(node, ast.stmt | ast.expr):
            continue
        targets: list[ast.expr] = []
        if isinstance(node, (ast.Assign, ast.Delete)):
            targets = list(node.targets)
        elif isinstance(node, (ast.AugAssign, ast.AnnAssign)):
            targets = [node.target]
        for target in targets:
            base = target
            while isinstance(base, (ast.Attribute, ast.Subscript)):
                base = base.value
            if (
                isinstance(target, ast.Attribute)
                and isinstance(base, ast.Name)
                and base.id in imported
            ):
                found.append(f"{path.name}:{node.lineno}: {ast.unparse(target)}")
        if (
            isinstance(node, ast.Call)
            and isinstance(node.func, ast.Name)
            and node.func.id in ("setattr", "delattr")
        ):
            found.append(f"{path.name}:{node.lineno}: {ast.unparse(node)}")
    return found


def test_nothing_in_the_gl_package_replaces_an_attribute_of_another_module():
    """No module of ``mirrorlab/gl/`` assigns or deletes an attribute of a name it
    imported, nor calls ``setattr``/``delattr``: recording is the layer's own state."""
    modules = sorted(GL_PACKAGE.glob("*.py"))
    assert GL_PACKAGE / "calls.py" in modules
    assert [found for path in modules for found in _replacements(path)] == []


def test_the_check_for_replacements_finds_one(tmp_path):
    """The check above finds both forms it looks for (it can fail)."""
    patched = tmp_path / "patched.py"
    patched.write_text(
        "from OpenGL import GL\nimport ctypes\n"
        "GL.glEnable = print\nsetattr(GL, 'glDisable', print)\nctypes.x.y = 1\n"
    )
    assert len(_replacements(patched)) == 3


def _direct_calls(path: Path) -> list[str]:
    """Where the module at ``path`` calls a GL function straight through PyOpenGL's ``GL``
    or ``RAW`` (``GL.glEnable(...)``), not through the layer (``file:line: call``)."""
    tree = ast.parse(path.read_text(), str(path))
    return [
        f"{path.name}:{node.lineno}: {ast.unparse(node.func)}"
        for node in ast.walk(tree)
        if isinstance(node, ast.Call)
        and isinstance(node.func, ast.Attribute)
        and isinstance(node.func.value, ast.Name)
        and node.func.value.id in ("GL", "RAW")
        and node.func.attr.startswith("gl")
    ]


def test_the_renderers_gl_calls_all_go_through_the_layer(tmp_path):
    """The renderer, its passes and the resources it draws with call GL only through the
    layer: a call made around it would be missing from a recorded frame's replay. (The
    check finds such a call: it can fail.)"""
    package = Path(mirrorlab.__file__).parent
    modules = [
        package / "renderer.py",
        GL_PACKAGE / "resources.py",
        *sorted((package / "passes").glob("*.py")),
    ]
    assert [found for path in modules for found in _direct_calls(path)] == []
    direct = tmp_path / "direct.py"
    direct.write_text("from OpenGL import GL\nGL.glEnable(GL.GL_BLEND)\nRAW.glFlush()\n")
    assert len(_direct_calls(direct)) == 2


def _snapshot() -> tuple[dict[str, int], dict[str, int]]:
    """The identity of every attribute of PyOpenGL's ``GL`` module and of ``RAW``."""
    return (
        {name: id(value) for name, value in vars(PYOPENGL_GL).items()},
        {name: id(value) for name, value in vars(RAW).items()},
    )


def test_a_recorded_frame_leaves_pyopengl_alone_and_records_only_calls_through_the_layer(
    registry,
):
    """A frame planned as the last one was is recorded; while it draws, PyOpenGL's
    functions and ``RAW``'s are the objects they were before and are after, the layer is
    recording, and a call made straight to PyOpenGL then is not among the frame's calls."""
    renderer = SceneRenderer(registry)  # the context's own draw path (per-draw on 4.1)
    target = Framebuffer(registry, 48, 48)
    scene = mirrorlab.load_scene("lab20")
    seen_during: list[tuple[dict[str, int], dict[str, int]]] = []
    outside = GL.glFlush  # a call the frame never makes itself
    draw = renderer.drawer.draw

    def spying_draw(*args, **kwargs):
        if gl.recording:
            seen_during.append(_snapshot())
            outside()  # straight to PyOpenGL, not through the layer
        return draw(*args, **kwargs)

    renderer.drawer.draw = spying_draw  # type: ignore[method-assign]
    try:
        before = _snapshot()
        renderer.render(scene, target)  # planned anew: not recorded
        assert seen_during == [] and renderer._recorded is None
        for _ in range(3):  # the capture made, a frame is planned as the last one
            renderer.render(scene, target)
            if renderer._recorded is not None:
                break
        after = _snapshot()
        recorded = renderer._recorded
        assert recorded is not None and recorded.calls
        assert seen_during and all(during == before for during in seen_during)
        assert after == before
        names = {getattr(function, "__name__", "") for function, _, _ in recorded.calls}
        assert "glFlush" not in names
        assert {"glClear", "glBindFramebuffer", "glUseProgram"} <= names
        assert not gl.recording and not raw.recording
        assert gl.glFlush is outside and raw.glEnable is RAW.glEnable
    finally:
        renderer.release()
        target.release()


def test_a_recording_holds_the_layers_state_changing_calls_in_order_and_makes_them():
    """Inside ``recording``, the calls through :data:`gl` and :data:`raw` that can change
    state are appended (the PyOpenGL function, its arguments) and made; queries are made,
    not recorded; outside it, the layer's attributes are PyOpenGL's functions."""
    assert gl.glEnable is GL.glEnable and raw.glEnable is RAW.glEnable
    calls: list[Call] = []
    was_on = bool(GL.glIsEnabled(GL.GL_BLEND))
    with recording(calls):
        assert gl.glEnable is not GL.glEnable
        gl.glEnable(GL.GL_BLEND)
        assert raw.glIsEnabled(GL.GL_BLEND)
        raw.glDisable(GL.GL_BLEND)
        GL.glEnable(GL.GL_DITHER)  # outside the layer
        assert gl.glGetError() == GL.GL_NO_ERROR
    assert calls == [(GL.glEnable, (GL.GL_BLEND,), {}), (RAW.glDisable, (GL.GL_BLEND,), {})]
    assert not GL.glIsEnabled(GL.GL_BLEND)
    if was_on:
        GL.glEnable(GL.GL_BLEND)
    assert gl.glEnable is GL.glEnable and raw.glDisable is RAW.glDisable


def test_a_recording_sets_every_uniform_it_reads_itself(registry):
    """A program leaves out setting a uniform to the value it holds, but not the first time
    in a recording for a value set before it began (a replay starts from what the last
    frame left, which the recorded one may have changed after reading): inside, a repeat
    is left out again; after a failed frame (:func:`forget_cached_state`) too, it is set."""
    program = Program(registry, "flat.vert", "flat.frag")
    program.use()

    def colour_calls(calls: list[Call]) -> int:
        return sum(function.__name__ == "glUniform3f" for function, _, _ in calls)

    program.set_vec3("color", (0.1, 0.2, 0.3))
    calls: list[Call] = []
    with recording(calls):
        program.set_vec3("color", (0.1, 0.2, 0.3))
        program.set_vec3("color", (0.1, 0.2, 0.3))
    assert colour_calls(calls) == 1
    calls = []
    with recording(calls):
        program.set_vec3("color", (0.1, 0.2, 0.3))  # set in the last recording: set again
        forget_cached_state()
        program.set_vec3("color", (0.1, 0.2, 0.3))  # and again after the memory is dropped
    assert colour_calls(calls) == 2
    GL.glUseProgram(0)


def test_recordings_do_not_nest_and_an_error_inside_stops_one():
    calls: list[Call] = []
    with pytest.raises(KeyError), recording(calls):
        raise KeyError("inside a recording")
    assert not gl.recording and not raw.recording and gl.glEnable is GL.glEnable
    with recording(calls), pytest.raises(RuntimeError, match="already"):
        with recording([]):
            pass
    assert not gl.recording and not raw.recording and raw.glEnable is RAW.glEnable


def test_another_threads_calls_through_a_recording_layer_are_made_and_not_recorded():
    """A recording holds the calls of the thread that made it (a GL context is current in
    one thread): a call another thread makes through the layer meanwhile is made, and
    recorded nowhere. (A layer over a namespace of plain functions: no other thread here
    has a context.)"""
    made: list[int] = []

    def glEnable(cap: int) -> None:
        made.append(cap)

    layer = GLCalls(SimpleNamespace(glEnable=glEnable))
    calls: list[Call] = []
    layer._record_into(calls)
    try:
        seen: list[bool] = []

        def other_thread() -> None:
            seen.append(layer.recording)
            layer.glEnable(2)

        thread = threading.Thread(target=other_thread)
        thread.start()
        thread.join()
        layer.glEnable(1)
        assert layer.recording and seen == [False]
    finally:
        layer._stop_recording()
    assert made == [2, 1]
    assert calls == [(glEnable, (1,), {})]
    assert layer.glEnable is glEnable and not layer.recording
