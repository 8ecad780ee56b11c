"""The `shadowvol` command.

    shadowvol render SCENE -o out.png [--method zpass|zfail|auto] [--silhouettes cpu|gpu]
                                      [--masks out.npz] [--volumes out.png] [--stencil out.png]
    shadowvol render A.toml B.json ... -o outdir/ [--masks] [--volumes] [--stencil]

Each subcommand lives in its own module and registers itself: SUBCOMMANDS lists
(module, function) pairs; the function gets argparse's subparsers object, adds its parser and
sets `func` to a callable taking the parsed arguments and returning the exit status.  Adding a
command = writing such a function and listing it here.

Exit status (EXIT_STATUS_HELP, shown by --help and in docs/robustness.md): 0 success; 1 a
comparison over its budget (`compare --max-interior`); 2 bad input (a scene file, a mesh, an
argument, a scene beyond the documented limits); 3 rendering failed (no usable EGL/GL 4.5, a
GL error, out of memory, a stencil overflow).  Errors are printed as `error: <message>` on
stderr, without a traceback.  Outputs are written atomically (shadowvol.files): an error or
Ctrl-C never leaves half a file behind.  With several scenes, each one that fails is reported
and the others still render; the status is the highest of theirs.
"""

from __future__ import annotations

import argparse
import importlib
import re
import sys
from pathlib import Path

EXIT_OK = 0
EXIT_OVER_BUDGET = 1
EXIT_BAD_INPUT = 2
EXIT_RENDER_FAILED = 3

EXIT_STATUS_HELP = """\
exit status: 0 success; 1 a comparison over its budget (compare --max-interior); 2 bad input
(scene file, mesh, arguments, a scene beyond the documented limits); 3 rendering failed (no
usable EGL/OpenGL 4.5, a GL error, out of memory, a stencil overflow).  With several scenes,
the highest status of any of them."""

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

Several scenes in one call: -o names a directory (made if missing) and each scene writes
OUTDIR/NAME.png, NAME being the scene FILE's name without its extension, reduced to letters,
digits, '.', '_' and '-' (never the `name` inside the scene: a scene cannot choose where its
output goes); --masks, --volumes and --stencil then take no file name and write
OUTDIR/NAME-masks.npz, NAME-volumes.png, NAME-stencil.png.  A scene that fails is reported on
stderr and the others still render.

