"""A generated class for lab 20: reference solutions (as files and folders), the forms the
handout allows, the untouched starter, every mutant (two of them twice: two students make
the same mistake), students whose files raise, do not parse or lack a function, and the
attacks on the machine. Each student comes with the verdicts the checker must give: task
id -> (passed, a phrase its hint must contain)."""

from __future__ import annotations

from pathlib import Path

from mirrorlab.labs import find_lab
from mirrorlab.labs.content import starter
from mirrorlab.labs.trusted.variants import default_variant
from tests.labs.mutants import EQUIVALENT, LAB20, solution

TASKS = [t.id for t in find_lab("lab20").tasks]

STARTER = {
    "lab20": {
        "capture_camera": "create_mirror() is never called",
        "capture_scene": "create_mirror() is never called",
        "capture_copy": "create_mirror() is never called",
        "environment_texture": "GL_NEAREST_MIPMAP_LINEAR (GL's default: never set)",
        "base_texture": 'robot["base"].texture is no texture',
        "mirror_texture": "render_mirror() is never called",
        "mirror_quad": "render_mirror() is never called",
        "passes": "create_mirror() is never called",
    },
    "spheremap": {
        "reflection": "reflect_eye: it gives the same value (0, 0, 1) for every input",
        "sphere_coordinates": "sphere_map_st: it gives the same value (0.5, 0.5)",
        "texgen_setup": "makes no glTexGeni(GL_S, GL_TEXTURE_GEN_MODE, GL_SPHERE_MAP)",
        "texgen_draw": "draw_cone_texgen() is never called",
        "side_by_side": "draw_cone_texgen() is never called",
    },
    "cubemap": {
        "face_selection": "cube_face: it gives the same value 0 for every input",
        "face_coordinates": "cube_face_st: it gives the same value (0.5, 0.5)",
        "capture_cameras": "capture_cube() is never called",
        "capture_copy": "capture_cube() is never called",
        "live_frame": "capture_cube() is never called",
    },
}


def starter_text(lab: str) -> str:
    return starter(find_lab(lab), default_variant(lab))


def verdicts(fails: dict[str, str]) -> dict[str, tuple[bool, str]]:
    """Every task of lab 20: failing with its phrase where listed, passing elsewhere."""
    return {task: (False, fails[task]) if task in fails else (True, "") for task in TASKS}


def every_task(phrase: str) -> dict[str, tuple[bool, str]]:
    return {task: (False, phrase) for task in TASKS}


def line_of(text: str, needle: str) -> int:
    return next(i for i, line in enumerate(text.splitlines(), 1) if needle in line)


def attacks(canary_dir: Path, port: int) -> dict[str, tuple[str, dict[str, tuple[bool, str]]]]:
    """The attacks on the machine, by student: each file's text and its verdicts. Two files
    in ``canary_dir`` are targets; the folder and files are writable by anyone, so only
    the sandbox keeps them whole (it cannot even see them). ``port`` is a port this
    machine listens on (loopback): the sandbox has no network, so it is refused there."""
    delete, overwrite = canary_dir / "delete_me.txt", canary_dir / "overwrite_me.txt"
    return {
        "attack_endless_loop": ("while True:\n    pass\n", every_task("CPU-time limit")),
        "attack_fork_bomb": (
            "import os\nwhile True:\n    try:\n        os.fork()\n"
            "    except OSError:\n        pass\n",
            every_task("fork bomb"),
        ),
        # bytes(n), not bytearray(n): it maps zero pages without touching them, so the
        # address-space limit is reached at no CPU cost (bytearray's page faults could
        # reach the CPU limit first on a loaded machine).
        "attack_huge_allocation": (
            "hog = []\nwhile True:\n    hog.append(bytes(256 << 20))\n",
            every_task("MemoryError"),
        ),
        "attack_crash": ("import ctypes\nctypes.string_at(0)\n", every_task("SIGSEGV")),
        "attack_delete_outside": (
            f"import os\nos.remove({str(delete)!r})\n",
            every_task("No such file or directory"),
        ),
        "attack_overwrite_outside": (
            f"open({str(overwrite)!r}, 'w').write('overwritten')\n",
            every_task("No such file or directory"),
        ),
        "attack_network": (
            f"import socket\nsocket.create_connection(('127.0.0.1', {port}), 5)\n",
            every_task("ConnectionRefusedError"),
        ),
    }


