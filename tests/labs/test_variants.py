"""Variants and giving labs out: each student's numbers follow from the course key and
their name (HMAC) and nothing else; every variant's handout, starter and solution render
and compile; ``lab release`` gives each student a folder with their handout, starter,
variant and reference; ``lab solution`` prints a student's variant of the solution
(from the teacher's copy); ``lab grade --key`` gives each honest student full marks and
fails a file copied from another student, saying so (and the teacher's report says
whose); a student's ``lab check`` at home judges against their own released reference."""

from __future__ import annotations

import csv
import html
import json
import re

import pytest

from mirrorlab.labs import find_lab, lab_names, labs
from mirrorlab.labs.content import MARK, handout, solution_for, starter
from mirrorlab.labs.trusted.variants import (
    VariantError,
    default_variant,
    derive_variant,
    header_line,
    read_key,
    student_key,
    variant_from_file,
)
from tests.labs.conftest import LIMITS, SOLUTIONS, mirrorlab_command, read_csv
from tests.labs.mutants import solution

KEY = b"a course key for the tests: 0123456789abcdef"


def test_a_variant_follows_from_the_key_and_the_name_alone():
    for lab in lab_names():
        ada = derive_variant(lab, KEY, "Ada Lovelace")
        for same in ("ada_lovelace", " ADA-LOVELACE "):
            other = derive_variant(lab, KEY, same)
            assert (other.id, other.values) == (ada.id, ada.values)
        assert re.fullmatch(r"[0-9a-f]{8}", ada.id) and ada.student == "Ada Lovelace"
        assert derive_variant(lab, KEY + b"!", "Ada Lovelace").id != ada.id
        for name, value in ada.values.items():
            assert value in find_lab(lab).options[name]
        # a class of 40 gets many different numbers, not one shared set
        ids = {
            tuple(sorted(derive_variant(lab, KEY, f"student {i}").values.items()))
            for i in range(40)
        }
        assert len(ids) >= (10 if lab == "spheremap" else 25), lab
    assert student_key("Ada  Lovelace!") == "ada_lovelace"


def test_every_variant_renders_and_compiles():
    for spec in labs():
        lab = spec.name
        text = (SOLUTIONS / f"{spec.folder}.py").read_text()
        for variant in [
            default_variant(lab),
            *(derive_variant(lab, KEY, f"s{i}") for i in range(12)),
        ]:
            for rendered in (
                handout(spec, variant),
                starter(spec, variant),
                solution_for(text, variant),
            ):
                assert not MARK.search(rendered), MARK.search(rendered)
            compile(starter(spec, variant), "starter.py", "exec")
            compile(solution_for(text, variant), "solution.py", "exec")
            if lab == "lab20":
                x = variant["mirror_x"]
                assert f"plane x = {x:g}" in handout(spec, variant)
                assert f"MIRROR_X = {x:g}" in solution_for(text, variant)
        assert solution_for(text, default_variant(lab)) == text


def test_bad_keys_and_variant_files_are_one_line(tmp_path):
    short = tmp_path / "short.key"
    short.write_bytes(b"too short")
    with pytest.raises(VariantError, match="holds 9 bytes"):
        read_key(short)
    path = tmp_path / "variant.json"
    good = derive_variant("lab20", KEY, "ada").plain()
    for change, message in (
        ({"lab": "cubemap"}, "not of lab20"),
        ({"values": {**good["values"], "mirror_x": -70}}, "mirror_x = -70"),
        ({"values": {"mirror_x": -7}}, "expected the values"),
        ({"id": "../../etc"}, "not a variant id"),
    ):
        path.write_text(json.dumps({**good, **change}))
        with pytest.raises(VariantError, match=re.escape(message)):
            variant_from_file(path, "lab20")
    path.write_text(json.dumps(good))
    assert variant_from_file(path, "lab20").same_numbers(derive_variant("lab20", KEY, "ada"))


