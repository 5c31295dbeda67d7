"""Screen-space reflections with a probe fallback (technique ``ssr``), judged against its
numpy reference and the ray tracer:

- the shader's march is :func:`mirrorlab.screen_space.march`, run on the shader's own
  rays and the frame it copied (the same reasons; hits at the same place);
- the miss mask is right: under 1% of the reflector's pixels are false hits (the ray
  tracer's first hit for the reflected ray is off the screen or hidden in the view, yet
  the march used a screen pixel), on every SSR scene shipped and with ``--method ssr`` on
  scenes built for other techniques;
- the fallback earns its place: with its probe, each scene has a lower mean FLIP than
  without (a miss showing the background's colour), and no seam: the largest error where
  hits fade into the probe is no greater than elsewhere on the reflector;
- where every reflected point is on the screen and unoccluded, its MAE is within 1/255
  of the reflected-camera mirror's at the same resolution;
- any map technique serves as its probe, on a curved and a planar reflector;
- hard cases stay finite (a float target, the miss mask in floats): rays towards the
  eye and along the line of sight, a view grazing the glass or on its plane, a near
  plane at the glass, an orthographic view, views through a stencil mirror and in a
  reflected capture;
- the miss mask through the API and ``mirrorlab render --save-ssr-mask``.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest
from PIL import Image

import mirrorlab
from mirrorlab import accuracy, flip
from mirrorlab import screen_space as ss
from mirrorlab.cli import main
from mirrorlab.gl.resources import FloatFramebuffer
from mirrorlab.options import apply_options
from mirrorlab.passes import ssr as ssr_pass
from mirrorlab.raytrace import reflection_hits, trace_scene
from mirrorlab.scene.model import Camera, Scene
from mirrorlab.techniques import technique
from mirrorlab.views import ortho_capture_view
from tests.scenekit import map_technique_names, planar_reflector

SIZE = (96, 96)
SCENES = (
    "ssr_box_room",
    "ssr_thin_pole",
    "ssr_behind_camera",
    "ssr_grazing_water",
    "ssr_sphere_near",
)
"""The shipped scenes made to show screen-space reflections' failures."""
OTHERS = ("mirror_and_sphere", "sphere_room")
"""Shipped scenes made for other techniques, drawn with ``--method ssr``."""


@pytest.fixture(scope="module")
def renderer():
    with mirrorlab.Renderer(SIZE, debug=True) as made:
        yield made


def ssr_scene(name: str) -> Scene:
    """A shipped scene with every reflector drawn by screen-space reflections."""
    scene = mirrorlab.load_scene(name)
    if all(technique(r.technique).texture == "screen" for r in scene.reflectors):
        return scene
    return apply_options(scene, {"method": "ssr"})


def without_probe(scene: Scene) -> Scene:
    return apply_options(
        scene,
        {"set": [f'reflectors[{i}].ssr.probe="none"' for i in range(len(scene.reflectors))]},
    )


def ssr_of(renderer, name):
    """The ssr pass of reflector ``name`` and the camera's view of the last frame."""
    scene_renderer = renderer.scene_renderer
    top = renderer.last_stats.plan.top
    draw_ = next(d for d in top.shown if d.reflector.name == name)
    drawn = scene_renderer.drawn_pass(draw_)
    assert isinstance(drawn, ssr_pass.ScreenSpaceReflections)
    return drawn, top.view


# ------------------------------------------------------------------ the numpy reference


