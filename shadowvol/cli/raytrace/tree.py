"""`raytrace tree`: the ray tree of one pixel, printed, and drawn with -o (the gallery's
slide)."""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

from raytrace.backends import BACKENDS
from raytrace.outlook.estimate import whitted
from raytrace.outlook.raytree import format_tree, ray_tree
from raytrace.outlook.whitted import render
from shadowvol import memory
from shadowvol.cli import options, output_paths, status
from shadowvol.course import raytree_slide
from shadowvol.course.slides import Layout
from shadowvol.errors import InputError
from shadowvol.io import save_png
from shadowvol.scenefile import load_scene


def add_parser(sub) -> None:
    t = options.command(sub, "tree", help="the ray tree of one pixel (the course's exercise)",
                       description="Print every ray the Whitted tracer follows for pixel "
                                   "(X, Y) — primary, shadow rays with their verdicts, "
                                   "reflected, refracted, total internal reflection — as an "
                                   "indented tree, and optionally draw the gallery's slide of "
                                   "it: the rays over the render, the tree as boxes beside "
                                   "it.")
    options.scene(t)
    t.add_argument("--pixel", nargs=2, type=int, required=True, metavar=("X", "Y"),
                   help="column X from the left, row Y from the top")
    t.add_argument("--depth", type=int, default=None, metavar="N",
                   help="reflection/refraction generations (default: the scene's "
                        "render.max_depth)")
    options.output(t, "PNG", "also draw the tree (a 1920x1080 slide): the rays over the "
                            "ray-traced image and one box per ray", required=False)
    options.backend(t, BACKENDS)
    options.memory_budget(t)
    t.set_defaults(func=command)


def command(args) -> int:
    """Print the ray tree of one pixel, draw it with -o."""
    if args.output:
        output_paths.check({"picture": Path(args.output)}, {"picture": "-o"}, "raytrace")
    if args.depth is not None and args.depth < 0:
        raise InputError("--depth", f"must be >= 0, got {args.depth}")
    scene = load_scene(args.scene)
    x, y = args.pixel
    if not (0 <= x < scene.width and 0 <= y < scene.height):
        raise InputError("--pixel", f"{x} {y} is outside the {scene.width}x{scene.height} "
                                    "image")
    layout = Layout(supersample=1)  # the gallery's slide, its image traced once a pixel
    if args.output:
        estimate = whitted(raytree_slide.traced_scene(layout, scene))
        memory.check(dataclasses.replace(estimate, what=f"{estimate.what} on the ray tree "
                                                        "slide's image"),
                     args.memory_budget, args.scene)
    tree = ray_tree(scene, x, y, max_depth=args.depth, backend=args.backend)
    print(format_tree(tree, scene))
    if args.output:
        depth = scene.max_depth if args.depth is None else args.depth
        picture = raytree_slide.slide(layout, scene, tree, (x, y), depth, lambda s: render(
            s, max_depth=args.depth, backend=args.backend, progress=False))
        save_png(args.output, picture)
        print(f"wrote {args.output}", file=sys.stderr)
    return status.OK
