"""Scene options (the CLI's flags, the API's keywords): each changes the key it names and
nothing else, and a bad value is refused with the flag named."""

from __future__ import annotations

import re
from dataclasses import replace

import pytest

from mirrorlab.data import data_path
from mirrorlab.options import (
    OPTION_NAMES,
    OPTIONS,
    OptionError,
    apply_options,
    check_size,
    parse_count,
    parse_floats,
    parse_size,
    set_key,
)
from mirrorlab.scene.loader import load_scene
from mirrorlab.scene.model import BoxProxy, DistanceSearch, SphereProxy
from mirrorlab.techniques import technique, techniques
from tests.scenekit import curved_reflector, planar_reflector, scene_robot
from tests.twins import reflector_choices

CORRECTED = tuple(t.name for t in techniques("curved") if t.parallax and not t.probe)
"""The curved map techniques that take a parallax correction (the registry's, in order;
one with a probe takes it for its probe's map)."""

SKY_CUBE = data_path("textures") / "sky_cube"


def changed_fields(before, after) -> set[str]:
    return {
        name
        for name in before.__dataclass_fields__
        if getattr(before, name) != getattr(after, name)
    }


def test_no_option_gives_the_scene_back():
    lab = load_scene("lab20")
    assert apply_options(lab, {}) is lab
    assert apply_options(lab, {"camera": None, "method": None}) is lab


@pytest.mark.parametrize(
    "name, value, field, expected",
    [
        ("camera", (1.0, 2.0, 3.0), "eye", (1.0, 2.0, 3.0)),
        ("target", (-1.0, 0.5, 0.0), "target", (-1.0, 0.5, 0.0)),
        ("fovy", 30, "fovy", 30.0),
    ],
)
def test_camera_options_change_only_their_camera_field(name, value, field, expected):
    lab = load_scene("lab20")
    moved = apply_options(lab, {name: value})
    assert getattr(moved.camera, field) == expected
    assert changed_fields(lab.camera, moved.camera) == {field}
    assert changed_fields(lab, moved) == {"camera"}
    assert moved.source == lab.source


def test_angles_pose_every_robot_and_nothing_else():
    lab = load_scene("lab20")
    posed = apply_options(lab, {"angles": (10.0, -20.0, 30.0)})
    assert scene_robot(posed).angles == (10.0, -20.0, 30.0)
    assert posed == lab.with_angles((10.0, -20.0, 30.0))
    with pytest.raises(OptionError, match=r"^--angles: scene 'spheremap_cone' has no robot"):
        apply_options(load_scene("cone"), {"angles": (1.0, 2.0, 3.0)})


def test_method_changes_the_reflectors_of_its_kind_only():
    both = load_scene("mirror_and_sphere")
    stencil = apply_options(both, {"method": "stencil"})
    assert stencil.reflector("mirror").technique == "stencil"
    assert stencil.reflector("sphere") == both.reflector("sphere")
    latlong = apply_options(both, {"method": "latlong"})
    assert latlong.reflector("sphere").technique == "latlong"
    assert latlong.reflector("mirror") == both.reflector("mirror")
    two = apply_options(load_scene("two_mirrors"), {"method": "ortho"})
    assert [r.technique for r in two.reflectors] == ["ortho", "ortho"]
    with pytest.raises(
        OptionError,
        match=r"^--method: latlong is a technique for a curved "
        "reflector, and scene 'lab20' has none",
    ):
        apply_options(load_scene("lab20"), {"method": "latlong"})


def test_leaving_ortho_drops_the_labs_capture_camera():
    lab = load_scene("lab20")
    assert planar_reflector(lab, "mirror").ortho is not None
    reflected = planar_reflector(apply_options(lab, {"method": "reflected"}), "mirror")
    assert reflected.technique == "reflected" and reflected.ortho is None
    assert apply_options(lab, {"method": "ortho"}) == lab


