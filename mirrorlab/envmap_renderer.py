"""Environment-mapping renderer: the reflector of an environment-mapping scene drawn with
one technique by name, over the sky and the scene's lit objects.

A frame is: (when needed) bake a sphere map for the current view or capture a live
cube map from the reflector's centre, then sky, scene, reflector. Like the lab's
:class:`~mirrorlab.renderer.Renderer`, :class:`EnvmapRenderer` is handed a context's
resource registry and a render target and never creates a context;
:func:`render_envmap_frame` is the headless one-shot.

For the accuracy benchmark: :data:`ENVMAP_METHODS`, :func:`ground_truth_scene` (the
ray-traced reference of a scene) and :func:`reflective_mask` (the pixels each
technique is judged on).

Importing this module loads no OpenGL (the GL layers are imported when a renderer
is made), so command lines can list the methods cheaply.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from mirrorlab.plan import PlannedPass
from mirrorlab.scene.envscenes import (
    CONE_LIMITS,
    ENV_SCENES,
    ENVMAP_METHODS,
    EnvScene,
    build_cone_scene,
    build_env_scene,
    check_method,
)
from mirrorlab.scene.robot import Camera

if TYPE_CHECKING:
    from mirrorlab.gl.context import ResourceRegistry
    from mirrorlab.gl.resources import RenderTarget
    from mirrorlab.raytrace import RayImage, RayScene

__all__ = ["DEFAULT_MAP_SIZE", "ENVMAP_METHODS", "ENV_SCENES", "EnvFrameStats",
           "EnvmapFrame", "EnvmapRenderer", "ground_truth", "ground_truth_scene",
           "reflective_mask", "render_envmap_frame"]

DEFAULT_MAP_SIZE = 256
"""Edge of the sphere map and of each cube face, in texels; latitude-longitude maps are
twice as wide as high, ``2 * map_size`` x ``map_size``."""
SKY_SIZE = 256
"""Edge of the static cube map the sky (background) is drawn from, whatever the method."""
_SPHERE_MAP_METHODS = ("sphere", "sphere-vertex", "sphere-texgen", "normal")
GL_TEXTURE_MAX_ANISOTROPY = 0x84FE  # core in GL 4.6; ARB/EXT_texture_filter_anisotropic here


@dataclass
class EnvFrameStats:
    """What the last frame did: ``passes`` run and skipped (with reasons), ``draw_calls``."""

    method: str
    passes: list[PlannedPass]
    draw_calls: int

    @property
    def ran(self) -> list[str]:
        return [p.name for p in self.passes if p.runs]


_bake_cache: dict[tuple[object, int], np.ndarray] = {}


def _cube_faces(scene: EnvScene, size: int) -> np.ndarray:
    """``bake_cube_faces`` of the scene's environment, remembered per (environment, size)."""
    from mirrorlab.envmap import bake_cube_faces

    key = (scene.environment, size)
    if key not in _bake_cache:
        if len(_bake_cache) > 16:
            _bake_cache.clear()
        _bake_cache[key] = bake_cube_faces(scene.environment, size)
    return _bake_cache[key]


