"""The labs and their registry. Each lab is one package (``mirrorlab/labs/<folder>/`` for
the shipped ones) that registers its :class:`LabSpec` with :func:`register` when imported:

- ``__init__.py``: the spec (tasks, the student's functions, the variants' choices);
- ``student.py``: the lab object of the sandbox (imports only the standard library, numpy
  and :mod:`mirrorlab.labs.student`);
- ``trusted.py``: the lab's session (its given drawing in the checker's GL context), its
  kit calls as the executor runs them, what the checker observes after the frames, the
  calls it leaves out, and what a variant's numbers write into its templates;
- ``judge.py``: each task's verdict and hint from the evidence;
- ``handout.md``, ``starter.py`` (templates) and ``reference/`` (its reference solution's
  evidence for the lab's own numbers), shipped as package data.

The teacher's solution is not in the package: :attr:`LabSpec.solution` names where it is
(the repository's ``labs/solutions/`` for the shipped labs). The shared machinery asks
the registry: :mod:`mirrorlab.labs.student` runs in the sandbox with the student's file
(stand-ins for OpenGL, GLU and the kit), :mod:`mirrorlab.labs.trusted` runs outside (the
sandbox, the executor of the student's calls, the checker, grading, release, reports).

Importing this package loads no OpenGL.
"""

from __future__ import annotations

import importlib
import sys
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType
from typing import Any


@dataclass(frozen=True)
class Task:
    """One task of a lab: its number and id, the function of the student's file it lives
    in, and a title."""

    number: int
    id: str
    function: str
    title: str

    @property
    def name(self) -> str:
        """The task's one name, in hints, reports, CSVs and HTML alike: its number in the
        handout and its id, ``task 1 (capture_camera)``."""
        return f"task {self.number} ({self.id})"


@dataclass(frozen=True)
class LabSpec:
    """A lab's registry entry: ``name`` (what the command line takes), ``folder`` (its
    package's folder name and its solution's file name, also accepted on the command
    line), the functions the student's file defines (``setup`` run once, then ``frame``
    every frame), its tasks in the handout's order, ``options`` (each variant value's
    choices) and ``defaults`` (the lab's own numbers), ``declared`` (module-level strings
    of the student's file the checker judges even when a frame never draws them: the
    GLSL of the lab's shaders), ``package`` (the dotted name of the lab's package, whose
    folder ``home`` holds its modules and content) and ``solution`` (the teacher's
    solution file; it may not exist, as outside a checkout)."""

    name: str
    folder: str
    title: str
    setup: tuple[str, ...]
    frame: str
    functions: tuple[str, ...]
    tasks: tuple[Task, ...]
    package: str
    home: Path
    solution: Path
    options: dict[str, tuple[Any, ...]] = field(default_factory=dict, compare=False)
    defaults: dict[str, Any] = field(default_factory=dict, compare=False)
    declared: tuple[str, ...] = ()

    def module(self, part: str) -> ModuleType:
        """The lab's module ``part`` (``trusted``, ``judge``); imports it (``trusted``
        imports OpenGL)."""
        return importlib.import_module(f"{self.package}.{part}")

    @property
    def student_file(self) -> Path:
        """The lab's student side (``student.py``), which the sandbox is given read-only."""
        return self.home / "student.py"

    @property
    def import_root(self) -> Path:
        """The folder on ``sys.path`` the lab's package is imported from (what another
        process adds to its path to import it)."""
        return self.home.parents[self.package.count(".")]

    def task(self, task_id: str) -> Task:
        return next(t for t in self.tasks if t.id == task_id)

    def task_name(self, task_id: str) -> str:
        """The name of the task ``task_id`` (:attr:`Task.name`), for a hint that points to
        it."""
        return self.task(task_id).name


_REGISTRY: dict[str, LabSpec] = {}


def register(spec: LabSpec) -> LabSpec:
    """Add ``spec`` to the labs: ``lab start``, ``check``, ``run``, ``release``,
    ``solution`` and ``grade`` take it from then on. ValueError when its name or folder
    is another lab's."""
    for other in _REGISTRY.values():
        if spec.name in (other.name, other.folder) or spec.folder in (other.name, other.folder):
            raise ValueError(f"lab {spec.name!r} ({spec.folder}) is registered already")
    missing = set(spec.defaults) ^ set(spec.options)
    if missing:
        raise ValueError(f"lab {spec.name!r}: options and defaults differ on {sorted(missing)}")
    _REGISTRY[spec.name] = spec
    return spec


def unregister(name: str) -> None:
    """Remove the lab ``name`` (tests that register one of their own)."""
    spec = _REGISTRY.pop(name, None)
    if spec is not None:
        for module in [
            m for m in sys.modules if m == spec.package or m.startswith(spec.package + ".")
        ]:
            del sys.modules[module]


def labs() -> tuple[LabSpec, ...]:
    """The registered labs, in the order they were registered."""
    return tuple(_REGISTRY.values())


def lab_names() -> tuple[str, ...]:
    """The registered labs' names (what the command line takes)."""
    return tuple(_REGISTRY)


def task_name(lab: str, task_id: str) -> str:
    """The name of ``lab``'s task ``task_id`` (``task 8 (passes)``): how a hint points to
    another task, so that hints, CSVs and reports name a task one way."""
    return find_lab(lab).task_name(task_id)


def find_lab(name: str) -> LabSpec:
    """The lab called ``name`` (``lab20``, ``spheremap``, ``cubemap``, a registered lab's
    name, or a folder name such as ``lab20_mirror``); ValueError naming the choices
    otherwise."""
    folder = name.rstrip("/").split("/")[-1]
    for spec in _REGISTRY.values():
        if name == spec.name or folder == spec.folder:
            return spec
    choices = ", ".join([*_REGISTRY, *(spec.folder for spec in _REGISTRY.values())])
    raise ValueError(f"LAB: unknown lab {name!r}; expected one of {choices}")


def load_lab(name: str, package: str, import_root: str) -> LabSpec:
    """The lab ``name`` in another process (the checker's GL process): its ``package``
    imported from ``import_root`` first when it is not registered here."""
    if name not in _REGISTRY:
        if import_root not in sys.path:
            sys.path.append(import_root)
        importlib.import_module(package)
    return find_lab(name)


SHIPPED = ("lab20_mirror", "lab_spheremap", "lab_cubemap")
"""The labs mirrorlab ships, each a package of this one (registered on import)."""

for _folder in SHIPPED:
    importlib.import_module(f"{__name__}.{_folder}")
