"""GL object wrappers with explicit lifetimes: Program, Texture2D, TextureCube,
DepthTextureCube, Framebuffer, MeshBuffer, PackedMeshes, Buffer.

Each wrapper registers with the context's
:class:`~mirrorlab.gl.context.ResourceRegistry` and frees its GL name in
``release()`` (idempotent). Nothing is freed in ``__del__``: GL calls need the
right context current, which a garbage collector cannot promise.

Images cross this module as numpy arrays ``(height, width, 3)`` uint8 in
image row order (row 0 at the top); GL keeps row 0 at the bottom, and the
flip happens here, nowhere else.
"""

from __future__ import annotations

import ctypes
import re
from collections.abc import Callable
from typing import Protocol

import numpy as np

from mirrorlab.errors import GLLimitError
from mirrorlab.gl.calls import cached_state_epoch, gl, raw
from mirrorlab.gl.context import GLContextError, ResourceRegistry, unchecked
from mirrorlab.gl.opengl import GL
from mirrorlab.shaders import shader_source


class RenderTarget(Protocol):
    """Something a pass can draw into: :class:`Framebuffer` or :class:`DefaultFramebuffer`."""

    @property
    def size(self) -> tuple[int, int]:
        """(width, height) in pixels."""
        ...

    def bind(self) -> None: ...

    def read(self) -> np.ndarray: ...


class _Resource:
    def __init__(self, registry: ResourceRegistry) -> None:
        self._registry = registry
        self._released = False
        registry.add(self)

    @property
    def released(self) -> bool:
        return self._released

    def release(self) -> None:
        if self._released:
            return
        self._free()
        self._released = True
        self._registry.discard(self)

    def _free(self) -> None:  # pragma: no cover - overridden
        raise NotImplementedError


_INCLUDE = re.compile(r'^\s*#include\s+"([^"]+)"\s*$', re.MULTILINE)


def expand_includes(
    name: str, seen: tuple[str, ...] = (), aliases: dict[str, str] | None = None
) -> str:
    """The shader file ``name`` with every ``#include "other.glsl"`` line replaced by that
    package shader file's text (recursively; an include cycle is a ValueError). An
    include named in ``aliases`` pulls in the file it maps to instead (a view's warp
    standing in for ``warp.glsl``)."""
    if name in seen:
        raise ValueError(f"shader include cycle: {' -> '.join((*seen, name))}")
    chosen = (aliases or {}).get(name, name) if seen else name
    return _INCLUDE.sub(
        lambda match: expand_includes(match.group(1), (*seen, name), aliases),
        shader_source(chosen),
    )


class Program(_Resource):
    """A linked shader program built from package shader files. Lines ``#include
    "file.glsl"`` pull in shared GLSL from the same folder (``includes`` maps an included
    name to another file that stands in for it); ``defines`` are added as ``#define NAME
    VALUE`` lines after the ``#version`` line."""

    def __init__(
        self,
        registry: ResourceRegistry,
        vertex: str,
        fragment: str,
        defines: dict[str, str | int] | None = None,
        includes: dict[str, str] | None = None,
    ) -> None:
        header = "".join(f"#define {key} {value}\n" for key, value in (defines or {}).items())
        shaders: list[int] = []
        for name, kind in ((vertex, GL.GL_VERTEX_SHADER), (fragment, GL.GL_FRAGMENT_SHADER)):
            version, _, body = expand_includes(name, aliases=includes).partition("\n")
            shader = gl.glCreateShader(kind)
            gl.glShaderSource(shader, f"{version}\n{header}{body}")
            gl.glCompileShader(shader)
            if not gl.glGetShaderiv(shader, GL.GL_COMPILE_STATUS):
                log = gl.glGetShaderInfoLog(shader).decode(errors="replace").strip()
                gl.glDeleteShader(shader)
                for done in shaders:
                    gl.glDeleteShader(done)
                raise GLContextError(f"shader {name} did not compile: {log}")
            shaders.append(shader)
        self.name = gl.glCreateProgram()
        for shader in shaders:
            gl.glAttachShader(self.name, shader)
        gl.glLinkProgram(self.name)
        for shader in shaders:
            gl.glDetachShader(self.name, shader)
            gl.glDeleteShader(shader)
        if not gl.glGetProgramiv(self.name, GL.GL_LINK_STATUS):
            log = gl.glGetProgramInfoLog(self.name).decode(errors="replace").strip()
            gl.glDeleteProgram(self.name)
            raise GLContextError(f"program {vertex}+{fragment} did not link: {log}")
        self.label = f"{vertex}+{fragment}"
        self._locations: dict[str, int] = {}
        self._values: dict[int, object] = {}  # what each uniform location holds
        self._epoch = cached_state_epoch()  # when _values was begun
        super().__init__(registry)

    def use(self) -> None:
        gl.glUseProgram(self.name)

    def location(self, uniform: str) -> int:
        """Uniform location (cached); KeyError if the program has no active uniform by that name."""
        loc = self._locations.get(uniform)
        if loc is None:
            loc = int(gl.glGetUniformLocation(self.name, uniform))
            if loc < 0:
                raise KeyError(f"program {self.label} has no active uniform {uniform!r}")
            self._locations[uniform] = loc
        return loc

    def has_uniform(self, uniform: str) -> bool:
        """True when the linked program uses ``uniform`` (the compiler drops unused ones)."""
        try:
            self.location(uniform)
        except KeyError:
            return False
        return True

    # Each setter skips the call when the uniform already holds the value: a program keeps
    # its uniforms, and a still frame sets the same ones every frame. Not in a recording
    # for a value set before it began (the replay rule, mirrorlab.gl.calls): a replay
    # starts from the uniforms the recorded frame left, not from those it found.

    def _unchanged(self, location: int, value: object) -> bool:
        epoch = cached_state_epoch()
        if self._epoch != epoch:
            self._values.clear()
            self._epoch = epoch
        if self._values.get(location) == value:
            return True
        self._values[location] = value
        return False

    def set_mat4(self, uniform: str, matrix: np.ndarray) -> None:
        """Set a ``(4, 4)`` row-major (numpy) matrix."""
        data = np.asarray(matrix, dtype=np.float32)
        location = self.location(uniform)
        if not self._unchanged(location, data.tobytes()):
            raw.glUniformMatrix4fv(location, 1, GL.GL_TRUE, data)

    def set_mat3(self, uniform: str, matrix: np.ndarray) -> None:
        """Set a ``(3, 3)`` row-major (numpy) matrix."""
        data = np.asarray(matrix, dtype=np.float32)
        location = self.location(uniform)
        if not self._unchanged(location, data.tobytes()):
            gl.glUniformMatrix3fv(location, 1, GL.GL_TRUE, data)

    def set_vec2(self, uniform: str, value) -> None:
        x, y = (float(v) for v in value)
        location = self.location(uniform)
        if not self._unchanged(location, ("2f", x, y)):
            gl.glUniform2f(location, x, y)

    def set_vec3(self, uniform: str, value) -> None:
        x, y, z = (float(v) for v in value)
        location = self.location(uniform)
        if not self._unchanged(location, ("3f", x, y, z)):
            gl.glUniform3f(location, x, y, z)

    def set_vec4(self, uniform: str, value) -> None:
        x, y, z, w = (float(v) for v in value)
        location = self.location(uniform)
        if not self._unchanged(location, ("4f", x, y, z, w)):
            gl.glUniform4f(location, x, y, z, w)

    def set_vec3_array(self, uniform: str, values: np.ndarray) -> None:
        """Set a ``vec3`` array uniform from ``values`` ``(n, 3)``."""
        data = np.asarray(values, dtype=np.float32)
        location = self.location(uniform)
        if not self._unchanged(location, data.tobytes()):
            raw.glUniform3fv(location, len(data), data)

    def set_float(self, uniform: str, value: float) -> None:
        location = self.location(uniform)
        if not self._unchanged(location, ("1f", float(value))):
            gl.glUniform1f(location, float(value))

    def set_int(self, uniform: str, value: int) -> None:
        location = self.location(uniform)
        if not self._unchanged(location, ("1i", int(value))):
            gl.glUniform1i(location, int(value))

    def set_ivec2(self, uniform: str, value) -> None:
        x, y = (int(v) for v in value)
        location = self.location(uniform)
        if not self._unchanged(location, ("2i", x, y)):
            gl.glUniform2i(location, x, y)

    def _free(self) -> None:
        gl.glDeleteProgram(self.name)


