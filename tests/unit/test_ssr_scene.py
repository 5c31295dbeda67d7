"""Screen-space reflections in scene files, options and the plan: the ``ssr`` table's keys
and their one-line errors, a planar mirror's probe map, ``--method`` for both kinds of
reflector, and the plan of a ``screen`` draw (its probe planned as the probe technique's
own draw, no pass of its own, its view drawn whole)."""

from __future__ import annotations

from dataclasses import replace

import pytest

import mirrorlab
from mirrorlab.options import OptionError, apply_options
from mirrorlab.plan import TextureState, plan_frame
from mirrorlab.scene.loader import SceneError, loads
from mirrorlab.scene.model import (
    SSR_NO_PROBE,
    BoxProxy,
    CurvedReflector,
    DistanceSearch,
    PlanarReflector,
    ScreenSpace,
)
from mirrorlab.screen_space import DEFAULTS, probe_reflector
from mirrorlab.techniques import technique
from tests.scenekit import map_technique_names
from tests.twins import techniques_named

FLOOR = """
name = "floor"
[camera]
eye = [0.0, 3.0, 6.0]
target = [0.0, 0.0, 0.0]
[[reflectors]]
name = "floor"
technique = "ssr"
center = [0.0, 0.0, 0.0]
normal = [0.0, 1.0, 0.0]
width = 8.0
height = 8.0
up = [0.0, 0.0, -1.0]
"""


def floor(extra: str = "") -> str:
    return FLOOR + extra


def test_an_ssr_table_reads_back_every_key_and_round_trips():
    scene = loads(
        floor(
            """
map_size = 64
capture_center = [0.0, 1.0, 0.0]
[reflectors.parallax]
proxy = "box"
min = [-4.0, -1.0, -4.0]
max = [4.0, 3.0, 4.0]
[reflectors.ssr]
probe = "latlong"
stride = 2.5
steps = 100
thickness = 0.1
max_distance = 20.0
refine = 3
edge_fade = 0.1
"""
        ).replace('probe = "latlong"', 'probe = "cube-live"')
    )
    (glass,) = scene.reflectors
    assert isinstance(glass, PlanarReflector) and glass.technique == "ssr"
    assert glass.ssr == ScreenSpace("cube-live", 2.5, 100, 0.1, 20.0, 3, 0.1)
    assert glass.map_size == 64 and glass.parallax == BoxProxy((-4, -1, -4), (4, 3, 4))
    assert (glass.probe_center() == (0.0, 1.0, 0.0)).all()
    assert loads(scene.to_toml()) == scene
    bare = loads(floor())
    assert bare.reflectors[0].ssr is None and loads(bare.to_toml()) == bare


def test_the_defaults_are_documented_in_one_place():
    assert ScreenSpace() == DEFAULTS
    assert DEFAULTS.probe == "cube-live" and DEFAULTS.stride == 1.0 and DEFAULTS.steps >= 64
    assert 0 < DEFAULTS.thickness < 1 and DEFAULTS.max_distance == 0.0


