"""``lab check --watch``: each save is checked by the warm checker, whatever way the editor
saves; a save during a check has the newest file checked and the stale report dropped;
Ctrl-C ends it with status 0 and leaves no process and no temporary folder. And the warm
checker's isolation, attacked: what one run leaves (processes, files in its box and its
/tmp, GL state and objects) reaches neither the next run nor the checker."""

from __future__ import annotations

import json
import os
import time
from pathlib import Path

import numpy as np
import pytest

from mirrorlab.labs import find_lab
from mirrorlab.labs.trusted.gl_process import run_job
from mirrorlab.labs.trusted.sandbox import UID_BASE, sandbox_mode, sandboxed, uid_processes
from mirrorlab.labs.trusted.variants import default_variant
from mirrorlab.labs.trusted.warm import WarmProcess
from tests.labs.conftest import LIMITS, leftovers
from tests.labs.mutants import LAB20, solution
from tests.labs.warm_checks import GIVE_UP_S, Watch, save_by_rename

WRONG_EXTENTS = next(m for m in LAB20 if m.name == "wrong_extents")


def wait_for(condition, what: str):
    deadline = time.monotonic() + GIVE_UP_S
    while time.monotonic() < deadline:
        value = condition()
        if value:
            return value
        time.sleep(0.02)
    raise AssertionError(f"timed out waiting for {what}")


def notes_only(errors: str) -> bool:
    """Whether stderr holds nothing but the one note a run without a sandbox prints."""
    lines = [line for line in errors.splitlines() if line.strip()]
    return lines == [] if sandboxed() else len(lines) == 1 and "not sandboxed" in lines[0]


def test_each_save_is_checked_until_ctrl_c_which_leaves_nothing(tmp_path, lab_environment):
    path = tmp_path / "mine.py"
    path.write_text(solution("lab20"))
    with Watch(tmp_path) as watch:
        each_save_is_checked(watch, path, lab_environment)


def each_save_is_checked(watch: Watch, path: Path, lab_environment: Path) -> None:
    assert "8/8 tasks passed" in watch.report()
    checkers = watch.checkers()
    assert len(checkers) == 1

    save_by_rename(path, WRONG_EXTENTS.source())
    report = watch.report()
    cause = WRONG_EXTENTS.fails["capture_camera"]
    assert "[FAIL] task 1 (capture_camera)" in report and cause in report, report

    with open(path, "w") as stream:  # in place, as an editor that truncates and writes
        stream.write(solution("lab20"))
    assert "8/8 tasks passed" in watch.report()

    path.unlink()  # as an editor that removes the file before it writes the new one
    watch.until("is gone; waiting for it")
    path.write_text(WRONG_EXTENTS.source())
    assert "[FAIL] task 1 (capture_camera)" in watch.report()
    assert watch.checkers() == checkers  # one warm checker all along

    code, out, errors = watch.interrupt()
    assert code == 0 and "stopped watching mine.py" in out, (out, errors)
    assert "Traceback" not in out + errors and notes_only(errors), errors
    wait_for(lambda: not any(Path(f"/proc/{pid}").exists() for pid in checkers), "the checker")
    if os.geteuid() == 0 and sandbox_mode() != "none":
        assert uid_processes(UID_BASE + watch.process.pid) == []
    assert leftovers(lab_environment) == []


SLOW = "import time\ntime.sleep(5)\n" + WRONG_EXTENTS.source()
"""A file whose check takes seconds (and would fail task 1)."""


def test_a_save_during_a_check_has_the_newest_file_checked(tmp_path, lab_environment):
    """The stale file takes seconds to load; the save while it runs stops it, and the
    report printed is the new file's alone. Ctrl-C during a check leaves nothing either."""
    path = tmp_path / "mine.py"
    path.write_text(SLOW)
    with Watch(tmp_path) as watch:
        newest_is_checked(watch, path, lab_environment)


def under_way(watch: Watch, lab_environment: Path) -> None:
    """Wait until the watch has a check running (its job's folder is there)."""
    wait_for(
        lambda: list(lab_environment.glob(f"mirrorlab-check-{watch.process.pid}-*")),
        "a check to be under way",
    )


