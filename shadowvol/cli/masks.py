"""`shadowvol masks`: a scene's exact shadow masks alone, by the faster of the two renderers on
this machine (`shadowvol.compare.fastest`), or by the one named with --renderer."""

from __future__ import annotations

import sys
from pathlib import Path

from shadowvol import memory
from shadowvol.cli import options, output_paths, status
from shadowvol.compare import fastest
from shadowvol.frame import save_masks
from shadowvol.io import save_png
from shadowvol.pictures import masks_image
from shadowvol.scene import SceneError, light_samples
from shadowvol.scenefile import load_scene

EPILOG = """\
Both renderers give the float64 answer at every pixel except the ties of docs/CONVENTIONS.md
("Which renderer makes the masks"); with --renderer auto (the default) which one runs depends
on the scene and the machine, so a tie pixel may differ between machines.  Name the renderer
for the same bytes everywhere.  The log line says which renderer made the masks, and why.

""" + status.EPILOG


def add_parser(subparsers) -> None:
    p = options.command(
        subparsers, "masks", help="exact shadow masks alone, by the faster renderer here",
        description="Write the exact shadow masks of SCENE (.npz: lit (L, H, W) and coverage "
                    "(H, W), the camera matrices and the light arrays; with an area light "
                    "also lit_count and samples) by the rasterizer's mask-only frame or the "
                    "ray tracer, whichever a cost model says is faster on this machine.",
        epilog=EPILOG)
    options.scene(p)
    options.output(p, "NPZ", "where to write the masks (.npz)")
    p.add_argument("--renderer", choices=fastest.RENDERERS, default="auto",
                   help="which renderer makes the masks: shadowvol (the rasterizer's mask-only "
                        "frame), raytrace (the ray tracer, Embree), or auto (the one the cost "
                        "model of shadowvol.compare.fastest says is faster for this scene on "
                        "this machine; default)")
    p.add_argument("--png", metavar="PNG", default=None,
                   help="also write a picture of the masks, one panel per light (white lit, "
                        "grey shadowed, black empty)")
    options.memory_budget(p)
    p.set_defaults(func=command)


def _context(asked: str):
    """The GL context the choice and the rasterizer need (None where the ray tracer was
    named, or, under auto, where none can be made: then the ray tracer runs)."""
    if asked == "raytrace":
        return None
    from shadowvol.raster.platform.context import ContextError, create_context

    if asked == "shadowvol":
        return create_context()
    try:
        return create_context()
    except ContextError:   # no EGL driver or no OpenGL 4.5 here: auto takes the ray tracer
        return None


def _estimate(scene, renderer: str, ctx, picture: bool) -> memory.Estimate:
    if renderer == "shadowvol":
        from shadowvol.raster import estimate

        return estimate.render(scene, ("lit", "coverage"), written=("masks",),
                               gl_in_host=memory.gl_in_host(ctx.info["GL_RENDERER"]))
    import raytrace.estimate

    return raytrace.estimate.masks(scene, (), picture=picture)


def command(args) -> int:
    paths = {"masks": Path(args.output)}
    if args.png:
        paths["picture"] = Path(args.png)
    output_paths.check(paths, {"masks": "-o", "picture": "--png"})
    scene = load_scene(args.scene)
    ctx = _context(args.renderer)
    try:
        choice = fastest.choose_for(scene, args.renderer,
                                    None if ctx is None else ctx.info["GL_RENDERER"])
        if choice.renderer != "shadowvol" and ctx is not None:
            ctx.release()
            ctx = None
        memory.check(_estimate(scene, choice.renderer, ctx, "picture" in paths),
                     args.memory_budget, args.scene)
        lit, coverage, arrays = fastest.masks(scene, choice.renderer, ctx)
    except SceneError as exc:   # a renderer's (e.g. `image`): named with the scene file
        raise (exc.in_file(args.scene) if exc.file is None else exc) from None
    finally:
        if ctx is not None:
            ctx.release()
    save_masks(paths["masks"], lit, coverage,
               light_samples=[light_samples(lt) for lt in scene.lights], arrays=arrays)
    if "picture" in paths:
        save_png(paths["picture"], masks_image(lit, coverage))
    print(f"wrote {', '.join(str(p) for p in paths.values())} {choice.describe()}",
          file=sys.stderr)
    return status.OK
