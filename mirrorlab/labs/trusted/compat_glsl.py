"""GLSL that names the compatibility profile's built-ins, rewritten for a core context.

A lab's GLSL (a student's functions, or a kit shader written for immediate mode) may name
``gl_ModelViewMatrix``, ``gl_Vertex``, ``gl_MultiTexCoord0``, ``gl_FragColor``,
``texture2D`` and the like, which a core profile does not have. :func:`translate_compat_glsl`
replaces each such name, token by token (comments and a student's own identifiers are left
as they are), with a declared variable of mirrorlab's own (``ml_...``):

- the matrices become uniforms that the trusted side sets before each draw from the
  legacy matrix stacks (:func:`mirrorlab.labs.trusted.legacy.load_matrix_uniforms`);
- the vertex attributes become inputs at the locations :data:`ATTRIBUTES` gives (those the
  trusted side's immediate mode feeds);
- ``gl_FrontColor``/``gl_Color`` and ``gl_TexCoord[]`` become a varying pair,
  ``gl_FragColor`` an output; ``texture2D``/``textureCube``/... become ``texture`` ...;
  ``attribute``/``varying`` become ``in``/``out``.

The line numbers of the text stay those of the original (the declarations go on the lines
of the ``#version``/``#extension`` block, or before a ``#line`` that restores the count),
so a compiler's message still points at the student's line. Pure text in, text out.
"""

from __future__ import annotations

import re

ATTRIBUTES = {
    "gl_Vertex": (0, "vec4"),
    "gl_Normal": (1, "vec3"),
    "gl_Color": (3, "vec4"),
    **{f"gl_MultiTexCoord{i}": (4 + i, "vec4") for i in range(8)},
}
"""Vertex-stage built-in attributes: generic location and type."""
MATRICES = {
    "gl_ModelViewMatrix": "mat4",
    "gl_ProjectionMatrix": "mat4",
    "gl_ModelViewProjectionMatrix": "mat4",
    "gl_NormalMatrix": "mat3",
    **{
        f"gl_{base}{suffix}": "mat4"
        for base in ("ModelViewMatrix", "ProjectionMatrix", "ModelViewProjectionMatrix")
        for suffix in ("Inverse", "Transpose", "InverseTranspose")
    },
}
"""Built-in uniform matrices (``gl_TextureMatrix`` is an array of 8, handled apart)."""
FUNCTIONS = {
    "texture2D": "texture",
    "textureCube": "texture",
    "texture2DProj": "textureProj",
    "texture2DLod": "textureLod",
    "textureCubeLod": "textureLod",
    "texture2DProjLod": "textureProjLod",
    "texture1D": "texture",
    "texture3D": "texture",
    "shadow2D": "texture",
}
PREFIX = "ml_"
GL_FLOAT_MAT3, GL_FLOAT_MAT4 = 0x8B5B, 0x8B5C
TRANSLATED_STATE = {
    **{
        PREFIX + name[3:]: GL_FLOAT_MAT3 if kind == "mat3" else GL_FLOAT_MAT4
        for name, kind in MATRICES.items()
    },
    PREFIX + "TextureMatrix[0]": GL_FLOAT_MAT4,
}
"""The uniforms the built-in matrices become, as GL lists an active one (name and type):
GL's own state, which a student's function may read (as it may read
``gl_ModelViewMatrix`` on a compatibility context); a student's GLSL may not name them
itself (:mod:`.glsl_source`)."""
_TOKENS = re.compile(r"//[^\n]*|/\*.*?\*/|[A-Za-z_][A-Za-z0-9_]*|\n|.", re.DOTALL)
_VERSION = re.compile(r"#\s*version\s+(\d+)(\s+\w+)?")


def translate_compat_glsl(text: str, stage: str) -> str:
    """``text`` (GLSL of ``stage``, "vertex" or "fragment"; a whole shader with its
    ``#version`` line, or a part of one without) with the compatibility built-ins it names
    replaced by declared ``ml_`` variables (see the module's text), every line where it was.
    Text that names none of them comes back unchanged but for a ``compatibility``
    ``#version``, which becomes ``core``."""
    if stage not in ("vertex", "fragment"):
        raise ValueError(f"stage: expected 'vertex' or 'fragment', got {stage!r}")
    used: dict[str, str] = {}
    pieces: list[str] = []
    for token in _TOKENS.findall(text):
        replaced = _replace(token, stage)
        if replaced is not None:
            used[token] = replaced
            token = replaced
        pieces.append(token)
    body = "".join(pieces)
    lines = body.split("\n")
    head = 0  # the leading #version / #extension lines (blank lines among them)
    for index, line in enumerate(lines):
        stripped = line.strip()
        match = _VERSION.match(stripped)
        if match:
            number, profile = int(match.group(1)), (match.group(2) or "").strip()
            if number < 330 or profile in ("", "compatibility"):
                lines[index] = f"#version {max(number, 330)} core"
            head = index + 1
        elif stripped.startswith("#extension"):
            head = index + 1
        elif stripped:
            break
    declarations = _declarations(used, stage)
    if not declarations:
        return "\n".join(lines)
    return "\n".join([*lines[:head], declarations, f"#line {head + 1}", *lines[head:]])


def _replace(token: str, stage: str) -> str | None:
    if token in MATRICES or token == "gl_TextureMatrix":
        return PREFIX + token[3:]
    if token in FUNCTIONS:
        return FUNCTIONS[token]
    if stage == "vertex":
        if token in ATTRIBUTES:
            return PREFIX + token[3:]
        if token in ("gl_FrontColor", "gl_TexCoord"):
            return PREFIX + token[3:]
        if token == "attribute":
            return "in"
        if token == "varying":
            return "out"
    else:
        if token == "gl_Color":
            return PREFIX + "FrontColor"
        if token == "gl_TexCoord":
            return PREFIX + "TexCoord"
        if token == "gl_FragColor":
            return PREFIX + "FragColor"
        if token == "varying":
            return "in"
    return None


def _declarations(used: dict[str, str], stage: str) -> str:
    """One line declaring what the replaced built-ins need."""
    out = []
    for token, name in used.items():
        if token in MATRICES:
            out.append(f"uniform {MATRICES[token]} {name};")
        elif token == "gl_TextureMatrix":
            out.append(f"uniform mat4 {name}[8];")
        elif stage == "vertex" and token in ATTRIBUTES:
            location, kind = ATTRIBUTES[token]
            out.append(f"layout(location = {location}) in {kind} {name};")
        elif token == "gl_FrontColor":
            out.append(f"out vec4 {name};")
        elif token == "gl_Color" and stage == "fragment":
            out.append(f"in vec4 {name};")
        elif token == "gl_TexCoord":
            out.append(f"{'out' if stage == 'vertex' else 'in'} vec4 {name}[8];")
        elif token == "gl_FragColor":
            out.append(f"layout(location = 0) out vec4 {name};")
    return " ".join(dict.fromkeys(out))
