"""Rendered frames as numpy arrays that show themselves as pictures in Jupyter.

:func:`mirrorlab.render` and :class:`mirrorlab.Renderer` return a :class:`Frame`: a plain
``(height, width, 3)`` uint8 numpy array (row 0 at the top) in every respect, which a
notebook displays as a picture, the last expression of a cell or through
``IPython.display.display``. :func:`show` makes one of any such array (a capture texture,
a picture you composed). Numpy only: no OpenGL, no IPython needed.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np


class Frame(np.ndarray):
    """An image array that Jupyter shows as a picture (IPython's ``_repr_png_``).

    Slices and copies of a Frame stay Frames; arithmetic on it (``frame - other``,
    ``frame.mean()``) gives plain arrays and numbers, as for any array. Only a
    ``(h, w, 3)`` or ``(h, w, 4)`` uint8 Frame with pixels shows as a picture; any other
    shape or type shows as the array it is.
    """

    def __new__(cls, image: Any) -> Frame:
        return np.asarray(image).view(cls)

    def __array_wrap__(
        self, array: np.ndarray, context: Any = None, return_scalar: bool = False
    ) -> Any:
        # Results of ufuncs and reductions are numbers, not pictures: plain arrays.
        plain = np.asarray(array)
        return plain[()] if return_scalar else plain

    @property
    def is_picture(self) -> bool:
        """True when this array is an RGB or RGBA picture Jupyter can show."""
        return (
            self.ndim == 3
            and self.shape[2] in (3, 4)
            and self.dtype == np.uint8
            and self.shape[0] > 0
            and self.shape[1] > 0
        )

    def png(self) -> bytes:
        """The picture as PNG file bytes; ValueError when it is no picture."""
        if not self.is_picture:
            raise ValueError(
                f"a picture is (h, w, 3) or (h, w, 4) uint8; this array is "
                f"{self.shape} {self.dtype}"
            )
        import io

        from PIL import Image

        with io.BytesIO() as buffer:
            Image.fromarray(np.ascontiguousarray(np.asarray(self))).save(buffer, format="PNG")
            return buffer.getvalue()

    def _repr_png_(self) -> bytes | None:
        return self.png() if self.is_picture else None

    def save(self, path: str | Path) -> Path:
        """Write the picture to ``path`` as a PNG (whole or not at all); returns the path."""
        from mirrorlab.files import write_bytes_atomic

        target = Path(path)
        write_bytes_atomic(target, self.png())
        return target


def show(image: Any) -> Frame:
    """``image`` (any ``(h, w, 3)`` or ``(h, w, 4)`` uint8 array) as a :class:`Frame`, which a
    notebook shows as a picture: ``mirrorlab.show(renderer.read_texture("mirror"))``."""
    return Frame(image)
