"""A student's GLSL as the checker compiles it: preprocessed here, checked token by token,
and handed to the driver with no directive left.

The driver's own preprocessor never sees a student's macro: :func:`prepare` splices line
continuations, drops comments, runs the directives (``#define`` object- and function-like
with ``##`` pasting, ``#undef``, ``#if``/``#ifdef``/``#ifndef``/``#elif``/``#else``/
``#endif`` with ``defined``, ``#error``; ``#pragma`` and ``#line`` are dropped), expands
the macros, and checks the tokens that come out, which are the only text the driver
compiles. So a name is judged as the compiler will see it, however it was spelled:
pasted by a macro, split by a comment or a line continuation, nested in a struct, an
array or a block.

The checks (each a :class:`GlslRefused` naming the student's line):

- **reserved names**: an identifier (or a macro) beginning with ``ml_`` is the checker's
  own (the uniforms that GL's built-in state becomes, the probe's inputs and outputs);
- **nothing outside the functions**: no ``uniform``, ``in``, ``out``, ``buffer``,
  ``attribute``, ``varying``, ``shared``, ``layout`` or interpolation qualifier at global
  scope (a block, an array of structs and a sampler among them): the lab's functions take
  what they need as arguments, so nothing a student declares can carry a value in or
  out, and nothing can be bound beside the checker's own;
- ``#version`` and ``#extension`` (the kit's version line is the student's too);
- what GLSL does not allow outside a comment (a stray ``#``, a quote, a character that is
  no GLSL token).

Every line keeps its number (what a directive or a comment took is left blank, a macro's
expansion stands on the line of its name), so a compiler's message still names the
student's line. Bounded: at most :data:`MAX_TOKENS` tokens out, :data:`MAX_STEPS`
expansion steps and :data:`MAX_DEPTH` nested macro arguments, or the file's shader "could
not be compiled within the limits". Pure text in, text out; no OpenGL.
"""

from __future__ import annotations

import re
from collections import deque
from collections.abc import Iterable
from dataclasses import dataclass, field

RESERVED_PREFIX = "ml_"
"""Names the trusted side keeps for itself in any GLSL it links a student's with."""
MAX_TOKENS = 20_000
MAX_STEPS = 200_000
MAX_DEPTH = 64
MAX_CONDITIONALS = 64
GLOBAL_QUALIFIERS = frozenset(
    {
        "uniform",
        "buffer",
        "in",
        "out",
        "inout",
        "attribute",
        "varying",
        "shared",
        "layout",
        "subroutine",
        "patch",
        "flat",
        "smooth",
        "noperspective",
        "centroid",
        "sample",
    }
)
"""Qualifiers that declare something outside the functions (an input, an output, a
uniform, a block, a binding): refused at global scope."""


class GlslRefused(ValueError):
    """The student's GLSL breaks a rule of the checker or of the preprocessor: ``line`` is
    the line in the student's string (1-based, 0 when none), ``message`` one line."""

    def __init__(self, line: int, message: str) -> None:
        self.line, self.message = line, message
        super().__init__(f"line {line}: {message}" if line else message)


@dataclass(frozen=True)
class Token:
    text: str
    line: int
    hidden: frozenset[str] = frozenset()
    """Macros whose expansion made this token (never expanded again inside them)."""

    @property
    def is_name(self) -> bool:
        return bool(_NAME.fullmatch(self.text))


@dataclass
class Macro:
    name: str
    body: list[Token]
    parameters: list[str] | None = None
    """None for an object-like macro."""


_NAME = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
_LEXEME = re.compile(
    r"(?P<space>[ \t\f\v\r]+)"
    r"|(?P<name>[A-Za-z_][A-Za-z0-9_]*)"
    r"|(?P<number>\.?[0-9](?:[eE][+-]|[0-9A-Za-z_.])*)"
    r"|(?P<op><<=|>>=|\+\+|--|<<|>>|<=|>=|==|!=|&&|\|\||\^\^|\+=|-=|\*=|/=|%=|&=|\^=|\|=|##"
    r"|[(){}\[\];,.+\-*/%<>=!&|^~?:#])"
)