@pytest.mark.parametrize(
    "extra,key,message",
    [
        ('[reflectors.ssr]\nprobe = "ssr"', "reflectors[0].ssr.probe", "expected one of"),
        ('[reflectors.ssr]\nprobe = "reflected"', "reflectors[0].ssr.probe", "expected one of"),
        ("[reflectors.ssr]\nstride = 0.1", "reflectors[0].ssr.stride", "at least 0.25"),
        ("[reflectors.ssr]\nstride = 100", "reflectors[0].ssr.stride", "at most 64"),
        ("[reflectors.ssr]\nsteps = 0", "reflectors[0].ssr.steps", "from 1 to 4096"),
        ("[reflectors.ssr]\nsteps = 2.5", "reflectors[0].ssr.steps", "a whole number"),
        ("[reflectors.ssr]\nthickness = 0", "reflectors[0].ssr.thickness", "greater than 0"),
        ("[reflectors.ssr]\nthickness = nan", "reflectors[0].ssr.thickness", "finite"),
        ("[reflectors.ssr]\nmax_distance = -1", "reflectors[0].ssr.max_distance", "at least 0"),
        ("[reflectors.ssr]\nrefine = 17", "reflectors[0].ssr.refine", "from 0 to 16"),
        ("[reflectors.ssr]\nedge_fade = 0.6", "reflectors[0].ssr.edge_fade", "at most 0.5"),
        ("[reflectors.ssr]\nsteeps = 4", "reflectors[0].ssr.steeps", "did you mean 'steps'"),
        ("ssr = 3", "reflectors[0].ssr", "expected a table"),
        ("map_size = 2", "reflectors[0].map_size", "from 4 to 4096"),
        (
            '[reflectors.parallax]\nproxy = "box"\nmin = [1, 1, 1]\nmax = [2, 2, 2]',
            "reflectors[0].parallax",
            "outside the box proxy",
        ),
        (
            '[reflectors.parallax]\nproxy = "sphere"\nradius = 2\n[reflectors.ssr]\nprobe = "cube"',
            "reflectors[0].parallax",
            "not 'ssr' with probe 'cube'",
        ),
        ('source = "nowhere"', "reflectors[0].source", "takes no source"),
    ],
)
def test_bad_ssr_values_are_one_line_errors_naming_the_key(extra, key, message):
    with pytest.raises(SceneError) as info:
        loads(floor("\n" + extra + "\n"), "floor.toml")
    error = info.value
    assert error.key == key and message in error.problem, str(error)
    assert "\n" not in str(error) and str(error).startswith("floor.toml: " + key)


def test_ssr_keys_belong_to_techniques_with_a_probe():
    reflected = floor().replace('technique = "ssr"', 'technique = "reflected"')
    owners = techniques_named(lambda t: bool(t.probe))  # 'ssr', and any copy registered
    for extra, key in (
        ("[reflectors.ssr]\nsteps = 8", "ssr"),
        ("map_size = 64", "map_size"),
        ("capture_center = [0, 1, 0]", "capture_center"),
    ):
        with pytest.raises(SceneError) as info:
            loads(reflected + "\n" + extra + "\n")
        assert info.value.key == f"reflectors[0].{key}"
        assert f"applies to a planar mirror of {owners}" in info.value.problem
    sphere = mirrorlab.load_scene("chrome_sphere")
    document = sphere.to_toml() + "\n[reflectors.ssr]\nsteps = 8\n"
    with pytest.raises(SceneError) as info:
        loads(document, sphere.source)
    assert info.value.key == "reflectors[0].ssr"
    assert info.value.problem.startswith(f"applies to {owners}, not ")


def test_no_probe_keeps_the_maps_settings_for_later():
    scene = loads(
        floor(
            'map_size = 64\n[reflectors.parallax]\nproxy = "distance"\n'
            '[reflectors.ssr]\nprobe = "none"'
        )
    )
    (glass,) = scene.reflectors
    assert glass.ssr is not None and glass.ssr.probe == SSR_NO_PROBE
    assert probe_reflector(glass) is None
    assert isinstance(glass.parallax, DistanceSearch) and glass.map_size == 64


def test_a_probe_is_the_reflector_as_its_probe_technique_draws_it():
    sphere = mirrorlab.load_scene("ssr_sphere_near").reflectors[0]
    assert isinstance(sphere, CurvedReflector)
    probe = probe_reflector(sphere)
    assert isinstance(probe, CurvedReflector)
    assert probe.technique == "cube-live" and probe.ssr is None
    assert probe.parallax == sphere.parallax and probe.transform == sphere.transform
    glass = loads(floor("map_size = 32\ncapture_center = [0, 1.5, 0]")).reflectors[0]
    assert isinstance(glass, PlanarReflector)
    probe = probe_reflector(glass)
    assert isinstance(probe, CurvedReflector) and probe.map_size == 32
    assert (probe.center() == glass.probe_center()).all()
    assert (glass.probe_center() == (0.0, 1.5, 0.0)).all()
    moved = glass.moved(position=(1.0, 0.0, 0.0), rotation=(0.0, 0.0, 90.0))
    assert moved.probe_center() == pytest.approx((-0.5, 0.0, 0.0))  # turned with it


