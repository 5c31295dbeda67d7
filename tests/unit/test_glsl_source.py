"""A student's GLSL as the checker compiles it (mirrorlab/labs/trusted/glsl_source.py):
preprocessed here, so the driver sees no directive and no macro; the checker's ``ml_``
names refused however they are spelled (pasted, split by a comment or a line
continuation, nested in a struct, an array, a block, a macro); nothing declared outside
the functions; every line where it was; bounded. And a fuzz of GLSL declarations: each
ends in text the rules hold for, or one line."""

from __future__ import annotations

import re

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from mirrorlab.labs.trusted.glsl_source import (
    GLOBAL_QUALIFIERS,
    MAX_TOKENS,
    GlslRefused,
    prepare,
    preprocess,
)

NAMES = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")


def tokens(text: str) -> list[str]:
    return [t.text for t in preprocess(text)]


@pytest.mark.parametrize(
    "text, line",
    [
        ("uniform float ml_ModelViewMatrix;\n", 1),
        ("struct S { samplerCube c; };\nuniform S ml_ModelViewMatrix[2];\n", 2),
        ("uniform ml_Block { vec4 v; };\n", 1),
        ("uniform Block { vec4 v; } ml_block;\n", 1),
        ("struct S { float ml_x; };\n", 1),
        ("vec3 ml_helper(vec3 v) { return v; }\n", 1),
        ("vec3 f(vec3 ml_u) { return ml_u; }\n", 1),
        ("float f() {\n    float ml_x = 1.0;\n    return ml_x;\n}\n", 2),
        ("#define ml_X 1.0\n", 1),
        ("#define CAT(a, b) a ## b\nfloat f() { return CAT(ml, _x); }\n", 2),
        ("#define CAT(a, b) a##b\n#define TWICE(a, b) CAT(a, b)\nfloat TWICE(ml, _y);\n", 3),
        ("#define P ml\n#define CAT(a, b) a ## b\n#define X(a) CAT(a, _z)\nfloat X(P);\n", 4),
        ("float ml_/**/ModelViewMatrix;\n", 1),
        ("float m\\\nl_ModelViewMatrix;\n", 1),
        ("#if 1\nfloat ml_x;\n#endif\n", 2),
        ("#define E\nfloat E ml_x E;\n", 2),
    ],
)
def test_reserved_names_are_refused_however_spelled(text, line):
    with pytest.raises(GlslRefused) as refused:
        prepare(text)
    assert refused.value.line == line
    assert "names beginning with ml_ are the checker's own" in refused.value.message
    assert "\n" not in str(refused.value)


@pytest.mark.parametrize(
    "text",
    [
        "// ml_ModelViewMatrix is the checker's\nfloat f() { return 1.0; }\n",
        "/* ml_x */ float f() { return 1.0; }\n",
        "#if 0\nfloat ml_x;\n#endif\nfloat f() { return 1.0; }\n",
        "#ifdef ml_x\nfloat g;\n#endif\n",
        "float xml_y() { return 1.0; }\nfloat ML_x;\n",
    ],
)
def test_reserved_names_that_never_reach_the_driver_are_allowed(text):
    assert "ml_" not in " ".join(t for t in tokens(text) if not t.startswith(("x", "M")))
    prepare(text)


@pytest.mark.parametrize(
    "text",
    [
        "uniform samplerCube cube;\n",
        "uniform float values[4];\n",
        "struct S { samplerCube c; };\nuniform S many[2];\n",
        "uniform Block { vec4 v; } block;\n",
        "buffer Data { float x[]; };\n",
        "layout(location = 1) out vec4 extra;\n",
        "out vec4 colour;\n",
        "in vec3 position;\n",
        "flat in int which;\n",
        "varying vec2 st;\n",
        "attribute vec4 position;\n",
        "#define U uniform\nU float hidden;\n",
        "#define Q(x) x\nQ(uniform) float hidden;\n",
        "#define CAT(a, b) a ## b\nCAT(uni, form) float hidden;\n",
    ],
)
def test_declarations_outside_the_functions_are_refused(text):
    with pytest.raises(GlslRefused, match="outside a function: the lab's functions take"):
        prepare(text)


def test_qualifiers_inside_a_function_and_constants_outside_are_allowed():
    text = (
        "const float HALF = 0.5;\nstruct Pair { float a; float b; };\n"
        "void split(in vec3 v, out float a, inout float b) { a = v.x; b += v.y; }\n"
        "vec2 f(vec3 r) { float a; float b = 0.0; split(r, a, b); return vec2(a, b) * HALF; }\n"
    )
    assert prepare(text).count("\n") == text.count("\n")