# ------------------------------------------------------------------ lines and tokens
def _logical_lines(text: str) -> list[tuple[int, str, list[int]]]:
    """``text`` with its line continuations spliced, then its comments replaced by a space:
    its logical lines, each with the physical line it starts on and the physical line of
    each of its characters (a token stays on the line it was written on)."""
    text = text.replace("\r\n", "\n")
    chars: list[str] = []
    lines: list[int] = []
    line, i = 1, 0
    while i < len(text):
        if text[i] == "\\" and text.startswith("\n", i + 1):
            i, line = i + 2, line + 1
            continue
        chars.append(text[i])
        lines.append(line)
        line += text[i] == "\n"
        i += 1
    spliced = "".join(chars)
    out: list[tuple[int, str, list[int]]] = []
    current: list[str] = []
    where: list[int] = []
    start, j = 1, 0
    while j < len(spliced):
        if spliced.startswith("//", j):
            end = spliced.find("\n", j)
            j = len(spliced) if end < 0 else end
            continue
        if spliced.startswith("/*", j):
            end = spliced.find("*/", j + 2)
            if end < 0:
                raise GlslRefused(lines[j], "a /* comment is never closed")
            current.append(" ")
            where.append(lines[j])
            j = end + 2
            continue
        if spliced[j] == "\n":
            out.append((start, "".join(current), where))
            current, where, start = [], [], lines[j] + 1
        else:
            current.append(spliced[j])
            where.append(lines[j])
        j += 1
    out.append((start, "".join(current), where))
    return out


def _tokens(text: str, line: int, where: list[int] | None = None) -> list[Token]:
    """The tokens of ``text``, each on ``line`` or, given ``where`` (a line per
    character), on the line its first character was written on."""
    found: list[Token] = []
    at = 0
    while at < len(text):
        match = _LEXEME.match(text, at)
        if match is None:
            character = text[at]
            shown = repr(character) if character.isprintable() else f"U+{ord(character):04X}"
            raise GlslRefused(line, f"{shown} is not a character GLSL allows outside a comment")
        if match.lastgroup != "space":
            found.append(Token(match.group(), where[at] if where else line))
        at = match.end()
    return found


# ------------------------------------------------------------------ the preprocessor
@dataclass
class _State:
    macros: dict[str, Macro] = field(default_factory=dict)
    steps: int = 0
    produced: int = 0
    version: int = 330
    core: bool = True

    def step(self, line: int, count: int = 1) -> None:
        self.steps += count
        if self.steps > MAX_STEPS:
            raise GlslRefused(
                line,
                f"your shader could not be compiled within the limits: its macros take more "
                f"than {MAX_STEPS:,} steps to expand",
            )


def _limits(line: int) -> GlslRefused:
    return GlslRefused(
        line,
        f"your shader could not be compiled within the limits: its macros expand to more "
        f"than {MAX_TOKENS:,} tokens",
    )


def _predefined(name: str, token: Token, state: _State) -> Token | None:
    if name == "__LINE__":
        return Token(str(token.line), token.line)
    if name == "__FILE__":
        return Token("1", token.line)
    if name == "__VERSION__":
        return Token(str(state.version), token.line)
    if name == "GL_core_profile" and state.core:
        return Token("1", token.line)
    return None


def _is_defined(name: str, state: _State) -> bool:
    return (
        name in state.macros
        or name in ("__LINE__", "__FILE__", "__VERSION__")
        or (name == "GL_core_profile" and state.core)
    )


def _arguments(pending: deque[Token], name: Token) -> tuple[list[list[Token]], Token] | None:
    """The arguments of a function-like macro call whose ``(`` starts ``pending``, and its
    closing ``)``; consumed from ``pending``. None (nothing consumed) when no ``(``."""
    if not pending or pending[0].text != "(":
        return None
    opening = pending.popleft()
    arguments: list[list[Token]] = [[]]
    depth = 0
    while pending:
        token = pending.popleft()
        if token.text == "(":
            depth += 1
        elif token.text == ")":
            if depth == 0:
                return arguments, token
            depth -= 1
        elif token.text == "," and depth == 0:
            arguments.append([])
            continue
        arguments[-1].append(token)
    raise GlslRefused(opening.line, f"the call of macro {name.text} is never closed with )")