def test_a_reflectors_source_is_kept_only_where_it_means_the_same():
    cone = load_scene("cone")
    picture = curved_reflector(cone, "cone").source
    kind = technique(curved_reflector(cone, "cone").technique).source
    assert picture is not None and kind == "picture"
    # A sphere-map picture is no folder of cube faces, nor a picture of another map's
    # layout; a technique that takes no source bakes its map or captures it instead.
    for entry in techniques("curved"):
        kept = curved_reflector(apply_options(cone, {"method": entry.name}), "cone").source
        assert kept == (picture if entry.source == kind else None), entry.name
    faces = apply_options(
        load_scene("sphere"),
        {"set": ['reflectors[0].technique="cube"', f'reflectors[0].source="{SKY_CUBE}"']},
    )
    assert curved_reflector(faces, "sphere").source == SKY_CUBE
    assert curved_reflector(apply_options(faces, {"method": "sphere"}), "sphere").source is None
    assert curved_reflector(apply_options(faces, {"method": "cube"}), "sphere").source == SKY_CUBE


def test_parallax_sets_every_live_cube_map_in_any_form():
    sphere = apply_options(load_scene("sphere"), {"method": "cube-live"})
    room = load_scene("sphere_room")
    forms = {
        "box:-3,-2,-3,3,3,3": BoxProxy((-3.0, -2.0, -3.0), (3.0, 3.0, 3.0)),
        "sphere:4": SphereProxy(4.0),
        "distance": DistanceSearch(),
        "distance:16": DistanceSearch(steps=16),
        "distance:4+0": DistanceSearch(steps=4, secant=0),
        # the API also takes the scene file's table
        "table": DistanceSearch(steps=3, thickness=0.5),
    }
    for text, expected in forms.items():
        value = {"proxy": "distance", "steps": 3, "thickness": 0.5} if text == "table" else text
        assert (
            curved_reflector(apply_options(sphere, {"parallax": value}), "sphere").parallax
            == expected
        )
    # given before --method in the API, it still applies after it
    both = apply_options(load_scene("sphere"), {"parallax": "sphere:2", "method": "cube-live"})
    assert curved_reflector(both, "sphere").parallax == SphereProxy(2.0)
    off = apply_options(room, {"parallax": "none"})
    assert curved_reflector(off, "sphere").parallax is None
    assert changed_fields(room.reflector("sphere"), off.reflector("sphere")) == {"parallax"}
    # the planar mirror of a mixed scene is left alone
    mixed = apply_options(load_scene("mirror_and_sphere"), {"parallax": "distance"})
    assert mixed.reflector("mirror") == load_scene("mirror_and_sphere").reflector("mirror")


def test_leaving_cube_live_drops_the_parallax_correction():
    """... for every curved technique that takes none; one that takes it keeps it."""
    room = load_scene("sphere_room")
    corrected = curved_reflector(room, "sphere").parallax
    assert corrected is not None
    for entry in techniques("curved"):
        moved = curved_reflector(apply_options(room, {"method": entry.name}), "sphere")
        assert moved.parallax == (corrected if entry.parallax else None), entry.name
    assert apply_options(room, {"method": "cube-live"}) == room


@pytest.mark.parametrize(
    ("scene", "text", "message"),
    [
        (
            "sphere_room",
            "cone",
            "--parallax: expected one of none, box:X0,Y0,Z0,X1,Y1,Z1, "
            "sphere:RADIUS, distance[:STEPS[+SECANT]], got 'cone'",
        ),
        ("sphere_room", "box:1,2,3", "--parallax: expected 6 numbers X0,Y0,Z0,X1,Y1,Z1 after box:"),
        ("sphere_room", "sphere:", "--parallax: expected 1 numbers RADIUS after sphere:"),
        ("sphere_room", "distance:x", "--parallax: expected one of none"),
        (
            "sphere_room",
            "sphere:-1",
            "--parallax: reflectors[0].parallax.radius: expected a number greater than 0, got -1.0",
        ),
        (
            "sphere_room",
            "distance:99",
            "--parallax: reflectors[0].parallax.steps: expected a whole "
            "number from 1 to 64, got 99",
        ),
        (
            "sphere_room",
            "box:2,2,2,3,3,3",
            "--parallax: reflectors[0].parallax: the reflector's "
            "capture centre [0.5, 1.0, -0.8] is outside the box",
        ),
        (
            "chrome_sphere",
            "distance",
            f"--parallax: scene 'chrome_sphere' has no {' or '.join(CORRECTED)} "
            f"reflector (--method {CORRECTED[0]} makes every curved",
        ),
        ("lab20", "distance", "--parallax: scene 'lab20' has no curved reflector"),
    ],
)
def test_a_bad_parallax_is_refused_naming_the_flag(scene, text, message):
    # the API takes the text as it is; the command line parses it first
    with pytest.raises(OptionError) as info:
        apply_options(load_scene(scene), {"parallax": text})
    assert str(info.value).startswith(message), str(info.value)
    assert "\n" not in str(info.value)
    try:
        parsed = OPTION_NAMES["parallax"].parse("--parallax", text)
    except OptionError as refused:
        assert str(refused) == str(info.value)
    else:
        with pytest.raises(OptionError, match=f"^{re.escape(str(info.value))}$"):
            apply_options(load_scene(scene), {"parallax": parsed})


