"""The ``screen`` texture kind of the pass contract: a view's own frame, its colour and
depth as the view's target holds them when a reflector of such a technique is drawn
(after the view's objects: its entry's ``draws_after_objects``).

The rules a pass of that kind follows (``tests/gl/test_pass_contract.py`` checks them):

- **Planning.** The frame is not a capture: the planner plans no pass for it and keeps
  no slot of it; it is copied at each draw, in every view the reflector is drawn in
  (the camera's, a reflected capture's, a cube face's), so it is never reused across
  views or frames, and a view that moves or an object that moves is in the next copy.
- **Recording and replay.** The copy is one of the frame's GL calls (through
  :mod:`mirrorlab.gl.calls`), so a recorded frame holds it and a replayed frame copies
  again what that frame drew. The textures it copies into are kept by size
  (:data:`SIZES_KEPT`), never made anew for a size held, so the recorded calls' texture
  names stay valid while the frame may be replayed.
- **What it holds.** The whole view: a view that shows such a reflector is planned
  without a scissor (its pixels are all drawn), so the copy holds the view and nothing
  else, and the frame does not depend on the plan (planned frames equal ``--no-plan``
  ones).
"""

from __future__ import annotations

from collections import OrderedDict

from mirrorlab.gl.context import ResourceRegistry
from mirrorlab.gl.resources import FrameTextures
from mirrorlab.plan import Rectangle

SIZES_KEPT = 8
"""Frame copies kept, by size (most recently used): every view size one frame draws the
reflector in, with room to spare."""


class ViewFrame:
    """Copies of the views' own frames, one pair of textures (:class:`FrameTextures`) per
    view size."""

    def __init__(self, registry: ResourceRegistry) -> None:
        self.registry = registry
        self._held: OrderedDict[tuple[int, int], FrameTextures] = OrderedDict()

    def textures(self, size: tuple[int, int]) -> FrameTextures:
        """The textures for views of ``size`` (made on first use)."""
        held = self._held.pop(size, None)
        if held is None:
            held = FrameTextures(self.registry, *size)
        self._held[size] = held  # now the most recently used
        while len(self._held) > SIZES_KEPT:
            self._held.pop(next(iter(self._held))).release()
        return held

    def copy(self, size: tuple[int, int], region: Rectangle | None) -> FrameTextures:
        """Copy the bound target's frame of a view of ``size`` (the part ``region`` that
        view drew; None: all of it) and return the textures holding it."""
        textures = self.textures(size)
        textures.copy(region)
        return textures

    def release(self) -> None:
        for textures in self._held.values():
            textures.release()
        self._held.clear()
