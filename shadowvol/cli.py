"""The `shadowvol` command.

    shadowvol render SCENE -o out.png [--method zpass|zfail|auto] [--silhouettes cpu|gpu]
                                      [--masks out.npz] [--volumes out.png] [--stencil out.png]

Each subcommand lives in its own module and registers itself: SUBCOMMANDS lists
(module, function) pairs; the function gets argparse's subparsers object, adds its parser and
sets `func` to a callable taking the parsed arguments and returning the exit status.  Adding a
command = writing such a function and listing it here.

Exit status: 0 success; 2 bad input (scene file, arguments) or no usable GL (EGL driver, GL 4.5)
— printed as `error: <message>` on stderr, without a traceback.  Outputs are written atomically
(shadowvol.files): an error never leaves half a file behind.
"""

from __future__ import annotations

import argparse
import importlib
import sys

EXIT_OK = 0
EXIT_ERROR = 2

SUBCOMMANDS = (
    ("shadowvol.cli", "add_render_parser"),
    ("shadowvol.shadow2d", "add_shadow2d_parser"),
    ("shadowvol.compare", "add_compare_parser"),
    ("shadowvol.demo", "add_demo_parser"),
)

RENDER_EPILOG = """\
Every image is 8-bit sRGB, row 0 at the top; masks follow CONVENTIONS.md.  Scene files are TOML
or JSON (scenes/README.md).  Rendering needs an EGL driver with OpenGL 4.5 (Mesa's llvmpipe is
enough: on Debian/Ubuntu `apt-get install libegl1 libgl1-mesa-dri`).
"""


def add_render_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "render", help="render a scene with stencil shadow volumes",
        description="Render SCENE with exact hard shadows counted in the stencil buffer "
                    "(direct Phong lighting: ambient + each light where unshadowed).",
        epilog=RENDER_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene", metavar="SCENE", help="scene file (.toml or .json)")
    p.add_argument("-o", "--output", required=True, metavar="PNG",
                   help="where to write the image")
    p.add_argument("--method", choices=("auto", "zpass", "zfail"), default="auto",
                   help="how volumes are counted: zpass (from the near plane to the surface; "
                        "wrong when the near plane cuts a volume, e.g. the camera stands in a "
                        "shadow), zfail (from the surface to infinity, with caps; always "
                        "right, costs more), auto (z-fail only for casters whose volume the "
                        "near plane may cut; default)")
    p.add_argument("--silhouettes", choices=("cpu", "gpu"), default="cpu",
                   help="where silhouette edges and caps are found: cpu (numpy, per light) "
                        "or gpu (geometry shader over an edge buffer) (default: cpu)")
    p.add_argument("--masks", metavar="NPZ",
                   help="also write the shadow masks: lit (L, H, W) bool per light and "
                        "coverage (H, W) bool")
    p.add_argument("--volumes", metavar="PNG",
                   help="also write the teaching view: the shadow-volume polygons the stencil "
                        "pass drew, over the image (orange sides, green near caps, violet far "
                        "caps)")
    p.add_argument("--stencil", metavar="PNG",
                   help="also write the stencil counts as a heat map, one panel per light, "
                        "with a legend (0: lit, the image darkened; 1, 2, ... yellow to red to "
                        "violet; negative: blue).  Every triangle casts, so a closed object "
                        "counts 2 behind it (its front and its back)")
    p.set_defaults(func=render_command)
    return p


def render_command(args) -> int:
    from .files import encode_srgb, save_masks, save_png
    from .renderer import Renderer
    from .scenefile import load_scene
    from .views import heat_maps

    scene = load_scene(args.scene)
    with Renderer(scene) as renderer:
        result = renderer.render(args.method, args.silhouettes, stencil=bool(args.stencil))
        volumes = renderer.volume_view(args.method, args.silhouettes) if args.volumes else None
    written = [args.output]
    save_png(args.output, result.image)
    if args.masks:
        save_masks(args.masks, result.lit, result.coverage)
        written.append(args.masks)
    if volumes is not None:
        save_png(args.volumes, volumes)
        written.append(args.volumes)
    if args.stencil:
        save_png(args.stencil, heat_maps(result.stencil, encode_srgb(result.image), legend=True))
        written.append(args.stencil)
    print(f"wrote {', '.join(written)}", file=sys.stderr)
    return EXIT_OK


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="shadowvol",
        description="Exact hard shadows with stencil shadow volumes, headless (OpenGL on EGL).")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for module, function in SUBCOMMANDS:
        getattr(importlib.import_module(module), function)(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    from .context import ContextError
    from .glsl import ShaderError
    from .scene import SceneError
    from .stencil import RawGLError

    args = build_parser().parse_args(argv)
    try:
        return args.func(args)
    except (SceneError, ContextError, ShaderError, RawGLError, OSError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_ERROR


if __name__ == "__main__":
    sys.exit(main())
