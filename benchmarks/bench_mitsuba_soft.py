"""Benchmark (not a test): Mitsuba 3's `direct` integrator under a `rectangle` emitter against
the exact irradiance (`raytrace.exact_soft`, `irradiance_exact`), issue 41 step 3.

    python -m benchmarks.bench_mitsuba_soft [--size 64x48] [--calls 128] [--spp 16]

The scene is scenes/soft.toml (its rect light, the ball's tessellation, the box and the slab
over the floor) at a small size.  Mitsuba gets the same triangles (`mi.Mesh`, in the eye's
frame), the light as a `rectangle` shape with an `area` emitter of unit radiance (its to_world
the light's axes u, v scaled by half its size and its normal), the floor a `diffuse` BSDF of
reflectance RHO, every other object black.  Each floor pixel's own pixel-centre ray
(`raytrace.camera.primary_rays`) goes to `direct`'s `sample` (emitter_samples = --spp,
bsdf_samples = 0) --calls times with independent samplers, so the pixel's radiance is estimated
at the same point as the exact value: RHO / pi x irradiance_exact there (a Lambertian floor
under a unit-radiance emitter, with the inverse-square fall-off Mitsuba has).

Reported: the penumbra's mean relative difference and the p-value of a one-sample t-test of the
per-call penumbra means against the exact one (p >= 0.01: no bias seen), the largest per-pixel
|z| (each pixel's mean over the calls against its exact value, by its standard error), the
variant that ran and the time.  The variant is `scalar_rgb` (one ray a call, no JIT): Mitsuba
3.9.1's llvm variants compile with an LLVM JIT that on this AVX-512 machine aborts the process
("LLVM ERROR: Cannot select: ... fminimum", even on its own Cornell box).  Without Mitsuba installed (`pip install '.[bench]'`) it prints why and
exits 0.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
RHO = 0.5
VARIANT = "scalar_rgb"


def _scene(width: int, height: int):
    from shadowvol.scenefile import load_scene
    return load_scene(ROOT / "scenes" / "soft.toml").replace(width=width, height=height)


def mitsuba_scene(mi, scene, origin: np.ndarray):
    """The Mitsuba scene of `scene` in the frame of `origin`: its triangles as meshes (the
    floor, object 0, diffuse RHO; the others black) and its first light a rectangle emitter."""
    from shadowvol.planes import default_plane_axes

    shapes = {"type": "scene"}
    for i, o in enumerate(scene.objects):
        v = np.asarray(o.vertices, np.float64) - origin
        f = np.asarray(o.faces, np.uint32)
        bsdf = mi.load_dict({"type": "diffuse", "reflectance": {
            "type": "rgb", "value": [RHO if i == 0 else 0.0] * 3}})
        m = mi.Mesh(f"object{i}", vertex_count=len(v), face_count=len(f),
                    has_vertex_normals=False, has_vertex_texcoords=False, props=_props(mi, bsdf))
        params = mi.traverse(m)
        params["vertex_positions"] = np.ascontiguousarray(v, np.float32).ravel().tolist()
        params["faces"] = np.ascontiguousarray(f).ravel().tolist()
        params.update()
        shapes[f"object{i}"] = m
    light = scene.lights[0]
    u, w = default_plane_axes(light.normal)
    matrix = np.eye(4)
    matrix[:3, 0] = u * light.size[0] / 2
    matrix[:3, 1] = w * light.size[1] / 2
    matrix[:3, 2] = light.normal
    matrix[:3, 3] = light.center - origin
    shapes["light"] = {"type": "rectangle", "to_world": mi.ScalarTransform4f(matrix.tolist()),
                       "emitter": {"type": "area", "radiance": {"type": "rgb",
                                                                "value": [1.0, 1.0, 1.0]}}}
    return mi.load_dict(shapes)


def _props(mi, bsdf):
    props = mi.Properties()
    props["bsdf"] = bsdf
    return props


def measure(width: int, height: int, calls: int, spp: int, variant: str = VARIANT) -> dict:
    try:
        import mitsuba as mi
    except ImportError:
        return {"skipped": "Mitsuba 3 is not installed (pip install '.[bench]')"}
    from scipy import stats

    from raytrace.camera import primary_rays
    from raytrace.exact_soft import exact_visibility
    from raytrace.groundtruth import ground_truth
    from shadowvol.cameras import frame_origin

    mi.set_variant(variant)
    scene = _scene(width, height)
    origin = frame_origin(scene.camera)
    t0 = time.perf_counter()
    exact = exact_visibility(scene)
    exact_s = time.perf_counter() - t0
    v, irradiance = exact.visibility[0].ravel(), exact.irradiance[0].ravel()
    floor = (ground_truth(scene, outputs=("object_id",)).object_id == 1).ravel()
    penumbra = np.flatnonzero(floor & (v > 0.02) & (v < 0.98))
    want = RHO / np.pi * irradiance[penumbra]
    framed = replace(scene.camera, eye=scene.camera.eye - origin,
                     target=scene.camera.target - origin)
    o, d = primary_rays(framed, width, height)
    mscene = mitsuba_scene(mi, scene, origin)
    integrator = mi.load_dict({"type": "direct", "emitter_samples": spp, "bsdf_samples": 0})
    got = np.zeros((calls, len(penumbra)))
    t0 = time.perf_counter()
    for c in range(calls):
        sampler = mi.load_dict({"type": "independent", "sample_count": 1, "seed": c})
        for k, pix in enumerate(penumbra):
            sampler.seed(c * len(penumbra) + k)
            ray = mi.Ray3f(mi.Point3f(*o[pix]), mi.Vector3f(*(d[pix] / np.linalg.norm(d[pix]))))
            spec, _, _ = integrator.sample(mscene, sampler, ray)
            got[c, k] = spec[0]
    mitsuba_s = time.perf_counter() - t0
    per_call = (got - want).mean(axis=1)            # the penumbra's mean difference per call
    mean, se = got.mean(axis=0), got.std(axis=0, ddof=1) / np.sqrt(calls)
    spread = se > 0
    z = (mean - want)[spread] / se[spread]
    brighter = (got - 1.02 * want).mean(axis=1)     # the test's power: the exact one 2% off
    return {"variant": variant, "size": [width, height], "calls": calls, "spp": spp,
            "penumbra_pixels": int(len(penumbra)), "exact_s": exact_s, "mitsuba_s": mitsuba_s,
            "relative_difference": float(per_call.mean() / want.mean()),
            "p_value": float(stats.ttest_1samp(per_call, 0.0).pvalue),
            "p_value_2_percent_off": float(stats.ttest_1samp(brighter, 0.0).pvalue),
            "max_abs_z": float(np.abs(z).max()), "constant_pixels": int((~spread).sum()),
            "load": os.getloadavg()}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--size", default="64x48")
    ap.add_argument("--calls", type=int, default=128)
    ap.add_argument("--spp", type=int, default=16)
    ap.add_argument("--json", type=Path)
    args = ap.parse_args(argv)
    w, h = (int(x) for x in args.size.split("x"))
    r = measure(w, h, args.calls, args.spp)
    if args.json:
        args.json.write_text(json.dumps(r, indent=2) + "\n")
    if "skipped" in r:
        print(f"skipped: {r['skipped']}")
        return 0
    print(f"Mitsuba 3 {r['variant']}, direct integrator, rectangle emitter: scenes/soft.toml at "
          f"{w}x{h}, {r['penumbra_pixels']} penumbra floor pixels, {r['calls']} calls x "
          f"{r['spp']} emitter samples each; load {r['load'][0]:.1f}")
    print(f"penumbra mean vs exact: relative difference {r['relative_difference']:+.2e}, "
          f"t-test p = {r['p_value']:.3f} ({'no bias seen' if r['p_value'] >= 0.01 else 'BIASED'}"
          f" at p >= 0.01); against the exact one 2% brighter p = {r['p_value_2_percent_off']:.1e}; "
          f"largest per-pixel |z| {r['max_abs_z']:.2f} ({r['constant_pixels']} pixels with "
          "no spread left out)")
    print(f"time: exact {r['exact_s']:.2f} s, Mitsuba {r['mitsuba_s']:.2f} s "
          f"({1e6 * r['mitsuba_s'] / (r['calls'] * r['penumbra_pixels']):.0f} us a call)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
