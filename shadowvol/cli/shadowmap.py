"""`shadowvol shadowmap`: a shadow map measured against the exact shadow."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from shadowvol import memory
from shadowvol.cli import options, output_paths, status
from shadowvol.compare.shadowmaps import ShadowMapper
from shadowvol.course.shadowmap_plot import plot, sweep
from shadowvol.errors import InputError
from shadowvol.io import save_png, write_bytes
from shadowvol.raster import estimate
from shadowvol.scene import SceneError
from shadowvol.scenefile import load_scene

MAX_RESOLUTION = 8192
MAX_PCF = 15


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = options.command(
        subparsers, "shadowmap", help="a shadow map against the exact shadow: acne and "
                                      "peter-panning counted",
        description="Shadow-map one light of SCENE (its depth map in GL, a bias, PCF) and "
                    "count the pixels it gets wrong against the exact shadow of shadow "
                    "volumes: acne (lit surfaces called shadowed) and peter-panning (shadowed "
                    "surfaces called lit), among the visible pixels that face the light.")
    options.scene(p)
    options.output(p, "PNG", "the picture: the map's shadow | the exact shadow | the difference")
    p.add_argument("--resolution", type=int, default=1024, metavar="N",
                   help="the map's texels a side (default 1024)")
    p.add_argument("--bias", type=float, default=0.002, metavar="B",
                   help="depth bias, in the map's depth units (0..1 over the light's depth "
                        "range; default 0.002)")
    p.add_argument("--pcf", type=int, default=1, metavar="K",
                   help="percentage-closer filtering over K x K texels (default 1: none)")
    p.add_argument("--light", type=int, default=0, metavar="I",
                   help="the light to map, by index (default 0): point, spot or directional")
    p.add_argument("--json", metavar="F", default=None,
                   help="also write the counts as JSON (misclassified, acne, peter_panning)")
    p.add_argument("--plot", metavar="PNG", default=None,
                   help="also write the error against resolution (256-4096) and bias")
    options.memory_budget(p)
    p.set_defaults(func=command)
    return p


def _check(args) -> None:
    if not 16 <= args.resolution <= MAX_RESOLUTION:
        raise InputError("--resolution", f"must be 16..{MAX_RESOLUTION}, got {args.resolution}")
    if not (math.isfinite(args.bias) and args.bias >= 0):
        raise InputError("--bias", f"must be a finite number >= 0, got {args.bias}")
    if not 1 <= args.pcf <= MAX_PCF:
        raise InputError("--pcf", f"must be 1..{MAX_PCF}, got {args.pcf}")


def command(args) -> int:
    paths = {"image": Path(args.output)}
    if args.json:
        paths["json"] = Path(args.json)
    if args.plot:
        paths["picture"] = Path(args.plot)
    output_paths.check(paths, {"image": "-o", "json": "--json", "picture": "--plot"})
    _check(args)
    scene = load_scene(args.scene)
    memory.check(estimate.render(scene, written=("png",)), args.memory_budget, args.scene)
    try:
        with status.naming(args.scene):   # the Renderer's refusals name the scene file
            mapper = ShadowMapper(scene, args.light)
    except SceneError:
        raise   # the scene's (`image`, `objects`), not the light's
    except ValueError as exc:
        raise InputError("--light", str(exc)) from None
    with mapper:
        result = mapper.measure(args.resolution, args.bias, args.pcf)
        rows = sweep(mapper, pcf=args.pcf) if args.plot else None
    counts = {"scene": str(args.scene), "light": args.light, **result.counts()}
    save_png(paths["image"], result.picture())
    if args.json:
        write_bytes(paths["json"], (json.dumps(counts, indent=2) + "\n").encode("utf-8"))
    if rows is not None:
        save_png(paths["picture"], plot(rows, f"{scene.name}, light {args.light}: the shadow "
                                              f"map against the exact shadow (PCF {args.pcf})"))
    print(f"{counts['misclassified']} of {counts['pixels']} pixels misclassified: "
          f"{counts['acne']} acne, {counts['peter_panning']} peter-panning")
    print(f"wrote {', '.join(str(p) for p in paths.values())}", file=sys.stderr)
    return status.OK