def check_texture_size(width: int, height: int, what: str, cube: bool = False) -> None:
    """GLLimitError naming ``what`` when a ``width`` x ``height`` texture (a cube map's face,
    with ``cube``) is larger than this GL allows."""
    limit_name = "GL_MAX_CUBE_MAP_TEXTURE_SIZE" if cube else "GL_MAX_TEXTURE_SIZE"
    limit = int(np.asarray(gl.glGetIntegerv(getattr(GL, limit_name))).reshape(-1)[0])
    if width > limit or height > limit:
        raise GLLimitError(
            f"{what} is {width}x{height}, larger than this OpenGL allows ({limit_name} {limit})"
        )


class Texture2D(_Resource):
    """A 2D RGB texture (RGBA when made from ``(h, w, 4)`` pixels). Make one with
    :meth:`from_image` or :meth:`blank`."""

    def __init__(
        self,
        registry: ResourceRegistry,
        width: int,
        height: int,
        pixels: np.ndarray | None,
        mipmaps: bool,
        clamp: bool,
        what: str = "a texture",
    ) -> None:
        check_texture_size(width, height, what)
        self.name = int(gl.glGenTextures(1))
        self.width, self.height = int(width), int(height)
        self.mipmaps = mipmaps
        alpha = pixels is not None and pixels.shape[-1] == 4
        gl.glBindTexture(GL.GL_TEXTURE_2D, self.name)
        gl.glPixelStorei(GL.GL_UNPACK_ALIGNMENT, 1)
        data = None if pixels is None else np.ascontiguousarray(pixels[::-1])
        gl.glTexImage2D(
            GL.GL_TEXTURE_2D,
            0,
            GL.GL_RGBA8 if alpha else GL.GL_RGB8,
            self.width,
            self.height,
            0,
            GL.GL_RGBA if alpha else GL.GL_RGB,
            GL.GL_UNSIGNED_BYTE,
            data,
        )
        wrap = GL.GL_CLAMP_TO_EDGE if clamp else GL.GL_REPEAT
        gl.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_WRAP_S, wrap)
        gl.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_WRAP_T, wrap)
        gl.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAG_FILTER, GL.GL_LINEAR)
        if mipmaps:
            gl.glGenerateMipmap(GL.GL_TEXTURE_2D)
            min_filter = GL.GL_LINEAR_MIPMAP_LINEAR
        else:
            min_filter = GL.GL_LINEAR
        gl.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MIN_FILTER, min_filter)
        if not mipmaps:
            gl.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAX_LEVEL, 0)
        super().__init__(registry)

    @classmethod
    def from_image(
        cls, registry: ResourceRegistry, image: np.ndarray, what: str = "a texture"
    ) -> Texture2D:
        """A mipmapped, repeating texture from ``image`` ``(h, w, 3)`` (or ``(h, w, 4)``, with
        alpha) uint8, row 0 at the top; ``what`` names it in a GLLimitError."""
        image = np.asarray(image)
        if image.ndim != 3 or image.shape[2] not in (3, 4) or image.dtype != np.uint8:
            raise ValueError(
                f"texture image must be (h, w, 3) or (h, w, 4) uint8, got "
                f"{image.shape} {image.dtype}"
            )
        return cls(
            registry, image.shape[1], image.shape[0], image, mipmaps=True, clamp=False, what=what
        )

    @classmethod
    def blank(cls, registry: ResourceRegistry, width: int, height: int) -> Texture2D:
        """An empty ``width`` x ``height`` texture for a capture: level 0 only, GL_LINEAR,
        clamped to the edge (the lab's ENVIRONMENT texture)."""
        return cls(registry, width, height, None, mipmaps=False, clamp=True)

    @classmethod
    def with_levels(
        cls,
        registry: ResourceRegistry,
        sizes: tuple[int, ...],
        levels: list[np.ndarray] | None = None,
        what: str = "a texture",
    ) -> Texture2D:
        """A square RGB texture whose mip levels are its own, not GL's filtering of level
        0 (an octahedral map's, each with a border of its own): level ``k`` is
        ``sizes[k]`` texels wide, GL's ``size >> k``, and holds ``levels[k]`` (``(n_k,
        n_k, 3)`` uint8, row 0 at the top) or nothing yet, for a pass to draw into
        (:class:`TextureFramebuffer` of that level). Clamped to the edge, linear within
        and between levels, no level past the last of ``sizes``."""
        if any(size != sizes[0] >> k for k, size in enumerate(sizes)):
            raise ValueError(f"mip level sizes must halve as GL's do, got {sizes}")
        texture = cls(registry, sizes[0], sizes[0], None, mipmaps=False, clamp=True, what=what)
        texture.mipmaps = True
        gl.glPixelStorei(GL.GL_UNPACK_ALIGNMENT, 1)
        for level, size in enumerate(sizes):
            data = None
            if levels is not None:
                image = np.asarray(levels[level])
                if image.shape != (size, size, 3) or image.dtype != np.uint8:
                    raise ValueError(
                        f"mip level {level} must be ({size}, {size}, 3) uint8, got "
                        f"{image.shape} {image.dtype}"
                    )
                data = np.ascontiguousarray(image[::-1])
            gl.glTexImage2D(
                GL.GL_TEXTURE_2D,
                level,
                GL.GL_RGB8,
                size,
                size,
                0,
                GL.GL_RGB,
                GL.GL_UNSIGNED_BYTE,
                data,
            )
        gl.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAX_LEVEL, len(sizes) - 1)
        gl.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MIN_FILTER, GL.GL_LINEAR_MIPMAP_LINEAR)
        return texture

    def bind(self, unit: int = 0) -> None:
        gl.glActiveTexture(GL.GL_TEXTURE0 + unit)
        gl.glBindTexture(GL.GL_TEXTURE_2D, self.name)

    def generate_mipmaps(self) -> None:
        """Rebuild the mipmap levels from level 0 (after a capture); needs ``mipmaps``."""
        if not self.mipmaps:
            raise ValueError("this texture was made without mipmaps")
        gl.glBindTexture(GL.GL_TEXTURE_2D, self.name)
        gl.glGenerateMipmap(GL.GL_TEXTURE_2D)

    def copy_square_from_framebuffer(self, x: int, size: int, source: tuple[int, int]) -> None:
        """Copy the bound read framebuffer's lower-left ``size`` x ``size`` square into
        level 0 at column ``x`` (the storage the texture has; ``glCopyTexSubImage2D``).
        ``source`` is the size of the framebuffer read, which must hold the square, and
        the texture must hold it at ``x``."""
        if size > min(source) or x < 0 or x + size > self.width or size > self.height:
            raise ValueError(
                f"a {size}x{size} copy from a {source[0]}x{source[1]} framebuffer does "
                f"not fit a {self.width}x{self.height} texture at column {x}"
            )
        gl.glBindTexture(GL.GL_TEXTURE_2D, self.name)
        gl.glCopyTexSubImage2D(GL.GL_TEXTURE_2D, 0, int(x), 0, 0, 0, int(size), int(size))

    def copy_from_framebuffer(
        self,
        width: int,
        height: int,
        source: tuple[int, int],
        region: tuple[int, int, int, int] | None = None,
    ) -> None:
        """Copy the bound read framebuffer's lower-left ``width`` x ``height`` into level 0.

        This is the lab's ``glCopyTexImage2D(GL_TEXTURE_2D, 0, GL_RGB, 0, 0, w, h, 0)``;
        the texture takes the copied size. Once it has that size, later copies go into
        the storage it has (``glCopyTexSubImage2D``) rather than defining level 0 anew
        every frame, as ``glCopyTexImage2D`` does, and only ``region`` (x, y, width,
        height in pixels, clipped to the texture) is copied when given: the caller knows
        the rest is as the last copy left it. ``source`` is the size of the framebuffer
        read: a copy reaching outside it (whose texels GL leaves undefined) is refused.
        """
        if width > source[0] or height > source[1]:
            raise ValueError(
                f"a {width}x{height} copy reaches outside the {source[0]}x"
                f"{source[1]} framebuffer it reads"
            )
        gl.glBindTexture(GL.GL_TEXTURE_2D, self.name)
        if (int(width), int(height)) == (self.width, self.height):
            x, y, w, h = (0, 0, int(width), int(height)) if region is None else region
            x0, y0 = max(int(x), 0), max(int(y), 0)
            x1, y1 = min(int(x + w), int(width)), min(int(y + h), int(height))
            if x1 > x0 and y1 > y0:
                gl.glCopyTexSubImage2D(GL.GL_TEXTURE_2D, 0, x0, y0, x0, y0, x1 - x0, y1 - y0)
            return
        gl.glCopyTexImage2D(GL.GL_TEXTURE_2D, 0, GL.GL_RGB, 0, 0, int(width), int(height), 0)
        self.width, self.height = int(width), int(height)

    def allocate(self, width: int, height: int) -> None:
        """Give level 0 fresh, undefined storage of ``width`` x ``height`` (for an FBO to draw
        into); a no-op when it already has that size."""
        if (int(width), int(height)) == (self.width, self.height):
            return
        gl.glBindTexture(GL.GL_TEXTURE_2D, self.name)
        gl.glTexImage2D(
            GL.GL_TEXTURE_2D,
            0,
            GL.GL_RGB8,
            int(width),
            int(height),
            0,
            GL.GL_RGB,
            GL.GL_UNSIGNED_BYTE,
            None,
        )
        self.width, self.height = int(width), int(height)

    def read(self) -> np.ndarray:
        """Level 0 as ``(height, width, 3)`` uint8, row 0 at the top."""
        gl.glBindTexture(GL.GL_TEXTURE_2D, self.name)
        gl.glPixelStorei(GL.GL_PACK_ALIGNMENT, 1)
        data = gl.glGetTexImage(GL.GL_TEXTURE_2D, 0, GL.GL_RGB, GL.GL_UNSIGNED_BYTE)
        pixels = np.frombuffer(data, dtype=np.uint8).reshape(self.height, self.width, 3)
        return pixels[::-1].copy()

    def _free(self) -> None:
        gl.glDeleteTextures([self.name])


