"""Command-line input checking, without GL: each bad value gets a one-line error naming it,
exit status 2, and nothing written."""

import json
import pkgutil

import pytest

from mirrorlab import commands
from mirrorlab.cli import COMMANDS, build_parser, join_negative_vectors, main
from mirrorlab.commands.arguments import scene_from_args
from mirrorlab.options import OptionError, parse_floats, parse_size
from mirrorlab.scene.loader import load_scene


def test_parse_size_and_vectors():
    assert parse_size("--size", "640x480") == (640, 480)
    assert parse_floats("--camera", "1, -2.5,3e1", 3, "X,Y,Z") == (1.0, -2.5, 30.0)


@pytest.mark.parametrize("text", ["640", "0x10", "10x-1", "axb", "9000x10", ""])
def test_bad_sizes_are_refused(text):
    with pytest.raises(OptionError, match=r"^--size: "):
        parse_size("--size", text)


@pytest.mark.parametrize("text", ["1,2", "1,2,3,4", "1,x,3", "1,nan,3", "1,inf,2"])
def test_bad_vectors_are_refused(text):
    with pytest.raises(OptionError, match=r"^--angles: "):
        parse_floats("--angles", text, 3, "BASE,LOWER,UPPER")


def test_negative_vectors_may_follow_their_option_as_a_separate_word():
    assert join_negative_vectors(["render", "--target", "-4,1,-2", "--out", "a.png"]) == [
        "render",
        "--target=-4,1,-2",
        "--out",
        "a.png",
    ]
    assert join_negative_vectors(["render", "--fovy", "-5"]) == ["render", "--fovy=-5"]
    assert join_negative_vectors(["render", "--out", "-4.png"]) == ["render", "--out", "-4.png"]


def test_flags_override_the_scene_file():
    args = build_parser().parse_args(
        join_negative_vectors(
            [
                "render",
                "two_mirrors",
                "--camera",
                "-1,2,9",
                "--method",
                "stencil",
                "--set",
                "max_bounces=3",
                "--set",
                "camera.fovy=40",
            ]
        )
    )
    scene = scene_from_args(args)
    base = load_scene("two_mirrors")
    assert scene.camera.eye == (-1.0, 2.0, 9.0) and scene.camera.fovy == 40.0
    assert scene.max_bounces == 3
    assert [r.technique for r in scene.reflectors] == ["stencil", "stencil"]
    assert scene.objects == base.objects
    assert scene_from_args(build_parser().parse_args(["plan", "--scene", "cone"])) == load_scene(
        "spheremap_cone"
    )


@pytest.mark.parametrize(
    "argv, words",
    [
        (["render", "--angles", "1,2"], "--angles: expected 3 numbers"),
        (["render", "--out", "picture.jpg"], "--out: expected a file name ending in .png"),
        (["render", "--save-env", "env.bmp"], "--save-env"),
        (
            ["render", "--camera", "1,2,3", "--target", "1,2,3"],
            "--target: camera.target: must differ from camera.eye",
        ),
        (
            ["render", "--set", "camera.fvoy=3"],
            "--set: camera.fvoy: unknown key; did you mean 'fovy'?",
        ),
        (["render", "--method", "spheer"], "--method: expected one of ortho, reflected"),
        (["render", "nosuch"], "nosuch: unknown scene; expected a .toml file or one of"),
        (["render", "missing.toml"], "missing.toml: no such scene file"),
        (["render", "lab", "--scene", "cone"], "--scene: give the scene once"),
        (["render", "robot_wave", "--frame", "30"], "--frame: scene robot_wave has frames 0 to 23"),
        (["render", "robot_wave", "--frames", "25"], "--frames: scene robot_wave has 24 frames"),
        (
            ["render", "--frame", "1", "--frames", "2"],
            "--frame and --frames: give one or the other",
        ),
        (["plan", "--frames", "0"], "--frames: expected a whole number from 1"),
        (["plan", "--size", "10x0"], "--size: expected WIDTHxHEIGHT"),
        (["bench", "speed", "--scale-size", "8"], "--scale-size: expected a whole number"),
        (["bench", "accuracy", "--sizes", "64,x"], "--sizes: expected a whole number"),
        (["demo", "--size", "big"], "--size"),
    ],
)
def test_main_reports_bad_input_in_one_line_with_exit_2(argv, words, capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"mirrorlab {argv[0]}: error: ")
    assert words in err and "\n" not in err
    assert not any(tmp_path.iterdir())  # nothing written


def test_a_bad_scene_file_is_named_with_its_key(capsys, tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "bad.toml").write_text("[camera]\nfvoy = 30\n")
    assert main(["plan", "bad.toml"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == (
        "mirrorlab plan: error: bad.toml: camera.fvoy: unknown key; did you mean 'fovy'?"
    )


def test_plan_prints_each_frames_passes_as_json(capsys):
    assert main(["plan", "robot_wave", "--frames", "6", "--size", "64x64", "--json"]) == 0
    document = json.loads(capsys.readouterr().out)
    assert document["scene"] == "robot_wave" and document["size"] == [64, 64]
    captured = [
        any(p["pass"] == "capture" and p["runs"] for p in frame["passes"])
        for frame in document["frames"]
    ]
    assert captured == [True, False, False, False, False, True]
    assert document["frames"][1]["draws"] == [
        {"reflector": "mirror", "technique": "ortho", "mode": "texture", "reason": "its capture"}
    ]


def test_plan_without_the_plan_runs_every_pass(capsys):
    assert main(["plan", "lab20", "--frames", "2", "--no-plan"]) == 0
    out = capsys.readouterr().out
    assert out.count("run  capture mirror") == 2 and "skip " not in out
    assert out.count("2 passes run, 0 skipped") == 2


def test_every_command_module_is_a_command_of_the_parser():
    """A module in mirrorlab/commands/ (besides the shared arguments) is a command: its
    NAME is its module's, and the parser lists it, in COMMANDS' order."""
    modules = {m.name for m in pkgutil.iter_modules(commands.__path__)} - {"arguments"}
    assert {command.__name__.rsplit(".", 1)[1] for command in COMMANDS} == modules
    assert all(command.__name__.endswith("." + command.NAME) for command in COMMANDS)
    subparsers = next(a for a in build_parser()._actions if a.dest == "command")
    assert subparsers.choices is not None
    assert list(subparsers.choices) == [command.NAME for command in COMMANDS]