def newest_is_checked(watch: Watch, path: Path, lab_environment: Path) -> None:
    watch.until("watching mine.py")
    under_way(watch, lab_environment)
    save_by_rename(path, solution("lab20"))
    assert "8/8 tasks passed" in watch.report()
    save_by_rename(path, SLOW)
    under_way(watch, lab_environment)
    checkers = watch.checkers()
    code, out, errors = watch.interrupt()
    assert code == 0 and "[FAIL]" not in out and out.count("tasks passed") == 1, out
    assert notes_only(errors), errors
    wait_for(lambda: not any(Path(f"/proc/{pid}").exists() for pid in checkers), "the checker")
    if os.geteuid() == 0 and sandbox_mode() != "none":
        assert uid_processes(UID_BASE + watch.process.pid) == []
    assert leftovers(lab_environment) == []


ADVERSARY = """
import os
for where in (".", "/tmp", os.path.expanduser("~")):
    try:
        with open(os.path.join(where, "left_by_the_last_run.txt"), "w") as note:
            note.write("for the next run")
    except OSError:
        pass
if os.fork() == 0:  # a process that means to outlive its run
    os.setsid()
    if os.fork() == 0:
        os.execv("/usr/bin/sleep", ["sleep", "3141.5"])
    os._exit(0)
"""
"""Put at the top of the solution: notes in its box, its /tmp and its home, and a
detached process. The solution's display() then ends with GL state left on (below)."""
LEFT_STATE = """    glEnable(GL_CULL_FACE)
    glCullFace(GL_FRONT_AND_BACK)
    glColorMask(GL_TRUE, GL_FALSE, GL_FALSE, GL_TRUE)
    glDepthFunc(GL_NEVER)
    glClearColor(1, 0, 0, 1)
    glMatrixMode(GL_PROJECTION)
    glLoadIdentity()
    glScalef(0.1, 0.1, 0.1)
    for texture in glGenTextures(8):
        glBindTexture(GL_TEXTURE_2D, texture)
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGB, 1, 1, 0, GL_RGB, GL_UNSIGNED_BYTE, None)
"""
PROBE = """
import json, os
pids = [p for p in os.listdir("/proc") if p.isdigit()]
commands = []
for pid in pids:
    try:
        commands.append(open(f"/proc/{pid}/cmdline", "rb").read().decode(errors="replace"))
    except OSError:
        pass
raise RuntimeError(json.dumps({
    "box": sorted(os.listdir(".")), "tmp": sorted(os.listdir("/tmp")),
    "sleepers": [c for c in commands if "3141" in c],
}))
"""
"""A file that reports, as its error, what it finds of the run before it."""


def sleepers() -> list[int]:
    found = []
    for entry in Path("/proc").iterdir():
        try:
            if entry.name.isdigit() and b"3141.5" in (entry / "cmdline").read_bytes():
                found.append(int(entry.name))
        except OSError:
            continue
    return found


@pytest.mark.skipif(
    sandbox_mode() == "none", reason="without a sandbox nothing keeps a run's processes in"
)
def test_nothing_of_a_run_reaches_the_next_or_the_checker():
    spec, variant = find_lab("lab20"), default_variant("lab20")
    honest = solution("lab20")
    adversary = ADVERSARY + honest.replace(
        "    render_mirror()\n", "    render_mirror()\n" + LEFT_STATE, 1
    )
    assert adversary.count("glScalef(0.1") == 1
    process = WarmProcess()
    try:

        def run(source: str):
            return run_job(
                spec, source.encode(), "mine.py", variant, LIMITS, (128, 128), process=process
            )

        first = run(honest)
        left = run(adversary)
        assert left.status == "ok" and not left.errors, (left.detail, left.errors)
        wait_for(lambda: not sleepers(), "the detached process to be ended with its run")
        probed = run(PROBE)
        again = run(honest)
    finally:
        process.close()
    seen = json.loads(probed.errors[0]["message"].split("RuntimeError: ", 1)[1])
    assert seen == {"box": ["student.py"], "tmp": [], "sleepers": []}, seen
    assert first.status == again.status == "ok" and not again.errors
    # the state left did change the adversary's own second frame, and nothing after it
    assert not np.array_equal(first.arrays["frame"], left.arrays["frame"])
    assert np.array_equal(first.arrays["frame"], again.arrays["frame"])
    assert sorted(first.textures) == sorted(again.textures)  # the same names: a new context
    assert json.dumps(first.frames, sort_keys=True) == json.dumps(again.frames, sort_keys=True)
