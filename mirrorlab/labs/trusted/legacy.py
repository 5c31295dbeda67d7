"""The labs' legacy OpenGL, carried out by the trusted side on a context without the
compatibility profile (macOS's 4.1 core context).

The labs' students write the fixed-function style: matrix modes and stacks, ``gluLookAt``,
``glBegin``/``glEnd``, texgen, texture environment. A compatibility context runs those
calls itself (Mesa's own pipeline is the oracle); a core context has none of them. When
:func:`start` finds no compatibility profile, :func:`gl` gives a :class:`FixedFunction`:
an object with PyOpenGL's names for the legacy calls the labs allow, which carries them
out (matrix stacks in numpy, GLU's matrices from its man pages, immediate-mode vertices
gathered into a buffer and drawn with :data:`FIXED_VERTEX`/:data:`FIXED_FRAGMENT`, a
shader that does what the fixed pipeline did: default ``GL_LIGHT0`` lighting, texgen by
the OpenGL specification's formulas, the texture environment of each unit), and hands
every other call to GL. On a compatibility context :func:`gl` is PyOpenGL's GL itself.

What the fixed pipeline's shader leaves out (the labs give no call that would change it):
lights and materials other than their defaults, fog other than its default, alpha test
other than ``GL_ALWAYS``, texture units above 7, lines wider than 1 pixel (a core context
draws them 1 pixel wide), ``glPolygonMode`` of one face only.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from mirrorlab.labs.trusted.calls import GL_SPECS, TYPE_RANGES, form_type, gl_error

GL_MODELVIEW, GL_PROJECTION, GL_TEXTURE = 0x1700, 0x1701, 0x1702
GL_STACK_OVERFLOW, GL_STACK_UNDERFLOW = 0x0503, 0x0504
GL_INVALID_ENUM, GL_INVALID_VALUE, GL_INVALID_OPERATION = 0x0500, 0x0501, 0x0502
GL_TEXTURE_2D, GL_TEXTURE_CUBE_MAP = 0x0DE1, 0x8513
GL_TEXTURE_GEN = (0x0C60, 0x0C61, 0x0C62, 0x0C63)  # S, T, R, Q
GL_S = 0x2000
GL_TEXTURE_GEN_MODE, GL_OBJECT_PLANE, GL_EYE_PLANE = 0x2500, 0x2501, 0x2502
GL_EYE_LINEAR, GL_OBJECT_LINEAR, GL_SPHERE_MAP = 0x2400, 0x2401, 0x2402
GL_NORMAL_MAP, GL_REFLECTION_MAP = 0x8511, 0x8512
GL_TEXTURE_ENV, GL_TEXTURE_ENV_MODE = 0x2300, 0x2200
GL_MODULATE, GL_DECAL, GL_BLEND, GL_REPLACE, GL_ADD = 0x2100, 0x2101, 0x0BE2, 0x1E01, 0x0104
GL_NORMALIZE, GL_RESCALE_NORMAL = 0x0BA1, 0x803A
GL_LIGHTING, GL_LIGHT0, GL_LIGHT1, GL_COLOR_MATERIAL = 0x0B50, 0x4000, 0x4001, 0x0B57
GL_ALPHA_TEST, GL_FOG, GL_POINT_SMOOTH = 0x0BC0, 0x0B60, 0x0B10
GL_FLAT, GL_SMOOTH = 0x1D00, 0x1D01
GL_TEXTURE0 = 0x84C0
GL_ACCUM_BUFFER_BIT = 0x0200
GL_GENERATE_MIPMAP = 0x8191
GL_CLAMP, GL_CLAMP_TO_BORDER = 0x2900, 0x812D
UNIT_CAPS = (GL_TEXTURE_2D, GL_TEXTURE_CUBE_MAP, *GL_TEXTURE_GEN)
"""Legacy switches that belong to the active texture unit."""
GLOBAL_CAPS = (
    GL_NORMALIZE,
    GL_RESCALE_NORMAL,
    GL_LIGHTING,
    GL_LIGHT0,
    GL_LIGHT1,
    GL_COLOR_MATERIAL,
    GL_ALPHA_TEST,
    GL_FOG,
    GL_POINT_SMOOTH,
)
STACK_DEPTHS = {GL_MODELVIEW: 32, GL_PROJECTION: 32, GL_TEXTURE: 10}
"""Mesa's own limits (GL_MAX_*_STACK_DEPTH), so overflow errors come where they did."""
UNITS = 8
"""Texture units the fixed pipeline has (GL_MAX_TEXTURE_UNITS)."""
ENV_MODES = {GL_MODULATE: 0, GL_REPLACE: 1, GL_DECAL: 2, GL_BLEND: 3, GL_ADD: 4}
GEN_MODES = {
    GL_EYE_LINEAR: 1,
    GL_OBJECT_LINEAR: 2,
    GL_SPHERE_MAP: 3,
    GL_NORMAL_MAP: 4,
    GL_REFLECTION_MAP: 5,
}
SPARE_UNIT = 8
"""Unit 8 + i takes the fixed shader's sampler of unit i that is not used (a program may
not point two kinds of sampler at one unit)."""

# attribute locations, as compat_glsl.ATTRIBUTES
POSITION, NORMAL, COLOR, TEXCOORD0 = 0, 1, 3, 4
FLOATS = 4 + 3 + 4 + 4 * UNITS
"""Floats per immediate-mode vertex: position, normal, colour, 8 texture coordinates."""

