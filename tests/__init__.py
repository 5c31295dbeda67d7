import os
from pathlib import Path

REPO_DIR = Path(__file__).resolve().parents[1]
"""The checkout the tests run from (its bench/ scripts, tools/ and docs/)."""

if os.environ.get("MIRRORLAB_TEST_TWINS"):  # a run with copies of techniques: tests/twins.py
    from tests.twins import register_from_environment

    register_from_environment()

MACOS_CONTEXT = {
    "MESA_GL_VERSION_OVERRIDE": "4.1FC",
    "MESA_GLSL_VERSION_OVERRIDE": "410",
    "MESA_EXTENSION_OVERRIDE": " ".join(
        f"-GL_{name}"
        for name in (
            "ARB_shader_draw_parameters",
            "ARB_multi_draw_indirect",
            "ARB_base_instance",
            "ARB_shading_language_420pack",
            "ARB_shader_storage_buffer_object",
            "ARB_compute_shader",
            "ARB_buffer_storage",
            "ARB_clear_texture",
            "ARB_copy_image",
            "ARB_texture_view",
            "MESA_pack_invert",
        )
    ),
}
"""The environment in which Mesa simulates macOS's forward-compatible OpenGL 4.1 core
context (DESIGN.md; ``./dev test-macos`` sets the same): with 4.1FC every context Mesa
makes is 4.1 core, without the extensions macOS lacks."""
