"""The work of each command-line command (``mirrorlab.cli`` only parses arguments)."""