FIXED_VERTEX = """#version 330 core
// The fixed pipeline's vertex stage as the labs use it: transform, default GL_LIGHT0
// lighting, texgen (OpenGL 2.1 section 2.12.4), texture matrices.
layout(location = 0) in vec4 position;
layout(location = 1) in vec3 normal;
layout(location = 3) in vec4 color;
layout(location = 4) in vec4 texcoord[8];

uniform mat4 modelview;
uniform mat4 modelview_projection;
uniform mat3 normal_matrix;
uniform mat4 texture_matrix[8];
uniform ivec4 gen_mode[8];   // per unit (s, t, r, q): 0 off, 1 eye, 2 object, 3 sphere,
                             // 4 normal map, 5 reflection map
uniform vec4 object_plane[32];
uniform vec4 eye_plane[32];
uniform bool normalize_normals;
uniform bool lighting;
uniform bool light0;
uniform bool color_material;
uniform vec4 material_ambient;   // the material without GL_COLOR_MATERIAL: the defaults,
uniform vec4 material_diffuse;   // or the colour it last took while that was on
uniform int units;           // units with texturing on (the highest + 1)

smooth out vec4 smooth_color;
flat out vec4 flat_color;
out vec4 coord[8];
out float eye_depth;

vec4 generated(int unit, vec4 given, vec4 object, vec4 eye, vec3 n, vec3 r, vec2 sphere) {
    vec4 result = given;
    for (int c = 0; c < 4; ++c) {
        int mode = gen_mode[unit][c];
        float value = given[c];
        if (mode == 1) {
            value = dot(eye_plane[unit * 4 + c], eye);
        } else if (mode == 2) {
            value = dot(object_plane[unit * 4 + c], object);
        } else if (mode == 3) {
            value = c < 2 ? sphere[c] : value;
        } else if (mode == 4) {
            value = c < 3 ? n[c] : value;
        } else if (mode == 5) {
            value = c < 3 ? r[c] : value;
        }
        result[c] = value;
    }
    return result;
}

void main() {
    vec4 eye = modelview * position;
    vec3 n = normal_matrix * normal;
    if (normalize_normals) {
        n = normalize(n);
    }
    // finite where Mesa's texgen gives NaN (as mirrorlab.envmap.sphere_map): a vertex at
    // the eye has u = 0, so r = 0 and (0.5, 0.5); r = (0, 0, -1) gives the rim's (1, 0.5)
    float distance = length(eye.xyz);
    vec3 u = distance > 0.0 ? eye.xyz / distance : vec3(0.0);
    vec3 r = u - 2.0 * n * dot(n, u);
    float m = 2.0 * sqrt(r.x * r.x + r.y * r.y + (r.z + 1.0) * (r.z + 1.0));
    vec2 sphere = m > 0.0 ? vec2(r.x / m + 0.5, r.y / m + 0.5) : vec2(1.0, 0.5);
    vec4 c = clamp(color, 0.0, 1.0);
    if (lighting) {
        vec4 ambient = color_material ? c : material_ambient;
        vec4 diffuse = color_material ? c : material_diffuse;
        vec3 lit = 0.2 * ambient.rgb;
        if (light0) {
            lit += max(dot(n, vec3(0.0, 0.0, 1.0)), 0.0) * diffuse.rgb;
        }
        c = vec4(clamp(lit, 0.0, 1.0), diffuse.a);
    }
    smooth_color = c;
    flat_color = c;
    for (int unit = 0; unit < 8; ++unit) {
        coord[unit] = unit < units ? texture_matrix[unit] *
            generated(unit, texcoord[unit], position, eye, n, r, sphere) : vec4(0.0);
    }
    eye_depth = abs(eye.z / eye.w);
    gl_Position = modelview_projection * position;
}
"""

FIXED_FRAGMENT = """#version 330 core
// The fixed pipeline's fragment stage: each unit's texture (a cube map before a 2D one)
// combined with the colour so far by that unit's texture environment; default fog.
smooth in vec4 smooth_color;
flat in vec4 flat_color;
in vec4 coord[8];
in float eye_depth;

uniform sampler2D texture_2d[8];
uniform samplerCube texture_cube[8];
uniform ivec2 unit_mode[8];   // (0 off, 1 2D, 2 cube; environment: 0 modulate,
                              // 1 replace, 2 decal, 3 blend, 4 add)
uniform bool unit_alpha[8];   // whether the unit's texture has an alpha channel
uniform bvec2 unit_clamp[8];  // GL_CLAMP for s, t: coordinates clamped to [0, 1], then
                              // sampled with GL_CLAMP_TO_BORDER (GL_CLAMP's own way)
uniform int units;
uniform bool flat_shading;
uniform bool fog;

out vec4 frag_color;

vec4 environment(vec4 color, vec4 s, int env, bool alpha) {
    if (env == 0) {
        return vec4(color.rgb * s.rgb, alpha ? color.a * s.a : color.a);
    } else if (env == 1) {
        return vec4(s.rgb, alpha ? s.a : color.a);
    } else if (env == 2) {
        return vec4(alpha ? mix(color.rgb, s.rgb, s.a) : s.rgb, color.a);
    } else if (env == 3) {
        return vec4(color.rgb * (1.0 - s.rgb), alpha ? color.a * s.a : color.a);
    }
    return vec4(min(color.rgb + s.rgb, 1.0), alpha ? color.a * s.a : color.a);
}

void main() {
    vec4 color = flat_shading ? flat_color : smooth_color;
    vec4 s;
    vec2 st;
UNITS
    if (fog) {
        float f = clamp(exp(-eye_depth), 0.0, 1.0);
        color = vec4(f * color.rgb, color.a);
    }
    frag_color = color;
}
""".replace(
    "UNITS",
    "".join(
        f"""    if ({unit} < units && unit_mode[{unit}].x != 0) {{
        st = coord[{unit}].xy / coord[{unit}].w;
        st = vec2(unit_clamp[{unit}].x ? clamp(st.x, 0.0, 1.0) : st.x,
                  unit_clamp[{unit}].y ? clamp(st.y, 0.0, 1.0) : st.y);
        s = unit_mode[{unit}].x == 2 ? texture(texture_cube[{unit}], coord[{unit}].xyz)
                                     : texture(texture_2d[{unit}], st);
        color = environment(color, s, unit_mode[{unit}].y, unit_alpha[{unit}]);
    }}
"""
        for unit in range(8)
    ),
)
"""Sampler arrays take constant indices only: one block per unit."""


def _gl() -> Any:
    from mirrorlab.gl.opengl import GL

    return GL


_active: FixedFunction | None = None


def start() -> None:
    """Look at the current context once (a lab session's): without the compatibility
    profile, a fresh :class:`FixedFunction` carries out the legacy calls from now on."""
    global _active
    # like the session's meshes, the emulation's shader and buffers live as long as the
    # session's context: nothing to free here (the old ones may be another context's)
    _active = None if has_compatibility() else FixedFunction()


def has_compatibility() -> bool:
    """Whether the current context runs the fixed-function calls itself: a version below
    3.1, a 3.1 with ``GL_ARB_compatibility``, or a profile mask with the compatibility bit."""
    GL = _gl()
    text = GL.glGetString(GL.GL_VERSION) or b""
    parts = text.decode(errors="replace").split(" ")[0].split(".")
    version = (
        (int(parts[0]), int(parts[1]))
        if len(parts) > 1 and parts[0].isdigit() and parts[1].isdigit()
        else (0, 0)
    )
    if version < (3, 1):
        return True
    if version == (3, 1):
        count = int(GL.glGetIntegerv(GL.GL_NUM_EXTENSIONS))
        return any(
            GL.glGetStringi(GL.GL_EXTENSIONS, i) == b"GL_ARB_compatibility" for i in range(count)
        )
    mask = int(np.asarray(GL.glGetIntegerv(GL.GL_CONTEXT_PROFILE_MASK)).reshape(-1)[0])
    return bool(mask & GL.GL_CONTEXT_COMPATIBILITY_PROFILE_BIT)


def emulated() -> FixedFunction | None:
    """The emulation in use, or None when the context does the legacy calls itself."""
    return _active


def gl() -> Any:
    """What the legacy calls go to: the emulation on a core context, else PyOpenGL's GL."""
    return _active if _active is not None else _gl()


def current_matrices() -> tuple[np.ndarray, np.ndarray]:
    """The (projection, modelview) matrices now, ``(4, 4)`` float64 each, row-major: the
    emulated stacks' tops, or the context's own."""
    if _active is not None:
        return (
            _active.top(GL_PROJECTION).astype(np.float64),
            _active.top(GL_MODELVIEW).astype(np.float64),
        )
    GL = _gl()
    projection = np.asarray(GL.glGetDoublev(GL.GL_PROJECTION_MATRIX), dtype=np.float64)
    modelview = np.asarray(GL.glGetDoublev(GL.GL_MODELVIEW_MATRIX), dtype=np.float64)
    return projection.reshape(4, 4).T.copy(), modelview.reshape(4, 4).T.copy()


