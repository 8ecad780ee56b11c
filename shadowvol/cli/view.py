"""`shadowvol view`: the interactive window (needs a display; see shadowvol.view.app)."""

from __future__ import annotations

import argparse
import os

from shadowvol.cli import options, status
from shadowvol.errors import InputError
from shadowvol.scenefile import load_scene

KEYS = """\
mouse: left drag orbit, shift+left or middle drag pan, wheel zoom, right drag moves the light,
left click probes the pixel (every shadow-volume face its eye ray crosses, with +1/-1, the
z-pass and z-fail sums, the stencil read back and the ray-traced shadow ray).
keys: A auto, Z z-pass, F z-fail; N shaded, V volumes by role, S silhouettes, C stencil counts,
P planar shadows, T ray traced, E sampled | exact area light; L next light, [ and ] shrink and grow an area light,
, and . halve and double its samples (shown with at most 16 at first), M light marker,
H help, Esc quit.

"""


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = options.command(
        subparsers, "view", help="open an interactive window on a scene (orbit, drag the light, probe)",
        description="Open SCENE in a window: the shadow-volume frame, live, with the counting "
                    "method, the shadow polygons by role, the silhouette edges, the stencil "
                    "counts, planar shadows and the ray-traced image on keys, and the count "
                    "probe on a click.  Needs an X display (Xvfb works) and pyglet "
                    "(pip install 'shadowvol[view]').",
        epilog=KEYS + status.EPILOG)
    options.scene(p)
    p.add_argument("--size", metavar="WxH", default=None,
                   help="the frame's size in pixels (default: the scene's)")
    p.set_defaults(func=command)
    return p


def command(args) -> int:
    scene = load_scene(args.scene)
    if args.size:
        from shadowvol.course.gallery import parse_size
        w, h = parse_size(args.size)
        scene = scene.replace(width=w, height=h)
    if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
        raise InputError("view", "no display (DISPLAY is not set): shadowvol view opens a "
                                 "window; run it on a desktop, over ssh -X, or under Xvfb")
    from shadowvol.view.app import Viewer

    viewer = Viewer(scene)
    try:
        viewer.run()
    finally:
        viewer.close()
    return status.OK