def test_method_ssr_takes_both_kinds_and_other_methods_drop_its_keys():
    scene = apply_options(mirrorlab.load_scene("mirror_and_sphere"), {"method": "ssr"})
    assert [r.technique for r in scene.reflectors] == ["ssr", "ssr"]
    assert {r.kind for r in scene.reflectors} == {"planar", "curved"}
    tuned = apply_options(
        scene, {"set": ["reflectors[0].ssr.thickness=0.05", "reflectors[0].map_size=64"]}
    )
    assert tuned.reflectors[0].ssr == replace(DEFAULTS, thickness=0.05)
    back = apply_options(tuned, {"method": "reflected"})
    mirror = back.reflectors[0]
    assert isinstance(mirror, PlanarReflector)
    assert mirror.technique == "reflected" and mirror.ssr is None and mirror.map_size == 256
    with pytest.raises(OptionError, match="has no reflector"):
        apply_options(mirrorlab.load_scene("no_mirror"), {"method": "ssr"})
    boxed = apply_options(scene, {"parallax": "box:-9,-9,-9,9,9,9"})
    assert all(isinstance(r.parallax, BoxProxy) for r in boxed.reflectors)


def test_every_map_technique_may_be_a_probe_and_nothing_else():
    for name in map_technique_names():
        settings = loads(floor(f'[reflectors.ssr]\nprobe = "{name}"')).reflectors[0].ssr
        assert settings is not None and settings.probe == name
    for other in ("reflected", "stencil", "ortho", "ssr", "raytrace"):
        with pytest.raises(SceneError, match=r"ssr\.probe: expected one of"):
            loads(floor(f'[reflectors.ssr]\nprobe = "{other}"'))


def test_a_screen_draw_plans_its_probe_and_no_pass_of_its_own():
    scene = mirrorlab.load_scene("ssr_sphere_near")
    state = TextureState()
    plan = plan_frame(scene, (64, 64), state)
    (sphere,) = plan.top.draws
    assert sphere.mode == "screen" and sphere.own
    assert sphere.fallback is not None and sphere.fallback.mode == "texture"
    assert sphere.fallback.reflector.technique == "cube-live"
    (capture,) = [p for p in plan.ran if p.name == "capture"]
    assert capture.reflector == "sphere" and len(capture.views) == 6
    for step in plan.ran:
        if step.name == "capture":
            state.record(step)
    again = plan_frame(scene, (64, 64), state)
    assert [p.name for p in again.ran] == ["camera"]  # the probe's capture is reused
    moved = replace(scene, camera=replace(scene.camera, eye=(1.0, 2.0, 7.0)))
    assert [p.name for p in plan_frame(moved, (64, 64), state).ran] == ["camera"]
    bare = apply_options(scene, {"set": ['reflectors[0].ssr.probe="none"']})
    alone = plan_frame(bare, (64, 64))
    assert [p.name for p in alone.passes] == ["camera"]
    assert alone.top.draws[0].fallback is None


def test_a_view_that_shows_a_screen_draw_is_drawn_whole():
    """A reflected mirror's capture is scissored to its glass; where that capture shows a
    reflector drawn from the view's own frame, it is drawn whole (the march reads all
    of it), and is the same planned or not."""
    scene = mirrorlab.load_scene("mirror_and_sphere")
    plain = plan_frame(scene, (64, 64))
    capture = next(p for p in plain.ran if p.name == "capture" and p.reflector == "mirror")
    assert capture.views[0].scissor is not None
    screened = scene.with_reflector("sphere", technique="ssr")
    plan = plan_frame(screened, (64, 64))
    capture = next(p for p in plan.ran if p.name == "capture" and p.reflector == "mirror")
    (view,) = capture.views
    assert view.scissor is None
    assert any(d.reflector.name == "sphere" and d.mode == "screen" for d in view.draws)


def test_the_entry_says_what_the_planner_and_renderer_read():
    entry = technique("ssr")
    assert entry.kind == "both" and entry.texture == "screen" and entry.draws_after_objects
    assert entry.serves("planar") and entry.serves("curved") and not entry.serves("frame")
    assert entry.probe_function() is probe_reflector
