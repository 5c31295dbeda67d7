"""How fast a check answers: `mirrorlab lab check` cold (a process of its own) beside
`mirrorlab lab check --watch` re-checking on a save, side by side in one run.

    python bench/watch.py [--labs lab20,spheremap,cubemap] [--rounds 10]
                          [--json PATH] [--before REV]

For each lab, a folder with the lab's reference solution as ``mine.py`` (the lab's own
numbers, judged against the shipped reference, as a student's check is). One
``lab check --watch mine.py`` process runs throughout. Each round, in turn:

- cold: ``mirrorlab lab check LAB mine.py`` from the start of the process to its end;
- (with ``--before REV``) the same with git revision REV's checker;
- a save: ``mine.py`` replaced by rename (as vim and JetBrains editors save), alternately
  by the solution and by a copy with one slip (another far plane, another texgen mode or
  another face order: a change of verdict), timed from the rename to the watch's line
  "checked at ..." (the report printed and its picture written);
- for the labs with GLSL, a save whose GLSL differs (a comment in the shader string), so
  the checker compiles a new shader.

Figures are medians with the 10th and 90th percentiles, in seconds, and the ratio of the
watch's median to the cold check's, from the same rounds; beside them, the CPU seconds of
every process each took (Linux's /proc: the command and what it waited for; for the
watch, its process tree's growth from the save to the answer, which also counts a
process its checker started ahead for the next save once that one is reaped). The cache folder
(``MIRRORLAB_CACHE``) is a fresh one, filled by a first, untimed check of each kind, as
the second check of a student's day finds it.
"""

from __future__ import annotations

import argparse
import json
import os
import queue
import shutil
import signal
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
SLIPS = {
    "lab20": ("glOrtho(Z0, Z1, Y0, Y1, 0, 15)", "glOrtho(Z0, Z1, Y0, Y1, 0, 14)"),
    "spheremap": ("GL_SPHERE_MAP", "GL_OBJECT_LINEAR"),
    "cubemap": (
        "GL_TEXTURE_CUBE_MAP_POSITIVE_X + face, 0, GL_RGB",
        "GL_TEXTURE_CUBE_MAP_POSITIVE_X + 5 - face, 0, GL_RGB",
    ),
}
"""Per lab: a text of its solution and what one slip makes of it."""
GLSL_MARK = {"spheremap": "vec3 reflect_eye", "cubemap": "int cube_face"}
"""Per lab with GLSL: a line of its shader string a comment is put before."""


def percentiles(values: list[float]) -> tuple[float, float, float]:
    ordered = sorted(values)
    if len(ordered) == 1:
        return ordered[0], ordered[0], ordered[0]
    deciles = statistics.quantiles(ordered, n=10, method="inclusive")
    return statistics.median(ordered), deciles[0], deciles[-1]


def solution_text(lab: str) -> str:
    from mirrorlab.labs import find_lab
    from mirrorlab.labs.content import solution_for
    from mirrorlab.labs.trusted.variants import default_variant

    spec = find_lab(lab)
    return solution_for(spec.solution.read_text(), default_variant(lab))


def save(path: Path, text: str) -> float:
    """Write ``text`` to a new file beside ``path`` and rename it over ``path``; the time of
    the rename (perf_counter)."""
    staging = path.with_name(f".{path.name}.swp")
    staging.write_text(text)
    moment = time.perf_counter()
    os.replace(staging, path)
    return moment


def tree_cpu(pid: int) -> float:
    """CPU seconds of process ``pid``, of the children it has waited for and of its living
    children (and theirs), from Linux's /proc; 0 elsewhere."""
    tick = os.sysconf("SC_CLK_TCK") if hasattr(os, "sysconf") else 100
    total = 0.0
    try:
        fields = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()
        total += sum(int(f) for f in fields[11:15]) / tick
        children = Path(f"/proc/{pid}/task/{pid}/children").read_text().split()
    except OSError:
        return total
    return total + sum(tree_cpu(int(child)) for child in children)


def children_cpu() -> float:
    import resource

    usage = resource.getrusage(resource.RUSAGE_CHILDREN)
    return usage.ru_utime + usage.ru_stime


