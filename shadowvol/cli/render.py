"""`shadowvol render`: scenes to images, masks and the teaching views."""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

import numpy as np

from shadowvol import memory
from shadowvol.cli import options, output_paths, status
from shadowvol.errors import InputError, OutOfMemory, RenderError
from shadowvol.frame import GROUND_TRUTH, LAYERS, layer_exrs, save_masks
from shadowvol.io import encode_srgb, save_exr, save_png, save_png16
from shadowvol.pictures import ROLE_COLOURS, captioned, heat_maps
from shadowvol.raster import estimate, methods
from shadowvol.raster.platform.context import create_context
from shadowvol.raster.renderer import Renderer
from shadowvol.scene import AreaLight, SceneError, light_samples
from shadowvol.scenefile import load_scene

EPILOG = """\
Every image is 8-bit sRGB, row 0 at the top; masks follow docs/CONVENTIONS.md.  Scene files are
TOML or JSON (scenes/README.md).  Rendering needs an EGL driver with OpenGL 4.5 (Mesa's
llvmpipe is enough: on Debian/Ubuntu `apt-get install libegl1 libgl1-mesa-dri`).

Several scenes in one call: -o names a directory (made if missing) and each scene writes
OUTDIR/NAME.png, NAME being the scene FILE's name without its extension, reduced to letters,
digits, '.', '_' and '-' (never the `name` inside the scene: a scene cannot choose where its
output goes); --masks, --volumes, --stencil, --exr and --png16 then take no file name and
write OUTDIR/NAME-masks.npz, NAME-volumes.png, NAME-stencil.png, NAME.exr, NAME-16bit.png.
A scene that fails is reported on stderr and the others still render.

""" + status.EPILOG

# output kind -> the suffix of its file when it goes beside the image
EXTRAS = (("masks", "-masks.npz"), ("volumes", "-volumes.png"), ("stencil", "-stencil.png"),
          ("exr", ".exr"), ("png16", "-16bit.png"))
SCENE_SUFFIXES = (".toml", ".json")


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = options.command(
        subparsers, "render", help="render scenes with stencil shadow volumes",
        description="Render SCENE with exact hard shadows counted in the stencil buffer "
                    "(direct Phong lighting: ambient + each light where unshadowed).",
        epilog=EPILOG)
    options.scene(p, options.SCENE_HELP + "; several: -o is a directory", nargs="*")
    options.output(p, "PNG|DIR", "where to write the image (one scene: a .png) or the images "
                                "(several scenes: a directory)")
    p.add_argument("--method", choices=methods.METHODS, default="auto",
                   help="how volumes are counted: zpass (from the near plane to the surface; "
                        "wrong when the near plane cuts a volume, e.g. the camera stands in a "
                        "shadow), zfail (from the surface to infinity, with caps; always "
                        "right, costs more), auto (z-fail only for casters whose volume the "
                        "near plane may cut; default)")
    p.add_argument("--silhouettes", choices=methods.SILHOUETTES, default="cpu",
                   help="where silhouette edges and caps are found: cpu (numpy, per light) "
                        "or gpu (geometry shader over an edge buffer) (default: cpu)")
    p.add_argument("--masks", metavar="NPZ", nargs="?", const=True,
                   help="also write the shadow masks (.npz): lit (L, H, W) bool per light, "
                        "coverage (H, W) bool and the camera matrices K, world_to_camera, "
                        "camera_to_world and the light arrays (with an area light also "
                        "lit_count (L, H, W) and samples (L,)); without a name, beside the "
                        "image")
    p.add_argument("--volumes", metavar="PNG", nargs="?", const=True,
                   help="also write the teaching view: the shadow-volume polygons the stencil "
                        "pass drew, over the image, under a title naming the lights and the "
                        "method, with a legend (orange sides, green near caps, violet far "
                        "caps)")
    p.add_argument("--stencil", metavar="PNG", nargs="?", const=True,
                   help="also write the stencil counts as a heat map, one panel per light "
                        "under its name, with a legend (0: lit, the image darkened; 1, 2, ... yellow to red to "
                        "violet; negative: blue).  Every triangle casts, so a closed object "
                        "counts 2 behind it (its front and its back)")
    options.ground_truth(p, "ground truth to add to the mask file, comma-separated: "
                           f"{', '.join(GROUND_TRUTH)} (or all); and the intrinsic layers "
                           f"{', '.join(LAYERS)}; see docs/CONVENTIONS.md.  "
                           "Implies --masks (beside the image unless named)")
    options.exr(p, "also write the image as linear OpenEXR (32-bit float RGB), and each "
                  "intrinsic layer asked for beside it (X-albedo.exr, X-direct-0.exr, ...); "
                  "without a name, beside the image", nargs="?", const=True)
    p.add_argument("--png16", metavar="PNG", nargs="?", const=True,
                   help="also write the image as a 16-bit sRGB PNG; without a name, beside the "
                        "image (NAME-16bit.png)")
    options.memory_budget(p)
    p.set_defaults(func=command)
    return p


