"""One registry entry per technique (:mod:`mirrorlab.techniques`): a technique added here,
in this file alone, is in the scene schema, the command line and the plan; the lists
are derived from the registry when they are used, not kept in step by hand."""

from __future__ import annotations

import argparse
import contextlib
import subprocess
import sys
from dataclasses import replace

import pytest

from mirrorlab import techniques as registry
from mirrorlab.cli import build_parser, main
from mirrorlab.commands.arguments import scene_from_args
from mirrorlab.options import OptionError, apply_options, split_frame_technique
from mirrorlab.plan import TextureState, plan_frame
from mirrorlab.scene.loader import SceneError, load_scene, loads
from mirrorlab.techniques import (
    Technique,
    reflector_technique_names,
    register,
    technique,
    technique_names,
    techniques,
    unregister,
)
from tests import REPO_DIR
from tests.scenekit import curved_reflector

PROBE_MIRROR = Technique(
    "probe-mirror",
    "planar",
    "a test's planar technique: the reflected camera again",
    texture="viewer",
    pass_class="mirrorlab.passes.reflected:ReflectedMirror",
    capture_camera="mirrorlab.captures:reflected_camera",
)
PROBE_MAP = Technique(
    "probe-map",
    "curved",
    "a test's curved technique: a live cube map again",
    texture="fixed",
    pass_class="mirrorlab.passes.cube_live:LiveCubeMapped",
    vertex_shader="envmap.vert",
    fragment_shader="envmap_cube.frag",
    sampler="cube_map_texture",
    capture_camera="mirrorlab.captures:cube_camera",
    view_ray=True,
    parallax=True,
)


def grey_frame(scene, size, progress=False):
    import numpy as np

    return np.full((size[1], size[0], 3), 128, dtype=np.uint8)


PROBE_FRAME = Technique(
    "probe-frame", "frame", "a flat grey frame (a test's)", draw_frame=f"{__name__}:grey_frame"
)


@contextlib.contextmanager
def registered(*entries: Technique):
    for entry in entries:
        register(entry)
    try:
        yield
    finally:
        for entry in entries:
            unregister(entry.name)


MIRROR_SCENE = """
name = "probe"
[camera]
eye = [10.0, 4.0, 3.0]
target = [-7.0, 1.0, -2.0]
[[objects]]
type = "robot"
[[reflectors]]
name = "mirror"
technique = "probe-mirror"
center = [-7.0, 1.0, -2.0]
normal = [1.0, 0.0, 0.0]
width = 8.0
height = 8.0
"""


def test_a_technique_registered_here_is_in_the_scene_schema():
    with pytest.raises(SceneError, match="expected one of"):
        loads(MIRROR_SCENE)
    with registered(PROBE_MIRROR, PROBE_MAP):
        scene = loads(MIRROR_SCENE)
        assert scene.reflector("mirror").technique == "probe-mirror"
        assert scene.reflector("mirror").kind == "planar"
        with pytest.raises(SceneError) as refused:
            loads(MIRROR_SCENE.replace('"probe-mirror"', '"no-such"'))
        assert "probe-mirror" in str(refused.value) and "probe-map" in str(refused.value)
        sphere = load_scene("chrome_sphere")
        live = apply_options(sphere, {"method": "probe-map", "parallax": "sphere:3"})
        assert live.reflector("sphere").technique == "probe-map"
        assert curved_reflector(live, "sphere").parallax is not None
    with pytest.raises(SceneError):
        loads(MIRROR_SCENE)  # gone with its entry