@pytest.mark.parametrize(
    "name, value, field, expected",
    [
        ("capture", "fbo", "capture", "fbo"),
        ("env_size", 128, "texture_size", 128),
    ],
)
def test_planar_options_set_every_planar_mirror(name, value, field, expected):
    two = apply_options(load_scene("two_mirrors"), {name: value})
    assert [getattr(r, field) for r in two.reflectors] == [expected, expected]
    both = apply_options(load_scene("mirror_and_sphere"), {name: value})
    assert getattr(both.reflector("mirror"), field) == expected
    assert both.reflector("sphere") == load_scene("mirror_and_sphere").reflector("sphere")
    with pytest.raises(
        OptionError,
        match=f"^--{name.replace('_', '-')}: scene 'chrome_sphere' has no planar mirror",
    ):
        apply_options(load_scene("sphere"), {name: value})


def test_map_size_sets_curved_reflectors_only():
    both = apply_options(load_scene("mirror_and_sphere"), {"map_size": 64})
    assert curved_reflector(both, "sphere").map_size == 64
    assert both.reflector("mirror") == load_scene("mirror_and_sphere").reflector("mirror")
    with pytest.raises(OptionError, match=r"^--map-size: scene 'lab20' has no curved reflector"):
        apply_options(load_scene("lab20"), {"map_size": 64})


def test_max_bounces_and_cube_faces():
    assert apply_options(load_scene("lab20"), {"max_bounces": 0}).max_bounces == 0
    sky = apply_options(load_scene("lab20"), {"cube_faces": str(SKY_CUBE)})
    assert sky.background.kind == "cube_faces" and sky.background.path == SKY_CUBE
    assert changed_fields(load_scene("lab20"), sky) == {"background"}


def test_set_changes_any_key_path_as_a_file_would():
    lab = load_scene("lab20")
    fovy = apply_options(lab, {"set": ["camera.fovy=30"]})
    assert fovy.camera == replace(lab.camera, fovy=30.0)
    one = apply_options(lab, {"set": "camera.fovy=30"})  # one string from the API
    assert one == fovy
    deep = apply_options(
        lab,
        {
            "set": [
                "camera.eye[1]=3",
                "objects[0].angles=[0, 0, 0]",
                "reflectors[0].backing=[0.1, 0.2, 0.3]",
            ]
        },
    )
    assert deep.camera.eye == (12.0, 3.0, 9.0)
    assert scene_robot(deep).angles == (0.0, 0.0, 0.0)
    assert planar_reflector(deep, "mirror").backing == (0.1, 0.2, 0.3)
    parsed = apply_options(lab, {"set": (("max_bounces", 2), ("description", "x"))})
    assert (parsed.max_bounces, parsed.description) == (2, "x")
    bare = apply_options(lab, {"set": ["name=my_lab"]})  # a bare word is a string
    assert bare.name == "my_lab"


