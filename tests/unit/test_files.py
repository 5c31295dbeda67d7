"""Output files: staged beside their destination, committed all together or not at all,
and a refused write reported as ``cannot write PATH: REASON``."""

from __future__ import annotations

import pytest

from mirrorlab.errors import WriteError
from mirrorlab.files import OutputError, Outputs, check_output


def listing(folder):
    return sorted(p.name for p in folder.iterdir())


def test_a_failed_commit_puts_every_old_file_back(tmp_path):
    first, second, third = (tmp_path / n for n in ("a.png", "b.png", "c.png"))
    first.write_bytes(b"old a")
    with pytest.raises(WriteError, match=r"^cannot write .*c\.png: Is a directory$"):
        with Outputs() as outputs:
            outputs.add(first, b"new a")
            outputs.add(second, b"new b")
            outputs.add(third, b"new c")
            # After staging, c.png's place is taken by a folder with something in it: the
            # rename onto it fails after a.png and b.png were already renamed.
            third.mkdir()
            (third / "keep").write_bytes(b"")
    assert first.read_bytes() == b"old a"
    assert not second.exists()
    assert listing(tmp_path) == ["a.png", "c.png"]  # no staged or backup files left


def test_a_commit_replaces_every_file_and_leaves_nothing_else(tmp_path):
    first, second = tmp_path / "a.png", tmp_path / "b.png"
    first.write_bytes(b"old a")
    with Outputs() as outputs:
        outputs.add(first, b"new a")
        outputs.add(second, b"new b")
        assert first.read_bytes() == b"old a"  # nothing is in place before the commit
    assert (first.read_bytes(), second.read_bytes()) == (b"new a", b"new b")
    assert listing(tmp_path) == ["a.png", "b.png"]


def test_an_error_before_the_commit_writes_nothing(tmp_path):
    first = tmp_path / "a.png"
    first.write_bytes(b"old a")
    with pytest.raises(KeyboardInterrupt), Outputs() as outputs:
        outputs.add(first, b"new a")
        raise KeyboardInterrupt
    assert first.read_bytes() == b"old a" and listing(tmp_path) == ["a.png"]


def test_two_outputs_to_one_file_are_refused(tmp_path):
    with pytest.raises(OutputError, match="two outputs"), Outputs() as outputs:
        outputs.add(tmp_path / "a.png", b"1")
        outputs.add(tmp_path / "." / "a.png", b"2")
    assert listing(tmp_path) == []


def test_refused_writes_name_the_path_and_the_reason(tmp_path):
    with pytest.raises(WriteError, match=r"^cannot write /proc/x\.png: "):
        check_output("--out", "/proc/x.png")
    with pytest.raises(WriteError, match=r"^cannot write /proc/x\.png: "):
        with Outputs() as outputs:
            outputs.add(tmp_path / "fine.png", b"1")
            outputs.add("/proc/x.png", b"2")
    assert listing(tmp_path) == []


def test_output_folders_must_exist_unless_allowed(tmp_path):
    with pytest.raises(OutputError, match="does not exist"):
        check_output("--out", tmp_path / "missing" / "x.png")
    assert check_output("--out", tmp_path / "made" / "x.png", make_folder=True).name == "x.png"
    with pytest.raises(OutputError, match=r"expected a file name ending in \.png"):
        check_output("--out", tmp_path / "x.jpg")
