"""The Python API: :class:`Renderer` keeps one headless OpenGL context and its GL objects
across frames and scenes; :func:`render` is the one-shot built on it.

Importing this module loads no OpenGL; a Renderer does when it opens.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from pathlib import Path
from typing import TYPE_CHECKING, Any

from mirrorlab.draw_path import DRAW_PATHS, DrawPath
from mirrorlab.frame import Frame
from mirrorlab.options import apply_options, check_size, split_frame_technique
from mirrorlab.plan import TINY_PIXELS
from mirrorlab.scene.loader import load_scene
from mirrorlab.scene.model import Scene

if TYPE_CHECKING:
    from mirrorlab.gl.context import Context, gl_pass
    from mirrorlab.gl.resources import Framebuffer
    from mirrorlab.plan import FramePlan
    from mirrorlab.renderer import FrameStats, SceneRenderer
    from mirrorlab.screen_space import MissMask

SceneLike = Scene | str | Path


def resolve_scene(scene: SceneLike, **options: Any) -> Scene:
    """A Scene from a Scene, a scene file or a shipped scene's name, with ``options``
    (see :mod:`mirrorlab.options`) applied."""
    loaded = scene if isinstance(scene, Scene) else load_scene(scene)
    return apply_options(loaded, options)


class Renderer:
    """Headless rendering that keeps its context: make one, draw many frames::

        with mirrorlab.Renderer(size=(512, 512)) as renderer:
            image = renderer.render("lab20")

    ``size`` (width, height) is the default frame size in pixels. Everything is freed on
    leaving the ``with`` block (or by :meth:`close`). ``debug`` makes a debug context
    whose KHR_debug messages are checked after every pass (a GL error is raised, naming
    the pass, either way). ``draw_path`` is how objects are drawn: ``"auto"`` (one
    multi-draw a pass where the context offers it, else an instanced draw call for each
    run of parts of one mesh, as on macOS's OpenGL 4.1), ``"packed"`` or ``"per-draw"``;
    the frames are the same.

    The context is the renderer's own: make no GL calls in it (it is current after a
    :meth:`render`). A frame drawn anew leaves it in the state it had at the first; a
    replayed frame puts back what it changes and takes the rest as the last one left it.
    """

    def __init__(
        self,
        size: Sequence[int] | str = (512, 512),
        debug: bool = False,
        *,
        draw_path: DrawPath = "auto",
    ) -> None:
        self.size = check_size(size)
        self.debug = debug
        if draw_path not in DRAW_PATHS:
            raise ValueError(
                f"draw_path: expected one of {', '.join(DRAW_PATHS)}, got {draw_path!r}"
            )
        self.draw_path = draw_path
        self._context: Context | None = None
        self._renderer: SceneRenderer | None = None
        self._target: Framebuffer | None = None
        self._reading: gl_pass | None = None
        self.last_stats: FrameStats | None = None

    def __enter__(self) -> Renderer:
        self.open()
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    def open(self) -> None:
        """Make the context (done by ``with`` or the first :meth:`render`)."""
        if self._context is not None:
            return
        from mirrorlab.gl.context import gl_pass, offscreen_context

        self._reading = gl_pass("reading the frame back")
        self._context = offscreen_context(debug=self.debug)
        try:
            from mirrorlab.renderer import SceneRenderer

            self._renderer = SceneRenderer(
                self._context.resources, self.draw_path, own_context=True
            )
        except BaseException:
            self.close()
            raise

    def close(self) -> None:
        """Free the GL objects and the context; the renderer can be opened again."""
        if self._context is None:
            return
        self._context.make_current()
        try:
            if self._renderer is not None:
                self._renderer.release()
        finally:
            self._renderer = None
            self._target = None
            self._context.release()
            self._context = None

    @property
    def gl_renderer(self) -> str:
        """The GL renderer string (e.g. ``llvmpipe (LLVM 15.0.6, 256 bits)``)."""
        self.open()
        assert self._context is not None
        return self._context.info()["renderer"]

    @property
    def gl_description(self) -> dict[str, str]:
        """What a bug report needs of this renderer's context: its backend and PyOpenGL's
        platform, the OpenGL version, profile, GLSL version, renderer and vendor
        (:func:`mirrorlab.gl.context.describe`), and the draw path this renderer draws
        with (``draw_path``)."""
        from mirrorlab.gl.context import describe

        self.open()
        assert self._context is not None and self._renderer is not None
        found = describe(self._context)
        found["draw_path"] = self._renderer.drawer.draw_path
        return found

    @property
    def gl_objects(self) -> int:
        """How many GL objects (programs, textures, buffers, framebuffers) are live in
        this renderer's context now; 0 when it is closed."""
        return 0 if self._context is None else len(self._context.resources)

    @property
    def scene_renderer(self) -> SceneRenderer:
        """The GL-side renderer (for checks and benchmarks)."""
        self.open()
        assert self._renderer is not None
        return self._renderer

    def _target_of(self, size: tuple[int, int]) -> Framebuffer:
        target = self._target
        if target is not None and target.size == size:
            return target
        from mirrorlab.gl.context import gl_pass
        from mirrorlab.gl.resources import Framebuffer

        if self._target is None or self._target.size != size:
            with gl_pass("the frame's target"):
                if self._target is not None:
                    self._target.release()
                    self._target = None
                assert self._context is not None
                self._target = Framebuffer(self._context.resources, *size)
                # Made, it is bound; the renderer puts back at every frame's end what was
                # bound at its first (it owns the context): the default framebuffer, not
                # this one, which a frame of another size deletes (binding a deleted name
                # is an error in a core context, as on macOS).
                from mirrorlab.gl.calls import gl
                from mirrorlab.gl.opengl import GL

                gl.glBindFramebuffer(GL.GL_FRAMEBUFFER, 0)
        return self._target

    def render(
        self,
        scene: SceneLike,
        *,
        frame: int = 0,
        size: Sequence[int] | str | None = None,
        use_plan: bool = True,
        tiny_pixels: float = TINY_PIXELS,
        **options: Any,
    ) -> Frame:
        """Draw ``scene`` (a Scene, a file or a shipped name) posed at animation ``frame``,
        ``size`` (width, height) or this renderer's size, with ``options`` applied
        (``camera=(x, y, z)``, ``method="stencil"``, ...: see :mod:`mirrorlab.options`).
        ``use_plan`` False runs every pass. Returns the frame as a :class:`Frame`, an
        ``(height, width, 3)`` uint8 RGB array, row 0 at the top, that Jupyter shows as a
        picture; :attr:`last_stats` says what ran."""
        posed = resolve_scene(scene, **options).at_frame(frame)
        self.open()
        assert self._context is not None and self._renderer is not None
        assert self._reading is not None
        self._context.make_current()
        target = self._target_of(check_size(size) if size is not None else self.size)
        self.last_stats = self._renderer.render(posed, target, use_plan, tiny_pixels)
        with self._reading:
            return Frame(target.read())

    def frames(
        self,
        scene: SceneLike,
        *,
        frames: Sequence[int] | None = None,
        size: Sequence[int] | str | None = None,
        use_plan: bool = True,
        tiny_pixels: float = TINY_PIXELS,
        **options: Any,
    ) -> Iterator[tuple[int, Frame, FrameStats]]:
        """``(frame, image, stats)`` for each frame of the animation (or ``frames``)."""
        loaded = resolve_scene(scene, **options)
        for frame in frames if frames is not None else range(loaded.frame_count):
            image = self.render(
                loaded, frame=frame, size=size, use_plan=use_plan, tiny_pixels=tiny_pixels
            )
            assert self.last_stats is not None
            yield frame, image, self.last_stats

    def plan(
        self,
        scene: SceneLike,
        *,
        frame: int = 0,
        size: Sequence[int] | str | None = None,
        use_plan: bool = True,
        **options: Any,
    ) -> FramePlan:
        """The plan the next :meth:`render` of this frame would run (nothing is drawn)."""
        from mirrorlab.plan import plan_frame

        posed = resolve_scene(scene, **options).at_frame(frame)
        state = self._renderer.state if self._renderer is not None else None
        return plan_frame(
            posed, check_size(size) if size is not None else self.size, state, use_plan
        )

    def ssr_mask(self) -> MissMask:
        """What screen-space reflections (technique ``ssr``) did at each pixel of the last
        :meth:`render`: a :class:`~mirrorlab.screen_space.MissMask` of the frame (for
        each reflector pixel, whether its reflected ray was found on the screen, with
        what weight, or why it fell back to the probe), all zero where no reflector drawn
        by ``ssr`` shows. Its ``miss_share`` is the share of those pixels that fell back
        to the probe; ``image()`` is it as a picture."""
        from mirrorlab.passes.ssr import frame_mask

        renderer = self.scene_renderer
        if self.last_stats is None:
            raise ValueError("ssr_mask: no frame rendered yet")
        assert self._context is not None
        self._context.make_current()
        return frame_mask(renderer, self.last_stats.plan.top)

    def read_texture(self, reflector: str, *, slot: int = 0) -> Frame:
        """A planar reflector's capture texture from the last frame, ``(h, w, 3)`` uint8
        (a :class:`Frame`)."""
        renderer = self.scene_renderer
        capture = renderer.pass_for(reflector)
        textures = getattr(capture, "captures", None)
        if textures is None or slot not in textures.textures:
            raise ValueError(f"reflector {reflector!r} holds no capture texture")
        return Frame(textures.textures[slot].read())


