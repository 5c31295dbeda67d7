"""The value probe: each GLSL function a lab asks for, evaluated on inputs the checker
draws at random for every check, and judged on every value it gives.

**Inputs.** A lab declares each function (:class:`GlslFunction`, in its ``glsl.py``): its
formula in the handout's notation, the ways it is written, and its domain as named blocks
of inputs (:class:`Block`): general inputs over the whole domain, and the hard cases
(grazing and head-on reflections, the sphere map's rim and centre, a cube's face edges
and corners...). :func:`draw_inputs` draws them from a seed that the trusted process
takes from :mod:`secrets` for every GLSL text it sees (or ``$MIRRORLAB_PROBE_SEED``, to
reproduce a check); the sandbox never sees it or the inputs.

**Evaluation** (:func:`evaluate`) runs in the short-lived process that compiles the
student's GLSL first (:mod:`.glslcheck`), in a context of its own: nothing a student's
calls set can be there. The student's shader object is linked to a probe ``main`` of the
checker's own (``ml_`` names only, which a student's GLSL may not use) that reads one
input per point from vertex attributes, with no texture, sampler, uniform or binding, and
writes each result with a marker the student's code cannot write: a fragment discarded
(or never written) is a wrong value. GL's built-in matrices read as the identity there.

**Judging** (:func:`judge`): every input of the domain must give the formula's value
(within :data:`TOLERANCE`); the singular input of a formula accepts any value; inputs
outside the domain (reflection vectors not of unit length) only help name a mistake.
When a function fails, its values are fitted against the variants of its formula
(:mod:`.formulas`) and the variant they follow is named; else the hard case it fails on;
else "a mistake the checker does not know", with one input and both values. Numpy only
but :func:`evaluate`.
"""

from __future__ import annotations

import os
import re
import secrets
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np

from mirrorlab.labs.trusted import formulas as F
from mirrorlab.labs.trusted.judging import INTEGER_HALF, glsl_body

TOLERANCE = 1e-3
"""Largest difference between the GPU's float32 values and the formula's float64 ones on
an input of the domain (measured on Mesa llvmpipe over 20 seeds: the solutions within
3e-7; ``m = 2 sqrt(2 (rz + 1))``, right for unit r only, within 5e-5 at the rim)."""
MATCH_SHARE = 0.95
"""A variant is named when the values follow it on this share of the inputs (rounding at
the hard cases may put a few apart) and on nine in ten of those where they are wrong."""
SEED_VARIABLE = "MIRRORLAB_PROBE_SEED"
WIDTH = 64
"""Points a row of the probe's target."""
EXACT, ANY, DIAGNOSTIC = "exact", "any", "diagnostic"


@dataclass(frozen=True)
class Block:
    """Inputs of one kind: ``values`` per parameter name ``(n, k)``; ``rule`` says how
    they are judged: ``exact`` (the formula's value), ``any`` (a singular input: any
    value, but a discard is still wrong) or ``diagnostic`` (outside the domain: not
    judged, but used to tell variants apart)."""

    kind: str
    values: dict[str, np.ndarray]
    rule: str = EXACT


@dataclass(frozen=True)
class GlslFunction:
    """A lab's GLSL function as the probe judges it.

    ``parameters``: the formula's names for the function's arguments, in order (their
    widths in ``widths``); ``result``: the result's name(s) (``r``, ``st``); ``kind``:
    ``direction``, ``coordinates`` or ``face``; ``forms``: the right formula as written
    (the handout's first); ``handout``: the formula as a hint quotes it; ``domain``: the
    blocks of inputs drawn from a generator (the general inputs over the whole domain
    first, then the hard cases). Optional: ``family`` (variants that are not
    one slip of a formula), ``accepts`` (which rows are right, when the formula allows
    more than one answer: a cube edge's two faces) and ``cases`` (a per-row group, such as
    the face, whose own slips are named one by one)."""

    name: str
    variable: str
    parameters: tuple[str, ...]
    widths: tuple[int, ...]
    result: str
    kind: str
    handout: str
    domain: Callable[[np.random.Generator], list[Block]]
    forms: tuple[F.Expr, ...] = ()
    family: F.Generator | None = None
    right: Callable[[dict[str, np.ndarray]], np.ndarray] | None = None
    accepts: Callable[[np.ndarray, dict[str, np.ndarray]], np.ndarray] | None = None
    cases: Callable[[dict[str, np.ndarray]], tuple[np.ndarray, tuple[str, ...]]] | None = None

    def expected(self, inputs: dict[str, np.ndarray]) -> np.ndarray:
        """The right values ``(n, k)`` (float64) on ``inputs``."""
        if self.right is not None:
            return self.right(inputs)
        return F.evaluate(self.forms[0], inputs)


