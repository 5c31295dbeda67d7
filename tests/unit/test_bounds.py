"""How far things reach (:mod:`mirrorlab.bounds`): live cube faces that clip nothing of
the scene, reflection views that reach its far side, and whether the surroundings close
a point in."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from mirrorlab import bounds, math3d
from mirrorlab.scene.loader import load_scene
from mirrorlab.scene.mesh import load_mesh
from mirrorlab.scene.model import CurvedReflector, Scene
from mirrorlab.scene.robot import scene_parts
from tests.scenekit import ball, block, curved_reflector, transformed


def every_point(scene: Scene, leave_out: str = "") -> np.ndarray:
    points = [
        math3d.transform_points(part.model, load_mesh(part.mesh).positions)[:, :3]
        for part in scene_parts(scene)
    ]
    for reflector in scene.reflectors:
        if reflector.name == leave_out:
            continue
        if isinstance(reflector, CurvedReflector):
            points.append(
                math3d.transform_points(
                    reflector.model_matrix(), load_mesh(reflector.mesh).positions
                )[:, :3]
            )
        else:
            points.append(reflector.corner_array)
    return np.vstack(points)


@pytest.mark.parametrize("name", ["chrome_sphere", "sphere_room", "mirror_and_sphere"])
@pytest.mark.parametrize("scale", [1e-4, 1.0, 1e4])
def test_a_live_cube_maps_faces_clip_nothing_of_the_scene(name, scale):
    scene = transformed(load_scene(name), scale=scale)
    (live,) = [r for r in scene.reflectors if isinstance(r, CurvedReflector)]
    near, far = bounds.cube_depth_range(scene, live)
    assert 0 < near < far
    distances = np.linalg.norm(every_point(scene, live.name) - live.center(), axis=1)
    # a point d away lies between d / sqrt(3) and d along the axis of the face seeing it
    assert distances.min() / np.sqrt(3) >= near
    assert distances.max() <= far
    assert far <= 1.01 * (distances.max() + 2 * bounds.scene_sphere(scene)[1])


def test_a_ball_far_away_sets_the_reach():
    scene = load_scene("chrome_sphere")
    far_away = replace(
        scene, reflectors=(*scene.reflectors, ball("far", (0.0, 0.0, 400.0), 10.0, "cube"))
    )
    (live,) = [r for r in scene.reflectors if isinstance(r, CurvedReflector)]
    assert bounds.cube_depth_range(scene, live)[1] < 50
    assert bounds.cube_depth_range(far_away, live)[1] >= 410
    eye = np.array([1.3, 2.0, 7.4])
    assert bounds.reach(far_away, eye) >= np.linalg.norm(eye - (0.0, 0.0, 410.0))


def test_a_room_closes_its_middle_in_and_an_open_sky_does_not():
    room = load_scene("sphere_room")
    center = curved_reflector(room, "sphere").center()
    assert bounds.encloses(room, center, "sphere")
    without_ceiling = replace(room, objects=tuple(o for o in room.objects if o.name != "ceiling"))
    assert not bounds.encloses(without_ceiling, center, "sphere")
    assert not bounds.encloses(room, (0.0, 1.0, 50.0))  # outside the room
    sky = load_scene("chrome_sphere")
    assert not bounds.encloses(sky, curved_reflector(sky, "sphere").center(), "sphere")
    assert not bounds.encloses(Scene(name="empty"), np.zeros(3))


def test_a_scene_without_objects_keeps_its_objects_arrays_when_its_mirrors_change():
    """The arrays of a scene's objects are made once for its objects tuple, also when the
    tuple is empty (empty arrays, as false as an empty list, are still the ones kept)."""
    scene = replace(load_scene("lab20"), objects=())
    first = bounds.scene_index(scene).objects_part
    assert len(first) == 0
    moved = replace(
        scene, reflectors=tuple(replace(r, name=r.name + "2") for r in scene.reflectors)
    )
    assert bounds.scene_index(moved).objects_part is first


def test_scenes_drawn_in_turn_each_keep_their_index():
    """A program drawing a dozen scenes in turn finds each one's index again (none is
    worked out twice), however the turns are ordered."""
    cache = bounds._IndexCache()
    base = load_scene("lab20")
    scenes = [
        replace(base, objects=(*base.objects, block(f"b{i}", (i, 0.0, -5.0), 0.5, (1, 0, 0))))
        for i in range(12)
    ]
    first = [cache.index(scene) for scene in scenes]
    turns = list(zip(scenes, first, strict=True))
    for scene, index in [*turns, *reversed(turns)]:
        assert cache.index(scene) is index


def test_an_animation_holds_no_more_than_its_last_frames():
    """An animation makes new objects every frame: what the cache holds stays bounded by
    the frames it keeps, not by how many frames were drawn (200 frames of 51 objects
    would be 10 200 objects' bounds)."""
    cache = bounds._IndexCache()
    lab = load_scene("lab20")
    base = replace(
        lab,
        objects=(
            *lab.objects,
            *(block(f"b{i}", (0.1 * i, 0.0, -5.0), 0.05, (1, 0, 0)) for i in range(50)),
        ),
    )
    per_frame = len(base.objects) + len(base.reflectors)
    held = []
    for frame in range(200):
        cache.index(transformed(base, offset=(0.01 * frame, 0.0, 0.0)))
        held.append(len(cache.objects))
    assert len(cache.indexes) == cache.KEPT
    # between two clear-outs: twice what the kept arrays and the new frame hold, + 512
    assert max(held) <= 2 * (cache.KEPT + 1) * per_frame + 512 + per_frame
    assert held[-1] >= len(base.objects)
