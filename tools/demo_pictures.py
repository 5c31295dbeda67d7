"""Re-make the README's pictures of the demo window: docs/demo-window.png (the lab scene
with its help overlay, H) and docs/demo-inset.png (mirror_and_sphere with the sphere's
live cube map as an inset, E with the pointer on the sphere). Needs a display:

    xvfb-run -a -s "-screen 0 1280x1024x24" .venv/bin/python tools/demo_pictures.py
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from PIL import Image

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from mirrorlab import load_scene, math3d  # noqa: E402
from tests.scenekit import curved_reflector  # noqa: E402
from tests.window.xwindow import (  # noqa: E402
    Demo,
    find_window,
    frame_number,
    move_pointer,
    press,
    screenshot,
    settled,
)

SIZE = (640, 480)


def picture(scene: str, keys: list[str], pointer: tuple[int, int] | None, out: Path) -> None:
    from Xlib import display

    d = display.Display()
    demo = Demo(scene, "--size", f"{SIZE[0]}x{SIZE[1]}")
    try:
        window = find_window(d, f"mirrorlab demo - {scene}")
        settled(d, window, 0)
        if pointer is not None:
            move_pointer(d, window, *pointer)
        for key in keys:
            count = frame_number(window)
            press(d, window, key)
            settled(d, window, count)
        Image.fromarray(screenshot(d, window)).save(out)
        print(f"wrote {out}")
        press(d, window, "Escape")
        demo.finish()
    finally:
        demo.stop()
        d.close()


def main() -> int:
    docs = ROOT / "docs"
    picture("lab20", ["h"], None, docs / "demo-window.png")
    scene = load_scene("mirror_and_sphere")
    camera = scene.camera
    x, y, _ = math3d.project_to_pixels(
        camera.projection(SIZE[0] / SIZE[1]) @ camera.view(),
        np.asarray(curved_reflector(scene, "sphere").center()),
        *SIZE,
    )
    picture("mirror_and_sphere", ["e"], (int(x), int(y)), docs / "demo-inset.png")
    return 0


if __name__ == "__main__":
    sys.exit(main())
