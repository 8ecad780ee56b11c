"""The `raytrace` command: Whitted renders and reference shadow masks of a scene file.

    raytrace render scenes/whitted.toml -o whitted.png
    raytrace render scenes/whitted.toml -o whitted.png --exr whitted.exr --png16 whitted16.png
    raytrace render scenes/whitted.toml -o whitted-aa.png --spp 16 --filter tent --seed 1
    raytrace masks  scenes/whitted.toml -o whitted-masks.npz      (+ whitted-masks.png)
    raytrace masks  scenes/whitted.toml -o truth.npz --outputs depth,normal,object_id,casters
    raytrace tree   scenes/whitted.toml --pixel 420 300 --depth 3 -o tree.png
    raytrace render scenes/cornell.toml --integrator path --spp 64 -o cornell.png
    raytrace render scenes/caustic.toml --integrator photon --photons 500000 -o caustic.png
    raytrace radiosity scenes/cornell.toml --level 4 -o cornell-radiosity.png
    raytrace exercise plane -o plane.png                            (the worked solution)

Outputs are written atomically (shadowvol.io): an error never leaves half a file behind.
A bad scene prints `error: <file>: <key>: <problem>`; the exit statuses are shadowvol's
(`shadowvol.cli.status`).  The ray tracer (`raytrace`) is a library; this is its command line.
"""

from __future__ import annotations

import argparse
import dataclasses
import io
import sys
from pathlib import Path

from raytrace import exercise, photon, shadow_masks  # (area lights: lit where every sample reaches)
from raytrace.backends import BACKENDS
from raytrace.exact_soft import EXACT_OUTPUTS, check_exact, exact_visibility
from raytrace.groundtruth import check_outputs, ground_truth
from raytrace.photonmap import KERNELS
from raytrace.raytree import format_tree, ray_tree
from raytrace.sampling import FILTERS
from raytrace.whitted import render
from shadowvol import __version__, memory
from shadowvol.cameras import calibration
from shadowvol.cli import args as blocks
from shadowvol.cli import outputs, raytrace_outlook, status
from shadowvol.course import raytree_slide
from shadowvol.course.exercise_picture import plane_figure, tir_figure
from shadowvol.course.slides import Layout
from shadowvol.io import (
    atomic_write,
    save_exr,
    save_masks,
    save_png,
    save_png16,
)
from shadowvol.pictures import ground_truth_picture, masks_image
from shadowvol.scene import SceneError, hard_lights, light_samples
from shadowvol.scenefile import load_scene


