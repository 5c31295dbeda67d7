"""pyrender's side of ``mirrorlab bench speed``, run as a script by the interpreter of
pyrender's own environment (``--pyrender``; its PyOpenGL pin conflicts with mirrorlab's,
and its last release needs numpy < 2).

It reads one JSON command a line on standard input and answers each with one JSON line:

``{"cmd": "setup", "size": [w, h], "meshes": [{"path", "color", "pose"?}], "camera":
{"view", "yfov", "znear", "zfar"}, "light": {"direction", "intensity"}, "name"?}``
    builds the scene ``name`` (default ``""``; scenes of other names are kept while the
    size stays) and, when the size changed, an offscreen renderer; answers ``{"ok":
    true, "triangles": n, "nodes": n, "gl": renderer string}``. A mesh is placed by its
    ``pose`` (16 numbers, row-major; default: already in world space); meshes of one file
    and colour share one ``pyrender.Mesh``, a node each, as a program placing many copies
    would make them.
``{"cmd": "frames", "count": n, "flags": "default" | "flat", "scene"?}``
    renders ``n`` frames of the scene named ``scene`` (default ``""``), each read back to
    numpy (colour and depth, as pyrender does); answers ``{"ms": [...], "mean": mean
    colour of the last frame}``.
``{"cmd": "save", "path": p}``
    writes the last colour frame as a PNG.
``{"cmd": "quit"}``
    frees the renderer and ends.

It imports nothing from mirrorlab.
"""

from __future__ import annotations

import json
import os
import sys
import time

os.environ["PYOPENGL_PLATFORM"] = "egl"
os.environ.setdefault("EGL_PLATFORM", "surfaceless")

import numpy as np
import pyrender
import trimesh


def light_pose(direction: list[float]) -> np.ndarray:
    """A pose whose -z axis points along the light's travel (from the light to the scene),
    ``direction`` pointing from the scene towards the light."""
    towards = np.asarray(direction, dtype=np.float64)
    z = towards / np.linalg.norm(towards)  # the node's +z points back at the light
    helper = np.array([0.0, 1.0, 0.0]) if abs(z[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
    x = np.cross(helper, z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    pose = np.eye(4)
    pose[:3, 0], pose[:3, 1], pose[:3, 2] = x, y, z
    return pose


def build_scene(command: dict) -> tuple[pyrender.Scene, int, int]:
    """The scene a ``setup`` command describes, its triangles and its mesh nodes."""
    width, height = command["size"]
    scene = pyrender.Scene(bg_color=[0.16, 0.18, 0.22, 1.0], ambient_light=[0.3, 0.3, 0.3])
    triangles = nodes = 0
    shared: dict[tuple, tuple[pyrender.Mesh, int]] = {}
    for item in command["meshes"]:
        key = (item["path"], tuple(item["color"]))
        if key not in shared:
            mesh = trimesh.load(item["path"], process=False, force="mesh")
            material = pyrender.MetallicRoughnessMaterial(
                baseColorFactor=[*item["color"], 1.0], metallicFactor=0.0, roughnessFactor=1.0
            )
            shared[key] = (
                pyrender.Mesh.from_trimesh(mesh, material=material, smooth=True),
                len(mesh.faces),
            )
        mesh, faces = shared[key]
        pose = (
            np.asarray(item["pose"], dtype=np.float64).reshape(4, 4)
            if "pose" in item
            else np.eye(4)
        )
        scene.add(mesh, pose=pose)
        triangles += faces
        nodes += 1
    camera = command["camera"]
    pose = np.linalg.inv(np.asarray(camera["view"], dtype=np.float64).reshape(4, 4))
    scene.add(
        pyrender.PerspectiveCamera(
            yfov=camera["yfov"],
            aspectRatio=width / height,
            znear=camera["znear"],
            zfar=camera["zfar"],
        ),
        pose=pose,
    )
    light = command["light"]
    scene.add(
        pyrender.DirectionalLight(intensity=light["intensity"]), pose=light_pose(light["direction"])
    )
    return scene, triangles, nodes


def main() -> int:
    renderer = None
    size = None
    scenes: dict[str, pyrender.Scene] = {}
    last = None
    for line in sys.stdin:
        command = json.loads(line)
        if command["cmd"] == "setup":
            if renderer is None or size != tuple(command["size"]):
                if renderer is not None:
                    renderer.delete()
                scenes.clear()  # their GL objects went with the old renderer's context
                size = tuple(command["size"])
                renderer = pyrender.OffscreenRenderer(*size)
            scene, triangles, nodes = build_scene(command)
            scenes[command.get("name", "")] = scene
            from OpenGL import GL

            answer = {
                "ok": True,
                "triangles": triangles,
                "nodes": nodes,
                "gl": GL.glGetString(GL.GL_RENDERER).decode(),
            }
        elif command["cmd"] == "frames":
            flags = (
                pyrender.RenderFlags.FLAT
                if command["flags"] == "flat"
                else pyrender.RenderFlags.NONE
            )
            scene = scenes[command.get("scene", "")]
            times = []
            for _ in range(command["count"]):
                start = time.perf_counter()
                color, _depth = renderer.render(scene, flags=flags)
                times.append((time.perf_counter() - start) * 1e3)
            last = color
            answer = {"ms": times, "mean": float(color.mean())}
        elif command["cmd"] == "save":
            from PIL import Image

            Image.fromarray(last).save(command["path"])
            answer = {"ok": True}
        else:
            if renderer is not None:
                renderer.delete()
            print(json.dumps({"ok": True}), flush=True)
            return 0
        print(json.dumps(answer), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
