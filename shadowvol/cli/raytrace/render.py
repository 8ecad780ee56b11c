"""`raytrace render`: an image of a scene file — Whitted (the default), or the outlook's
integrators, `--integrator path` (path tracing) and `--integrator photon` (photon mapping)."""

from __future__ import annotations

import sys
from pathlib import Path

from raytrace.backends import BACKENDS
from raytrace.outlook import estimate, photon
from raytrace.outlook.path import pathtrace
from raytrace.outlook.photonmap import KERNELS
from raytrace.outlook.sampling import FILTERS
from raytrace.outlook.whitted import render
from shadowvol import memory
from shadowvol.cli import options, output_paths, status
from shadowvol.errors import InputError
from shadowvol.io import save_exr, save_png, save_png16
from shadowvol.scene import SceneError
from shadowvol.scenefile import load_scene

PATH_SPP = 16  # the path tracer's paths per pixel when --spp is not given


def add_parser(sub) -> None:
    r = options.command(sub, "render", help="ray-trace an image (Whitted: shadows, reflection, "
                                           "refraction, Phong)",
                       description="Ray-trace SCENE into an 8-bit sRGB PNG.")
    options.scene(r)
    options.output(r, "PNG", "where to write the image (PNG, sRGB, row 0 at the top)")
    r.add_argument("--max-depth", type=int, default=None, metavar="N",
                   help="reflection/refraction generations; 0 = direct lighting only, as the "
                        "rasterizer draws it (default: the scene's render.max_depth)")
    r.add_argument("--png16", metavar="PNG", default=None,
                   help="also write the image as a 16-bit sRGB PNG")
    options.backend(r, BACKENDS)
    options.memory_budget(r)
    r.add_argument("--no-progress", action="store_true",
                   help="no progress bar (it is shown only on a terminal anyway)")
    r.add_argument("--filter", choices=FILTERS, default="box",
                   help="Whitted with --spp N: the pixel filter the samples are drawn from, "
                        "'box' (the pixel's square, default) or 'tent' (radius 1 pixel)")
    r.add_argument("--integrator", choices=("whitted", "path", "photon", "analytic"),
                   default="whitted",
                   help="'whitted' (default) or 'path': unidirectional path tracing with "
                        "next-event estimation of emissive surfaces (material.emission); "
                        "'photon': photon mapping (needs scipy: the outlook extra); "
                        "'analytic': Whitted's direct light with the diffuse light of rect, "
                        "disk and polygon lights exact, no sample noise (needs shapely: the "
                        "exact extra)")
    r.add_argument("--spp", type=int, default=None, metavar="N",
                   help="samples per pixel: path tracing's paths and the photon map's eye "
                        f"rays (default {PATH_SPP}); Whitted's stratified jittered samples, "
                        "see --filter (default 1: the pixel centre, no jitter)")
    options.seed(r, "random seed of the path tracer, the photon map and Whitted's "
                   "distributed samples (--spp, roughness, aperture); the same seed gives "
                   "the same image "
                   "(default 0)")
    options.exr(r, "also write the linear image as OpenEXR")
    options.photon(r, KERNELS)
    r.set_defaults(func=command)


def command(args) -> int:
    if args.integrator == "path":
        return path_traced(args)
    if args.integrator == "photon":
        return photon_mapped(args)
    if args.integrator == "analytic":
        return analytic_rendered(args)
    paths = {"image": Path(args.output)}
    for kind in ("exr", "png16"):
        if getattr(args, kind):
            paths[kind] = Path(getattr(args, kind))
    output_paths.check(paths, {"image": "-o", "exr": "--exr", "png16": "--png16"}, "raytrace")
    if args.max_depth is not None and args.max_depth < 0:
        raise InputError("--max-depth", f"must be >= 0, got {args.max_depth}")
    spp = 1 if args.spp is None else args.spp
    for flag, value, low in (("--spp", spp, 1), ("--seed", args.seed, 0)):
        if value < low:
            raise InputError(flag, f"must be >= {low}, got {value}")
    scene = load_scene(args.scene)
    memory.check(estimate.whitted(scene, tuple(paths.keys() - {"image"}) + ("png",)),
                 args.memory_budget, args.scene)
    image = render(scene, max_depth=args.max_depth, backend=args.backend,
                   progress=False if args.no_progress else None, spp=spp, seed=args.seed,
                   pixel_filter=args.filter)
    return _written(paths, image)