# ------------------------------------------------------------------ drawing inputs
def seed() -> int:
    """A fresh secret seed, or ``$MIRRORLAB_PROBE_SEED`` (to reproduce a check)."""
    fixed = os.environ.get(SEED_VARIABLE, "").strip()
    if fixed:
        try:
            return int(fixed) % (1 << 63)
        except ValueError:
            pass
    return secrets.randbits(63)


def unit_vectors(rng: np.random.Generator, count: int) -> np.ndarray:
    """``(count, 3)`` directions uniform on the sphere."""
    v = rng.normal(size=(count, 3))
    norm = np.linalg.norm(v, axis=-1, keepdims=True)
    return v / np.where(norm > 1e-6, norm, 1.0)


@dataclass(frozen=True)
class Drawn:
    """A function's inputs: per parameter ``(n, k)`` float32 (as the GPU gets them), the
    index of each row's block, and the blocks' (kind, rule)."""

    values: dict[str, np.ndarray]
    block: np.ndarray
    blocks: tuple[tuple[str, str], ...]

    @property
    def count(self) -> int:
        return int(self.block.shape[0])


def draw_inputs(function: GlslFunction, seed_value: int) -> Drawn:
    """The inputs of ``function`` drawn from ``seed_value``, rounded to float32."""
    rng = np.random.default_rng([seed_value, sum(map(ord, function.name))])
    blocks = function.domain(rng)
    values = {
        p: np.concatenate([np.asarray(b.values[p], dtype=np.float32) for b in blocks])
        for p in function.parameters
    }
    which = np.concatenate(
        [np.full(len(next(iter(b.values.values()))), i, np.int16) for i, b in enumerate(blocks)]
    )
    return Drawn(values, which, tuple((b.kind, b.rule) for b in blocks))


def draw_all(functions: tuple[GlslFunction, ...], seed_value: int) -> dict[str, Drawn]:
    return {f.name: draw_inputs(f, seed_value) for f in functions}


# ------------------------------------------------------------------ the lab's declarations
def lab_functions(lab: str) -> tuple[GlslFunction, ...]:
    """The GLSL functions ``lab`` declares (its package's ``glsl.FUNCTIONS``), () when it
    has none."""
    import importlib

    from mirrorlab.labs import find_lab

    spec = find_lab(lab)
    try:
        module = importlib.import_module(f"{spec.package}.glsl")
    except ModuleNotFoundError as exc:
        if exc.name != f"{spec.package}.glsl":
            raise
        return ()
    return tuple(module.FUNCTIONS)


def function_named(lab: str, name: str) -> GlslFunction:
    return next(f for f in lab_functions(lab) if f.name == name)


# ------------------------------------------------------------------ the GL part
ARGUMENT = {
    "float": "{}.x",
    "int": "int(floor({}.x + 0.5))",
    "bool": "({}.x > 0.5)",
    "vec2": "{}.xy",
    "vec3": "{}.xyz",
}
RESULT = {
    "float": "vec4({}, 0.0, 0.0, 1.0)",
    "int": "vec4(float({}), 0.0, 0.0, 1.0)",
    "bool": "vec4({} ? 1.0 : 0.0, 0.0, 0.0, 1.0)",
    "vec2": "vec4({}, 0.0, 1.0)",
    "vec3": "vec4({}, 1.0)",
}
"""How the probe's main passes an argument (from a ``vec4`` slot) and keeps a result: the
last component, 1, is written by the main alone, after the call returns."""


