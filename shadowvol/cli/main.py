"""The `shadowvol` command: one module per subcommand, each with `add_parser(subparsers)`.

    shadowvol render SCENE -o out.png [--masks out.npz] [--volumes v.png] [--stencil s.png]
    shadowvol masks SCENE -o masks.npz [--renderer auto|shadowvol|raytrace] [--png m.png]
    shadowvol compare SCENE -o cmp.png [--pyrender] [--max-interior N]
    shadowvol planar SCENE -o out.png [--receiver NAME] [--masks m.npz]
    shadowvol demo -o DIR [--size WxH] [--small]
    shadowvol view SCENE                      (a window: orbit, drag the light, probe a pixel)
    shadowvol shadow2d --example -o shadow2d.png
    shadowvol batch JOBS.jsonl -o OUT [--workers N] [--shard I/N] [--ray [ADDRESS]]
    shadowvol shadowmap SCENE -o pic.png [--resolution N] [--bias B] [--pcf K] [--json F]
    shadowvol course new|solutions DIR,  shadowvol course grade DIR [--json F]

Exit statuses: `shadowvol.cli.status` (one table for both tools).
"""

from __future__ import annotations

import argparse
import sys

from shadowvol import __version__
from shadowvol.cli import (
    batch,
    compare,
    course,
    demo,
    masks,
    options,
    planar,
    render,
    shadow2d,
    shadowmap,
    status,
    view,
)

COMMANDS = (render, masks, planar, shadow2d, compare, shadowmap, demo, view, batch, course)


def build_parser() -> argparse.ArgumentParser:
    parser = options.Parser(
        prog="shadowvol",
        description="Exact hard shadows with stencil shadow volumes, headless (OpenGL on EGL).",
        epilog=status.EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--version", action="version", version=f"shadowvol {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for module in COMMANDS:
        module.add_parser(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    return status.main(build_parser, argv)


if __name__ == "__main__":
    sys.exit(main())
