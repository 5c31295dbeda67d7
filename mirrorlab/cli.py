"""Command line: ``mirrorlab render | plan | demo | bench``.

Bad input ends with a one-line message naming the option and what was
expected, exit status 2, and no output file written or clobbered.
"""

from __future__ import annotations

import argparse
import dataclasses
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
    render.add_argument("--camera",
                        help="viewer position X,Y,Z (default: the scene's, for the lab "
                        f"{_joined(DEFAULT_CAMERA)})")
    render.add_argument("--target",
                        help="point the viewer looks at X,Y,Z (default: the scene's, for the "
                        f"lab {_joined(DEFAULT_TARGET)})")
    render.add_argument("--scene", default="lab",
                        help="lab (the robot and its mirror), cone (the textbook's sphere-map "
                        "experiment) or sphere (a reflective sphere) (default %(default)s)")
    render.add_argument("--envmap",
                        help="environment-map technique for the cone and sphere scenes: sphere, "
                        "sphere-vertex, sphere-texgen, cube, cube-live, latlong, normal "
                        "(default: sphere-texgen for cone, sphere for sphere)")
    render.add_argument("--map-size", metavar="N",
                        help="environment map side in texels for --envmap (default 256)")
    render.add_argument("--cube-faces", metavar="DIR",
                        help="six images DIR/{px,nx,py,ny,pz,nz}.png as the static cube map "
                        "and the sky (sphere scene; e.g. textures/sky_cube)")
    render.add_argument("--cone-height", metavar="Y",
                        help="height of the cone's base in the cone scene (default 1)")
    render.add_argument("--save-env", metavar="PATH",
                        help="also write the captured environment texture as a PNG")
    render.add_argument("--method", default="ortho",
                        help="mirror technique: ortho (the lab), reflected, stencil or raytrace "
                        "(default %(default)s)")
    render.add_argument("--capture", default="copy",
                        help="how a capture reaches its texture: copy (glCopyTexImage2D) or "
                        "fbo (drawn into it) (default %(default)s)")
    render.add_argument("--env-size", metavar="N",
                        help="environment texture side in pixels (default: the frame's size)")

    plan = commands.add_parser("plan", help="print the passes a frame would run, and why")
    plan.add_argument("--size", default="512x512", help="WIDTHxHEIGHT (default %(default)s)")
    plan.add_argument("--camera", default=_joined(DEFAULT_CAMERA),
                      help="viewer position X,Y,Z (default %(default)s)")
    plan.add_argument("--target", default=_joined(DEFAULT_TARGET),
                      help="point the viewer looks at X,Y,Z (default %(default)s)")
    plan.add_argument("--method", default="ortho",
                      help="ortho, reflected or stencil (default %(default)s)")

    bench = commands.add_parser("bench", help="measure error against the ray tracer, and time")
    bench.add_argument("what", metavar="accuracy", help="the benchmark to run: accuracy")
    bench.add_argument("--quick", action="store_true",
                       help="a small sweep (128-pixel frames, maps 64 and 128, two viewpoints)")
    bench.add_argument("--out-dir", default="out/bench",
                       help="where accuracy.csv, accuracy.md and accuracy.png go "
                       "(default %(default)s)")
    bench.add_argument("--frame", metavar="N", help="frame side in pixels (default 512)")
    bench.add_argument("--sizes", metavar="N,N,...",
                       help="environment texture sides (default 64,128,256,512,1024,2048)")
    bench.add_argument("--frames", metavar="N", help="timed frames per configuration (default 15)")
    bench.add_argument("--from-csv", metavar="PATH",
                       help="measure nothing: re-make the tables and plot from a saved "
                       "accuracy.csv")
    bench.add_argument("--scene", default="all",
                       help="lab (the mirror techniques), sphere (the environment maps) or all "
                       "(default %(default)s)")

    demo = commands.add_parser("demo", help="open a window on the lab scene (needs a display)")
    demo.add_argument("--size", default="800x800", help="window WIDTHxHEIGHT (default %(default)s)")
    demo.add_argument("--angles", default=_joined(DEFAULT_ANGLES),
                      help="starting joint angles BASE,LOWER,UPPER (default %(default)s)")
    demo.add_argument("--max-frames", type=int, default=0,
                      help="close after this many frames (0: run until Esc or the window closes)")
    demo.add_argument("--screenshot", metavar="PATH",
                      help="write the last frame as a PNG when the demo ends")
    demo.add_argument("--scene", default="lab", help="lab, cone or sphere (default %(default)s)")
    demo.add_argument("--method", default="ortho",
                      help="the lab's mirror technique: ortho, reflected or stencil "
                      "(default %(default)s; M cycles them in the window)")
    demo.add_argument("--envmap",
                      help="technique for the cone and sphere scenes (keys 1-7 switch)")
    return parser