def _written(paths: dict[str, Path], image) -> int:
    """Write `image` to `paths` (the PNG, and the EXR and 16-bit PNG asked for) and say so."""
    save_png(paths["image"], image)
    if "exr" in paths:
        save_exr(paths["exr"], image)
    if "png16" in paths:
        save_png16(paths["png16"], image)
    print(f"wrote {', '.join(str(p) for p in paths.values())}", file=sys.stderr)
    return status.OK


def analytic_rendered(args) -> int:
    """`raytrace render --integrator analytic` (`raytrace.outlook.analytic`)."""
    from raytrace.outlook import analytic

    paths = {"image": Path(args.output)}
    for kind in ("exr", "png16"):
        if getattr(args, kind):
            paths[kind] = Path(getattr(args, kind))
    output_paths.check(paths, {"image": "-o", "exr": "--exr", "png16": "--png16"}, "raytrace")
    for flag, value in (("--spp", args.spp), ("--max-depth", args.max_depth)):
        if value is not None:
            raise InputError(flag, "not with --integrator analytic (the direct light at the "
                                   "pixel centres)")
    scene = load_scene(args.scene)
    memory.check(estimate.whitted(scene, tuple(paths.keys() - {"image"}) + ("png",)),
                 args.memory_budget, args.scene)
    try:
        image = analytic.render(scene, backend=args.backend)
    except SceneError as exc:
        raise exc.in_file(args.scene) from None
    return _written(paths, image)


def path_traced(args) -> int:
    """`raytrace render --integrator path`."""
    paths = {"image": Path(args.output)}
    if args.exr:
        paths["exr"] = Path(args.exr)
    output_paths.check(paths, {"image": "-o", "exr": "--exr"}, "raytrace")
    spp = PATH_SPP if args.spp is None else args.spp
    for flag, value, low in (("--spp", spp, 1), ("--seed", args.seed, 0)):
        if value < low:
            raise InputError(flag, f"must be >= {low}, got {value}")
    depth = args.max_depth
    if depth is not None and depth < 1:
        raise InputError("--max-depth", f"must be >= 1 for path tracing, got {depth}")
    scene = load_scene(args.scene)
    memory.check(estimate.path_traced(scene, spp, tuple(paths.keys() - {"image"}) + ("png",)),
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


def photon_mapped(args) -> int:
    """`raytrace render --integrator photon`."""
    paths = {"image": Path(args.output)} | ({"exr": Path(args.exr)} if args.exr else {})
    output_paths.check(paths, {"image": "-o", "exr": "--exr"}, "raytrace")
    spp = PATH_SPP if args.spp is None else args.spp
    for flag, value, ok, rule in (("--photons", args.photons, args.photons >= 1, ">= 1"),
                                  ("--spp", spp, spp >= 1, ">= 1"),
                                  ("--seed", args.seed, args.seed >= 0, ">= 0"),
                                  ("--final-gather", args.final_gather, args.final_gather >= 0,
                                   ">= 0"),
                                  ("--light-samples", args.light_samples,
                                   args.light_samples >= 1, ">= 1")):
        if not ok:
            raise InputError(flag, f"must be {rule}, got {value}")
    if args.knn is not None and args.radius is not None:
        raise InputError("--knn", "give --knn or --radius, not both")
    try:
        k = photon.DEFAULT_K if args.knn is None else args.knn
        density = photon.Estimate(k=None if args.radius is not None else k,
                                  radius=args.radius, kernel=args.kernel)
    except ValueError as exc:
        raise InputError("--radius" if args.radius is not None else "--knn", str(exc)) from None
    scene = load_scene(args.scene)
    memory.check(estimate.path_traced(scene, spp, tuple(paths.keys() - {"image"}) + ("png",)),
                 args.memory_budget, args.scene)
    result = photon.render(scene, photons=args.photons, estimate=density, spp=spp,
                           gather=args.final_gather, seed=args.seed, backend=args.backend,
                           light_samples=args.light_samples)
    save_png(args.output, result.image)
    if args.exr:
        save_exr(args.exr, result.image)
    print(f"{result.maps.shot} photons ({len(result.maps.caustic)} caustic, "
          f"{len(result.maps.global_)} global), {spp} spp, {result.rays / 1e6:.1f} M rays "
          f"in {result.seconds:.1f} s; wrote {', '.join(str(p) for p in paths.values())}",
          file=sys.stderr)
    return status.OK