def _paste(left: Token, right: Token) -> Token:
    """``left ## right`` (an empty argument is a placemarker, the empty text)."""
    if not left.text or not right.text:
        return left if right.text == "" else Token(right.text, left.line, right.hidden)
    text = left.text + right.text
    tokens = _tokens(text, left.line)
    if len(tokens) != 1:
        raise GlslRefused(left.line, f"## makes {text!r}, which is not one GLSL token")
    return Token(tokens[0].text, left.line, left.hidden & right.hidden)


def _substitute(
    macro: Macro,
    arguments: list[list[Token]],
    hidden: frozenset[str],
    line: int,
    state: _State,
    depth: int,
) -> list[Token]:
    """The body of ``macro`` with its parameters replaced (an argument next to ``##`` as
    written, elsewhere fully expanded first), pasted, every token on ``line`` and hidden
    from the macros in ``hidden``."""
    parameters = macro.parameters or []
    expanded: dict[int, list[Token]] = {}
    out: list[Token] = []
    body = macro.body
    paste_next = False
    for index, token in enumerate(body):
        if token.text == "##":
            if index == 0 or index == len(body) - 1:
                raise GlslRefused(line, f"## at the edge of macro {macro.name}")
            paste_next = True
            continue
        glued = index + 1 < len(body) and body[index + 1].text == "##"
        if token.text in parameters:
            which = parameters.index(token.text)
            if paste_next or glued:
                piece = list(arguments[which]) or [Token("", line)]
            else:
                if which not in expanded:
                    expanded[which] = _expand(arguments[which], state, depth + 1)
                piece = expanded[which]
        else:
            piece = [token]
        piece = [Token(t.text, line, t.hidden) for t in piece]
        if paste_next:
            paste_next = False
            out[-1] = _paste(out[-1], piece[0])
            piece = piece[1:]
        out.extend(piece)
        state.step(line, len(piece) + 1)
    return [Token(t.text, line, t.hidden | hidden) for t in out if t.text]


def _expand(tokens: Iterable[Token], state: _State, depth: int = 0) -> list[Token]:
    """``tokens`` with every macro expanded (the C standard's rescanning, with each
    token's set of macros it may not expand again)."""
    if depth > MAX_DEPTH:
        first = next(iter(tokens), None)
        raise GlslRefused(
            first.line if first else 0,
            f"your shader could not be compiled within the limits: macro arguments nested "
            f"more than {MAX_DEPTH} deep",
        )
    pending = deque(tokens)
    out: list[Token] = []
    while pending:
        token = pending.popleft()
        state.step(token.line)
        name = token.text
        macro = state.macros.get(name) if token.is_name else None
        builtin = _predefined(name, token, state) if macro is None else None
        if builtin is not None:
            out.append(builtin)
            continue
        if macro is None or name in token.hidden:
            out.append(token)
            if len(out) > MAX_TOKENS:
                raise _limits(token.line)
            continue
        if macro.parameters is None:
            body = _substitute(macro, [], token.hidden | {name}, token.line, state, depth)
        else:
            found = _arguments(pending, token)
            if found is None:  # a function-like macro's name alone is just a name
                out.append(token)
                continue
            arguments, closing = found
            if arguments == [[]] and not macro.parameters:
                arguments = []
            if len(arguments) != len(macro.parameters):
                raise GlslRefused(
                    token.line,
                    f"macro {name} takes {len(macro.parameters)} argument(s), "
                    f"given {len(arguments)}",
                )
            hidden = (token.hidden & closing.hidden) | {name}
            body = _substitute(macro, arguments, hidden, token.line, state, depth)
        if len(pending) + len(body) > MAX_TOKENS:
            raise _limits(token.line)
        pending.extendleft(reversed(body))
    return out


