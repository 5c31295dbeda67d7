"""Command line: ``mirrorlab render | demo``.

Bad input ends with a one-line message naming the option and what was
expected, exit status 2, and no output file written or clobbered.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from mirrorlab.scene.robot import DEFAULT_ANGLES, DEFAULT_CAMERA, DEFAULT_TARGET


class UsageError(Exception):
    """Bad input from the command line; the message is shown as is."""


def parse_floats(option: str, text: str, count: int, names: str) -> tuple[float, ...]:
    """``'1,2,3'`` -> (1.0, 2.0, 3.0); UsageError naming ``option`` otherwise."""
    parts = [p.strip() for p in text.split(",")]
    try:
        values = tuple(float(p) for p in parts)
    except ValueError:
        values = ()
    if len(values) != count or not all(np.isfinite(v) for v in values):
        raise UsageError(f"{option}: expected {count} finite numbers {names}, got {text!r}")
    return values


def parse_size(option: str, text: str) -> tuple[int, int]:
    """``'640x480'`` -> (640, 480); UsageError naming ``option`` otherwise."""
    parts = text.lower().split("x")
    if len(parts) == 2 and all(p.strip().isdigit() for p in parts):
        width, height = int(parts[0]), int(parts[1])
        if 1 <= width <= 8192 and 1 <= height <= 8192:
            return width, height
    raise UsageError(f"{option}: expected WIDTHxHEIGHT with each from 1 to 8192, got {text!r}")


def png_path(option: str, text: str) -> Path:
    path = Path(text)
    if path.suffix.lower() != ".png":
        raise UsageError(f"{option}: expected a file name ending in .png, got {text!r}")
    if path.exists() and path.is_dir():
        raise UsageError(f"{option}: {text!r} is a directory, expected a .png file name")
    existing = next(p for p in path.absolute().parents if p.exists())
    if not existing.is_dir():
        raise UsageError(f"{option}: {existing} is a file, so {text!r} cannot be written")
    return path


def write_png_atomic(path: Path, image: np.ndarray) -> None:
    """Write ``image`` ``(h, w, 3)`` uint8 to ``path`` via a temporary file and a rename,
    so that a failure never leaves a partial or clobbered file."""
    from PIL import Image

    path.parent.mkdir(parents=True, exist_ok=True)
    handle, temp_name = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(handle, "wb") as stream:
            Image.fromarray(image).save(stream, format="PNG")
        os.chmod(temp_name, 0o666 & ~_umask())  # mkstemp makes 0600; give the usual mode
        os.replace(temp_name, path)
    except BaseException:
        Path(temp_name).unlink(missing_ok=True)
        raise


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _joined(values: Sequence[float]) -> str:
    return ",".join(f"{v:g}" for v in values)


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="mirrorlab",
        description="The CS370 multipass mirror: capture the scene from the mirror, "
        "then texture the mirror with it.",
    )
    commands = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    render = commands.add_parser("render", help="render the lab scene headless to a PNG")
    render.add_argument("--out", default="out/robot.png", help="output PNG (default %(default)s)")
    render.add_argument("--size", default="512x512", help="WIDTHxHEIGHT (default %(default)s)")
    render.add_argument("--angles", default=_joined(DEFAULT_ANGLES),
                        help="joint angles in degrees BASE,LOWER,UPPER (default %(default)s)")
    render.add_argument("--camera", default=_joined(DEFAULT_CAMERA),
                        help="viewer position X,Y,Z (default %(default)s)")
    render.add_argument("--target", default=_joined(DEFAULT_TARGET),
                        help="point the viewer looks at X,Y,Z (default %(default)s)")
    render.add_argument("--save-env", metavar="PATH",
                        help="also write the captured environment texture as a PNG")

    demo = commands.add_parser("demo", help="open a window on the lab scene (needs a display)")
    demo.add_argument("--size", default="800x800", help="window WIDTHxHEIGHT (default %(default)s)")
    demo.add_argument("--angles", default=_joined(DEFAULT_ANGLES),
                      help="starting joint angles BASE,LOWER,UPPER (default %(default)s)")
    demo.add_argument("--max-frames", type=int, default=0,
                      help="close after this many frames (0: run until Esc or the window closes)")
    demo.add_argument("--screenshot", metavar="PATH",
                      help="write the last frame as a PNG when the demo ends")
    return parser


def run_render(args: argparse.Namespace) -> int:
    size = parse_size("--size", args.size)
    angles = parse_floats("--angles", args.angles, 3, "BASE,LOWER,UPPER")
    camera = parse_floats("--camera", args.camera, 3, "X,Y,Z")
    target = parse_floats("--target", args.target, 3, "X,Y,Z")
    out = png_path("--out", args.out)
    env_out = png_path("--save-env", args.save_env) if args.save_env else None
    if camera == target:
        raise UsageError(f"--camera and --target: must differ, both are {args.camera!r}")

    from mirrorlab.headless import render_lab_frame

    start = time.perf_counter()
    frame = render_lab_frame(size, angles, camera, target)
    elapsed = time.perf_counter() - start
    write_png_atomic(out, frame.image)
    print(f"wrote {out} ({size[0]}x{size[1]}, passes: {' + '.join(frame.passes)}, "
          f"{elapsed * 1000:.0f} ms with start-up, {frame.gl_renderer})")
    if env_out is not None:
        write_png_atomic(env_out, frame.environment)
        print(f"wrote {env_out} (environment capture, "
              f"{frame.environment.shape[1]}x{frame.environment.shape[0]})")
    return 0


def run_demo(args: argparse.Namespace) -> int:
    size = parse_size("--size", args.size)
    angles = parse_floats("--angles", args.angles, 3, "BASE,LOWER,UPPER")
    screenshot = png_path("--screenshot", args.screenshot) if args.screenshot else None
    if args.max_frames < 0:
        raise UsageError(f"--max-frames: expected 0 or more, got {args.max_frames}")

    from mirrorlab.gl.context import use_platform

    use_platform("glx")  # before anything imports OpenGL in this process
    from mirrorlab.app.demo import run

    return run(size, angles, max_frames=args.max_frames, screenshot=screenshot,
               save_png=write_png_atomic)


VECTOR_OPTIONS = ("--angles", "--camera", "--target")


def join_negative_vectors(argv: Sequence[str]) -> list[str]:
    """``['--target', '-4,1,-2']`` -> ``['--target=-4,1,-2']``: argparse would otherwise
    take a leading minus for an option."""
    out: list[str] = []
    tokens = list(argv)
    i = 0
    while i < len(tokens):
        token = tokens[i]
        following = tokens[i + 1] if i + 1 < len(tokens) else ""
        if token in VECTOR_OPTIONS and re.match(r"^-[\d.]", following):
            out.append(f"{token}={following}")
            i += 2
        else:
            out.append(token)
            i += 1
    return out


def main(argv: Sequence[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(join_negative_vectors(sys.argv[1:] if argv is None else argv))
    try:
        if args.command == "render":
            return run_render(args)
        return run_demo(args)
    except UsageError as exc:
        print(f"mirrorlab {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except (ValueError, FileNotFoundError) as exc:
        print(f"mirrorlab {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except OSError as exc:
        where = exc.filename or "output"
        print(f"mirrorlab {args.command}: error: cannot write {where}: {exc.strerror or exc}",
              file=sys.stderr)
        return 1
    except Exception as exc:
        from mirrorlab.gl.context import GLContextError

        if isinstance(exc, GLContextError):
            print(f"mirrorlab {args.command}: error: {exc}", file=sys.stderr)
            return 1
        raise


if __name__ == "__main__":
    sys.exit(main())
