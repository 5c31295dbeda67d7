"""Command line: ``mirrorlab render | plan | bench | demo | techniques | lab | info``.

Argument parsing and dispatch only: each command is a module of :mod:`mirrorlab.commands`
that adds its own subparser (``add_parser``) and does its work (``run``), in the order of
:data:`COMMANDS`. Bad input ends with a one-line message naming the option or file and
what was expected, exit status 2, and no output file written or clobbered.
"""

from __future__ import annotations

import argparse
import re
import sys
import warnings
from collections.abc import Sequence

from mirrorlab.commands import bench, demo, info, lab, plan, render, techniques
from mirrorlab.commands.arguments import UsageError, check_executor
from mirrorlab.errors import BatchError, BenchmarkError, GLContextError, GLPassError, WriteError
from mirrorlab.files import OutputError
from mirrorlab.options import OPTIONS, OptionError
from mirrorlab.scene.loader import SceneError

COMMANDS = (render, plan, bench, demo, techniques, lab, info)
"""The command modules, in the order ``--help`` lists them: each has ``NAME``,
``add_parser(subparsers)`` and ``run(args) -> exit status``."""
EXIT_BAD_INPUT, EXIT_MACHINE, EXIT_INTERRUPTED = 2, 1, 130


def build_parser() -> argparse.ArgumentParser:
    """The whole command line: the top-level options and one subparser per command."""
    from mirrorlab import __version__

    parser = argparse.ArgumentParser(
        prog="mirrorlab",
        description="Mirrors and environment maps, rendered headless or in a window and "
        "measured against a ray tracer. A scene is a TOML file (see the documentation's "
        "'Writing a scene').",
    )
    parser.add_argument("--version", action="version", version=f"mirrorlab {__version__}")
    subparsers = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for command in COMMANDS:
        command.add_parser(subparsers)
    return parser


_VECTOR_FLAGS = (*tuple(o.flag for o in OPTIONS if "," in o.metavar), "--fovy", "--size")


def join_negative_vectors(argv: Sequence[str]) -> list[str]:
    """``['--target', '-4,1,-2']`` -> ``['--target=-4,1,-2']``: argparse would otherwise
    take a leading minus for an option."""
    out: list[str] = []
    tokens = list(argv)
    i = 0
    while i < len(tokens):
        token = tokens[i]
        following = tokens[i + 1] if i + 1 < len(tokens) else ""
        if token in _VECTOR_FLAGS and re.match(r"^-[\d.]", following):
            out.append(f"{token}={following}")
            i += 2
        else:
            out.append(token)
            i += 1
    return out


def _close_progress_bars() -> None:
    """Close the tqdm bars an interrupt left open, so the next line starts a line."""
    tqdm_module = sys.modules.get("tqdm")
    if tqdm_module is None:
        return
    for bar in list(getattr(tqdm_module.tqdm, "_instances", ())):
        try:
            bar.close()
        except Exception:  # a bar interrupted while it was being made
            pass


BAD_INPUT = (
    UsageError,
    OptionError,
    OutputError,
    SceneError,
    WriteError,
    ValueError,
    FileNotFoundError,
)


def main(argv: Sequence[str] | None = None) -> int:
    """Run one command; returns its exit status: 0 done, 2 bad input (including a write
    the system refuses and a size the GL cannot allocate), 1 a problem with the machine
    (no display, no OpenGL, an OpenGL too old or failing), 130 interrupted (Ctrl-C).
    Every failure is one line on stderr, never a traceback or a numpy warning."""
    command = "mirrorlab"
    try:
        parser = build_parser()
        args = parser.parse_args(join_negative_vectors(sys.argv[1:] if argv is None else argv))
        command = f"mirrorlab {args.command}"
        check_executor(args)
        run = {command.NAME: command.run for command in COMMANDS}[args.command]
        with warnings.catch_warnings():
            # A numeric warning means a value out of range slipped past the checks: stop
            # with one line rather than print numpy's warning and go on.
            warnings.simplefilter("error", RuntimeWarning)
            return run(args)
    except KeyboardInterrupt:
        _close_progress_bars()
        # An interrupt inside a progress bar's own drawing can leave its line open: go
        # back to the line's start (and, on a terminal, clear it) before the message.
        clear = "\r\033[K" if sys.stderr.isatty() else "\r"
        print(f"{clear}{command}: interrupted", file=sys.stderr)
        return EXIT_INTERRUPTED
    except RuntimeWarning as exc:
        print(
            f"{command}: error: a value is out of range for the computation ({exc})",
            file=sys.stderr,
        )
        return EXIT_BAD_INPUT
    except BAD_INPUT as exc:
        print(f"{command}: error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except OSError as exc:  # reading a file the checks let through
        where = exc.filename or "a file"
        print(f"{command}: error: cannot read {where}: {exc.strerror or exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except (GLContextError, GLPassError, BatchError, BenchmarkError) as exc:
        print(f"{command}: error: {exc}", file=sys.stderr)
        return EXIT_MACHINE
    except Exception as exc:
        from mirrorlab.labs.trusted.checker import CheckError
        from mirrorlab.labs.trusted.gl_process import CheckerError
        from mirrorlab.labs.trusted.grading import GradingStopped
        from mirrorlab.labs.trusted.sandbox import SandboxError

        if isinstance(exc, GradingStopped):
            print(f"{command}: error: grading stopped, nothing written: {exc}", file=sys.stderr)
            return EXIT_BAD_INPUT
        if isinstance(exc, SandboxError | CheckError):
            print(f"{command}: error: {exc}", file=sys.stderr)
            return EXIT_BAD_INPUT
        if isinstance(exc, CheckerError):
            print(f"{command}: error: {exc}", file=sys.stderr)
            return EXIT_MACHINE
        raise


if __name__ == "__main__":
    sys.exit(main())
