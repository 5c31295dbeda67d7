"""A short soak (bench/soak.py is the long one): two rounds of every (shipped scene,
technique) pair in one Renderer with the camera and joints moving, and repeated one-shot
renders. The second round leaves exactly the GL objects and file descriptors the first
left, and resident memory does not grow by more than allocator noise."""

from __future__ import annotations

import importlib.util
import sys

import pytest

import mirrorlab
from mirrorlab.techniques import technique_names
from tests import REPO_DIR


@pytest.fixture(scope="module")
def soak():
    spec = importlib.util.spec_from_file_location("soak", REPO_DIR / "bench" / "soak.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules["soak"] = module  # dataclasses look their module up there
    spec.loader.exec_module(module)
    return module


def test_rounds_of_every_scene_and_technique_leave_what_the_last_left(soak):
    schedule = soak.schedule()
    # every shipped scene with each technique (from the registry) its first reflector may
    # take, or as it is when it has none
    expected: list[tuple[str, str | None]] = []
    for name in soak.scene_names():
        reflectors = mirrorlab.load_scene(name).reflectors
        kind = reflectors[0].kind if reflectors else None
        expected += [(name, t) for t in technique_names(kind)] if kind else [(name, None)]
    assert [technique for _, technique in schedule] == [t for _, t in expected]
    assert len({(scene.name, t) for scene, t in schedule}) == len(expected)
    pairs = len(schedule)
    samples, blocks = soak.frame_soak(
        frames=3 * pairs, switch_every=1, size=(32, 32), sample_every=1
    )
    assert blocks[:pairs] == blocks[pairs : 2 * pairs] == blocks[2 * pairs :]
    assert len(set(blocks)) == pairs
    rounds = [samples[i * pairs : (i + 1) * pairs] for i in range(3)]
    # The first round also fills the caches shared across scenes (programs, meshes,
    # pictures); from then on, after the same pair the same GL objects are live: nothing
    # a frame, a pass or a scene made is left behind.
    assert [s.gl_objects for s in rounds[1]] == [s.gl_objects for s in rounds[2]]
    assert [s.fds for s in rounds[1]] == [s.fds for s in rounds[2]]
    grown = max(s.rss_mb for s in rounds[2]) - max(s.rss_mb for s in rounds[1])
    assert grown < 32.0, f"resident memory grew {grown:.1f} MB in the third round"


def test_one_shot_renders_free_their_contexts(soak):
    shots = soak.one_shot_soak(calls=16, size=(16, 16), sample_every=1)
    assert len({s.fds for s in shots[8:]}) == 1, [s.fds for s in shots]
    grown = max(s.rss_mb for s in shots[8:]) - max(s.rss_mb for s in shots[:8])
    assert grown < 32.0, f"resident memory grew {grown:.1f} MB over 8 one-shot renders"


def test_a_closed_renderer_holds_no_gl_objects():
    import mirrorlab

    renderer = mirrorlab.Renderer((16, 16))
    with renderer:
        renderer.render("mirror_and_sphere")
        assert renderer.gl_objects > 0
    assert renderer.gl_objects == 0
