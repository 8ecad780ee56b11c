"""`shadowvol compare`: raster against ray traced, as a picture, a table and JSON."""

from __future__ import annotations

import argparse
import json
import re
import sys
from pathlib import Path

from shadowvol import memory
from shadowvol.cli import options, output_paths, status
from shadowvol.compare import estimate, pyrender_peer
from shadowvol.compare.comparison import compare
from shadowvol.raster import methods
from shadowvol.errors import InputError
from shadowvol.io import atomic_write, save_png
from shadowvol.scene import SceneError
from shadowvol.scenefile import load_scene

EPILOG = """\
Interior mismatches are pixels whose lit masks differ farther than one pixel from an edge of
either renderer's lit or coverage mask: exact shadows should have none; pixels on an edge may
differ by rounding.  Difference colours: white both lit, grey both shadowed, red shadowed only
in the raster, blue shadowed only in the ray tracer, black uncovered, yellow covered in one
renderer only.

""" + status.EPILOG


def _size(text: str) -> tuple[int, int]:
    m = re.fullmatch(r"\s*(\d+)\s*[xX]\s*(\d+)\s*", text)
    if not m or int(m[1]) <= 0 or int(m[2]) <= 0:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT, e.g. 320x240, got {text!r}")
    return int(m[1]), int(m[2])


def _count(text: str) -> int:
    try:
        n = int(text)
    except ValueError:
        n = -1
    if n < 0:
        raise argparse.ArgumentTypeError(f"expected a whole number >= 0, got {text!r}")
    return n


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = options.command(
        subparsers, "compare", help="raster against ray-traced shadows: picture, table, numbers",
        description="Render SCENE with shadow volumes and with the reference ray tracer; print "
                    "per light the mismatched pixels, those away from mask edges, the IoU of "
                    "the shadow regions and each renderer's time; draw both side by side with "
                    "the masks' difference.",
        epilog=EPILOG)
    options.scene(p)
    options.output(p, "PNG", "the picture")
    p.add_argument("--method", choices=methods.METHODS, default="auto",
                   help="how the rasterizer counts shadow volumes (default: auto)")
    p.add_argument("--json", metavar="FILE", help="also write the numbers as JSON")
    p.add_argument("--max-interior", type=_count, metavar="N",
                   help="exit with status 1 when any light has more than N interior "
                        "mismatches (for CI)")
    p.add_argument("--pyrender", action="store_true",
                   help="add pyrender's shadow-mapped image and count its mask errors against "
                        "the ray tracer (spot and directional lights; pyrender has no "
                        "point-light shadows; needs the [peer] extra)")
    p.add_argument("--size", type=_size, metavar="WxH",
                   help="render at this size instead of the scene's image size")
    options.memory_budget(p)
    p.set_defaults(func=command)
    return p


def command(args) -> int:
    paths = {"picture": Path(args.output)}
    if args.json:
        paths["json"] = Path(args.json)
    output_paths.check(paths, {"picture": "-o", "json": "--json"})
    if args.pyrender:
        pyrender_peer.import_pyrender()  # a missing [peer] extra is reported before any work
    scene = load_scene(args.scene)
    if args.size is not None:
        try:
            scene = scene.replace(width=args.size[0], height=args.size[1])
        except SceneError as exc:
            raise InputError("--size", exc.problem) from None
    # the GL frame is counted as this process's memory: the context is made later
    memory.check(estimate.compare(scene), args.memory_budget, args.scene)
    with status.naming(args.scene):
        result = compare(scene, method=args.method, pyrender=args.pyrender)
    print(result.table())
    save_png(args.output, result.picture())
    written = [args.output]
    if args.json:
        with atomic_write(args.json) as f:
            f.write((json.dumps(result.to_dict(), indent=2) + "\n").encode())
        written.append(args.json)
    print(f"wrote {', '.join(written)}", file=sys.stderr)
    if args.max_interior is not None and result.exceeds(args.max_interior):
        worst = max(l.interior for l in result.lights)
        print(f"over budget: {worst} interior mismatches > --max-interior "
              f"{args.max_interior}", file=sys.stderr)
        return status.OVER_BUDGET
    return status.OK
