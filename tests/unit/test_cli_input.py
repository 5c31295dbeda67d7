"""Command-line input checking, without GL: each bad value gets a one-line error naming it."""

import pytest

from mirrorlab.cli import (
    UsageError,
    join_negative_vectors,
    main,
    parse_floats,
    parse_size,
)


def test_parse_size_and_vectors():
    assert parse_size("--size", "640x480") == (640, 480)
    assert parse_floats("--camera", "1, -2.5,3e1", 3, "X,Y,Z") == (1.0, -2.5, 30.0)


@pytest.mark.parametrize("text", ["640", "0x10", "10x-1", "axb", "9000x10", ""])
def test_bad_sizes_are_refused(text):
    with pytest.raises(UsageError, match="--size"):
        parse_size("--size", text)


@pytest.mark.parametrize("text", ["1,2", "1,2,3,4", "1,x,3", "1,nan,3", "1,inf,2"])
def test_bad_vectors_are_refused(text):
    with pytest.raises(UsageError, match="--angles"):
        parse_floats("--angles", text, 3, "BASE,LOWER,UPPER")


def test_negative_vectors_may_follow_their_option_as_a_separate_word():
    assert join_negative_vectors(["render", "--target", "-4,1,-2", "--out", "a.png"]) == [
        "render", "--target=-4,1,-2", "--out", "a.png"]


@pytest.mark.parametrize("argv, words", [
    (["render", "--angles", "1,2"], "--angles"),
    (["render", "--out", "picture.jpg"], "--out"),
    (["render", "--save-env", "env.bmp"], "--save-env"),
    (["render", "--camera", "1,2,3", "--target", "1,2,3"], "must differ"),
    (["demo", "--size", "big"], "--size"),
])
def test_main_reports_bad_input_in_one_line_with_exit_2(argv, words, capsys, tmp_path,
                                                        monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert words in err and "\n" not in err
    assert not any(tmp_path.iterdir())  # nothing written
