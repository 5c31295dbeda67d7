"""Render every shipped scene file to docs/scenes/NAME.png (headless; from the checkout):

    .venv/bin/python tools/render_scenes.py [NAME ...]

(the scenes named, else all of them).

An animated scene is shown at its first, middle and last frames side by side.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

import mirrorlab
from mirrorlab.data import scenes_dir
from mirrorlab.files import write_png_atomic

DOCS = Path(__file__).resolve().parent.parent / "docs" / "scenes"
SIZE = (384, 384)


def main(names: list[str]) -> None:
    with mirrorlab.Renderer(SIZE) as renderer:
        for path in sorted(scenes_dir().glob("*.toml")):
            if names and path.stem not in names:
                continue
            scene = mirrorlab.load_scene(path)
            frames = sorted({0, scene.frame_count // 2, scene.frame_count - 1})
            image = np.hstack([renderer.render(scene, frame=frame) for frame in frames])
            write_png_atomic(DOCS / f"{scene.name}.png", image)
            print(f"wrote {DOCS / scene.name}.png (frames {frames})")


if __name__ == "__main__":
    import sys

    main(sys.argv[1:])
