"""``python -m mirrorlab``: the same command line as ``mirrorlab``."""

import sys

from mirrorlab.cli import main

if __name__ == "__main__":
    sys.exit(main())
