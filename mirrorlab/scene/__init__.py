"""Scene description in numpy: graph, meshes, the lab scene. No OpenGL here."""
