"""Generate the robot's part meshes (models/*.obj) and the METAL texture (textures/metal.png).

Run from the repository root: ``python tools/make_assets.py``. The outputs are
committed; this script is how they were made, so they can be re-made or changed.
Everything is procedural (fixed random seed), so there is no third-party asset.

Units are scene units; each part is modelled in its own joint frame with the
joint at the origin and the part extending along +y.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import trimesh
from PIL import Image

ROOT = Path(__file__).resolve().parents[1]


def box(size: tuple[float, float, float], y0: float = 0.0):
    """Box centred on the y axis from y0 to y0+size[1], one UV square per face."""
    sx, sy, sz = (s / 2 for s in size)
    cy = y0 + sy
    positions, normals, uvs, faces = [], [], [], []
    for axis in range(3):
        for sign in (1.0, -1.0):
            n = np.zeros(3)
            n[axis] = sign
            u_axis, v_axis = [a for a in range(3) if a != axis]
            corners = []
            for du, dv in ((-1, -1), (1, -1), (1, 1), (-1, 1)):
                p = np.zeros(3)
                p[axis] = sign
                p[u_axis], p[v_axis] = du, dv
                corners.append(p)
            # keep counter-clockwise winding seen from outside
            if np.dot(np.cross(corners[1] - corners[0], corners[2] - corners[0]), n) < 0:
                corners = corners[::-1]
            base = len(positions)
            for p in corners:
                positions.append(p * [sx, sy, sz] + [0.0, cy, 0.0])
                normals.append(n)
            uvs += [(0, 0), (1, 0), (1, 1), (0, 1)]
            faces += [(base, base + 1, base + 2), (base, base + 2, base + 3)]
    return np.array(positions), np.array(normals), np.array(uvs, float), np.array(faces)


def cylinder(radius: float, height: float, segments: int):
    """Capped cylinder on the y axis from y=-height to y=0, cylindrical UVs on the side."""
    positions, normals, uvs, faces = [], [], [], []
    angles = np.linspace(0.0, 2.0 * np.pi, segments + 1)
    for i, a in enumerate(angles):  # side: a seam column duplicated at a = 2 pi
        n = np.array([np.cos(a), 0.0, -np.sin(a)])
        for y, v in ((-height, 0.0), (0.0, 1.0)):
            positions.append(n * radius + [0.0, y, 0.0])
            normals.append(n)
            uvs.append((3.0 * i / segments, v))
    for i in range(segments):
        a, b = 2 * i, 2 * i + 2
        faces += [(a, b, b + 1), (a, b + 1, a + 1)]
    for y, ny in ((0.0, 1.0), (-height, -1.0)):  # caps, planar UVs
        centre = len(positions)
        positions.append((0.0, y, 0.0))
        normals.append((0.0, ny, 0.0))
        uvs.append((0.5, 0.5))
        for a in angles[:-1]:
            positions.append((radius * np.cos(a), y, -radius * np.sin(a)))
            normals.append((0.0, ny, 0.0))
            uvs.append((0.5 + 0.5 * np.cos(a), 0.5 + 0.5 * np.sin(a)))
        for i in range(segments):
            a, b = centre + 1 + i, centre + 1 + (i + 1) % segments
            faces.append((centre, a, b) if ny > 0 else (centre, b, a))
    return np.array(positions), np.array(normals), np.array(uvs, float), np.array(faces)


def sphere(radius: float, subdivisions: int):
    ico = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    n = ico.vertices / np.linalg.norm(ico.vertices, axis=1, keepdims=True)
    return ico.vertices, n, np.zeros((len(n), 2)), ico.faces


def write_obj(path: Path, mesh, comment: str) -> None:
    positions, normals, uvs, faces = mesh
    lines = [f"# {comment}", "# made by tools/make_assets.py"]
    lines += [f"v {x:.6f} {y:.6f} {z:.6f}" for x, y, z in positions]
    lines += [f"vt {u:.6f} {v:.6f}" for u, v in uvs]
    lines += [f"vn {x:.6f} {y:.6f} {z:.6f}" for x, y, z in normals]
    lines += ["f " + " ".join(f"{i + 1}/{i + 1}/{i + 1}" for i in tri) for tri in faces]
    path.write_text("\n".join(lines) + "\n")
    print(f"wrote {path.relative_to(ROOT)}: {len(faces)} triangles")


def metal_texture(size: int = 256) -> np.ndarray:
    """Brushed steel plate: horizontal streaks, plate seams, rivets. ``(size, size, 3)`` uint8."""
    rng = np.random.default_rng(370)
    streaks = rng.normal(0.0, 1.0, (size, 1)) * 0.06 + rng.normal(0.0, 1.0, (size, size)) * 0.025
    streaks = np.cumsum(streaks, axis=1) / np.sqrt(np.arange(1, size + 1))
    value = 0.62 + 0.35 * (streaks - streaks.mean()) / (np.abs(streaks).max() + 1e-9)
    y, x = np.mgrid[0:size, 0:size]
    seam = (x % (size // 2) < 2) | (y % (size // 2) < 2)
    value[seam] *= 0.45
    for cx in (size // 8, 3 * size // 8, 5 * size // 8, 7 * size // 8):
        for cy in (size // 8, 3 * size // 8, 5 * size // 8, 7 * size // 8):
            d2 = (x - cx) ** 2 + (y - cy) ** 2
            value = np.where(d2 < 16, 0.9 - 0.02 * d2, value)
    tint = np.array([0.92, 0.95, 1.0])
    return (np.clip(value, 0, 1)[..., None] * tint * 255).round().astype(np.uint8)


def main() -> None:
    models = ROOT / "models"
    models.mkdir(exist_ok=True)
    write_obj(models / "base.obj", cylinder(2.0, 1.0, 48), "robot base: textured cylinder")
    write_obj(models / "lower_arm.obj", box((0.8, 4.0, 0.8)), "robot lower arm")
    write_obj(models / "upper_arm.obj", box((0.6, 3.2, 0.6)), "robot upper arm")
    write_obj(models / "joint.obj", sphere(0.55, 1), "joint ball")
    write_obj(models / "mirror_frame.obj", box((0.25, 8.6, 8.6)), "frame behind the mirror")
    write_obj(models / "hand.obj", box((0.5, 0.5, 1.4), y0=-0.25),
              "hand (placed off-centre by its node)")
    textures = ROOT / "textures"
    textures.mkdir(exist_ok=True)
    Image.fromarray(metal_texture()).save(textures / "metal.png")
    print("wrote textures/metal.png")


if __name__ == "__main__":
    main()