@pytest.mark.parametrize(
    "values, message",
    [
        (
            {"camera": (1.0, 2.0, 3.0), "target": (1.0, 2.0, 3.0)},
            "--target: camera.target: must differ from camera.eye, both are [1.0, 2.0, 3.0]",
        ),
        ({"fovy": 200}, "--fovy: camera.fovy: expected a number at most 179, got 200.0"),
        ({"camera": "1,2,3"}, "--camera: camera.eye: expected an array, got the string '1,2,3'"),
        (
            {"camera": (1.0, float("nan"), 3.0)},
            "--camera: camera.eye[1]: expected a finite number, got nan",
        ),
        (
            {"capture": "fbx"},
            "--capture: reflectors[0].capture: expected one of copy, fbo, "
            "got 'fbx' (did you mean 'fbo'?)",
        ),
        (
            {"env_size": 0},
            "--env-size: reflectors[0].texture_size: expected a whole number from 1 to 4096, got 0",
        ),
        (
            {"max_bounces": 9},
            "--max-bounces: max_bounces: expected a whole number from 0 to 6, got 9",
        ),
        (
            {"method": "spheer"},
            f"--method: reflectors[0].technique: expected one of {reflector_choices()}, "
            "got 'spheer' (did you mean 'sphere'?)",
        ),
        ({"method": 5}, "--method: reflectors[0].technique: expected a string, got the number 5"),
        (
            {"cube_faces": "/no/such/folder"},
            "--cube-faces: '/no/such/folder' is not a folder of six cube faces",
        ),
        ({"set": ["camera.fvoy=30"]}, "--set: camera.fvoy: unknown key; did you mean 'fovy'?"),
        (
            {"set": ["camera..eye=3"]},
            "--set: expected a key path such as camera.eye or "
            "reflectors[0].technique, got 'camera..eye'",
        ),
        (
            {"set": ['reflectors[3].technique="stencil"']},
            "--set: reflectors[3].technique: no item [3] there",
        ),
        ({"set": ["name.x=3"]}, "--set: name.x: 'x' is not inside a table"),
        ({"set": ["fovy"]}, "--set: expected KEY=VALUE (e.g. camera.fovy=30), got 'fovy'"),
        ({"set": ["camera.eye=[1, 2]"]}, "--set: camera.eye: expected 3 numbers, got 2"),
    ],
)
def test_bad_values_are_refused_in_one_line_naming_the_flag(values, message):
    with pytest.raises(OptionError) as info:
        apply_options(load_scene("lab20"), values)
    assert str(info.value) == message
    assert info.value.option == message.split(":")[0]


def test_cube_faces_folder_lacking_a_face_is_named(tmp_path):
    with pytest.raises(
        OptionError,
        match=r"^--cube-faces: background\.cube_faces: cube-face "
        r"folder .* lacks px\.png, nx\.png",
    ):
        apply_options(load_scene("lab20"), {"cube_faces": str(tmp_path)})


def test_an_unknown_option_name_is_a_programming_error():
    with pytest.raises(TypeError, match="unknown option 'zoom'; options are camera, target"):
        apply_options(load_scene("lab20"), {"zoom": 2})


def test_every_option_has_a_flag_and_parses_its_text():
    assert [o.flag for o in OPTIONS] == ["--" + o.name.replace("_", "-") for o in OPTIONS]
    lab = load_scene("lab20")
    texts = {
        "camera": "1,2,3",
        "target": "-4,1,-2",
        "fovy": "30",
        "angles": "0,10,20",
        "method": "stencil",
        "capture": "fbo",
        "env_size": "128",
        "max_bounces": "2",
        "cube_faces": str(SKY_CUBE),
        "set": "camera.near=0.5",
    }
    for name, option in OPTION_NAMES.items():
        if name in ("map_size", "parallax"):
            continue
        value = option.parse(option.flag, texts[name])
        assert apply_options(lab, {name: value}) != lab, name
    assert (
        curved_reflector(
            apply_options(
                load_scene("sphere"),
                {"map_size": OPTION_NAMES["map_size"].parse("--map-size", "64")},
            ),
            "sphere",
        ).map_size
        == 64
    )
    live = apply_options(
        load_scene("sphere"),
        {
            "method": "cube-live",
            "parallax": OPTION_NAMES["parallax"].parse("--parallax", "sphere:4"),
        },
    )
    assert curved_reflector(live, "sphere").parallax == SphereProxy(4.0)


def test_set_key_walks_into_nested_tables_and_arrays():
    document: dict = {"reflectors": [{"technique": "ortho"}]}
    set_key(document, "reflectors[0].technique", "stencil")
    set_key(document, "camera.eye", [1, 2, 3])
    assert document == {"reflectors": [{"technique": "stencil"}], "camera": {"eye": [1, 2, 3]}}
    with pytest.raises(OptionError, match=r"^--x: reflectors\[1\]\.name: no item \[1\] there"):
        set_key(document, "reflectors[1].name", "a", "--x")


# --------------------------------------------------------------------------- parsing