def _define(rest: str, line: int, state: _State) -> None:
    """``#define`` with ``rest`` after the word: a function-like macro when ``(`` follows
    the name with no space between."""
    tokens = _tokens(rest, line)
    if not tokens or not tokens[0].is_name:
        raise GlslRefused(line, "#define needs a macro name")
    name = tokens[0].text
    if name.startswith("GL_") or name in ("__LINE__", "__FILE__", "__VERSION__", "defined"):
        raise GlslRefused(line, f"#define {name}: names beginning with GL_ are GLSL's own")
    if name.startswith(RESERVED_PREFIX):
        raise GlslRefused(line, _reserved(name))
    body = tokens[1:]
    parameters: list[str] | None = None
    if rest.lstrip()[len(name) :].startswith("("):
        end = next((i for i, t in enumerate(body) if t.text == ")"), -1)
        if end < 0:
            raise GlslRefused(line, f"#define {name}(: the parameter list is never closed")
        inside = body[1:end]
        parameters = [t.text for t in inside[::2]]
        well_formed = all(t.is_name for t in inside[::2]) and all(
            t.text == "," for t in inside[1::2]
        )
        if (inside and not well_formed) or (inside and inside[-1].text == ","):
            raise GlslRefused(line, f"#define {name}: its parameters must be names")
        if len(set(parameters)) != len(parameters):
            raise GlslRefused(line, f"#define {name}: a parameter named twice")
        body = body[end + 1 :]
    if any(t.text == "#" for t in body):
        raise GlslRefused(line, f"#define {name}: # (making a string) is not GLSL")
    if len(state.macros) >= 4096:
        raise _limits(line)
    state.macros[name] = Macro(name, body, parameters)


def _condition(tokens: list[Token], line: int, state: _State) -> bool:
    """The value of an ``#if``/``#elif`` expression: ``defined`` first, then the macros,
    then C's integer arithmetic (an unknown name is 0)."""
    resolved: list[Token] = []
    i = 0
    while i < len(tokens):
        token = tokens[i]
        if token.text == "defined":
            if i + 1 < len(tokens) and tokens[i + 1].text == "(":
                if i + 3 >= len(tokens) or tokens[i + 3].text != ")":
                    raise GlslRefused(line, "defined( needs a name and )")
                name, i = tokens[i + 2], i + 4
            elif i + 1 < len(tokens):
                name, i = tokens[i + 1], i + 2
            else:
                raise GlslRefused(line, "defined needs a name")
            resolved.append(Token("1" if _is_defined(name.text, state) else "0", line))
            continue
        resolved.append(token)
        i += 1
    expanded = [t if not t.is_name else Token("0", line) for t in _expand(resolved, state)]
    if not expanded:
        raise GlslRefused(line, "#if needs an expression")
    try:
        value, at = _Expression(expanded, line).parse(0, 0)
    except IndexError:
        raise GlslRefused(line, "#if's expression ends too soon") from None
    if at != len(expanded):
        raise GlslRefused(line, f"#if's expression: unexpected {expanded[at].text!r}")
    return value != 0


_BINARY = {
    "||": 1,
    "&&": 2,
    "|": 3,
    "^": 4,
    "&": 5,
    "==": 6,
    "!=": 6,
    "<": 7,
    ">": 7,
    "<=": 7,
    ">=": 7,
    "<<": 8,
    ">>": 8,
    "+": 9,
    "-": 9,
    "*": 10,
    "/": 10,
    "%": 10,
}
"""The binary operators of ``#if`` expressions and their precedence (C's)."""


