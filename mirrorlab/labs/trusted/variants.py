"""Each student's own numbers for a lab (a variant), derived from the course key and the
student's name with HMAC-SHA256, so the teacher can derive them again and nobody without
the key can. The default variant is the lab's own numbers (the handout as published).

What a variant changes is what changes the answer; each lab's registry entry gives its
choices (:attr:`~mirrorlab.labs.LabSpec.options`) and its ``variant`` module what they
mean: for lab 20 the mirror's position and size (so glOrtho, gluLookAt and the quad's
corners) and the robot's pose; for the sphere-map lab the side the shader's cone goes
and the texture unit texgen uses (and the cone's tilt); for the cube-map lab the
sphere's centre, where the six cameras sit.
"""

from __future__ import annotations

import hashlib
import hmac
import json
import re
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mirrorlab.labs import find_lab

KEY_BYTES = 16
"""The shortest course key accepted."""


class VariantError(ValueError):
    """A key or variant file that cannot be used; one line naming it."""


@dataclass(frozen=True)
class Variant:
    """One set of a lab's numbers: ``values`` (one choice of each of the lab's
    :attr:`~mirrorlab.labs.LabSpec.options`), ``id`` (``default`` or 8 hex digits) and the
    ``student`` it was derived for ('' for the default)."""

    lab: str
    values: dict[str, Any] = field(compare=False)
    id: str = "default"
    student: str = ""

    @property
    def is_default(self) -> bool:
        return self.id == "default"

    def __getitem__(self, key: str) -> Any:
        return self.values[key]

    def plain(self) -> dict[str, Any]:
        return {
            "lab": self.lab,
            "id": self.id,
            "student": self.student,
            "values": dict(self.values),
        }

    def same_numbers(self, other: Variant) -> bool:
        return self.lab == other.lab and self.values == other.values


def default_variant(lab: str) -> Variant:
    """The lab's own numbers (its registry entry's defaults)."""
    return Variant(lab, dict(find_lab(lab).defaults))


def student_key(student: str) -> str:
    """The form of a name variants are derived from: case, spaces and punctuation do not
    matter ("Ada Lovelace", "ada_lovelace" and "ADA-LOVELACE" are one student)."""
    return re.sub(r"[^0-9a-z]+", "_", student.casefold()).strip("_")


def derive_variant(lab: str, key: bytes, student: str) -> Variant:
    """The variant of ``student`` for ``lab`` under the course ``key``."""
    digest = hmac.new(
        key, f"mirrorlab variant\0{lab}\0{student_key(student)}".encode(), hashlib.sha256
    ).digest()
    values = {}
    for index, (name, choices) in enumerate(find_lab(lab).options.items()):
        values[name] = choices[
            int.from_bytes(digest[2 * index : 2 * index + 2], "big") % len(choices)
        ]
    return Variant(lab, values, digest.hex()[:8], student)


def read_key(path: Path) -> bytes:
    """The course key in ``path`` (its bytes; at least :data:`KEY_BYTES`)."""
    try:
        key = path.read_bytes()
    except OSError as exc:
        raise VariantError(f"--key: cannot read {str(path)!r}: {exc.strerror}") from None
    if len(key.strip()) < KEY_BYTES:
        raise VariantError(
            f"--key: {str(path)!r} holds {len(key.strip())} bytes; a course "
            f"key needs at least {KEY_BYTES} (mirrorlab lab release makes one)"
        )
    return key.strip()


def variant_from_file(path: Path, lab: str) -> Variant:
    """The variant a released folder's ``variant.json`` names (checked against the lab's
    options: a hand-edited file cannot ask for numbers outside them)."""
    try:
        data = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, ValueError) as exc:
        raise VariantError(f"{path}: not a variant file ({exc})") from None
    return variant_from_plain(data, lab, str(path))


def variant_from_plain(data: Any, lab: str, where: str) -> Variant:
    """The variant ``data`` (:meth:`Variant.plain`'s form, read from ``where``) names,
    checked against ``lab``'s options; VariantError (one line naming ``where``) when it is
    not one of them."""
    if not isinstance(data, dict) or data.get("lab") != lab:
        other = data.get("lab") if isinstance(data, dict) else None
        raise VariantError(f"{where}: a variant of {other!r}, not of {lab}")
    values = data.get("values")
    options = find_lab(lab).options
    if not isinstance(values, dict) or set(values) != set(options):
        raise VariantError(f"{where}: expected the values {', '.join(options)}")
    for name, value in values.items():
        if value not in options[name]:
            raise VariantError(
                f"{where}: {name} = {value!r} is not one of {', '.join(map(str, options[name]))}"
            )
    ident = str(data.get("id", ""))
    if not re.fullmatch(r"default|[0-9a-f]{8}", ident):
        raise VariantError(f"{where}: id {ident!r} is not a variant id")
    if ident == "default" and values != dict(find_lab(lab).defaults):
        raise VariantError(f"{where}: the default variant with numbers of its own")
    return Variant(lab, dict(values), ident, str(data.get("student", ""))[:200])


HEADER = "# mirrorlab variant: "
"""The first line of every starter ``lab start`` and ``lab release`` write: the variant's
numbers (:meth:`Variant.plain` as one line of JSON), which ``lab check`` reads when the
file is checked away from its ``variant.json``. ``lab grade`` never reads it: a variant
follows from the course key and the student's name there."""
HEADER_LINES = 5
"""How far down a file the header may have moved (a shebang or coding line above it)."""


def header_line(variant: Variant) -> str:
    """The header of a starter of ``variant`` (one line, with its newline)."""
    return f"{HEADER}{json.dumps(variant.plain(), separators=(', ', ': '))}\n"


def variant_from_header(text: str, lab: str, where: str) -> Variant | None:
    """The variant a file's header names (:data:`HEADER`), None when it has none;
    VariantError (one line) when the line is there but names no variant of ``lab``."""
    for number, line in enumerate(text.splitlines()[:HEADER_LINES], 1):
        if line.startswith(HEADER):
            try:
                data = json.loads(line[len(HEADER) :])
            except ValueError as exc:
                raise VariantError(
                    f"{where}: line {number}, its variant line, is not one ({exc}); take it "
                    f"again from the starter you were given"
                ) from None
            return variant_from_plain(data, lab, f"{where}, line {number}")
    return None
