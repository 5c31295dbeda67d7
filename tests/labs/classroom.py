"""A generated class for lab 20: reference solutions (as files and folders, one in the lab
text's legacy GL_CLAMP), the untouched starter, every mutant (twice: two students make the
same mistake), students whose files raise, do not parse or lack a function, and the
attacks. Each student comes with the verdicts the checker must give: task id -> (passed,
a phrase its hint must contain)."""

from __future__ import annotations

from pathlib import Path

from mirrorlab.labs import LABS
from tests.labs.mutants import LAB20, LEGACY

TASKS = [t.id for t in LABS["lab20"].tasks]

STARTER = {
    "lab20": {"capture_camera": "did not run", "capture_scene": "draws nothing",
              "capture_copy": "never called", "environment_texture": "mipmaps",
              "base_texture": "base not textured", "mirror_texture": "not called",
              "mirror_quad": "not called", "passes": "never calls create_mirror"},
    "spheremap": {"reflection": "differs from u - 2 (n.u) n",
                  "sphere_coordinates": "differs from Hoff",
                  "texgen_setup": "never drawn", "texgen_draw": "never draws the cone",
                  "side_by_side": "cone is not drawn"},
    "cubemap": {"face_selection": "wrong face", "face_coordinates": "task 1",
                "capture_cameras": "never called", "capture_copy": "never called",
                "live_frame": "never calls capture_cube"},
}


def verdicts(fails: dict[str, str]) -> dict[str, tuple[bool, str]]:
    """Every task of lab 20: failing with its phrase where listed, passing elsewhere."""
    return {task: (False, fails[task]) if task in fails else (True, "") for task in TASKS}


def every_task(phrase: str) -> dict[str, tuple[bool, str]]:
    return {task: (False, phrase) for task in TASKS}


def line_of(text: str, needle: str) -> int:
    return next(i for i, line in enumerate(text.splitlines(), 1) if needle in line)


def attacks(canary_dir: Path, port: int) -> dict[str, tuple[str, dict[str, tuple[bool, str]]]]:
    """The attacks, by student: each file's text and its verdicts. Two files in
    ``canary_dir`` are targets; the folder and files are writable by anyone, so only the
    sandbox keeps them whole. ``port`` is a port this machine listens on (loopback): the
    sandbox has no network, so it is refused there."""
    delete, overwrite = canary_dir / "delete_me.txt", canary_dir / "overwrite_me.txt"
    return {
        "attack_endless_loop": ("while True:\n    pass\n", every_task("CPU-time limit")),
        "attack_fork_bomb": ("import os\nwhile True:\n    try:\n        os.fork()\n"
                             "    except OSError:\n        pass\n", every_task("fork bomb")),
        # bytes(n), not bytearray(n): it maps zero pages without touching them, so the
        # address-space limit is reached at no CPU cost. bytearray zeroes each block, and
        # the kernel's page faults for that took over the 3 s CPU limit on a loaded
        # machine: the verdict then depended on which limit came first.
        "attack_huge_allocation": ("hog = []\nwhile True:\n    hog.append(bytes(256 << 20))\n",
                                   every_task("MemoryError")),
        "attack_crash": ("import ctypes\nctypes.string_at(0)\n", every_task("SIGSEGV")),
        "attack_delete_outside": (f"import os\nos.remove({str(delete)!r})\n",
                                  every_task("Read-only file system")),
        "attack_overwrite_outside": (f"open({str(overwrite)!r}, 'w').write('overwritten')\n",
                                     every_task("Read-only file system")),
        "attack_network": (f"import socket\nsocket.create_connection(('127.0.0.1', {port}), 5)\n",
                           every_task("ConnectionRefusedError")),
    }


def make_class(folder: Path, canary_dir: Path, port: int
               ) -> dict[str, dict[str, tuple[bool, str]]]:
    """Write the class into ``folder``; returns student -> expected verdicts."""
    spec = LABS["lab20"]
    solution, starter = spec.solution.read_text(), spec.starter.read_text()
    expected: dict[str, dict[str, tuple[bool, str]]] = {}
    files: dict[str, str] = {}

    def add(student: str, text: str, verdict: dict[str, tuple[bool, str]],
            as_folder: str = "") -> None:
        expected[student] = verdict
        if as_folder:
            (folder / student).mkdir(parents=True)
            (folder / student / as_folder).write_text(text)
        else:
            files[student] = text

    add("ada_solution", solution, verdicts({}))
    add("ben_solution_folder", solution, verdicts({}), as_folder="starter.py")
    add("cy_solution_only_file", solution, verdicts({}), as_folder="mirror.py")
    for mutant in LEGACY:
        add(f"dee_{mutant.name}", mutant.source(), verdicts(mutant.fails))
    add("eli_untouched_starter", starter, verdicts(STARTER["lab20"]))
    for i, mutant in enumerate(LAB20):
        add(f"m{i:02d}_{mutant.name}", mutant.source(), verdicts(mutant.fails))
        add(f"n{i:02d}_{mutant.name}_again", mutant.source(), verdicts(mutant.fails),
            as_folder="lab20.py")
    typo = solution.replace("glOrtho(-6, 2, -3, 5, 0, 15)", "glOrth(-6, 2, -3, 5, 0, 15)")
    line = line_of(typo, "glOrth(")
    raised = f"line {line}: glOrth(-6, 2, -3, 5, 0, 15) -> NameError"
    add("err_name_error", typo, verdicts({
        "capture_camera": raised, "capture_scene": raised, "capture_copy": raised,
        "mirror_texture": "stopped at create_mirror()", "mirror_quad": "stopped at create_mirror()",
        "passes": "stopped at create_mirror()"}))
    missing = solution.replace("def render_mirror():", "def render_mirrors():")
    add("err_missing_function", missing, verdicts({
        "mirror_texture": "render_mirror() is missing", "mirror_quad": "render_mirror() is missing",
        "passes": "stopped at render_mirror()"}))
    broken = solution + "\n\ndef half_written(:\n    pass\n"
    add("err_syntax", broken, every_task(f"line {line_of(broken, 'def half_written(:')}"))
    add("err_import", "import no_such_module_anywhere\n" + solution,
        every_task("line 1: import no_such_module_anywhere -> ModuleNotFoundError"))
    for student, (text, verdict) in attacks(canary_dir, port).items():
        add(student, text, verdict)
    for student, text in files.items():
        (folder / f"{student}.py").write_text(text)
    return expected


def compare(rows: list[dict[str, str]], expected: dict[str, dict[str, tuple[bool, str]]]
            ) -> list[str]:
    """What in ``rows`` (grades.csv as dicts) differs from ``expected``; empty when none."""
    problems = []
    got: dict[str, dict[str, tuple[bool, str]]] = {}
    for row in rows:
        got.setdefault(row["student"], {})[row["task"]] = (row["passed"] == "yes", row["hint"])
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