def tex_parameter(target: int, pname: int) -> int:
    """An integer parameter of the texture bound to ``target``, as the file set it (a core
    context holds GL_CLAMP as GL_CLAMP_TO_BORDER, and no GL_GENERATE_MIPMAP)."""
    kept = _active.tex_parameter(target, pname) if _active is not None else None
    if kept is not None:
        return int(kept)
    return int(np.asarray(_gl().glGetTexParameteriv(target, pname)).reshape(-1)[0])


def _inverse(matrix: np.ndarray) -> np.ndarray:
    try:
        return np.linalg.inv(matrix)
    except np.linalg.LinAlgError:
        return np.zeros_like(matrix)


def normal_matrix(modelview: np.ndarray) -> np.ndarray:
    """The inverse transpose of ``modelview``'s upper 3 x 3, ``(3, 3)``."""
    return _inverse(modelview[:3, :3]).T


def load_matrix_uniforms(program: int) -> None:
    """Set the ``ml_`` matrix uniforms (:mod:`.compat_glsl`) that ``program`` (in use)
    declares, from :func:`current_matrices` and the texture matrices."""
    GL = _gl()
    projection, modelview = current_matrices()
    combined = multiply(projection.astype(F), modelview.astype(F)).astype(np.float64)
    values = {
        "ml_ModelViewMatrix": modelview,
        "ml_ProjectionMatrix": projection,
        "ml_ModelViewProjectionMatrix": combined,
    }
    for name, matrix in list(values.items()):
        inverse = _inverse(matrix)
        values[name + "Inverse"] = inverse
        values[name + "Transpose"] = matrix.T
        values[name + "InverseTranspose"] = inverse.T
    for name, matrix in values.items():
        location = int(GL.glGetUniformLocation(program, name))
        if location >= 0:
            GL.glUniformMatrix4fv(location, 1, GL.GL_TRUE, matrix.astype(np.float32))
    location = int(GL.glGetUniformLocation(program, "ml_NormalMatrix"))
    if location >= 0:
        GL.glUniformMatrix3fv(location, 1, GL.GL_TRUE, normal_matrix(modelview).astype(np.float32))
    location = int(GL.glGetUniformLocation(program, "ml_TextureMatrix"))
    if location >= 0:
        textures = np.stack([texture_matrix(unit) for unit in range(UNITS)])
        GL.glUniformMatrix4fv(location, UNITS, GL.GL_TRUE, textures.astype(np.float32))


def texture_matrix(unit: int) -> np.ndarray:
    """The texture matrix of ``unit`` now, ``(4, 4)`` row-major."""
    if _active is not None:
        return _active.top(GL_TEXTURE, unit).astype(np.float64)
    GL = _gl()
    active = int(GL.glGetIntegerv(GL.GL_ACTIVE_TEXTURE))
    GL.glActiveTexture(GL_TEXTURE0 + unit)
    matrix = np.asarray(GL.glGetDoublev(GL.GL_TEXTURE_MATRIX), dtype=np.float64)
    GL.glActiveTexture(active)
    return matrix.reshape(4, 4).T.copy()


def current_texcoords(unit: int) -> np.ndarray:
    """The current texture coordinates (s, t, r, q) of ``unit`` now, ``(4,)``."""
    if _active is not None:
        return np.asarray(_active.texcoords[unit], dtype=np.float64).copy()
    GL = _gl()
    active = int(GL.glGetIntegerv(GL.GL_ACTIVE_TEXTURE))
    GL.glActiveTexture(GL_TEXTURE0 + unit)
    coords = np.asarray(GL.glGetFloatv(GL.GL_CURRENT_TEXTURE_COORDS), dtype=np.float64)
    GL.glActiveTexture(active)
    return coords.reshape(-1)[:4].copy()


# ---------------------------------------------------------------------- the matrices
# In float32, each entry computed and each product summed in the order Mesa's own matrix
# code does (src/mesa/math/m_matrix.c) and GLU's: a vertex exactly on a clip plane (lab
# 20's mirror quad, on its own capture's near plane) then lands where it lands there.
F = np.float32


def multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``a @ b`` of two float32 ``(4, 4)`` matrices, each entry summed left to right."""
    a, b = a.astype(F), b.astype(F)
    return (
        ((a[:, 0:1] * b[0:1, :] + a[:, 1:2] * b[1:2, :]) + a[:, 2:3] * b[2:3, :])
        + a[:, 3:4] * b[3:4, :]
    ).astype(F)


def translation(x: float, y: float, z: float) -> np.ndarray:
    m = np.eye(4, dtype=F)
    m[:3, 3] = (F(x), F(y), F(z))
    return m


def rotation(angle: float, ax: float, ay: float, az: float) -> np.ndarray | None:
    """glRotate's matrix: ``angle`` degrees about (x, y, z), normalised; None where Mesa
    leaves the matrix alone (an axis shorter than 1e-4)."""
    x, y, z = F(ax), F(ay), F(az)
    radians = float(F(float(F(angle)) * math.pi / 180.0))  # sinf of a float, as Mesa's
    s, c = F(math.sin(radians)), F(math.cos(radians))
    m = np.eye(4, dtype=F)
    if x == 0 and y == 0 and z != 0:
        m[0, 0] = m[1, 1] = c
        m[0, 1], m[1, 0] = (s, -s) if z < 0 else (-s, s)
        return m
    if x == 0 and z == 0 and y != 0:
        m[0, 0] = m[2, 2] = c
        m[0, 2], m[2, 0] = (-s, s) if y < 0 else (s, -s)
        return m
    if y == 0 and z == 0 and x != 0:
        m[1, 1] = m[2, 2] = c
        m[1, 2], m[2, 1] = (s, -s) if x < 0 else (-s, s)
        return m
    magnitude = F(math.sqrt(float(x * x + y * y + z * z)))
    if magnitude <= F(1.0e-4):
        return None
    x, y, z = x / magnitude, y / magnitude, z / magnitude
    one_c = F(1) - c
    xs, ys, zs = x * s, y * s, z * s
    m[:3, :3] = [
        [one_c * (x * x) + c, one_c * (x * y) - zs, one_c * (z * x) + ys],
        [one_c * (x * y) + zs, one_c * (y * y) + c, one_c * (y * z) - xs],
        [one_c * (z * x) - ys, one_c * (y * z) + xs, one_c * (z * z) + c],
    ]
    return m


def ortho(
    left: float, right: float, bottom: float, top: float, near: float, far: float
) -> np.ndarray | None:
    """glOrtho's matrix (None where GL gives GL_INVALID_VALUE)."""
    if left == right or bottom == top or near == far:
        return None
    lo, r, b, t, n, f = (F(v) for v in (left, right, bottom, top, near, far))
    m = np.eye(4, dtype=F)
    m[0, 0], m[0, 3] = F(2) / (r - lo), -(r + lo) / (r - lo)
    m[1, 1], m[1, 3] = F(2) / (t - b), -(t + b) / (t - b)
    m[2, 2], m[2, 3] = F(-2) / (f - n), -(f + n) / (f - n)
    return m