def parse_count(option: str, text: str, low: int = 1, high: int = 8192) -> int:
    """``'256'`` -> 256 when ``low <= value <= high``; UsageError naming ``option`` otherwise."""
    if text.strip().isdigit() and low <= int(text) <= high:
        return int(text)
    raise UsageError(f"{option}: expected a whole number from {low} to {high}, got {text!r}")


def parse_choice(option: str, text: str, choices: Sequence[str]) -> str:
    if text not in choices:
        raise UsageError(f"{option}: expected one of {', '.join(choices)}, got {text!r}")
    return text


ENVMAP_DEFAULTS = {"cone": "sphere-texgen", "sphere": "sphere"}


def check_scene_options(args: argparse.Namespace, lab_only: Sequence[str]) -> str:
    """The scene name, after refusing options that do not fit it (UsageError naming them)."""
    from mirrorlab.scene.envscenes import ENV_SCENES, ENVMAP_METHODS

    scene = parse_choice("--scene", args.scene, ("lab", *ENV_SCENES))
    if scene == "lab":
        if args.envmap is not None:
            raise UsageError("--envmap: applies to --scene cone or sphere, not the lab")
        return scene
    for option in lab_only:
        if getattr(args, option.lstrip("-").replace("-", "_")) != _LAB_DEFAULTS[option]:
            raise UsageError(f"{option}: applies to --scene lab only, not {scene}")
    if args.envmap is None:
        args.envmap = ENVMAP_DEFAULTS[scene]
    parse_choice("--envmap", args.envmap, ENVMAP_METHODS)
    return scene


_LAB_DEFAULTS = {"--method": "ortho", "--capture": "copy", "--env-size": None,
                 "--save-env": None, "--angles": _joined(DEFAULT_ANGLES)}


def run_render(args: argparse.Namespace) -> int:
    from mirrorlab.headless import RENDER_METHODS
    from mirrorlab.plan import CAPTURE_MODES

    scene = check_scene_options(
        args, ("--method", "--capture", "--env-size", "--save-env", "--angles"))
    size = parse_size("--size", args.size)
    method = parse_choice("--method", args.method, RENDER_METHODS)
    capture = parse_choice("--capture", args.capture, CAPTURE_MODES)
    env_size = parse_count("--env-size", args.env_size) if args.env_size else None
    angles = parse_floats("--angles", args.angles, 3, "BASE,LOWER,UPPER")
    camera = parse_floats("--camera", args.camera, 3, "X,Y,Z") if args.camera else None
    target = parse_floats("--target", args.target, 3, "X,Y,Z") if args.target else None
    out = png_path("--out", args.out)
    env_out = png_path("--save-env", args.save_env) if args.save_env else None
    if scene != "lab":
        return render_env_scene(args, scene, size, camera, target, out)
    for option in ("--map-size", "--cone-height", "--cube-faces"):
        if getattr(args, option[2:].replace("-", "_")) is not None:
            raise UsageError(f"{option}: applies to --scene cone or sphere, not the lab")
    camera = camera or DEFAULT_CAMERA
    target = target or DEFAULT_TARGET
    if camera == target:
        raise UsageError(f"--camera and --target: must differ, both are {_joined(camera)!r}")

    from mirrorlab.headless import render_lab_frame

    start = time.perf_counter()
    frame = render_lab_frame(size, angles, camera, target, method, capture, env_size)
    elapsed = time.perf_counter() - start
    write_png_atomic(out, frame.image)
    print(f"wrote {out} ({size[0]}x{size[1]}, {method}, passes: {' + '.join(frame.passes)}, "
          f"{elapsed * 1000:.0f} ms with start-up, {frame.gl_renderer})")
    if env_out is not None and frame.environment.size == 0:
        print(f"no environment texture with --method {method}; {env_out} not written")
    elif env_out is not None:
        write_png_atomic(env_out, frame.environment)
        print(f"wrote {env_out} (environment capture, "
              f"{frame.environment.shape[1]}x{frame.environment.shape[0]})")
    return 0


