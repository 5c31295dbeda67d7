"""Drawing one frame of a scene in a test: ``draw(renderer, scene, size)``."""

from __future__ import annotations


def draw(renderer, scene, size=(128, 128), **render_options):
    """Render ``scene`` (a Scene) with ``renderer`` into a fresh ``size`` framebuffer;
    returns ``(image (h, w, 3) uint8, FrameStats)``. The framebuffer is released."""
    from mirrorlab.gl.resources import Framebuffer

    target = Framebuffer(renderer.registry, *size)
    try:
        stats = renderer.render(scene, target, **render_options)
        return target.read(), stats
    finally:
        target.release()
