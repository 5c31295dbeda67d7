"""Runs one student's lab file and notes what its GL state and pictures show.

``python -m mirrorlab.labs.harness LAB FILE OUT_DIR [--size WxH]`` is what the sandbox
runs (:mod:`mirrorlab.labs.sandbox`); it is the only place a student's code is executed.
It opens a headless context and the lab's session, runs the file, calls the lab's
functions in the order the lab's own program does, and writes ``OUT_DIR/run.json`` (what
ran, each error with its function and the student's line, the state it read) and
``OUT_DIR/observations.npz`` (pictures and matrices). The checker reads only those two
files. ``--window`` runs the same file in a window instead (``mirrorlab lab run``).
"""

from __future__ import annotations

import argparse
import json
import sys
import traceback
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from mirrorlab.labs import LABS, LabSpec

FRAMES = 2
"""Frames drawn by the check: the second shows what a capture left for the next frame."""


class StudentFailure(Exception):
    """A student's function raised; the error is already recorded."""


class Run:
    """What one run of a student's file showed: errors, calls, state and pictures."""

    def __init__(self, spec: LabSpec, path: Path) -> None:
        self.spec = spec
        self.path = path
        self.errors: list[dict[str, Any]] = []
        self.calls: list[str] = []
        self.state: dict[str, Any] = {}
        self.arrays: dict[str, np.ndarray] = {}

    def error(self, function: str, kind: str, message: str, line: int = 0,
              code: str = "") -> None:
        if any(e["function"] == function for e in self.errors):
            return
        self.errors.append({"function": function, "kind": kind, "message": message[:300],
                            "line": int(line), "code": code.strip()[:200]})

    def exception(self, function: str, exc: BaseException) -> None:
        """Record ``exc`` raised in ``function`` at the deepest line of the student's file."""
        line, code = 0, ""
        for frame in traceback.extract_tb(exc.__traceback__):
            if Path(frame.filename) == self.path:
                line, code = frame.lineno or 0, frame.line or ""
        from mirrorlab.labs.kit import StudentShaderError

        if isinstance(exc, StudentShaderError):
            self.error(function, "glsl", str(exc), line, code)
            return
        message = f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__
        self.error(function, "exception", message, line, code)

    def write(self, out_dir: Path) -> None:
        out_dir.mkdir(parents=True, exist_ok=True)
        np.savez_compressed(out_dir / "observations.npz", **self.arrays)
        (out_dir / "run.json").write_text(json.dumps(
            {"lab": self.spec.name, "errors": self.errors, "calls": self.calls[:2000],
             "state": self.state}, default=_plain))