PACK_INVERT_MESA = 0x8758
"""``GL_PACK_INVERT_MESA`` (``GL_MESA_pack_invert``): pixels read back top row first."""


def read_pixels(
    width: int, height: int, rows: np.ndarray | None = None, top_first: bool = False
) -> np.ndarray:
    """The bound read framebuffer's lower-left region as a new ``(height, width, 3)`` uint8
    array, top row first. With ``top_first`` (the context has ``GL_MESA_pack_invert``)
    GL writes the rows in that order straight into the new array; else ``rows``, a
    C-contiguous ``(height, width, 3)`` uint8 array, is where GL writes them first
    (bottom row first, as GL keeps them), and they are copied over in the other order
    (one is made when not given)."""
    pixel_store = unchecked(gl.glPixelStorei)  # an error shows at the caller's check
    pixel_store(GL.GL_PACK_ALIGNMENT, 1)
    # Into an array of ours: PyOpenGL's own result array and its conversion cost 0.8 ms
    # of Python at 512 x 512, more than the driver's copy (0.27 ms).
    if top_first:
        image = np.empty((height, width, 3), dtype=np.uint8)
        pixel_store(PACK_INVERT_MESA, 1)
        try:
            raw.glReadPixels(0, 0, width, height, GL.GL_RGB, GL.GL_UNSIGNED_BYTE, image)
        finally:
            pixel_store(PACK_INVERT_MESA, 0)  # glGetTexImage follows it too
        return image
    if rows is None:
        rows = np.empty((height, width, 3), dtype=np.uint8)
    raw.glReadPixels(0, 0, width, height, GL.GL_RGB, GL.GL_UNSIGNED_BYTE, rows)
    return rows[::-1].copy()


class _FramebufferObject(_Resource):
    """What every framebuffer object offers: its size, binding and a colour readback.
    Subclasses set ``name``, ``width`` and ``height``."""

    name: int
    width: int
    height: int
    _rows: np.ndarray | None = None
    """Where :meth:`read` has GL write the rows when GL cannot write them top row first,
    kept from frame to frame: a fresh 0.8 MB array a frame (at 512 x 512) would be
    fresh pages for the kernel to zero."""
    top_first: bool | None = None
    """Whether :meth:`read` has GL write the rows top row first (``GL_MESA_pack_invert``;
    asked of the context at the first read)."""

    @property
    def size(self) -> tuple[int, int]:
        return self.width, self.height

    def bind(self) -> None:
        gl.glBindFramebuffer(GL.GL_FRAMEBUFFER, self.name)

    def read(self) -> np.ndarray:
        """Colour as ``(height, width, 3)`` uint8, row 0 at the top (a new array)."""
        self.bind()
        if self.top_first is None:
            self.top_first = "GL_MESA_pack_invert" in self._registry.extensions()
        if self.top_first:
            return read_pixels(self.width, self.height, top_first=True)
        if self._rows is None or self._rows.shape[:2] != (self.height, self.width):
            self._rows = np.empty((self.height, self.width, 3), dtype=np.uint8)
        return read_pixels(self.width, self.height, self._rows)


class Framebuffer(_FramebufferObject):
    """An offscreen render target: RGBA8 colour and 24-bit depth + 8-bit stencil renderbuffers."""

    COLOR_FORMAT = GL.GL_RGBA8

    def __init__(self, registry: ResourceRegistry, width: int, height: int) -> None:
        if width < 1 or height < 1:
            raise ValueError(f"framebuffer size must be positive, got {width}x{height}")
        max_size = int(gl.glGetIntegerv(GL.GL_MAX_RENDERBUFFER_SIZE))
        if width > max_size or height > max_size:
            raise ValueError(
                f"framebuffer size {width}x{height} exceeds this GL's limit of {max_size}"
            )
        self.width, self.height = int(width), int(height)
        self.name = int(gl.glGenFramebuffers(1))
        self._renderbuffers = [int(n) for n in np.atleast_1d(gl.glGenRenderbuffers(2))]
        gl.glBindFramebuffer(GL.GL_FRAMEBUFFER, self.name)
        for rb, fmt, attachment in zip(
            self._renderbuffers,
            (self.COLOR_FORMAT, GL.GL_DEPTH24_STENCIL8),
            (GL.GL_COLOR_ATTACHMENT0, GL.GL_DEPTH_STENCIL_ATTACHMENT),
            strict=True,
        ):
            gl.glBindRenderbuffer(GL.GL_RENDERBUFFER, rb)
            gl.glRenderbufferStorage(GL.GL_RENDERBUFFER, fmt, self.width, self.height)
            gl.glFramebufferRenderbuffer(GL.GL_FRAMEBUFFER, attachment, GL.GL_RENDERBUFFER, rb)
        status = gl.glCheckFramebufferStatus(GL.GL_FRAMEBUFFER)
        if status != GL.GL_FRAMEBUFFER_COMPLETE:
            gl.glDeleteRenderbuffers(2, self._renderbuffers)
            gl.glDeleteFramebuffers(1, [self.name])
            raise GLContextError(f"framebuffer {width}x{height} incomplete (status {status:#x})")
        super().__init__(registry)

    def _free(self) -> None:
        gl.glDeleteRenderbuffers(2, self._renderbuffers)
        gl.glDeleteFramebuffers(1, [self.name])


