"""Re-make the golden frames under tests/gl/golden/ from the current renderer.

Only after looking at the new picture and agreeing that it is right:
``python tools/make_golden.py``. ``python tools/make_golden.py --out DIR`` writes the
frames into DIR instead (to look at them, or compare them, first).

tests/gl/golden/lab_default_128.png: the shipped lab20 scene as it is (its camera, the
lab's ortho mirror), 128 x 128, as ``mirrorlab.render(size=(128, 128))`` draws it in
tests/gl/test_golden_and_api.py.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import mirrorlab
from mirrorlab.files import write_png_atomic

GOLDEN = Path(__file__).resolve().parents[1] / "tests" / "gl" / "golden"
FRAMES = {"lab_default_128.png": ("lab20", (128, 128))}
"""Golden file name: (scene, size)."""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=GOLDEN,
                        help=f"folder to write the frames into (default {GOLDEN})")
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    with mirrorlab.Renderer() as renderer:
        for name, (scene, size) in FRAMES.items():
            path = args.out / name
            write_png_atomic(path, renderer.render(scene, size=size))
            print(f"wrote {path}")


if __name__ == "__main__":
    main()