def make_class(folder: Path, canary_dir: Path, port: int) -> dict[str, dict[str, tuple[bool, str]]]:
    """Write the class into ``folder``; returns student -> expected verdicts."""
    text, start = solution("lab20"), starter_text("lab20")
    expected: dict[str, dict[str, tuple[bool, str]]] = {}
    files: dict[str, str] = {}

    def add(
        student: str, source: str, verdict: dict[str, tuple[bool, str]], as_folder: str = ""
    ) -> None:
        expected[student] = verdict
        if as_folder:
            (folder / student).mkdir(parents=True)
            (folder / student / as_folder).write_text(source)
        else:
            files[student] = source

    add("ada_solution", text, verdicts({}))
    add("ben_solution_folder", text, verdicts({}), as_folder="starter.py")
    for mutant in EQUIVALENT:
        add(f"dee_{mutant.name}", mutant.source(), verdicts({}))
    add("eli_untouched_starter", start, verdicts(STARTER["lab20"]))
    for i, mutant in enumerate(LAB20):
        add(f"m{i:02d}_{mutant.name}", mutant.source(), verdicts(mutant.fails))
    for mutant in (LAB20[4], LAB20[13]):  # the same mistake, from two students
        add(f"n_{mutant.name}_again", mutant.source(), verdicts(mutant.fails), as_folder="lab20.py")
    typo = text.replace("glOrtho(Z0, Z1, Y0, Y1, 0, 15)", "glOrth(Z0, Z1, Y0, Y1, 0, 15)")
    line = line_of(typo, "glOrth(")
    raised = f"line {line}: glOrth(Z0, Z1, Y0, Y1, 0, 15) -> NameError"
    add(
        "err_name_error",
        typo,
        verdicts(
            {
                "capture_camera": raised,
                "capture_scene": raised,
                "capture_copy": raised,
                "base_texture": "stopped at create_mirror()",
                "mirror_texture": "stopped at create_mirror()",
                "mirror_quad": "stopped at create_mirror()",
                "passes": "stopped at create_mirror()",
            }
        ),
    )
    missing = text.replace("def render_mirror():", "def render_mirrors():")
    add(
        "err_missing_function",
        missing,
        verdicts(
            {
                "mirror_texture": "render_mirror() is missing",
                "mirror_quad": "render_mirror() is missing",
                "passes": "stopped at render_mirror()",
            }
        ),
    )
    broken = text + "\n\ndef half_written(:\n    pass\n"
    add("err_syntax", broken, every_task(f"line {line_of(broken, 'def half_written(:')}"))
    add(
        "err_import",
        "import no_such_module_anywhere\n" + text,
        every_task("line 1: import no_such_module_anywhere -> ModuleNotFoundError"),
    )
    for student, (source, verdict) in attacks(canary_dir, port).items():
        add(student, source, verdict)
    for student, source in files.items():
        (folder / f"{student}.py").write_text(source)
    return expected


def compare(
    rows: list[dict[str, str]], expected: dict[str, dict[str, tuple[bool, str]]]
) -> list[str]:
    """What in ``rows`` (grades.csv as dicts, each task by its name: ``task 1
    (capture_camera)``) differs from ``expected`` (by task id); empty when none."""
    problems = []
    ids = {task.name: task.id for task in find_lab("lab20").tasks}
    got: dict[str, dict[str, tuple[bool, str]]] = {}
    for row in rows:
        task = ids.get(row["task"], f"unknown task {row['task']!r}")
        got.setdefault(row["student"], {})[task] = (row["passed"] == "yes", row["hint"])
    if sorted(got) != sorted(expected):
        problems.append(f"students {sorted(set(got) ^ set(expected))} differ")
    for student, tasks in expected.items():
        for task, (passed, phrase) in tasks.items():
            have = got.get(student, {}).get(task)
            if have is None:
                problems.append(f"{student} {task}: no row")
            elif have[0] != passed or phrase not in have[1]:
                problems.append(f"{student} {task}: got {have}, expected {(passed, phrase)}")
    return problems