def raytrace(
    scene: SceneLike, *, frame: int = 0, size: Sequence[int] | str = (512, 512), **options: Any
) -> Frame:
    """The ray-traced ground truth of ``scene`` (see :mod:`mirrorlab.raytrace`), as an
    ``(height, width, 3)`` uint8 :class:`Frame`. Needs no OpenGL."""
    from mirrorlab.raytrace import trace_scene

    posed = resolve_scene(scene, **options).at_frame(frame)
    return Frame(trace_scene(posed, check_size(size)).to_uint8())


def render(
    scene: SceneLike = "lab20",
    *,
    frame: int = 0,
    size: Sequence[int] | str = (512, 512),
    use_plan: bool = True,
    **options: Any,
) -> Frame:
    """Draw one frame headless and return it as ``(height, width, 3)`` uint8 RGB, row 0 at
    the top: a :class:`~mirrorlab.frame.Frame`, which Jupyter shows as a picture.

    ``scene`` is a Scene, a scene file or a shipped scene's name (``lab20``, ``lab``,
    ``cone``, ``sphere``, ...); ``options`` change it (``camera``, ``target``,
    ``angles``, ``method``, ``capture``, ``env_size``, ``map_size``, ``max_bounces``,
    ``cube_faces``, ``set``: see :mod:`mirrorlab.options`). A ``method`` that draws the
    whole frame (``"raytrace"``: the ray-traced ground truth; see
    :mod:`mirrorlab.techniques`) draws it instead of OpenGL. Each call makes and frees its
    own context; keep a :class:`Renderer` for many frames.
    """
    frame_technique, options = split_frame_technique(options)
    if frame_technique is not None:
        posed = resolve_scene(scene, **options).at_frame(frame)
        return Frame(frame_technique.frame_function()(posed, check_size(size), progress=False))
    with Renderer(size) as renderer:
        return renderer.render(scene, frame=frame, use_plan=use_plan, **options)