class TextureFramebuffer(_FramebufferObject):
    """An offscreen target that draws straight into a :class:`Texture2D`'s ``level`` (0 by
    default), with a 24-bit depth + 8-bit stencil renderbuffer of the same size unless
    ``depth`` is False (a pass that fills a texture without depth testing).

    The texture keeps its own lifetime; this frees only the framebuffer and
    its depth buffer. Re-make it after the texture is re-allocated.
    """

    def __init__(
        self, registry: ResourceRegistry, texture: Texture2D, level: int = 0, depth: bool = True
    ) -> None:
        self.texture = texture
        self.width, self.height = max(1, texture.width >> level), max(1, texture.height >> level)
        self.name = int(gl.glGenFramebuffers(1))
        self._depth = int(gl.glGenRenderbuffers(1)) if depth else 0
        gl.glBindFramebuffer(GL.GL_FRAMEBUFFER, self.name)
        gl.glFramebufferTexture2D(
            GL.GL_FRAMEBUFFER, GL.GL_COLOR_ATTACHMENT0, GL.GL_TEXTURE_2D, texture.name, level
        )
        if depth:
            gl.glBindRenderbuffer(GL.GL_RENDERBUFFER, self._depth)
            gl.glRenderbufferStorage(
                GL.GL_RENDERBUFFER, GL.GL_DEPTH24_STENCIL8, self.width, self.height
            )
            gl.glFramebufferRenderbuffer(
                GL.GL_FRAMEBUFFER, GL.GL_DEPTH_STENCIL_ATTACHMENT, GL.GL_RENDERBUFFER, self._depth
            )
        status = gl.glCheckFramebufferStatus(GL.GL_FRAMEBUFFER)
        if status != GL.GL_FRAMEBUFFER_COMPLETE:
            self._free()
            raise GLContextError(
                f"texture framebuffer {self.width}x{self.height} incomplete (status {status:#x})"
            )
        super().__init__(registry)

    def _free(self) -> None:
        if self._depth:
            gl.glDeleteRenderbuffers(1, [self._depth])
        gl.glDeleteFramebuffers(1, [self.name])


class TimerQuery(_Resource):
    """GPU time of the commands between :meth:`begin` and :meth:`end` (GL_TIME_ELAPSED)."""

    def __init__(self, registry: ResourceRegistry) -> None:
        self.name = int(np.asarray(gl.glGenQueries(1)).reshape(-1)[0])
        super().__init__(registry)

    def begin(self) -> None:
        gl.glBeginQuery(GL.GL_TIME_ELAPSED, self.name)

    def end(self) -> None:
        gl.glEndQuery(GL.GL_TIME_ELAPSED)

    def milliseconds(self) -> float:
        """The elapsed time of the last begin/end pair; waits for it to be available."""
        # The 32-bit query (PyOpenGL 3.1 cannot convert the 64-bit one's result type)
        # holds up to 4.29 s, far more than a frame.
        nanoseconds = gl.glGetQueryObjectuiv(self.name, GL.GL_QUERY_RESULT)
        return float(np.asarray(nanoseconds).reshape(-1)[0]) / 1e6

    def _free(self) -> None:
        gl.glDeleteQueries(1, [self.name])


class DefaultFramebuffer:
    """The window's own framebuffer (GL name 0), with the same interface as Framebuffer.

    ``size`` is asked of the window each time, so it follows resizes.
    """

    def __init__(self, size_source: Callable[[], tuple[int, int]]) -> None:
        self._size_source = size_source

    @property
    def size(self) -> tuple[int, int]:
        return self._size_source()

    def bind(self) -> None:
        gl.glBindFramebuffer(GL.GL_FRAMEBUFFER, 0)

    def read(self) -> np.ndarray:
        self.bind()
        gl.glReadBuffer(GL.GL_BACK)
        width, height = self.size
        return read_pixels(width, height)


def upload_mesh(vertices: np.ndarray, indices: np.ndarray) -> tuple[int, int, int]:
    """A new VAO over a new interleaved VBO of ``vertices`` ``(n, 8)`` float32 (location 0
    position xyz, 1 normal xyz, 2 uv) and an index buffer of ``indices`` (flat uint32);
    returns the names ``(vao, vbo, ebo)``, the VAO unbound. Whoever calls it deletes them."""
    vao = int(gl.glGenVertexArrays(1))
    vbo, ebo = (int(n) for n in gl.glGenBuffers(2))
    gl.glBindVertexArray(vao)
    gl.glBindBuffer(GL.GL_ARRAY_BUFFER, vbo)
    gl.glBufferData(GL.GL_ARRAY_BUFFER, vertices.nbytes, vertices, GL.GL_STATIC_DRAW)
    gl.glBindBuffer(GL.GL_ELEMENT_ARRAY_BUFFER, ebo)
    gl.glBufferData(GL.GL_ELEMENT_ARRAY_BUFFER, indices.nbytes, indices, GL.GL_STATIC_DRAW)
    stride = vertices.shape[1] * vertices.itemsize
    for location, (size, offset) in enumerate(((3, 0), (3, 12), (2, 24))):
        gl.glEnableVertexAttribArray(location)
        gl.glVertexAttribPointer(
            location, size, GL.GL_FLOAT, GL.GL_FALSE, stride, GL.GLvoidp(offset)
        )
    gl.glBindVertexArray(0)
    return vao, vbo, ebo


class MeshBuffer(_Resource):
    """A mesh in GPU memory: one VAO over an interleaved VBO and an index buffer.

    Vertex layout (float32): location 0 position xyz, 1 normal xyz, 2 uv.
    """

    STRIDE = 8 * 4

    def __init__(
        self, registry: ResourceRegistry, vertices: np.ndarray, indices: np.ndarray
    ) -> None:
        vertices = np.ascontiguousarray(vertices, dtype=np.float32)
        indices = np.ascontiguousarray(indices, dtype=np.uint32).reshape(-1)
        if vertices.ndim != 2 or vertices.shape[1] != 8:
            raise ValueError(f"mesh vertices must be (n, 8) float32, got {vertices.shape}")
        if indices.size and int(indices.max()) >= len(vertices):
            raise ValueError(
                f"mesh index {int(indices.max())} out of range for {len(vertices)} vertices"
            )
        self.index_count = int(indices.size)
        self.vao, self.vbo, self.ebo = upload_mesh(vertices, indices)
        super().__init__(registry)

    def update_vertices(self, vertices: np.ndarray) -> None:
        """Replace the vertices with ``vertices`` ``(n, 8)`` of the same count (a mesh that
        moves: one ``glBufferSubData``)."""
        vertices = np.ascontiguousarray(vertices, dtype=np.float32)
        gl.glBindBuffer(GL.GL_ARRAY_BUFFER, self.vbo)
        gl.glBufferSubData(GL.GL_ARRAY_BUFFER, 0, vertices.nbytes, vertices)
        gl.glBindBuffer(GL.GL_ARRAY_BUFFER, 0)

    def draw(self) -> None:
        """One ``glDrawElements`` call for the whole mesh."""
        gl.glBindVertexArray(self.vao)
        gl.glDrawElements(GL.GL_TRIANGLES, self.index_count, GL.GL_UNSIGNED_INT, None)

    def _free(self) -> None:
        gl.glDeleteVertexArrays(1, [self.vao])
        gl.glDeleteBuffers(2, [self.vbo, self.ebo])