def probe_shaders(
    version: str, prototypes: list[tuple[str, str, str]], functions: list[str]
) -> tuple[str, str]:
    """The probe's vertex and fragment shaders calling ``functions`` (of the kit's
    ``prototypes``): point i is call ``ml_which``'s input i."""
    by_name = {name: (result, params) for result, name, params in prototypes}
    slots = max(
        (len([p for p in by_name[f][1].split(",") if p.strip()]) for f in functions), default=0
    )
    inputs = "".join(
        f"layout(location = {2 + i}) in vec4 ml_in{i};\nflat out vec4 ml_arg{i};\n"
        for i in range(slots)
    )
    copies = "".join(f"    ml_arg{i} = ml_in{i};\n" for i in range(slots))
    vertex = (
        f"{version}\nlayout(location = 0) in vec2 ml_position;\n"
        "layout(location = 1) in float ml_which;\nflat out int ml_call;\n"
        f"{inputs}void main() {{\n    ml_call = int(floor(ml_which + 0.5));\n{copies}"
        "    gl_Position = vec4(ml_position, 0.0, 1.0);\n    gl_PointSize = 1.0;\n}\n"
    )
    branches = []
    for index, name in enumerate(functions):
        result, params = by_name[name]
        types = [p.split()[-2] for p in params.split(",") if p.strip()]
        arguments = ", ".join(ARGUMENT[t].format(f"ml_arg{i}") for i, t in enumerate(types))
        value = RESULT[result].format(f"{name}({arguments})")
        branches.append(f"    {'else ' if index else ''}if (ml_call == {index}) ml_out = {value};")
    declared = "".join(f"{r} {n}({p});\n" for r, n, p in prototypes)
    arguments_in = "".join(f"flat in vec4 ml_arg{i};\n" for i in range(slots))
    fragment = (
        f"{version}\n{declared}flat in int ml_call;\n{arguments_in}"
        "layout(location = 0) out vec4 ml_out;\nvoid main() {\n    ml_out = vec4(0.0);\n"
        + "\n".join(branches)
        + "\n}\n"
    )
    return vertex, fragment


