"""The shipped meshes (OBJ files; README.md lists them). pyproject.toml maps this folder
into the package as ``mirrorlab.data.models`` (this file makes it one), so the wheel and
an editable install both find the meshes through ``mirrorlab.data.model_file``."""