class _Expression:
    """C's integer constant expressions, by precedence climbing."""

    def __init__(self, tokens: list[Token], line: int) -> None:
        self.tokens, self.line = tokens, line

    def unary(self, at: int) -> tuple[int, int]:
        text = self.tokens[at].text
        if text in ("+", "-", "!", "~"):
            value, at = self.unary(at + 1)
            return {"+": value, "-": -value, "!": int(not value), "~": ~value}[text], at
        if text == "(":
            value, at = self.parse(at + 1, 0)
            if at >= len(self.tokens) or self.tokens[at].text != ")":
                raise GlslRefused(self.line, "#if's expression: ( without )")
            return value, at + 1
        number = re.fullmatch(r"(0[xX][0-9a-fA-F]+|0[0-7]*|[1-9][0-9]*)[uU]?", text)
        if number is None:
            raise GlslRefused(self.line, f"#if's expression: {text!r} is not an integer")
        digits = number.group(1)
        base = 16 if digits[:2].lower() == "0x" else 8 if digits.startswith("0") else 10
        return int(digits, base), at + 1

    def parse(self, at: int, floor: int) -> tuple[int, int]:
        left, at = self.unary(at)
        while at < len(self.tokens):
            operator = self.tokens[at].text
            if operator == "?":
                middle, at = self.parse(at + 1, 0)
                if at >= len(self.tokens) or self.tokens[at].text != ":":
                    raise GlslRefused(self.line, "#if's expression: ? without :")
                right, at = self.parse(at + 1, 0)
                left = middle if left else right
                continue
            precedence = _BINARY.get(operator)
            if precedence is None or precedence <= floor:
                break
            right, at = self.parse(at + 1, precedence)
            left = self._apply(operator, left, right)
        return left, at

    def _apply(self, operator: str, left: int, right: int) -> int:
        if operator in ("/", "%") and right == 0:
            raise GlslRefused(self.line, "#if's expression divides by zero")
        if operator in ("<<", ">>") and not 0 <= right < 64:
            raise GlslRefused(self.line, "#if's expression shifts by more than 63")
        value = {
            "||": lambda: int(bool(left) or bool(right)),
            "&&": lambda: int(bool(left) and bool(right)),
            "|": lambda: left | right,
            "^": lambda: left ^ right,
            "&": lambda: left & right,
            "==": lambda: int(left == right),
            "!=": lambda: int(left != right),
            "<": lambda: int(left < right),
            ">": lambda: int(left > right),
            "<=": lambda: int(left <= right),
            ">=": lambda: int(left >= right),
            "<<": lambda: left << right,
            ">>": lambda: left >> right,
            "+": lambda: left + right,
            "-": lambda: left - right,
            "*": lambda: left * right,
            "/": lambda: int(left / right),
            "%": lambda: left - right * int(left / right),
        }[operator]()
        # 32-bit wrap-around, as the driver computes
        return (value + (1 << 31)) % (1 << 32) - (1 << 31)


def _reserved(name: str) -> str:
    return f"{name}: names beginning with {RESERVED_PREFIX} are the checker's own; rename it"