def safe_name(stem: str) -> str:
    """A file name made from a scene file's stem: letters, digits, '.', '_', '-' only, no
    leading dot, at most 100 characters; "scene" if nothing is left."""
    name = re.sub(r"[^A-Za-z0-9._-]+", "_", stem).lstrip(".")[:100]
    return name or "scene"


def _take_back_scenes(args) -> None:
    """`render --masks scene.toml -o x.png`: argparse hands the scene to --masks (its file name
    is optional).  A mask file can never end in .toml/.json, so such a value is the scene."""
    for key, _ in EXTRAS:
        value = getattr(args, key)
        if isinstance(value, str) and Path(value).suffix.lower() in SCENE_SUFFIXES:
            args.scene.insert(0, value)
            setattr(args, key, True)
    if not args.scene:
        raise InputError("SCENE", "no scene file given")


def plan(args) -> list[dict[str, Path]]:
    """Per scene, where each output goes: {"image": Path, "masks": Path, ...}.  Raises
    InputError (exit 2) for arguments that do not fit the number of scenes."""
    _take_back_scenes(args)
    args.truth = options.outputs_named(getattr(args, "outputs", None))
    if args.truth and not args.masks:
        args.masks = True
    flags = {"image": "-o", **{key: f"--{key}" for key, _ in EXTRAS}}
    if len(args.scene) == 1:
        out = {"image": Path(args.output)}
        for key, suffix in EXTRAS:
            value = getattr(args, key)
            if value is True:  # no file name: beside the image
                value = out["image"].with_name(out["image"].stem + suffix)
            if value:
                out[key] = Path(value)
        output_paths.check(out, flags)
        return [out]
    directory = Path(args.output)
    if directory.suffix.lower() in (".png", ".npz") or directory.is_file():
        raise InputError("-o", f"with {len(args.scene)} scenes, -o must name a directory, "
                               f"got {args.output!r}")
    for key, _ in EXTRAS:
        if getattr(args, key) not in (None, True):
            raise InputError(f"--{key}", f"with several scenes, --{key} takes no file name "
                                         f"(each scene writes OUTDIR/NAME{dict(EXTRAS)[key]})")
    plans, taken = [], set()
    for scene in args.scene:
        name = safe_name(Path(scene).stem)
        unique, k = name, 2
        while unique in taken:
            unique, k = f"{name}-{k}", k + 1
        taken.add(unique)
        out = {"image": directory / f"{unique}.png"}
        for key, suffix in EXTRAS:
            if getattr(args, key):
                out[key] = directory / f"{unique}{suffix}"
        for path in out.values():  # belt and braces: nothing may land outside `directory`
            if path.resolve().parent != directory.resolve():
                raise InputError("-o", f"refusing to write {path} outside {directory}")
        plans.append(out)
    return plans


def command(args) -> int:
    try:
        plans = plan(args)
    except (InputError, SceneError) as exc:
        return status.report(exc)
    code, ctx = status.OK, None
    try:
        for scene_path, out in zip(args.scene, plans):
            one, ctx = _render_one(args, scene_path, out, ctx, prefix=len(args.scene) > 1)
            code = max(code, one)
    finally:
        if ctx is not None:
            ctx.release()
    return code


def _check_gl(ctx) -> None:
    """A GL allocation that failed sets GL_OUT_OF_MEMORY and carries on (moderngl raises
    nothing): such a frame is not written."""
    error = ctx.error
    if error == "GL_OUT_OF_MEMORY":
        raise OutOfMemory("rendering", "the GL reported GL_OUT_OF_MEMORY")
    if error != "GL_NO_ERROR":
        raise RenderError(f"the GL reported {error} while rendering")


