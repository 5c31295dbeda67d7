"""The context chooser's decision (:func:`mirrorlab.gl.context.choose_backend`): a pure
function of the operating system, what the machine offers and the two variables. No GL is
loaded here; the contexts themselves are tested in tests/gl and tests/window."""

from __future__ import annotations

import pytest

from mirrorlab.errors import GLContextError
from mirrorlab.gl.context import (
    BACKEND_VARIABLE,
    CORE_VARIABLE,
    Choice,
    choose_backend,
    system_platform,
)


def offscreen(
    system: str,
    *,
    egl: bool = True,
    display: bool = True,
    bound: str | None = None,
    environ: dict[str, str] | None = None,
) -> Choice:
    return choose_backend(
        "offscreen", system, egl=egl, display=display, environ=environ or {}, bound=bound
    )


@pytest.mark.parametrize(
    "system, kind",
    [("linux", "linux"), ("win32", "nt"), ("darwin", "darwin"), ("freebsd14", "linux")],
)
def test_the_opengl_system_follows_sys_platform(system, kind):
    assert system_platform(system) == kind


@pytest.mark.parametrize(
    "egl, display, backend, platform",
    [
        (True, True, "egl", "egl"),
        (True, False, "egl", "egl"),
        (False, True, "hidden-window", "glx"),
    ],
)
def test_linux_offscreen_takes_egl_when_it_loads_else_a_hidden_window(
    egl, display, backend, platform
):
    assert offscreen("linux", egl=egl, display=display) == Choice(backend, platform, False)


def test_linux_without_egl_and_display_names_both_ways_out_in_one_line():
    with pytest.raises(GLContextError) as caught:
        offscreen("linux", egl=False, display=False)
    message = str(caught.value)
    assert "\n" not in message
    assert "libEGL.so.1 cannot be loaded" in message and "DISPLAY is not set" in message
    assert "libegl1" in message and "xvfb-run -a" in message


@pytest.mark.parametrize(
    "system, platform, core", [("win32", "nt", False), ("darwin", "darwin", True)]
)
@pytest.mark.parametrize("egl", [True, False])
def test_macos_and_windows_render_offscreen_in_a_hidden_window(system, platform, core, egl):
    # what a probe of libEGL.so.1 says does not matter there: EGL is never tried
    assert offscreen(system, egl=egl) == Choice("hidden-window", platform, core)


@pytest.mark.parametrize(
    "system, platform", [("linux", "glx"), ("win32", "nt"), ("darwin", "darwin")]
)
def test_a_window_is_a_window_whatever_the_backend_variable_says(system, platform):
    for forced in ("", "auto", "egl", "hidden-window"):
        choice = choose_backend(
            "window", system, egl=True, display=True, environ={BACKEND_VARIABLE: forced}
        )
        assert choice == Choice("window", platform, system == "darwin")


def test_a_window_on_linux_needs_a_display():
    with pytest.raises(
        GLContextError,
        match=r"^no display for a window \(DISPLAY is not "
        r"set\); run it on a desktop or under "
        r"'xvfb-run -a'",
    ):
        choose_backend("window", "linux", egl=True, display=False, environ={})


@pytest.mark.parametrize(
    "forced, egl, display, backend",
    [
        ("egl", True, True, "egl"),
        ("EGL", True, False, "egl"),
        ("egl", False, True, "egl"),  # forced: the library's own error comes when it is made
        ("hidden-window", True, True, "hidden-window"),
        (" hidden-window ", False, True, "hidden-window"),
        ("auto", True, True, "egl"),
        ("", False, True, "hidden-window"),
    ],
)
def test_the_backend_variable_forces_the_offscreen_backend(forced, egl, display, backend):
    choice = offscreen("linux", egl=egl, display=display, environ={BACKEND_VARIABLE: forced})
    assert choice.backend == backend
    assert choice.platform == ("egl" if backend == "egl" else "glx")


def test_a_keyword_overrides_the_variable():
    choice = choose_backend(
        "offscreen",
        "linux",
        egl=True,
        display=True,
        environ={BACKEND_VARIABLE: "egl", CORE_VARIABLE: "0"},
        backend="hidden-window",
        core=True,
    )
    assert choice == Choice("hidden-window", "glx", True)


@pytest.mark.parametrize("value", ["glx", "window", "osmesa", "1", "hidden_window"])
def test_an_unknown_backend_is_one_line_naming_the_variable_and_the_values(value):
    with pytest.raises(GLContextError) as caught:
        offscreen("linux", environ={BACKEND_VARIABLE: value})
    assert str(caught.value) == (
        f"MIRRORLAB_GL_BACKEND={value!r} is not a backend; expected one of auto, egl, hidden-window"
    )
    assert isinstance(caught.value, ValueError)  # bad input: the command exits 2
    with pytest.raises(GLContextError, match=r"^backend='x' is not a backend; expected"):
        choose_backend("offscreen", "linux", egl=True, display=True, environ={}, backend="x")


@pytest.mark.parametrize("system", ["win32", "darwin"])
def test_egl_forced_where_there_is_none_says_so(system):
    with pytest.raises(GLContextError) as caught:
        offscreen(system, environ={BACKEND_VARIABLE: "egl"})
    assert str(caught.value) == (
        f"MIRRORLAB_GL_BACKEND=egl: EGL is used on Linux only, "
        f"not on {system}; unset it or set it to hidden-window"
    )


def test_a_hidden_window_forced_without_a_display_says_what_to_do():
    with pytest.raises(GLContextError) as caught:
        offscreen("linux", display=False, environ={BACKEND_VARIABLE: "hidden-window"})
    assert str(caught.value) == (
        "MIRRORLAB_GL_BACKEND=hidden-window needs a display "
        "(DISPLAY is not set); run under 'xvfb-run -a', or unset "
        "it to render with EGL"
    )


@pytest.mark.parametrize("value, core", [("1", True), ("0", False), ("", False)])
@pytest.mark.parametrize("system", ["linux", "win32"])
def test_the_core_variable_asks_for_a_core_context(system, value, core):
    assert offscreen(system, environ={CORE_VARIABLE: value}).core is core
    window = choose_backend(
        "window", system, egl=True, display=True, environ={CORE_VARIABLE: value}
    )
    assert window.core is core


@pytest.mark.parametrize("value", ["", "0", "1"])
def test_macos_always_asks_for_a_core_context(value):
    assert offscreen("darwin", environ={CORE_VARIABLE: value}).core
    assert choose_backend(
        "offscreen", "darwin", egl=False, display=True, environ={}, core=False
    ).core


@pytest.mark.parametrize("value", ["yes", "true", "2", "core"])
def test_an_unknown_core_value_is_one_line(value):
    with pytest.raises(GLContextError) as caught:
        offscreen("linux", environ={CORE_VARIABLE: value})
    assert str(caught.value) == (
        f"MIRRORLAB_GL_CORE={value!r} is not allowed; expected 1 "
        f"(ask for an OpenGL 4.1 core context) or 0"
    )


def test_opengl_bound_to_glx_already_takes_a_hidden_window_when_there_is_a_display():
    # a program that imported OpenGL first on X11: a hidden window can share its platform
    assert offscreen("linux", bound="glx").backend == "hidden-window"
    assert offscreen("linux", bound="egl").backend == "egl"
    # with no display, EGL is the one to try (and its error says what to do)
    assert offscreen("linux", bound="glx", display=False).backend == "egl"