def frustum(
    left: float, right: float, bottom: float, top: float, near: float, far: float
) -> np.ndarray | None:
    """glFrustum's matrix (None where GL gives GL_INVALID_VALUE)."""
    if near <= 0 or far <= 0 or left == right or bottom == top or near == far:
        return None
    lo, r, b, t, n, f = (F(v) for v in (left, right, bottom, top, near, far))
    m = np.zeros((4, 4), dtype=F)
    m[0, 0], m[1, 1] = (F(2) * n) / (r - lo), (F(2) * n) / (t - b)
    m[0, 2], m[1, 2] = (r + lo) / (r - lo), (t + b) / (t - b)
    m[2, 2], m[2, 3] = -(f + n) / (f - n), -(F(2) * f * n) / (f - n)
    m[3, 2] = -1.0
    return m


def perspective(fovy: float, aspect: float, near: float, far: float) -> np.ndarray | None:
    """gluPerspective's matrix, by its man page, in double as GLU makes it (None where
    GLU multiplies nothing)."""
    radians = fovy / 2 * math.pi / 180
    sine = math.sin(radians)
    depth = far - near
    if depth == 0 or sine == 0 or aspect == 0:
        return None
    cotangent = math.cos(radians) / sine
    m = np.zeros((4, 4))
    m[0, 0], m[1, 1] = cotangent / aspect, cotangent
    m[2, 2], m[2, 3] = -(far + near) / depth, -2 * near * far / depth
    m[3, 2] = -1.0
    return m.astype(F)


def look_at(
    eye: tuple[float, float, float],
    center: tuple[float, float, float],
    up: tuple[float, float, float],
) -> np.ndarray:
    """gluLookAt's rotation, by its man page, in float as GLU makes it (GLU leaves a zero
    vector unnormalised); GLU then multiplies by the translation by -eye, a product of its
    own (float products do not associate)."""

    def unit(v: np.ndarray) -> np.ndarray:
        length = F(math.sqrt(float(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])))
        return v / length if length != 0 else v

    def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return np.array(
            [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]],
            dtype=F,
        )

    forward = unit(np.array([center[i] - eye[i] for i in range(3)], dtype=F))
    side = unit(cross(forward, np.array(up, dtype=F)))
    upward = cross(side, forward)
    m = np.eye(4, dtype=F)
    m[0, :3], m[1, :3], m[2, :3] = side, upward, -forward
    return m


QUADS, QUAD_STRIP, POLYGON = 0x0007, 0x0008, 0x0009
GL_TRIANGLES, GL_TRIANGLE_STRIP = 0x0004, 0x0005
GL_LINE_LOOP = 0x0002


