"""``mirrorlab lab start | check | run | grade | release | solution``: their arguments;
the work is in :mod:`mirrorlab.labs.trusted`."""

from __future__ import annotations

import argparse
from pathlib import Path

from mirrorlab.commands.arguments import add_executor_arguments
from mirrorlab.files import check_output
from mirrorlab.options import parse_count, parse_size

NAME = "lab"


def add_parser(commands: argparse._SubParsersAction) -> None:
    """The ``lab`` command and its actions' arguments, as a subcommand of ``commands``."""
    lab = commands.add_parser(NAME, help="start, check, run, release and grade the lab exercises")
    lab_commands = lab.add_subparsers(dest="lab_command", required=True, metavar="ACTION")
    limits = argparse.ArgumentParser(add_help=False)
    limits.add_argument(
        "--timeout",
        metavar="SECONDS",
        default="20",
        help="CPU-time limit of one submission (default %(default)s); it may "
        "take three times as long on the clock, plus 30 s",
    )
    limits.add_argument(
        "--memory",
        metavar="MB",
        default="1536",
        help="memory limit of one submission (default %(default)s)",
    )
    solutions = argparse.ArgumentParser(add_help=False)
    solutions.add_argument(
        "--solutions",
        metavar="DIR",
        help="the teacher's solutions (the repository's labs/solutions; "
        "default $MIRRORLAB_SOLUTIONS): references are made from them",
    )
    from mirrorlab.labs import lab_names

    lab_help = f"{', '.join(lab_names())} (or the lab's folder name)"
    start = lab_commands.add_parser(
        "start", help="write a lab's handout (README.md) and starter.py into a folder"
    )
    start.add_argument("lab_name", metavar="LAB", help=lab_help)
    start.add_argument("folder", metavar="DIR", help="a new or empty folder")
    check = lab_commands.add_parser(
        "check",
        parents=[limits, solutions],
        help="check one file: each task passed or failed, with a hint; exit 0 only when all pass",
    )
    check.add_argument("lab_name", metavar="LAB", help=lab_help)
    check.add_argument(
        "file",
        metavar="FILE",
        nargs="?",
        help="the student's file (default: starter.py of the current folder, "
        "where lab start puts it); a variant.json beside it (from lab release) "
        "names its variant",
    )
    check.add_argument(
        "--out", help="the picture student | reference | difference (default out/LAB_check.png)"
    )
    check.add_argument(
        "--watch",
        action="store_true",
        help="check the file again every time it is saved, until Ctrl-C (the checker "
        "stays ready between saves, so each check takes a fraction of the first)",
    )
    run = lab_commands.add_parser(
        "run",
        help="run a lab file in a window (the file itself runs in the sandbox)",
        description="Run a lab file in a window: the lab's set-up functions once, then "
        "display() every frame, drawn as the checker draws it. Esc or the window's close "
        "button ends it; an error in the file is one line naming its task and line.",
    )
    run.add_argument("lab_name", metavar="LAB", help=lab_help)
    run.add_argument(
        "file",
        metavar="FILE",
        nargs="?",
        help="the student's file (default: starter.py of the current folder, where lab "
        "start puts it, as for lab check); a variant.json beside it (from lab release) "
        "names its variant",
    )
    run.add_argument(
        "--size", default="512x512", help="the window's size, WIDTHxHEIGHT (default %(default)s)"
    )
    run.add_argument(
        "--max-frames", metavar="N", default="0", help="close after this many frames (0: until Esc)"
    )
    run.add_argument("--screenshot", metavar="PATH", help="write the last frame as a PNG")
    run.add_argument(
        "--watch",
        action="store_true",
        help="run the file again in the same window every time it is saved",
    )
    grade = lab_commands.add_parser(
        "grade",
        parents=[limits, solutions],
        help="grade a folder of submissions: grades.csv, "
        "gradebook.csv, feedback pages, pictures and report.html",
    )
    grade.add_argument("lab_name", metavar="LAB")
    grade.add_argument(
        "submissions", metavar="SUBMISSIONS_DIR", help="one .py file or one folder per student"
    )
    add_executor_arguments(grade, jobs="submissions graded at once", scheduler="grade on")
    grade.add_argument(
        "--out-dir",
        metavar="DIR",
        help="where grades.csv, report.html and the pictures go (default: "
        "SUBMISSIONS_DIR-grades beside the submissions)",
    )
    grade.add_argument(
        "--key",
        metavar="KEYFILE",
        help="the course key the class was "
        "released with: each student is judged against their own variant "
        "(needs --students)",
    )
    grade.add_argument(
        "--students",
        metavar="FILE",
        help="the class list, as for lab release: one name a line, or a .csv with a "
        "header (a name, and an id and an email where it has them); submissions by "
        "nobody on it are reported and not graded, and every output keeps its names "
        "and ids",
    )
    grade.add_argument(
        "--format",
        metavar="LAYOUT",
        default="plain",
        help="gradebook.csv's layout: plain (mirrorlab's own), canvas (Canvas's "
        "gradebook import) or moodle (Moodle's CSV grade import; needs a class list "
        "with ids or emails); default %(default)s",
    )
    grade.add_argument(
        "--assignment",
        metavar="NAME",
        help="the gradebook's column for the lab, as the LMS names the assignment "
        "(Canvas: 'Title (ID)' as its export writes it); default the lab's title",
    )
    grade.add_argument(
        "--copies",
        metavar="POLICY",
        default="flag",
        help="a file carrying another student's variant or the lab's own, in "
        "gradebook.csv: flag (the score as judged, copy_of names whose), zero "
        "(score 0) or hold (no score until you decide); default %(default)s",
    )
    grade.add_argument(
        "--unsandboxed",
        action="store_true",
        help="grade even where there is no sandbox (bubblewrap, Linux only): "
        "each submission then runs as you, able to read and write what you "
        "can; without it, grading there stops (exit 2)",
    )
    release = lab_commands.add_parser(
        "release",
        parents=[limits, solutions],
        help="one folder per student: a handout and starter "
        "with the student's own numbers, and their reference",
    )
    release.add_argument("lab_name", metavar="LAB")
    release.add_argument("out", metavar="OUT", help="where the students' folders go")
    release.add_argument(
        "--students",
        metavar="FILE",
        required=True,
        help="the class list: one name a line, or a .csv with a header (name, id, email)",
    )
    release.add_argument(
        "--key",
        metavar="KEYFILE",
        required=True,
        help="the course key (made, mode 0600, if the file does not exist)",
    )
    release.add_argument(
        "--jobs",
        metavar="J",
        default="1",
        help="references made by J processes at once (default %(default)s)",
    )
    solution = lab_commands.add_parser(
        "solution",
        parents=[solutions],
        help="print one student's variant of the reference solution (teachers only)",
    )
    solution.add_argument("lab_name", metavar="LAB")
    solution.add_argument("--student", metavar="NAME", required=True)
    solution.add_argument("--key", metavar="KEYFILE", required=True)