def evaluate(
    kit_fragment: str,
    glsl: str,
    variable: str,
    calls: dict[str, list[np.ndarray]],
    registry: Any,
) -> dict[str, np.ndarray]:
    """Each function of ``calls`` (its arguments' arrays ``(n, k)``, in order) evaluated
    by the student's ``glsl`` linked to the probe's main in the current context: ``{name:
    (n, 4) float32}``, the last component 1 where the main wrote the result and 0 where
    the fragment was discarded. Sets every piece of state it depends on; deletes what it
    made. StudentShaderError when the GLSL does not compile or link with the probe."""
    from mirrorlab.gl.opengl import GL
    from mirrorlab.gl.resources import FloatFramebuffer, expand_includes
    from mirrorlab.labs.trusted import session

    kit_source = expand_includes(kit_fragment)
    version, prototypes = session.student_interface(kit_source)
    version = version or "#version 330 core"
    names = list(calls)
    vertex_text, fragment_text = probe_shaders(version, prototypes, names)
    shaders = [session.student_shader(GL.GL_FRAGMENT_SHADER, kit_source, glsl, variable)]
    program = vao = buffer = 0
    target = None
    try:
        shaders.append(
            session._compiled(GL.GL_VERTEX_SHADER, vertex_text, "the probe's vertex shader", "")
        )
        shaders.append(
            session._compiled(GL.GL_FRAGMENT_SHADER, fragment_text, "the probe's main", "")
        )
        program = _probe_program(shaders, variable)
        counts = [int(calls[n][0].shape[0]) if calls[n] else 0 for n in names]
        total = sum(counts)
        slots = max((len(calls[n]) for n in names), default=0)
        rows = max(1, -(-total // WIDTH))
        index = np.arange(total)
        data = np.zeros((total, 3 + 4 * slots), dtype=np.float32)
        data[:, 0] = (index % WIDTH + 0.5) / WIDTH * 2 - 1
        data[:, 1] = (index // WIDTH + 0.5) / rows * 2 - 1
        start = 0
        for which, name in enumerate(names):
            count = counts[which]
            data[start : start + count, 2] = which
            for slot, array in enumerate(calls[name]):
                array = np.asarray(array, dtype=np.float32).reshape(count, -1)
                data[start : start + count, 3 + 4 * slot : 3 + 4 * slot + array.shape[1]] = array
            start += count
        target = FloatFramebuffer(registry, WIDTH, rows)
        target.bind()
        _state_for_points(GL, WIDTH, rows)
        GL.glUseProgram(program)
        _identity_matrices(GL, program)
        vao = int(GL.glGenVertexArrays(1))
        GL.glBindVertexArray(vao)
        buffer = int(GL.glGenBuffers(1))
        GL.glBindBuffer(GL.GL_ARRAY_BUFFER, buffer)
        GL.glBufferData(GL.GL_ARRAY_BUFFER, data.nbytes, data, GL.GL_STATIC_DRAW)
        stride = data.shape[1] * 4
        layout = [(0, 2, 0), (1, 1, 8)] + [(2 + s, 4, 12 + 16 * s) for s in range(slots)]
        for location, size, offset in layout:
            GL.glEnableVertexAttribArray(location)
            GL.glVertexAttribPointer(
                location, size, GL.GL_FLOAT, GL.GL_FALSE, stride, GL.GLvoidp(offset)
            )
        GL.glClearColor(0.0, 0.0, 0.0, 0.0)
        GL.glClear(GL.GL_COLOR_BUFFER_BIT)
        GL.glDrawArrays(GL.GL_POINTS, 0, total)
        # read_rgba gives row 0 at the top; point i sits in row i // WIDTH from the bottom
        pixels = target.read_rgba()[::-1].reshape(-1, 4)[:total].astype(np.float32)
        found, start = {}, 0
        for which, name in enumerate(names):
            found[name] = pixels[start : start + counts[which]].copy()
            start += counts[which]
        return found
    finally:
        GL.glUseProgram(0)
        GL.glBindVertexArray(0)
        GL.glBindBuffer(GL.GL_ARRAY_BUFFER, 0)
        if buffer:
            GL.glDeleteBuffers(1, [buffer])
        if vao:
            GL.glDeleteVertexArrays(1, [vao])
        if target is not None:
            target.release()
        if program:
            GL.glDeleteProgram(program)
        for shader in shaders:
            GL.glDeleteShader(shader)


def _probe_program(shaders: list[int], variable: str) -> int:
    """The linked probe; a link that fails is the student's GLSL's failure (the probe's
    own shaders link with any functions of the kit's prototypes)."""
    from mirrorlab.labs.trusted.session import LabSetupError, StudentShaderError, _linked

    try:
        return _linked(shaders, "probe", variable)
    except StudentShaderError as exc:
        raise StudentShaderError(
            variable, 0, exc.detail.replace("the lab's shader", "the checker's probe")
        ) from None
    except LabSetupError as exc:  # pragma: no cover - the probe's own shaders
        raise StudentShaderError(
            variable, 0, f"it does not link to the checker's probe ({exc})"
        ) from None


def _state_for_points(GL: Any, width: int, height: int) -> None:
    """Everything a one-pixel point's colour depends on, set."""
    GL.glViewport(0, 0, width, height)
    for cap in (
        GL.GL_SCISSOR_TEST,
        GL.GL_BLEND,
        GL.GL_DEPTH_TEST,
        GL.GL_STENCIL_TEST,
        GL.GL_CULL_FACE,
        GL.GL_RASTERIZER_DISCARD,
        GL.GL_MULTISAMPLE,
        GL.GL_SAMPLE_ALPHA_TO_COVERAGE,
        GL.GL_SAMPLE_COVERAGE,
        GL.GL_COLOR_LOGIC_OP,
        GL.GL_FRAMEBUFFER_SRGB,
    ):
        GL.glDisable(cap)
    GL.glEnable(GL.GL_PROGRAM_POINT_SIZE)
    GL.glColorMask(1, 1, 1, 1)
    GL.glPolygonMode(GL.GL_FRONT_AND_BACK, GL.GL_FILL)
    while GL.glGetError() != GL.GL_NO_ERROR:  # a compatibility-only cap on a core context
        pass


def _identity_matrices(GL: Any, program: int) -> None:
    """GL's built-in matrices (their ``ml_`` uniforms) as the identity in the probe."""
    eye4 = np.eye(4, dtype=np.float32)
    for index in range(int(GL.glGetProgramiv(program, GL.GL_ACTIVE_UNIFORMS))):
        name, size, kind = GL.glGetActiveUniform(program, index)
        name = name.decode() if isinstance(name, bytes) else str(name)
        location = int(GL.glGetUniformLocation(program, name))
        if location < 0:
            continue
        if kind == GL.GL_FLOAT_MAT4:
            GL.glUniformMatrix4fv(location, int(size), GL.GL_FALSE, np.tile(eye4, (int(size), 1)))
        elif kind == GL.GL_FLOAT_MAT3:
            GL.glUniformMatrix3fv(
                location,
                int(size),
                GL.GL_FALSE,
                np.tile(np.eye(3, dtype=np.float32), (int(size), 1)),
            )


# ------------------------------------------------------------------ judging
def _close(values: np.ndarray, predicted: np.ndarray, relative: float = 0.0) -> np.ndarray:
    """Per row: every component within the tolerance (both not finite counts as equal)."""
    with np.errstate(invalid="ignore"):
        bound = TOLERANCE + relative * np.abs(predicted)
        near = np.abs(values - predicted) <= bound
    both_off = ~np.isfinite(values) & ~np.isfinite(predicted)
    return np.all(near | both_off, axis=-1)


def _show_vector(v: np.ndarray) -> str:
    parts = [f"{x:.3g}" if np.isfinite(x) else str(x) for x in np.asarray(v).reshape(-1)]
    return parts[0] if len(parts) == 1 else "(" + ", ".join(parts) + ")"


def _example(function: GlslFunction, inputs: dict[str, np.ndarray], row: int) -> str:
    return ", ".join(f"{p} = {_show_vector(inputs[p][row])}" for p in function.parameters)


@dataclass
class Probed:
    """A function's probe as a judge reads it from the evidence."""

    function: GlslFunction
    inputs: dict[str, np.ndarray]
    values: np.ndarray
    written: np.ndarray
    block: np.ndarray
    blocks: tuple[tuple[str, str], ...]

    @property
    def rules(self) -> np.ndarray:
        return np.array([self.blocks[int(b)][1] for b in self.block])


def record(
    evidence: Any, drawn: dict[str, Drawn], found: dict[str, np.ndarray], seed_value: int
) -> None:
    """Keep the probe's inputs and values in ``evidence`` (its arrays and state)."""
    evidence.state["probe_seed"] = str(seed_value)
    kinds = evidence.state.setdefault("probe_blocks", {})
    for name, inputs in drawn.items():
        for slot, array in enumerate(inputs.values.values()):
            padded = np.zeros((inputs.count, 4), np.float32)
            padded[:, : array.shape[1]] = array
            evidence.arrays[f"probe_{name}_arg{slot}"] = padded
        evidence.arrays[f"probe_{name}_block"] = inputs.block.astype(np.int16)
        kinds[name] = [list(b) for b in inputs.blocks]
        if name in found:
            evidence.arrays[f"probe_{name}"] = np.asarray(found[name], np.float32)


def probed(evidence: Any, function: GlslFunction) -> Probed | None:
    """The probe of ``function`` in ``evidence``, None when there is none."""
    name = function.name
    block = evidence.arrays.get(f"probe_{name}_block")
    blocks = (evidence.state.get("probe_blocks") or {}).get(name)
    if not isinstance(block, np.ndarray) or block.ndim != 1 or not isinstance(blocks, list):
        return None
    count = int(block.shape[0])
    values = evidence.floats(f"probe_{name}", (count, 4))
    if values is None or count == 0:
        return None
    inputs = {}
    for slot, (parameter, width) in enumerate(
        zip(function.parameters, function.widths, strict=True)
    ):
        array = evidence.floats(f"probe_{name}_arg{slot}", (count, 4))
        if array is None:
            return None
        inputs[parameter] = array[:, :width]
    kinds = tuple((str(k), str(r)) for k, r in blocks)
    if block.min() < 0 or block.max() >= len(kinds):
        return None
    return Probed(function, inputs, values, values[:, 3] == 1.0, block.astype(np.int64), kinds)


def _width(function: GlslFunction) -> int:
    return {"direction": 3, "coordinates": 2, "face": 1}[function.kind]


def right_rows(p: Probed) -> np.ndarray:
    """Per row: the value given is right (``any`` rows: any value; diagnostic rows: not
    judged, True)."""
    f = p.function
    out = p.values[:, : _width(f)]
    if f.accepts is not None:
        ok = f.accepts(out, p.inputs)
    else:
        ok = _close(out, f.expected(p.inputs)) & np.all(np.isfinite(out), axis=-1)
    rules = p.rules
    return (ok | (rules == ANY) | (rules == DIAGNOSTIC)) & p.written


def judge(evidence: Any, lab: str, name: str) -> tuple[bool, str]:
    """(passed, hint) for the student's GLSL function ``name`` of ``lab``: every probed
    value right, else the mistake named (see the module's text). The function's text in
    the student's file is read only where values cannot tell two forms apart (``1/2``,
    integer division, against no ``+ 1/2`` at all)."""
    function = function_named(lab, name)
    error = evidence.state.get("probe_error")
    if isinstance(error, str) and error:
        return False, error
    p = probed(evidence, function)
    if p is None:
        declared = evidence.state.get("declared") or []
        if function.variable not in declared and not evidence.state.get("probe_blocks"):
            return False, f"{function.variable} is missing: keep the string of GLSL the starter has"
        return False, f"{name} could not be evaluated by the checker's probe"
    ok = right_rows(p)
    if bool(ok.all()):
        return True, ""
    return False, name_mistake(p, ok, glsl_body(evidence.source, name))


@dataclass(frozen=True)
class Candidate:
    """A variant on the probe's inputs: its values ``(n, k)``, its words, its tree and the
    written form it was made from (None and -1: not one slip of a formula)."""

    values: np.ndarray
    words: str
    expr: F.Expr | None = None
    form: int = -1


Candidates = list[Candidate]


def name_mistake(
    p: Probed, ok: np.ndarray, source_body: str = "", candidates: Candidates | None = None
) -> str:
    """The hint for a function whose values are wrong on the rows ``ok`` is False
    (``candidates``: :func:`_candidates` of its inputs, when known)."""
    f, name = p.function, p.function.name
    total = len(ok)
    missing = ~p.written
    if missing.any():
        row = int(np.flatnonzero(missing)[0])
        return (
            f"{name} wrote no value for {int(missing.sum())} of the {total} inputs the "
            f"checker chose (a discarded fragment counts as a wrong value), e.g. for "
            f"{_example(f, p.inputs, row)}"
        )
    width = _width(f)
    out = p.values[:, :width]
    judged = p.rules != ANY
    expected = f.expected(p.inputs)
    constant = constant_hint(p)
    if constant:
        if INTEGER_HALF.search(source_body):
            return (
                f"{name}: {constant}: 1/2 in GLSL is integer division, 0; write 0.5 (or "
                f"divide by 2.0)"
            )
        return f"{name}: {constant}; the formula: {f.handout}"
    found = _fitted(p, ok, out, judged, candidates)
    if found:
        words, shown = found
        hint = f"{name}: {words}"
        if INTEGER_HALF.search(source_body) and ("1/2" in words or "the same value" in words):
            return (
                f"{name}: 1/2 in GLSL is integer division, 0, so it adds or multiplies "
                f"nothing: write 0.5 (or divide by 2.0)"
            )
        return (
            hint
            + (f"; your values follow {shown}" if shown else "")
            + (f" (the formula: {f.handout})")
        )
    wrong = ~ok
    row = int(np.flatnonzero(wrong)[0])
    example = (
        f"for {_example(f, p.inputs, row)} it gives {_show_vector(out[row])}, the formula "
        f"{_show_vector(expected[row])}"
    )
    if not np.all(np.isfinite(out[wrong & judged])):
        bad = int(np.flatnonzero(wrong & ~np.all(np.isfinite(out), axis=-1))[0])
        kind = p.blocks[int(p.block[bad])][0]
        return (
            f"{name} gives NaN or infinity for {_example(f, p.inputs, bad)} ({kind}); "
            f"the formula: {f.handout}"
        )
    general = p.block == 0
    if general.any() and ok[general].mean() >= 0.99:
        kinds = sorted({p.blocks[int(b)][0] for b in p.block[wrong]})
        return f"{name} is right on general inputs but not on {', '.join(kinds)}: {example}"
    share = wrong[judged].mean()
    return (
        f"a mistake the checker does not know: {name} differs from {f.handout} on "
        f"{share:.0%} of the inputs; {example}"
    )


ARITHMETIC = re.compile(r"\b(squared|doubled|halved)\b")
"""Words of a slip that says another's arithmetic again (a square root squared)."""


def _matches(out: np.ndarray, candidates: Candidates) -> np.ndarray:
    """``(variants, rows)``: where each candidate's values are the student's ``out``
    (within the tolerance, 1e-3 of the size too; not finite both counts as equal)."""
    stack = np.stack([c.values for c in candidates])
    with np.errstate(invalid="ignore"):
        near = np.abs(stack - out[None]) <= TOLERANCE + 1e-3 * np.abs(stack)
    near |= ~np.isfinite(stack) & ~np.isfinite(out)[None]
    return near.all(-1)


def _fitted(
    p: Probed,
    ok: np.ndarray,
    out: np.ndarray,
    judged: np.ndarray,
    candidates: Candidates | None = None,
) -> tuple[str, str] | None:
    """(the words for the variant the values follow, its formula or ''), or None."""
    f = p.function
    wrong = ~ok & judged
    candidates = _candidates(f, p.inputs) if candidates is None else candidates
    if not candidates:
        return None
    match = _matches(out, candidates)
    share = match[:, judged].mean(-1)
    explained = match[:, wrong].mean(-1) if wrong.any() else np.ones(len(candidates))
    good = np.flatnonzero((share >= MATCH_SHARE) & (explained >= 0.9))
    if good.size:
        best = good[np.argmax(share[good])]  # the first of the best (the likelier words)
        chosen = candidates[best]
        words = chosen.words
        shown = F.formula_text(chosen.expr, f.result) if chosen.expr is not None else ""
        # another reading of the very same numbers (a factor missing, or a vector not
        # normalised), another written form's first, then not the same arithmetic said
        # again (a root squared)
        readings = [candidates[i] for i in good if share[i] == share[best]]
        other = [c for c in readings if c.form not in (-1, chosen.form)]
        other += [c for c in readings if c.form == chosen.form and not ARITHMETIC.search(c.words)]
        same = [
            c.words
            for c in other
            if not (c.words.startswith(words) or words.startswith(c.words.split(",")[0]))
        ][:1]
        if same:
            words += f" (the same numbers as: {same[0]})"
        return words, (shown if len(shown) <= 100 else "")
    if f.cases is None:
        return None
    # one slip per case (a face), each named on its own inputs: a slip of that case's
    # entry first, then one of the whole formula
    case, titles = f.cases(p.inputs)
    words = [c.words for c in candidates]
    named = []
    for which in sorted(set(case[wrong].tolist())):
        on = (case == which) & judged
        fits = match[:, on].mean(-1) >= MATCH_SHARE
        own = [i for i in np.flatnonzero(fits) if words[i].startswith(f"on the {titles[which]}")]
        whole = [i for i in np.flatnonzero(fits) if not words[i].startswith(("on ", "every "))]
        if own:
            named.append(words[own[0]])
        elif whole:
            named.append(f"on the {titles[which]}: {words[whole[0]]}")
        else:
            return None
    return ("; ".join(named), "") if named else None


def _candidates(f: GlslFunction, inputs: dict[str, np.ndarray]) -> Candidates:
    """Each variant's values on ``inputs``, its words and its formula's text: the
    function's argument or a constant returned, the formula's one-slip variants, the
    lab's own family."""
    width = _width(f)
    count = next(iter(inputs.values())).shape[0]
    found: Candidates = []
    for parameter, w in zip(f.parameters, f.widths, strict=True):
        if w == width:
            found.append(
                Candidate(inputs[parameter], f"it returns its argument {parameter} unchanged")
            )
    if f.forms:
        sizes = dict(zip(f.parameters, f.widths, strict=True))
        memo: dict[int, np.ndarray] = {}
        for variant in F.variants(f.forms, sizes, f.result, f.kind):
            values = F.evaluate(variant.expr, inputs, memo)
            if values.shape == (count, width):
                found.append(Candidate(values, variant.slip, variant.expr, variant.form))
    if f.family is not None:
        for values, words in f.family(inputs):
            found.append(Candidate(np.asarray(values, np.float64).reshape(count, width), words))
    return found


def constant_hint(p: Probed) -> str:
    """Words for values that are one constant for every input ('' when they are not)."""
    out = p.values[:, : _width(p.function)]
    if out.shape[0] and np.all(np.isfinite(out)) and np.ptp(out, axis=0).max() == 0:
        return f"it gives the same value {_show_vector(out[0])} for every input"
    return ""