def core_primitive(mode: int, count: int, flat: bool = False) -> tuple[int, np.ndarray | None]:
    """A legacy primitive's (core mode, vertex order or None for as given), the winding
    kept: quads split into triangles along the diagonal Mesa splits them on (v0-v2), or,
    with ``flat`` shading, each triangle ending on the quad's last vertex, whose colour
    the fixed pipeline gives it; quad strips likewise; polygons into a fan, each triangle
    ending on the polygon's first vertex."""
    if mode == QUADS:
        order = []
        for q in range(count // 4):
            a, b, c, d = 4 * q, 4 * q + 1, 4 * q + 2, 4 * q + 3
            order += [a, b, d, b, c, d] if flat else [a, b, c, a, c, d]
        return GL_TRIANGLES, np.asarray(order, dtype=np.int64)
    if mode == QUAD_STRIP:
        order = []
        for q in range(max(count // 2 - 1, 0)):  # the quad (a, b, c, d), flat colour of c
            a, b, c, d = 2 * q, 2 * q + 1, 2 * q + 3, 2 * q + 2
            order += [a, b, c, d, a, c]
        return GL_TRIANGLES, np.asarray(order, dtype=np.int64)
    if mode == POLYGON:
        order = []
        for i in range(1, count - 1):
            order += [i, i + 1, 0]
        return GL_TRIANGLES, np.asarray(order, dtype=np.int64)
    return mode, None


class FixedFunction:
    """The fixed-function state of one lab session on a core context, and the legacy calls
    that change or use it (PyOpenGL's names and arguments); any other name is GL's own."""

    def __init__(self) -> None:
        GL = _gl()
        self.mode = GL_MODELVIEW
        self.stacks: dict[tuple[int, int], list[np.ndarray]] = {}
        self.caps: dict[tuple[int, int], bool] = {}
        self.gen_modes: dict[tuple[int, int], int] = {}
        self.planes: dict[tuple[int, int, int], np.ndarray] = {}
        self.env: dict[int, int] = {}
        self.shade = GL_SMOOTH
        self.color = np.array([1.0, 1.0, 1.0, 1.0])
        self.material = (np.array([0.2, 0.2, 0.2, 1.0]), np.array([0.8, 0.8, 0.8, 1.0]))
        """Ambient and diffuse; GL_COLOR_MATERIAL writes the current colour into both."""
        self.normal = np.array([0.0, 0.0, 1.0])
        self.texcoords = np.tile(np.array([0.0, 0.0, 0.0, 1.0]), (UNITS, 1))
        self.begun: int | None = None
        self.vertices: list[np.ndarray] = []
        self.tex_values: dict[tuple[int, int], Any] = {}
        """Texture parameters a core context takes otherwise (GL_CLAMP, GL_GENERATE_MIPMAP),
        by (texture, pname): what the file set."""
        self.line_width = 1.0
        self.program = _compile(FIXED_VERTEX, FIXED_FRAGMENT)
        self.locations: dict[str, int] = {}
        self.vao = int(GL.glGenVertexArrays(1))
        self.vbo = int(GL.glGenBuffers(1))

    def __getattr__(self, name: str) -> Any:
        return getattr(_gl(), name)

    # ---------------------------------------------------------------- state
    @staticmethod
    def unit() -> int:
        GL = _gl()
        return int(np.asarray(GL.glGetIntegerv(GL.GL_ACTIVE_TEXTURE)).reshape(-1)[0]) - GL_TEXTURE0

    def _stack(self, mode: int, unit: int | None = None) -> list[np.ndarray]:
        key = (mode, (self.unit() if unit is None else unit) if mode == GL_TEXTURE else 0)
        stack = self.stacks.get(key)
        if stack is None:
            stack = self.stacks[key] = [np.eye(4, dtype=F)]
        return stack

    def top(self, mode: int, unit: int | None = None) -> np.ndarray:
        return self._stack(mode, unit)[-1]

    def _outside(self, name: str) -> None:
        if self.begun is not None:
            raise gl_error(GL_INVALID_OPERATION, f"{name} between glBegin and glEnd")

    # ---------------------------------------------------------------- matrices
    def glMatrixMode(self, mode: int) -> None:
        self._outside("glMatrixMode")
        if mode not in STACK_DEPTHS:
            raise gl_error(GL_INVALID_ENUM)
        self.mode = int(mode)

    def _apply(self, matrix: np.ndarray | None, replace: bool = False) -> None:
        if matrix is None:
            raise gl_error(GL_INVALID_VALUE)
        stack = self._stack(self.mode)
        stack[-1] = np.array(matrix, dtype=F) if replace else multiply(stack[-1], matrix)

    def glLoadIdentity(self) -> None:
        self._apply(np.eye(4, dtype=F), replace=True)

    def glPushMatrix(self) -> None:
        stack = self._stack(self.mode)
        if len(stack) >= STACK_DEPTHS[self.mode]:
            raise gl_error(GL_STACK_OVERFLOW)
        stack.append(stack[-1].copy())

    def glPopMatrix(self) -> None:
        stack = self._stack(self.mode)
        if len(stack) <= 1:
            raise gl_error(GL_STACK_UNDERFLOW)
        stack.pop()

    @staticmethod
    def _matrix(values: Any, transpose: bool) -> np.ndarray:
        m = np.asarray(values, dtype=np.float64).reshape(4, 4).astype(F)
        return m if transpose else m.T  # GL's arrays are column-major

    def glLoadMatrixf(self, values: Any) -> None:
        self._apply(self._matrix(values, False), replace=True)

    glLoadMatrixd = glLoadMatrixf

    def glMultMatrixf(self, values: Any) -> None:
        self._apply(self._matrix(values, False))

    glMultMatrixd = glMultMatrixf

    def glLoadTransposeMatrixf(self, values: Any) -> None:
        self._apply(self._matrix(values, True), replace=True)

    glLoadTransposeMatrixd = glLoadTransposeMatrixf

    def glMultTransposeMatrixf(self, values: Any) -> None:
        self._apply(self._matrix(values, True))

    glMultTransposeMatrixd = glMultTransposeMatrixf

    def glOrtho(self, *args: float) -> None:
        self._apply(ortho(*args))

    def glFrustum(self, *args: float) -> None:
        self._apply(frustum(*args))

    def glTranslatef(self, x: float, y: float, z: float) -> None:
        self._apply(translation(x, y, z))

    glTranslated = glTranslatef

    def glScalef(self, x: float, y: float, z: float) -> None:
        self._apply(np.diag([x, y, z, 1.0]).astype(F))

    glScaled = glScalef

    def glRotatef(self, angle: float, x: float, y: float, z: float) -> None:
        matrix = rotation(angle, x, y, z)
        if matrix is not None:
            self._apply(matrix)

    glRotated = glRotatef

    def gluLookAt(
        self,
        ex: float,
        ey: float,
        ez: float,
        cx: float,
        cy: float,
        cz: float,
        ux: float,
        uy: float,
        uz: float,
    ) -> None:
        self._apply(look_at((ex, ey, ez), (cx, cy, cz), (ux, uy, uz)))
        self._apply(translation(-ex, -ey, -ez))

    def gluPerspective(self, fovy: float, aspect: float, near: float, far: float) -> None:
        matrix = perspective(fovy, aspect, near, far)
        if matrix is not None:  # GLU returns without a word
            self._apply(matrix)

    def gluOrtho2D(self, left: float, right: float, bottom: float, top: float) -> None:
        self._apply(ortho(left, right, bottom, top, -1.0, 1.0))

    # ---------------------------------------------------------------- switches
    def _cap_key(self, cap: int) -> tuple[int, int] | None:
        if cap in UNIT_CAPS:
            return cap, self.unit()
        if cap in GLOBAL_CAPS:
            return cap, -1
        return None

    def glEnable(self, cap: int) -> None:
        key = self._cap_key(cap)
        if key is None:
            _gl().glEnable(cap)
        else:
            self.caps[key] = True
        if cap == GL_COLOR_MATERIAL:
            self.set_color(self.color)

    def set_color(self, color: np.ndarray) -> None:
        """The current colour (and the material's, while GL_COLOR_MATERIAL is on)."""
        self.color = np.asarray(color, dtype=np.float64)
        if self.enabled(GL_COLOR_MATERIAL):
            self.material = (self.color.copy(), self.color.copy())

    def glDisable(self, cap: int) -> None:
        key = self._cap_key(cap)
        if key is None:
            _gl().glDisable(cap)
        else:
            self.caps[key] = False

    def glIsEnabled(self, cap: int) -> bool:
        key = self._cap_key(cap)
        if key is None:
            return bool(_gl().glIsEnabled(cap))
        return self.caps.get(key, False)

    def enabled(self, cap: int, unit: int = -1) -> bool:
        return self.caps.get((cap, unit), False)

    def glShadeModel(self, mode: int) -> None:
        self.shade = int(mode)

    def glHint(self, target: int, mode: int) -> None:
        GL = _gl()
        if target in (GL.GL_LINE_SMOOTH_HINT, GL.GL_POLYGON_SMOOTH_HINT):
            GL.glHint(target, mode)

    def glLineWidth(self, width: float) -> None:
        if width <= 0:
            raise gl_error(GL_INVALID_VALUE)
        self.line_width = float(width)

    def glPolygonMode(self, face: int, mode: int) -> None:
        _gl().glPolygonMode(_gl().GL_FRONT_AND_BACK, mode)

    def glClear(self, mask: int) -> None:
        _gl().glClear(mask & ~GL_ACCUM_BUFFER_BIT)

    # ---------------------------------------------------------------- texturing
    def glTexEnvi(self, target: int, pname: int, mode: int) -> None:
        if target != GL_TEXTURE_ENV or pname != GL_TEXTURE_ENV_MODE:
            raise gl_error(GL_INVALID_ENUM)
        if mode not in ENV_MODES:
            raise gl_error(GL_INVALID_ENUM)
        self.env[self.unit()] = int(mode)

    glTexEnvf = glTexEnvi

    def glGetTexEnviv(self, target: int, pname: int) -> np.ndarray:
        if target != GL_TEXTURE_ENV or pname != GL_TEXTURE_ENV_MODE:
            raise gl_error(GL_INVALID_ENUM)
        return np.array([self.env.get(self.unit(), GL_MODULATE)], dtype=np.int32)

    def glTexGeni(self, coord: int, pname: int, mode: int) -> None:
        index = coord - GL_S
        if not 0 <= index < 4 or pname != GL_TEXTURE_GEN_MODE or mode not in GEN_MODES:
            raise gl_error(GL_INVALID_ENUM)
        if (mode == GL_SPHERE_MAP and index > 1) or (
            mode in (GL_NORMAL_MAP, GL_REFLECTION_MAP) and index > 2
        ):
            raise gl_error(GL_INVALID_ENUM)
        self.gen_modes[(self.unit(), index)] = int(mode)

    glTexGenf = glTexGeni

    def glTexGenfv(self, coord: int, pname: int, values: Any) -> None:
        index = coord - GL_S
        if not 0 <= index < 4 or pname not in (GL_OBJECT_PLANE, GL_EYE_PLANE):
            raise gl_error(GL_INVALID_ENUM)
        plane = np.asarray(values, dtype=np.float64).reshape(4)
        if pname == GL_EYE_PLANE:  # kept in eye space: p times the inverse modelview
            plane = plane @ _inverse(self.top(GL_MODELVIEW).astype(np.float64))
        self.planes[(self.unit(), index, pname)] = plane

    def glGetTexGeniv(self, coord: int, pname: int) -> np.ndarray:
        index = coord - GL_S
        if not 0 <= index < 4 or pname != GL_TEXTURE_GEN_MODE:
            raise gl_error(GL_INVALID_ENUM)
        return np.array([self.gen_modes.get((self.unit(), index), GL_EYE_LINEAR)], dtype=np.int32)

    def plane(self, unit: int, index: int, pname: int) -> np.ndarray:
        found = self.planes.get((unit, index, pname))
        if found is not None:
            return found
        default = np.zeros(4)
        if index < 2:
            default[index] = 1.0
        return default

    def _bound(self, target: int) -> int:
        GL = _gl()
        binding = (
            GL.GL_TEXTURE_BINDING_2D if target == GL_TEXTURE_2D else GL.GL_TEXTURE_BINDING_CUBE_MAP
        )
        return int(np.asarray(GL.glGetIntegerv(binding)).reshape(-1)[0])

    def glTexParameteri(self, target: int, pname: int, value: Any) -> None:
        GL = _gl()
        texture = self._bound(target)
        if pname == GL_GENERATE_MIPMAP:
            self.tex_values[(texture, pname)] = value
            return
        if value == GL_CLAMP:
            self.tex_values[(texture, pname)] = value
            value = GL_CLAMP_TO_BORDER
        else:
            self.tex_values.pop((texture, pname), None)
        GL.glTexParameteri(target, pname, int(value))

    def glTexParameterf(self, target: int, pname: int, value: Any) -> None:
        if pname == GL_GENERATE_MIPMAP or value == GL_CLAMP:
            self.glTexParameteri(target, pname, int(value))
        else:
            _gl().glTexParameterf(target, pname, value)

    def glTexImage2D(
        self,
        target: int,
        level: int,
        internalformat: int,
        width: int,
        height: int,
        border: int,
        fmt: int,
        kind: int,
        pixels: Any,
    ) -> None:
        from OpenGL.raw.GL.VERSION import GL_1_0 as RAW

        internal, swizzle = CORE_FORMATS.get(internalformat, (internalformat, None))
        RAW.glTexImage2D(
            target,
            level,
            internal,
            width,
            height,
            border,
            PIXEL_FORMATS.get(fmt, fmt),
            kind,
            pixels,
        )
        self._swizzle(target, swizzle)

    def glCopyTexImage2D(
        self,
        target: int,
        level: int,
        internalformat: int,
        x: int,
        y: int,
        width: int,
        height: int,
        border: int,
    ) -> None:
        if internalformat in (1, 2, 3, 4):  # a copy takes no number of components (Mesa's)
            raise gl_error(GL_INVALID_ENUM)
        internal, swizzle = CORE_FORMATS.get(internalformat, (internalformat, None))
        _gl().glCopyTexImage2D(target, level, internal, x, y, width, height, border)
        self._swizzle(target, swizzle)

    @staticmethod
    def _swizzle(target: int, swizzle: tuple[int, int, int, int] | None) -> None:
        GL = _gl()
        bind = GL_TEXTURE_CUBE_MAP if target != GL_TEXTURE_2D else GL_TEXTURE_2D
        values = swizzle or (GL.GL_RED, GL.GL_GREEN, GL.GL_BLUE, GL.GL_ALPHA)
        GL.glTexParameteriv(bind, GL.GL_TEXTURE_SWIZZLE_RGBA, np.asarray(values, np.int32))

    def tex_parameter(self, target: int, pname: int) -> Any:
        """What the file set for a parameter a core context takes otherwise, or None."""
        return self.tex_values.get((self._bound(target), pname))

    def regenerate_mipmaps(self, target: int) -> None:
        """GL_GENERATE_MIPMAP's work after a write to level 0 of the bound texture."""
        if self.tex_values.get((self._bound(target), GL_GENERATE_MIPMAP)):
            _gl().glGenerateMipmap(target)

    # ---------------------------------------------------------------- queries
    def answers(self, pname: int) -> bool:
        GL = _gl()
        return (
            pname
            in (
                GL.GL_MODELVIEW_MATRIX,
                GL.GL_PROJECTION_MATRIX,
                GL.GL_TEXTURE_MATRIX,
                GL.GL_MATRIX_MODE,
                GL.GL_CURRENT_COLOR,
                GL.GL_CURRENT_TEXTURE_COORDS,
                GL.GL_MODELVIEW_STACK_DEPTH,
                GL.GL_PROJECTION_STACK_DEPTH,
                GL.GL_SHADE_MODEL,
                GL.GL_MAX_TEXTURE_UNITS,
                GL.GL_LINE_WIDTH,
            )
            or pname in UNIT_CAPS
            or pname in GLOBAL_CAPS
        )

    def get(self, pname: int) -> np.ndarray:
        """The value of a legacy query ``pname`` (:meth:`answers`), as floats."""
        GL = _gl()
        matrices = {
            GL.GL_MODELVIEW_MATRIX: GL_MODELVIEW,
            GL.GL_PROJECTION_MATRIX: GL_PROJECTION,
            GL.GL_TEXTURE_MATRIX: GL_TEXTURE,
        }
        if pname in matrices:
            return self.top(matrices[pname]).T.reshape(-1).copy()
        values: Any = {
            GL.GL_MATRIX_MODE: [self.mode],
            GL.GL_CURRENT_COLOR: self.color,
            GL.GL_CURRENT_TEXTURE_COORDS: self.texcoords[self.unit()]
            if self.unit() < UNITS
            else [0.0, 0.0, 0.0, 1.0],
            GL.GL_MODELVIEW_STACK_DEPTH: [len(self._stack(GL_MODELVIEW))],
            GL.GL_PROJECTION_STACK_DEPTH: [len(self._stack(GL_PROJECTION))],
            GL.GL_SHADE_MODEL: [self.shade],
            GL.GL_MAX_TEXTURE_UNITS: [UNITS],
            GL.GL_LINE_WIDTH: [self.line_width],
        }.get(pname)
        if values is None:
            values = [float(self.glIsEnabled(pname))]
        return np.asarray(values, dtype=np.float64)

    # ---------------------------------------------------------------- immediate mode
    def glBegin(self, mode: int) -> None:
        if self.begun is not None:
            raise gl_error(GL_INVALID_OPERATION, "glBegin inside glBegin")
        self.begun = int(mode)
        self.vertices = []

    def _vertex(self, values: Any) -> None:
        values = [float(v) for v in np.asarray(values, dtype=np.float64).reshape(-1)]
        position = (
            (values + [0.0, 0.0, 1.0][len(values) - 1 :])[:4] if len(values) < 4 else values[:4]
        )
        if self.begun is None:
            return  # outside glBegin/glEnd a vertex does nothing
        self.vertices.append(
            np.concatenate([position, self.normal, self.color, self.texcoords.reshape(-1)])
        )

    def texcoord(self, unit: int, values: Any) -> None:
        values = [float(v) for v in np.asarray(values, dtype=np.float64).reshape(-1)]
        if 0 <= unit < UNITS:
            self.texcoords[unit] = (values + [0.0, 0.0, 1.0][len(values) - 1 :])[:4]

    def glEnd(self) -> None:
        if self.begun is None:
            raise gl_error(GL_INVALID_OPERATION, "glEnd without glBegin")
        mode, self.begun = self.begun, None
        vertices, self.vertices = self.vertices, []
        if vertices:
            self.draw_vertices(mode, np.asarray(vertices, dtype=np.float32))

    # ---------------------------------------------------------------- drawing
    def draw_vertices(self, mode: int, data: np.ndarray) -> None:
        """Draw ``data`` ((n, FLOATS) float32: position, normal, colour, texture
        coordinates) as the legacy primitive ``mode``, with the program in use (a lab's
        program, its built-ins translated) or else the fixed pipeline's shader."""
        GL = _gl()
        mode, order = core_primitive(mode, len(data), self.shade == GL_FLAT)
        if order is not None:
            data = data[order] if order.size else data[:0]
        if not len(data):
            return
        previous_vao = int(np.asarray(GL.glGetIntegerv(GL.GL_VERTEX_ARRAY_BINDING)).reshape(-1)[0])
        GL.glBindVertexArray(self.vao)
        GL.glBindBuffer(GL.GL_ARRAY_BUFFER, self.vbo)
        GL.glBufferData(
            GL.GL_ARRAY_BUFFER, data.nbytes, np.ascontiguousarray(data), GL.GL_STREAM_DRAW
        )
        stride = FLOATS * 4
        layout = [(POSITION, 4, 0), (NORMAL, 3, 4), (COLOR, 4, 7)] + [
            (TEXCOORD0 + i, 4, 11 + 4 * i) for i in range(UNITS)
        ]
        for location, size, offset in layout:
            GL.glEnableVertexAttribArray(location)
            GL.glVertexAttribPointer(
                location, size, GL.GL_FLOAT, GL.GL_FALSE, stride, GL.GLvoidp(offset * 4)
            )
        self._with_program(lambda: GL.glDrawArrays(mode, 0, len(data)))
        GL.glBindBuffer(GL.GL_ARRAY_BUFFER, 0)
        GL.glBindVertexArray(previous_vao)

    def draw_elements(self, vao: int, count: int) -> None:
        """Draw a kit mesh (its vertex array: position at 0, normal at 1; indexed
        triangles) in the fixed pipeline, the current colour and texture coordinates for
        every vertex."""
        GL = _gl()
        previous_vao = int(np.asarray(GL.glGetIntegerv(GL.GL_VERTEX_ARRAY_BINDING)).reshape(-1)[0])
        GL.glBindVertexArray(vao)
        for location in [COLOR] + [TEXCOORD0 + i for i in range(UNITS)]:
            GL.glDisableVertexAttribArray(location)
        GL.glVertexAttrib4f(COLOR, *(float(v) for v in self.color))
        for i in range(UNITS):
            GL.glVertexAttrib4f(TEXCOORD0 + i, *(float(v) for v in self.texcoords[i]))
        self._with_program(
            lambda: GL.glDrawElements(GL.GL_TRIANGLES, count, GL.GL_UNSIGNED_INT, None)
        )
        GL.glBindVertexArray(previous_vao)

    def _with_program(self, draw: Any) -> None:
        GL = _gl()
        current = int(np.asarray(GL.glGetIntegerv(GL.GL_CURRENT_PROGRAM)).reshape(-1)[0])
        if current:
            load_matrix_uniforms(current)
            draw()
            return
        GL.glUseProgram(self.program)
        try:
            self._fixed_uniforms()
            draw()
        finally:
            GL.glUseProgram(0)

    def _uniform(self, name: str) -> int:
        location = self.locations.get(name)
        if location is None:
            location = self.locations[name] = int(_gl().glGetUniformLocation(self.program, name))
        return location

    def _fixed_uniforms(self) -> None:
        GL = _gl()
        u = self._uniform
        modelview = self.top(GL_MODELVIEW)
        GL.glUniformMatrix4fv(u("modelview"), 1, GL.GL_TRUE, modelview.astype(np.float32))
        GL.glUniformMatrix4fv(
            u("modelview_projection"), 1, GL.GL_TRUE, multiply(self.top(GL_PROJECTION), modelview)
        )
        GL.glUniformMatrix3fv(
            u("normal_matrix"),
            1,
            GL.GL_TRUE,
            normal_matrix(modelview.astype(np.float64)).astype(np.float32),
        )
        GL.glUniform1i(
            u("normalize_normals"),
            int(self.enabled(GL_NORMALIZE) or self.enabled(GL_RESCALE_NORMAL)),
        )
        GL.glUniform1i(u("lighting"), int(self.enabled(GL_LIGHTING)))
        GL.glUniform1i(u("light0"), int(self.enabled(GL_LIGHT0)))
        GL.glUniform1i(u("color_material"), int(self.enabled(GL_COLOR_MATERIAL)))
        GL.glUniform4f(u("material_ambient"), *(float(v) for v in self.material[0]))
        GL.glUniform4f(u("material_diffuse"), *(float(v) for v in self.material[1]))
        GL.glUniform1i(u("flat_shading"), int(self.shade == GL_FLAT))
        GL.glUniform1i(u("fog"), int(self.enabled(GL_FOG)))
        matrices = np.stack([self.top(GL_TEXTURE, unit) for unit in range(UNITS)])
        GL.glUniformMatrix4fv(u("texture_matrix"), UNITS, GL.GL_TRUE, matrices.astype(np.float32))
        modes = np.zeros((UNITS, 4), dtype=np.int32)
        unit_modes = np.zeros((UNITS, 2), dtype=np.int32)
        alpha = np.zeros(UNITS, dtype=np.int32)
        clamps = np.zeros((UNITS, 2), dtype=np.int32)
        objects = np.zeros((UNITS * 4, 4), dtype=np.float32)
        eyes = np.zeros((UNITS * 4, 4), dtype=np.float32)
        units = 0
        active = self.unit()
        for unit in range(UNITS):
            for index in range(4):
                if self.enabled(GL_TEXTURE_GEN[index], unit):
                    modes[unit, index] = GEN_MODES[self.gen_modes.get((unit, index), GL_EYE_LINEAR)]
                objects[unit * 4 + index] = self.plane(unit, index, GL_OBJECT_PLANE)
                eyes[unit * 4 + index] = self.plane(unit, index, GL_EYE_PLANE)
            cube = self.enabled(GL_TEXTURE_CUBE_MAP, unit)
            kind = 2 if cube else 1 if self.enabled(GL_TEXTURE_2D, unit) else 0
            if kind:
                GL.glActiveTexture(GL_TEXTURE0 + unit)
                # the fixed pipeline leaves a unit whose texture is incomplete untextured
                kind = kind if _complete(GL_TEXTURE_CUBE_MAP if cube else GL_TEXTURE_2D) else 0
            unit_modes[unit] = (kind, ENV_MODES[self.env.get(unit, GL_MODULATE)])
            if kind:
                units = unit + 1
                alpha[unit] = int(
                    _has_alpha(GL_TEXTURE_CUBE_MAP_POSITIVE_X if cube else GL_TEXTURE_2D)
                )
                if not cube:
                    clamps[unit] = [
                        tex_parameter(GL_TEXTURE_2D, wrap) == GL_CLAMP
                        for wrap in (GL.GL_TEXTURE_WRAP_S, GL.GL_TEXTURE_WRAP_T)
                    ]
            # a 2D and a cube sampler may not share a unit: the unused one takes a spare
            GL.glUniform1i(u(f"texture_2d[{unit}]"), SPARE_UNIT + unit if cube else unit)
            GL.glUniform1i(u(f"texture_cube[{unit}]"), unit if cube else SPARE_UNIT + unit)
        GL.glActiveTexture(GL_TEXTURE0 + active)
        GL.glUniform1i(u("units"), units)
        GL.glUniform4iv(u("gen_mode"), UNITS, modes)
        GL.glUniform2iv(u("unit_mode"), UNITS, unit_modes)
        GL.glUniform1iv(u("unit_alpha"), UNITS, alpha)
        GL.glUniform2iv(u("unit_clamp"), UNITS, clamps)
        GL.glUniform4fv(u("object_plane"), UNITS * 4, objects)
        GL.glUniform4fv(u("eye_plane"), UNITS * 4, eyes)


GL_TEXTURE_CUBE_MAP_POSITIVE_X = 0x8515
_R, _G, _ZERO, _ONE = 0x1903, 0x1904, 0, 1
CORE_FORMATS: dict[int, tuple[int, tuple[int, int, int, int] | None]] = {
    1: (0x8229, (_R, _R, _R, _ONE)),
    2: (0x822B, (_R, _R, _R, _G)),
    3: (0x1907, None),
    4: (0x1908, None),
    0x1909: (0x8229, (_R, _R, _R, _ONE)),
    0x8040: (0x8229, (_R, _R, _R, _ONE)),
    0x190A: (0x822B, (_R, _R, _R, _G)),
    0x1906: (0x8229, (_ZERO, _ZERO, _ZERO, _R)),
}
"""Legacy internal formats (1-4, GL_LUMINANCE, GL_LUMINANCE8, GL_LUMINANCE_ALPHA,
GL_ALPHA) as a core context's (GL_R8, GL_RG8, GL_RGB, GL_RGBA) and the swizzle that reads
them as the legacy ones were read."""
PIXEL_FORMATS = {0x1909: 0x1903, 0x190A: 0x8227, 0x1906: 0x1903}
"""Legacy pixel formats (GL_LUMINANCE, GL_LUMINANCE_ALPHA, GL_ALPHA) as GL_RED, GL_RG."""


def _normalised(name: str, values: Any) -> np.ndarray:
    """``values`` of call form ``name`` as floats; an integer colour's or normal's as GL
    converts them (the type's largest value is 1.0, the smallest no less than -1.0)."""
    array = np.asarray(values, dtype=np.float64).reshape(-1)
    kind = form_type(name)
    if kind in TYPE_RANGES and name.startswith(("glColor", "glNormal")):
        array = np.maximum(array / TYPE_RANGES[kind][1], -1.0)
    return array


def _immediate_call(name: str) -> Any:
    """The emulation of one form of glVertex, glTexCoord, glMultiTexCoord, glColor or
    glNormal (any size and type, scalar or ``v``)."""
    vector = name.endswith("v")

    def call(self: FixedFunction, *args: Any) -> None:
        if name.startswith("glMultiTexCoord"):
            unit, values = int(args[0]) - GL_TEXTURE0, args[1] if vector else args[1:]
        else:
            unit, values = 0, args[0] if vector else args
        array = _normalised(name, values)
        if name.startswith("glVertex"):
            self._vertex(array)
        elif name.startswith(("glTexCoord", "glMultiTexCoord")):
            self.texcoord(unit, array)
        elif name.startswith("glColor"):
            self.set_color(np.concatenate([array, [1.0] * (4 - array.size)])[:4])
        else:
            self.normal = array.reshape(3).copy()

    return call


for _name in GL_SPECS:
    if (
        _name.startswith(("glVertex", "glTexCoord", "glMultiTexCoord", "glColor", "glNormal"))
        and form_type(_name)
        and not hasattr(FixedFunction, _name)
    ):
        setattr(FixedFunction, _name, _immediate_call(_name))


MIPMAP_FILTERS = (0x2700, 0x2701, 0x2702, 0x2703)


def _complete(target: int) -> bool:
    """Whether the texture bound to ``target`` on the active unit can be sampled: a level 0
    (of each face), and every level down to 1 x 1 (or GL_TEXTURE_MAX_LEVEL) when its
    minifying filter wants mipmaps."""
    GL = _gl()
    faces = (
        [GL_TEXTURE_2D]
        if target == GL_TEXTURE_2D
        else [GL_TEXTURE_CUBE_MAP_POSITIVE_X + i for i in range(6)]
    )

    def size(face: int, level: int) -> tuple[int, int]:
        value = np.zeros(1, dtype=np.int32)
        GL.glGetTexLevelParameteriv(face, level, GL.GL_TEXTURE_WIDTH, value)
        width = int(value[0])
        GL.glGetTexLevelParameteriv(face, level, GL.GL_TEXTURE_HEIGHT, value)
        return width, int(value[0])

    width, height = size(faces[0], 0)
    if width == 0 or height == 0 or any(size(face, 0) != (width, height) for face in faces[1:]):
        return False
    if tex_parameter(target, GL.GL_TEXTURE_MIN_FILTER) not in MIPMAP_FILTERS:
        return True
    top = max(width, height).bit_length() - 1
    last = min(top, tex_parameter(target, GL.GL_TEXTURE_MAX_LEVEL))
    return all(size(face, last)[0] > 0 for face in faces)


def _has_alpha(target: int) -> bool:
    GL = _gl()
    size = np.zeros(1, dtype=np.int32)
    GL.glGetTexLevelParameteriv(target, 0, GL.GL_TEXTURE_ALPHA_SIZE, size)
    return bool(size[0])


def _compile(vertex: str, fragment: str) -> int:
    GL = _gl()
    program = GL.glCreateProgram()
    shaders = []
    for source, kind in ((vertex, GL.GL_VERTEX_SHADER), (fragment, GL.GL_FRAGMENT_SHADER)):
        shader = GL.glCreateShader(kind)
        GL.glShaderSource(shader, source)
        GL.glCompileShader(shader)
        if not GL.glGetShaderiv(shader, GL.GL_COMPILE_STATUS):
            log = GL.glGetShaderInfoLog(shader).decode(errors="replace").strip()
            raise RuntimeError(f"the fixed pipeline's shader did not compile: {log}")
        GL.glAttachShader(program, shader)
        shaders.append(shader)
    GL.glLinkProgram(program)
    for shader in shaders:
        GL.glDeleteShader(shader)
    if not GL.glGetProgramiv(program, GL.GL_LINK_STATUS):
        log = GL.glGetProgramInfoLog(program).decode(errors="replace").strip()
        raise RuntimeError(f"the fixed pipeline's shader did not link: {log}")
    return int(program)