@pytest.mark.parametrize("name", ["ssr_box_room", "ssr_sphere_near"])
def test_the_shaders_march_is_its_numpy_reference(renderer, name):
    """The reference marched on the shader's own rays (read back through the march's
    float target) and the frame it copied: the same reason for at least 99.5% of the
    reflector's pixels (measured 100%: float32 against float64 can flip a comparison
    made exactly at a bound), and where both hit, the same place."""
    scene = mirrorlab.load_scene(name)
    reflector = scene.reflectors[0].name
    renderer.render(scene)
    drawn, view = ssr_of(renderer, reflector)
    mask = drawn.miss_mask(view)
    frame = drawn.frame_copy(view.size)
    color, depth = frame.read_color()[::-1], frame.read_depth()[::-1]  # GL's row order
    rays = {}
    try:
        for mode in (ssr_pass.OUTPUT_RAY_ORIGIN, ssr_pass.OUTPUT_RAY_DIRECTION):
            # pass_for: what is changed in the pass, the next frame draws (not replayed)
            renderer.scene_renderer.pass_for(reflector).output_mode = mode
            renderer.render(scene)
            drawn, view = ssr_of(renderer, reflector)
            rays[mode] = drawn.read_rays(view)[::-1]
    finally:
        renderer.scene_renderer.pass_for(reflector).output_mode = ssr_pass.OUTPUT_MARCH
    reason = mask.reason[::-1]
    ys, xs = np.nonzero(reason)
    assert len(ys) > 800
    origins = rays[ssr_pass.OUTPUT_RAY_ORIGIN][ys, xs, :3]
    directions = rays[ssr_pass.OUTPUT_RAY_DIRECTION][ys, xs, :3]
    settings = scene.reflectors[0].ssr or ss.DEFAULTS
    result = ss.march(
        origins, directions, view.projection, depth.astype(np.float64), color[..., 3] == 0, settings
    )
    same = result.reason == reason[ys, xs]
    assert same.mean() >= 0.995, np.bincount(result.reason[~same], minlength=8)
    both = same & (result.reason == ss.HIT)
    assert both.sum() > 200
    # a halving that float32 and float64 decide the other way moves the hit by up to a
    # sixteenth of a step and the halvings after it: 99% agree to 0.01 pixels, all to 0.5
    gap = np.abs(mask.pixel[::-1][ys, xs] - result.pixel).max(axis=-1)[both]
    assert np.quantile(gap, 0.99) < 0.01 and gap.max() < 0.5, np.quantile(gap, [0.99, 1])
    weight_gap = np.abs(mask.weight[::-1][ys, xs] - result.weight)[both]
    assert np.quantile(weight_gap, 0.99) < 1e-3 and weight_gap.max() < 0.1
    assert set(np.unique(reason[ys, xs])) <= set(range(1, len(ss.REASONS)))


# ------------------------------------------------------------------ against the truth


def judged(renderer, scene: Scene):
    """The frame with its probe and without, the miss mask, the truth and where each
    reflected ray goes, at :data:`SIZE`."""
    image = np.asarray(renderer.render(scene))
    mask = renderer.ssr_mask()
    bare = np.asarray(renderer.render(without_probe(scene)))
    truth = trace_scene(scene, SIZE).to_uint8()
    hits = reflection_hits(scene, SIZE)
    return image, bare, mask, truth, hits


@pytest.mark.parametrize("name", SCENES + OTHERS)
def test_the_miss_mask_is_right_and_the_fallback_earns_its_place(renderer, name):
    """Measured at 96 x 96 (false hits; FLIP with and without the probe): ssr_box_room
    0%, 0.032 against 0.245; ssr_thin_pole 0.38%, 0.044 against 0.390;
    ssr_behind_camera 0.12%, 0.023 against 0.922; ssr_grazing_water 0.57%, 0.163 against
    0.672; ssr_sphere_near 0.66%, 0.110 against 0.684; mirror_and_sphere 0%, 0.085
    against 0.814; sphere_room 0%, 0.031 against 0.810."""
    scene = ssr_scene(name)
    image, bare, mask, truth, hits = judged(renderer, scene)
    region = (hits.reflector >= 0) & mask.reflector
    assert region.sum() > 200
    false = ss.false_hits(mask, hits.visible, hits.reflector >= 0)
    share = false.sum() / region.sum()
    assert share < 0.01, f"{name}: {100 * share:.2f}% of {region.sum()} pixels are false hits"
    # what the truth puts off the screen or out of sight, the march left to the probe
    hidden = region & ~hits.visible
    if hidden.sum() > 50:
        assert (mask.weight[hidden] == 0).mean() > 0.98
        with_probe = accuracy.image_error(image, truth, region)
        alone = accuracy.image_error(bare, truth, region)
        if flip.available():
            assert with_probe.flip < alone.flip, (with_probe, alone)
        assert with_probe.mae < alone.mae
    # no seam: where hits fade into the probe, no larger error than anywhere else
    band = ss.handover(mask) & region
    error = np.abs(image.astype(int) - truth.astype(int)).max(axis=-1)
    if band.any():
        assert error[band].max() <= error[region & ~band].max()


