"""Re-make the README's comparison pictures in docs/ (headless; run from the checkout):

    .venv/bin/python tools/make_docs.py [methods] [envmaps] [cone] [parallax] [maps] [warp]
                                        [ssr]

(all of them when none is named). docs/methods.png: the lab scene (lab20) 30 degrees off
the mirror's normal, by each mirror technique and the ray tracer. docs/envmaps.png: the
sphere scene (chrome_sphere) by each environment-map technique and the ray tracer (4 x 4
rays a pixel). docs/cone.png: the textbook's cone (spheremap_cone) at two heights (texgen
sphere map). docs/parallax.png: the live cube map without and with its parallax
corrections against the ray tracer, among chrome_sphere's objects and in sphere_room, and
where the pixels that still differ lie. docs/direction_maps.png: the chrome sphere by the
octahedral and dual-paraboloid maps, each above the map it samples. docs/paraboloid_warp.png:
the room's sphere by the dual-paraboloid map converted from the cube capture and by the
vertex-warped one, with the room's walls as shipped (two triangles each) and cut into
small triangles, above their maps. docs/ssr.png: each of the scenes made to show
screen-space reflections' failures: the frame, its miss mask, the frame without its probe
and the ray tracer. The accuracy plot comes from `mirrorlab bench accuracy`, the
texel-budget study's from `bench/texel_budget.py`.
"""

from __future__ import annotations

import math
import sys
from dataclasses import replace
from pathlib import Path
from typing import Any

import numpy as np
from PIL import Image, ImageDraw

import mirrorlab
from mirrorlab.accuracy import erode
from mirrorlab.options import apply_options
from mirrorlab.raytrace import trace_scene
from mirrorlab.scene.model import CurvedReflector, MeshObject
from mirrorlab.techniques import technique_names

DOCS = Path(__file__).resolve().parent.parent / "docs"
SIZE = 256


def labelled(image: np.ndarray, text: str) -> np.ndarray:
    picture = Image.fromarray(image)
    draw = ImageDraw.Draw(picture)
    draw.rectangle((0, 0, 8 + 7 * len(text), 16), fill=(0, 0, 0))
    draw.text((4, 2), text, fill=(255, 255, 255))
    return np.asarray(picture)


def grid(tiles: list[np.ndarray], columns: int) -> np.ndarray:
    blank = np.zeros_like(tiles[0])
    tiles = tiles + [blank] * (-len(tiles) % columns)
    rows = [np.hstack(tiles[i : i + columns]) for i in range(0, len(tiles), columns)]
    return np.vstack(rows)


RIM, EDGE, OTHER = (255, 220, 0), (0, 200, 255), (255, 0, 255)
"""Colours of the differing pixels in docs/parallax.png, by where they lie."""


def differences(
    image: np.ndarray,
    truth: np.ndarray,
    reflective: np.ndarray,
) -> tuple[np.ndarray, dict[str, float]]:
    """The pixels of ``image`` off by more than 10/255 inside the reflector (shrunk by a
    pixel, as the sweep compares it), coloured by where they lie: within 3 pixels of the
    reflector's silhouette (RIM), where the truth itself changes by more than 20/255 from
    a neighbouring pixel (EDGE: outlines, texture detail) or elsewhere (OTHER); the rest of
    the reflector dimmed. Returns the picture and each kind's share of the reflector."""
    mask = erode(reflective, 1)
    expected = truth.astype(int)
    off = (np.abs(image.astype(int) - expected).max(axis=-1) > 10) & mask
    rim = mask & ~erode(reflective, 4)
    change = np.zeros(mask.shape, dtype=int)
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            moved = np.roll(np.roll(expected, dy, axis=0), dx, axis=1)
            change = np.maximum(change, np.abs(moved - expected).max(axis=-1))
    edge = change > 20
    picture = truth // 4
    picture[mask] = image[mask] // 2
    kinds = {"rim": off & rim, "edge": off & ~rim & edge, "other": off & ~rim & ~edge}
    for kind, colour in zip(kinds.values(), (RIM, EDGE, OTHER), strict=True):
        picture[kind] = colour
    return picture, {name: float(kind.sum() / mask.sum()) for name, kind in kinds.items()}


def crop_to(reflective: np.ndarray, margin: int = 6) -> tuple[slice, slice]:
    rows, columns = np.nonzero(reflective)
    return (
        slice(max(rows.min() - margin, 0), rows.max() + margin + 1),
        slice(max(columns.min() - margin, 0), columns.max() + margin + 1),
    )


