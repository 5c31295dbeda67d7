"""A lab's formula as a small expression tree, and its common variants made from it by rule.

A GLSL task's function is declared by its formula (:class:`Expr`, in the handout's own
notation: ``u - 2 (n.u) n``, ``m = 2 sqrt(rx^2 + ry^2 + (rz + 1)^2)``). :func:`variants`
makes, from each written form of it, every formula one slip away, each with the words
that name the slip:

- a term of a sum dropped, doubled, squared or its sign flipped; a factor dropped,
  squared or moved below the line; a constant dropped, doubled, halved, squared, negated
  (a 1/2 applied twice);
- a square root, an ``abs``, a ``normalize`` left out; a vector normalised that the
  formula does not; a dot product clamped (``max``/``clamp``) or taken ``abs``;
- a component swapped for another (``rx`` for ``ry``), an input for another of its kind
  (``u`` for ``n``);
- a division applied to one term of a sum only, or to the whole sum; a square written
  without its parentheses (``rz + 1 * rz + 1``);
- per case of a table (a cube map's faces): any of the above on one face, the same on
  every face, every face taking one face's entry, two columns swapped on a face;
- on the result: its components swapped, one flipped (1 - s) or negated, the whole
  negated or normalised.

:func:`evaluate` gives a tree's values on the probe's inputs, ``(n, k)`` float64; a
judge (:mod:`.probe`) keeps the variants whose values the student's follow. Numpy only.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterator
from dataclasses import dataclass, replace
from functools import lru_cache

import numpy as np

AXES = "xyz"


@dataclass(frozen=True)
class Expr:
    """One node: ``op`` (``in``, ``comp``, ``const``, ``add``, ``neg``, ``mul``, ``div``,
    ``sqrt``, ``abs``, ``square``, ``normalize``, ``length``, ``dot``, ``max0``, ``vec``,
    ``select``), its operands, ``value`` (an input's name, a component's index, a
    constant's number) and ``text`` (how the handout writes a constant, ``1/2``). A node
    with a ``name`` (``m``) is shown by its name, its definition after the formula.
    ``cases`` names a ``select``'s branches (``+X face (face 0)``)."""

    op: str
    args: tuple[Expr, ...] = ()
    value: float | int | str = 0
    text: str = ""
    name: str = ""
    cases: tuple[str, ...] = ()
    selector: str = ""


# ------------------------------------------------------------------ building formulas
def var(name: str) -> Expr:
    return Expr("in", value=name)


def comp(vector: Expr, axis: str) -> Expr:
    return Expr("comp", (vector,), AXES.index(axis))


def const(value: float, text: str = "") -> Expr:
    return Expr("const", value=float(value), text=text)


def add(*terms: Expr) -> Expr:
    return Expr("add", terms)


def neg(x: Expr) -> Expr:
    return Expr("neg", (x,))


def sub(a: Expr, b: Expr) -> Expr:
    return add(a, neg(b))


def mul(*factors: Expr) -> Expr:
    return Expr("mul", factors)


def div(a: Expr, b: Expr) -> Expr:
    return Expr("div", (a, b))


def call(op: str, *args: Expr) -> Expr:
    return Expr(op, args)


def vec(*components: Expr) -> Expr:
    return Expr("vec", components)


def select(selector: str, branches: tuple[Expr, ...], cases: tuple[str, ...]) -> Expr:
    return Expr("select", branches, cases=cases, selector=selector)


def named(name: str, x: Expr) -> Expr:
    return replace(x, name=name)


# ------------------------------------------------------------------ values
def evaluate(
    expr: Expr, inputs: dict[str, np.ndarray], memo: dict[int, np.ndarray] | None = None
) -> np.ndarray:
    """``expr`` on ``inputs`` (name -> ``(n, k)``): ``(n, k)`` float64 (k = 1 for a
    number). ``memo`` keeps each node's values by identity, for many trees that share
    their unchanged parts (the variants of one formula), alive while it is used."""
    with np.errstate(all="ignore"):
        return _value(expr, inputs, {} if memo is None else memo)


def _value(e: Expr, inputs: dict[str, np.ndarray], memo: dict[int, np.ndarray]) -> np.ndarray:
    known = memo.get(id(e))
    if known is None:
        known = memo[id(e)] = _compute(e, inputs, memo)
    return known


def _compute(e: Expr, inputs: dict[str, np.ndarray], memo: dict[int, np.ndarray]) -> np.ndarray:
    op, args = e.op, e.args
    if op == "in":
        return np.asarray(inputs[str(e.value)], dtype=np.float64)
    if op == "const":
        size = next(iter(inputs.values())).shape[0]
        return np.full((size, 1), float(e.value))
    values = [_value(a, inputs, memo) for a in args]
    if op == "comp":
        index = int(e.value)
        return values[0][:, index : index + 1]
    if op == "add":
        return sum(values[1:], values[0])
    if op == "neg":
        return -values[0]
    if op == "mul":
        product = values[0]
        for v in values[1:]:
            product = product * v
        return product
    if op == "div":
        return values[0] / values[1]
    if op == "sqrt":
        return np.sqrt(values[0])
    if op == "abs":
        return np.abs(values[0])
    if op == "square":
        return values[0] * values[0]
    if op == "max0":
        return np.maximum(values[0], 0.0)
    if op == "length":
        return np.sqrt((values[0] ** 2).sum(-1, keepdims=True))
    if op == "normalize":
        return values[0] / np.sqrt((values[0] ** 2).sum(-1, keepdims=True))
    if op == "dot":
        return (values[0] * values[1]).sum(-1, keepdims=True)
    if op == "vec":
        return np.concatenate(values, -1)
    if op == "select":
        which = np.asarray(inputs[e.selector]).reshape(-1).astype(np.int64)
        out = np.full_like(values[0], np.nan)
        for index, branch in enumerate(values):
            on = which == index
            out[on] = branch[on]
        return out
    raise ValueError(f"unknown operation {op!r}")


# ------------------------------------------------------------------ text
_PRECEDENCE = {"add": 1, "neg": 2, "mul": 3, "div": 3}


def show(e: Expr, top: bool = False) -> str:
    """``e`` in the handout's notation (a named node by its name unless ``top``)."""
    if e.name and not top:
        return e.name
    op, args = e.op, e.args
    if op == "in":
        return str(e.value)
    if op == "comp":
        inner = show(args[0])
        return (
            f"{inner}{AXES[int(e.value)]}"
            if args[0].op == "in"
            else f"({inner}).{AXES[int(e.value)]}"
        )
    if op == "const":
        if e.text:
            return e.text
        value = float(e.value)
        if value == 0.5:
            return "1/2"
        if value == 0.25:
            return "1/4"
        return f"{value:g}"
    if op == "add":
        parts = []
        for index, term in enumerate(args):
            if term.op == "neg" and not term.name:
                parts.append(("- " if index else "-") + _wrap(term.args[0], 2))
            else:
                parts.append(("+ " if index else "") + _wrap(term, 1))
        return " ".join(parts)
    if op == "neg":
        return "-" + _wrap(args[0], 2)
    if op == "mul":
        return " ".join(_wrap(a, 3, product=True) for a in args)
    if op == "div":
        return f"{_wrap(args[0], 3)} / {_wrap(args[1], 4)}"
    if op in ("sqrt", "normalize"):
        return f"{op}({show(args[0])})"
    if op == "abs":
        return f"|{show(args[0])}|"
    if op == "length":
        return f"|{show(args[0])}|"
    if op == "square":
        return f"{_wrap(args[0], 5)}^2"
    if op == "max0":
        return f"max({show(args[0])}, 0)"
    if op == "dot":
        return f"{show(args[0])}.{show(args[1])}"
    if op == "vec":
        return "(" + ", ".join(show(a) for a in args) + ")"
    if op == "select":
        return "; ".join(f"{case}: {show(b)}" for case, b in zip(e.cases, args, strict=True))
    return op


def _wrap(e: Expr, floor: int, product: bool = False) -> str:
    text = show(e)
    own = _PRECEDENCE.get(e.op, 9) if not e.name else 9
    if ((e.op == "const" and "/" in text) or e.op == "dot") and product:
        own = 2
    return f"({text})" if own < floor or (product and e.op == "div" and not e.name) else text


def definitions(e: Expr) -> list[str]:
    """``name = ...`` of every named node below ``e``, innermost last, once each."""
    found: dict[str, str] = {}

    def visit(x: Expr) -> None:
        if x.name and x.name not in found:
            found[x.name] = f"{x.name} = {show(x, top=True)}"
        for a in x.args:
            visit(a)

    for a in e.args:
        visit(a)
    return list(found.values())


# ------------------------------------------------------------------ variants
@dataclass(frozen=True)
class Variant:
    """A formula one slip away from the right one: its tree and the words for the slip."""

    expr: Expr
    slip: str
    form: int = 0
    """Which written form of the formula it was made from."""


Path = tuple[int, ...]


def _at(e: Expr, path: Path) -> Expr:
    for index in path:
        e = e.args[index]
    return e


def _put(e: Expr, path: Path, new: Expr) -> Expr:
    if not path:
        return new
    args = list(e.args)
    args[path[0]] = _put(args[path[0]], path[1:], new)
    return replace(e, args=tuple(args))


def _nodes(e: Expr, path: Path = ()) -> Iterator[tuple[Path, Expr]]:
    yield path, e
    for index, a in enumerate(e.args):
        yield from _nodes(a, (*path, index))


def _label(e: Expr) -> str:
    return show(e, top=False)


def _scalar(e: Expr, sizes: dict[str, int]) -> bool:
    return _width(e, sizes) == 1


def _width(e: Expr, sizes: dict[str, int]) -> int:
    op = e.op
    if op == "in":
        return sizes.get(str(e.value), 1)
    if op in ("comp", "const", "dot", "length"):
        return 1
    if op == "vec":
        return sum(_width(a, sizes) for a in e.args)
    if op == "select":
        return _width(e.args[0], sizes)
    return max((_width(a, sizes) for a in e.args), default=1)


def _local(
    e: Expr, path: Path, root: Expr, sizes: dict[str, int]
) -> Iterator[tuple[Expr, str, str]]:
    """The slips of node ``e`` (at ``path`` in ``root``): its replacement (``__parent__``:
    its parent's new operands), the words for the slip, and a tag that says the same
    without the node's own text (for one slip made on every case of a table)."""
    parent = _at(root, path[:-1]) if path else None
    index = path[-1] if path else -1
    label = _label(e)
    scalar = _scalar(e, sizes)
    if e.op == "const":
        value = float(e.value)
        if value not in (0.0, 1.0):
            if value == 0.5:
                yield replace(e, value=0.25, text=""), "1/2 applied twice", "twice"
            elif value != 2.0:  # 2 squared is 2 doubled, named so
                words = f"{label} squared ({value * value:g})"
                yield replace(e, value=value * value, text=""), words, "squared"
        if value == 2.0 and _in_denominator(root, path):
            yield replace(e, value=4.0, text=""), "1/2 applied twice (the 2 counted twice)", "twice"
        elif value != 0.0:
            yield replace(e, value=2 * value, text=""), f"{label} doubled ({2 * value:g})", "2x"
        if value not in (0.0, 1.0):
            yield replace(e, value=value / 2, text=""), f"{label} halved ({value / 2:g})", "x/2"
        if value != 0.0:
            yield replace(e, value=-value, text=""), f"the sign of {label} flipped", "sign"
    if parent is not None and parent.op == "add" and len(parent.args) > 1:
        rest = parent.args[:index] + parent.args[index + 1 :]
        term = _label(e.args[0]) if e.op == "neg" else label
        yield Expr("__parent__", rest), f"the term {term} missing", "dropped"
    if parent is not None and parent.op == "mul" and len(parent.args) > 1:
        rest = parent.args[:index] + parent.args[index + 1 :]
        yield Expr("__parent__", rest), f"the factor {label} missing", "dropped"
        others = rest[0] if len(rest) == 1 else mul(*rest)
        yield (
            Expr("__parent__", (div(others, e),)),
            f"{label} below the line instead of above it",
            "moved below",
        )
    if parent is not None and parent.op == "div" and index == 1:
        yield Expr("__parent__", (parent.args[0],)), f"the division by {label} missing", "no /"
        if e.op in ("abs", "length", "sqrt"):
            for name, width in sizes.items():
                if width > 1 and e != call("length", var(name)):
                    yield (
                        call("length", var(name)),
                        f"divided by the length of {name} where the formula divides by {label}",
                        f"/ |{name}|",
                    )
        yield (
            Expr("__parent__", (mul(parent.args[0], e),)),
            f"multiplied by {label} instead of divided",
            "* for /",
        )
    if e.op == "neg":
        yield e.args[0], f"the sign of {_label(e.args[0])} flipped", "sign"
    elif e.op != "const" and parent is not None and parent.op in ("add", "mul", "vec", "div"):
        yield neg(e), f"the sign of {label} flipped", "sign"
    if e.op != "const" and parent is not None and parent.op in ("add", "mul", "div") and scalar:
        yield mul(const(2), e), f"{label} doubled", "2x"
        yield call("square", e), f"{label} squared", "squared"
    if e.op in ("sqrt", "abs", "normalize"):
        inner = _label(e.args[0])
        words, tag = {
            "sqrt": (f"{inner} without its square root", "without sqrt()"),
            "abs": (f"abs() missing around {inner}", "without abs()"),
            "normalize": (f"{inner} not normalised", "not normalised"),
        }[e.op]
        yield e.args[0], words, tag
    if e.op == "dot":
        yield call("max0", e), f"{label} clamped to 0 or more (clamp or max)", "clamped"
        yield call("abs", e), f"abs({label}): the sign of {label} matters", "abs()"
        yield call("square", e), f"{label} squared", "squared"
        for side in (0, 1):
            kept = e.args[1 - side]
            if e.args[side] != kept:
                twice = Expr("dot", (kept, kept))
                yield twice, f"{_label(twice)} where the formula has {label}", f"dot {side}"
    if e.op == "in" and sizes.get(str(e.value), 1) > 1:
        for name, width in sizes.items():
            if name != e.value and width == sizes[str(e.value)]:
                yield var(name), f"{name} where the formula has {e.value}", f"-> {name}"
    if e.op == "comp":
        for axis in range(3):
            if axis != int(e.value):
                swapped = replace(e, value=axis)
                yield swapped, f"{_label(swapped)} where the formula has {label}", f"-> {axis}"
    if e.op == "square" and e.args[0].op == "add" and len(e.args[0].args) == 2:
        a, b = e.args[0].args
        yield (
            add(a, mul(b, a), b),
            f"{_label(e.args[0])} squared without its parentheses "
            f"({_label(a)} + {_label(b)} * {_label(a)} + {_label(b)})",
            "no parentheses",
        )
        yield add(call("square", a), b), f"only {_label(a)} squared in {label}", "half squared"
    if e.op == "div" and e.args[0].op == "add" and len(e.args[0].args) == 2:
        a, b = e.args[0].args
        below = _label(e.args[1])
        yield add(div(a, e.args[1]), b), f"the / {below} applied to {_label(a)} only", "/ first"
        yield add(a, div(b, e.args[1])), f"the / {below} applied to {_label(b)} only", "/ last"
    if e.op in ("add", "in") and not scalar and (parent is None or parent.op != "normalize"):
        yield call("normalize", e), f"{label} normalised where the formula does not", "normalised"


def _in_denominator(root: Expr, path: Path) -> bool:
    node = root
    for index in path:
        if node.op == "div" and index == 1:
            return True
        node = node.args[index]
    return False


def _apply(root: Expr, path: Path, new: Expr) -> Expr:
    """``root`` with the node at ``path`` replaced by ``new`` (which keeps the node's name
    unless it wraps the node); a ``__parent__`` replaces the node's parent. A change
    inside a named part (``m``) is made wherever that part is used."""
    if new.op == "__parent__":
        parent = _at(root, path[:-1])
        changed = new.args[0] if len(new.args) == 1 else replace(parent, args=new.args)
        changed = replace(changed, name=parent.name or changed.name)
        where: Path = path[:-1]
    else:
        old = _at(root, path)
        changed = replace(new, name=old.name) if old.name and old not in new.args else new
        where = path
    result = _put(root, where, changed)
    for depth in range(len(where), -1, -1):
        part = _at(root, where[:depth])
        if part.name:
            return _replace_all(root, part, _at(result, where[:depth]))
    return result


def _replace_all(e: Expr, old: Expr, new: Expr) -> Expr:
    if e is old or e == old:
        return new
    if not e.args:
        return e
    args = tuple(_replace_all(a, old, new) for a in e.args)
    return e if all(a is b for a, b in zip(args, e.args, strict=True)) else replace(e, args=args)


def _inside_table(form: Expr, path: Path) -> bool:
    return any(_at(form, path[:i]).op == "select" for i in range(len(path) + 1))


def _case_slips(root: Expr, sizes: dict[str, int]) -> Iterator[tuple[Expr, str, str]]:
    """Slips of a table (``select``): on one case, the same on every case, every case
    taking one case's entry, and two tables' entries swapped on one case."""
    selects = list(dict.fromkeys(e for _, e in _nodes(root) if e.op == "select"))
    for table in selects:
        title = table.name or "the table's entry"
        by_tag: dict[tuple[Path, str], list[Expr]] = {}
        for case, branch in enumerate(table.args):
            for sub_path, node in _nodes(branch):
                for new, words, tag in _local(node, sub_path, branch, sizes):
                    changed = _apply(branch, sub_path, new)
                    by_tag.setdefault((sub_path, tag), []).append(changed)
                    every_use = replace(table, args=_swap(table.args, case, changed))
                    yield (
                        _replace_all(root, table, every_use),
                        f"on the {table.cases[case]}, {title}: {words}",
                        tag,
                    )
        for (sub_path, tag), changes in by_tag.items():
            if len(changes) == len(table.args) > 1:
                every = replace(table, args=tuple(changes))
                where = title if not sub_path else f"a part of {title}"
                yield _replace_all(root, table, every), f"on every face, {where} {tag}", tag
        for case, branch in enumerate(table.args):
            same = replace(table, args=tuple(branch for _ in table.args))
            if same != table:
                yield (
                    _replace_all(root, table, same),
                    f"every face takes {title} of the {table.cases[case]} ({show(branch)})",
                    "every",
                )
    for a, b in itertools.combinations(selects, 2):
        if a.selector != b.selector or len(a.args) != len(b.args):
            continue
        for case in range(len(a.args)):
            if a.args[case] == b.args[case]:
                continue
            a_new = replace(a, args=_swap(a.args, case, b.args[case]))
            b_new = replace(b, args=_swap(b.args, case, a.args[case]))
            swapped = _replace_all(_replace_all(root, a, a_new), b, b_new)
            yield swapped, f"on the {a.cases[case]}: {a.name} and {b.name} swapped", "swapped"


def _swap(args: tuple[Expr, ...], index: int, new: Expr) -> tuple[Expr, ...]:
    return (*args[:index], new, *args[index + 1 :])


def _parallel_slips(root: Expr, sizes: dict[str, int]) -> Iterator[tuple[Expr, str, str]]:
    """One slip made in every component of the result alike (the + 1/2 missing from s
    and t), where the components are written alike; a named part is changed everywhere
    already."""
    if root.op != "vec" or len(root.args) < 2:
        return
    by_tag: dict[tuple[Path, str], list[tuple[int, Expr, str]]] = {}
    for index, part in enumerate(root.args):
        for sub_path, node in _nodes(part):
            path = (index, *sub_path)
            if any(
                _at(root, path[:i]).name or _at(root, path[:i]).op == "select"
                for i in range(1, len(path) + 1)
            ):
                continue
            for new, words, tag in _local(node, path, root, sizes):
                by_tag.setdefault((sub_path, tag), []).append(
                    (index, _at(_apply(root, path, new), (index,)), words)
                )
    for (_, tag), changes in by_tag.items():
        if len(changes) == len(root.args) and [c[0] for c in changes] == list(
            range(len(root.args))
        ):
            together = vec(*(c[1] for c in changes))
            words = changes[0][2]
            yield together, f"{words}, in {' and in '.join(_component_names(root))}", tag


def _component_names(root: Expr) -> list[str]:
    return list("st" if len(root.args) == 2 else "xyz"[: len(root.args)])


def _result_slips(root: Expr, result: str, kind: str) -> Iterator[tuple[Expr, str, str]]:
    """Slips of the whole result: components swapped, one flipped, the whole negated or
    normalised (``kind``: ``"direction"`` or ``"coordinates"``, values in [0, 1])."""
    names = {"coordinates": "st", "direction": "xyz"}[kind]
    if root.op == "vec":
        parts = root.args
        for i, j in itertools.combinations(range(len(parts)), 2):
            swapped = list(parts)
            swapped[i], swapped[j] = parts[j], parts[i]
            yield vec(*swapped), f"{names[i]} and {names[j]} swapped", "swapped"
        for i, part in enumerate(parts):
            flipped = list(parts)
            if kind == "coordinates":
                flipped[i] = sub(const(1), part)
                yield (
                    vec(*flipped),
                    f"{names[i]} flipped ({names[i]} becomes 1 - {names[i]})",
                    "flipped",
                )
            else:
                flipped[i] = neg(part)
                yield vec(*flipped), f"the sign of {result}{names[i]} flipped", "sign"
    if kind == "direction":
        yield neg(root), f"{result} points the wrong way (it is -{result})", "sign"
        yield (
            call("normalize", root),
            f"{result} normalised where the formula does not",
            "normalised",
        )


def variants(
    forms: tuple[Expr, ...], sizes: dict[str, int], result: str, kind: str
) -> list[Variant]:
    """Every formula one slip from any of ``forms`` (the ways the right formula is
    written), in a fixed order (the handout's form first); ``sizes`` gives each input's
    width, ``result`` the result's name (``r``) and ``kind`` its sort (see
    :func:`_result_slips`)."""
    return list(_variants(forms, tuple(sorted(sizes.items())), result, kind))


@lru_cache(maxsize=16)
def _variants(
    forms: tuple[Expr, ...], sizes_items: tuple[tuple[str, int], ...], result: str, kind: str
) -> tuple[Variant, ...]:
    sizes = dict(sizes_items)
    found: list[Variant] = []
    seen: set[Expr] = set(forms)
    for index, form in enumerate(forms):
        candidates: list[tuple[Expr, str, str]] = []
        for path, node in _nodes(form):
            if not _inside_table(form, path):
                for new, words, tag in _local(node, path, form, sizes):
                    candidates.append((_apply(form, path, new), words, tag))
        candidates.extend(_case_slips(form, sizes))
        candidates.extend(_parallel_slips(form, sizes))
        candidates.extend(_result_slips(form, result, kind))
        candidates.sort(key=lambda c: _rank(c[2]))
        for expr, words, _ in candidates:
            if expr not in seen:
                seen.add(expr)
                found.append(Variant(expr, words, index))
    return tuple(found)


_PRIORITY = {
    tag: rank
    for rank, tag in enumerate(
        (
            "dropped",
            "no /",
            "sign",
            "without sqrt()",
            "without abs()",
            "not normalised",
            "swapped",
            "flipped",
            "-> ",
            "clamped",
            "abs()",
            "no parentheses",
            "twice",
            "half squared",
            "/ first",
            "/ last",
            "squared",
            "2x",
            "x/2",
        )
    )
}
"""Which words name a slip first when two slips give the same numbers (a factor 2
missing, not the 2 halved)."""


def _rank(tag: str) -> int:
    return _PRIORITY.get(tag, _PRIORITY["-> "] if tag.startswith("-> ") else len(_PRIORITY))


def formula_text(e: Expr, result: str) -> str:
    """``result = ...`` with the definitions of its named parts after it."""
    body = show(e, top=True)
    if e.op == "vec" and len(result) == len(e.args):
        body = ", ".join(f"{r} = {show(a)}" for r, a in zip(result, e.args, strict=True))
    else:
        body = f"{result} = {body}"
    defined = definitions(e)
    return body + (f" with {', '.join(defined)}" if defined else "")


Generator = Callable[[dict[str, np.ndarray]], list[tuple[np.ndarray, str]]]
"""A lab's own family of variants that are not one slip of a formula (a cube map's face
chosen by other comparisons): from the inputs, each variant's values and words."""
