"""The student side's process, started in the sandbox and waiting for its session.

:func:`start_runner` makes a run's box, starts the runner (:mod:`mirrorlab.labs.student.runner`)
in the sandbox with a pipe to this process, and returns at once: the runner loads
Python and its modules while the trusted side gets ready (imports OpenGL, makes its
context and the lab's session), and :class:`~.lab_run.LabRun` then sends it the session.
A runner may be started before its file is known (a warm checker's next run): the file
then comes with the session, as bytes, and the runner writes it into its working folder
(in its scratch: :mod:`.scratch`) before anything of it runs. Either way the runner is a
new process in a new run folder and scratch, which has run nothing of any student's
yet.

This module imports neither OpenGL nor numpy, so that a checker process can start the
runner before it loads them.
"""

from __future__ import annotations

import os
import shutil
from dataclasses import dataclass
from pathlib import Path

from mirrorlab.labs import LabSpec
from mirrorlab.labs.trusted.sandbox import (
    SANDBOX_LAB_SIDE,
    SANDBOX_PACKAGES,
    SANDBOX_SITE,
    STUDENT_PACKAGE,
    Limits,
    Sandboxed,
    interpreter,
    new_box,
    remove_box,
    sandbox_mode,
    user_interpreter,
)

BOX_FILE = "student.py"
"""The student's file in its working folder (whatever it was called)."""
BOOT = (
    "import sys; sys.path[:0] = [{packages!r}]; sys.path.append({site!r}); "
    "from labstudent.runner import main; sys.exit(main(sys.argv[1:]))"
)


def _offer_numpy(folder: Path) -> str:
    """A folder that offers numpy alone (links to its folders), as the sandbox does; where
    links cannot be made (Windows without the right), numpy's own site folder."""
    from mirrorlab.labs.trusted.sandbox import numpy_folders

    found = numpy_folders()
    folder.mkdir()
    try:
        for source in found:
            (folder / source.name).symlink_to(source, target_is_directory=True)
    except OSError:
        return str(found[0].parent) if found else ""
    return str(folder)


@dataclass
class Runner:
    """A runner started in the sandbox, waiting for its session: its run folder ``box``,
    its process (``sandbox``), this side's ends of its pipe (``read_fd``, ``write_fd``),
    the paths by which it finds the student's ``file`` and the lab's student side
    (``lab_side``), and whether its working folder holds the file yet (``has_file``: when
    not, the session carries it)."""

    box: Path
    sandbox: Sandboxed
    read_fd: int
    write_fd: int
    file: str
    lab_side: str
    has_file: bool

    def release(self) -> None:
        """End a runner that no run took: its process, its pipe and its run folder."""
        self.sandbox.kill()
        self.sandbox.wait(timeout=10)
        for fd in (self.read_fd, self.write_fd):
            try:
                os.close(fd)
            except OSError:
                pass
        remove_box(self.box)


def start_runner(
    spec: LabSpec, limits: Limits, owner: int | None = None, source: bytes | None = None
) -> Runner:
    """Start ``spec``'s runner in a new run folder, with ``source`` (the student's file) in
    its working folder, or without a file yet when ``source`` is None; SandboxError when
    it cannot start."""
    box = new_box()
    try:
        mode = sandbox_mode()
        lab_side = spec.student_file
        if mode == "bwrap":
            python, packages, site = interpreter(), SANDBOX_PACKAGES, SANDBOX_SITE
            lab_side_path = SANDBOX_LAB_SIDE
        else:  # the student side beside the scratch, where the run may read, not write
            library = box / "lib"
            library.mkdir()
            python, packages, site = user_interpreter(), str(library / "pkg"), ""
            if mode == "none":
                python, site = interpreter(), _offer_numpy(library / "site")
            shutil.copytree(
                STUDENT_PACKAGE,
                library / "pkg" / "labstudent",
                ignore=shutil.ignore_patterns("__pycache__"),
            )
            shutil.copyfile(lab_side, library / "pkg" / "lab_side.py")
            lab_side_path = str(library / "pkg" / "lab_side.py")
        argv = [str(python), "-I", "-S", "-B", "-c", BOOT.format(packages=packages, site=site)]
        sandbox = Sandboxed(
            argv,
            box,
            limits,
            pipe=True,
            owner=owner,
            lab_side=lab_side,
            files={} if source is None else {BOX_FILE: source},
        )
    except BaseException:
        remove_box(box)
        raise
    # the pipe: the runner's stdin and stdout, as file descriptors of this side's own
    process = sandbox.process
    assert process.stdin is not None and process.stdout is not None
    read_fd, write_fd = os.dup(process.stdout.fileno()), os.dup(process.stdin.fileno())
    process.stdout.close()
    process.stdin.close()
    path = sandbox.place(BOX_FILE)
    return Runner(box, sandbox, read_fd, write_fd, path, lab_side_path, source is not None)