class Buffer(_Resource):
    """A GL buffer object whose contents are replaced as a whole (per-draw data, indirect
    draw commands): :meth:`upload` keeps the storage it has when the data fits."""

    def __init__(self, registry: ResourceRegistry) -> None:
        self.name = int(gl.glGenBuffers(1))
        self.capacity = 0
        self.size = 0
        super().__init__(registry)

    def upload(self, target: int, data: np.ndarray) -> None:
        """Bind to ``target`` and fill with ``data`` (any contiguous array)."""
        data = np.ascontiguousarray(data)
        gl.glBindBuffer(target, self.name)
        if data.nbytes > self.capacity:
            gl.glBufferData(target, data.nbytes, data, GL.GL_DYNAMIC_DRAW)
            self.capacity = data.nbytes
        elif data.nbytes:
            raw.glBufferSubData(target, 0, data.nbytes, data)
        self.size = data.nbytes

    def _free(self) -> None:
        gl.glDeleteBuffers(1, [self.name])


class PackedMeshes(_Resource):
    """Many meshes in one VAO: their interleaved vertices (the :class:`MeshBuffer` layout)
    in one vertex buffer and their indices in one index buffer, so that a pass binds one
    vertex array and draws any of them by its range, as many instances as parts in a run
    (``glDrawElementsInstancedBaseVertex``), or all of a pass's in one
    ``glMultiDrawElementsIndirect``. A mesh is added once; adding
    one re-makes the buffers (meshes are few and added on first use)."""

    def __init__(self, registry: ResourceRegistry) -> None:
        self._vertices: list[np.ndarray] = []
        self._indices: list[np.ndarray] = []
        self.vertex_count = 0
        self.index_count = 0
        self.vao = self.vbo = self.ebo = 0
        self.carries_parts = False
        """Whether the vertex array reads per-part data (:meth:`carry_parts`)."""
        super().__init__(registry)

    def carry_parts(self) -> None:
        """Give the vertex array the attributes of a parts buffer: each part's two
        matrices, :data:`PART_BYTES` by column, at locations 3 to 6 and 7 to 10, one part
        an instance (divisor 1: core OpenGL 3.3), read from the buffer
        :meth:`bind_parts` points them at. Point them before every draw: an enabled
        array has no buffer until then."""
        self.carries_parts = True
        if self.vao:
            self._add_part_attributes()

    def _add_part_attributes(self) -> None:
        gl.glBindVertexArray(self.vao)
        for column in range(8):
            gl.glEnableVertexAttribArray(PART_LOCATION + column)
            gl.glVertexAttribDivisor(PART_LOCATION + column, 1)
        gl.glBindVertexArray(0)

    def bind_parts(self, buffer: int, first_part: int = 0) -> None:
        """Read the parts' data from ``buffer`` (the vertex array bound first), from part
        ``first_part`` on: instance ``i`` of a draw whose base instance is ``b`` reads
        part ``first_part + b + i``. Leaves ``buffer`` bound to ``GL_ARRAY_BUFFER``."""
        raw.glBindBuffer(GL.GL_ARRAY_BUFFER, buffer)
        self.point_parts(first_part)

    def point_parts(self, first_part: int) -> None:
        """Point the parts' attributes at part ``first_part`` of the buffer bound to
        ``GL_ARRAY_BUFFER`` (the parts buffer :meth:`bind_parts` bound): where base
        instances are missing (OpenGL 4.1), a draw's first instance is chosen this way."""
        start = PART_BYTES * int(first_part)
        for column in range(8):
            raw.glVertexAttribPointer(
                PART_LOCATION + column,
                4,
                GL.GL_FLOAT,
                GL.GL_FALSE,
                PART_BYTES,
                ctypes.c_void_p(start + 16 * column),
            )

    def add(self, vertices: np.ndarray, indices: np.ndarray) -> tuple[int, int, int]:
        """Add a mesh of ``vertices`` ``(n, 8)`` and flat ``indices``; returns its
        ``(first index, index count, base vertex)``."""
        vertices = np.ascontiguousarray(vertices, dtype=np.float32)
        indices = np.ascontiguousarray(indices, dtype=np.uint32).reshape(-1)
        if vertices.ndim != 2 or vertices.shape[1] != 8:
            raise ValueError(f"mesh vertices must be (n, 8) float32, got {vertices.shape}")
        placed = (self.index_count, int(indices.size), self.vertex_count)
        self._vertices.append(vertices)
        self._indices.append(indices)
        self.vertex_count += len(vertices)
        self.index_count += int(indices.size)
        self._free()
        self.vao, self.vbo, self.ebo = upload_mesh(
            np.concatenate(self._vertices), np.concatenate(self._indices)
        )
        if self.carries_parts:
            self._add_part_attributes()
        return placed

    def bind(self) -> None:
        gl.glBindVertexArray(self.vao)

    def draw_instanced(
        self, first_index: int, count: int, base_vertex: int, instances: int
    ) -> None:
        """``instances`` instances of one mesh's triangles (bound first, its parts
        attributes pointed at the first instance's part: :meth:`point_parts`)."""
        raw.glDrawElementsInstancedBaseVertex(
            GL.GL_TRIANGLES,
            count,
            GL.GL_UNSIGNED_INT,
            ctypes.c_void_p(4 * first_index),
            instances,
            base_vertex,
        )

    def multi_draw(self, first_command: int, count: int) -> None:
        """``count`` draws from the bound ``GL_DRAW_INDIRECT_BUFFER``'s commands
        (``(count, instances, first index, base vertex, base instance)`` uint32 each),
        starting at command ``first_command`` (bound first)."""
        gl.glMultiDrawElementsIndirect(
            GL.GL_TRIANGLES,
            GL.GL_UNSIGNED_INT,
            GL.GLvoidp(INDIRECT_COMMAND_BYTES * first_command),
            count,
            INDIRECT_COMMAND_BYTES,
        )

    def _free(self) -> None:
        if self.vao:
            gl.glDeleteVertexArrays(1, [self.vao])
            gl.glDeleteBuffers(2, [self.vbo, self.ebo])
        self.vao = self.vbo = self.ebo = 0


INDIRECT_COMMAND_BYTES = 20
"""Bytes of one ``DrawElementsIndirectCommand``: five uint32."""
PART_LOCATION = 3
"""The first of the eight attribute locations of a part's data
(:meth:`PackedMeshes.carry_parts`)."""
PART_BYTES = 128
"""Bytes of one part's data: two 4x4 float32 matrices."""