def preprocess(text: str, version: int = 330, core: bool = True) -> list[Token]:
    """The tokens the driver will compile from ``text`` (a student's GLSL, compiled under
    ``#version version``): directives run, macros expanded, each token on its line.
    GlslRefused for what the preprocessor refuses or at a limit."""
    state = _State(version=version, core=core)
    out: list[Token] = []
    chunk: list[Token] = []
    # each conditional: (this branch taken, some branch already taken, #else seen)
    conditionals: list[tuple[bool, bool, bool]] = []
    for line, logical, where in _logical_lines(text):
        stripped = logical.lstrip()
        active = all(taken for taken, _, _ in conditionals)
        if not stripped.startswith("#"):
            if active:
                chunk.extend(_tokens(logical, line, where))
            continue
        if chunk:
            out.extend(_expand(chunk, state))
            chunk = []
            if len(out) > MAX_TOKENS:
                raise _limits(line)
        body = stripped[1:].lstrip()
        word = _NAME.match(body)
        directive = word.group() if word else ""
        rest = body[len(directive) :]
        if directive in ("if", "ifdef", "ifndef"):
            if len(conditionals) >= MAX_CONDITIONALS:
                raise GlslRefused(line, f"#if nested more than {MAX_CONDITIONALS} deep")
            if not active:
                conditionals.append((False, True, False))
                continue
            tokens = _tokens(rest, line)
            if directive == "if":
                taken = _condition(tokens, line, state)
            else:
                if len(tokens) != 1 or not tokens[0].is_name:
                    raise GlslRefused(line, f"#{directive} needs one name")
                taken = _is_defined(tokens[0].text, state) == (directive == "ifdef")
            conditionals.append((taken, taken, False))
            continue
        if directive in ("elif", "else", "endif"):
            if not conditionals:
                raise GlslRefused(line, f"#{directive} without #if")
            taken, done, seen_else = conditionals.pop()
            if directive == "endif":
                continue
            if seen_else:
                raise GlslRefused(line, f"#{directive} after #else")
            outer = all(t for t, _, _ in conditionals)
            if directive == "else":
                conditionals.append((outer and not done, True, True))
            else:
                now = outer and not done and _condition(_tokens(rest, line), line, state)
                conditionals.append((now, done or now, False))
            continue
        if not active:
            continue
        if directive == "define":
            _define(rest, line, state)
        elif directive == "undef":
            tokens = _tokens(rest, line)
            if len(tokens) != 1 or not tokens[0].is_name:
                raise GlslRefused(line, "#undef needs one name")
            state.macros.pop(tokens[0].text, None)
        elif directive == "error":
            raise GlslRefused(line, f"#error{rest.rstrip()}")
        elif directive in ("pragma", "line", ""):
            continue  # dropped: nothing of them reaches the driver
        elif directive in ("version", "extension"):
            raise GlslRefused(
                line,
                f"#{directive}: the lab's shader gives the version (GLSL {version}) and "
                f"your functions need no extension",
            )
        else:
            raise GlslRefused(line, f"#{directive or body.split()[0]} is not a GLSL directive")
    if conditionals:
        raise GlslRefused(0, "an #if is never closed with #endif")
    if chunk:
        out.extend(_expand(chunk, state))
    if len(out) > MAX_TOKENS:
        raise _limits(out[-1].line if out else 0)
    return out


def check_tokens(tokens: list[Token]) -> None:
    """GlslRefused for the first token that breaks a rule: a reserved name, a declaration
    outside the functions, a character that is no GLSL outside a directive."""
    for token in tokens:  # the reserved names first: the one line names them
        if token.text in ("#", "##"):
            raise GlslRefused(token.line, f"{token.text} outside a directive is not GLSL")
        if token.is_name and token.text.startswith(RESERVED_PREFIX):
            raise GlslRefused(token.line, _reserved(token.text))
    braces = parentheses = 0
    for token in tokens:
        text = token.text
        if text == "{":
            braces += 1
        elif text == "}":
            braces -= 1
        elif text == "(":
            parentheses += 1
        elif text == ")":
            parentheses -= 1
        elif braces == 0 and parentheses == 0 and text in GLOBAL_QUALIFIERS:
            raise GlslRefused(
                token.line,
                f"'{text}' outside a function: the lab's functions take what they need as "
                f"arguments and return their result; declare no uniform, input, output, "
                f"buffer or block of your own",
            )


def text_of(tokens: list[Token], lines: int) -> str:
    """The tokens as GLSL text of ``lines`` lines, each token on its own line (separated by
    spaces, so no two run together)."""
    rows: list[list[str]] = [[] for _ in range(max(lines, 1))]
    for token in tokens:
        row = min(max(token.line, 1), len(rows)) - 1
        rows[row].append(token.text)
    return "\n".join(" ".join(row) for row in rows)


def prepare(text: str, version_line: str = "#version 330 core") -> str:
    """The student's GLSL ``text`` as the driver is to compile it (after the kit's
    ``version_line``): preprocessed and checked (see the module's text), every line where
    it was. GlslRefused for what is refused."""
    match = re.match(r"\s*#\s*version\s+(\d+)\s*(\w*)", version_line)
    version = int(match.group(1)) if match else 330
    core = not match or match.group(2) in ("", "core")
    tokens = preprocess(text, version, core)
    check_tokens(tokens)
    return text_of(tokens, text.count("\n") + 1)
