"""Where the labs' files are found (the top-level ``labs/`` folder of the checkout) until
they move into the package; shipped scenes, meshes and pictures are in
:mod:`mirrorlab.data`, shaders in :mod:`mirrorlab.shaders`."""

from __future__ import annotations

from pathlib import Path

PACKAGE_DIR = Path(__file__).resolve().parent
REPO_DIR = PACKAGE_DIR.parent
