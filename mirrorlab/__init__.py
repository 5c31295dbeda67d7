"""mirrorlab: the CS370 multipass mirror, and environment mapping, measured.

Importing this package loads neither OpenGL nor glfw; :func:`render` does,
when called.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from mirrorlab.scene.robot import DEFAULT_ANGLES, DEFAULT_CAMERA, DEFAULT_TARGET

__all__ = ["DEFAULT_ANGLES", "DEFAULT_CAMERA", "DEFAULT_TARGET", "render"]
__version__ = "0.1.0"


def render(
    size: Sequence[int] = (512, 512),
    angles: Sequence[float] = DEFAULT_ANGLES,
    camera: Sequence[float] = DEFAULT_CAMERA,
    target: Sequence[float] = DEFAULT_TARGET,
    method: str = "ortho",
    capture: str = "copy",
    environment_size: int | None = None,
    scene: str = "lab",
    envmap: str | None = None,
    map_size: int = 256,
    cube_faces: str | None = None,
) -> np.ndarray:
    """Render the lab scene headless and return the frame.

    Parameters
    ----------
    size : (width, height) in pixels.
    angles : base, lower-arm and upper-arm joint angles in degrees.
    camera, target : viewer position and the point it looks at, world units.
    method : ``"ortho"`` (the lab's capture), ``"reflected"``, ``"stencil"`` or
        ``"raytrace"`` (the ground truth, no GL).
    capture : ``"copy"`` (glCopyTexImage2D) or ``"fbo"`` (drawn into the texture).
    environment_size : side of the square environment texture in pixels; None
        makes it the frame's size.
    scene : ``"lab"`` (the robot and its mirror; everything above applies), or an
        environment-mapping scene, ``"cone"`` (the textbook's sphere-map experiment)
        or ``"sphere"``, which use ``envmap``, ``map_size`` and the scene's own
        camera unless ``camera``/``target`` differ from the lab's defaults.
    envmap : ``"sphere"``, ``"sphere-vertex"``, ``"sphere-texgen"``, ``"cube"``,
        ``"cube-live"``, ``"latlong"`` or ``"normal"``; None picks
        ``"sphere-texgen"`` for the cone and ``"sphere"`` for the sphere.
    map_size : environment map side in texels for ``envmap``.
    cube_faces : a folder with six pictures ``{px,nx,py,ny,pz,nz}.png`` to use as the
        static cube map and the sky (sphere scene), e.g. ``"textures/sky_cube"``.

    Returns
    -------
    ``(height, width, 3)`` uint8 RGB image, row 0 at the top.
    """
    if scene != "lab":
        from dataclasses import replace

        from mirrorlab.envmap_renderer import render_envmap_frame
        from mirrorlab.scene.envscenes import build_env_scene

        viewer = None
        if tuple(camera) != DEFAULT_CAMERA or tuple(target) != DEFAULT_TARGET:
            viewer = replace(build_env_scene(scene).camera,
                             eye=tuple(float(v) for v in camera),
                             target=tuple(float(v) for v in target))
        chosen = envmap or ("sphere-texgen" if scene == "cone" else "sphere")
        faces = None
        if cube_faces is not None:
            from mirrorlab.scene.envscenes import load_cube_faces

            faces = load_cube_faces(cube_faces)
        return render_envmap_frame(scene, chosen, size, viewer, map_size,
                                   cube_faces=faces).image
    if envmap is not None or cube_faces is not None:
        raise ValueError("envmap and cube_faces apply to the cone and sphere scenes, not the lab")
    from mirrorlab.headless import render_lab_frame

    return render_lab_frame(size, angles, camera, target, method, capture,
                            environment_size).image
