"""Recording a stretch of GL calls to replay them: code that would issue exactly the same
calls again (a still frame, drawn by the same renderer into the same target) replays the
list instead of working it out once more.

:class:`CallRecorder` records, while it is entered, every call made through PyOpenGL's
``GL`` namespace and mirrorlab's raw entry points (:data:`mirrorlab.gl.opengl.RAW`), with
its arguments, and still makes each call: what is recorded is what ran. The arguments
are kept as they were given, so whoever records must not change an array it passed
afterwards (mirrorlab's passes hand GL fresh or read-only arrays). :func:`replay` makes
the calls again, in order, ignoring what they return; errors surface at the next
checked call or pass check (:func:`mirrorlab.gl.context.check_gl_errors`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from functools import lru_cache
from types import ModuleType, SimpleNamespace
from typing import Any

from mirrorlab.gl.opengl import GL, RAW

Call = tuple[Callable[..., Any], tuple, dict]


@lru_cache(maxsize=1)
def _gl_names() -> tuple[str, ...]:
    return tuple(name for name in dir(GL) if name.startswith("gl") and callable(getattr(GL,
                                                                                       name)))


def _changes_state(name: str) -> bool:
    """Whether a call can change GL state: queries (``glGet*``, ``glIs*``) cannot, and are
    not recorded (a replayed ``glGetError`` would swallow an error the replay made)."""
    return not name.startswith(("glGet", "glIs"))


class CallRecorder:
    """``with CallRecorder() as recorder:`` records every GL call made inside that can
    change GL state into ``recorder.calls`` (a list of ``(function, args, kwargs)``)."""

    def __init__(self) -> None:
        self.calls: list[Call] = []
        self._patched: list[tuple[ModuleType | SimpleNamespace, str, Any]] = []

    def __enter__(self) -> CallRecorder:
        calls = self.calls
        targets: list[tuple[ModuleType | SimpleNamespace, Sequence[str]]] = [
            (GL, _gl_names()), (RAW, tuple(vars(RAW)))]
        for namespace, names in targets:
            for name in names:
                if not _changes_state(name):
                    continue
                function = getattr(namespace, name)

                def recorded(*args, _function=function, **kwargs):
                    calls.append((_function, args, kwargs))
                    return _function(*args, **kwargs)

                self._patched.append((namespace, name, function))
                setattr(namespace, name, recorded)
        return self

    def __exit__(self, *exc: object) -> None:
        for namespace, name, function in reversed(self._patched):
            setattr(namespace, name, function)
        self._patched.clear()


def replay(calls: Sequence[Call]) -> None:
    """Make ``calls`` again, in order."""
    for function, args, kwargs in calls:
        function(*args, **kwargs)
