"""`shadowvol planar`: planar projected shadows (Blinn 1988) from the command line."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from shadowvol import memory
from shadowvol.cameras import calibration
from shadowvol.cli import options, output_paths, status
from shadowvol.errors import InputError
from shadowvol.frame import save_masks
from shadowvol.io import save_png
from shadowvol.raster import estimate
from shadowvol.raster.planar.draw import ReceiverError, render_planar
from shadowvol.scenefile import load_scene


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = options.command(
        subparsers, "planar", help="render planar projected shadows (Blinn 1988) onto one plane",
        description="Render SCENE with planar projected shadows: every object squashed from "
                    "each light onto the receiving plane by a 4x4 matrix and drawn there as "
                    "shadow (the stencil keeps it on the receiver, once per pixel).  Only the "
                    "receiver is ever shadowed: no shadows on other objects, no self-shadows "
                    "(`shadowvol render` draws those, with shadow volumes).")
    options.scene(p)
    options.output(p, "PNG", "where to write the image (8-bit sRGB PNG, row 0 at the top)")
    p.add_argument("--receiver", metavar="NAME", default=None,
                   help="the object that receives the shadows: a plane or a flat mesh, by "
                        "name (default: the largest plane object)")
    p.add_argument("--masks", metavar="NPZ", default=None,
                   help="also write the masks (.npz: lit (L, H, W), coverage (H, W)); lit is "
                        "False only in the projected shadows on the receiver")
    options.memory_budget(p)
    p.set_defaults(func=command)
    return p


def command(args) -> int:
    paths = {"image": Path(args.output)}
    if args.masks:
        paths["masks"] = Path(args.masks)
    output_paths.check(paths, {"image": "-o", "masks": "--masks"})
    scene = load_scene(args.scene)
    memory.check(estimate.render(scene, written=tuple(k for k in ("png", "masks")
                                                      if k in paths or k == "png")),
                 args.memory_budget, args.scene)
    try:
        with status.naming(args.scene):
            result = render_planar(scene, args.receiver)
    except ReceiverError as exc:
        raise InputError("--receiver", str(exc)) from None
    save_png(paths["image"], result.image)
    if "masks" in paths:
        save_masks(paths["masks"], result.lit, result.coverage,
                   arrays=calibration(scene).arrays())
    receiver = scene.objects[result.receiver].name
    print(f"wrote {', '.join(str(p) for p in paths.values())} (shadows on {receiver!r})",
          file=sys.stderr)
    return status.OK
