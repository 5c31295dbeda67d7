"""Generate the shipped meshes and pictures in the repository's top-level models/ and
textures/ folders (package data: the wheel carries them in mirrorlab/data/): the robot's
part meshes (models/*.obj) and the METAL texture (textures/metal.png), and the
environment-mapping assets: the reflective cone and sphere, the backdrop quad, the unit
panel the room's walls are made of, and the rocket-launch picture (textures/launch.png).

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
from numpy.typing import ArrayLike
from PIL import Image

ROOT = Path(__file__).resolve().parents[1]


def box(size: tuple[float, float, float], y0: float = 0.0):
    """Box centred on the y axis from y0 to y0+size[1], one UV square per face."""
    sx, sy, sz = (s / 2 for s in size)
    cy = y0 + sy
    positions: list[ArrayLike] = []
    normals: list[ArrayLike] = []
    uvs, faces = [], []
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
    positions: list[ArrayLike] = []
    normals: list[ArrayLike] = []
    uvs, faces = [], []
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


def sphere(radius: float, subdivisions: int, spherical_uv: bool = False):
    """Icosphere with exact unit normals; uv zero, or longitude/latitude with
    ``spherical_uv`` (only to give the file real texture coordinates: no seam split)."""
    ico = trimesh.creation.icosphere(subdivisions=subdivisions, radius=radius)
    n = ico.vertices / np.linalg.norm(ico.vertices, axis=1, keepdims=True)
    uv = np.zeros((len(n), 2))
    if spherical_uv:
        uv = np.stack(
            [
                np.arctan2(n[:, 0], n[:, 2]) / (2 * np.pi) + 0.5,
                np.arcsin(np.clip(n[:, 1], -1, 1)) / np.pi + 0.5,
            ],
            axis=1,
        )
    return ico.vertices, n, uv, ico.faces


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


def cone(radius: float, height: float, segments: int, rings: int):
    """Cone on the y axis, base disc at y=0, apex at y=height; smooth side normals.

    The side is split into ``rings`` bands so that per-vertex shading has more than the
    apex and the rim to interpolate between; the apex is one vertex per segment, with
    that segment's mid-angle normal, so no normal is undefined.
    """
    positions, normals, uvs, faces = [], [], [], []
    slope = radius / height  # normal = (cos a, slope, -sin a), normalised
    angles = np.linspace(0.0, 2.0 * np.pi, segments + 1)
    for j in range(rings + 1):
        f = j / rings  # 0 at the rim, 1 at the apex
        for i, a in enumerate(angles):
            if j == rings:
                a = a + np.pi / segments  # apex: the mid-angle of the segment it closes
            n = np.array([np.cos(a), slope, -np.sin(a)])
            positions.append(
                ((1 - f) * radius * np.cos(a), f * height, -(1 - f) * radius * np.sin(a))
            )
            normals.append(n / np.linalg.norm(n))
            uvs.append((i / segments, f))
    row = segments + 1
    for j in range(rings):
        for i in range(segments):
            a, b = j * row + i, j * row + i + 1
            c, d = a + row, b + row
            if j == rings - 1:  # the apex band: one triangle per segment
                faces.append((a, b, c))
            else:
                faces += [(a, b, d), (a, d, c)]
    centre = len(positions)  # base cap, facing -y
    positions.append((0.0, 0.0, 0.0))
    normals.append((0.0, -1.0, 0.0))
    uvs.append((0.5, 0.5))
    for a in angles[:-1]:
        positions.append((radius * np.cos(a), 0.0, -radius * np.sin(a)))
        normals.append((0.0, -1.0, 0.0))
        uvs.append((0.5 + 0.5 * np.cos(a), 0.5 + 0.5 * np.sin(a)))
    for i in range(segments):
        a, b = centre + 1 + i, centre + 1 + (i + 1) % segments
        faces.append((centre, b, a))
    return np.array(positions), np.array(normals), np.array(uvs, float), np.array(faces)


def quad(width: float, height: float):
    """Rectangle in the z=0 plane facing +z, centred on the origin, uv (0,0) bottom left."""
    w, h = width / 2, height / 2
    positions = np.array([(-w, -h, 0.0), (w, -h, 0.0), (w, h, 0.0), (-w, h, 0.0)])
    normals = np.tile([0.0, 0.0, 1.0], (4, 1))
    uvs = np.array([(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)])
    return positions, normals, uvs, np.array([(0, 1, 2), (0, 2, 3)])


def _smoothstep(edge0: float, edge1: float, x: np.ndarray) -> np.ndarray:
    t = np.clip((x - edge0) / (edge1 - edge0), 0.0, 1.0)
    return t * t * (3.0 - 2.0 * t)


def _value_noise(rng: np.random.Generator, shape: tuple[int, int], cells: int) -> np.ndarray:
    """Smooth noise in [0, 1]: a ``cells`` x ``cells`` random grid, bicubically upsampled."""
    grid = Image.fromarray((rng.random((cells + 1, cells + 1)) * 255).astype(np.uint8))
    big = grid.resize((shape[1], shape[0]), Image.Resampling.BICUBIC)
    return np.asarray(big, dtype=np.float64) / 255.0


def launch_texture(size: int = 512) -> np.ndarray:
    """A rocket launch at dusk, drawn from shapes and noise: sky, pad, service tower, the
    stack (orbiter, tank, boosters), flame and billowing smoke. ``(size, size, 3)`` uint8,
    row 0 at the top. Stands in for the textbook's photograph, which we may not ship."""
    rng = np.random.default_rng(1312)
    y, x = (np.mgrid[0:size, 0:size] + 0.5) / size  # y down, both in [0, 1]
    # sky: deep blue at the top to orange at the horizon (y = 0.78)
    horizon = 0.78
    k = np.clip(y / horizon, 0, 1)[..., None]
    sky = (1 - k) * np.array([0.10, 0.22, 0.52]) + k * np.array([0.98, 0.62, 0.32])
    clouds = _value_noise(rng, (size, size), 6) * _value_noise(rng, (size, size), 14)
    sky = sky + (0.25 * _smoothstep(0.25, 0.6, clouds) * (y < horizon))[..., None]
    image = sky
    # ground and water: dark olive land, a bluish strip of water reflecting the sky
    land = np.array([0.16, 0.17, 0.10]) * (
        0.8 + 0.4 * _value_noise(rng, (size, size), 30)[..., None]
    )
    image = np.where((y > horizon)[..., None], land, image)
    water = (y > 0.9) & (y < 0.96)
    image = np.where(water[..., None], 0.5 * sky[::-1] + 0.1, image)
    # stack, centred at x = 0.55: tank, two boosters, orbiter, all from y = 0.32 to 0.72
    cx = 0.55
    top, bottom = 0.30, 0.72

    def rect(x0, x1, y0, y1):
        return (x > x0) & (x < x1) & (y > y0) & (y < y1)

    tank = rect(cx - 0.035, cx + 0.035, top + 0.03, bottom) | (
        (np.abs(x - cx) < 0.035 * np.clip((y - top) / 0.03, 0, 1)) & (y > top) & (y < top + 0.03)
    )
    image = np.where(
        tank[..., None],
        np.array([0.85, 0.42, 0.12])
        * (0.75 + 0.35 * np.clip((x - cx + 0.035) / 0.07, 0, 1))[..., None],
        image,
    )
    for bx in (cx - 0.05, cx + 0.05):
        booster = rect(bx - 0.014, bx + 0.014, top + 0.09, bottom + 0.01) | (
            (np.abs(x - bx) < 0.014 * np.clip((y - top - 0.06) / 0.03, 0, 1))
            & (y > top + 0.06)
            & (y < top + 0.09)
        )
        image = np.where(booster[..., None], np.array([0.93, 0.93, 0.9]), image)
    orbiter = rect(cx + 0.035, cx + 0.07, top + 0.12, bottom - 0.03) | (
        (x > cx + 0.035)
        & (x < cx + 0.07 + 0.08 * np.clip((y - 0.55) / 0.14, 0, 1))
        & (y > 0.55)
        & (y < bottom - 0.03)
    )
    image = np.where(orbiter[..., None], np.array([0.95, 0.95, 0.97]), image)
    nose = rect(cx + 0.035, cx + 0.07, top + 0.12, top + 0.16)
    image = np.where(nose[..., None], np.array([0.12, 0.12, 0.14]), image)
    # service tower to the left: dark lattice
    tower = rect(0.36, 0.43, 0.22, horizon)
    lattice = ((np.floor(y * 90) + np.floor(x * 90)) % 2 == 0) | (np.abs(x - 0.395) > 0.03)
    image = np.where((tower & lattice)[..., None], np.array([0.22, 0.2, 0.2]), image)
    image = np.where(rect(0.43, 0.5, 0.40, 0.42)[..., None], np.array([0.25, 0.22, 0.2]), image)
    # flame below the stack, then smoke billowing sideways over the pad
    smoke = np.zeros((size, size))
    for _ in range(40):
        side = rng.choice([-1.0, 1.0])
        bx = cx + side * rng.uniform(0.02, 0.35)
        by = horizon + rng.uniform(-0.07, 0.02) - 0.1 * max(0.0, 0.2 - abs(bx - cx))
        radius = rng.uniform(0.03, 0.07) * (1.0 + abs(bx - cx) * 1.5)
        smoke = np.maximum(smoke, np.exp(-((((x - bx) ** 2 + (y - by) ** 2) / radius**2) ** 2)))
    smoke_shade = 0.65 + 0.35 * _value_noise(rng, (size, size), 40)
    lit = np.clip(1.0 - 0.8 * np.abs(x - cx), 0.55, 1.0)  # the flame lights it from within
    smoke_color = (smoke_shade * lit)[..., None] * np.array([0.98, 0.93, 0.88])
    a = _smoothstep(0.3, 0.6, smoke)[..., None]
    image = image * (1 - a) + a * smoke_color
    d_flame = ((x - cx) / 0.05) ** 2 + ((y - bottom - 0.05) / 0.06) ** 2
    flame = np.exp(-d_flame * 1.5)[..., None]
    image = image * (1 - flame) + flame * np.array([1.0, 0.95, 0.65])
    return (np.clip(image, 0, 1) * 255).round().astype(np.uint8)