def _plain(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(f"cannot write {type(value).__name__} to run.json")


def load_student(path: Path, run: Run) -> dict[str, Any] | None:
    """Execute the student's file as a module of its own; None when it does not run."""
    try:
        source = path.read_text()
    except (OSError, UnicodeDecodeError) as exc:
        run.error("<file>", "unreadable", f"cannot read {path.name}: {exc}")
        return None
    try:
        code = compile(source, str(path), "exec")
    except SyntaxError as exc:
        run.error("<file>", "syntax", f"SyntaxError: {exc.msg}", exc.lineno or 0,
                  exc.text or "")
        return None
    namespace: dict[str, Any] = {"__name__": "student_lab", "__file__": str(path)}
    try:
        exec(code, namespace)
    except BaseException as exc:
        run.exception("<file>", exc)
        return None
    return namespace


def wrap_functions(namespace: dict[str, Any], run: Run, session: Any,
                   after: dict[str, Callable[[], None]]) -> None:
    """Replace each of the lab's functions in ``namespace`` by a wrapper that notes its
    calls, records an error once (at the function that raised), and calls ``after[name]``
    when it returns. A missing function becomes one that records so."""
    for name in run.spec.functions:
        original = namespace.get(name)
        if not callable(original):
            problem = ("is missing" if original is None else
                       f"is a {type(original).__name__}, not a function")
            run.error(name, "missing", f"{name}() {problem}: define def {name}(): as in "
                      f"the starter")

            def missing(*args: Any, _name: str = name, **kwargs: Any) -> None:
                run.calls.append(f"raise {_name}")
                raise StudentFailure(_name)

            namespace[name] = missing
            continue

        def wrapper(*args: Any, _name: str = name, _original: Callable = original,
                    **kwargs: Any) -> Any:
            session.steps.append(_name)
            run.calls.append(f"start {_name}")
            try:
                return _original(*args, **kwargs)
            except StudentFailure:
                raise
            except BaseException as exc:
                run.exception(_name, exc)
                run.calls.append(f"raise {_name}")
                raise StudentFailure(_name) from None
            finally:
                session.steps.pop()
                run.calls.append(f"end {_name}")
                hook = after.get(_name)
                if hook is not None:
                    hook()

        namespace[name] = wrapper


def call(namespace: dict[str, Any], name: str) -> bool:
    """Call the student's ``name()``; False when it (or a function it called) raised."""
    try:
        namespace[name]()
    except StudentFailure:
        return False
    return True


def run_frames(namespace: dict[str, Any], run: Run, session: Any) -> None:
    """The student's ``display()`` for up to FRAMES frames (until one raises), then the last
    frame read back; its events (what was drawn, in which of the student's functions) are
    kept in ``session.events`` and, the first 100, in the run's ``frame_events``."""
    for frame in range(FRAMES):
        session.events.clear()
        run.calls.append(f"frame {frame}")
        if not call(namespace, "display"):
            break
    finish_frame(run, session)
    run.state["frame_events"] = [
        {"kind": e["kind"], "steps": e["steps"]} for e in session.events][:100]


# ---------------------------------------------------------------------------- the labs


def drive_lab20(namespace: dict[str, Any], run: Run, session: Any) -> None:
    from mirrorlab.gl.opengl import GL
    from mirrorlab.labs import kit

    def ids() -> tuple[int, int] | None:
        try:
            tex_ids = namespace["tex_ids"]
            return int(tex_ids[namespace["ENVIRONMENT"]]), int(tex_ids[namespace["METAL"]])
        except Exception:
            return None

    def after_load_textures() -> None:
        got = ids()
        if got is None or not GL.glIsTexture(got[0]):
            run.state["environment_parameters"] = None
            return
        run.state["environment_parameters"] = kit.texture_parameters(got[0])

    def after_build_scene_graph() -> None:
        got = ids()
        robot = namespace.get("robot")
        texture = None
        try:
            texture = robot["base"].texture if robot is not None else None
        except Exception:
            texture = None
        names = {None: "none", 0: "none"}
        if got is not None:
            names.update({got[0]: "environment", got[1]: "metal"})
        try:
            run.state["base_texture"] = names.get(texture, f"other ({texture!r})"[:60])
        except TypeError:
            run.state["base_texture"] = f"other ({type(texture).__name__})"

    def after_create_mirror() -> None:
        projection, modelview = kit.current_matrices()
        run.arrays["projection_after_capture"] = projection
        run.arrays["modelview_after_capture"] = modelview
        got = ids()
        if got is not None and GL.glIsTexture(got[0]):
            run.arrays["capture"] = kit.read_texture_2d(got[0])

    def after_render_mirror() -> None:
        value = np.zeros(1, dtype=np.int32)
        if session.texSampler >= 0:
            GL.glGetUniformiv(session.textureShader, session.texSampler, value)
        run.state["sampler"] = int(value[0])
        got = ids()
        run.state["environment_units"] = kit.bound_units(got[0]) if got else []

    wrap_functions(namespace, run, session, {
        "load_textures": after_load_textures, "build_scene_graph": after_build_scene_graph,
        "create_mirror": after_create_mirror, "render_mirror": after_render_mirror})
    call(namespace, "load_textures")
    call(namespace, "build_scene_graph")
    run_frames(namespace, run, session)
    got = ids()
    if got is not None and GL.glIsTexture(got[1]):
        metal = kit.read_texture_2d(got[1])
        original = kit.picture("metal")
        run.state["metal_intact"] = bool(metal.shape == original.shape
                                         and np.array_equal(metal, original))
    scene_draws = [e for e in session.events if e["kind"] == "draw_scene"]
    capture_draws = [e for e in scene_draws if "create_mirror" in e["steps"]]
    if capture_draws:
        run.arrays["projection_capture"] = capture_draws[0]["projection"]
        run.arrays["modelview_capture"] = capture_draws[0]["modelview"]


def drive_spheremap(namespace: dict[str, Any], run: Run, session: Any) -> None:
    from mirrorlab.gl.opengl import GL

    def after_draw_cone_texgen() -> None:
        run.state["texgen_after"] = {
            "gen_s": bool(GL.glIsEnabled(GL.GL_TEXTURE_GEN_S)),
            "gen_t": bool(GL.glIsEnabled(GL.GL_TEXTURE_GEN_T))}

    wrap_functions(namespace, run, session, {"draw_cone_texgen": after_draw_cone_texgen})
    call(namespace, "load_textures")
    call(namespace, "setup_texgen")
    run_frames(namespace, run, session)
    fixed = [e for e in session.events if e["kind"] == "draw_cone_fixed_function"]
    run.state["texgen_draws"] = [{k: v for k, v in e.items() if k != "kind"} for e in fixed]
    run.state["launch_texture"] = int(session.backdrop_texture)
    texture = namespace.get("launch")
    run.state["student_launch"] = int(texture) if isinstance(texture, int | np.integer) else -1
    glsl = namespace.get("SPHERE_MAP_GLSL")
    check_values(run, session, lambda mode: session.draw_cone_shader(
        glsl, session.backdrop_texture, mode), {"r": 1, "u": 2, "n": 3, "st": 4},
        "reflect_eye")


def drive_cubemap(namespace: dict[str, Any], run: Run, session: Any) -> None:
    from mirrorlab.gl.opengl import GL

    def cube_id() -> int:
        value = namespace.get("cube_texture")
        return int(value) if isinstance(value, int | np.integer) else 0

    def after_capture_cube() -> None:
        texture = cube_id()
        if not texture or not GL.glIsTexture(texture):
            return
        faces = read_cube_faces(texture)
        if faces is not None:
            run.arrays["cube_faces"] = faces

    wrap_functions(namespace, run, session, {"capture_cube": after_capture_cube})
    call(namespace, "create_cube_texture")
    run_frames(namespace, run, session)
    draws = [e for e in session.events if e["kind"] == "draw_scene"
             and "capture_cube" in e["steps"]]
    if draws:
        run.arrays["capture_projections"] = np.stack([e["projection"] for e in draws][:12])
        run.arrays["capture_modelviews"] = np.stack([e["modelview"] for e in draws][:12])
        run.state["capture_viewports"] = [e["viewport"] for e in draws][:12]
    run.state["cube_texture"] = cube_id()
    glsl = namespace.get("CUBE_MAP_GLSL")
    check_values(run, session, lambda mode: session.draw_sphere(glsl, cube_id(), mode),
                 {"face_st": 1, "r": 2}, "cube_face")


def read_cube_faces(texture: int) -> np.ndarray | None:
    """The six level-0 faces of cube map ``texture``, ``(6, n, n, 3)`` uint8 (row 0 at
    ``t = 1``), or None when they are not all the same square size."""
    from mirrorlab.gl.opengl import GL

    previous = int(GL.glGetIntegerv(GL.GL_TEXTURE_BINDING_CUBE_MAP))
    GL.glBindTexture(GL.GL_TEXTURE_CUBE_MAP, texture)
    faces = []
    for face in range(6):
        target = GL.GL_TEXTURE_CUBE_MAP_POSITIVE_X + face
        width = int(GL.glGetTexLevelParameteriv(target, 0, GL.GL_TEXTURE_WIDTH))
        height = int(GL.glGetTexLevelParameteriv(target, 0, GL.GL_TEXTURE_HEIGHT))
        if width == 0 or width != height or (faces and faces[0].shape[0] != width):
            GL.glBindTexture(GL.GL_TEXTURE_CUBE_MAP, previous)
            return None
        GL.glPixelStorei(GL.GL_PACK_ALIGNMENT, 1)
        data = GL.glGetTexImage(target, 0, GL.GL_RGB, GL.GL_UNSIGNED_BYTE)
        faces.append(np.frombuffer(data, dtype=np.uint8).reshape(width, width, 3)[::-1])
    GL.glBindTexture(GL.GL_TEXTURE_CUBE_MAP, previous)
    return np.stack(faces)


def check_values(run: Run, session: Any, draw: Callable[[int], None], modes: dict[str, int],
                 function: str) -> None:
    """Draw with each check ``mode`` of the kit's shader into a float target and keep the
    values (``values_<name>``, ``(h, w, 3)`` float32) and the coverage mask."""
    from mirrorlab.gl.opengl import GL
    from mirrorlab.gl.resources import FloatFramebuffer
    from mirrorlab.labs.kit import LabSetupError

    target = FloatFramebuffer(session.registry, session.width, session.height)
    try:
        target.bind()
        GL.glViewport(0, 0, session.width, session.height)
        session.set_viewer()
        for name, mode in modes.items():
            GL.glClearColor(0.0, 0.0, 0.0, 0.0)
            GL.glClear(GL.GL_COLOR_BUFFER_BIT | GL.GL_DEPTH_BUFFER_BIT)
            try:
                draw(mode)
            except LabSetupError as exc:
                run.exception(function, exc)
                return
            rgba = target.read_rgba()
            run.arrays[f"values_{name}"] = rgba[..., :3].astype(np.float32)
            run.arrays["values_mask"] = rgba[..., 3] > 0.5
    finally:
        target.release()


def finish_frame(run: Run, session: Any) -> None:
    """Read the frame the student's display() left in the target."""
    from mirrorlab.gl.opengl import GL

    target = getattr(session, "target", None)
    if target is not None:
        target.bind()
    GL.glViewport(0, 0, session.width, session.height)
    run.arrays["frame"] = session.read_frame()
    while GL.glGetError() != GL.GL_NO_ERROR:
        run.state["gl_error"] = True


DRIVERS = {"lab20": drive_lab20, "spheremap": drive_spheremap, "cubemap": drive_cubemap}


def check_file(lab: str, path: Path, out_dir: Path, size: tuple[int, int]) -> int:
    """Run ``path`` headless as lab ``lab`` and write what it showed into ``out_dir``."""
    from mirrorlab.gl.context import HeadlessContext, use_platform

    use_platform("egl")
    spec = LABS[lab]
    run = Run(spec, path.resolve())
    context = HeadlessContext()
    from mirrorlab.gl.resources import Framebuffer
    from mirrorlab.labs import kit

    target = Framebuffer(context.resources, *size)
    target.bind()
    session = kit.open_session(lab, size)
    session.target = target
    session.registry = context.resources
    namespace = load_student(run.path, run)
    if namespace is not None:
        DRIVERS[lab](namespace, run, session)
    else:
        finish_frame(run, session)
    run.write(out_dir)
    return 0


def run_window(lab: str, path: Path, size: tuple[int, int], max_frames: int,
               screenshot: Path | None) -> int:
    """Run ``path`` in a window until Esc or ``max_frames``: the lab's set-up functions
    once, then its frame function every frame. Errors are printed as the checker would."""
    from mirrorlab.gl.context import WindowContext, use_platform

    use_platform("glx")
    import glfw

    from mirrorlab.gl.opengl import GL
    from mirrorlab.labs import kit

    spec = LABS[lab]
    run = Run(spec, path.resolve())
    context = WindowContext(size[0], size[1], f"mirrorlab lab {lab} - {path.name}")
    try:
        width, height = context.framebuffer_size()
        session = kit.open_session(lab, (width, height), context)
        namespace = load_student(run.path, run)
        if namespace is not None:
            wrap_functions(namespace, run, session, {})
            for name in spec.setup:
                call(namespace, name)
        last = None
        frames = 0
        while namespace is not None and not context.should_close():
            glfw.poll_events()
            if glfw.get_key(context.window, glfw.KEY_ESCAPE) == glfw.PRESS:
                break
            GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, 0)
            if not call(namespace, spec.frame):
                break
            frames += 1
            if screenshot is not None:
                GL.glReadBuffer(GL.GL_BACK)
                last = session.read_frame()
            context.swap_buffers()
            if max_frames and frames >= max_frames:
                break
        for error in run.errors:
            print(format_error(spec, error), file=sys.stderr)
        if screenshot is not None and last is not None:
            from mirrorlab.files import write_png_atomic

            write_png_atomic(screenshot, last)
            print(f"wrote {screenshot}")
        return 1 if run.errors else 0
    finally:
        kit.close_session()
        context.release()


def format_error(spec: LabSpec, error: dict[str, Any]) -> str:
    """One line for an error: the task it belongs to, the student's line and the message."""
    function = error["function"]
    tasks = [t for t in spec.tasks if t.function == function]
    where = f"in {function}()" if not function.startswith("<") else "while loading the file"
    if tasks:
        where += f" (task {tasks[0].number}: {tasks[0].title})"
    line = f", line {error['line']}" if error.get("line") else ""
    code = f": {error['code']}" if error.get("code") else ""
    return f"{where}{line}{code} -> {error['message']}"


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m mirrorlab.labs.harness")
    parser.add_argument("lab", choices=sorted(LABS))
    parser.add_argument("file")
    parser.add_argument("out_dir")
    parser.add_argument("--size", default="256x256")
    args = parser.parse_args(argv)
    width, height = (int(v) for v in args.size.split("x"))
    return check_file(args.lab, Path(args.file), Path(args.out_dir), (width, height))


if __name__ == "__main__":
    sys.exit(main())