def test_macros_expand_as_the_c_preprocessor_does():
    assert tokens("#define TWO 2.0\nfloat x = TWO;\n") == ["float", "x", "=", "2.0", ";"]
    assert tokens("#define SQ(x) ((x) * (x))\nfloat y = SQ(a + 1.0);\n")[3:] == (
        "( ( a + 1.0 ) * ( a + 1.0 ) ) ;".split()
    )
    # a macro is not expanded again inside its own expansion
    assert tokens("#define foo foo + 1\nint x = foo;\n") == "int x = foo + 1 ;".split()
    # a function-like macro's name without ( is a name; with a space before ( in the
    # #define, it is an object-like macro
    assert tokens("#define F(x) x\nfloat F;\n") == ["float", "F", ";"]
    assert tokens("#define G (x)\nfloat y = G;\n") == "float y = ( x ) ;".split()
    assert tokens("#define CAT(a, b) a ## b\nfloat CAT(my, name);\n") == ["float", "myname", ";"]
    assert tokens("#define CAT(a, b) a ## b\nfloat CAT(, name);\n") == ["float", "name", ";"]
    assert tokens("#define A B\n#define B 3\nint x = A;\n#undef B\nint y = A;\n") == (
        "int x = 3 ; int y = B ;".split()
    )
    assert tokens("int line = __LINE__;\n\nint v = __VERSION__;\n") == (
        "int line = 1 ; int v = 330 ;".split()
    )


@pytest.mark.parametrize(
    "condition, taken",
    [
        ("1", True),
        ("0", False),
        ("(1 + 2) * 3 == 9 && !0", True),
        ("defined(TWO) && TWO > 1", True),
        ("defined NOPE || 0", False),
        ("UNKNOWN", False),
        ("__VERSION__ >= 330 && GL_core_profile", True),
        ("7 / 2 == 3 && -7 % 3 == -1 && (1 << 4) == 16 && 0x10 == 16 && 010 == 8", True),
        ("1 ? 0 : 1", False),
    ],
)
def test_conditions_are_evaluated_as_integers(condition, taken):
    text = f"#define TWO 2\n#if {condition}\nfloat yes;\n#elif 1\nfloat no;\n#endif\n"
    assert tokens(text) == (["float", "yes", ";"] if taken else ["float", "no", ";"])


@pytest.mark.parametrize(
    "text, words",
    [
        ("#error stop here\n", "#error stop here"),
        ("#if 1\nfloat x;\n", "never closed"),
        ("#else\n", "without #if"),
        ("#if 1\n#else\n#else\n#endif\n", "after #else"),
        ("#version 450\n", "#version"),
        ("#extension GL_ARB_bindless_texture : enable\n", "#extension"),
        ("#include <x>\n", "not a GLSL directive"),
        ("#define S(x) #x\n", "not GLSL"),
        ("#define H #\n", "not GLSL"),
        ("#define CAT(a, b) a ## b\nfloat CAT(+, ;);\n", "not one GLSL token"),
        ("#define F(a, b) a\nfloat F(1);\n", "takes 2 argument(s), given 1"),
        ("#define F(a) a\nfloat F(1;\n", "never closed"),
        ("#define GL_MINE 1\n", "GLSL's own"),
        ("float x; /* never closed\n", "never closed"),
        ('float x = "string";\n', "not a character GLSL allows"),
        ("float x = 1.0 @ 2.0;\n", "not a character GLSL allows"),
        ("#if 1 / 0\n#endif\n", "divides by zero"),
    ],
)
def test_what_the_preprocessor_refuses_is_one_line(text, words):
    with pytest.raises(GlslRefused) as refused:
        prepare(text)
    assert words in str(refused.value) and "\n" not in str(refused.value)


def test_every_line_stays_where_it_was():
    text = (
        "// a comment\n"  # 1
        "#define ADD(a, b) ((a) + (b))\n"  # 2
        "/* a comment\n"  # 3
        "   over lines */ float f() {\n"  # 4
        "    return ADD(1.0,\n"  # 5
        "               2.0);\n"  # 6
        "}\n"  # 7
        "float g() { return 1.0 + \\\n"  # 8
        "    2.0; }\n"  # 9
        "oops\n"  # 10
    )
    lines = prepare(text).split("\n")
    assert len(lines) == text.count("\n") + 1
    assert lines[3] == "float f ( ) {"
    assert lines[4] == "return ( ( 1.0 ) + ( 2.0 ) )" and lines[5] == ";"
    assert lines[7] == "float g ( ) { return 1.0 +" and lines[8] == "2.0 ; }"
    assert lines[9] == "oops"


