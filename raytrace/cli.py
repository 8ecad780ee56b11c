"""The `raytrace` command: Whitted renders and reference shadow masks of a scene file.

    raytrace render scenes/whitted.toml -o whitted.png
    raytrace masks  scenes/whitted.toml -o whitted-masks.npz      (+ whitted-masks.png)
    raytrace tree   scenes/whitted.toml --pixel 420 300 --depth 3 -o tree.png

Outputs are written atomically (shadowvol.files): an error never leaves half a file behind.
A bad scene prints `error: <file>: <key>: <problem>` and exits with status 2.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from .backends import BACKENDS

EXIT_BAD_INPUT = 2


def _parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(
        prog="raytrace",
        description="Reference CPU ray tracer of shadowvol: Whitted images and the exact "
                    "shadow masks the shadow-volume rasterizer is checked against.",
        epilog="Scene files: TOML or JSON, see scenes/README.md.  Masks follow "
               "CONVENTIONS.md: lit (L, H, W) bool per light in scene order, coverage (H, W).")
    sub = ap.add_subparsers(dest="command", required=True, metavar="COMMAND")

    r = sub.add_parser("render", help="ray-trace an image (Whitted: shadows, reflection, "
                                      "refraction, Phong)",
                       description="Ray-trace SCENE into an 8-bit sRGB PNG.")
    r.add_argument("scene", metavar="SCENE", help="scene file (.toml or .json)")
    r.add_argument("-o", "--output", required=True, metavar="PNG",
                   help="where to write the image (PNG, sRGB, row 0 at the top)")
    r.add_argument("--max-depth", type=int, default=None, metavar="N",
                   help="reflection/refraction generations; 0 = direct lighting only, as the "
                        "rasterizer draws it (default: the scene's render.max_depth)")
    _backend(r)
    r.add_argument("--no-progress", action="store_true",
                   help="no progress bar (it is shown only on a terminal anyway)")

    m = sub.add_parser("masks", help="reference shadow masks (lit per light, coverage)",
                       description="Trace the reference shadow masks of SCENE on its triangles "
                                   "and write them as a .npz (lit, coverage) and a picture.")
    m.add_argument("scene", metavar="SCENE", help="scene file (.toml or .json)")
    m.add_argument("-o", "--output", required=True, metavar="NPZ",
                   help="where to write the masks (.npz with lit (L, H, W) and coverage (H, W))")
    m.add_argument("--png", metavar="PNG", default=None,
                   help="where to write a picture of the masks, one panel per light (white lit, "
                        "grey shadowed, black empty) (default: beside the .npz, same name, .png)")
    m.add_argument("--no-png", action="store_true", help="write the .npz only")
    _backend(m)

    t = sub.add_parser("tree", help="the ray tree of one pixel (the course's exercise)",
                       description="Print every ray the Whitted tracer follows for pixel "
                                   "(X, Y) — primary, shadow rays with their verdicts, "
                                   "reflected, refracted, total internal reflection — as an "
                                   "indented tree, and optionally draw them over the render "
                                   "and in a side view.")
    t.add_argument("scene", metavar="SCENE", help="scene file (.toml or .json)")
    t.add_argument("--pixel", nargs=2, type=int, required=True, metavar=("X", "Y"),
                   help="column X from the left, row Y from the top")
    t.add_argument("--depth", type=int, default=None, metavar="N",
                   help="reflection/refraction generations (default: the scene's "
                        "render.max_depth)")
    t.add_argument("-o", "--output", metavar="PNG", default=None,
                   help="also draw the tree: the rays over the ray-traced image and a side view")
    _backend(t)
    return ap


def _backend(p: argparse.ArgumentParser) -> None:
    p.add_argument("--backend", choices=BACKENDS, default="embree",
                   help="triangle intersection: 'embree' (fast, float32) or 'numpy' (the float64 "
                        "reference, for small scenes) (default: embree)")


def main(argv: list[str] | None = None) -> int:
    args = _parser().parse_args(argv)
    from shadowvol.files import masks_image, save_masks, save_png
    from shadowvol.scene import SceneError
    from shadowvol.scenefile import load_scene

    try:
        scene = load_scene(args.scene)
    except SceneError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT

    try:
        if args.command == "tree":
            return _tree(args, scene)
        if args.command == "render":
            from .whitted import render
            if args.max_depth is not None and args.max_depth < 0:
                print(f"error: --max-depth must be >= 0, got {args.max_depth}", file=sys.stderr)
                return EXIT_BAD_INPUT
            image = render(scene, max_depth=args.max_depth, backend=args.backend,
                           progress=False if args.no_progress else None)
            save_png(args.output, image)
            print(f"wrote {args.output}", file=sys.stderr)
        else:
            from shadowvol.scene import light_samples

            from . import shadow_masks  # (area lights: lit where every sample reaches)
            png = None if args.no_png else args.png or str(Path(args.output).with_suffix(".png"))
            if png is not None and Path(png).resolve() == Path(args.output).resolve():
                print(f"error: the masks and their picture would both be {args.output}; "
                      "give the masks a .npz name or choose --png", file=sys.stderr)
                return EXIT_BAD_INPUT
            lit, coverage = shadow_masks(scene, backend=args.backend)
            save_masks(args.output, lit, coverage,
                       light_samples=[light_samples(lt) for lt in scene.lights])
            written = [args.output]
            if png is not None:
                save_png(png, masks_image(lit, coverage))
                written.append(png)
            print(f"wrote {', '.join(written)}", file=sys.stderr)
    except ImportError as exc:  # e.g. embreex missing: say so, and how to do without
        print(f"error: {exc}", file=sys.stderr)
        return 1
    except OSError as exc:
        print(f"error: cannot write output: {exc}", file=sys.stderr)
        return 1
    return 0


def _tree(args, scene) -> int:
    """The `tree` command: print the ray tree of one pixel, draw it with -o."""
    import io

    from shadowvol.files import atomic_write

    from .raytree import draw_tree, format_tree, ray_tree
    from .whitted import render

    x, y = args.pixel
    if args.depth is not None and args.depth < 0:
        print(f"error: --depth must be >= 0, got {args.depth}", file=sys.stderr)
        return EXIT_BAD_INPUT
    if not (0 <= x < scene.width and 0 <= y < scene.height):
        print(f"error: --pixel {x} {y} is outside the {scene.width}x{scene.height} image",
              file=sys.stderr)
        return EXIT_BAD_INPUT
    tree = ray_tree(scene, x, y, max_depth=args.depth, backend=args.backend)
    print(format_tree(tree, scene))
    if args.output:
        image = render(scene, max_depth=args.depth, backend=args.backend, progress=False)
        buf = io.BytesIO()
        draw_tree(scene, tree, image).savefig(buf, format="png")
        with atomic_write(args.output) as f:
            f.write(buf.getvalue())
        print(f"wrote {args.output}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