class EnvmapRenderer:
    """Draws ``scene`` with its reflector environment-mapped by ``envmap`` (one of
    :data:`ENVMAP_METHODS`), maps ``map_size`` texels on edge.

    Which maps exist and when they are refreshed:

    - sphere methods and ``normal``: the scene's own picture (``scene.sphere_texture``,
      the textbook's cone) or a sphere map baked from the environment for the current
      view direction, re-baked only when the view rotates (sphere maps live in eye space);
    - ``cube``: six faces baked once from the environment;
    - ``cube-live``: six captures from the reflector's centre, redone only when the
      scene changed (an object or the reflector moved), not when the viewer moves;
    - ``latlong``: one ``2 map_size`` x ``map_size`` map baked once.

    Baked maps see only the distant environment; ``cube-live`` also sees the lit objects.
    ``cube_faces`` ``(6, n, n, 3)`` uint8 (e.g. from
    :func:`~mirrorlab.scene.envscenes.load_cube_faces`) replaces the cube baked from the
    environment, both as the ``cube`` method's map (whatever ``map_size``) and as the
    sky drawn behind the scene: a static cube map from six images.

    Every map is mipmapped (trilinear); ``anisotropy`` > 1 adds anisotropic filtering up to
    that ratio. It is off by default: on llvmpipe it brings sphere maps closer to the ray
    tracer but cube and latitude-longitude maps further away (measured).
    """

    def __init__(self, registry: ResourceRegistry, scene: EnvScene, envmap: str,
                 map_size: int = DEFAULT_MAP_SIZE, anisotropy: float = 1.0,
                 cube_faces: np.ndarray | None = None) -> None:
        from mirrorlab.envmap import bake_latlong
        from mirrorlab.gl.opengl import GL
        from mirrorlab.gl.resources import Framebuffer, Texture2D, TextureCube
        from mirrorlab.passes.cube_capture import CubeCapturePass
        from mirrorlab.passes.envmap import EnvmapPass
        from mirrorlab.passes.scene_draw import SceneDrawer
        from mirrorlab.passes.sky import SkyPass
        from mirrorlab.scene.mesh import load_texture

        self.method = check_method(envmap)
        if int(map_size) != map_size or not 4 <= map_size <= 4096:
            raise ValueError(f"map_size must be a whole number from 4 to 4096, got {map_size!r}")
        self.map_size = int(map_size)
        self.scene = scene
        self._registry = registry
        self._owned: list = []
        self.drawer = SceneDrawer(registry, scene)
        if cube_faces is not None:
            cube_faces = np.asarray(cube_faces)
            if cube_faces.ndim != 4 or cube_faces.shape[0] != 6 or cube_faces.shape[3] != 3 \
                    or cube_faces.shape[1] != cube_faces.shape[2] or cube_faces.dtype != np.uint8:
                raise ValueError(f"cube_faces must be (6, n, n, 3) uint8, got "
                                 f"{cube_faces.shape} {cube_faces.dtype}")
        sky_faces = _cube_faces(scene, SKY_SIZE) if cube_faces is None else cube_faces
        self.sky_map = TextureCube.from_faces(registry, sky_faces)
        self.sky_pass = SkyPass(registry, self.sky_map)
        self._owned += [self.drawer, self.sky_pass, self.sky_map]
        self.capture_pass: CubeCapturePass | None = None
        self.capture_target: Framebuffer | None = None
        self._captured_revision: int | None = None
        self._baked_rotation: np.ndarray | None = None
        size = self.map_size
        if self.method in _SPHERE_MAP_METHODS:
            if scene.sphere_texture is not None:
                image = load_texture(scene.sphere_texture)
                self._baked_rotation = np.full((3, 3), np.nan)  # never re-baked
            else:
                image = np.zeros((size, size, 3), np.uint8)  # baked at the first frame
            texture = Texture2D(registry, image.shape[1], image.shape[0], image, mipmaps=True,
                                clamp=True)
        elif self.method == "cube":
            faces = _cube_faces(scene, size) if cube_faces is None else cube_faces
            texture = TextureCube.from_faces(registry, faces)
        elif self.method == "cube-live":
            texture = TextureCube.blank(registry, size, mipmaps=True)
            self.capture_target = Framebuffer(registry, size, size)
            self.capture_pass = CubeCapturePass(self.drawer, self.sky_pass, texture)
            self._owned.append(self.capture_target)
        else:  # latlong: repeat across the phi seam, clamp at the poles
            texture = Texture2D(registry, 2 * size, size,
                                bake_latlong(scene.environment, 2 * size, size),
                                mipmaps=True, clamp=False)
            GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_WRAP_T, GL.GL_CLAMP_TO_EDGE)
        self.texture = texture
        self._owned.append(texture)
        if anisotropy > 1.0:  # the reflection squeezes the map hard towards the silhouette
            target = GL.GL_TEXTURE_CUBE_MAP if self.method in ("cube", "cube-live") else (
                GL.GL_TEXTURE_2D)
            texture.bind(0)
            GL.glTexParameterf(target, GL_TEXTURE_MAX_ANISOTROPY, float(anisotropy))
        self.envmap_pass = EnvmapPass(registry, scene.reflector, self.method, texture)
        self._owned.append(self.envmap_pass)
        self.last_frame: EnvFrameStats | None = None

    def release(self) -> None:
        """Free every GL object the renderer made. Call with its context current."""
        for resource in reversed(self._owned):
            resource.release()
        self._owned.clear()

    def _needs_sphere_bake(self, view: np.ndarray) -> PlannedPass:
        if self.method not in _SPHERE_MAP_METHODS:
            return PlannedPass("sphere-bake", False, f"{self.method} uses no sphere map")
        if self.scene.sphere_texture is not None:
            return PlannedPass("sphere-bake", False,
                               f"the scene's picture {self.scene.sphere_texture!r} is the map")
        if self._baked_rotation is None:
            return PlannedPass("sphere-bake", True, "the sphere map is still blank")
        if not np.allclose(self._baked_rotation, view[:3, :3], atol=1e-9):
            return PlannedPass("sphere-bake", True, "the view turned (sphere maps are eye-space)")
        return PlannedPass("sphere-bake", False, "the view direction is unchanged")

    def _needs_capture(self, force: bool) -> PlannedPass:
        if self.method != "cube-live":
            return PlannedPass("cube-capture", False, f"{self.method} captures nothing live")
        if force:
            return PlannedPass("cube-capture", True, "capture forced (e.g. for a benchmark)")
        if self._captured_revision is None:
            return PlannedPass("cube-capture", True, "the live cube map is still blank")
        if self._captured_revision != self.scene.revision:
            return PlannedPass("cube-capture", True, "the scene changed since the last capture")
        return PlannedPass("cube-capture", False, "nothing changed since the last capture")

    def bake_sphere_map(self, view: np.ndarray) -> None:
        """Re-bake the sphere map from the environment for ``view``'s rotation ``(4, 4)``."""
        from mirrorlab.envmap import bake_sphere_map
        from mirrorlab.gl.opengl import GL

        rotation = np.asarray(view, dtype=np.float64)[:3, :3].copy()
        image = bake_sphere_map(self.scene.environment, self.map_size, rotation)
        self.texture.bind(0)
        GL.glPixelStorei(GL.GL_UNPACK_ALIGNMENT, 1)
        GL.glTexSubImage2D(GL.GL_TEXTURE_2D, 0, 0, 0, self.map_size, self.map_size, GL.GL_RGB,
                           GL.GL_UNSIGNED_BYTE, np.ascontiguousarray(image[::-1]))
        GL.glGenerateMipmap(GL.GL_TEXTURE_2D)
        self._baked_rotation = rotation

    def render(self, target: RenderTarget, camera: Camera, output: int = 0,
               force_capture: bool = False) -> EnvFrameStats:
        """Draw one frame of ``camera``'s view into ``target`` (Framebuffer or window).

        ``output`` 1 makes the reflector show its lookup coordinates instead of colours
        (see :mod:`mirrorlab.passes.envmap`; for numerical checks in a float target).
        ``force_capture`` re-captures a live cube map even when nothing changed.
        """
        from mirrorlab.gl.opengl import GL

        width, height = target.size
        view = camera.view()
        projection = camera.projection(width / height)
        bake, capture = self._needs_sphere_bake(view), self._needs_capture(force_capture)
        draws = 0
        if bake.runs:
            self.bake_sphere_map(view)
        if capture.runs:
            assert self.capture_pass is not None and self.capture_target is not None
            draws += self.capture_pass.run(self.capture_target, self.scene.reflector.center())
            self._captured_revision = self.scene.revision
        target.bind()
        GL.glViewport(0, 0, width, height)
        GL.glClearColor(0.0, 0.0, 0.0, 1.0)
        GL.glClear(GL.GL_COLOR_BUFFER_BIT | GL.GL_DEPTH_BUFFER_BIT)
        draws += self.sky_pass.run(view, projection)
        GL.glEnable(GL.GL_DEPTH_TEST)
        GL.glEnable(GL.GL_CULL_FACE)
        draws += self.drawer.draw(projection @ view)
        draws += self.envmap_pass.run(view, projection, output)
        passes = [bake, capture, PlannedPass("sky", True, "the distant environment"),
                  PlannedPass("scene", True, "the lit objects"),
                  PlannedPass("envmap", True, f"the reflector, by {self.method}")]
        self.last_frame = EnvFrameStats(self.method, passes, draws)
        return self.last_frame