def render_env_scene(args: argparse.Namespace, scene: str, size: tuple[int, int],
                     camera: tuple[float, ...] | None, target: tuple[float, ...] | None,
                     out: Path) -> int:
    from mirrorlab.envmap_renderer import DEFAULT_MAP_SIZE, render_envmap_frame
    from mirrorlab.scene.envscenes import CONE_LIMITS, build_env_scene

    map_size = parse_count("--map-size", args.map_size, 4, 4096) if args.map_size else (
        DEFAULT_MAP_SIZE)
    cone_height = None
    if args.cone_height is not None:
        if scene != "cone":
            raise UsageError(f"--cone-height: applies to --scene cone, not {scene}")
        (cone_height,) = parse_floats("--cone-height", args.cone_height, 1, "Y")
        low, high = CONE_LIMITS
        if not low <= cone_height <= high:
            raise UsageError(f"--cone-height: expected a height from {low:g} to {high:g}, "
                             f"got {args.cone_height!r}")
    cube_faces = None
    if args.cube_faces is not None:
        from mirrorlab.scene.envscenes import load_cube_faces

        if scene != "sphere":
            raise UsageError(f"--cube-faces: applies to --scene sphere, not {scene}")
        try:
            cube_faces = load_cube_faces(args.cube_faces)
        except ValueError as exc:
            raise UsageError(f"--cube-faces: {exc}") from None
    viewer = None
    if camera or target:
        own = build_env_scene(scene).camera
        viewer = dataclasses.replace(own, eye=camera or own.eye, target=target or own.target)
        if viewer.eye == viewer.target:
            raise UsageError(f"--camera and --target: must differ, both are "
                             f"{_joined(viewer.eye)!r}")
    start = time.perf_counter()
    frame = render_envmap_frame(scene, args.envmap, size, viewer, map_size, cone_height,
                                cube_faces)
    elapsed = time.perf_counter() - start
    write_png_atomic(out, frame.image)
    source = (f"cube faces from {args.cube_faces}" if cube_faces is not None
              and args.envmap == "cube" else f"{args.envmap} map of {map_size}")
    print(f"wrote {out} ({size[0]}x{size[1]}, {scene} scene, {source}, passes: "
          f"{' + '.join(frame.passes)}, {elapsed * 1000:.0f} ms with start-up, "
          f"{frame.gl_renderer})")
    return 0


def run_plan(args: argparse.Namespace) -> int:
    from mirrorlab.plan import METHODS, CaptureState, plan_frame
    from mirrorlab.scene.robot import Camera, build_lab_scene

    size = parse_size("--size", args.size)
    camera = parse_floats("--camera", args.camera, 3, "X,Y,Z")
    target = parse_floats("--target", args.target, 3, "X,Y,Z")
    method = parse_choice("--method", args.method, METHODS)
    if camera == target:
        raise UsageError(f"--camera and --target: must differ, both are {args.camera!r}")
    scene = build_lab_scene()
    viewer = Camera(eye=camera, target=target)
    first = plan_frame(scene, viewer, size, CaptureState(), method=method)
    settled = CaptureState(scene.graph.revision, size, viewer)
    second = plan_frame(scene, viewer, size, settled, method=method)
    for title, plan in (("first frame", first), ("next frame, nothing changed", second)):
        print(f"{title}:")
        for planned in plan:
            print(f"  {'run ' if planned.runs else 'skip'} {planned.name:<20} {planned.reason}")
    return 0