def test_parse_size_floats_and_counts():
    assert parse_size("--size", " 640 x 480 ") == (640, 480)
    assert parse_floats("--camera", "1, -2.5,3e1", 3, "X,Y,Z") == (1.0, -2.5, 30.0)
    assert parse_count("--frames", "12") == 12
    assert check_size((32, 16.0)) == (32, 16) and check_size("8x4") == (8, 4)


@pytest.mark.parametrize("size", [(0, 10), (10,), "ten", (True, 4), (8.5, 4), (9000, 10), None])
def test_check_size_refuses_what_is_not_two_whole_numbers_in_range(size):
    with pytest.raises(OptionError, match=r"^size: expected"):
        check_size(size)


@pytest.mark.parametrize("text", ["-1", "1.5", "x", "", "100001"])
def test_parse_count_refuses_what_is_not_a_whole_number_in_range(text):
    with pytest.raises(
        OptionError,
        match=r"^--frames: expected a whole number from 1 to "
        r"100000",
    ):
        parse_count("--frames", text, 1, 100_000)


CENTERED_MIRROR = """
name = "centred"
[[objects]]
type = "robot"
[[reflectors]]
name = "mirror"
technique = "reflected"
center = [-7.0, 1.0, -2.0]
normal = [1.0, 0.0, 0.0]
width = 8.0
height = 6.0
up = [0.0, 1.0, 0.0]
"""


def test_set_changes_a_mirror_given_by_centre_normal_and_size(tmp_path, capsys):
    """A file that gives its mirror by center, normal, width and height takes --set on
    any of them (the scene is written back with corners, which once made the file's own
    form look like "corners and width both")."""
    import numpy as np

    from mirrorlab.cli import main
    from mirrorlab.scene.loader import load_scene

    path = tmp_path / "centred.toml"
    path.write_text(CENTERED_MIRROR)
    scene = load_scene(path)
    wider = planar_reflector(apply_options(scene, {"set": "reflectors[0].width=12"}), "mirror")
    corners = wider.corner_array
    assert np.allclose(np.ptp(corners, axis=0), (0.0, 6.0, 12.0))
    assert np.allclose(wider.center, (-7.0, 1.0, -2.0))
    assert np.allclose(wider.normal, (1.0, 0.0, 0.0))
    moved = planar_reflector(
        apply_options(
            scene, {"set": ("reflectors[0].center=[-6, 2, 0]", "reflectors[0].height=2")}
        ),
        "mirror",
    )
    assert np.allclose(moved.center, (-6.0, 2.0, 0.0))
    assert np.allclose(np.ptp(moved.corner_array, axis=0), (0.0, 2.0, 8.0))
    turned = planar_reflector(
        apply_options(scene, {"set": "reflectors[0].normal=[1, 0, 1]"}), "mirror"
    )
    assert np.allclose(turned.normal, np.array([1.0, 0.0, 1.0]) / np.sqrt(2))
    # corners then replace the whole form
    given = planar_reflector(
        apply_options(
            scene,
            {
                "set": (
                    "reflectors[0].width=12",
                    "reflectors[0].corners=[[0,0,0],[0,1,0],[0,1,1],[0,0,1]]",
                )
            },
        ),
        "mirror",
    )
    assert np.allclose(given.corner_array[2], (0.0, 1.0, 1.0))
    assert main(["plan", str(path), "--set", "reflectors[0].width=12", "--frames", "1"]) == 0
    capsys.readouterr()
    # the shipped lab's mirror is given by corners: a rectangle, so it takes width too
    lab = apply_options(load_scene("lab20"), {"set": "reflectors[0].width=4"})
    assert np.allclose(
        np.ptp(planar_reflector(lab, "mirror").corner_array, axis=0), (0.0, 8.0, 4.0)
    )


def test_set_refuses_a_size_for_a_mirror_whose_corners_are_no_rectangle(tmp_path):
    from mirrorlab.scene.loader import loads

    scene = loads(
        CENTERED_MIRROR.replace(
            "center = [-7.0, 1.0, -2.0]\nnormal = [1.0, 0.0, 0.0]\nwidth = 8.0\nheight = 6.0\n"
            "up = [0.0, 1.0, 0.0]",
            "corners = [[-7, -3, -6], [-7, 5, -5], [-7, 5, 2], [-7, -3, 2]]",
        )
    )
    with pytest.raises(OptionError, match=r"--set: reflectors\[0\].width: .*no rectangle"):
        apply_options(scene, {"set": "reflectors[0].width=12"})
