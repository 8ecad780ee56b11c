"""`shadowvol shadow2d`: the 2D shadow-polygon exercise from the command line."""

from __future__ import annotations

import argparse
import json
import sys
import tomllib
from pathlib import Path

import numpy as np

from shadowvol.cli import options, output_paths, status
from shadowvol.course.shadow2d import (
    as_light,
    as_segments,
    draw_shadow2d,
    example,
    listing,
    polygon_segments,
    shadow_polygons,
)
from shadowvol.io import save_png
from shadowvol.scene import SceneError, reject_unknown_keys

INPUT_KEYS = {"light", "segments", "polygons", "back_faces"}

INPUT_HELP = """\
Input: an optional TOML or JSON file, plus command-line numbers that extend or override it.

  light = [0.45, 0.35]                         # the point light L
  segments = [[0.2, 0.7, 0.4, 0.7], ...]       # v_a x, v_a y, v_b x, v_b y (or [[ax, ay], [bx, by]])
  polygons = [[[0.6, 0.4], [0.8, 0.5], [0.6, 0.6]]]   # closed outlines, vertices CCW
  back_faces = true                            # back-facing segments cast (two-sided occluders)

Everything lies in the unit square (0,0)-(1,1).  A segment's outward normal is the right-hand
perpendicular of v_a -> v_b (outward for CCW outlines).  Every shadow polygon is printed CCW
around its shadow region with its normal pointing out of the shadow.  A segment whose line passes
through the light (edge-on, or holding the light) casts a zero-area shadow and is listed without
shadow polygons.  Without any input, --example draws the course's example.
"""


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = options.command(
        subparsers, "shadow2d",
        help="the 2D shadow-polygon exercise: list and draw shadow polygons",
        description="Shadow polygons of segments lit by a point light in the unit square.",
        epilog=INPUT_HELP + "\n" + status.EPILOG)
    add_shadow2d_arguments(p)
    p.set_defaults(func=command)
    return p


def add_shadow2d_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("input", nargs="?", type=Path, help="a .toml or .json file (see below)")
    p.add_argument("--light", nargs=2, type=float, metavar=("X", "Y"), help="the light L")
    p.add_argument("--segment", nargs=4, type=float, action="append", default=[],
                   metavar=("AX", "AY", "BX", "BY"), help="a segment v_a -> v_b (repeatable)")
    p.add_argument("--polygon", nargs="+", type=float, action="append", default=[],
                   metavar="XY", help="a closed CCW outline x1 y1 x2 y2 ... (repeatable)")
    p.add_argument("--front-only", action="store_true",
                   help="back-facing segments do not cast (for closed outlines, light outside)")
    p.add_argument("--example", action="store_true", help="use the course's example scene")
    p.add_argument("-o", "--output", type=Path, help="write the picture to this PNG")
    p.add_argument("--size", type=int, default=800, help="picture size in pixels (default 800)")


def _read_input(path: Path) -> dict:
    text = path.read_bytes()
    if path.suffix.lower() == ".json":
        data = json.loads(text)
    elif path.suffix.lower() == ".toml":
        data = tomllib.loads(text.decode("utf-8"))
    else:
        raise ValueError(f"{path}: the input must end in .toml or .json")
    try:
        reject_unknown_keys(data, INPUT_KEYS)
    except SceneError as exc:
        raise exc.in_file(str(path)) from None
    return data


def _gather(args) -> tuple[np.ndarray, np.ndarray, bool]:
    """Light (2,), segments (n, 2, 2) and back_faces from the parsed command line."""
    light, parts, back_faces = None, [], True
    if args.example:
        light, ex = example()
        parts.append(ex)
    if args.input is not None:
        data = _read_input(args.input)
        light = data.get("light", light)
        back_faces = bool(data.get("back_faces", True))
        if data.get("segments"):
            parts.append(as_segments(data["segments"]))
        for k, outline in enumerate(data.get("polygons", [])):
            try:
                parts.append(polygon_segments(outline))
            except ValueError as exc:
                raise ValueError(f"polygons[{k}]: {exc}") from None
    if args.light is not None:
        light = args.light
    if args.segment:
        parts.append(as_segments(args.segment))
    for k, numbers in enumerate(args.polygon):
        if len(numbers) % 2 or len(numbers) < 4:
            raise ValueError(f"--polygon #{k + 1}: needs pairs x y, at least two vertices")
        parts.append(polygon_segments(np.reshape(numbers, (-1, 2))))
    if light is None:
        raise ValueError("no light: give --light X Y, a file with `light`, or --example")
    if not parts:
        raise ValueError("no segments: give --segment, --polygon, a file, or --example")
    return as_light(light), as_segments(np.concatenate(parts)), \
        back_faces and not args.front_only


def command(args) -> int:
    """Run `shadowvol shadow2d`: print the listing, write the picture if -o is given."""
    if args.output is not None:
        output_paths.check({"picture": args.output}, {"picture": "-o"})
    try:
        light, segments, back_faces = _gather(args)
    except (OSError, ValueError, tomllib.TOMLDecodeError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return status.BAD_INPUT
    shadows = shadow_polygons(light, segments, back_faces=back_faces)
    print(listing(light, segments, shadows))
    if args.output is not None:
        save_png(args.output, draw_shadow2d(light, segments, shadows, size_px=args.size))
        print(f"wrote {args.output}")
    return status.OK
