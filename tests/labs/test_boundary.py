"""The trust boundary: the student side imports nothing of the trusted side; the sandbox's
file system holds the interpreter, the student side, numpy and the box, and no solution,
reference, cache, checkout or other package; the reference evidence shipped in the
package is what the teachers' solutions give now."""

from __future__ import annotations

import ast
import json
import os
import shutil
import sys
from pathlib import Path

import pytest

from mirrorlab.labs import find_lab, lab_names, labs
from mirrorlab.labs.content import reference_folder
from mirrorlab.labs.trusted import sandbox
from mirrorlab.labs.trusted.checker import CHECK_SIZE, trim_reference
from mirrorlab.labs.trusted.evidence import Evidence
from mirrorlab.labs.trusted.gl_process import run_job
from mirrorlab.labs.trusted.judging import Context, same_picture
from mirrorlab.labs.trusted.sandbox import STUDENT_PACKAGE, Limits, Sandboxed, new_box
from mirrorlab.labs.trusted.variants import default_variant
from tests import REPO_DIR
from tests.labs.conftest import LIMITS, SOLUTIONS


def student_side_imports(path: Path) -> list[str]:
    """The modules ``path`` imports that the student side may not: anything but the
    standard library, numpy, its own package (relative imports) and the shared student
    side (``mirrorlab.labs.student``, which a lab's ``student.py`` imports)."""
    allowed = set(sys.stdlib_module_names) | {"numpy", "__future__"}
    wrong = []
    for node in ast.walk(ast.parse(path.read_text())):
        if isinstance(node, ast.ImportFrom):
            names = [] if node.level >= 1 else [str(node.module)]
        elif isinstance(node, ast.Import):
            names = [alias.name for alias in node.names]
        else:
            continue
        for name in names:
            if name.split(".")[0] not in allowed and not (
                name == "mirrorlab.labs.student" or name.startswith("mirrorlab.labs.student.")
            ):
                wrong.append(name)
    return wrong


def test_the_student_side_imports_only_itself_and_the_standard_library():
    files = sorted(STUDENT_PACKAGE.glob("*.py"))
    assert {p.name for p in files} >= {"runner.py", "wire.py", "gl.py", "kit_standin.py"}
    for path in files:
        assert student_side_imports(path) == [], path.name
    # each lab's own student side: the standard library and the shared student side alone
    for spec in labs():
        assert spec.student_file.is_file(), spec.name
        assert student_side_imports(spec.student_file) == [], spec.student_file
    # the shared student side imports itself relatively: the sandbox binds it as labstudent
    for path in files:
        absolute = [
            node.module
            for node in ast.walk(ast.parse(path.read_text()))
            if isinstance(node, ast.ImportFrom) and node.level == 0
        ]
        assert not [m for m in absolute if str(m).startswith("mirrorlab")], path.name


PROBE = """
import json, os, sys
seen = []
for root, folders, files in os.walk("/"):
    folders[:] = [f for f in folders if os.path.join(root, f) not in ("/proc", "/dev", "/usr")]
    seen += [os.path.join(root, name) for name in files + folders]
print(json.dumps({"seen": seen, "path": sys.path, "uid": os.getuid()}))
"""


def test_the_sandbox_holds_no_answers(tmp_path):
    """What a student's file can see outside /usr (the system's libraries), /proc (its own
    processes) and /dev: the interpreter's own folder, the student side, numpy, its box."""
    if sandbox.sandbox_mode() != "bwrap":
        pytest.fail("bubblewrap is needed (./dev setup installs it)")
    box = new_box(tmp_path)
    try:
        run = Sandboxed(
            [str(sandbox.interpreter()), "-I", "-S", "-c", PROBE],
            box,
            Limits(cpu_seconds=20, seconds=60),
            lab_side=find_lab("lab20").student_file,
            files={"mine.py": b"# a student's file\n"},
        )
        code, _, _ = run.wait()
        assert code == 0, sandbox.tail(box / "stderr.txt")
        found = json.loads((box / "stdout.txt").read_text())
    finally:
        shutil.rmtree(box, ignore_errors=True)
    base = str(Path(sys.base_prefix).resolve())
    allowed = (
        base,
        "/lab/pkg/labstudent",
        sandbox.SANDBOX_LAB_SIDE,
        "/lab/site/numpy",
        "/lab/site/numpy.libs",
        "/lab/box",
        "/etc/ld.so.cache",
        "/tmp",
    )
    skeleton = {
        "/lab",
        "/lab/pkg",
        "/lab/site",
        "/etc",
        "/bin",
        "/sbin",
        "/lib",
        "/lib64",
        "/lib32",
        "/libx32",
        "/usr",
        "/proc",
        "/dev",
    }
    outside = []
    for path in found["seen"]:
        if path in skeleton or any(
            path == a or path.startswith(a + "/") or a.startswith(path + "/") for a in allowed
        ):
            continue
        outside.append(path)
    assert outside == [], outside[:20]
    text = "\n".join(found["seen"])
    for secret in (
        "solutions",
        "/trusted",
        "evidence.json",
        "lab-references",
        os.environ["MIRRORLAB_CACHE"],
        str(REPO_DIR),
        "site-packages/mirrorlab",
    ):
        assert secret not in text, secret
    assert sorted(
        p.rsplit("/", 1)[1] for p in found["seen"] if p.startswith("/lab/pkg/labstudent/")
    ) == sorted(p.name for p in STUDENT_PACKAGE.iterdir() if p.name != "__pycache__")
    assert "/lab/box/mine.py" in found["seen"]
    assert sandbox.SANDBOX_LAB_SIDE in found["seen"]
    if os.geteuid() == 0:
        assert found["uid"] >= sandbox.UID_BASE


@pytest.mark.parametrize("lab", sorted(lab_names()))
def test_the_shipped_reference_is_what_the_solution_gives(lab):
    spec = find_lab(lab)
    shipped = Evidence.load(reference_folder(spec))
    run = run_job(
        spec,
        (SOLUTIONS / f"{spec.folder}.py").read_bytes(),
        "solution.py",
        default_variant(lab),
        LIMITS,
        CHECK_SIZE,
    )
    assert run.status == "ok" and not run.errors and not run.call_errors, run.detail
    fresh = trim_reference(run)
    assert sorted(shipped.arrays) == sorted(fresh.arrays)
    for name, array in fresh.arrays.items():
        if array.dtype.kind == "u" and array.ndim == 3:
            assert same_picture(array, shipped.arrays[name]), name
        elif array.ndim == 4:  # the cube's faces
            assert all(
                same_picture(a, b) for a, b in zip(array, shipped.arrays[name], strict=True)
            ), name
    # the fresh run judged against the shipped evidence passes every task
    results = spec.module("judge").judge(spec, run, shipped, Context(default_variant(lab)))
    assert all(r.passed for r in results), [(r.task.id, r.hint) for r in results if not r.passed]