class TextureCube(_Resource):
    """A cube-map RGB texture: six square faces in GL order +X, -X, +Y, -Y, +Z, -Z (face
    ``k`` is ``GL_TEXTURE_CUBE_MAP_POSITIVE_X + k``), clamped to the edge, GL_LINEAR.

    Face images cross this class as ``(size, size, 3)`` uint8 with row 0 at the top,
    that is at face coordinate ``t = 1`` (as :func:`mirrorlab.envmap.bake_cube_faces`
    makes them); the rows are flipped on upload and read-back, here only.
    Sample it with ``GL_TEXTURE_CUBE_MAP_SEAMLESS`` enabled (a context-wide switch
    the passes that sample cube maps turn on).
    """

    def __init__(
        self,
        registry: ResourceRegistry,
        size: int,
        faces: np.ndarray | None,
        mipmaps: bool,
        what: str = "a cube map's face",
    ) -> None:
        if size < 1:
            raise ValueError(f"cube-map size must be positive, got {size}")
        check_texture_size(size, size, what, cube=True)
        if faces is not None:
            faces = np.asarray(faces)
            if faces.shape != (6, size, size, 3) or faces.dtype != np.uint8:
                raise ValueError(
                    f"cube faces must be (6, {size}, {size}, 3) uint8, got "
                    f"{faces.shape} {faces.dtype}"
                )
        self.name = int(gl.glGenTextures(1))
        self.size = int(size)
        self.mipmaps = mipmaps
        gl.glBindTexture(GL.GL_TEXTURE_CUBE_MAP, self.name)
        gl.glPixelStorei(GL.GL_UNPACK_ALIGNMENT, 1)
        for face in range(6):
            data = None if faces is None else np.ascontiguousarray(faces[face, ::-1])
            gl.glTexImage2D(
                GL.GL_TEXTURE_CUBE_MAP_POSITIVE_X + face,
                0,
                GL.GL_RGB8,
                self.size,
                self.size,
                0,
                GL.GL_RGB,
                GL.GL_UNSIGNED_BYTE,
                data,
            )
        for wrap in (GL.GL_TEXTURE_WRAP_S, GL.GL_TEXTURE_WRAP_T, GL.GL_TEXTURE_WRAP_R):
            gl.glTexParameteri(GL.GL_TEXTURE_CUBE_MAP, wrap, GL.GL_CLAMP_TO_EDGE)
        gl.glTexParameteri(GL.GL_TEXTURE_CUBE_MAP, GL.GL_TEXTURE_MAG_FILTER, GL.GL_LINEAR)
        min_filter = GL.GL_LINEAR_MIPMAP_LINEAR if mipmaps else GL.GL_LINEAR
        gl.glTexParameteri(GL.GL_TEXTURE_CUBE_MAP, GL.GL_TEXTURE_MIN_FILTER, min_filter)
        if mipmaps:
            if faces is not None:
                gl.glGenerateMipmap(GL.GL_TEXTURE_CUBE_MAP)
        else:
            gl.glTexParameteri(GL.GL_TEXTURE_CUBE_MAP, GL.GL_TEXTURE_MAX_LEVEL, 0)
        super().__init__(registry)

    @classmethod
    def from_faces(
        cls,
        registry: ResourceRegistry,
        faces: np.ndarray,
        mipmaps: bool = True,
        what: str = "a cube map's face",
    ) -> TextureCube:
        """A (by default mipmapped) cube map from ``faces`` ``(6, n, n, 3)`` uint8; ``what``
        names a face in a GLLimitError."""
        faces = np.asarray(faces)
        if faces.ndim != 4:
            raise ValueError(f"cube faces must be (6, n, n, 3) uint8, got {faces.shape}")
        return cls(registry, faces.shape[1], faces, mipmaps=mipmaps, what=what)

    @classmethod
    def blank(
        cls,
        registry: ResourceRegistry,
        size: int,
        mipmaps: bool = False,
        what: str = "a cube map's face",
    ) -> TextureCube:
        """Six empty ``size`` x ``size`` faces for a live capture (or an :meth:`upload`).
        With ``mipmaps``, call :meth:`generate_mipmaps` after each capture."""
        return cls(registry, size, None, mipmaps=mipmaps, what=what)

    def bind(self, unit: int = 0) -> None:
        gl.glActiveTexture(GL.GL_TEXTURE0 + unit)
        gl.glBindTexture(GL.GL_TEXTURE_CUBE_MAP, self.name)

    def upload(self, faces: np.ndarray) -> None:
        """Fill level 0 of every face from ``faces`` ``(6, size, size, 3)`` uint8 (rows as
        :meth:`from_faces` takes them) and rebuild the mipmaps, if any."""
        faces = np.asarray(faces)
        if faces.shape != (6, self.size, self.size, 3) or faces.dtype != np.uint8:
            raise ValueError(
                f"cube faces must be (6, {self.size}, {self.size}, 3) uint8, got "
                f"{faces.shape} {faces.dtype}"
            )
        gl.glBindTexture(GL.GL_TEXTURE_CUBE_MAP, self.name)
        gl.glPixelStorei(GL.GL_UNPACK_ALIGNMENT, 1)
        for face in range(6):
            gl.glTexSubImage2D(
                GL.GL_TEXTURE_CUBE_MAP_POSITIVE_X + face,
                0,
                0,
                0,
                self.size,
                self.size,
                GL.GL_RGB,
                GL.GL_UNSIGNED_BYTE,
                np.ascontiguousarray(faces[face, ::-1]),
            )
        if self.mipmaps:
            gl.glGenerateMipmap(GL.GL_TEXTURE_CUBE_MAP)

    def copy_face_from_framebuffer(self, face: int, source: tuple[int, int]) -> None:
        """Copy the bound read framebuffer's lower-left ``size`` x ``size`` square into level 0
        of ``face`` (0..5): the lab's ``glCopyTexImage2D(GL_TEXTURE_CUBE_MAP_POSITIVE_X +
        face, ...)``, done as ``glCopyTexSubImage2D`` into the storage the face was given
        when made. Window row 0 (the bottom) becomes the face's ``t = 0``. ``source`` is the size of
        the framebuffer read, which must hold the square."""
        if not 0 <= face < 6:
            raise ValueError(f"cube face must be 0..5, got {face}")
        if self.size > min(source):
            raise ValueError(
                f"a {self.size}x{self.size} face reaches outside the "
                f"{source[0]}x{source[1]} framebuffer it reads"
            )
        gl.glBindTexture(GL.GL_TEXTURE_CUBE_MAP, self.name)
        gl.glCopyTexSubImage2D(
            GL.GL_TEXTURE_CUBE_MAP_POSITIVE_X + face, 0, 0, 0, 0, 0, self.size, self.size
        )

    def generate_mipmaps(self) -> None:
        """Rebuild the mipmap levels from level 0 (after a capture); needs ``mipmaps=True``."""
        if not self.mipmaps:
            raise ValueError("this cube map was made without mipmaps")
        gl.glBindTexture(GL.GL_TEXTURE_CUBE_MAP, self.name)
        gl.glGenerateMipmap(GL.GL_TEXTURE_CUBE_MAP)

    def read_face(self, face: int) -> np.ndarray:
        """Level 0 of ``face`` as ``(size, size, 3)`` uint8, row 0 at the top (``t = 1``)."""
        gl.glBindTexture(GL.GL_TEXTURE_CUBE_MAP, self.name)
        gl.glPixelStorei(GL.GL_PACK_ALIGNMENT, 1)
        data = gl.glGetTexImage(
            GL.GL_TEXTURE_CUBE_MAP_POSITIVE_X + face, 0, GL.GL_RGB, GL.GL_UNSIGNED_BYTE
        )
        pixels = np.frombuffer(data, dtype=np.uint8).reshape(self.size, self.size, 3)
        return pixels[::-1].copy()

    def _free(self) -> None:
        gl.glDeleteTextures([self.name])


