"""The call trace's reasoning on traces made here (numpy only): the alignment names a missing,
an extra, a moved call and other arguments in the student's terms; a call that acted on
other state says what state and which line set it; and, as a property over random traces
and hints, a guarded hint never asks for a call the file made with the same arguments."""

from __future__ import annotations

import re
from typing import Any

from hypothesis import given, settings
from hypothesis import strategies as st

from mirrorlab.labs.trusted.evidence import Evidence
from mirrorlab.labs.trusted.trace_hints import CALL_TEXT, QUOTED, Hints, suggested_calls

GL_TEXTURE_2D, GL_TEXTURE0 = 0x0DE1, 0x84C0
NAMES = {0x0DE1: "GL_TEXTURE_2D", 0x2801: "GL_TEXTURE_MIN_FILTER", 0x2601: "GL_LINEAR"}
NAMES |= {GL_TEXTURE0 + u: f"GL_TEXTURE{u}" for u in range(4)}
NAMES |= {0x0C60: "GL_TEXTURE_GEN_S", 0x0C61: "GL_TEXTURE_GEN_T", 0x2600: "GL_NEAREST"}


def call(fn: str, args: list[Any], line: int, unit: int = 0, bound: int = 0) -> dict[str, Any]:
    """A ``call`` event as the tracker records it, its enums named."""
    names = {str(i): NAMES[a] for i, a in enumerate(args) if isinstance(a, int) and a in NAMES}
    if fn == "glBindTexture":
        names.pop("1", None)
    return {
        "kind": "call",
        "fn": fn,
        "op": "gl",
        "args": args,
        "names": names,
        "line": line,
        "function": "draw",
        "steps": ["draw"],
        "ctx": {"u": unit, "t2": bound, "tc": 0, "m": 0x1700, "p": 0, "b": 0},
    }


def replay(calls: list[tuple[str, list[Any]]]) -> list[dict[str, Any]]:
    """The events of ``calls`` made in order in lab function ``draw`` (lines 10, 11, ...),
    each with the unit active and the texture bound at that moment."""
    unit, bound, events = (
        0,
        {0: 0},
        [{"kind": "enter", "function": "draw", "steps": ["draw"], "line": 1}],
    )
    for i, (fn, args) in enumerate(calls):
        events.append(call(fn, args, 10 + i, unit, bound.get(unit, 0)))
        if fn == "glActiveTexture":
            unit = args[0] - GL_TEXTURE0
        elif fn == "glBindTexture" and len(args) == 2 and isinstance(args[1], int):
            bound[unit] = args[1]
    events.append({"kind": "leave", "function": "draw", "steps": ["draw"]})
    return events


def evidence(calls: list[tuple[str, list[Any]]], source: str = "") -> Evidence:
    return Evidence(
        "lab", frames=[{"events": replay(calls)}], state={"environment": 2}, source=source
    )


SOLUTION = [
    ("glActiveTexture", [GL_TEXTURE0 + 1]),
    ("glBindTexture", [GL_TEXTURE_2D, 2]),
    ("glTexParameteri", [GL_TEXTURE_2D, 0x2801, 0x2601]),
    ("glEnable", [0x0C60]),
    ("glActiveTexture", [GL_TEXTURE0]),
]


def hints(mine: list[tuple[str, list[Any]]]) -> Hints:
    lines = "\n" * 9 + "\n".join(f"{fn}({', '.join(map(str, args))})" for fn, args in mine)
    return Hints(evidence(mine, lines), evidence(SOLUTION), {"environment": "ENVIRONMENT"}, ())


def texts(found: Hints) -> list[str]:
    return [d.text for d in found.divergences("draw")]


def test_a_missing_call_is_asked_for_with_its_place():
    found = texts(hints([c for c in SOLUTION if c[0] != "glEnable"]))
    assert found and "draw() makes no glEnable(GL_TEXTURE_GEN_S) with unit 1 active" in found[0]
    assert "after glTexParameteri at line 12" in found[0]


def test_other_arguments_are_named_by_the_calls_own_names():
    changed = [*SOLUTION]
    changed[2] = ("glTexParameteri", [GL_TEXTURE_2D, 0x2801, 0x2600])
    (said,) = texts(hints(changed))
    assert said.startswith("glTexParameteri at line 12")
    assert "= GL_NEAREST (the solution's: GL_LINEAR)" in said


