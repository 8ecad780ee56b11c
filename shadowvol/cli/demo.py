"""`shadowvol demo`: the course's gallery, one PNG per picture and an index.html."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from shadowvol.cli import status
from shadowvol.course.gallery import SCENES, SMALL_SCALE, build_gallery, index_html
from shadowvol.io import atomic_write, save_png


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "demo", help="render the course's gallery of demos and an index.html",
        description="Render every demo of the course (shadow volumes, z-pass against z-fail, "
                    "the stencil heat map, planar projected shadows, the 2D exercise, the ray "
                    "tree, Whitted ray tracing, raster against ray traced), each PNG with a "
                    "title, and DIR/index.html showing them with captions.",
        epilog=status.EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("-o", "--output", required=True, metavar="DIR", type=Path,
                   help="the folder to write the pictures and index.html into")
    p.add_argument("--small", action="store_true",
                   help=f"every scene at 1/{SMALL_SCALE} of its size (fast: for CI)")
    p.add_argument("--scenes", type=Path, default=SCENES, metavar="DIR",
                   help="the scenes folder (default: the example scenes installed with "
                        "shadowvol, or a source checkout's scenes/)")
    p.set_defaults(func=command)
    return p


def command(args) -> int:
    def progress(name: str, seconds: float) -> None:
        print(f"  {name}: {seconds:.1f} s", file=sys.stderr)

    pictures = build_gallery(args.small, args.scenes, progress=progress)
    out = Path(args.output)
    for p in pictures:
        save_png(out / f"{p.name}.png", p.image)
    with atomic_write(out / "index.html") as f:
        f.write(index_html(pictures, args.small).encode("utf-8"))
    print(f"wrote {len(pictures)} pictures and {out / 'index.html'}", file=sys.stderr)
    return status.OK
