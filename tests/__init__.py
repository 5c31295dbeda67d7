from pathlib import Path

REPO_DIR = Path(__file__).resolve().parents[1]
"""The checkout the tests run from (its bench/ scripts, tools/ and docs/)."""
