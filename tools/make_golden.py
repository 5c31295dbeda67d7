"""Re-make the golden frames under tests/gl/golden/ from the current renderer.

Only after looking at the new picture and agreeing that it is right:
``python tools/make_golden.py``.
"""

from pathlib import Path

from PIL import Image

import mirrorlab

GOLDEN = Path(__file__).resolve().parents[1] / "tests" / "gl" / "golden"

if __name__ == "__main__":
    GOLDEN.mkdir(parents=True, exist_ok=True)
    path = GOLDEN / "lab_default_128.png"
    Image.fromarray(mirrorlab.render(size=(128, 128))).save(path)
    print(f"wrote {path}")