""" + EXIT_STATUS_HELP


class RenderFailed(RuntimeError):
    """Rendering failed for a reason other than the input (GL, memory): exit status 3."""


def add_render_parser(subparsers) -> argparse.ArgumentParser:
    p = subparsers.add_parser(
        "render", help="render scenes with stencil shadow volumes",
        description="Render SCENE with exact hard shadows counted in the stencil buffer "
                    "(direct Phong lighting: ambient + each light where unshadowed).",
        epilog=RENDER_EPILOG, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("scene", metavar="SCENE", nargs="+",
                   help="scene file (.toml or .json); several: -o is a directory")
    p.add_argument("-o", "--output", required=True, metavar="PNG|DIR",
                   help="where to write the image (one scene) or the images (several scenes: "
                        "a directory)")
    p.add_argument("--method", choices=("auto", "zpass", "zfail"), default="auto",
                   help="how volumes are counted: zpass (from the near plane to the surface; "
                        "wrong when the near plane cuts a volume, e.g. the camera stands in a "
                        "shadow), zfail (from the surface to infinity, with caps; always "
                        "right, costs more), auto (z-fail only for casters whose volume the "
                        "near plane may cut; default)")
    p.add_argument("--silhouettes", choices=("cpu", "gpu"), default="cpu",
                   help="where silhouette edges and caps are found: cpu (numpy, per light) "
                        "or gpu (geometry shader over an edge buffer) (default: cpu)")
    p.add_argument("--masks", metavar="NPZ", nargs="?", const=True,
                   help="also write the shadow masks: lit (L, H, W) bool per light and "
                        "coverage (H, W) bool (several scenes: no file name, see below)")
    p.add_argument("--volumes", metavar="PNG", nargs="?", const=True,
                   help="also write the teaching view: the shadow-volume polygons the stencil "
                        "pass drew, over the image (orange sides, green near caps, violet far "
                        "caps)")
    p.add_argument("--stencil", metavar="PNG", nargs="?", const=True,
                   help="also write the stencil counts as a heat map, one panel per light, "
                        "with a legend (0: lit, the image darkened; 1, 2, ... yellow to red to "
                        "violet; negative: blue).  Every triangle casts, so a closed object "
                        "counts 2 behind it (its front and its back)")
    p.set_defaults(func=render_command)
    return p


EXTRAS = (("masks", "-masks.npz"), ("volumes", "-volumes.png"), ("stencil", "-stencil.png"))


def safe_name(stem: str) -> str:
    """A file name made from a scene file's stem: letters, digits, '.', '_', '-' only, no
    leading dot, at most 100 characters; "scene" if nothing is left."""
    name = re.sub(r"[^A-Za-z0-9._-]+", "_", stem).lstrip(".")[:100]
    return name or "scene"


def _outputs(args) -> list[dict[str, Path]]:
    """Per scene, where each output goes: {"image": Path, "masks": Path, ...}.  Raises
    SceneError-like ValueError (exit 2) for arguments that do not fit the number of scenes."""
    from .scene import SceneError

    if len(args.scene) == 1:
        out = {"image": Path(args.output)}
        for key, suffix in EXTRAS:
            value = getattr(args, key)
            if value is True:  # no file name: beside the image
                value = out["image"].with_name(out["image"].stem + suffix)
            if value:
                out[key] = Path(value)
        return [out]
    directory = Path(args.output)
    if directory.suffix.lower() in (".png", ".npz") or directory.is_file():
        raise SceneError("-o", f"with {len(args.scene)} scenes, -o must name a directory, "
                               f"got {args.output!r}")
    for key, _ in EXTRAS:
        if getattr(args, key) not in (None, True):
            raise SceneError(f"--{key}", f"with several scenes, --{key} takes no file name "
                                         f"(each scene writes OUTDIR/NAME{dict(EXTRAS)[key]})")
    outs, taken = [], set()
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
                raise SceneError("-o", f"refusing to write {path} outside {directory}")
        outs.append(out)
    return outs


def render_command(args) -> int:
    from .scene import SceneError

    try:
        outputs = _outputs(args)
    except SceneError as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    status, ctx = EXIT_OK, None
    try:
        for scene_path, out in zip(args.scene, outputs):
            code, ctx = _render_one(args, scene_path, out, ctx, prefix=len(args.scene) > 1)
            status = max(status, code)
    finally:
        if ctx is not None:
            ctx.release()
    return status


def _render_one(args, scene_path: str, out: dict, ctx, prefix: bool):
    """Load, render and write one scene; returns (exit status, the GL context to reuse).
    Errors are reported here, one line each, naming the scene when there are several."""
    import moderngl

    from .context import ContextError, create_context
    from .files import encode_srgb, save_masks, save_png
    from .glsl import ShaderError
    from .overflow import StencilOverflowError
    from .renderer import Renderer
    from .scene import SceneError, light_samples
    from .scenefile import load_scene
    from .stencil import RawGLError
    from .views import heat_maps

    def where(exc) -> str:  # name the scene, unless the message already starts with it
        return f"{scene_path}: " if prefix and not str(exc).startswith(scene_path) else ""

    try:
        scene = load_scene(scene_path)
        if ctx is None:
            ctx = create_context()
        limit = min(ctx.info["GL_MAX_RENDERBUFFER_SIZE"], ctx.info["GL_MAX_TEXTURE_SIZE"])
        if max(scene.width, scene.height) > limit:
            raise SceneError("image", f"{scene.width}x{scene.height} is larger than this GL "
                                      f"allows ({limit} pixels per side)", scene_path)
        with Renderer(scene, ctx) as renderer:
            result = renderer.render(args.method, args.silhouettes,
                                     stencil="stencil" in out)
            volumes = (renderer.volume_view(args.method, args.silhouettes)
                       if "volumes" in out else None)
        save_png(out["image"], result.image)
        if "masks" in out:
            save_masks(out["masks"], result.lit, result.coverage,
                       light_samples=[light_samples(lt) for lt in scene.lights])
        if volumes is not None:
            save_png(out["volumes"], volumes)
        if "stencil" in out:
            save_png(out["stencil"],
                     heat_maps(result.stencil, encode_srgb(result.image), legend=True))
    except (SceneError, OSError) as exc:
        print(f"error: {where(exc)}{exc}", file=sys.stderr)
        return EXIT_BAD_INPUT, ctx
    except MemoryError as exc:
        print(f"error: {where(exc)}out of memory while rendering"
              f"{': ' + str(exc) if str(exc) else ''}; try a smaller image or fewer triangles",
              file=sys.stderr)
        return EXIT_RENDER_FAILED, ctx
    except (ContextError, ShaderError, RawGLError, RenderFailed, StencilOverflowError,
            moderngl.Error) as exc:
        print(f"error: {where(exc)}{exc}", file=sys.stderr)
        return EXIT_RENDER_FAILED, ctx
    print(f"wrote {', '.join(str(p) for p in out.values())}", file=sys.stderr)
    return EXIT_OK, ctx


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="shadowvol",
        description="Exact hard shadows with stencil shadow volumes, headless (OpenGL on EGL).",
        epilog=EXIT_STATUS_HELP, formatter_class=argparse.RawDescriptionHelpFormatter)
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
    except (SceneError, OSError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_BAD_INPUT
    except (ContextError, ShaderError, RawGLError, RenderFailed) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return EXIT_RENDER_FAILED
    except MemoryError:
        print("error: out of memory; try a smaller image or fewer triangles", file=sys.stderr)
        return EXIT_RENDER_FAILED


if __name__ == "__main__":
    sys.exit(main())