def test_where_every_reflected_point_is_seen_it_matches_the_reflected_mirror(renderer):
    """On the reflector pixels whose reflected point the viewer sees (on the screen, the
    first surface along its line of sight), SSR's MAE is within 1/255 of the reflected
    camera's, both at 160 x 160. Measured: ssr_box_room 0.58 against 0.16, ssr_thin_pole
    0.55 against 0.00 (at 128 x 128: 0.73 against 0.17, and 1.07 against 0.01: the thin
    pole's reflection is a pixel or two wide, and the march misses the rays that meet it
    between pixel centres)."""
    size = (160, 160)
    for name in ("ssr_box_room", "ssr_thin_pole"):
        scene = mirrorlab.load_scene(name)
        ssr = np.asarray(renderer.render(scene, size=size))
        mask = renderer.ssr_mask()
        mirrored = np.asarray(
            renderer.render(apply_options(scene, {"method": "reflected"}), size=size)
        )
        truth = trace_scene(scene, size).to_uint8()
        hits = reflection_hits(scene, size)
        seen = (hits.reflector >= 0) & mask.reflector & hits.visible
        assert seen.sum() > 4000
        mine = accuracy.image_error(ssr, truth, seen).mae
        theirs = accuracy.image_error(mirrored, truth, seen).mae
        assert mine <= theirs + 1.0, (name, mine, theirs)


# ------------------------------------------------------------------ the probe


@pytest.mark.parametrize("probe", [*map_technique_names(), "none"])
def test_any_map_technique_is_a_probe(renderer, probe):
    """Every curved technique whose reflection is a map serves as the probe, of a curved
    reflector and of a planar mirror: its draw is planned as the probe technique's own
    (its map or its capture), and the frame shows it where the march misses (in the sky
    around the sphere: the background's colour with no probe, something else with one)."""
    for name in ("ssr_sphere_near", "ssr_box_room"):
        scene = mirrorlab.load_scene(name)
        if probe == "none" or not technique(probe).parallax:
            scene = apply_options(scene, {"parallax": "none"})
        small = [f'reflectors[0].ssr.probe="{probe}"', "reflectors[0].map_size=32"]
        scene = apply_options(scene, {"set": small})
        image = np.asarray(renderer.render(scene, size=(48, 48)))
        (glass,) = renderer.last_stats.plan.top.shown
        assert glass.mode == "screen"
        if probe == "none":
            assert glass.fallback is None
        else:
            assert glass.fallback is not None and glass.fallback.mode in ("map", "texture")
            assert glass.fallback.reflector.technique == probe
        mask = renderer.ssr_mask()
        missed = mask.reflector & (mask.weight == 0)
        assert missed.sum() > 20 and np.isfinite(image).all()
        if name == "ssr_sphere_near":
            background = np.round(np.asarray(scene.background.color) * 255)
            shown = (np.abs(image[missed] - background) <= 1).all(axis=-1).mean()
            assert (shown > 0.99) == (probe == "none"), (probe, shown)


# ------------------------------------------------------------------ hard cases


def float_frame(scene_renderer, scene: Scene, size=(64, 64), view=None):
    """The frame drawn into a float target: ``(h, w, 3)`` float32, its plan, and the miss
    mask of the camera's view."""
    target = FloatFramebuffer(scene_renderer.registry, *size)
    try:
        stats = scene_renderer.render(scene, target, view=view)
        return target.read(), stats, ssr_pass.frame_mask(scene_renderer, stats.plan.top)
    finally:
        target.release()


def assert_sane(colour: np.ndarray, mask: ss.MissMask, what: str) -> None:
    assert np.isfinite(colour).all(), f"{what}: NaN/Inf in the frame"
    assert colour.min() >= 0.0 and colour.max() <= 1.0, what
    assert np.isfinite(mask.weight).all() and np.isfinite(mask.pixel).all(), what
    assert mask.weight.min() >= 0.0 and mask.weight.max() <= 1.0, what
    assert set(np.unique(mask.reason)) <= set(range(len(ss.REASONS))), what
    hit = mask.reason == ss.HIT
    height, width = mask.reason.shape
    assert (mask.pixel[hit] >= 0).all() and (mask.pixel[hit][:, 0] <= width).all(), what
    assert (mask.pixel[hit][:, 1] <= height).all(), what
    assert (mask.weight[~hit] == 0).all(), what


def floor_scene(camera: Camera) -> Scene:
    return replace(mirrorlab.load_scene("ssr_box_room"), camera=camera)


HARD_CAMERAS = {
    # straight down at the floor: every reflected ray runs back along the line of sight
    "top-down": Camera(eye=(0.3, 3.5, 0.2), target=(0.3, 0.0, 0.2), up=(0, 0, -1), fovy=60.0),
    # a breath above the glass: rays graze it and run nearly along the screen
    "grazing": Camera(eye=(0.0, 1e-3, 3.5), target=(0.0, 0.0, -4.0), fovy=50.0),
    # on the glass's plane: only its edge, or its back
    "in the plane": Camera(eye=(0.0, 0.0, 3.5), target=(0.0, 0.0, -4.0), fovy=50.0),
    # the near plane at the glass
    "near plane": Camera(eye=(0.0, 0.1, 0.0), target=(0.0, 0.0, -1.0), fovy=70.0, near=0.1),
    # the glass reaching past every edge of the view, seen sideways and rolled
    "off-screen": Camera(eye=(-3.0, 0.8, 1.0), target=(3.0, 0.2, -2.0), up=(0.3, 1, 0), fovy=30.0),
}