def run_bench(args: argparse.Namespace) -> int:
    parse_choice("bench", args.what, ("accuracy",))
    from mirrorlab import bench

    settings = bench.SweepSettings.quick() if args.quick else bench.SweepSettings()
    changes = {}
    if args.frame:
        changes["frame"] = parse_count("--frame", args.frame, 16, 4096)
    if args.sizes:
        parts = [p.strip() for p in args.sizes.split(",")]
        changes["sizes"] = tuple(parse_count("--sizes", p, 1, 8192) for p in parts)
    if args.frames:
        changes["frames"] = parse_count("--frames", args.frames, 1, 10000)
    if changes:
        settings = dataclasses.replace(settings, **changes)
    scenes = parse_choice("--scene", args.scene, ("lab", "sphere", "all"))
    out_dir = Path(args.out_dir)
    if out_dir.exists() and not out_dir.is_dir():
        raise UsageError(f"--out-dir: {args.out_dir!r} is a file, expected a directory")
    if args.from_csv:
        source = Path(args.from_csv)
        try:
            rows = bench.rows_from_csv(source.read_text())
        except (OSError, UnicodeDecodeError) as exc:
            raise UsageError(f"--from-csv: cannot read {source}: {exc}") from None
        except ValueError as exc:
            raise UsageError(f"--from-csv: {source}: {exc}") from None
        title = f"accuracy vs time, from {source.name}"
    else:
        rows = []
        if scenes in ("lab", "all"):
            rows += bench.run_accuracy(settings, bench.progress_bar())
        if scenes in ("sphere", "all"):
            rows += bench.run_envmap_accuracy(settings, bench.progress_bar())
        title = (f"accuracy vs time, {settings.frame}x{settings.frame} frames, llvmpipe; "
                 f"medians of {settings.frames} frames")
        bench.write_bytes_atomic(out_dir / "accuracy.csv", bench.rows_to_csv(rows).encode())
    summary = bench.summarise(rows)
    markdown = [title, ""]
    for scene in dict.fromkeys(r.scene for r in summary):
        table = bench.summary_table([r for r in summary if r.scene == scene])
        heading = bench.SCENE_TITLES.get(scene, scene)
        print(f"\n{heading}:\n{bench.format_text(table)}")
        markdown += [f"### {heading}", "", bench.format_markdown(table), ""]
    bench.write_bytes_atomic(out_dir / "accuracy.md", "\n".join(markdown).encode())
    written = ["accuracy.md"] if args.from_csv else ["accuracy.csv", "accuracy.md"]
    if bench.plot_summary(summary, out_dir / "accuracy.png", title):
        written.append("accuracy.png")
    else:
        print("matplotlib is not installed, so no plot (pip install 'mirrorlab[plot]')")
    print(f"wrote {', '.join(str(out_dir / name) for name in written)}")
    return 0


def run_demo(args: argparse.Namespace) -> int:
    from mirrorlab.plan import METHODS

    scene = check_scene_options(args, ("--method", "--angles"))
    size = parse_size("--size", args.size)
    angles = parse_floats("--angles", args.angles, 3, "BASE,LOWER,UPPER")
    method = parse_choice("--method", args.method, METHODS)
    screenshot = png_path("--screenshot", args.screenshot) if args.screenshot else None
    if args.max_frames < 0:
        raise UsageError(f"--max-frames: expected 0 or more, got {args.max_frames}")

    from mirrorlab.gl.context import use_platform

    use_platform("glx")  # before anything imports OpenGL in this process
    from mirrorlab.app.demo import run

    return run(size, angles, max_frames=args.max_frames, screenshot=screenshot,
               save_png=write_png_atomic, scene=scene, envmap=args.envmap or "sphere-texgen",
               method=method)


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
        runners = {"render": run_render, "plan": run_plan, "bench": run_bench,
                   "demo": run_demo}
        return runners[args.command](args)
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
