"""The `raytrace` command: Whitted renders and reference shadow masks of a scene file.

    raytrace render scenes/whitted.toml -o whitted.png
    raytrace render scenes/whitted.toml -o whitted.png --exr whitted.exr --png16 whitted16.png
    raytrace render scenes/whitted.toml -o whitted-aa.png --spp 16 --filter tent --seed 1
    raytrace masks  scenes/whitted.toml -o whitted-masks.npz      (+ whitted-masks.png)
    raytrace masks  scenes/whitted.toml -o truth.npz --outputs depth,normal,object_id,casters
    raytrace tree   scenes/whitted.toml --pixel 420 300 --depth 3 -o tree.png
    raytrace render scenes/cornell.toml --integrator path --spp 64 -o cornell.png
    raytrace render scenes/caustic.toml --integrator photon --photons 500000 -o caustic.png
    raytrace radiosity scenes/cornell.toml --level 4 -o cornell-radiosity.png
    raytrace exercise plane -o plane.png                            (the worked solution)

Outputs are written atomically (shadowvol.io): an error never leaves half a file behind.
A bad scene prints `error: <file>: <key>: <problem>`; the exit statuses are shadowvol's
(`shadowvol.cli.status`).  The ray tracer (`raytrace`) is a library; this is its command line:
the parser here, one module per subcommand (`render`, with the outlook's path tracer and
photon map, `radiosity`, `masks`, `tree`, `exercise`), as `shadowvol`'s own commands are
(`shadowvol.cli.main`).
"""

from __future__ import annotations

import argparse
import sys

from shadowvol import __version__
from shadowvol.cli import options, status
from shadowvol.cli.raytrace import exercise, masks, radiosity, render, tree

COMMANDS = (render, radiosity, masks, tree, exercise)


def build_parser() -> argparse.ArgumentParser:
    ap = options.Parser(
        prog="raytrace",
        description="Reference CPU ray tracer of shadowvol: Whitted images and the exact "
                    "shadow masks the shadow-volume rasterizer is checked against.",
        epilog="Scene files: TOML or JSON, see scenes/README.md.  Masks follow "
               "docs/CONVENTIONS.md: lit (L, H, W) bool per light in scene order, coverage "
               "(H, W).\n\n" + status.EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--version", action="version", version=f"raytrace (shadowvol) {__version__}")
    sub = ap.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for module in COMMANDS:
        module.add_parser(sub)
    return ap


def main(argv: list[str] | None = None) -> int:
    return status.main(build_parser, argv)


if __name__ == "__main__":
    sys.exit(main())
