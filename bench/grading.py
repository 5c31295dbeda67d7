"""Submissions graded per minute by `mirrorlab lab grade`, on each engine, side by side;
with --before REV, also the checker of an earlier revision beside this one: the seconds
of one `mirrorlab lab check` and submissions a minute of `lab grade --jobs 2`, what
running the student's file behind the pipe costs.

    python bench/grading.py [--students 40] [--rounds 2] [--json PATH]
                            [--before REV] [--checks 8] [--skip-engines]

Builds a class of lab 20 submissions (the reference solution, the untouched starter and
every mutant of tests/labs/mutants.py, repeated up to --students), then grades it with
--jobs 1 (in this process, one sandboxed run after another), --jobs 2 on a process pool,
and --jobs 2 on a local Dask cluster of two worker processes (its start-up counted, and
also reported alone). The engines alternate, in rotating order, for --rounds rounds; the
medians are reported. The reference run is made once, before the timings.

--before REV exports REV of this repository (git archive) into a temporary folder, makes a
venv beside it whose mirrorlab is that export and whose other packages are this venv's
(a .pth file; same interpreter, same machine), and runs its command line alternating with
this checkout's, for --checks checks of the reference solution and --rounds gradings of
the class at --jobs 2: both judge the same files, each against its own cached (or
shipped) reference. (The export and its venv sit one folder below the temporary folder:
an earlier sandbox could not reach a venv deeper.)
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from mirrorlab.labs import find_lab  # noqa: E402
from mirrorlab.labs.trusted.checker import reference_evidence  # noqa: E402
from mirrorlab.labs.trusted.grading import grade_folder  # noqa: E402
from mirrorlab.labs.trusted.sandbox import Limits  # noqa: E402
from mirrorlab.labs.trusted.variants import default_variant  # noqa: E402
from tests.labs.classroom import starter_text  # noqa: E402
from tests.labs.mutants import EQUIVALENT, LAB20, solution  # noqa: E402

ENGINES = {
    "--jobs 1": (1, "pool"),
    "--jobs 2 (pool)": (2, "pool"),
    "--jobs 2 --engine dask (2 workers)": (2, "dask"),
}


def make_class(folder: Path, students: int) -> None:
    sources = [
        solution("lab20"),
        starter_text("lab20"),
        *(m.source() for m in (*LAB20, *EQUIVALENT)),
    ]
    for i in range(students):
        (folder / f"student{i:03d}.py").write_text(sources[i % len(sources)])


def command(python: str, *args: str, cache: Path) -> float:
    """Seconds one ``mirrorlab ARGS`` takes, run by ``python`` (this venv's, or the venv of
    an exported earlier revision)."""
    env = {**os.environ, "MIRRORLAB_CACHE": str(cache)}
    env.pop("MIRRORLAB_SOLUTIONS", None)
    started = time.perf_counter()
    done = subprocess.run(
        [python, "-m", "mirrorlab.cli", *args], cwd=cache, env=env, capture_output=True, text=True
    )
    seconds = time.perf_counter() - started
    if done.returncode not in (0, 1) or (done.returncode == 1 and args[1] == "grade"):
        raise SystemExit(f"{' '.join(args)} failed: {done.stderr.strip()[-500:]}")
    if args[1] == "check" and "tasks passed" not in done.stdout:
        raise SystemExit(
            f"{' '.join(args)} judged nothing: {done.stdout[-300:]} {done.stderr.strip()[-500:]}"
        )
    return seconds


def compare(before: str, folder: Path, checks: int, rounds: int, students: int) -> dict:
    """This checkout's checker and REV's, side by side (see the module's text)."""
    old = Path(tempfile.mkdtemp(prefix="mirrorlab-bench-before-"))
    venv = Path(tempfile.mkdtemp(prefix="mirrorlab-bench-venv-"))
    cache = Path(tempfile.mkdtemp(prefix="mirrorlab-bench-cache-"))
    try:
        archive = subprocess.run(
            ["git", "-C", str(REPO), "archive", before], capture_output=True, check=True
        )
        subprocess.run(["tar", "-x", "-C", str(old)], input=archive.stdout, check=True)
        for made in (old, venv, cache):  # an earlier sandbox's dropped user must enter them
            made.chmod(0o755)
        base = Path(getattr(sys, "_base_executable", sys.executable)).resolve()
        subprocess.run([str(base), "-m", "venv", "--without-pip", str(venv)], check=True)
        site = next(venv.glob("lib/python3*/site-packages"))
        import numpy

        (site / "before.pth").write_text(f"{old}\n{Path(numpy.__file__).parent.parent}\n")
        solution_file = folder / "student000.py"
        designs = {
            f"before ({before})": str(venv / "bin" / "python"),
            "after (this checkout)": sys.executable,
        }
        out = cache / "check.png"
        for design in designs.values():  # warm: each design makes or finds its reference
            command(
                design, "lab", "check", "lab20", str(solution_file), "--out", str(out), cache=cache
            )
        timings: dict[str, dict[str, list[float]]] = {
            n: {"check": [], "grade": []} for n in designs
        }
        names = list(designs)
        for i in range(checks):
            for name in names[i % 2 :] + names[: i % 2]:
                timings[name]["check"].append(
                    command(
                        designs[name],
                        "lab",
                        "check",
                        "lab20",
                        str(solution_file),
                        "--out",
                        str(out),
                        cache=cache,
                    )
                )
        for i in range(rounds):
            for name in names[i % 2 :] + names[: i % 2]:
                timings[name]["grade"].append(
                    command(
                        designs[name],
                        "lab",
                        "grade",
                        "lab20",
                        str(folder),
                        "--jobs",
                        "2",
                        "--out-dir",
                        str(cache / "grades"),
                        cache=cache,
                    )
                )
    finally:
        for made in (old, venv, cache):
            shutil.rmtree(made, ignore_errors=True)
    print(
        f"\nthe pipe's cost: {checks} checks of the solution and {rounds} gradings of "
        f"{students} submissions (--jobs 2) each, alternating; medians:"
    )
    print("| checker | one lab check (s) | lab grade --jobs 2 (s) | submissions per minute |")
    print("|---|---:|---:|---:|")
    rows = {}
    for name, values in timings.items():
        check, grade = statistics.median(values["check"]), statistics.median(values["grade"])
        rows[name] = {**values, "per_minute": 60 * students / grade}
        print(f"| {name} | {check:.2f} | {grade:.1f} | {60 * students / grade:.0f} |")
    first, second = (statistics.median(timings[n]["check"]) for n in names)
    print(f"one check: after / before = {second / first:.2f}")
    return rows


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--students", type=int, default=40)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--json", help="write the figures here as JSON")
    parser.add_argument(
        "--before",
        metavar="REV",
        help="also measure the checker of git revision REV beside this one",
    )
    parser.add_argument(
        "--checks", type=int, default=8, help="with --before: lab checks timed per checker"
    )
    parser.add_argument(
        "--skip-engines", action="store_true", help="measure only what --before asks"
    )
    args = parser.parse_args()
    spec, limits = find_lab("lab20"), Limits()
    folder = Path(tempfile.mkdtemp(prefix="mirrorlab-bench-class-"))
    figures: dict = {"students": args.students}
    try:
        make_class(folder, args.students)
        if args.before:
            figures["before_after"] = compare(
                args.before, folder, args.checks, args.rounds, args.students
            )
        if args.skip_engines:
            return _write(args, figures)
        reference_evidence(spec, default_variant(spec.name), None, limits)
        seconds: dict[str, list[float]] = {name: [] for name in ENGINES}
        names = list(ENGINES)
        for round_ in range(args.rounds):
            for name in names[round_ % len(names) :] + names[: round_ % len(names)]:
                jobs, engine = ENGINES[name]
                started = time.perf_counter()
                grades, _ = grade_folder(spec, folder, jobs, None, engine, limits, progress=False)
                seconds[name].append(time.perf_counter() - started)
                assert len(grades) == args.students
        from distributed import LocalCluster

        starts = []
        for _ in range(args.rounds):
            started = time.perf_counter()
            with LocalCluster(
                n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
            ):
                starts.append(time.perf_counter() - started)
    finally:
        shutil.rmtree(folder, ignore_errors=True)
    rows = {}
    print(f"{args.students} lab 20 submissions, {args.rounds} rounds, medians:")
    print("| engine | seconds | submissions per minute |\n|---|---:|---:|")
    for name, values in seconds.items():
        median = statistics.median(values)
        rows[name] = {"seconds": values, "per_minute": 60 * args.students / median}
        print(f"| {name} | {median:.1f} | {60 * args.students / median:.0f} |")
    print(f"Dask LocalCluster(2) start-up alone: {statistics.median(starts):.1f} s")
    figures.update(engines=rows, dask_start=starts)
    return _write(args, figures)


def _write(args: argparse.Namespace, figures: dict) -> int:
    if args.json:
        Path(args.json).write_text(json.dumps(figures, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