# ---------------------------------------------------------------------------------------
# headless one-shot


@dataclass(frozen=True)
class EnvmapFrame:
    """``image`` ``(h, w, 3)`` uint8, row 0 at the top; ``passes`` names the passes that
    ran; ``scene`` and ``method`` as rendered."""

    image: np.ndarray
    passes: list[str]
    scene: str
    method: str
    gl_renderer: str


def resolve_scene(scene: str | EnvScene, cone_height: float | None = None) -> EnvScene:
    """A scene object from a built-in name (ValueError naming it and the choices), or the
    object itself. ``cone_height`` places the cone scene's cone (y of its base)."""
    if isinstance(scene, EnvScene):
        return scene
    if cone_height is not None:
        if scene != "cone":
            raise ValueError(f"cone_height applies to the cone scene only, not {scene!r}")
        low, high = CONE_LIMITS
        if not np.isfinite(cone_height) or not low <= cone_height <= high:
            raise ValueError(f"cone_height must be from {low} to {high}, got {cone_height!r}")
        return build_cone_scene(float(cone_height))
    return build_env_scene(scene)


def render_envmap_frame(scene: str | EnvScene = "sphere", envmap: str = "sphere",
                        size: Sequence[int] = (512, 512), camera: Camera | None = None,
                        map_size: int = DEFAULT_MAP_SIZE,
                        cone_height: float | None = None,
                        cube_faces: np.ndarray | None = None) -> EnvmapFrame:
    """Render an environment-mapping scene once, headless (EGL), and read the frame back.

    ``scene`` is a name from :data:`ENV_SCENES` (or an :class:`EnvScene`), ``envmap`` a
    name from :data:`ENVMAP_METHODS`; ``camera`` defaults to the scene's own;
    ``cube_faces`` as in :class:`EnvmapRenderer`. Bad
    values raise ValueError with a one-line message naming them and the choices.
    """
    from mirrorlab.gl.context import HeadlessContext, check_gl_errors
    from mirrorlab.gl.resources import Framebuffer
    from mirrorlab.headless import check_size

    check_method(envmap)
    width, height = check_size(size)
    env_scene = resolve_scene(scene, cone_height)
    viewer = camera if camera is not None else env_scene.camera
    viewer.view()  # raises ValueError for a degenerate camera before any GL work
    with HeadlessContext() as context:
        target = Framebuffer(context.resources, width, height)
        renderer = EnvmapRenderer(context.resources, env_scene, envmap, map_size,
                                  cube_faces=cube_faces)
        stats = renderer.render(target, viewer)
        image = target.read()
        check_gl_errors(f"rendering the {env_scene.name} scene with {envmap}")
        return EnvmapFrame(image, stats.ran, env_scene.name, envmap,
                           context.info()["renderer"])