def _parser() -> argparse.ArgumentParser:
    ap = blocks.Parser(
        prog="raytrace",
        description="Reference CPU ray tracer of shadowvol: Whitted images and the exact "
                    "shadow masks the shadow-volume rasterizer is checked against.",
        epilog="Scene files: TOML or JSON, see scenes/README.md.  Masks follow "
               "docs/CONVENTIONS.md: lit (L, H, W) bool per light in scene order, coverage "
               "(H, W).\n\n" + status.EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--version", action="version", version=f"raytrace (shadowvol) {__version__}")
    sub = ap.add_subparsers(dest="command", required=True, metavar="COMMAND")
    _render_parser(sub)
    raytrace_outlook.add_parsers(sub)
    _masks_parser(sub)
    _tree_parser(sub)
    _exercise_parser(sub)
    return ap


def _render_parser(sub) -> None:
    r = blocks.command(sub, "render", help="ray-trace an image (Whitted: shadows, reflection, "
                                           "refraction, Phong)",
                       description="Ray-trace SCENE into an 8-bit sRGB PNG.")
    blocks.scene(r)
    blocks.output(r, "PNG", "where to write the image (PNG, sRGB, row 0 at the top)")
    r.add_argument("--max-depth", type=int, default=None, metavar="N",
                   help="reflection/refraction generations; 0 = direct lighting only, as the "
                        "rasterizer draws it (default: the scene's render.max_depth)")
    r.add_argument("--png16", metavar="PNG", default=None,
                   help="also write the image as a 16-bit sRGB PNG")
    blocks.backend(r, BACKENDS)
    blocks.memory_budget(r)
    r.add_argument("--no-progress", action="store_true",
                   help="no progress bar (it is shown only on a terminal anyway)")
    r.add_argument("--filter", choices=FILTERS, default="box",
                   help="Whitted with --spp N: the pixel filter the samples are drawn from, "
                        "'box' (the pixel's square, default) or 'tent' (radius 1 pixel)")
    raytrace_outlook.add_options(r)
    blocks.photon(r, KERNELS)


def _masks_parser(sub) -> None:
    m = blocks.command(sub, "masks", help="reference shadow masks (lit per light, coverage)",
                       description="Trace the reference shadow masks of SCENE on its triangles "
                                   "and write them as a .npz (lit, coverage, the camera "
                                   "matrices K, world_to_camera, camera_to_world and the light "
                                   "arrays; with --outputs, the ground truth too) and a "
                                   "picture.")
    blocks.scene(m)
    blocks.output(m, "NPZ",
                  "where to write the masks (.npz with lit (L, H, W) and coverage (H, W); "
                  "with an area light also lit_count (L, H, W) and samples (L,))")
    m.add_argument("--png", metavar="PNG", default=None,
                   help="where to write a picture of the masks, one panel per light (white lit, "
                        "grey shadowed, black empty), with --outputs also of the outputs side by "
                        "side (default: beside the .npz, same name, .png)")
    m.add_argument("--no-png", action="store_true", help="write the .npz only")
    blocks.ground_truth(m, "ground truth to add to the .npz, comma-separated: "
                           f"{blocks.GROUND_TRUTH_LIST} (or all), and visibility_exact, "
                           "irradiance_exact (the exact visible part of rect, disk and polygon "
                           "lights, float64; named only); see docs/CONVENTIONS.md")
    blocks.backend(m, BACKENDS)
    blocks.memory_budget(m)


def _tree_parser(sub) -> None:
    t = blocks.command(sub, "tree", help="the ray tree of one pixel (the course's exercise)",
                       description="Print every ray the Whitted tracer follows for pixel "
                                   "(X, Y) — primary, shadow rays with their verdicts, "
                                   "reflected, refracted, total internal reflection — as an "
                                   "indented tree, and optionally draw the gallery's slide of "
                                   "it: the rays over the render, the tree as boxes beside "
                                   "it.")
    blocks.scene(t)
    t.add_argument("--pixel", nargs=2, type=int, required=True, metavar=("X", "Y"),
                   help="column X from the left, row Y from the top")
    t.add_argument("--depth", type=int, default=None, metavar="N",
                   help="reflection/refraction generations (default: the scene's "
                        "render.max_depth)")
    blocks.output(t, "PNG", "also draw the tree (a 1920x1080 slide): the rays over the "
                            "ray-traced image and one box per ray", required=False)
    blocks.backend(t, BACKENDS)
    blocks.memory_budget(t)


def _exercise_parser(sub) -> None:
    e = blocks.command(sub, "exercise", help="a worked exercise of the course, printed and drawn",
                       description="Print the worked solution of one of the course's "
                                   "exercises, computed with the ray tracer's own formulas, "
                                   "and optionally draw it.  plane: the ray (5,1) + λ(−1,3) "
                                   "against the plane through (2,2) with normal (1,−1).  tir: "
                                   "Snell's law from glass into air, past the critical angle.")
    e.add_argument("name", choices=tuple(EXERCISES), metavar="NAME",
                   help="the exercise: " + ", ".join(EXERCISES))
    blocks.output(e, "PNG", "also draw the exercise's 2D picture", required=False)


def main(argv: list[str] | None = None) -> int:
    try:
        args = _parser().parse_args(argv)
    except KeyboardInterrupt as exc:
        return status.report(exc)
    return status.run(COMMANDS[args.command], args)


def _render(args) -> int:
    if args.integrator == "path":
        return raytrace_outlook.path_traced(args)
    if args.integrator == "photon":
        return _photon(args)
    paths = {"image": Path(args.output)}
    for kind in ("exr", "png16"):
        if getattr(args, kind):
            paths[kind] = Path(getattr(args, kind))
    outputs.check(paths, {"image": "-o", "exr": "--exr", "png16": "--png16"}, "raytrace")
    if args.max_depth is not None and args.max_depth < 0:
        raise SceneError("--max-depth", f"must be >= 0, got {args.max_depth}")
    spp = 1 if args.spp is None else args.spp
    for flag, value, low in (("--spp", spp, 1), ("--seed", args.seed, 0)):
        if value < low:
            raise SceneError(flag, f"must be >= {low}, got {value}")
    scene = load_scene(args.scene)
    memory.check(memory.whitted(scene, tuple(paths.keys() - {"image"}) + ("png",)),
                 args.memory_budget, args.scene)
    image = render(scene, max_depth=args.max_depth, backend=args.backend,
                   progress=False if args.no_progress else None, spp=spp, seed=args.seed,
                   pixel_filter=args.filter)
    save_png(args.output, image)
    if "exr" in paths:
        save_exr(paths["exr"], image)
    if "png16" in paths:
        save_png16(paths["png16"], image)
    print(f"wrote {', '.join(str(p) for p in paths.values())}", file=sys.stderr)
    return status.OK


def _photon(args) -> int:
    """`raytrace render --integrator photon`."""
    paths = {"image": Path(args.output)} | ({"exr": Path(args.exr)} if args.exr else {})
    outputs.check(paths, {"image": "-o", "exr": "--exr"}, "raytrace")
    spp = raytrace_outlook.PATH_SPP if args.spp is None else args.spp
    for flag, value, ok, rule in (("--photons", args.photons, args.photons >= 1, ">= 1"),
                                  ("--spp", spp, spp >= 1, ">= 1"),
                                  ("--seed", args.seed, args.seed >= 0, ">= 0"),
                                  ("--final-gather", args.final_gather, args.final_gather >= 0,
                                   ">= 0"),
                                  ("--light-samples", args.light_samples,
                                   args.light_samples >= 1, ">= 1")):
        if not ok:
            raise SceneError(flag, f"must be {rule}, got {value}")
    if args.knn is not None and args.radius is not None:
        raise SceneError("--knn", "give --knn or --radius, not both")
    try:
        k = photon.DEFAULT_K if args.knn is None else args.knn
        estimate = photon.Estimate(k=None if args.radius is not None else k,
                                   radius=args.radius, kernel=args.kernel)
    except ValueError as exc:
        raise SceneError("--radius" if args.radius is not None else "--knn", str(exc)) from None
    scene = load_scene(args.scene)
    memory.check(memory.path_traced(scene, spp, tuple(paths.keys() - {"image"}) + ("png",)),
                 args.memory_budget, args.scene)
    result = photon.render(scene, photons=args.photons, estimate=estimate, spp=spp,
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


def _masks(args) -> int:
    wanted = outputs.ground_truth(args.outputs, extra=EXACT_OUTPUTS)
    exact = tuple(o for o in wanted if o in EXACT_OUTPUTS)
    wanted = tuple(o for o in wanted if o not in EXACT_OUTPUTS)
    paths = {"masks": Path(args.output)}
    if not args.no_png:
        paths["picture"] = Path(args.png) if args.png else Path(args.output).with_suffix(".png")
    outputs.check(paths, {"masks": "-o", "picture": "--png"}, "raytrace")
    scene = load_scene(args.scene)
    memory.check(memory.ray_masks(scene, wanted, picture="picture" in paths, exact=len(exact)),
                 args.memory_budget, args.scene)
    if exact:
        try:
            check_exact(scene)
        except SceneError as exc:
            raise exc.in_file(args.scene) from None
    if wanted or any(len(hard_lights(lt)) > 1 for lt in scene.lights):
        # the counts of an area light (lit_count, samples) come with the ground truth's rays
        truth = ground_truth(scene, check_outputs(scene, wanted), backend=args.backend)
        lit, coverage, arrays = truth.lit, truth.coverage, truth.arrays()
        picture = (ground_truth_picture(truth, [o.name for o in scene.objects]) if wanted
                   else masks_image(lit, coverage))
    else:
        lit, coverage = shadow_masks(scene, backend=args.backend)
        arrays = calibration(scene).arrays()
        picture = masks_image(lit, coverage)
    if exact:
        found = exact_visibility(scene, backend=args.backend)
        arrays = arrays | {name: getattr(found, name.removesuffix("_exact")) for name in exact}
    save_masks(paths["masks"], lit, coverage,
               light_samples=[light_samples(lt) for lt in scene.lights], arrays=arrays)
    if "picture" in paths:
        save_png(paths["picture"], picture)
    print(f"wrote {', '.join(str(p) for p in paths.values())}", file=sys.stderr)
    return status.OK


def _tree(args) -> int:
    """The `tree` command: print the ray tree of one pixel, draw it with -o."""
    if args.output:
        outputs.check({"picture": Path(args.output)}, {"picture": "-o"}, "raytrace")
    if args.depth is not None and args.depth < 0:
        raise SceneError("--depth", f"must be >= 0, got {args.depth}")
    scene = load_scene(args.scene)
    x, y = args.pixel
    if not (0 <= x < scene.width and 0 <= y < scene.height):
        raise SceneError("--pixel", f"{x} {y} is outside the {scene.width}x{scene.height} "
                                    "image")
    layout = Layout(supersample=1)  # the gallery's slide, its image traced once a pixel
    if args.output:
        estimate = memory.whitted(raytree_slide.traced_scene(layout, scene))
        memory.check(dataclasses.replace(estimate, what=f"{estimate.what} on the ray tree "
                                                        "slide's image"),
                     args.memory_budget, args.scene)
    tree = ray_tree(scene, x, y, max_depth=args.depth, backend=args.backend)
    print(format_tree(tree, scene))
    if args.output:
        depth = scene.max_depth if args.depth is None else args.depth
        picture = raytree_slide.slide(layout, scene, tree, (x, y), depth, lambda s: render(
            s, max_depth=args.depth, backend=args.backend, progress=False))
        save_png(args.output, picture)
        print(f"wrote {args.output}", file=sys.stderr)
    return status.OK


def _plane():
    s = exercise.solve_plane()
    return exercise.plane_text(s), plane_figure(s)


def _tir():
    rays = exercise.solve_tir()
    return exercise.tir_text(rays), tir_figure(rays)


EXERCISES = {"plane": _plane, "tir": _tir}


def _exercise(args) -> int:
    """The `exercise` command: print the worked solution, draw it with -o."""
    if args.output:
        outputs.check({"picture": Path(args.output)}, {"picture": "-o"}, "raytrace")
    text, fig = EXERCISES[args.name]()
    print(text)
    if args.output:
        buf = io.BytesIO()
        fig.savefig(buf, format="png")
        with atomic_write(args.output) as f:
            f.write(buf.getvalue())
        print(f"wrote {args.output}", file=sys.stderr)
    return status.OK


COMMANDS = {"render": _render, "masks": _masks, "tree": _tree, "exercise": _exercise,
            "radiosity": raytrace_outlook.radiosity_command}


if __name__ == "__main__":
    sys.exit(main())
