"""A run's scratch space has a total: at most SCRATCH_MB MiB and SCRATCH_FILES files and
folders, its box and its /tmp together, on a tmpfs of its own that the kernel bounds and
throws away whole (bubblewrap as root and as a user, the user-id fallback), or watched and
stopped (no mount namespace: macOS, Windows, MIRRORLAB_SANDBOX=none). Nothing a run makes
stays, however deep or closed, and after any file the next run in the same temporary
folder works: the issue's 3,000-deep tree and 1.5 GB of 64 MiB files among them."""

from __future__ import annotations

import errno
import json
import os
import shutil
import subprocess
import sys
import tempfile
import textwrap
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mirrorlab.labs.trusted import sandbox
from mirrorlab.labs.trusted.scratch import SCRATCH_BYTES, SCRATCH_FILES, WATCH_DEPTH
from tests import REPO_DIR
from tests.labs.conftest import SOLUTIONS, leftovers, mirrorlab_command

FLOOD = textwrap.dedent(
    """
    import json, os
    report = {"bytes": 0, "files": 0, "refused": []}
    chunk = b"\\1" * (16 << 20)
    try:  # the issue's file: 24 files of 64 MiB, each under the per-file limit
        for i in range(24):
            with open(f"f{i}.bin", "wb") as stream:
                for _ in range(4):
                    stream.write(chunk)
                    report["bytes"] += len(chunk)
    except OSError as exc:
        report["refused"].append(exc.errno)
    for name in os.listdir("."):
        if name.endswith(".bin"):
            os.remove(name)
    folder = os.environ.get("TMPDIR", "/tmp")
    try:  # then empty files, in its /tmp, until refused
        for i in range(20000):
            open(os.path.join(folder, f"e{i}"), "w").close()
            report["files"] += 1
    except OSError as exc:
        report["refused"].append(exc.errno)
    print(json.dumps(report))
    """
)

RUNNER = textwrap.dedent(
    """
    import json, sys
    from pathlib import Path
    from mirrorlab.labs.trusted import sandbox
    box = sandbox.new_box(Path(sys.argv[1]))
    user = sandbox.sandbox_mode() == "user"
    python = sandbox.user_interpreter() if user else sandbox.interpreter()
    limits = sandbox.Limits(cpu_seconds=20, seconds=120, unsandboxed=True)
    source = Path(sys.argv[2]).read_bytes()
    run = sandbox.Sandboxed([str(python), "-I", "-S", "student.py"], box, limits,
                            files={"student.py": source})
    code, _, stopped = run.wait()
    on_host = sorted(p.name for p in run.scratch.iterdir())
    output = (box / "stdout.txt").read_text()
    sandbox.remove_box(box)
    print(json.dumps({"mode": sandbox.sandbox_mode(), "kind": run.kind, "code": code,
                      "stopped": stopped, "on_host": on_host, "output": output,
                      "gone": not box.exists()}))
    """
)

WAYS = {
    # how the run is made: (MIRRORLAB_SANDBOX, as a user who is not root)
    "bubblewrap as root": ("", False),
    "bubblewrap as a user": ("", True),
    "the user-id fallback": ("user", False),
    "watched (no mount namespace)": ("none", False),
}


def run_elsewhere(program: Path, folder: Path, mode: str, as_user: bool) -> dict:
    """RUNNER in a process of its own, with MIRRORLAB_SANDBOX=``mode``, as root or (in a
    user namespace of bubblewrap's) as user 1000."""
    environment = {**os.environ, "MIRRORLAB_SANDBOX": mode}
    command = [sys.executable, "-c", RUNNER, str(folder), str(program)]
    if as_user:
        bwrap = shutil.which("bwrap")
        assert bwrap, "bubblewrap is needed (./dev setup installs it)"
        command = [bwrap, "--dev-bind", "/", "/", "--unshare-user", "--uid", "1000"]
        command += ["--gid", "1000", "--die-with-parent", sys.executable, "-c", RUNNER]
        command += [str(folder), str(program)]
    done = subprocess.run(
        command, capture_output=True, text=True, env=environment, cwd=REPO_DIR, timeout=300
    )
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


@pytest.mark.parametrize("way", list(WAYS))
def test_one_run_writes_at_most_its_total_and_leaves_nothing(way, tmp_path):
    if os.geteuid() != 0:
        pytest.fail("the sandbox's ways are tested as root (./dev test runs as root in CI)")
    mode, as_user = WAYS[way]
    program = tmp_path / "flood.py"
    program.write_text(FLOOD)
    # the fallback's own user id must reach its box: a folder others may enter, as /tmp is
    # (on a tmpfs: what the watched way writes before it is stopped costs no disk)
    folder = Path(tempfile.mkdtemp(prefix="mirrorlab-scratch-", dir="/dev/shm"))
    folder.chmod(0o755)
    try:
        found = run_elsewhere(program, folder, mode, as_user)
        assert list(folder.iterdir()) == []
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    assert found["gone"], found
    if mode == "none":
        # no mount namespace: the watch stops it at its first look past the total
        assert found["kind"] == "watched" and found["stopped"] == "scratch", found
        return
    assert found["kind"] == "tmpfs" and found["code"] == 0, found
    report = json.loads(found["output"])
    assert report["refused"] == [errno.ENOSPC, errno.ENOSPC], report
    assert 0 < report["bytes"] <= SCRATCH_BYTES, report
    assert 0 < report["files"] < SCRATCH_FILES, report
    # nothing of it ever reached the host's temporary folder
    assert found["on_host"] == [], found