# ---------------------------------------------------------------------------------------
# ground truth for the accuracy benchmark


def reflector_surface(scene: EnvScene):
    """The scene's reflector as a perfect-mirror :class:`~mirrorlab.raytrace.RaySurface`
    (world space, smooth vertex normals, both faces reflect)."""
    from mirrorlab.raytrace import mesh_surface

    return mesh_surface(scene.reflector.mesh, scene.reflector.model_matrix(), reflective=True)


def ground_truth_scene(scene: EnvScene) -> RayScene:
    """The ray tracer's model of ``scene``: the lit objects, the reflector as a perfect
    mirror, and the environment function for rays that escape."""
    from mirrorlab.raytrace import RayScene, surfaces_from_graph

    surfaces = [*surfaces_from_graph(scene.graph), reflector_surface(scene)]
    return RayScene(surfaces, scene.light_direction, scene.ambient, scene.diffuse,
                    background=scene.environment)


def ground_truth(scene: EnvScene, camera: Camera, size: Sequence[int],
                 supersample: int = 1) -> RayImage:
    """Ray-traced image and reflective mask of ``scene`` seen by ``camera`` at ``size``
    (width, height): :class:`~mirrorlab.raytrace.RayImage`.

    With ``supersample`` k > 1, k x k rays per pixel are traced and averaged (a box
    filter over the pixel, which is what a mipmapped texture lookup approximates, while
    one ray per pixel aliases wherever the reflection compresses the environment); a
    pixel's mask is then True only when all its k x k rays meet the reflector.
    """
    from mirrorlab.raytrace import RayImage

    width, height = (int(v) for v in size)
    k = int(supersample)
    if k < 1:
        raise ValueError(f"supersample must be a positive whole number, got {supersample!r}")
    traced = ground_truth_scene(scene).render(
        camera.view(), camera.projection(width / height), (k * width, k * height))
    if k == 1:
        return traced
    image = traced.image.reshape(height, k, width, k, 3).mean(axis=(1, 3))
    mask = traced.reflective_mask.reshape(height, k, width, k).all(axis=(1, 3))
    return RayImage(image, mask)


def erode(mask: np.ndarray, pixels: int) -> np.ndarray:
    """``mask`` ``(h, w)`` bool shrunk by ``pixels`` (4-neighbour steps); outside is False."""
    out = np.asarray(mask, dtype=bool).copy()
    for _ in range(int(pixels)):
        padded = np.pad(out, 1, constant_values=False)
        out = (padded[1:-1, 1:-1] & padded[:-2, 1:-1] & padded[2:, 1:-1]
               & padded[1:-1, :-2] & padded[1:-1, 2:])
    return out


def reflective_mask(scene: EnvScene, camera: Camera, size: Sequence[int],
                    inset_px: int = 0, supersample: int = 1) -> np.ndarray:
    """``(h, w)`` bool: pixels whose centre ray (with ``supersample`` k > 1: all k x k rays)
    meets the front of the reflector first (ray traced), shrunk by ``inset_px`` pixels to
    leave out the silhouette's edge, where every technique and the tracer disagree most."""
    return erode(ground_truth(scene, camera, size, supersample).reflective_mask, inset_px)