@pytest.fixture(scope="module")
def released(tmp_path_factory):
    """Lab 20 released with variants to three students, each submitting: Ada and Ben their
    own variant's solution, Cy a copy of Ada's file."""
    base = tmp_path_factory.mktemp("released")
    (base / "class.txt").write_text("Ada Lovelace\nBen Ng\n\n# late enrolment\nCy Twombly\n")
    key = base / "course.key"
    done = mirrorlab_command(
        "lab",
        "release",
        "lab20",
        str(base / "out"),
        "--students",
        str(base / "class.txt"),
        "--key",
        str(key),
        "--jobs",
        "2",
        "--timeout",
        str(LIMITS.cpu_seconds),
    )
    assert done.returncode == 0, done.stderr
    assert key.stat().st_mode & 0o777 == 0o600
    submissions = base / "submissions"
    submissions.mkdir()
    for student in ("Ada Lovelace", "Ben Ng"):
        printed = mirrorlab_command(
            "lab", "solution", "lab20", "--student", student, "--key", str(key)
        )
        assert printed.returncode == 0, printed.stderr
        (submissions / f"{student.replace(' ', '_')}.py").write_text(printed.stdout)
    (submissions / "Cy_Twombly.py").write_text((submissions / "Ada_Lovelace.py").read_text())
    return base, key, submissions


def test_release_gives_each_student_their_own_numbers(released):
    base, key, _ = released
    folders = sorted(p.name for p in (base / "out").iterdir())
    assert folders == ["Ada_Lovelace", "Ben_Ng", "Cy_Twombly"]
    spec = find_lab("lab20")
    seen = set()
    for folder, student in zip(folders, ("Ada Lovelace", "Ben Ng", "Cy Twombly"), strict=True):
        path = base / "out" / folder
        variant = variant_from_file(path / "variant.json", "lab20")
        assert variant.same_numbers(derive_variant("lab20", read_key(key), student))
        assert (path / "starter.py").read_text() == starter(spec, variant)
        assert (path / "README.md").read_text() == handout(spec, variant)
        assert variant.id in (path / "starter.py").read_text()
        assert sorted(p.name for p in (path / "reference").iterdir()) == [
            "arrays.npz",
            "evidence.json",
        ]
        seen.add(tuple(sorted(variant.values.items())))
    assert len(seen) == 3


def test_grading_with_the_key_passes_the_honest_and_fails_the_copy(released, tmp_path):
    base, key, submissions = released
    out = tmp_path / "grades"
    done = mirrorlab_command(
        "lab",
        "grade",
        "lab20",
        str(submissions),
        "--key",
        str(key),
        "--students",
        str(base / "class.txt"),
        "--out-dir",
        str(out),
        "--jobs",
        "2",
        "--timeout",
        str(LIMITS.cpu_seconds),
    )
    assert done.returncode == 0, done.stderr
    # every output keeps the class list's names (the files are Ada_Lovelace.py ...)
    book = {row["student"]: row for row in read_csv(out / "gradebook.csv")}
    assert book["Ada Lovelace"]["score"] == book["Ben Ng"]["score"] == "8"
    assert book["Ada Lovelace"]["copy_of"] == book["Ben Ng"]["copy_of"] == ""
    # --copies=flag (the default): the score as judged, the copy named in the gradebook
    assert int(book["Cy Twombly"]["score"]) < 8
    assert book["Cy Twombly"]["copy_of"] == "Ada Lovelace"
    assert book["Cy Twombly"]["variant"] == derive_variant("lab20", read_key(key), "Cy Twombly").id
    assert "copy: 'Cy Twombly' carries the numbers of Ada Lovelace" in done.stdout
    copied = [row for row in read_csv(out / "grades.csv") if row["student"] == "Cy Twombly"]
    failed = {row["task"]: row["hint"] for row in copied if row["passed"] == "no"}
    assert "another student's" in failed["task 1 (capture_camera)"]
    assert "another student's" in failed["task 7 (mirror_quad)"]
    report = (out / "report.html").read_text()
    assert "numbers of Ada Lovelace" in report
    # the flag sits in the score's cell (the second column, on screen at any width)
    found = re.search(
        r'<tr data-student="Cy Twombly"><td[^>]*>[^<]*</td>'
        r'(<td class="score".*?</td>)',
        report,
    )
    assert found is not None
    score_cell = found.group(1)
    assert "copy: the numbers of Ada Lovelace" in score_cell
    page = html.unescape(
        re.sub(
            r"data:image/png;base64,[A-Za-z0-9+/=]+",
            "",
            (out / "feedback" / "Cy_Twombly.html").read_text(),
        )
    )
    assert "another student's" in page and "Ada" not in page