class DepthTextureCube(_Resource):
    """A cube map of depths (``GL_DEPTH_COMPONENT24``): six square faces in GL order, each
    copied from a capture's depth buffer, sampled ``GL_NEAREST`` (a depth between two
    surfaces would be a surface that is not there), clamped, no mipmaps, no depth
    comparison: a lookup returns the stored depth in ``.r``."""

    def __init__(self, registry: ResourceRegistry, size: int) -> None:
        if size < 1:
            raise ValueError(f"cube-map size must be positive, got {size}")
        self.name = int(gl.glGenTextures(1))
        self.size = int(size)
        gl.glBindTexture(GL.GL_TEXTURE_CUBE_MAP, self.name)
        for face in range(6):
            gl.glTexImage2D(
                GL.GL_TEXTURE_CUBE_MAP_POSITIVE_X + face,
                0,
                GL.GL_DEPTH_COMPONENT24,
                self.size,
                self.size,
                0,
                GL.GL_DEPTH_COMPONENT,
                GL.GL_FLOAT,
                None,
            )
        for wrap in (GL.GL_TEXTURE_WRAP_S, GL.GL_TEXTURE_WRAP_T, GL.GL_TEXTURE_WRAP_R):
            gl.glTexParameteri(GL.GL_TEXTURE_CUBE_MAP, wrap, GL.GL_CLAMP_TO_EDGE)
        gl.glTexParameteri(GL.GL_TEXTURE_CUBE_MAP, GL.GL_TEXTURE_MAG_FILTER, GL.GL_NEAREST)
        gl.glTexParameteri(GL.GL_TEXTURE_CUBE_MAP, GL.GL_TEXTURE_MIN_FILTER, GL.GL_NEAREST)
        gl.glTexParameteri(GL.GL_TEXTURE_CUBE_MAP, GL.GL_TEXTURE_MAX_LEVEL, 0)
        gl.glTexParameteri(GL.GL_TEXTURE_CUBE_MAP, GL.GL_TEXTURE_COMPARE_MODE, GL.GL_NONE)
        super().__init__(registry)

    def bind(self, unit: int = 0) -> None:
        gl.glActiveTexture(GL.GL_TEXTURE0 + unit)
        gl.glBindTexture(GL.GL_TEXTURE_CUBE_MAP, self.name)

    def copy_face_from_framebuffer(self, face: int) -> None:
        """Copy the bound read framebuffer's lower-left ``size`` x ``size`` depths into
        ``face`` (0..5), as :meth:`TextureCube.copy_face_from_framebuffer` copies colour."""
        if not 0 <= face < 6:
            raise ValueError(f"cube face must be 0..5, got {face}")
        gl.glBindTexture(GL.GL_TEXTURE_CUBE_MAP, self.name)
        gl.glCopyTexSubImage2D(
            GL.GL_TEXTURE_CUBE_MAP_POSITIVE_X + face, 0, 0, 0, 0, 0, self.size, self.size
        )

    def read_face(self, face: int) -> np.ndarray:
        """``face``'s depths as ``(size, size)`` float32 in [0, 1], row 0 at the top
        (``t = 1``)."""
        gl.glBindTexture(GL.GL_TEXTURE_CUBE_MAP, self.name)
        gl.glPixelStorei(GL.GL_PACK_ALIGNMENT, 4)
        data = gl.glGetTexImage(
            GL.GL_TEXTURE_CUBE_MAP_POSITIVE_X + face, 0, GL.GL_DEPTH_COMPONENT, GL.GL_FLOAT
        )
        depths = np.frombuffer(data, dtype=np.float32).reshape(self.size, self.size)
        return depths[::-1].copy()

    def _free(self) -> None:
        gl.glDeleteTextures([self.name])


class FloatFramebuffer(Framebuffer):
    """An offscreen target with a 32-bit float RGBA colour buffer (and depth + stencil), for
    checks that must see NaN, Inf or values outside [0, 1] that an 8-bit buffer would hide.
    Same interface as :class:`Framebuffer`; :meth:`read` gives float32."""

    COLOR_FORMAT = GL.GL_RGBA32F

    def read(self) -> np.ndarray:
        """Colour as ``(height, width, 3)`` float32, unclamped, row 0 at the top."""
        return self.read_rgba()[..., :3].copy()

    def read_rgba(self) -> np.ndarray:
        """Colour and alpha as ``(height, width, 4)`` float32, unclamped, row 0 at the top."""
        self.bind()
        gl.glPixelStorei(GL.GL_PACK_ALIGNMENT, 4)
        data = gl.glReadPixels(0, 0, self.width, self.height, GL.GL_RGBA, GL.GL_FLOAT)
        pixels = np.frombuffer(data, dtype=np.float32).reshape(self.height, self.width, 4)
        return pixels[::-1].copy()


class FrameTextures(_Resource):
    """A copy of a target's own frame: its colour (``GL_RGBA8``, alpha kept, filtered
    ``GL_LINEAR`` for reads between pixels) and its depth (``GL_DEPTH_COMPONENT24``, the
    bits mirrorlab's targets keep it in, as a live cube map's depth copies are; read
    ``GL_NEAREST``: a depth between two surfaces would be a surface that is not there),
    each ``width`` x ``height``, clamped, no mipmaps, no depth comparison (a lookup of
    the depth returns it in ``.r``)."""

    def __init__(self, registry: ResourceRegistry, width: int, height: int) -> None:
        check_texture_size(width, height, "the view's frame copy")
        self.width, self.height = int(width), int(height)
        self.color, self.depth = (int(n) for n in np.atleast_1d(gl.glGenTextures(2)))
        formats = (
            (self.color, GL.GL_RGBA8, GL.GL_RGBA, GL.GL_UNSIGNED_BYTE),
            (self.depth, GL.GL_DEPTH_COMPONENT24, GL.GL_DEPTH_COMPONENT, GL.GL_FLOAT),
        )
        for name, internal, layout, kind in formats:
            gl.glBindTexture(GL.GL_TEXTURE_2D, name)
            gl.glTexImage2D(
                GL.GL_TEXTURE_2D, 0, internal, self.width, self.height, 0, layout, kind, None
            )
            smooth = GL.GL_LINEAR if name == self.color else GL.GL_NEAREST
            for parameter, value in (
                (GL.GL_TEXTURE_MIN_FILTER, smooth),
                (GL.GL_TEXTURE_MAG_FILTER, smooth),
                (GL.GL_TEXTURE_WRAP_S, GL.GL_CLAMP_TO_EDGE),
                (GL.GL_TEXTURE_WRAP_T, GL.GL_CLAMP_TO_EDGE),
                (GL.GL_TEXTURE_MAX_LEVEL, 0),
            ):
                gl.glTexParameteri(GL.GL_TEXTURE_2D, parameter, value)
        gl.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_COMPARE_MODE, GL.GL_NONE)
        super().__init__(registry)

    @property
    def size(self) -> tuple[int, int]:
        return self.width, self.height

    def copy(self, region: tuple[int, int, int, int] | None = None) -> None:
        """Copy the bound read framebuffer's colour and depth into both textures, all of
        them or the pixel rectangle ``region`` (x, y, width, height, clipped to them)."""
        x, y, w, h = (0, 0, self.width, self.height) if region is None else region
        x0, y0 = max(int(x), 0), max(int(y), 0)
        x1, y1 = min(int(x + w), self.width), min(int(y + h), self.height)
        if x1 <= x0 or y1 <= y0:
            return
        for name in (self.color, self.depth):
            gl.glBindTexture(GL.GL_TEXTURE_2D, name)
            gl.glCopyTexSubImage2D(GL.GL_TEXTURE_2D, 0, x0, y0, x0, y0, x1 - x0, y1 - y0)

    def bind(self, color_unit: int, depth_unit: int) -> None:
        """The colour on texture unit ``color_unit``, the depth on ``depth_unit``."""
        for unit, name in ((color_unit, self.color), (depth_unit, self.depth)):
            gl.glActiveTexture(GL.GL_TEXTURE0 + unit)
            gl.glBindTexture(GL.GL_TEXTURE_2D, name)

    def read_color(self) -> np.ndarray:
        """The colour copy as ``(height, width, 4)`` uint8, row 0 at the top."""
        gl.glBindTexture(GL.GL_TEXTURE_2D, self.color)
        gl.glPixelStorei(GL.GL_PACK_ALIGNMENT, 1)
        data = gl.glGetTexImage(GL.GL_TEXTURE_2D, 0, GL.GL_RGBA, GL.GL_UNSIGNED_BYTE)
        pixels = np.frombuffer(data, dtype=np.uint8).reshape(self.height, self.width, 4)
        return pixels[::-1].copy()

    def read_depth(self) -> np.ndarray:
        """The depth copy as ``(height, width)`` float32 window depths in [0, 1], row 0 at
        the top."""
        gl.glBindTexture(GL.GL_TEXTURE_2D, self.depth)
        gl.glPixelStorei(GL.GL_PACK_ALIGNMENT, 4)
        data = gl.glGetTexImage(GL.GL_TEXTURE_2D, 0, GL.GL_DEPTH_COMPONENT, GL.GL_FLOAT)
        depths = np.frombuffer(data, dtype=np.float32).reshape(self.height, self.width)
        return depths[::-1].copy()

    def _free(self) -> None:
        gl.glDeleteTextures([self.color, self.depth])


