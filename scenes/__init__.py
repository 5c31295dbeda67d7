"""The shipped scene files (TOML; docs/scenes.md describes them). pyproject.toml maps this
folder into the package as ``mirrorlab.data.scenes`` (this file makes it one), so the
wheel and an editable install both find the scenes through ``mirrorlab.data.scenes_dir``.
A scene's meshes and pictures are named relative to its file (``../models/base.obj``):
the three folders sit side by side in the checkout and in the wheel alike."""
