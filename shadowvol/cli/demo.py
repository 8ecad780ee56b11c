"""`shadowvol demo`: the course's gallery, one PNG per picture and an index.html."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from shadowvol.cli import options, status
from shadowvol.course.gallery import SCENES, build_gallery, index_html, parse_size
from shadowvol.course.slides import SLIDE, SMALL_SLIDE
from shadowvol.errors import InputError
from shadowvol.io import atomic_write, save_png


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = options.command(
        subparsers, "demo", help="render the course's gallery of demos and an index.html",
        description="Render every picture of the course as a slide (shadows, planar shadows, "
                    "the shadow polygons of one box, the stencil counter, counting along an "
                    "eye ray, z-pass against z-fail, Whitted ray tracing, the ray tree, total "
                    "internal reflection, the exercises, raster against ray traced, shadow "
                    "mapping against shadow volumes, the rendering equation, the ladder of its "
                    "solutions, a caustic, aliasing, gloss and depth of field), and "
                    "DIR/index.html showing them in the course's order with a table of "
                    "contents and captions.")
    options.output(p, "DIR", "the folder to write the pictures and index.html into", type=Path)
    p.add_argument("--size", metavar="WxH", default=None,
                   help=f"slide size in pixels (default {SLIDE[0]}x{SLIDE[1]})")
    p.add_argument("--small", action="store_true",
                   help=f"{SMALL_SLIDE[0]}x{SMALL_SLIDE[1]} slides (fast: for CI)")
    p.add_argument("--scenes", type=Path, default=SCENES, metavar="DIR",
                   help="the scenes folder (default: the example scenes installed with "
                        "shadowvol, or a source checkout's scenes/)")
    options.memory_budget(p)
    p.set_defaults(func=command)
    return p


def command(args) -> int:
    def progress(name: str, seconds: float) -> None:
        print(f"  {name}: {seconds:.1f} s", file=sys.stderr)

    if args.size and args.small:
        raise InputError("--size", "give --size or --small, not both")
    size = parse_size(args.size) if args.size else None
    skipped = []
    pictures = build_gallery(args.small, args.scenes, progress=progress, size=size,
                             skipped=skipped, memory_budget=args.memory_budget)
    for name, why in skipped:
        print(f"  {name}: left out: {why}", file=sys.stderr)
    out = Path(args.output)
    for p in pictures:
        save_png(out / f"{p.name}.png", p.image)
    with atomic_write(out / "index.html") as f:
        f.write(index_html(pictures, args.small, size, skipped).encode("utf-8"))
    print(f"wrote {len(pictures)} pictures and {out / 'index.html'}", file=sys.stderr)
    return status.OK