class AttachmentFramebuffer(_Resource):
    """A framebuffer that draws into textures of its own, one colour attachment per
    format of ``formats`` (``GL_RGBA8``, ``GL_RGBA32F``, ...), all ``width`` x ``height``,
    ``GL_NEAREST``, clamped, no depth buffer: fragment output ``k`` lands in
    :attr:`textures` ``[k]``."""

    def __init__(
        self, registry: ResourceRegistry, width: int, height: int, formats: tuple[int, ...]
    ) -> None:
        check_texture_size(width, height, "a pass's own target")
        self.width, self.height = int(width), int(height)
        self.formats = tuple(formats)
        self.textures = [int(n) for n in np.atleast_1d(gl.glGenTextures(len(formats)))]
        self.name = int(gl.glGenFramebuffers(1))
        gl.glBindFramebuffer(GL.GL_FRAMEBUFFER, self.name)
        for index, (name, internal) in enumerate(zip(self.textures, self.formats, strict=True)):
            float_format = internal in (GL.GL_RGBA32F, GL.GL_RGBA16F)
            gl.glBindTexture(GL.GL_TEXTURE_2D, name)
            gl.glTexImage2D(
                GL.GL_TEXTURE_2D,
                0,
                internal,
                self.width,
                self.height,
                0,
                GL.GL_RGBA,
                GL.GL_FLOAT if float_format else GL.GL_UNSIGNED_BYTE,
                None,
            )
            for parameter, value in (
                (GL.GL_TEXTURE_MIN_FILTER, GL.GL_NEAREST),
                (GL.GL_TEXTURE_MAG_FILTER, GL.GL_NEAREST),
                (GL.GL_TEXTURE_WRAP_S, GL.GL_CLAMP_TO_EDGE),
                (GL.GL_TEXTURE_WRAP_T, GL.GL_CLAMP_TO_EDGE),
                (GL.GL_TEXTURE_MAX_LEVEL, 0),
            ):
                gl.glTexParameteri(GL.GL_TEXTURE_2D, parameter, value)
            gl.glFramebufferTexture2D(
                GL.GL_FRAMEBUFFER, GL.GL_COLOR_ATTACHMENT0 + index, GL.GL_TEXTURE_2D, name, 0
            )
        self.buffers = np.array(
            [GL.GL_COLOR_ATTACHMENT0 + i for i in range(len(formats))], dtype=np.uint32
        )
        self.buffers.flags.writeable = False  # handed to GL by every recorded frame
        gl.glDrawBuffers(len(formats), self.buffers)
        status = gl.glCheckFramebufferStatus(GL.GL_FRAMEBUFFER)
        if status != GL.GL_FRAMEBUFFER_COMPLETE:
            gl.glDeleteFramebuffers(1, [self.name])
            gl.glDeleteTextures(self.textures)
            raise GLContextError(
                f"framebuffer {self.width}x{self.height} of {len(formats)} textures incomplete "
                f"(status {status:#x})"
            )
        super().__init__(registry)

    @property
    def size(self) -> tuple[int, int]:
        return self.width, self.height

    def bind(self) -> None:
        gl.glBindFramebuffer(GL.GL_FRAMEBUFFER, self.name)

    def bind_texture(self, index: int, unit: int) -> None:
        """Attachment ``index``'s texture on texture unit ``unit``."""
        gl.glActiveTexture(GL.GL_TEXTURE0 + unit)
        gl.glBindTexture(GL.GL_TEXTURE_2D, self.textures[index])

    def read_float(self, index: int) -> np.ndarray:
        """Attachment ``index`` as ``(height, width, 4)`` float32, row 0 at the top."""
        gl.glBindTexture(GL.GL_TEXTURE_2D, self.textures[index])
        gl.glPixelStorei(GL.GL_PACK_ALIGNMENT, 4)
        data = gl.glGetTexImage(GL.GL_TEXTURE_2D, 0, GL.GL_RGBA, GL.GL_FLOAT)
        pixels = np.frombuffer(data, dtype=np.float32).reshape(self.height, self.width, 4)
        return pixels[::-1].copy()

    def _free(self) -> None:
        gl.glDeleteFramebuffers(1, [self.name])
        gl.glDeleteTextures(self.textures)


class DepthPyramid(_Resource):
    """A pyramid of nearest depths over a ``width`` x ``height`` depth buffer: one
    ``GL_R32F`` texture whose level ``k`` (GL's sizes: ``max(1, size >> k)``) holds, for
    each texel, the least window depth of the level ``k - 1`` texels under it (the last
    texel of a row or column also takes the one left over where the level below has an
    odd count, so it covers the buffer to its end); one framebuffer a level to draw it.
    Read ``GL_NEAREST`` with ``texelFetch``."""

    def __init__(self, registry: ResourceRegistry, width: int, height: int) -> None:
        check_texture_size(width, height, "a depth pyramid")
        self.width, self.height = int(width), int(height)
        sizes = [(self.width, self.height)]
        while sizes[-1] != (1, 1):
            w, h = sizes[-1]
            sizes.append((max(1, w // 2), max(1, h // 2)))
        self.sizes = tuple(sizes)
        self.texture = int(gl.glGenTextures(1))
        gl.glBindTexture(GL.GL_TEXTURE_2D, self.texture)
        for level, (w, h) in enumerate(sizes):
            gl.glTexImage2D(
                GL.GL_TEXTURE_2D, level, GL.GL_R32F, w, h, 0, GL.GL_RED, GL.GL_FLOAT, None
            )
        for parameter, value in (
            (GL.GL_TEXTURE_MIN_FILTER, GL.GL_NEAREST_MIPMAP_NEAREST),
            (GL.GL_TEXTURE_MAG_FILTER, GL.GL_NEAREST),
            (GL.GL_TEXTURE_WRAP_S, GL.GL_CLAMP_TO_EDGE),
            (GL.GL_TEXTURE_WRAP_T, GL.GL_CLAMP_TO_EDGE),
            (GL.GL_TEXTURE_BASE_LEVEL, 0),
            (GL.GL_TEXTURE_MAX_LEVEL, len(sizes) - 1),
        ):
            gl.glTexParameteri(GL.GL_TEXTURE_2D, parameter, value)
        self.framebuffers = [int(n) for n in np.atleast_1d(gl.glGenFramebuffers(len(sizes)))]
        for level, name in enumerate(self.framebuffers):
            gl.glBindFramebuffer(GL.GL_FRAMEBUFFER, name)
            gl.glFramebufferTexture2D(
                GL.GL_FRAMEBUFFER, GL.GL_COLOR_ATTACHMENT0, GL.GL_TEXTURE_2D, self.texture, level
            )
            status = gl.glCheckFramebufferStatus(GL.GL_FRAMEBUFFER)
            if status != GL.GL_FRAMEBUFFER_COMPLETE:
                gl.glDeleteFramebuffers(len(self.framebuffers), self.framebuffers)
                gl.glDeleteTextures([self.texture])
                raise GLContextError(
                    f"depth pyramid level {level} {sizes[level]} incomplete (status {status:#x})"
                )
        super().__init__(registry)

    @property
    def levels(self) -> int:
        return len(self.sizes)

    def read_level(self, level: int) -> np.ndarray:
        """Level ``level`` as ``(h, w)`` float32, row 0 at the top."""
        width, height = self.sizes[level]
        gl.glBindTexture(GL.GL_TEXTURE_2D, self.texture)
        gl.glPixelStorei(GL.GL_PACK_ALIGNMENT, 4)
        data = gl.glGetTexImage(GL.GL_TEXTURE_2D, level, GL.GL_RED, GL.GL_FLOAT)
        values = np.frombuffer(data, dtype=np.float32).reshape(height, width)
        return values[::-1].copy()

    def _free(self) -> None:
        gl.glDeleteFramebuffers(len(self.framebuffers), self.framebuffers)
        gl.glDeleteTextures([self.texture])
