"""The stand-in for ``mirrorlab.labs.kit`` in the sandbox: ``kit.lab20()`` and the others
return the lab's object (its class in the lab's own ``student.py``, a
:class:`StudentLab`), whose drawing calls (the robot, the cone, the sphere) the checker
runs in its own context. The object holds the numbers a student may read (the frame's
size, the texture shader's name); the lab's answers are not among them."""

from __future__ import annotations

from types import ModuleType
from typing import Any

from .remote import LabSetupError, Remote, StudentShaderError


class StudentLab:
    """The base of every lab's object in the sandbox: the numbers the trusted side gave it
    as attributes, and the call every lab gives."""

    def __init__(self, remote: Remote, values: dict[str, Any]) -> None:
        self._remote = remote
        for key, value in values.items():
            setattr(self, key, tuple(value) if isinstance(value, list) else value)

    def _call(self, name: str, kinds: list[str], *args: Any) -> Any:
        return self._remote.call("kit", name, kinds, args)

    def load_picture_texture(self, texture_id: int, name: str) -> None:
        """Fill texture ``texture_id`` with the lab's picture ``name`` (mipmapped,
        repeating), on texture unit 0."""
        self._call("load_picture_texture", ["i", "s"], texture_id, name)


def build_kit(remote: Remote, description: dict, lab_object: type[StudentLab]) -> ModuleType:
    """The ``mirrorlab.labs.kit`` module of this run: ``kit.<lab>()`` for every registered
    lab (``description["labs"]``), the run's own returning its lab object (of the lab's
    class ``lab_object``, made once), the others saying the file asks for another lab."""
    lab = description["lab"]
    session = lab_object(remote, dict(description["kit"]))
    module = ModuleType("mirrorlab.labs.kit")

    def opener(name: str):
        def open_lab() -> StudentLab:
            if name != lab:
                raise LabSetupError(
                    f"this file is run as the {lab} lab, but it asks for kit.{name}()"
                )
            return session

        open_lab.__name__ = name
        return open_lab

    for name in description["labs"]:
        setattr(module, name, opener(name))
    for name, value in (
        ("LabSetupError", LabSetupError),
        ("StudentShaderError", StudentShaderError),
        ("ENV_UNIT", 1),
    ):
        setattr(module, name, value)
    return module
