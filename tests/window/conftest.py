"""Window tests need an X display: ./dev test runs them under xvfb-run. They start the
demo as its own process (GLX) and drive it with real X key and pointer events (XTEST)."""

from __future__ import annotations

import os

import pytest


def pytest_collection_modifyitems(config, items):
    if os.environ.get("DISPLAY"):
        return
    if os.environ.get("CI"):
        raise pytest.UsageError("window tests need DISPLAY; run them with xvfb-run -a")
    skip = pytest.mark.skip(reason="no DISPLAY: run under xvfb-run -a (./dev test does)")
    for item in items:
        item.add_marker(skip)


@pytest.fixture(scope="session")
def xdisplay():
    """One connection to the X server for the whole session. Xvfb resets itself when its
    last client leaves, and a connection made during that reset is refused: with this
    one held open (and ./dev starting Xvfb with -noreset) the server never resets
    between tests."""
    from Xlib import display

    d = display.Display()
    yield d
    d.close()
