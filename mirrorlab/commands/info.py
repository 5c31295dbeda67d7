"""``mirrorlab info``: what a bug report needs, one line each: the operating system,
Python, mirrorlab and the libraries it draws with, the OpenGL mirrorlab chose (backend,
PyOpenGL's platform, version, profile, GLSL, renderer, vendor) and the scene drawer's draw
path on it, EGL and the display, the labs' sandbox (bubblewrap and its version, or the
fallback and why) and their scratch space, and the variables that change any of these.

It makes one offscreen context, as ``render`` does, and says so in one line when it cannot
(render's line); the exit status is then 1 (a problem with the machine), else 0.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
from importlib import metadata
from typing import Any

NAME = "info"
VARIABLES = (
    "MIRRORLAB_GL_BACKEND",
    "MIRRORLAB_GL_CORE",
    "MIRRORLAB_SANDBOX",
    "PYOPENGL_PLATFORM",
    "EGL_PLATFORM",
    "DISPLAY",
    "WAYLAND_DISPLAY",
    "MESA_GL_VERSION_OVERRIDE",
    "MESA_GLSL_VERSION_OVERRIDE",
    "MESA_EXTENSION_OVERRIDE",
    "LIBGL_ALWAYS_SOFTWARE",
    "GALLIUM_DRIVER",
)
"""The environment variables that change what mirrorlab or its OpenGL does."""
PACKAGES = ("PyOpenGL", "PyOpenGL-accelerate", "glfw", "numpy", "Pillow", "trimesh")


def add_parser(commands: argparse._SubParsersAction) -> None:
    """The ``info`` command, as a subcommand of ``commands``."""
    info = commands.add_parser(
        NAME,
        help="print what a bug report needs: OS, Python, versions, the OpenGL chosen, "
        "the labs' sandbox",
        description="Print the system, Python, mirrorlab's version, the OpenGL mirrorlab "
        "chooses (backend, version, profile, renderer, draw path), EGL and the display, "
        "and the labs' sandbox. Paste it into a bug report. Exit status 1 when no OpenGL "
        "context can be made here (the output says why).",
    )
    info.add_argument("--json", action="store_true", help="print it as one JSON object")


def _system() -> str:
    found = f"{platform.system()} {platform.release()} ({platform.machine()})"
    if sys.platform.startswith("linux"):
        try:
            found += f", {platform.freedesktop_os_release()['PRETTY_NAME']}"
        except (OSError, KeyError):
            pass
    elif sys.platform == "darwin":
        found += f", macOS {platform.mac_ver()[0]}"
    elif sys.platform == "win32":
        found += f", {platform.win32_ver()[1]}"
    return found


def _version(package: str) -> str:
    try:
        return metadata.version(package)
    except metadata.PackageNotFoundError:
        return "not installed"


def _egl() -> str:
    from mirrorlab.gl.context import system_platform

    if system_platform(sys.platform) != "linux":
        return f"not used on {sys.platform} (offscreen frames use a hidden window)"
    import ctypes

    try:
        ctypes.CDLL("libEGL.so.1")
    except OSError as exc:
        return f"libEGL.so.1 cannot be loaded ({exc})"
    return "libEGL.so.1 loads"


def _display() -> str:
    from mirrorlab.gl.context import system_platform

    if system_platform(sys.platform) != "linux":
        return "the desktop's own"
    shown = os.environ.get("DISPLAY", "")
    return f"DISPLAY={shown}" if shown else "none (DISPLAY is not set)"


def _opengl() -> tuple[dict[str, str], str]:
    """What the offscreen context mirrorlab makes here is, or ({}, the one line saying why
    there is none)."""
    from mirrorlab.errors import GLContextError
    from mirrorlab.gl.context import describe, offscreen_context

    try:
        context = offscreen_context()
    except GLContextError as exc:
        return {}, str(exc)
    try:
        return describe(context), ""
    finally:
        context.release()


def _sandbox() -> dict[str, str]:
    import shutil

    from mirrorlab.labs.trusted import sandbox
    from mirrorlab.labs.trusted.scratch import SCRATCH_FILES, SCRATCH_MB, scratch_kind

    mode = sandbox.sandbox_mode()
    bwrap = shutil.which("bwrap")
    version = ""
    if bwrap is not None:
        try:
            done = subprocess.run([bwrap, "--version"], capture_output=True, text=True, timeout=30)
            version = done.stdout.strip() or done.stderr.strip()
        except (OSError, subprocess.SubprocessError) as exc:
            version = f"does not run ({exc})"
    if mode == "bwrap":
        how = "bubblewrap: lab files run sandboxed"
    else:
        how = (
            f"none ({sandbox.unsandboxed_reason()}): lab files run "
            f"{sandbox.unsandboxed_how()}; lab grade needs --unsandboxed"
        )
    kind = scratch_kind(mode)
    scratch = f"{kind}: at most {SCRATCH_MB} MiB and {SCRATCH_FILES} files and folders a run" + (
        ", a file system of its own that the kernel bounds"
        if kind == "tmpfs"
        else ", measured while it runs (no mount namespace here)"
    )
    return {
        "sandbox": how,
        "bubblewrap": f"{bwrap} ({version})" if bwrap else "not installed",
        "scratch": scratch,
    }


def gather() -> tuple[dict[str, Any], bool]:
    """Everything :func:`run` prints, and whether an OpenGL context was made."""
    # as the user set them, before mirrorlab's GL layer sets PyOpenGL's platform
    environment = {key: os.environ[key][:160] for key in VARIABLES if key in os.environ}
    from mirrorlab import __version__
    from mirrorlab.errors import GLContextError
    from mirrorlab.gl.context import choose
    from mirrorlab.labs import lab_names

    found: dict[str, Any] = {
        "mirrorlab": __version__,
        "system": _system(),
        "python": f"{platform.python_version()} ({platform.python_implementation()}, "
        f"{sys.executable})",
        "packages": {name: _version(name) for name in PACKAGES},
    }
    try:
        choice = choose("offscreen")
        found["chosen"] = (
            f"backend {choice.backend}, PyOpenGL platform {choice.platform}, "
            f"{'OpenGL 4.1 core asked for' if choice.core else 'any profile'}"
        )
    except GLContextError as exc:
        found["chosen"] = f"none: {exc}"
    opengl, why = _opengl()
    found["opengl"] = opengl if opengl else {"error": why}
    found["egl"] = _egl()
    found["display"] = _display()
    found.update(_sandbox())
    found["labs"] = ", ".join(lab_names())
    found["environment"] = environment
    return found, bool(opengl)


def lines(found: dict[str, Any]) -> list[str]:
    """:func:`gather`'s answer as the lines ``mirrorlab info`` prints."""
    opengl = found["opengl"]
    out = [
        f"mirrorlab   {found['mirrorlab']}",
        f"system      {found['system']}",
        f"python      {found['python']}",
        "packages    " + ", ".join(f"{k} {v}" for k, v in found["packages"].items()),
        f"chosen      {found['chosen']}",
    ]
    if "error" in opengl:
        out.append(f"OpenGL      none: {opengl['error']}")
    else:
        out += [
            f"OpenGL      {opengl['version']}",
            f"profile     {opengl['profile']} (GLSL {opengl['glsl']})",
            f"renderer    {opengl['renderer']} ({opengl['vendor']})",
            f"backend     {opengl['backend']} (PyOpenGL platform {opengl['platform']})",
            f"draw path   {opengl['draw_path']}"
            + (
                " (one multi-draw a pass)"
                if opengl["draw_path"] == "packed"
                else " (one draw call at a time: OpenGL below 4.3)"
            ),
        ]
    out += [
        f"EGL         {found['egl']}",
        f"display     {found['display']}",
        f"sandbox     {found['sandbox']}",
        f"bubblewrap  {found['bubblewrap']}",
        f"scratch     {found['scratch']}",
        f"labs        {found['labs']}",
    ]
    environment = found["environment"]
    out.append(
        "environment "
        + (", ".join(f"{k}={v}" for k, v in environment.items()) if environment else "(none set)")
    )
    return out


def run(args: argparse.Namespace) -> int:
    """``mirrorlab info``: 0 when an OpenGL context was made, 1 when not (said why)."""
    found, made = gather()
    if args.json:
        print(json.dumps(found, indent=2))
    else:
        print("\n".join(lines(found)))
    return 0 if made else 1
