"""Re-make the README's comparison pictures in docs/ (headless; run from the checkout):

    .venv/bin/python tools/make_docs.py

docs/methods.png: the lab scene (lab20) 30 degrees off the mirror's normal, by each
mirror technique and the ray tracer. docs/envmaps.png: the sphere scene (chrome_sphere)
by each environment-map technique and the ray tracer (4 x 4 rays a pixel). docs/cone.png:
the textbook's cone (spheremap_cone) at two heights (texgen sphere map). The accuracy
plot comes from `mirrorlab bench accuracy`.
"""

from __future__ import annotations

import math
from dataclasses import replace
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

import mirrorlab
from mirrorlab.options import apply_options
from mirrorlab.raytrace import trace_scene
from mirrorlab.scene.model import CURVED_TECHNIQUES, PLANAR_TECHNIQUES

DOCS = Path(__file__).resolve().parent.parent / "docs"
SIZE = 256


def labelled(image: np.ndarray, text: str) -> np.ndarray:
    picture = Image.fromarray(image)
    draw = ImageDraw.Draw(picture)
    draw.rectangle((0, 0, 8 + 7 * len(text), 16), fill=(0, 0, 0))
    draw.text((4, 2), text, fill=(255, 255, 255))
    return np.asarray(picture)


def grid(tiles: list[np.ndarray], columns: int) -> np.ndarray:
    blank = np.zeros_like(tiles[0])
    tiles = tiles + [blank] * (-len(tiles) % columns)
    rows = [np.hstack(tiles[i:i + columns]) for i in range(0, len(tiles), columns)]
    return np.vstack(rows)


def main() -> None:
    angle = math.radians(-30)  # 16 units out, 30 degrees off the normal, a little above
    eye = (-7 + 16 * math.cos(angle), 1.0 + 4.8, -2 + 16 * math.sin(angle))
    view = {"camera": eye, "target": (-7.0, 1.0, -2.0)}
    with mirrorlab.Renderer(size=(SIZE, SIZE)) as renderer:
        methods = [labelled(renderer.render("lab20", method=m, **view), m)
                   for m in PLANAR_TECHNIQUES]
        methods.append(labelled(mirrorlab.render("lab20", (SIZE, SIZE), method="raytrace",
                                                 **view), "raytrace"))
        Image.fromarray(grid(methods, 4)).save(DOCS / "methods.png")

        sphere = mirrorlab.load_scene("chrome_sphere")
        maps = [labelled(renderer.render(sphere, method=m), m) for m in CURVED_TECHNIQUES]
        truth = trace_scene(sphere, (SIZE, SIZE), supersample=4).to_uint8()
        Image.fromarray(grid([*maps, labelled(truth, "raytrace 4x4")], 4)).save(
            DOCS / "envmaps.png")

        cone = apply_options(mirrorlab.load_scene("spheremap_cone"),
                             {"method": "sphere-texgen"})
        placed = cone.reflector("cone").transform
        cones = []
        for height in (1.0, -1.0):
            moved = cone.with_reflector("cone", transform=replace(
                placed, position=(placed.position[0], height, placed.position[2])))
            cones.append(labelled(renderer.render(moved), f"cone at height {height:g}"))
        Image.fromarray(grid(cones, 2)).save(DOCS / "cone.png")
    print(f"wrote {DOCS}/methods.png, envmaps.png, cone.png")


if __name__ == "__main__":
    main()