@pytest.mark.parametrize("case", list(HARD_CAMERAS))
def test_hard_views_of_the_glass_stay_finite(scene_renderer, case):
    scene = floor_scene(HARD_CAMERAS[case])
    colour, _, mask = float_frame(scene_renderer, scene)
    assert_sane(colour, mask, case)


def test_rays_towards_the_eye_leave_through_the_near_plane(scene_renderer):
    """The floor seen from above reflects what hangs over and behind the eye: every one
    of those rays runs towards the viewer (w falls to the near plane) and leaves the
    view; none is a hit, all finite."""
    scene = mirrorlab.load_scene("ssr_behind_camera")
    colour, _, mask = float_frame(scene_renderer, scene, (96, 96))
    assert_sane(colour, mask, "behind the camera")
    hits = reflection_hits(scene, (96, 96))
    behind = (hits.reflector >= 0) & mask.reflector & ~hits.on_screen & ~hits.escaped
    assert behind.sum() > 100  # the lamp's reflection
    assert (mask.reason[behind] == ss.SCREEN).mean() > 0.95


def test_views_through_mirrors_and_orthographic_views_stay_finite(scene_renderer):
    """An ssr sphere seen in a stencil mirror (no march there: the probe alone), in a
    reflected mirror's capture (the capture's own frame), and in the lab's orthographic
    capture (no eye point: parallel rays)."""
    for method in ("stencil", "reflected", "ortho"):
        scene = apply_options(mirrorlab.load_scene("mirror_and_sphere"), {"method": method})
        scene = scene.with_reflector("sphere", technique="ssr")
        colour, stats, mask = float_frame(scene_renderer, scene)
        assert_sane(colour, mask, method)
        mirror = next(d for d in stats.plan.top.draws if d.reflector.name == "mirror")
        seen_in = mirror.nested.draws if mirror.nested is not None else ()
        if method == "stencil":
            assert any(d.reflector.name == "sphere" and d.mode == "screen" for d in seen_in)
    sphere = mirrorlab.load_scene("chrome_sphere").with_reflector("sphere", technique="ssr")
    glass = planar_reflector(mirrorlab.load_scene("lab20"), "mirror")
    colour, stats, mask = float_frame(
        scene_renderer, sphere, view=ortho_capture_view(glass, (64, 64))
    )
    (ball,) = stats.plan.top.shown
    assert ball.mode == "screen"
    assert_sane(colour, mask, "orthographic")
    assert mask.reflector.sum() > 100


# ------------------------------------------------------------------ the mask exported


def test_the_miss_mask_through_the_api_and_the_command_line(renderer, tmp_path, capsys):
    renderer.render("ssr_sphere_near")
    mask = renderer.ssr_mask()
    assert mask.reason.shape == (SIZE[1], SIZE[0])
    assert 0.3 < mask.miss_share < 1.0 and 0.0 <= mask.probe_share <= 1.0
    counts = mask.counts()
    assert counts["hit"] > 100 and sum(counts.values()) == mask.reflector.sum()
    out, saved = tmp_path / "frame.png", tmp_path / "mask.png"
    arguments = ["render", "ssr_sphere_near", "--size", "96x96", "--out", str(out)]
    assert main([*arguments, "--save-ssr-mask", str(saved)]) == 0
    assert "fell back to the probe" in capsys.readouterr().out
    with Image.open(saved) as picture:
        assert np.array_equal(np.asarray(picture.convert("RGB")), mask.image())
    # a scene no reflector of which is drawn by ssr: one line, exit 2, nothing written
    other = tmp_path / "other.png"
    assert main(["render", "lab20", "--out", str(other), "--save-ssr-mask", str(saved)]) == 2
    assert "no reflector drawn by screen-space reflections" in capsys.readouterr().err
    assert not other.exists()
    assert main([*arguments, "--save-ssr-mask", str(out)]) == 2  # one file for two outputs
    capsys.readouterr()
    renderer.render("lab20")
    empty = renderer.ssr_mask()
    assert not empty.reflector.any() and math.isnan(empty.miss_share)
