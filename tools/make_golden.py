"""Re-make the golden frames under tests/gl/golden/ from the current renderer.

Only after looking at the new pictures and agreeing that they are right:
``python tools/make_golden.py``. ``python tools/make_golden.py --out DIR`` writes the
frames into DIR instead (to look at them, or compare them, first).

tests/gl/golden/lab_default_128.png: the shipped lab20 scene as it is (its camera, the
lab's ortho mirror), 128 x 128, as ``mirrorlab.render(size=(128, 128))`` draws it in
tests/gl/test_golden_and_api.py.

tests/gl/golden/shipped/NAME.png: each sequence of tests/gl/golden_frames.py (every
shipped scene's frames, every technique on them), frames side by side, as
tests/gl/test_shipped_goldens.py draws and compares them exactly.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(REPO))  # for tests.gl.golden_frames

import mirrorlab  # noqa: E402
from mirrorlab.files import write_png_atomic  # noqa: E402

GOLDEN = REPO / "tests" / "gl" / "golden"
FRAMES = {"lab_default_128.png": ("lab20", (128, 128))}
"""Golden file name: (scene, size)."""


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--out",
        type=Path,
        default=GOLDEN,
        help=f"folder to write the frames into (default {GOLDEN})",
    )
    args = parser.parse_args()
    args.out.mkdir(parents=True, exist_ok=True)
    with mirrorlab.Renderer() as renderer:
        for name, (scene, size) in FRAMES.items():
            path = args.out / name
            write_png_atomic(path, renderer.render(scene, size=size))
            print(f"wrote {path}")

    from mirrorlab.gl.context import offscreen_context
    from mirrorlab.renderer import SceneRenderer
    from tests.gl.golden_frames import FOLDER, draw_sequence, sequences

    shipped = args.out / FOLDER.relative_to(GOLDEN)
    shipped.mkdir(parents=True, exist_ok=True)
    with offscreen_context() as context:
        for sequence in sequences():
            scene_renderer = SceneRenderer(context.resources)
            try:
                image = draw_sequence(scene_renderer, sequence)
            finally:
                scene_renderer.release()
            path = shipped / sequence.path.name
            write_png_atomic(path, image)
            print(f"wrote {path} ({len(sequence.frames)} frames)")


if __name__ == "__main__":
    main()