def wall_texture(size: int = 256) -> np.ndarray:
    """A wall's shading: white in the middle, darkening smoothly to 0.2 towards every edge
    (over the outer fifth), so that where two walls of different colours meet they meet
    in the same dark tone, without a hard edge. Grey ``(size, size, 3)`` uint8."""
    coordinate = (np.arange(size) + 0.5) / size
    to_edge = np.minimum(coordinate, 1.0 - coordinate)  # 0 at an edge, 0.5 in the middle
    ramp = 0.2 + 0.8 * _smoothstep(0.0, 0.2, to_edge)
    value = np.minimum(ramp[:, None], ramp[None, :])
    return np.repeat((value * 255).round().astype(np.uint8)[..., None], 3, axis=2)


def main() -> None:
    models = ROOT / "models"
    models.mkdir(exist_ok=True)
    write_obj(models / "base.obj", cylinder(2.0, 1.0, 48), "robot base: textured cylinder")
    write_obj(models / "lower_arm.obj", box((0.8, 4.0, 0.8)), "robot lower arm")
    write_obj(models / "upper_arm.obj", box((0.6, 3.2, 0.6)), "robot upper arm")
    write_obj(models / "joint.obj", sphere(0.55, 1), "joint ball")
    write_obj(models / "mirror_frame.obj", box((0.25, 8.6, 8.6)), "frame behind the mirror")
    write_obj(
        models / "hand.obj", box((0.5, 0.5, 1.4), y0=-0.25), "hand (placed off-centre by its node)"
    )
    write_obj(
        models / "cone.obj",
        cone(1.0, 2.4, 64, 12),
        "reflective rocket cone (environment mapping): base radius 1, height 2.4",
    )
    write_obj(
        models / "env_sphere.obj", sphere(1.0, 3, spherical_uv=True), "reflective sphere, radius 1"
    )
    write_obj(models / "backdrop.obj", quad(16.0, 16.0), "backdrop quad for the launch picture")
    write_obj(
        models / "panel.obj",
        quad(1.0, 1.0),
        "unit square facing +z: a room's walls, floor and ceiling, placed and scaled",
    )
    textures = ROOT / "textures"
    textures.mkdir(exist_ok=True)
    Image.fromarray(metal_texture()).save(textures / "metal.png")
    print("wrote textures/metal.png")
    Image.fromarray(launch_texture()).save(textures / "launch.png")
    print("wrote textures/launch.png")
    Image.fromarray(wall_texture()).save(textures / "wall.png")
    print("wrote textures/wall.png")
    write_sky_cube(textures / "sky_cube", 256)


def write_sky_cube(folder: Path, size: int) -> None:
    """The sphere scene's sky as six upright face pictures (see load_cube_faces)."""
    from mirrorlab.envmap import bake_cube_faces
    from mirrorlab.scene.backgrounds import CUBE_FACE_FILES, sky_environment

    folder.mkdir(exist_ok=True)
    faces = bake_cube_faces(sky_environment, size)
    for stem, face in zip(CUBE_FACE_FILES, faces, strict=True):
        Image.fromarray(np.ascontiguousarray(face[::-1])).save(folder / f"{stem}.png")
    print(f"wrote {folder.relative_to(ROOT)}/{{{','.join(CUBE_FACE_FILES)}}}.png")


if __name__ == "__main__":
    main()