def light_names(scene) -> list[str]:
    """"light 0 (point)", "light 1 (directional)", ...: the lights as the pictures name them."""
    return [f"light {i} ({type(lt).__name__.removesuffix('Light').lower()})"
            for i, lt in enumerate(scene.lights)]


def stencil_picture(stencil, image, scene):
    """--stencil's picture: a heat map per light ((L, H, W) counts over the (H, W, 3) uint8
    image), each under its light's name, the counts' legend below."""
    titles = [f"{name}: stencil count" for name in light_names(scene)] or ["no lights"]
    return heat_maps(stencil, image, with_legend=True, titles=titles)


def volumes_picture(image, scene, method: str):
    """--volumes' picture: the shadow-volume polygons over the (H, W, 3) uint8 image, under a
    title naming the lights and the method, the roles' colours below."""
    names = ", ".join(light_names(scene)) or "no lights"
    caps = "" if method == "zpass" else " (z-fail)"
    entries = [(label, encode_srgb(np.array([[ROLE_COLOURS[role]]], np.float64))[0, 0])
               for label, role in (("side quads", "side"), (f"near caps{caps}", "near cap"),
                                   (f"far caps{caps}", "far cap"))]
    return captioned([(f"shadow volumes ({method}) of {names}", image)], entries)


def _stencil_lights(scene, scene_path: str) -> None:
    """The heat map shows one light's stencil counts: hard lights only."""
    for i, light in enumerate(scene.lights):
        if isinstance(light, AreaLight):
            raise SceneError(f"lights[{i}]", "--stencil draws a hard light's stencil counts; "
                             "this is an area light (its per-sample counts are lit_count, in "
                             "--masks)", scene_path)


def _render_one(args, scene_path: str, out: dict, ctx, prefix: bool):
    """Load, render and write one scene; returns (exit status, the GL context to reuse).
    Errors are reported here, one line each, naming the scene when there are several."""
    try:
        scene = load_scene(scene_path)
        if ctx is None:
            ctx = create_context()
        if "stencil" in out:
            _stencil_lights(scene, scene_path)
        written = tuple(k for k in ("png", "masks", "exr", "png16", "stencil", "volumes")
                        if k in out or k == "png")
        memory.check(estimate.render(scene, ("image", "lit", "coverage") + args.truth,
                                     gl_in_host=memory.gl_in_host(ctx.info["GL_RENDERER"]),
                                     written=written, stencil="stencil" in out,
                                     volumes="volumes" in out),
                     args.memory_budget, scene_path)
        with Renderer(scene, ctx) as renderer:
            result = renderer.render(args.method, args.silhouettes,
                                     stencil="stencil" in out,
                                     outputs=("image", "lit", "coverage") + args.truth)
            volumes = (renderer.volume_view(args.method, args.silhouettes)
                       if "volumes" in out else None)
            _check_gl(ctx)
        save_png(out["image"], result.image)
        if "masks" in out:
            save_masks(out["masks"], result.lit, result.coverage,
                       light_samples=[light_samples(lt) for lt in scene.lights],
                       arrays=result.arrays())
        if "exr" in out:
            save_exr(out["exr"], result.image)
            for path, layer in layer_exrs(out["exr"], result).items():
                save_exr(path, layer)
        if "png16" in out:
            save_png16(out["png16"], result.image)
        if volumes is not None:
            save_png(out["volumes"], volumes_picture(encode_srgb(volumes), scene, args.method))
        if "stencil" in out:
            save_png(out["stencil"], stencil_picture(result.stencil, encode_srgb(result.image),
                                                     scene))
    except KeyboardInterrupt:
        raise
    except Exception as exc:  # noqa: BLE001 - report() re-raises what has no status
        if isinstance(exc, SceneError) and exc.file is None:  # the Renderer's (`image`)
            exc = exc.in_file(scene_path)
        where = f"{scene_path}: " if prefix and not str(exc).startswith(scene_path) else ""
        return status.report(exc, where), ctx
    print(f"wrote {', '.join(str(p) for p in out.values())}", file=sys.stderr)
    return status.OK, ctx
