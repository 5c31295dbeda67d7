"""Re-make the README's comparison pictures in docs/ (headless; run from the checkout):

    .venv/bin/python tools/make_docs.py

docs/methods.png: the lab scene 30 degrees off the mirror's normal, by each mirror
technique and the ray tracer. docs/envmaps.png: the sphere scene by each
environment-map technique and the ray tracer. docs/cone.png: the textbook's cone at
two heights (texgen sphere map). The accuracy plot comes from `mirrorlab bench`.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from PIL import Image, ImageDraw

import mirrorlab
from mirrorlab.envmap_renderer import ENVMAP_METHODS, ground_truth, render_envmap_frame
from mirrorlab.scene.envscenes import build_sphere_scene

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
    methods = [labelled(mirrorlab.render((SIZE, SIZE), camera=eye, target=(-7, 1, -2),
                                         method=m), m)
               for m in ("ortho", "reflected", "stencil", "raytrace")]
    Image.fromarray(grid(methods, 4)).save(DOCS / "methods.png")

    scene = build_sphere_scene()
    truth = ground_truth(scene, scene.camera, (SIZE, SIZE), supersample=4).to_uint8()
    maps = [labelled(render_envmap_frame("sphere", m, (SIZE, SIZE)).image, m)
            for m in ENVMAP_METHODS]
    Image.fromarray(grid([*maps, labelled(truth, "raytrace 4x4")], 4)).save(
        DOCS / "envmaps.png")

    cones = [labelled(render_envmap_frame("cone", "sphere-texgen", (SIZE, SIZE),
                                          cone_height=h).image, f"cone at height {h:g}")
             for h in (1.0, -1.0)]
    Image.fromarray(grid(cones, 2)).save(DOCS / "cone.png")
    print(f"wrote {DOCS}/methods.png, envmaps.png, cone.png")


if __name__ == "__main__":
    main()