def cold(python: str, lab: str, folder: Path, env: dict[str, str]) -> tuple[float, float]:
    """(seconds, CPU seconds of the command and every process it waited for)."""
    cpu = children_cpu()
    started = time.perf_counter()
    done = subprocess.run(
        [python, "-m", "mirrorlab.cli", "lab", "check", lab, "mine.py", "--out", "cold.png"],
        cwd=folder,
        env=env,
        capture_output=True,
        text=True,
    )
    seconds = time.perf_counter() - started
    if "tasks passed" not in done.stdout:
        raise SystemExit(f"lab check {lab} judged nothing: {done.stderr.strip()[-500:]}")
    return seconds, children_cpu() - cpu


class Watch:
    """``lab check --watch`` in a process of its own, its lines read as they come."""

    def __init__(self, lab: str, folder: Path, env: dict[str, str]) -> None:
        self.process = subprocess.Popen(
            [sys.executable, "-m", "mirrorlab.cli", "lab", "check", lab, "mine.py", "--watch"],
            cwd=folder,
            env=env,
            stdout=subprocess.PIPE,
            stderr=subprocess.PIPE,
            text=True,
            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
        )
        self.lines: queue.Queue[tuple[float, str]] = queue.Queue()
        self.reader = threading.Thread(target=self._read, daemon=True)
        self.reader.start()

    def _read(self) -> None:
        assert self.process.stdout is not None
        for line in self.process.stdout:
            self.lines.put((time.perf_counter(), line))

    def checked(self, timeout: float = 120.0) -> tuple[float, list[str]]:
        """The time the next report was finished, and its lines."""
        report: list[str] = []
        while True:
            moment, line = self.lines.get(timeout=timeout)
            report.append(line)
            if line.startswith("checked at "):
                return moment, report

    def close(self) -> None:
        self.process.send_signal(signal.SIGINT)
        try:
            self.process.wait(timeout=60)
        except subprocess.TimeoutExpired:
            self.process.kill()
            self.process.wait()


class Before:
    """Git revision REV of this repository exported beside this checkout, with a venv whose
    mirrorlab is that export and whose other packages are this venv's."""

    def __init__(self, revision: str) -> None:
        self.revision = revision
        self.folder = Path(tempfile.mkdtemp(prefix="mirrorlab-bench-before-"))
        self.venv = Path(tempfile.mkdtemp(prefix="mirrorlab-bench-venv-"))
        archive = subprocess.run(
            ["git", "-C", str(REPO), "archive", revision], capture_output=True, check=True
        )
        subprocess.run(["tar", "-x", "-C", str(self.folder)], input=archive.stdout, check=True)
        for data in ("scenes", "models", "textures"):  # where an install puts them
            shipped = self.folder / "mirrorlab" / "data" / data
            if (self.folder / data).is_dir() and not shipped.exists():
                shipped.symlink_to(self.folder / data, target_is_directory=True)
        for made in (self.folder, self.venv):  # a sandbox's dropped user must enter them
            made.chmod(0o755)
        base = Path(getattr(sys, "_base_executable", sys.executable)).resolve()
        subprocess.run([str(base), "-m", "venv", "--without-pip", str(self.venv)], check=True)
        site = next(self.venv.glob("lib/python3*/site-packages"))
        import numpy

        (site / "before.pth").write_text(f"{self.folder}\n{Path(numpy.__file__).parent.parent}\n")
        self.python = str(self.venv / "bin" / "python")

    def close(self) -> None:
        shutil.rmtree(self.folder, ignore_errors=True)
        shutil.rmtree(self.venv, ignore_errors=True)


