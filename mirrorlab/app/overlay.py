"""What the demo draws over the frame: text (rendered into a texture with Pillow) and
insets of a reflector's texture or a cube map's six faces, each a rectangle on the
screen drawn from one quad buffer with a small shader (no immediate mode)."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from mirrorlab.gl.context import ResourceRegistry
from mirrorlab.gl.opengl import GL
from mirrorlab.gl.resources import MeshBuffer, Program, Texture2D, TextureCube

TEXT_COLOR = (255, 255, 255, 255)
PANEL_COLOR = (16, 18, 24, 200)
"""The text's panel: dark and mostly opaque, so the text reads over any frame."""


Row = str | tuple[str, str]
"""A line of text, or a (key, what it does) pair set in two columns."""


def text_image(rows: Sequence[Row], scale: float = 1.0) -> np.ndarray:
    """``rows`` as white text on a dark, translucent panel: ``(h, w, 4)`` uint8 RGBA, row 0
    at the top; (key, text) rows in two aligned columns. ``scale`` multiplies the font
    size (13 pixels at 1; 2 on a high-DPI screen keeps the text's size on screen)."""
    from PIL import Image, ImageDraw, ImageFont

    size = max(6, round(13 * scale))
    font = ImageFont.load_default(size=size)
    line_height = round(size * 1.35)
    margin = round(6 * scale)
    keys = [row[0] for row in rows if isinstance(row, tuple)]
    column = max((font.getlength(key) for key in keys), default=0.0)
    column = int(column + 2 * font.getlength(" ")) if keys else 0

    def width_of(row: Row) -> float:
        if isinstance(row, tuple):
            return column + font.getlength(row[1])
        return font.getlength(row)

    width = int(max((width_of(row) for row in rows), default=0)) + 2 * margin
    height = line_height * len(rows) + 2 * margin
    image = Image.new("RGBA", (max(width, 1), max(height, 1)), PANEL_COLOR)
    draw = ImageDraw.Draw(image)
    for index, row in enumerate(rows):
        y = margin + index * line_height
        if isinstance(row, tuple):
            draw.text((margin, y), row[0], font=font, fill=TEXT_COLOR)
            draw.text((margin + column, y), row[1], font=font, fill=TEXT_COLOR)
        else:
            draw.text((margin, y), row, font=font, fill=TEXT_COLOR)
    return np.asarray(image)


def fitted_text_image(rows: Sequence[Row], scale: float, room: tuple[float, float]) -> np.ndarray:
    """:func:`text_image` at ``scale``, or smaller (down to half) until it fits ``room``
    (width, height) pixels."""
    image = text_image(rows, scale)
    step = scale
    while (image.shape[1] > room[0] or image.shape[0] > room[1]) and step > 0.5 * scale:
        step *= 0.9
        image = text_image(rows, step)
    return image


class Overlay:
    """Screen rectangles over the frame: :meth:`text` and :meth:`texture` and
    :meth:`cube_faces` insets. Positions are in framebuffer pixels from the top left."""

    def __init__(self, registry: ResourceRegistry) -> None:
        self.registry = registry
        corners = np.array(
            [
                [0, 0, 0, 0, 0, 1, 0, 0],
                [1, 0, 0, 0, 0, 1, 1, 0],
                [1, 1, 0, 0, 0, 1, 1, 1],
                [0, 1, 0, 0, 0, 1, 0, 1],
            ],
            dtype=np.float32,
        )
        self.quad = MeshBuffer(registry, corners, np.array([[0, 1, 2], [0, 2, 3]]))
        self.flat = Program(registry, "overlay.vert", "overlay.frag")
        self.cube = Program(registry, "overlay.vert", "overlay_cube.frag")
        self._texts: dict[str, tuple[tuple[Row, ...], tuple, Texture2D]] = {}

    # ------------------------------------------------------------- drawing

    def _begin(self) -> None:
        GL.glBindFramebuffer(GL.GL_FRAMEBUFFER, 0)
        GL.glDisable(GL.GL_DEPTH_TEST)
        GL.glDisable(GL.GL_STENCIL_TEST)
        GL.glDisable(GL.GL_CULL_FACE)
        GL.glDisable(GL.GL_CLIP_DISTANCE0)
        GL.glEnable(GL.GL_BLEND)
        GL.glBlendFunc(GL.GL_SRC_ALPHA, GL.GL_ONE_MINUS_SRC_ALPHA)

    def _end(self) -> None:
        GL.glDisable(GL.GL_BLEND)
        GL.glEnable(GL.GL_DEPTH_TEST)
        GL.glUseProgram(0)
        GL.glBindVertexArray(0)

    @staticmethod
    def _rect(
        left: float, top: float, width: float, height: float, screen: tuple[int, int]
    ) -> tuple[float, float, float, float]:
        """Pixels (from the top left) to (left, bottom, right, top) in device coordinates."""
        sw, sh = screen
        return (
            2.0 * left / sw - 1.0,
            1.0 - 2.0 * (top + height) / sh,
            2.0 * (left + width) / sw - 1.0,
            1.0 - 2.0 * top / sh,
        )

    def text(
        self,
        slot: str,
        lines: Sequence[Row],
        position: tuple[float, float],
        screen: tuple[int, int],
        scale: float = 1.0,
    ) -> tuple[int, int]:
        """Draw ``lines`` with their top left at ``position``, made smaller if they would
        not fit the screen; returns the panel's size. Each ``slot`` (``help``,
        ``label``) keeps its texture until its text or the screen changes."""
        held = self._texts.get(slot)
        key = (tuple(lines), (scale, screen))
        if held is None or held[:2] != key:
            if held is not None:
                held[2].release()
            room = (screen[0] - 2 * position[0], screen[1] - position[1])
            texture = Texture2D.from_image(
                self.registry, fitted_text_image(lines, scale, room), what="the help text"
            )
            GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MIN_FILTER, GL.GL_NEAREST)
            GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAG_FILTER, GL.GL_NEAREST)
            held = self._texts[slot] = (*key, texture)
        texture = held[2]
        self.texture(texture, position, (texture.width, texture.height), screen, opaque=False)
        return texture.width, texture.height

    def texture(
        self,
        texture: Texture2D,
        position: tuple[float, float],
        size: tuple[float, float],
        screen: tuple[int, int],
        opaque: bool = True,
    ) -> None:
        """Draw ``texture`` into the ``size`` rectangle at ``position`` (pixels, top left)."""
        self._begin()
        program = self.flat
        program.use()
        program.set_vec4("rect", self._rect(*position, *size, screen))
        program.set_int("picture", 0)
        program.set_int("opaque", opaque)
        texture.bind(0)
        self.quad.draw()
        self._end()

    def cube_faces(
        self,
        cube: TextureCube,
        position: tuple[float, float],
        face_size: float,
        screen: tuple[int, int],
    ) -> None:
        """The six faces in a row, GL order +X, -X, +Y, -Y, +Z, -Z, from ``position``."""
        self._begin()
        GL.glEnable(GL.GL_TEXTURE_CUBE_MAP_SEAMLESS)
        program = self.cube
        program.use()
        program.set_int("cube", 0)
        cube.bind(0)
        for face in range(6):
            left = position[0] + face * (face_size + 2)
            program.set_vec4("rect", self._rect(left, position[1], face_size, face_size, screen))
            program.set_int("face", face)
            self.quad.draw()
        self._end()

    def release(self) -> None:
        for _, _, texture in self._texts.values():
            texture.release()
        self._texts.clear()
        for resource in (self.quad, self.flat, self.cube):
            resource.release()