def parallax_picture(renderer) -> None:
    """docs/parallax.png: one row per scene: the truth, the plain live cube map and where
    it differs, the corrected one and where it still differs (see :func:`differences`)."""
    rows = []
    for name, correction, label in (
        ("chrome_sphere", "distance", "distance 8+2"),
        ("sphere_room", "box:-4,-2,-4,4,4,4", "box proxy"),
    ):
        scene = apply_options(mirrorlab.load_scene(name), {"method": "cube-live"})
        traced = trace_scene(scene, (512, 512), supersample=4)
        truth = traced.to_uint8()
        plain = renderer.render(scene, size=(512, 512), parallax="none")
        corrected = renderer.render(scene, size=(512, 512), parallax=correction)
        plain_where, plain_shares = differences(plain, truth, traced.reflective_mask)
        where, shares = differences(corrected, truth, traced.reflective_mask)
        window = crop_to(traced.reflective_mask)
        tiles = [truth, plain, plain_where, corrected, where]
        names = [
            "raytrace 4x4",
            "cube-live",
            "off >10: " + ", ".join(f"{k} {v:.1%}" for k, v in plain_shares.items()),
            f"cube-live, {label}",
            "off >10: " + ", ".join(f"{k} {v:.1%}" for k, v in shares.items()),
        ]
        side = max(t[window].shape[0] for t in tiles)
        row = []
        for tile, text in zip(tiles, names, strict=True):
            part = Image.fromarray(np.ascontiguousarray(tile[window]))
            part = part.resize(
                (part.width * 300 // side, part.height * 300 // side), Image.Resampling.NEAREST
            )
            row.append(labelled(np.asarray(part), text))
        rows.append(np.hstack(row))
        print(
            f"{name}: plain off {sum(plain_shares.values()):.1%} ({plain_shares}); "
            f"{label} off {sum(shares.values()):.1%} ({shares})"
        )
    width = max(r.shape[1] for r in rows)
    rows = [np.pad(r, ((0, 0), (0, width - r.shape[1]), (0, 0))) for r in rows]
    Image.fromarray(np.vstack(rows)).save(DOCS / "parallax.png")


PICTURES = ("methods", "envmaps", "cone", "parallax", "maps", "warp", "ssr")
FILES = {"maps": "direction_maps", "warp": "paraboloid_warp"}
"""The file a picture is written to, where it is not named as the picture is."""


def frames_and_maps(scenes: list[tuple[str, Any]]) -> np.ndarray:
    """Each ``(label, scene)`` drawn at ``SIZE``, above the map its sphere sampled (read
    back from the GL, level 0, scaled to the frame's width)."""
    from mirrorlab.gl.context import offscreen_context
    from mirrorlab.gl.resources import Framebuffer
    from mirrorlab.renderer import SceneRenderer

    columns = []
    with offscreen_context() as context:
        renderer = SceneRenderer(context.resources)
        target = Framebuffer(context.resources, SIZE, SIZE)
        try:
            for label, scene in scenes:
                stats = renderer.render(scene, target)
                frame = target.read()
                draw = next(d for d in stats.plan.top.draws if d.reflector.name == "sphere")
                texture = renderer.shown_texture(draw)
                assert texture is not None and hasattr(texture, "read")
                shown = Image.fromarray(texture.read())
                height = SIZE * shown.height // shown.width
                shown = shown.resize((SIZE, height), Image.Resampling.NEAREST)
                picture = np.zeros((SIZE, SIZE, 3), dtype=np.uint8)
                picture[(SIZE - height) // 2 : (SIZE - height) // 2 + height] = np.asarray(shown)
                columns.append(np.vstack([labelled(frame, label), picture]))
        finally:
            target.release()
            renderer.release()
    return np.hstack(columns)


def maps_picture() -> None:
    sphere = mirrorlab.load_scene("chrome_sphere")
    names = ("octahedral", "octahedral-live", "paraboloid", "paraboloid-live", "paraboloid-warped")
    scenes = [(m, apply_options(sphere, {"method": m, "map_size": 128})) for m in names]
    Image.fromarray(frames_and_maps(scenes)).save(DOCS / "direction_maps.png")


def warp_picture() -> None:
    import tempfile

    import trimesh

    room = mirrorlab.load_scene("sphere_room")
    with tempfile.TemporaryDirectory() as folder:
        objects = []
        for item in room.objects:
            assert isinstance(item, MeshObject)
            path = Path(folder) / f"{item.mesh.stem}.obj"
            if not path.exists():
                mesh = trimesh.load(item.mesh, force="mesh", process=False)
                assert isinstance(mesh, trimesh.Trimesh)
                for _ in range(4):  # each triangle into four: the walls' 8-unit edges 0.5
                    mesh = mesh.subdivide()
                mesh.export(path)
            objects.append(replace(item, mesh=path))
        finer = replace(room, objects=tuple(objects))
        warped = {"method": "paraboloid-warped", "map_size": 128}
        scenes = [
            (
                "converted",
                apply_options(
                    room, {"method": "paraboloid-live", "map_size": 128, "parallax": "none"}
                ),
            ),
            ("warped", apply_options(room, warped)),
            ("warped, walls cut", apply_options(finer, warped)),
        ]
        Image.fromarray(frames_and_maps(scenes)).save(DOCS / "paraboloid_warp.png")


def main(pictures: list[str]) -> None:
    chosen = set(pictures) or set(PICTURES)
    unknown = chosen - set(PICTURES)
    if unknown:
        raise SystemExit(
            f"make_docs.py: unknown picture {sorted(unknown)[0]!r}; expected one of "
            f"{', '.join(PICTURES)}"
        )
    if "maps" in chosen:
        maps_picture()
    if "warp" in chosen:
        warp_picture()
    with mirrorlab.Renderer(size=(SIZE, SIZE)) as renderer:
        if "methods" in chosen:
            methods_picture(renderer)
        if "envmaps" in chosen:
            envmaps_picture(renderer)
        if "cone" in chosen:
            cone_picture(renderer)
        if "parallax" in chosen:
            parallax_picture(renderer)
        if "ssr" in chosen:
            ssr_picture(renderer)
    print(f"wrote {', '.join(f'{DOCS}/{FILES.get(name, name)}.png' for name in sorted(chosen))}")


SSR_SCENES = (
    "ssr_behind_camera",
    "ssr_thin_pole",
    "ssr_grazing_water",
    "ssr_sphere_near",
    "ssr_box_room",
)


def ssr_picture(renderer) -> None:
    """docs/ssr.png: a row per scene of :data:`SSR_SCENES`: the frame, its miss mask, the
    frame without its probe (misses in the background's colour) and the ray tracer, with
    each one's mean FLIP and the share of false hits in the mask's label."""
    from mirrorlab import screen_space
    from mirrorlab.accuracy import image_error
    from mirrorlab.raytrace import reflection_hits

    size = (320, 320)
    rows = []
    for name in SSR_SCENES:
        scene = mirrorlab.load_scene(name)
        frame = np.asarray(renderer.render(scene, size=size))
        mask = renderer.ssr_mask()
        none = [f'reflectors[{i}].ssr.probe="none"' for i in range(len(scene.reflectors))]
        bare = np.asarray(renderer.render(scene, size=size, set=none))
        truth = trace_scene(scene, size).to_uint8()
        hits = reflection_hits(scene, size)
        region = (hits.reflector >= 0) & mask.reflector
        false = screen_space.false_hits(mask, hits.visible, hits.reflector >= 0)
        with_probe, alone = image_error(frame, truth, region), image_error(bare, truth, region)
        rows.append(
            np.hstack(
                [
                    labelled(frame, f"{name}: ssr, FLIP {with_probe.flip:.3f}"),
                    labelled(
                        mask.image(),
                        f"miss mask: {mask.miss_share:.0%} to the probe, "
                        f"{false.sum() / max(region.sum(), 1):.2%} false hits",
                    ),
                    labelled(bare, f"no probe, FLIP {alone.flip:.3f}"),
                    labelled(truth, "raytrace"),
                ]
            )
        )
        print(
            f"{name}: FLIP {with_probe.flip:.4f} (no probe {alone.flip:.4f}), miss share "
            f"{mask.miss_share:.3f}, false hits {false.sum()} of {region.sum()}"
        )
    Image.fromarray(np.vstack(rows)).save(DOCS / "ssr.png")


def methods_picture(renderer) -> None:
    angle = math.radians(-30)  # 16 units out, 30 degrees off the normal, a little above
    eye = (-7 + 16 * math.cos(angle), 1.0 + 4.8, -2 + 16 * math.sin(angle))
    view: dict[str, Any] = {"camera": eye, "target": (-7.0, 1.0, -2.0)}
    methods = [
        labelled(renderer.render("lab20", method=m, **view), m) for m in technique_names("planar")
    ]
    methods.append(
        labelled(
            mirrorlab.render("lab20", size=(SIZE, SIZE), method="raytrace", **view), "raytrace"
        )
    )
    Image.fromarray(grid(methods, 4)).save(DOCS / "methods.png")


def envmaps_picture(renderer) -> None:
    sphere = mirrorlab.load_scene("chrome_sphere")
    maps = [labelled(renderer.render(sphere, method=m), m) for m in technique_names("curved")]
    truth = trace_scene(sphere, (SIZE, SIZE), supersample=4).to_uint8()
    Image.fromarray(grid([*maps, labelled(truth, "raytrace 4x4")], 4)).save(DOCS / "envmaps.png")


def cone_picture(renderer) -> None:
    cone = apply_options(mirrorlab.load_scene("spheremap_cone"), {"method": "sphere-texgen"})
    placed_cone = cone.reflector("cone")
    assert isinstance(placed_cone, CurvedReflector)
    placed = placed_cone.transform
    cones = []
    for height in (1.0, -1.0):
        moved = cone.with_reflector(
            "cone",
            transform=replace(placed, position=(placed.position[0], height, placed.position[2])),
        )
        cones.append(labelled(renderer.render(moved), f"cone at height {height:g}"))
    Image.fromarray(grid(cones, 2)).save(DOCS / "cone.png")


if __name__ == "__main__":
    main(sys.argv[1:])
