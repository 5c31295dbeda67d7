"""Submissions graded per minute by `mirrorlab lab grade`, on each engine, side by side.

    python bench/grading.py [--students 40] [--rounds 2] [--json PATH]

Builds a class of lab 20 submissions (the reference solution, the untouched starter and
every mutant of tests/labs/mutants.py, repeated up to --students), then grades it with
--jobs 1 (in this process, one sandboxed run after another), --jobs 2 on a process pool,
and --jobs 2 on a local Dask cluster of two worker processes (its start-up counted, and
also reported alone). The engines alternate, in rotating order, for --rounds rounds; the
medians are reported. The reference run is made once, before the timings.
"""

from __future__ import annotations

import argparse
import json
import shutil
import statistics
import sys
import tempfile
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(REPO))

from mirrorlab.labs import LABS  # noqa: E402
from mirrorlab.labs.trusted.checker import reference_evidence  # noqa: E402
from mirrorlab.labs.trusted.grading import grade_folder  # noqa: E402
from mirrorlab.labs.trusted.sandbox import Limits  # noqa: E402
from mirrorlab.labs.trusted.variants import default_variant  # noqa: E402
from tests.labs.classroom import starter_text  # noqa: E402
from tests.labs.mutants import EQUIVALENT, LAB20, solution  # noqa: E402

ENGINES = {"--jobs 1": (1, "pool"), "--jobs 2 (pool)": (2, "pool"),
           "--jobs 2 --engine dask (2 workers)": (2, "dask")}


def make_class(folder: Path, students: int) -> None:
    sources = [solution("lab20"), starter_text("lab20"),
               *(m.source() for m in (*LAB20, *EQUIVALENT))]
    for i in range(students):
        (folder / f"student{i:03d}.py").write_text(sources[i % len(sources)])


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--students", type=int, default=40)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--json", help="write the figures here as JSON")
    args = parser.parse_args()
    spec, limits = LABS["lab20"], Limits()
    folder = Path(tempfile.mkdtemp(prefix="mirrorlab-bench-class-"))
    try:
        make_class(folder, args.students)
        reference_evidence(spec, default_variant(spec.name), None, limits)
        seconds: dict[str, list[float]] = {name: [] for name in ENGINES}
        names = list(ENGINES)
        for round_ in range(args.rounds):
            for name in names[round_ % len(names):] + names[:round_ % len(names)]:
                jobs, engine = ENGINES[name]
                started = time.perf_counter()
                grades, _ = grade_folder(spec, folder, jobs, None, engine, limits,
                                         progress=False)
                seconds[name].append(time.perf_counter() - started)
                assert len(grades) == args.students
        from distributed import LocalCluster

        starts = []
        for _ in range(args.rounds):
            started = time.perf_counter()
            with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                              dashboard_address=":0"):
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
    if args.json:
        Path(args.json).write_text(json.dumps({"students": args.students, "engines": rows,
                                               "dask_start": starts}, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
