"""``mirrorlab bench speed`` with pyrender beside it, from a clone.

Run from the repository root (``./dev bench speed`` does the set-up)::

    python bench/speed.py [mirrorlab bench speed's options]

pyrender needs an environment of its own (its PyOpenGL pin conflicts with mirrorlab's, and
its last release needs numpy < 2). This script makes it once, as ``.venv-pyrender`` in the
clone, then runs ``mirrorlab bench speed --pyrender .venv-pyrender/bin/python`` with the
options given. The benchmark itself is :mod:`mirrorlab.benchmarks.speed`.
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from mirrorlab.benchmarks.speed import PYRENDER_PACKAGES
from mirrorlab.cli import main

PYRENDER_VENV = Path(__file__).resolve().parent.parent / ".venv-pyrender"


def pyrender_python() -> Path:
    """The pyrender environment's interpreter, made (once) with pip when missing."""
    python = PYRENDER_VENV / "bin" / "python"
    stamp = PYRENDER_VENV / ".installed"
    wanted = " ".join(PYRENDER_PACKAGES)
    if not stamp.exists() or stamp.read_text() != wanted:
        print(
            f"[speed] making pyrender's environment in {PYRENDER_VENV} "
            f"({', '.join(PYRENDER_PACKAGES)})",
            file=sys.stderr,
            flush=True,
        )
        steps = {
            "python -m venv": [sys.executable, "-m", "venv", "--clear", str(PYRENDER_VENV)],
            "pip install " + wanted: [
                str(python),
                "-m",
                "pip",
                "install",
                "-q",
                "--disable-pip-version-check",
                *PYRENDER_PACKAGES,
            ],
        }
        for name, command in steps.items():
            if subprocess.run(command).returncode != 0:
                raise SystemExit(
                    f"speed.py: error: could not make pyrender's environment "
                    f"in {PYRENDER_VENV}: {name} failed"
                )
        stamp.write_text(wanted)
    return python


if __name__ == "__main__":
    arguments = sys.argv[1:]
    if "--from-csv" not in arguments and "--pyrender" not in arguments:
        arguments += ["--pyrender", str(pyrender_python())]
    sys.exit(main(["bench", "speed", *arguments]))
