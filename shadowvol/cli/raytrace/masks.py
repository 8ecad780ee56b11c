"""`raytrace masks`: the reference shadow masks of a scene file (and, asked for, the ground
truth), as a mask file and a picture."""

from __future__ import annotations

import dataclasses
import sys
from pathlib import Path

from raytrace import estimate, shadow_masks  # (area lights: lit where every sample reaches)
from raytrace.backends import BACKENDS
from raytrace.exact_soft import check_exact, exact_visibility
from raytrace.groundtruth import ground_truth
from raytrace.outlook.estimate import layers as layers_estimate
from raytrace.outlook.layers import layers
from shadowvol import memory
from shadowvol.cameras import calibration
from shadowvol.cli import options, output_paths, status
from shadowvol.frame import EXACT_OUTPUTS, LAYERS, save_masks
from shadowvol.io import save_png
from shadowvol.pictures import ground_truth_picture, masks_image
from shadowvol.scene import SceneError, hard_lights, light_samples
from shadowvol.scenefile import load_scene


def add_parser(sub) -> None:
    m = options.command(sub, "masks", help="reference shadow masks (lit per light, coverage)",
                       description="Trace the reference shadow masks of SCENE on its triangles "
                                   "and write them as a .npz (lit, coverage, the camera "
                                   "matrices K, world_to_camera, camera_to_world and the light "
                                   "arrays; with --outputs, the ground truth too) and a "
                                   "picture.")
    options.scene(m)
    options.output(m, "NPZ",
                  "where to write the masks (.npz with lit (L, H, W) and coverage (H, W); "
                  "with an area light also lit_count (L, H, W) and samples (L,))")
    m.add_argument("--png", metavar="PNG", default=None,
                   help="where to write a picture of the masks, one panel per light (white lit, "
                        "grey shadowed, black empty), with --outputs also of the outputs side by "
                        "side (default: beside the .npz, same name, .png)")
    m.add_argument("--no-png", action="store_true", help="write the .npz only")
    options.ground_truth(m, "ground truth to add to the .npz, comma-separated: "
                           f"{options.GROUND_TRUTH_LIST} (or all), and visibility_exact, "
                           "irradiance_exact (the exact visible part of rect, disk and polygon "
                           "lights, float64; named only); see docs/CONVENTIONS.md")
    options.backend(m, BACKENDS)
    options.memory_budget(m)
    m.set_defaults(func=command)


def command(args) -> int:
    wanted = options.outputs_named(args.outputs, extra=EXACT_OUTPUTS)
    exact = tuple(o for o in wanted if o in EXACT_OUTPUTS)
    wanted = tuple(o for o in wanted if o not in EXACT_OUTPUTS)
    paths = {"masks": Path(args.output)}
    if not args.no_png:
        paths["picture"] = Path(args.png) if args.png else Path(args.output).with_suffix(".png")
    output_paths.check(paths, {"masks": "-o", "picture": "--png"}, "raytrace")
    scene = load_scene(args.scene)
    need = estimate.masks(scene, wanted, picture="picture" in paths, exact=len(exact))
    if set(wanted) & set(LAYERS):
        need = dataclasses.replace(need, terms=need.terms + layers_estimate(scene).terms)
    memory.check(need, args.memory_budget, args.scene)
    if exact:
        try:
            check_exact(scene)
        except SceneError as exc:
            raise exc.in_file(args.scene) from None
    wanted, layer_names = (tuple(n for n in wanted if n not in LAYERS),
                           tuple(n for n in wanted if n in LAYERS))
    if wanted or layer_names or any(len(hard_lights(lt)) > 1 for lt in scene.lights):
        # the counts of an area light (lit_count, samples) come with the ground truth's rays
        truth = ground_truth(scene, wanted, backend=args.backend)
        lit, coverage, arrays = truth.lit, truth.coverage, truth.arrays()
        if layer_names:   # Whitted's depth-0 direct light (raytrace.outlook.layers)
            arrays |= layers(scene, layer_names, backend=args.backend)
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