def test_a_parameter_set_before_its_texture_is_bound_is_out_of_order():
    moved = [SOLUTION[2], SOLUTION[0], SOLUTION[1], SOLUTION[3], SOLUTION[4]]
    (said,) = texts(hints(moved))
    assert said.startswith("in the wrong order: glTexParameteri at line 10")
    assert "comes before glBindTexture at line 12" in said
    assert said.endswith("it acts on the texture bound at that moment")


def test_an_order_that_matters_is_the_wrong_order():
    swapped = [SOLUTION[1], SOLUTION[0], *SOLUTION[2:]]
    found = texts(hints(swapped))
    assert any("in the wrong order" in t or "bound the texture on unit 0" in t for t in found)


def test_a_call_made_elsewhere_is_never_asked_for():
    """glEnable made before the unit is chosen: the hint says what it acted on, by its line,
    and asks for nothing the file made."""
    early = [SOLUTION[3], *SOLUTION[:3], SOLUTION[4]]
    found = hints(early)
    said = [found.guard(t) for t in texts(found)]
    assert said and not any(asked_and_made(found, t) for t in said), said
    assert any("line 10" in t for t in said), said


def asked_and_made(found: Hints, hint: str) -> list[str]:
    """The calls ``hint`` asks for that the file made with those arguments."""
    made = {c.text.replace(" ", "") for c in found.mine.calls if c.kind != "function"}
    return [
        f"{fn}({', '.join(args)})"
        for fn, args in suggested_calls(hint)
        if f"{fn}({','.join(args)})".replace(" ", "") in made
    ]


def shown(value: Any) -> str:
    """An argument as a hint writes it: an enum by its name, a number as ``:g`` does."""
    if isinstance(value, int) and value in NAMES:
        return NAMES[value]
    return f"{value:g}" if isinstance(value, int | float) else str(value)


CALLS = st.sampled_from(
    [
        ("glActiveTexture", [GL_TEXTURE0]),
        ("glActiveTexture", [GL_TEXTURE0 + 1]),
        ("glBindTexture", [GL_TEXTURE_2D, 2]),
        ("glBindTexture", [GL_TEXTURE_2D, 3]),
        ("glTexParameteri", [GL_TEXTURE_2D, 0x2801, 0x2601]),
        ("glTexParameteri", [GL_TEXTURE_2D, 0x2801, 0x2600]),
        ("glEnable", [0x0C60]),
        ("glEnable", [0x0C61]),
        ("glDisable", [0x0C60]),
        ("glOrtho", [-1.0, 1.0, -1.0, 1.0, 0.0, 15.0]),
    ]
)


@settings(max_examples=150, deadline=None)
@given(st.lists(CALLS, max_size=10), st.data())
def test_a_guarded_hint_never_asks_for_a_call_the_file_made(mine, data):
    """Any trace and any hint that asks for calls (among them ones the file made): once
    guarded, no call it asks for is one the file made with the same arguments."""
    found = hints(mine)
    asked = data.draw(st.lists(CALLS, min_size=1, max_size=3))
    hint = "; ".join(f"call {fn}({', '.join(map(shown, args))}) first" for fn, args in asked)
    for text in [hint, *texts(found)]:
        guarded = found.guard(text)
        assert not asked_and_made(found, guarded), (text, guarded)
        # what it quotes of the file is the file's own lines
        for quoted in QUOTED.findall(guarded):
            assert re.match(r"line \d+", quoted)
        assert all(m.group(1) for m in CALL_TEXT.finditer(guarded))


JSON = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats() | st.text(max_size=8),
    lambda inner: (
        st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=4), inner, max_size=3)
    ),
    max_leaves=8,
)


@settings(max_examples=100, deadline=None)
@given(
    st.lists(
        st.tuples(
            st.sampled_from(["glOrtho", "glBindTexture", "glVertex3fv", "draw_scene", "x"]), JSON
        ),
        max_size=8,
    )
)
def test_any_trace_a_file_can_make_gives_hints_not_errors(calls):
    """Arguments of any shape and size (the trace keeps what the file sent): the hints'
    reasoning never fails, it only says less."""
    mine = [(fn, args if isinstance(args, list) else [args]) for fn, args in calls]
    found = hints(mine)
    for text in texts(found):
        assert isinstance(found.guard(text), str)
    assert isinstance(found.never_called("draw"), str)
