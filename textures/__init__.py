"""The shipped pictures (PNG files; README.md lists them). pyproject.toml maps this folder
into the package as ``mirrorlab.data.textures`` (this file makes it one), so the wheel and
an editable install both find the pictures through ``mirrorlab.data.texture_file``."""