def run(args: argparse.Namespace) -> int:
    """``mirrorlab lab ACTION``: the action's arguments checked, then its work in
    :mod:`mirrorlab.labs.trusted`."""
    action = args.lab_command
    if action == "start":
        from mirrorlab.labs.trusted.release import run_start

        return run_start(args.lab_name, Path(args.folder))
    if action == "solution":
        from mirrorlab.labs.trusted.release import run_solution

        return run_solution(args.lab_name, args.student, Path(args.key), args.solutions)
    if action == "run":
        from mirrorlab.labs.trusted.window import run_window

        size = parse_size("--size", args.size)
        max_frames = parse_count("--max-frames", args.max_frames, 0, 10**9)
        screenshot = check_output("--screenshot", args.screenshot) if args.screenshot else None
        return run_window(args.lab_name, args.file, size, max_frames, screenshot, watch=args.watch)
    from mirrorlab.labs.trusted.sandbox import Limits

    cpu = parse_count("--timeout", args.timeout, 1, 3600)
    limits = Limits(
        cpu_seconds=cpu,
        seconds=3.0 * cpu + 30,
        memory_mb=parse_count("--memory", args.memory, 256, 1 << 20),
        # without a sandbox: one's own file or solutions, or a grade told so
        unsandboxed=action != "grade" or args.unsandboxed,
    )
    if action == "check":
        from mirrorlab.labs.trusted.checker import run_check

        out = check_output("--out", args.out) if args.out else None
        return run_check(args.lab_name, args.file, out, limits, args.solutions, args.watch)
    if action == "release":
        from mirrorlab.labs.trusted.release import run_release

        jobs = parse_count("--jobs", args.jobs, 1, 1024)
        return run_release(
            args.lab_name,
            Path(args.out),
            Path(args.students),
            Path(args.key),
            args.solutions,
            jobs,
            limits,
        )
    from mirrorlab.labs.trusted.grading import run_grade

    jobs = parse_count("--jobs", args.jobs, 1, 1024)
    return run_grade(
        args.lab_name,
        Path(args.submissions),
        jobs,
        args.scheduler,
        args.engine,
        Path(args.out_dir) if args.out_dir else None,
        limits,
        Path(args.key) if args.key else None,
        args.solutions,
        Path(args.students) if args.students else None,
        args.copies,
        args.format,
        args.assignment,
    )
