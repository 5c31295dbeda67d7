"""Runs one student's lab file in the sandbox, as the trusted checker directs.

``python -I -S runner.py`` (the checker starts it so, in the sandbox, with this package's
folder on the path), the pipe to the checker on its stdin and stdout: what the student's
file prints goes to stderr. The checker first sends the session (the
lab, the file, the lab's own student side, the names and values of OpenGL, the lab
object's values), then commands:
``load`` (execute the file), ``call`` (one of the lab's functions), ``exit``; the runner
says ``ready`` before the student's code runs. Each command
ends with a ``done`` message carrying the errors the student's code raised (the function,
the student's line, the message); everything else that passes is the calls themselves.
"""

from __future__ import annotations

import importlib.util
import os
import sys
import traceback
from types import ModuleType
from typing import Any

from .gl import build_modules
from .kit_standin import build_kit
from .remote import Remote, StudentShaderError
from .wire import Channel


class StudentFailure(Exception):
    """A lab function raised; the error is already recorded."""


class Run:
    """The student's file and the errors its functions raised, once per function."""

    def __init__(self, channel: Channel, path: str, functions: list[str]) -> None:
        self.channel, self.path, self.functions = channel, path, functions
        self.errors: list[dict[str, Any]] = []

    def error(self, function: str, kind: str, message: str, line: int = 0) -> None:
        if not any(e["function"] == function for e in self.errors):
            self.errors.append(
                {"function": function, "kind": kind, "message": message[:300], "line": int(line)}
            )

    def exception(self, function: str, exc: BaseException) -> None:
        line = 0
        for frame in traceback.extract_tb(exc.__traceback__):
            if frame.filename == self.path:
                line = frame.lineno or 0
        if isinstance(exc, StudentShaderError):
            self.error(function, "glsl", str(exc), line)
            return
        message = f"{type(exc).__name__}: {exc}" if str(exc) else type(exc).__name__
        self.error(function, "exception", message, line)

    def load(self) -> dict[str, Any] | None:
        try:
            with open(self.path, encoding="utf-8") as stream:
                source = stream.read()
        except (OSError, UnicodeDecodeError) as exc:
            self.error("<file>", "unreadable", f"cannot read the file: {exc}")
            return None
        try:
            code = compile(source, self.path, "exec")
        except SyntaxError as exc:
            self.error("<file>", "syntax", f"SyntaxError: {exc.msg}", exc.lineno or 0)
            return None
        namespace: dict[str, Any] = {"__name__": "student_lab", "__file__": self.path}
        try:
            exec(code, namespace)
        except BaseException as exc:
            self.exception("<file>", exc)
            return None
        self.wrap(namespace)
        return namespace

    def wrap(self, namespace: dict[str, Any]) -> None:
        """Each lab function, noting its start and end to the checker and recording an
        error once, at the function that raised; a missing one records so."""
        for name in self.functions:
            original = namespace.get(name)
            if not callable(original):
                problem = (
                    "is missing"
                    if original is None
                    else f"is a {type(original).__name__}, not a function"
                )
                self.error(
                    name, "missing", f"{name}() {problem}: define def {name}(): as in the starter"
                )

                def missing(*args: Any, _name: str = name, **kwargs: Any) -> None:
                    self.channel.send({"op": "enter", "function": _name, "line": 0})
                    self.channel.send({"op": "leave", "function": _name, "raised": True})
                    raise StudentFailure(_name)

                namespace[name] = missing
                continue

            def wrapper(
                *args: Any, _name: str = name, _original: Any = original, **kwargs: Any
            ) -> Any:
                caller = sys._getframe(1)
                line = caller.f_lineno if caller.f_code.co_filename == self.path else 0
                self.channel.send({"op": "enter", "function": _name, "line": line})
                raised = False
                try:
                    return _original(*args, **kwargs)
                except StudentFailure:
                    raised = True
                    raise
                except BaseException as exc:
                    raised = True
                    self.exception(_name, exc)
                    raise StudentFailure(_name) from None
                finally:
                    self.channel.send({"op": "leave", "function": _name, "raised": raised})

            namespace[name] = wrapper


def student_side(labs: ModuleType) -> dict[str, ModuleType]:
    """This package under the name a lab's ``student.py`` imports it by,
    ``mirrorlab.labs.student`` (and its modules), so that a lab's object is written as
    any module of mirrorlab is, yet runs on this package alone."""
    package = sys.modules[__package__ or "labstudent"]
    found = {"mirrorlab.labs.student": package}
    for name, module in list(sys.modules.items()):
        if name.startswith(f"{package.__name__}."):
            found[f"mirrorlab.labs.student.{name.split('.', 1)[1]}"] = module
    labs.__dict__["student"] = package
    return found


def load_lab_side(path: str) -> ModuleType:
    """The lab's own student side (its ``student.py``, which the checker gives read-only at
    ``path``), whose ``LAB_OBJECT`` is the class of ``kit.<lab>()``."""
    spec = importlib.util.spec_from_file_location("lab_side", path)
    if spec is None or spec.loader is None:
        raise ImportError(f"the lab's student side {path!r} cannot be loaded")
    module = importlib.util.module_from_spec(spec)
    sys.modules["lab_side"] = module
    spec.loader.exec_module(module)
    return module


def install(modules: dict[str, ModuleType]) -> None:
    for name, module in modules.items():
        sys.modules[name] = module


def main(argv: list[str]) -> int:
    # the pipe keeps stdin and stdout; the names 0 and 1 become an empty input and stderr
    channel = Channel(os.dup(0), os.dup(1))
    empty = os.open(os.devnull, os.O_RDONLY)
    os.dup2(empty, 0)
    os.close(empty)
    os.dup2(2, 1)
    description, given = channel.receive()
    path = description["file"]
    if given:  # the file came with the session (the runner started before it was known)
        with open(path, "wb") as stream:
            stream.write(given[0][2])
    remote = Remote(channel, path, {int(k): v for k, v in description["pixel_types"].items()})
    modules = build_modules(remote, description)
    package, labs = ModuleType("mirrorlab"), ModuleType("mirrorlab.labs")
    package.__path__, labs.__path__ = [], []
    package.__dict__["labs"] = labs
    install({"mirrorlab": package, "mirrorlab.labs": labs, **student_side(labs)})
    kit = build_kit(remote, description, load_lab_side(description["lab_side"]).LAB_OBJECT)
    labs.__dict__["kit"] = kit
    install({**modules, "mirrorlab.labs.kit": kit})
    run = Run(channel, path, list(description["functions"]))
    channel.send({"op": "ready"})
    namespace: dict[str, Any] | None = None
    while True:
        command, _ = channel.receive()
        op = command.get("op")
        run.errors = []
        ok = False
        declared: dict[str, str] = {}
        if op == "load":
            namespace = run.load()
            ok = namespace is not None
            for name in description.get("declared", []):
                value = (namespace or {}).get(name)
                if isinstance(value, str):
                    declared[name] = value
        elif op == "call" and namespace is not None:
            try:
                namespace[command["function"]]()
                ok = True
            except StudentFailure:
                ok = False
        elif op == "exit":
            sys.stdout.flush()
            sys.stderr.flush()
            os._exit(0)
        channel.send({"op": "done", "ok": ok, "errors": run.errors, "declared": declared})


if __name__ == "__main__":  # pragma: no cover - the checker starts it with -c
    sys.exit(main(sys.argv[1:]))