def measure(lab: str, rounds: int, before: Before | None, cache: Path) -> dict[str, list[float]]:
    folder = Path(tempfile.mkdtemp(prefix=f"mirrorlab-bench-{lab}-"))
    env = {**os.environ, "MIRRORLAB_CACHE": str(cache)}
    env.pop("MIRRORLAB_SOLUTIONS", None)
    text = solution_text(lab)
    old, new = SLIPS[lab]
    if old not in text:
        raise SystemExit(f"{lab}: the solution has no {old!r} to make a slip of")
    versions = [text.replace(old, new, 1), text]
    mark = GLSL_MARK.get(lab)
    kinds: dict[str, list[float]] = {"cold": [], "watch, a save": []}
    cpu: dict[str, list[float]] = {}
    before_kind = f"cold, {before.revision}" if before is not None else ""
    if before is not None:
        kinds[before_kind] = []
    if mark is not None:
        if mark not in text:
            raise SystemExit(f"{lab}: the solution's GLSL has no {mark!r}")
        kinds["watch, a save with new GLSL"] = []
    path = folder / "mine.py"
    path.write_text(text)
    watch = None
    try:
        cold(sys.executable, lab, folder, env)  # fills the cache
        if before is not None:
            cold(before.python, lab, folder, env)
        watch = Watch(lab, folder, env)
        watch.checked()

        def timed(kind: str, seconds: float, used: float) -> None:
            kinds[kind].append(seconds)
            cpu.setdefault(kind, []).append(used)

        for round_ in range(rounds):
            timed("cold", *cold(sys.executable, lab, folder, env))
            if before is not None:
                timed(before_kind, *cold(before.python, lab, folder, env))
            time.sleep(0.5)  # the watch is waiting, as it is between a student's saves
            used = tree_cpu(watch.process.pid)
            saved = save(path, versions[round_ % 2])
            done, _ = watch.checked()
            timed("watch, a save", done - saved, tree_cpu(watch.process.pid) - used)
            if mark is not None:
                time.sleep(0.5)
                glsl = text.replace(mark, f"// round {round_}\n{mark}", 1)
                used = tree_cpu(watch.process.pid)
                saved = save(path, glsl)
                done, _ = watch.checked()
                timed(
                    "watch, a save with new GLSL", done - saved, tree_cpu(watch.process.pid) - used
                )
            print(f"{lab} round {round_ + 1}/{rounds}", file=sys.stderr, flush=True)
    finally:
        if watch is not None:
            watch.close()
        shutil.rmtree(folder, ignore_errors=True)
    return {**kinds, **{f"{kind} (CPU s)": values for kind, values in cpu.items()}}


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--labs", default="lab20,spheremap,cubemap")
    parser.add_argument("--rounds", type=int, default=10)
    parser.add_argument("--json", help="write the figures here as JSON")
    parser.add_argument(
        "--before", metavar="REV", help="also time the cold check of git revision REV"
    )
    args = parser.parse_args()
    before = Before(args.before) if args.before else None
    cache = Path(tempfile.mkdtemp(prefix="mirrorlab-bench-cache-"))
    cache.chmod(0o755)
    figures: dict[str, dict[str, list[float]]] = {}
    try:
        for lab in args.labs.split(","):
            figures[lab] = measure(lab, args.rounds, before, cache)
    finally:
        shutil.rmtree(cache, ignore_errors=True)
        if before is not None:
            before.close()
    print(
        f"\n{args.rounds} rounds a lab; seconds from the start or the save to the answer, and "
        f"CPU seconds of every process it took; median (p10-p90); the ratio of medians to "
        f"the cold check's"
    )
    print("| lab | check | s | p10-p90 | / cold | CPU s | p10-p90 | / cold |")
    print("|---|---|---:|---:|---:|---:|---:|---:|")
    for lab, kinds in figures.items():
        cold_median = statistics.median(kinds["cold"])
        cold_cpu = statistics.median(kinds["cold (CPU s)"])
        for kind, values in kinds.items():
            if kind.endswith("(CPU s)"):
                continue
            median, low, high = percentiles(values)
            used, used_low, used_high = percentiles(kinds[f"{kind} (CPU s)"])
            print(
                f"| {lab} | {kind} | {median:.2f} | {low:.2f}-{high:.2f} | "
                f"{median / cold_median:.2f}x | {used:.2f} | {used_low:.2f}-{used_high:.2f} | "
                f"{used / cold_cpu:.2f}x |"
            )
    if args.json:
        Path(args.json).write_text(json.dumps(figures, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