def test_a_student_checks_against_their_own_released_reference(released):
    """At home: no solutions, no key; the folder's variant.json and reference/ say what is
    right for this student."""
    base, _, submissions = released
    folder = base / "out" / "Ben_Ng"
    mine = folder / "mine.py"
    mine.write_text((submissions / "Ben_Ng.py").read_text())
    done = mirrorlab_command(
        "lab",
        "check",
        "lab20",
        str(mine),
        "--out",
        str(folder / "check.png"),
        "--timeout",
        str(LIMITS.cpu_seconds),
        env={"MIRRORLAB_SOLUTIONS": None, "MIRRORLAB_CACHE": str(base)},
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert "8/8 tasks passed" in done.stdout
    copied = folder / "copied.py"
    copied.write_text((submissions / "Ada_Lovelace.py").read_text())
    done = mirrorlab_command(
        "lab",
        "check",
        "lab20",
        str(copied),
        "--out",
        str(folder / "check.png"),
        "--timeout",
        str(LIMITS.cpu_seconds),
        env={"MIRRORLAB_SOLUTIONS": None},
    )
    # judged by Ben's numbers: the call trace names the arguments his mirror takes
    assert done.returncode == 1, done.stdout
    assert re.search(r"glOrtho at line \d+ \(.*\) has .*\(the solution's: ", done.stdout), (
        done.stdout
    )


def test_copies_policy_and_names_off_the_class_list(released, tmp_path):
    """--copies=zero books a copy at 0; a submission by a name not on the class list is
    reported (one line, and in the report) and not graded; a listed student with no
    submission is reported too."""
    base, key, submissions = released
    folder = tmp_path / "class"
    folder.mkdir()
    (folder / "cy_twombly.py").write_text((submissions / "Ada_Lovelace.py").read_text())
    (folder / "Zed_Stranger.py").write_text((submissions / "Ben_Ng.py").read_text())
    out = tmp_path / "grades"
    done = mirrorlab_command(
        "lab",
        "grade",
        "lab20",
        str(folder),
        "--key",
        str(key),
        "--students",
        str(base / "class.txt"),
        "--copies",
        "zero",
        "--out-dir",
        str(out),
        "--timeout",
        str(LIMITS.cpu_seconds),
    )
    assert done.returncode == 0, done.stderr
    assert (
        f"not graded: 'Zed_Stranger' (Zed_Stranger.py) is not on the class list "
        f"{base / 'class.txt'}" in done.stdout.splitlines()
    )
    assert "no submission: 'Ada Lovelace' of the class list" in done.stdout
    assert "graded 1 submissions" in done.stdout
    book = read_csv(out / "gradebook.csv")
    assert [row["student"] for row in book] == ["Cy Twombly"]
    assert (book[0]["score"], book[0]["percent"], book[0]["copy_of"]) == (
        "0",
        "0.0",
        "Ada Lovelace",
    )
    assert {row["student"] for row in read_csv(out / "grades.csv")} == {"Cy Twombly"}
    assert not (out / "feedback" / "Zed_Stranger.html").exists()
    report = (out / "report.html").read_text()
    assert re.search(r'id="unlisted">[^<]*<b>Zed_Stranger</b>', report)
    assert re.search(r'id="missing">[^<]*Ada Lovelace', report)
    assert "scored 0 (--copies=zero)" in report


def test_a_csv_class_list_names_every_output_and_the_canvas_gradebook(released, tmp_path):
    """The class as a CSV with ids and emails: submissions named by an id, an email's
    name and a name; every output says the list's names and ids; --format canvas writes
    Canvas's import layout. Ada's file carries a header naming Ben's variant: lab grade
    never reads it (a variant follows from the key and the name), so she passes."""
    _, key, submissions = released
    roster = tmp_path / "class.csv"
    roster.write_text(
        "id,name,email\n"
        "s1001,Ada Lovelace,ada@uni.edu\n"
        "s1002,Ben Ng,ben.ng@uni.edu\n"
        "s1003,Cy Twombly,cy@uni.edu\n"
    )
    ben = derive_variant("lab20", read_key(key), "Ben Ng")
    folder = tmp_path / "class"
    folder.mkdir()
    ada = (submissions / "Ada_Lovelace.py").read_text()
    (folder / "s1001.py").write_text(header_line(ben) + ada)
    (folder / "ben.ng@uni.edu.py").write_text((submissions / "Ben_Ng.py").read_text())
    (folder / "Twombly, Cy").mkdir()
    (folder / "Twombly, Cy" / "starter.py").write_text(ada)
    out = tmp_path / "grades"
    done = mirrorlab_command(
        "lab",
        "grade",
        "lab20",
        str(folder),
        "--key",
        str(key),
        "--students",
        str(roster),
        "--format",
        "canvas",
        "--assignment",
        "Lab 20 (4411)",
        "--out-dir",
        str(out),
        "--jobs",
        "2",
        "--timeout",
        str(LIMITS.cpu_seconds),
    )
    assert done.returncode == 0, done.stdout + done.stderr
    assert "copy: 'Cy Twombly (s1003)' carries the numbers of Ada Lovelace (s1001)" in done.stdout
    with open(out / "gradebook.csv", newline="") as stream:
        table = list(csv.reader(stream))
    assert table[:2] == [
        ["Student", "ID", "SIS User ID", "SIS Login ID", "Section", "Lab 20 (4411)"],
        ["Points Possible", "", "", "", "", "8"],
    ]
    assert [row[:5] for row in table[2:]] == [
        ["Ada Lovelace", "", "s1001", "ada@uni.edu", ""],
        ["Ben Ng", "", "s1002", "ben.ng@uni.edu", ""],
        ["Cy Twombly", "", "s1003", "cy@uni.edu", ""],
    ]
    assert table[2][5] == table[3][5] == "8" and int(table[4][5]) < 8
    rows = read_csv(out / "grades.csv")
    assert {(r["student"], r["id"]) for r in rows} == {
        ("Ada Lovelace", "s1001"),
        ("Ben Ng", "s1002"),
        ("Cy Twombly", "s1003"),
    }
    page = (out / "feedback" / "Ada_Lovelace.html").read_text()
    assert "Ada Lovelace (s1001)" in page and "8 of 8 tasks passed" in page
    assert '<span class="id">s1002</span>' in (out / "report.html").read_text()


def test_a_released_starter_checked_away_from_its_folder_is_judged_by_its_header(
    released, tmp_path
):
    """Ben's finished file without variant.json beside it: with its header, judged against
    Ben's numbers (the reference from the solutions) or told in one line where its
    reference is. (Without a header it is judged against the lab's own numbers, and told
    so: test_unsandboxed.py's check of the solution.)"""
    _, key, submissions = released
    ben = derive_variant("lab20", read_key(key), "Ben Ng")
    headed = tmp_path / "headed.py"
    headed.write_text(header_line(ben) + (submissions / "Ben_Ng.py").read_text())
    command = ("lab", "check", "lab20")
    limit = ("--timeout", str(LIMITS.cpu_seconds))
    done = mirrorlab_command(*command, str(headed), *limit, env={"MIRRORLAB_SOLUTIONS": None})
    assert done.returncode == 2 and done.stdout == "", done.stdout + done.stderr
    assert done.stderr.strip().splitlines() == [
        f"mirrorlab lab: error: no reference for variant {ben.id} of lab20: its released "
        f"folder's reference/ is missing; give --solutions DIR (the teacher's labs/solutions)"
    ]
    done = mirrorlab_command(*command, str(headed), *limit, "--out", str(tmp_path / "a.png"))
    assert done.returncode == 0 and "8/8 tasks passed" in done.stdout, done.stdout + done.stderr
    assert f"(variant {ben.id})" in done.stdout and done.stderr == ""


@pytest.mark.parametrize("lab", ["spheremap", "cubemap"])
def test_the_other_labs_variants_fail_a_copied_file(lab, tmp_path):
    """A student's own variant of the sphere- or cube-map solution passes; the lab's own
    solution, handed in by that student, fails saying it is another variant's."""
    spec = find_lab(lab)
    for i in range(100):  # a student whose numbers change the answer
        variant = derive_variant(lab, KEY, f"student {i}")
        default = default_variant(lab)
        if (
            lab == "spheremap"
            and (variant["shader_side"], variant["unit"])
            != (default["shader_side"], default["unit"])
        ) or (lab == "cubemap" and not variant.same_numbers(default)):
            break
    student = variant.student
    (tmp_path / "key").write_bytes(KEY)
    folder = tmp_path / "class"
    folder.mkdir()
    name = student.replace(" ", "_")
    (folder / f"{name}.py").write_text(solution_for(solution(lab), variant))
    (folder / "default_copy.py").write_text(solution(lab))
    names = f"{student}\ndefault copy\n"
    if lab == "spheremap":  # one file for every variant's unit (issue 44, forged pass 6)
        shared = next(
            v for i in range(100) if (v := derive_variant(lab, KEY, f"shared {i}"))["unit"]
        )
        (folder / f"{shared.student.replace(' ', '_')}.py").write_text(
            shared_file(solution_for(solution(lab), shared))
        )
        names += f"{shared.student}\n"
    (tmp_path / "class.txt").write_text(names)
    out = tmp_path / "grades"
    done = mirrorlab_command(
        "lab",
        "grade",
        lab,
        str(folder),
        "--key",
        str(tmp_path / "key"),
        "--students",
        str(tmp_path / "class.txt"),
        "--copies",
        "hold",
        "--out-dir",
        str(out),
        "--jobs",
        "2",
        "--timeout",
        str(LIMITS.cpu_seconds),
    )
    assert done.returncode == 0, done.stderr
    # the outputs say the class list's names (the files are student_N.py, default_copy.py)
    rows = read_csv(out / "grades.csv")
    mine = [r for r in rows if r["student"] == student]
    assert mine and all(r["passed"] == "yes" for r in mine), mine
    theirs = [r for r in rows if r["student"] == "default copy"]
    assert theirs and not all(r["passed"] == "yes" for r in theirs)
    # the lab's own numbers are another variant's for this student (unless both are alike)
    own = derive_variant(lab, KEY, "default_copy")
    if not own.same_numbers(default_variant(lab)):
        assert any("the lab" in r["hint"] or "another" in r["hint"] for r in theirs), theirs
        # --copies=hold: the gradebook flags the default variant's copy and books no score
        book = {row["student"]: row for row in read_csv(out / "gradebook.csv")}
        assert (
            book["default copy"]["copy_of"],
            book["default copy"]["score"],
            book["default copy"]["percent"],
        ) == ("default variant", "", "")
        assert book[student]["copy_of"] == "" and book[student]["score"] == str(len(spec.tasks))
    assert len(spec.tasks) == len(theirs)
    if lab == "spheremap":
        hints = {r["task"]: r for r in rows if r["student"] == shared.student}
        failed = [r for r in hints.values() if r["passed"] == "no"]
        assert failed and "a file made for several variants" in failed[0]["hint"], hints
        book = {row["student"]: row for row in read_csv(out / "gradebook.csv")}
        assert book[shared.student]["copy_of"], book[shared.student]


def shared_file(source: str) -> str:
    """A sphere-map solution that sets texgen up, and switches it on, on every unit a variant
    can name: the texgen cone looks right whatever the variant's unit."""
    units = "(0, 2, 3)"
    source = source.replace(
        "    glActiveTexture(GL_TEXTURE0 + UNIT)\n    glTexGeni(GL_S",
        f"    for unit in {units}:\n        glActiveTexture(GL_TEXTURE0 + unit)\n"
        "        glTexGeni(GL_S, GL_TEXTURE_GEN_MODE, GL_SPHERE_MAP)\n"
        "        glTexGeni(GL_T, GL_TEXTURE_GEN_MODE, GL_SPHERE_MAP)\n"
        "    glActiveTexture(GL_TEXTURE0 + UNIT)\n    glTexGeni(GL_S",
    )
    return source.replace(
        "    glEnable(GL_TEXTURE_GEN_S)\n    glEnable(GL_TEXTURE_GEN_T)\n",
        f"    for unit in {units}:\n        glActiveTexture(GL_TEXTURE0 + unit)\n"
        "        glEnable(GL_TEXTURE_GEN_S)\n        glEnable(GL_TEXTURE_GEN_T)\n"
        "    glActiveTexture(GL_TEXTURE0 + UNIT)\n",
    )
