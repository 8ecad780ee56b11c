"""`raytrace radiosity`: radiosity of the diffuse scene (patches, ray-cast form factors,
progressive refinement), shown from the camera.

    raytrace radiosity scenes/cornell.toml -o cornell-radiosity.png [--flat F.png] [--level 4]
"""

from __future__ import annotations

import sys
from pathlib import Path

from raytrace.backends import BACKENDS
from raytrace.outlook import estimate, radiosity
from shadowvol import memory
from shadowvol.cli import options, output_paths, status
from shadowvol.errors import InputError
from shadowvol.io import save_exr, save_png
from shadowvol.scene import SceneError
from shadowvol.scenefile import load_scene


def add_parser(sub) -> None:
    r = options.command(sub, "radiosity", help="radiosity of the diffuse scene (patches, "
                                              "ray-cast form factors, progressive refinement)",
                       description="Mesh SCENE into patches, compute form factors by casting "
                                   "rays through Embree, solve by progressive refinement and "
                                   "show the solution from the camera.  Prints the number of "
                                   "patches, iterations and time.")
    options.scene(r)
    options.output(r, "PNG", "the interpolated (Gouraud) display, sRGB PNG")
    r.add_argument("--flat", metavar="PNG", default=None,
                   help="also write the flat display (one colour per patch)")
    options.exr(r, "also write the interpolated display as linear OpenEXR")
    r.add_argument("--level", type=int, default=radiosity.DEFAULT_LEVEL, metavar="L",
                   help="subdivision level: patches no longer than the longest triangle edge "
                        f"/ 2^L (default {radiosity.DEFAULT_LEVEL})")
    r.add_argument("--rays", type=int, default=radiosity.DEFAULT_RAYS_PER_PATCH, metavar="K",
                   help="form-factor rays per patch (default "
                        f"{radiosity.DEFAULT_RAYS_PER_PATCH}: each wall of the Cornell box "
                        "within 2 %% of the path tracer)")
    r.add_argument("--tol", type=float, default=radiosity.DEFAULT_TOL, metavar="T",
                   help="stop when the unshot power is at most T times the emitted (default "
                        f"{radiosity.DEFAULT_TOL:g})")
    r.add_argument("--shots", type=int, default=1, metavar="N",
                   help="patches shot per iteration (default 1: Cohen et al.'s one at a time)")
    options.seed(r, "random seed (default 0)")
    options.backend(r, BACKENDS, "triangle intersection (default: embree)")
    options.memory_budget(r)
    r.set_defaults(func=command)


def command(args) -> int:
    paths = {"image": Path(args.output)}
    if args.flat:
        paths["flat"] = Path(args.flat)
    if args.exr:
        paths["exr"] = Path(args.exr)
    output_paths.check(paths, {"image": "-o", "flat": "--flat", "exr": "--exr"}, "raytrace")
    for flag, value, ok, rule in (("--level", args.level, args.level >= 0, ">= 0"),
                                  ("--rays", args.rays, args.rays >= 1, ">= 1"),
                                  ("--rays", args.rays, args.rays < 1 << 31, "< 2^31 a patch"),
                                  ("--tol", args.tol, args.tol > 0.0, "> 0"),
                                  ("--shots", args.shots, args.shots >= 1, ">= 1"),
                                  ("--seed", args.seed, args.seed >= 0, ">= 0")):
        if not ok:
            raise InputError(flag, f"must be {rule}, got {value}")
    scene = load_scene(args.scene)
    memory.check(estimate.radiosity_display(scene, ("exr",) if args.exr else ("png",),
                                            flat=bool(args.flat)),
                 args.memory_budget, args.scene)
    try:  # only the meshing depends on --level alone
        mesh = radiosity.mesh_patches(scene, args.level)
    except ValueError as exc:  # e.g. a level that would split a triangle absurdly
        raise SceneError("--level", str(exc), args.scene) from None
    solution = radiosity.solve(scene, level=args.level, rays_per_patch=args.rays, tol=args.tol,
                               shots=args.shots, seed=args.seed, backend=args.backend,
                               mesh=mesh)
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
