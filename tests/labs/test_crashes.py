"""The crash files (tests/labs/crashes.py): legal files that used to break the checker are
judged, every task with its line and no traceback; the honest ones pass like the
teacher's solution, the others say what was wrong in the words given."""

from __future__ import annotations

import re
from concurrent.futures import ThreadPoolExecutor

import pytest

from mirrorlab.labs import LABS
from tests.labs.conftest import mirrorlab_command
from tests.labs.crashes import CRASHES

TIMEOUT = "20"


@pytest.fixture(scope="module")
def checked(tmp_path_factory, lab_environment):
    folder = tmp_path_factory.mktemp("crashes")

    def check(crash):
        path = folder / f"{crash.name}.py"
        path.write_text(crash.source())
        return mirrorlab_command("lab", "check", crash.lab, str(path), "--out",
                                 str(folder / f"{crash.name}.png"), "--timeout", TIMEOUT)

    with ThreadPoolExecutor(2) as pool:
        return dict(zip((c.name for c in CRASHES), pool.map(check, CRASHES), strict=True))


@pytest.mark.parametrize("crash", CRASHES, ids=[c.name for c in CRASHES])
def test_each_crash_file_is_judged(checked, crash):
    done = checked[crash.name]
    tasks = len(LABS[crash.lab].tasks)
    assert done.stderr == "" and "Traceback" not in done.stdout, done.stdout + done.stderr
    score = re.search(rf"(\d+)/{tasks} tasks passed", done.stdout)
    assert score, done.stdout
    assert "could not be judged" not in done.stdout, done.stdout
    if crash.phrase is None:
        assert int(score.group(1)) == tasks and done.returncode == 0, done.stdout
    else:
        assert crash.phrase in done.stdout, (crash.phrase, done.stdout)