@pytest.mark.parametrize(
    "text",
    [
        "#define A0 1.0\n"
        + "".join(f"#define A{i} (A{i - 1} + A{i - 1})\n" for i in range(1, 29))
        + "float bomb() { return A28; }\n",
        "#define F(x) x x x x x x x x\nfloat f() { return F(F(F(F(F(F(F(1))))))); }\n",
        "#define F(x) x\nfloat f() { return " + "F(" * 200 + "1" + ")" * 200 + "; }\n",
        "#if 1\n" * 70 + "#endif\n" * 70,
    ],
)
def test_a_bomb_is_stopped_at_the_limits(text):
    with pytest.raises(GlslRefused) as refused:
        prepare(text)
    assert "limits" in str(refused.value) or "nested" in str(refused.value)


def test_the_limit_is_far_above_an_honest_file():
    honest = "float f(float x) { return x * 2.0 + 1.0; }\n" * 200
    assert len(tokens(honest)) < MAX_TOKENS // 4
    prepare(honest)


# ------------------------------------------------------------------ the fuzz
PLAIN = st.sampled_from(["plain", "other_name", "xml_ok", "ML_fine", "N"])
HIDDEN = st.one_of(
    PLAIN,
    PLAIN,
    st.sampled_from(
        [
            "ml_X",
            "ml_ModelViewMatrix",
            "CAT(ml, _Y)",
            "CAT(m, l_Z)",
            "ml_/**/Q",
            "m\\\nl_W",
            "RESERVED",
        ]
    ),
)
"""A name for a declaration: mostly the student's own, else the checker's, spelled
plainly or hidden (pasted, split by a comment or a line continuation, behind a macro)."""
TYPES = st.sampled_from(
    ["float", "vec3", "mat4", "int", "samplerCube", "sampler2D", "S", "bool", "uvec2"]
)
QUALIFIERS = st.sampled_from(
    [
        "",
        "const",
        "uniform",
        "in",
        "out",
        "flat in",
        "buffer",
        "layout(location = 0) out",
        "layout(std140) uniform",
        "varying",
        "attribute",
        "shared",
        "QUAL",
        "precision highp",
        "invariant",
    ]
)


@st.composite
def declaration(draw) -> str:
    qualifier, kind, name = draw(QUALIFIERS), draw(TYPES), draw(HIDDEN)
    shape = draw(st.sampled_from(["", "[2]", "[]", "[N]"]))
    form = draw(st.sampled_from(["variable", "struct", "block", "function", "macro"]))
    if form == "struct":
        return f"struct {name} {{ {kind} member{shape}; }};"
    if form == "block":
        return f"{qualifier} Block {{ {kind} member; }} {name}{shape};"
    if form == "function":
        return f"{kind} {name}({qualifier} {kind} a) {{ {kind} local = a; return local; }}"
    if form == "macro":
        return f"#define {name} {kind}\n{qualifier} {name} value;"
    return f"{qualifier} {kind} {name}{shape};"


PRELUDE = (
    "#define CAT(a, b) a ## b\n#define RESERVED ml_hidden\n#define QUAL uniform\n#define N 2\n"
    "struct S { float x; };\n"
)


@settings(max_examples=300)
@example(["uniform S ml_ModelViewMatrix[2];"])
@example(["#define ml_X float\nml_X value;"])
@given(st.lists(declaration(), min_size=1, max_size=3))
def test_fuzzed_declarations_are_refused_in_one_line_or_hold_the_rules(declarations):
    text = PRELUDE + "\n".join(declarations) + "\n"
    try:
        out = prepare(text)
    except GlslRefused as refused:
        assert "\n" not in str(refused) and len(str(refused)) < 400
        assert 0 <= refused.line <= text.count("\n") + 1
        return
    # what reaches the driver: no ml_ name, no directive, nothing declared outside a
    # function, and the same text again when prepared again
    names = NAMES.findall(out)
    assert not any(n.startswith("ml_") for n in names), out
    assert "#" not in out
    depth = 0
    for token in re.findall(r"[A-Za-z_]\w*|[{}()]", out):
        depth += {"{": 1, "(": 1, "}": -1, ")": -1}.get(token, 0)
        assert depth > 0 or token not in GLOBAL_QUALIFIERS, out
    assert prepare(out) == out


@settings(max_examples=300)
@given(st.text(alphabet=st.sampled_from(list("#define ml_()ab,\\\n/*{}uniform 1+")), max_size=80))
def test_fuzzed_text_is_refused_in_one_line_or_prepared(text):
    try:
        out = prepare(text)
    except GlslRefused as refused:
        assert "\n" not in str(refused)
        return
    assert not any(n.startswith("ml_") for n in NAMES.findall(out))
    assert out.count("\n") == text.replace("\r\n", "\n").count("\n")
