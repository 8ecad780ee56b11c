"""The `raytrace` commands of the rendering equation's outlook: path tracing and radiosity.

    raytrace render scenes/cornell.toml --integrator path --spp 64 -o cornell.png [--exr c.exr]
    raytrace radiosity scenes/cornell.toml --level 4 -o cornell-radiosity.png [--flat F.png]

`shadowvol.cli.raytrace` registers them (`add_options`, `add_parsers`) and hands over
(`path_traced`, `radiosity_command`); exit statuses are `shadowvol.cli.status`'s.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from raytrace import pathtrace, radiosity
from raytrace.backends import BACKENDS
from shadowvol import memory
from shadowvol.cli import args as blocks
from shadowvol.cli import outputs, status
from shadowvol.io import save_exr, save_png
from shadowvol.scene import SceneError
from shadowvol.scenefile import load_scene


PATH_SPP = 16  # the path tracer's paths per pixel when --spp is not given


def add_options(render: argparse.ArgumentParser) -> None:
    """The path tracer's options on `raytrace render`."""
    render.add_argument("--integrator", choices=("whitted", "path"), default="whitted",
                        help="'whitted' (default) or 'path': unidirectional path tracing with "
                             "next-event estimation of emissive surfaces (material.emission)")
    render.add_argument("--spp", type=int, default=None, metavar="N",
                        help="samples per pixel: path tracing's paths (default 16); Whitted's "
                             "stratified jittered samples, see --filter (default 1: the pixel "
                             "centre, no jitter)")
    blocks.seed(render, "random seed of the path tracer and of Whitted's distributed samples "
                        "(--spp, roughness, aperture); the same seed gives the same image "
                        "(default 0)")
    blocks.exr(render, "also write the linear image as OpenEXR")


def add_parsers(sub) -> None:
    """The `radiosity` subcommand."""
    r = blocks.command(sub, "radiosity", help="radiosity of the diffuse scene (patches, "
                                              "ray-cast form factors, progressive refinement)",
                       description="Mesh SCENE into patches, compute form factors by casting "
                                   "rays through Embree, solve by progressive refinement and "
                                   "show the solution from the camera.  Prints the number of "
                                   "patches, iterations and time.")
    blocks.scene(r)
    blocks.output(r, "PNG", "the interpolated (Gouraud) display, sRGB PNG")
    r.add_argument("--flat", metavar="PNG", default=None,
                   help="also write the flat display (one colour per patch)")
    blocks.exr(r, "also write the interpolated display as linear OpenEXR")
    r.add_argument("--level", type=int, default=3, metavar="L",
                   help="subdivision level: patches no longer than the longest triangle edge "
                        "/ 2^L (default 3)")
    r.add_argument("--rays", type=int, default=256, metavar="K",
                   help="form-factor rays per patch (default 256)")
    r.add_argument("--tol", type=float, default=1e-4, metavar="T",
                   help="stop when the unshot power is at most T times the emitted (default "
                        "1e-4)")
    r.add_argument("--shots", type=int, default=1, metavar="N",
                   help="patches shot per iteration (default 1: Cohen et al.'s one at a time)")
    blocks.seed(r, "random seed (default 0)")
    blocks.backend(r, BACKENDS, "triangle intersection (default: embree)")
    blocks.memory_budget(r)


def path_traced(args) -> int:
    """`raytrace render --integrator path`."""
    paths = {"image": Path(args.output)}
    if args.exr:
        paths["exr"] = Path(args.exr)
    outputs.check(paths, {"image": "-o", "exr": "--exr"})
    spp = PATH_SPP if args.spp is None else args.spp
    if spp < 1:
        raise SceneError("--spp", f"must be >= 1, got {spp}")
    depth = args.max_depth
    if depth is not None and depth < 1:
        raise SceneError("--max-depth", f"must be >= 1 for path tracing, got {depth}")
    scene = load_scene(args.scene)
    memory.check(memory.path_traced(scene, spp, tuple(paths.keys() - {"image"}) + ("png",)),
                 args.memory_budget, args.scene)
    kwargs = {} if depth is None else {"max_depth": depth}
    result = pathtrace.render(scene, spp=spp, seed=args.seed, backend=args.backend,
                              progress=False if args.no_progress else None, **kwargs)
    save_png(args.output, result.image)
    if args.exr:
        save_exr(args.exr, result.image)
    print(f"{spp} spp, {result.rays / 1e6:.1f} M rays in {result.seconds:.1f} s "
          f"({result.rays / result.seconds / 1e6:.2f} Mrays/s); wrote "
          f"{', '.join(str(p) for p in paths.values())}", file=sys.stderr)
    return status.OK


def radiosity_command(args) -> int:
    """`raytrace radiosity`."""
    paths = {"image": Path(args.output)}
    if args.flat:
        paths["flat"] = Path(args.flat)
    if args.exr:
        paths["exr"] = Path(args.exr)
    outputs.check(paths, {"image": "-o", "flat": "--flat", "exr": "--exr"})
    for flag, value, ok, rule in (("--level", args.level, args.level >= 0, ">= 0"),
                                  ("--rays", args.rays, args.rays >= 1, ">= 1"),
                                  ("--tol", args.tol, args.tol > 0.0, "> 0"),
                                  ("--shots", args.shots, args.shots >= 1, ">= 1")):
        if not ok:
            raise SceneError(flag, f"must be {rule}, got {value}")
    scene = load_scene(args.scene)
    memory.check(memory.radiosity_display(scene, ("exr",) if args.exr else ("png",),
                                          flat=bool(args.flat)),
                 args.memory_budget, args.scene)
    try:
        solution = radiosity.solve(scene, level=args.level, rays_per_patch=args.rays,
                                   tol=args.tol, shots=args.shots, seed=args.seed,
                                   backend=args.backend)
    except ValueError as exc:  # e.g. a level that would split a triangle absurdly
        raise SceneError("--level", str(exc)) from None
    print(radiosity.summary(solution), file=sys.stderr)
    smooth = radiosity.display(scene, solution, interpolate=True, backend=args.backend)
    save_png(args.output, smooth)
    if args.flat:
        save_png(args.flat, radiosity.display(scene, solution, interpolate=False,
                                              backend=args.backend))
    if args.exr:
        save_exr(args.exr, smooth)
    print(f"wrote {', '.join(str(p) for p in paths.values())}", file=sys.stderr)
    return status.OK