# ------------------------------------------------------------- any abuse, then an honest run
ACTIONS = st.one_of(
    st.tuples(st.just("deep"), st.integers(1, 3000)),
    st.tuples(st.just("wide"), st.integers(1, 6000), st.sampled_from(["box", "tmp"])),
    st.tuples(st.just("big"), st.integers(1, 320)),
    st.tuples(st.just("sparse"), st.integers(1, 8)),
    st.tuples(st.just("links"), st.integers(1, 3000)),
    st.tuples(st.just("closed"), st.integers(1, 50)),
    st.tuples(st.just("loop")),
    st.tuples(st.just("fifo")),
    st.tuples(st.just("names")),
)

ABUSE = textwrap.dedent(
    """
    import os, sys
    tmp = os.environ.get("TMPDIR", "/tmp")
    def act(kind, *args):
        if kind == "deep":  # a tree deeper than any path may name
            fd = os.open(".", os.O_RDONLY)
            for _ in range(args[0]):
                os.mkdir("d", dir_fd=fd)
                fd, old = os.open("d", os.O_RDONLY, dir_fd=fd), fd
                os.close(old)
        elif kind == "wide":
            where = "." if args[1] == "box" else tmp
            for i in range(args[0]):
                open(os.path.join(where, f"w{i}"), "w").close()
        elif kind == "big":
            with open("big.bin", "ab") as stream:
                for _ in range(args[0]):
                    stream.write(b"\\1" * (1 << 20))
        elif kind == "sparse":
            with open("sparse.bin", "wb") as stream:
                stream.truncate(args[0] << 30)
        elif kind == "links":
            open("target", "a").close()
            for i in range(args[0]):
                os.link("target", f"l{i}")
        elif kind == "closed":  # a folder closed to its owner, full of files
            os.makedirs("closed/inner", exist_ok=True)
            for i in range(args[0]):
                open(f"closed/inner/c{i}", "w").close()
            os.chmod("closed/inner", 0)
            os.chmod("closed", 0)
        elif kind == "loop":
            os.symlink("loop", "loop")
            os.symlink(".", "self")
        elif kind == "fifo":
            os.mkfifo("pipe")
        elif kind == "names":
            for name in ("x" * 255, "new\\nline", "\\u00e9t\\u00e9", "-rf", " "):
                open(name, "w").close()
    for action in ACTIONS:
        try:
            act(*action)
        except OSError as exc:
            print(action[0], exc, file=sys.stderr)
    """
)


def _run(box: Path, source: str) -> tuple[int | None, str, str]:
    limits = sandbox.Limits(cpu_seconds=20, seconds=120, unsandboxed=True)
    run = sandbox.Sandboxed(
        [str(sandbox.interpreter()), "-I", "-S", "student.py"],
        box,
        limits,
        files={"student.py": source.encode()},
    )
    code, _, stopped = run.wait()
    return code, stopped, (box / "stdout.txt").read_text()


@pytest.mark.parametrize("mode", ["bwrap", "none"])
def test_after_any_abuse_of_the_scratch_the_next_run_in_that_folder_works(
    mode, memory_folder, monkeypatch
):
    """Hypothesis: any mix of deep, wide, big, sparse, linked, closed, looping and oddly
    named files; the run's folder is then gone, and the next run works."""
    if mode == "bwrap" and sandbox.sandbox_mode() != "bwrap":
        pytest.fail("bubblewrap is needed (./dev setup installs it)")
    monkeypatch.setattr(sandbox, "sandbox_mode", lambda: mode)
    folder = memory_folder

    @settings(
        max_examples=6,
        deadline=None,
        derandomize=True,
        suppress_health_check=[HealthCheck.function_scoped_fixture],
    )
    @given(st.lists(ACTIONS, min_size=1, max_size=4))
    def abuse_then_honest(actions: list[tuple]) -> None:
        box = sandbox.new_box(folder)
        code, stopped, _ = _run(box, f"ACTIONS = {actions!r}\n{ABUSE}")
        assert code == 0 or stopped == "scratch", (code, stopped)
        sandbox.remove_box(box)
        assert not box.exists() and list(folder.iterdir()) == []
        box = sandbox.new_box(folder)
        code, stopped, output = _run(box, "open('mine.txt', 'w').write('ok')\nprint('ok')\n")
        sandbox.remove_box(box)
        assert (code, stopped, output.strip()) == (0, "", "ok")
        assert list(folder.iterdir()) == []

    abuse_then_honest()