def test_a_technique_registered_here_is_on_the_command_line():
    with registered(PROBE_MIRROR, PROBE_MAP, PROBE_FRAME):
        parser = build_parser()
        (commands,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
        render = commands.choices["render"]
        helps = {a.dest: a.help or "" for a in render._actions}
        assert "probe-mirror" in helps["option_method"]
        assert "probe-map" in helps["option_method"]
        assert "probe-frame" in helps["option_method"]
        assert any(a.option_strings == ["--probe-frame"] for a in render._actions)
        args = parser.parse_args(["plan", "lab20", "--method", "probe-mirror"])
        scene = scene_from_args(args)
        assert scene.reflector("mirror").technique == "probe-mirror"
        # a technique of the other kind is refused by name
        with pytest.raises(OptionError, match="probe-map is a technique for a curved"):
            scene_from_args(parser.parse_args(["plan", "lab20", "--method", "probe-map"]))
    with pytest.raises(OptionError):
        apply_options(load_scene("lab20"), {"method": "probe-mirror"})


def test_a_technique_registered_here_is_planned(capsys):
    with registered(PROBE_MIRROR, PROBE_MAP):
        scene = loads(MIRROR_SCENE)
        plan = plan_frame(scene, (64, 64), TextureState())
        (capture,) = [p for p in plan.ran if p.name == "capture"]
        assert capture.technique == "probe-mirror" and capture.views[0].view.eye is not None
        assert plan.top.draws[0].mode == "texture"
        sphere = apply_options(load_scene("chrome_sphere"), {"method": "probe-map"})
        plan = plan_frame(sphere, (64, 64), TextureState())
        (capture,) = [p for p in plan.ran if p.name == "capture"]
        assert capture.technique == "probe-map" and len(capture.views) == 6
        assert (
            main(
                [
                    "plan",
                    "chrome_sphere",
                    "--method",
                    "probe-map",
                    "--frames",
                    "1",
                    "--size",
                    "32x32",
                ]
            )
            == 0
        )
        assert "capture sphere (probe-map" in capsys.readouterr().out


def world_from_above(reflector, view, footprint, scissor, context):
    """A test's inline capture camera: the world seen from above, whatever the viewer."""
    from mirrorlab.plan import CaptureCameras
    from mirrorlab.scene.model import Camera
    from mirrorlab.views import camera_view

    above = Camera(eye=(0.0, 20.0, 0.0), target=(0.0, 0.0, 0.0), up=(0.0, 0.0, -1.0))
    return CaptureCameras((camera_view(above, view.size, "from above"),), ((1, 2, 3, 4),), None)


PROBE_INLINE = Technique(
    "probe-inline",
    "planar",
    "a test's inline technique: the world from above, drawn in place",
    texture="inline",
    pass_class="mirrorlab.passes.stencil:StencilMirror",
    capture_camera=f"{__name__}:world_from_above",
    draws_after_objects=True,
)


def test_an_inline_technique_nests_the_view_its_capture_camera_gives():
    with registered(PROBE_INLINE):
        scene = loads(MIRROR_SCENE.replace('"probe-mirror"', '"probe-inline"'))
        plan = plan_frame(scene, (64, 64), TextureState())
        assert [p.name for p in plan.passes] == ["camera"]
        (mirror,) = plan.top.draws
        assert mirror.mode == "inline" and mirror.own and mirror.nested is not None
        assert mirror.nested.view.label == "from above"
        assert mirror.nested.scissor == (1, 2, 3, 4)
        assert mirror.nested.excluded == "mirror"


def test_a_frame_technique_is_a_method_like_the_ray_tracer():
    with registered(PROBE_FRAME):
        entry, rest = split_frame_technique({"method": "probe-frame", "camera": (1, 2, 3)})
        assert entry is technique("probe-frame") and rest == {"camera": (1, 2, 3)}
        import mirrorlab

        image = mirrorlab.render("lab20", size=(8, 6), method="probe-frame")
        assert image.shape == (6, 8, 3) and (image == 128).all()
    assert split_frame_technique({"method": "reflected"})[0] is None
    assert technique("raytrace").kind == "frame"
    # a frame technique is no reflector's: where a scene is only changed, it is refused
    with pytest.raises(OptionError, match="raytrace draws the whole frame"):
        apply_options(load_scene("lab20"), {"method": "raytrace"})


def test_every_list_comes_from_the_registry():
    # each kind's list holds every technique that serves it (one for both kinds in
    # either), in the order registered, and nothing else
    every = techniques()
    names = technique_names()
    assert names == tuple(t.name for t in every) and len(set(names)) == len(names)
    for kind in ("planar", "curved", "frame"):
        assert technique_names(kind) == tuple(t.name for t in every if t.serves(kind))
    assert technique_names("planar") and technique_names("curved")
    both = [t.name for t in every if t.kind == "both"]
    assert all(n in technique_names("planar") and n in technique_names("curved") for n in both)
    assert reflector_technique_names() == tuple(t.name for t in every if t.kind != "frame")
    # the lab's and the textbook's techniques, each of its kind
    assert {"ortho", "reflected", "stencil"} <= set(technique_names("planar"))
    assert {"sphere", "cube", "cube-live", "latlong", "normal"} <= set(technique_names("curved"))
    with registered(replace(PROBE_MIRROR, name="probe-two")):
        assert technique_names("planar")[-1] == "probe-two"
    with pytest.raises(ValueError, match="already registered"):
        register(technique("cube"))
    with pytest.raises(ValueError, match="pass_class"):
        register(Technique("half", "curved", "no pass"))


def test_the_lists_hold_under_python_O():
    # No import-time asserts keep lists in step: -O (which drops asserts) changes nothing.
    # (the child imports the tests too, so a run with twins registered has them there)
    code = (
        "import tests; "
        "from mirrorlab.techniques import technique_names as t; "
        "from mirrorlab.scene.loader import load_scene; "
        "s = load_scene('mirror_and_sphere'); print(len(t()), s.reflectors[0].technique)"
    )
    out = subprocess.run(
        [sys.executable, "-O", "-c", code], capture_output=True, text=True, check=True, cwd=REPO_DIR
    ).stdout.split()
    assert out == [str(len(technique_names())), "reflected"]


def test_passes_planner_and_renderer_do_not_dispatch_on_technique_names():
    """The passes read their technique's registry flags, the planner its capture camera
    and texture kind, the renderer its draw order; none of them compares a technique's
    name (an entry like another, with another name, must draw alike)."""
    import ast
    import pathlib

    import mirrorlab.passes

    names = set(technique_names())
    package = pathlib.Path(mirrorlab.passes.__file__).parent.parent
    paths = [*(package / "passes").glob("*.py"), package / "plan.py", package / "renderer.py"]
    for path in paths:
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.Compare):
                constants = [c.value for c in ast.walk(node) if isinstance(c, ast.Constant)]
                assert not names & set(constants), f"{path.name}:{node.lineno}"
    assert dict(registry.technique("sphere-texgen").constants)["texgen"] == 1
