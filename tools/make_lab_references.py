"""Re-make the labs' shipped reference evidence, mirrorlab/labs/<folder>/reference/:
what each lab's reference solution (labs/solutions/, teachers' only) shows for the lab's
own numbers, run through the trusted checker like any submission. A student's
``mirrorlab lab check`` judges against it where no solutions are at hand (a wheel).

    .venv/bin/python tools/make_lab_references.py [LAB ...]

tests/labs/test_boundary.py checks that the shipped evidence is what the solutions give now.
"""

from __future__ import annotations

import shutil
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from mirrorlab.labs import find_lab, lab_names  # noqa: E402
from mirrorlab.labs.content import reference_folder  # noqa: E402
from mirrorlab.labs.trusted.checker import (  # noqa: E402
    CHECK_SIZE,
    DEFAULT_LIMITS,
    make_reference,
    solution_source,
)
from mirrorlab.labs.trusted.variants import default_variant  # noqa: E402

SOLUTIONS = ROOT / "labs" / "solutions"


def main(names: list[str]) -> int:
    for name in names or list(lab_names()):
        spec = find_lab(name)
        evidence = make_reference(
            spec,
            default_variant(spec.name),
            solution_source(spec, SOLUTIONS),
            DEFAULT_LIMITS,
            CHECK_SIZE,
        )
        folder = reference_folder(spec)
        shutil.rmtree(folder, ignore_errors=True)
        evidence.save(folder)
        sizes = ", ".join(
            f"{p.name} {p.stat().st_size // 1024} KiB" for p in sorted(folder.iterdir())
        )
        print(f"{spec.name}: {folder} ({sizes})")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
