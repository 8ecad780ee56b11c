"""The ladder slide of the rendering equation's outlook (`shadowvol.course.ladder`), the same
slide `shadowvol demo` puts in the gallery:

    python -m shadowvol.cli.ladder scenes/cornell.toml -o docs/ladder.png
"""

from __future__ import annotations

import dataclasses
import sys

from shadowvol.cli import options, status
from shadowvol.course.gallery import parse_size
from shadowvol.course.ladder import FULL, SMALL, ladder_slide
from shadowvol.course.slides import SLIDE, SMALL_SLIDE, Layout
from shadowvol.errors import InputError, MissingExtra
from shadowvol.io import save_png
from shadowvol.scene import SceneError
from shadowvol.scenefile import load_scene


def main(argv: list[str] | None = None) -> int:
    ap = options.Parser(prog="python -m shadowvol.cli.ladder",
                       description="Render the ladder slide (local -> Whitted -> direct -> "
                                   "path traced -> photon map -> radiosity), as the gallery "
                                   "of `shadowvol demo` has it.")
    ap.add_argument("scene", help="a scene with emissive surfaces, e.g. scenes/cornell.toml")
    ap.add_argument("-o", "--output", required=True, help="PNG to write")
    ap.add_argument("--size", metavar="WxH", default=None,
                    help=f"slide size in pixels (default {SLIDE[0]}x{SLIDE[1]})")
    ap.add_argument("--small", action="store_true",
                    help=f"{SMALL_SLIDE[0]}x{SMALL_SLIDE[1]} and the gallery's --small "
                         "settings (fast)")
    ap.add_argument("--spp", type=int, default=None,
                    help=f"paths per pixel (default {FULL.spp}; --small {SMALL.spp})")
    ap.add_argument("--level", type=int, default=None, help="radiosity's subdivision level")
    ap.add_argument("--rays", type=int, default=None, help="form-factor rays per patch")
    ap.add_argument("--photons", type=int, default=None, help="photons of the photon map")
    args = ap.parse_args(argv)
    try:
        if args.size and args.small:
            raise InputError("--size", "give --size or --small, not both")
        size = parse_size(args.size) if args.size else (SMALL_SLIDE if args.small else SLIDE)
        scene = load_scene(args.scene)
        settings = SMALL if args.small else FULL
        changes = {k: getattr(args, k) for k in ("spp", "level", "rays", "photons")
                   if getattr(args, k) is not None}
        for key, value in changes.items():
            if value < 1:
                raise InputError(f"--{key}", f"must be a whole number >= 1, got {value}")
        settings = dataclasses.replace(settings, **changes)
        image, info = ladder_slide(scene, Layout(*size), settings)
    except (InputError, SceneError, MissingExtra) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return status.BAD_INPUT
    save_png(args.output, image)
    for key, value in info.items():
        print(f"{key}: {value:.2f}" if isinstance(value, float) else f"{key}: {value}",
              file=sys.stderr)
    print(f"wrote {args.output}", file=sys.stderr)
    return status.OK


if __name__ == "__main__":
    sys.exit(main())
