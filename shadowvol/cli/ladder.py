"""The ladder picture of the rendering equation's outlook (`shadowvol.course.ladder`):

    python -m shadowvol.cli.ladder scenes/cornell.toml -o docs/ladder.png
"""

from __future__ import annotations

import sys

import numpy as np

from shadowvol.cli import args as blocks
from shadowvol.cli import status
from shadowvol.course.ladder import picture, rungs
from shadowvol.io import save_png
from shadowvol.scene import SceneError
from shadowvol.scenefile import load_scene


def main(argv: list[str] | None = None) -> int:
    ap = blocks.Parser(prog="python -m shadowvol.cli.ladder",
                                 description="Render the ladder picture (local -> Whitted -> "
                                             "direct -> path traced -> radiosity).")
    ap.add_argument("scene", help="a scene with emissive surfaces, e.g. scenes/cornell.toml")
    ap.add_argument("-o", "--output", required=True, help="PNG to write")
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--level", type=int, default=4)
    ap.add_argument("--rays", type=int, default=1024)
    ap.add_argument("--size", type=int, default=None, help="square image size (default: the "
                                                           "scene's)")
    args = ap.parse_args(argv)
    try:
        scene = load_scene(args.scene)
    except SceneError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return status.BAD_INPUT
    if args.size:
        scene = scene.replace(width=args.size, height=args.size)
    images, info = rungs(scene, spp=args.spp, level=args.level, rays=args.rays)
    save_png(args.output, picture(images, np.array(info["white_balance"]), scene.name))
    for key, value in info.items():
        print(f"{key}: {value:.2f}" if isinstance(value, float) else f"{key}: {value}",
              file=sys.stderr)
    print(f"wrote {args.output}", file=sys.stderr)
    return status.OK


if __name__ == "__main__":
    sys.exit(main())