@pytest.fixture
def memory_folder():
    """A folder on a tmpfs (/dev/shm): the trees these tests make cost a disk's metadata
    writes nothing."""
    folder = Path(tempfile.mkdtemp(prefix="mirrorlab-test-", dir="/dev/shm"))
    yield folder
    shutil.rmtree(folder, ignore_errors=True)


def test_a_stale_box_holding_a_deep_tree_is_swept(memory_folder):
    """A box a dead process left (a killed worker), with a tree deeper than Python's
    recursion and than a path may name: the next run's new_box removes it, raising
    nothing."""
    tmp_path = memory_folder
    dead = subprocess.Popen([sys.executable, "-c", "pass"])
    dead.wait()
    stale = tmp_path / f"{sandbox.BOX_PREFIX}{dead.pid}-left"
    stale.mkdir()
    fd = os.open(stale, os.O_RDONLY)
    for _ in range(3000):
        os.mkdir("d", dir_fd=fd)
        fd, old = os.open("d", os.O_RDONLY, dir_fd=fd), fd
        os.close(old)
    os.close(fd)
    box = sandbox.new_box(tmp_path)
    assert sorted(p.name for p in tmp_path.iterdir()) == [box.name]
    sandbox.remove_box(box)


DEEP_AND_BIG = textwrap.dedent(
    """
    import os
    fd = os.open(".", os.O_RDONLY)
    try:
        for _ in range(3000):
            os.mkdir("d", dir_fd=fd)
            fd, old = os.open("d", os.O_RDONLY, dir_fd=fd), fd
            os.close(old)
        for i in range(24):
            with open(f"{os.environ['TMPDIR']}/f{i}.bin", "wb") as stream:
                stream.write(b"\\1" * (64 << 20))
    except OSError:
        pass
    """
)


def test_after_a_3000_deep_tree_and_1_5_gb_the_next_honest_check_passes(tmp_path):
    """The issue's two files in one, checked, then the honest solution checked in the same
    temporary folder: it passes, and nothing of either is left there."""
    folder = tmp_path / "tmp"
    folder.mkdir()
    abusive = tmp_path / "abusive.py"
    abusive.write_text(DEEP_AND_BIG)
    env = {"TMPDIR": str(folder)}
    done = mirrorlab_command(
        "lab", "check", "lab20", str(abusive), "--out", str(tmp_path / "a.png"), env=env
    )
    assert done.returncode == 1 and "Traceback" not in done.stderr, done.stderr
    if sandbox.sandbox_mode() == "none":  # watched: stopped past the total (or the depth)
        assert "stopped when its scratch space held more than" in done.stdout, done.stdout
    assert leftovers(folder) == []
    done = mirrorlab_command(
        "lab",
        "check",
        "lab20",
        str(SOLUTIONS / "lab20_mirror.py"),
        "--out",
        str(tmp_path / "b.png"),
        env=env,
    )
    assert done.returncode == 0 and "8/8 tasks passed" in done.stdout, done.stdout + done.stderr
    assert leftovers(folder) == []


def test_the_watch_measures_without_following_links_or_recursing(tmp_path):
    """measure() counts a file of many names once, follows no link, and says a tree too
    deep to measure is so, without raising."""
    from mirrorlab.labs.trusted.scratch import measure

    (tmp_path / "big").write_bytes(b"1" * (1 << 20))
    for i in range(10):
        os.link(tmp_path / "big", tmp_path / f"name{i}")
    os.symlink("/", tmp_path / "root")
    total, entries, deep = measure(tmp_path)
    assert (1 << 20) <= total < (1 << 20) + 65536 and entries == 12 and not deep
    fd = os.open(tmp_path, os.O_RDONLY)
    for _ in range(WATCH_DEPTH + 2):
        os.mkdir("d", dir_fd=fd)
        fd, old = os.open("d", os.O_RDONLY, dir_fd=fd), fd
        os.close(old)
    os.close(fd)
    assert measure(tmp_path)[2]


def test_a_kernel_that_refuses_the_scratch_file_system_gets_a_watched_one(
    memory_folder, monkeypatch
):
    """Where the kernel refuses the run's mount namespace (a container without it), the run
    starts again with a watched scratch, and so do the process's later runs."""
    from mirrorlab.labs.trusted import scratch

    def refused(*args, **kwargs):
        def prepare() -> None:
            raise PermissionError(1, "unshare: Operation not permitted")

        return prepare

    monkeypatch.setattr(scratch, "tmpfs_preexec", refused)
    monkeypatch.setattr(scratch, "_refused", set())
    mode = sandbox.sandbox_mode()
    for _ in range(2):
        box = sandbox.new_box(memory_folder)
        code, stopped, output = _run(box, "open('mine.txt', 'w').write('ok')\nprint('ok')\n")
        sandbox.remove_box(box)
        assert (code, stopped, output.strip()) == (0, "", "ok")
        assert scratch.scratch_kind(mode) == "watched"
