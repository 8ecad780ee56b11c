"""Benchmark (not a test): the path tracer's CPU time to a fixed RMSE, against Mitsuba 3's path
integrator on the same scene in the same run (an optional peer: `pip install '.[bench]'`).

    python -m benchmarks.bench_time_to_rmse [--size 128] [--runs 3] [--json PATH] [--quick]

The scene is scenes/cornell.toml at size x size, max depth 4 (its own).  Mitsuba 3 gets it as a
Mitsuba user would write it: every object's triangles as a PLY mesh with a two-sided `diffuse`
BSDF of the same (normalised) reflectance, the emissive ones also an `area` emitter of the same
radiance (one-sided, by winding: the Cornell light faces down, and what its top would light
escapes the box), the same `perspective` camera with a `box` pixel filter (ours: uniform points
in the pixel), the `path` integrator with max_depth = ours + 1 (Mitsuba counts the camera
segment) and its own Russian roulette.  `llvm_ad_rgb` (Dr.Jit compiles each kernel once; every
sample count is rendered once untimed first) with two samplers: `independent` (its default) and
`ldsampler` (its low-discrepancy one).

The reference is Mitsuba's `independent` image at REF_SPP samples, rendered in REF_CHUNKS
parts: Mitsuba is the peer, independent of our code, so a bias of ours shows as an error that
stops falling; the parts' spread gives the reference's own variance, which is subtracted from
every measured MSE (so the error is against the converged image, not against its noise).

Each variant renders at every sample count of SPPS, `runs` times with other seeds, the
variants interleaved round by round; per sample count the MSE is the mean over the runs and the
time the median.  The sample count that reaches the target RMSE, and its time, are
interpolated between the two counts around it (log-log, where error and time are near straight
lines).  Time is the process's CPU time over every thread, during the call and in the 100 ms
after it (Dr.Jit's workers spin on after a call returns: `bench_mitsuba.cpu_per_frame`), and
the wall time.  The target RMSE is TARGET_RMSE in linear RGB over every pixel and channel;
RMSE' (target a quarter of it) leaves out the pixels where the reference sees the light (max
channel > LIGHT_SEEN) and LIGHT_MARGIN pixels around them: the light's edge, where a pixel is
part lamp (radiance ~17) and part ceiling (~0.1), weighs heavily in the first, and there how a
sampler spreads the positions in a pixel matters most; RMSE' is the path tracing's error.

Without Mitsuba installed it reports ours alone, saying so.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
SCENE = ROOT / "scenes" / "cornell.toml"
VARIANT = "llvm_ad_rgb"
# before: the path tracer as it was (balance heuristic, independent samples, roulette from the
# third bounce); then one step at a time to the default
OURS = (("ours before: balance, independent, RR 3", dict(mis="balance", sampler="independent",
                                                         rr_start=3)),
        ("ours: power, independent, RR 5", dict(mis="power", sampler="independent")),
        ("ours now: power, sobol, RR 5", dict(mis="power", sampler="sobol")))
PEERS = (("Mitsuba 3: independent", "independent"), ("Mitsuba 3: ldsampler", "ldsampler"))
SPPS = (4, 16, 64, 256, 1024)  # square powers of two: what `ldsampler` takes
REF_SPP, REF_CHUNKS = 8192, 8
QUICK_SPPS = (4, 64)
TARGET_RMSE = 0.02
LIGHT_SEEN = 1.0  # reference pixels brighter than this (max channel) see the light
LIGHT_MARGIN = 2  # pixels: RMSE' leaves out the light's pixels and this many around them


def _ply(path: Path, vertices: np.ndarray, faces: np.ndarray) -> None:
    header = (f"ply\nformat binary_little_endian 1.0\nelement vertex {len(vertices)}\n"
              "property float x\nproperty float y\nproperty float z\n"
              f"element face {len(faces)}\nproperty list uchar int vertex_indices\n"
              "end_header\n")
    rows = np.zeros(len(faces), dtype=[("n", "u1"), ("i", "<i4", 3)])
    rows["n"], rows["i"] = 3, faces
    path.write_bytes(header.encode() + np.ascontiguousarray(vertices, "<f4").tobytes()
                     + rows.tobytes())


def mitsuba_scene(scene, max_depth: int, sampler: str, folder: Path):
    """The Mitsuba 3 scene of `scene` (Lambertian and emissive materials only), PLY files
    written into folder."""
    import mitsuba as mi

    from raytrace.outlook.brdf import normalised_phong

    vertices, faces, tri_object = scene.triangles()
    d = {"type": "scene", "integrator": {"type": "path", "max_depth": max_depth + 1}}
    cam = scene.camera
    d["sensor"] = {
        "type": "perspective", "fov": float(cam.fov_y), "fov_axis": "y",
        "near_clip": float(cam.near), "far_clip": 1e3 * float(np.ptp(vertices, axis=0).max()),
        "to_world": mi.ScalarTransform4f().look_at(
            origin=[float(x) for x in cam.eye], target=[float(x) for x in cam.target],
            up=[float(x) for x in cam.up]),
        "film": {"type": "hdrfilm", "width": scene.width, "height": scene.height,
                 "rfilter": {"type": "box"}, "pixel_format": "rgb"},
        "sampler": {"type": sampler, "sample_count": 4}}
    for i, obj in enumerate(scene.objects):
        m = obj.material
        if m.reflectivity or m.transparency or any(m.specular):
            raise ValueError(f"object {obj.name!r}: only Lambertian materials convert")
        kd, _ = normalised_phong(np.array([m.diffuse]), np.array([m.specular]))
        path = folder / f"object{i}.ply"
        _ply(path, vertices, faces[tri_object == i])
        shape = {"type": "ply", "filename": str(path), "face_normals": True,
                 "bsdf": {"type": "twosided", "bsdf": {"type": "diffuse", "reflectance": {
                     "type": "rgb", "value": [float(x) for x in kd[0]]}}}}
        if max(m.emission) > 0:
            shape["emitter"] = {"type": "area", "radiance": {
                "type": "rgb", "value": [float(x) for x in m.emission]}}
        d[f"object{i}"] = shape
    return mi.load_dict(d)


def timed(fn):
    """(result, CPU seconds over every thread incl. the 100 ms after, wall seconds)."""
    time.sleep(0.1)
    c0, w0 = time.process_time(), time.perf_counter()
    out = fn()
    wall = time.perf_counter() - w0
    time.sleep(0.1)
    return out, time.process_time() - c0, wall


def _renderers(scene, max_depth: int, folder: Path, peers: bool) -> dict:
    """name -> fn(spp, seed) -> (H, W, 3) float64."""
    from raytrace.outlook.path import pathtrace

    fns = {}
    for name, kw in OURS:
        fns[name] = (lambda spp, seed, kw=kw: pathtrace.render(
            scene, spp=spp, seed=seed, max_depth=max_depth, progress=False, **kw).image)
    if peers:
        import mitsuba as mi

        mi.set_log_level(mi.LogLevel.Error)
        for name, sampler in PEERS:
            mscene = mitsuba_scene(scene, max_depth, sampler, folder)
            fns[name] = (lambda spp, seed, s=mscene: np.array(
                mi.render(s, spp=spp, seed=seed), np.float64))
    return fns


def reference(scene, max_depth: int, folder: Path, spp: int, chunks: int, peers: bool):
    """(image, per-pixel variance of it, who rendered it): Mitsuba's independent sampler at spp
    in `chunks` parts, or ours (independent) where Mitsuba is missing."""
    if peers:
        import mitsuba as mi

        mscene = mitsuba_scene(scene, max_depth, "independent", folder)
        parts = [np.array(mi.render(mscene, spp=spp // chunks, seed=10_000 + c), np.float64)
                 for c in range(chunks)]
        who = f"Mitsuba 3 {VARIANT} independent, {spp} spp"
    else:
        from raytrace.outlook.path import pathtrace

        parts = [pathtrace.render(scene, spp=spp // chunks, seed=10_000 + c,
                                  max_depth=max_depth, sampler="independent",
                                  progress=False).image for c in range(chunks)]
        who = f"ours, independent, {spp} spp"
    parts = np.array(parts)
    return parts.mean(axis=0), parts.var(axis=0, ddof=1) / chunks, who


def crossing(spps, values, times, target: float):
    """(spp, time, extrapolated) where the error values (decreasing with spp) reach target,
    log-log interpolated between the counts around it (or extrapolated from the nearest two)."""
    x, y, t = (np.log(np.asarray(a, float)) for a in (spps, values, times))
    below = np.flatnonzero(y <= math.log(target))
    i = 0 if not len(below) or below[0] == 0 else below[0] - 1
    if not len(below):
        i = len(x) - 2
    extrapolated = bool(not len(below) or below[0] == 0)
    slope = (y[i + 1] - y[i]) / (x[i + 1] - x[i])
    if not slope < 0:
        return math.nan, math.nan, True
    xs = x[i] + (math.log(target) - y[i]) / slope
    ts = t[i] + (t[i + 1] - t[i]) / (x[i + 1] - x[i]) * (xs - x[i])
    return math.exp(xs), math.exp(ts), extrapolated


def _peer_missing() -> str | None:
    """Why Mitsuba 3 cannot be the peer here, or None."""
    try:
        import mitsuba as mi
    except ImportError:
        return "Mitsuba 3 is not installed (pip install '.[bench]')"
    try:
        mi.set_variant(VARIANT)
    except (ImportError, AttributeError, RuntimeError) as exc:
        return f"Mitsuba 3 has no {VARIANT} here: {exc}"
    return None


def near_light(ref: np.ndarray) -> np.ndarray:
    """(H, W) bool: the reference's pixels that see the light, and LIGHT_MARGIN around them."""
    near = ref.max(axis=2) > LIGHT_SEEN
    for _ in range(LIGHT_MARGIN):
        grown = near.copy()
        grown[1:] |= near[:-1]
        grown[:-1] |= near[1:]
        grown[:, 1:] |= near[:, :-1]
        grown[:, :-1] |= near[:, 1:]
        near = grown
    return near


def _errors(image, ref, ref_var, light: np.ndarray) -> tuple[float, float]:
    """MSE over every pixel, and over the pixels away from the light, less the reference's
    own variance."""
    sq = (image - ref) ** 2
    return (float(sq.mean() - ref_var.mean()),
            float(sq[~light].mean() - ref_var[~light].mean()))


def measure(size: int = 128, runs: int = 3, spps=SPPS, target: float = TARGET_RMSE,
            ref_spp: int = REF_SPP, ref_chunks: int = REF_CHUNKS) -> dict:
    from shadowvol.scenefile import load_scene

    scene = load_scene(SCENE).replace(width=size, height=size)
    depth = scene.max_depth
    missing = _peer_missing()
    out = {"scene": "scenes/cornell.toml", "size": size, "max_depth": depth, "runs": runs,
           "spps": list(spps), "target_rmse": target, "peer": VARIANT if not missing else None,
           "peer_missing": missing, "load_before": os.getloadavg(), "cpus": os.cpu_count()}
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        fns = _renderers(scene, depth, folder, missing is None)
        for name, fn in fns.items():  # warm: numba's kernels, Dr.Jit's of every count
            for spp in spps if name.startswith("Mitsuba") else spps[:1]:
                fn(spp, 1)
        (ref, ref_var, who), ref_cpu, _ = timed(
            lambda: reference(scene, depth, folder, ref_spp, ref_chunks, missing is None))
        out.update(reference=who, reference_cpu_s=ref_cpu,
                   reference_rmse_own=float(np.sqrt(ref_var.mean())))
        light = near_light(ref)
        points = {name: {spp: [] for spp in spps} for name in fns}
        for rnd in range(runs):
            order = list(fns.items())
            for spp in spps:
                for name, fn in (order if rnd % 2 == 0 else order[::-1]):
                    image, cpu, wall = timed(lambda: fn(spp, 100 * rnd + spp))
                    points[name][spp].append((cpu, wall) + _errors(image, ref, ref_var, light))
    out["load_after"] = os.getloadavg()
    out["variants"] = {}
    for name, by_spp in points.items():
        rows = [np.array(by_spp[spp]) for spp in spps]
        cpu = [float(np.median(r[:, 0])) for r in rows]
        wall = [float(np.median(r[:, 1])) for r in rows]
        mse = [max(float(r[:, 2].mean()), 1e-30) for r in rows]
        mse_dark = [max(float(r[:, 3].mean()), 1e-30) for r in rows]
        spp_t, cpu_t, extra = crossing(spps, mse, cpu, target ** 2)
        _, wall_t, _ = crossing(spps, mse, wall, target ** 2)
        dark_spp, dark_cpu, dark_extra = crossing(spps, mse_dark, cpu, (target / 4) ** 2)
        out["variants"][name] = {
            "runs": {spp: by_spp[spp] for spp in spps}, "cpu_s": cpu, "wall_s": wall, "rmse": list(np.sqrt(mse)),
            "rmse_unlit": list(np.sqrt(mse_dark)), "spp_to_target": spp_t,
            "cpu_to_target": cpu_t, "wall_to_target": wall_t, "extrapolated": extra,
            "spp_to_target_unlit": dark_spp, "cpu_to_target_unlit": dark_cpu,
            "extrapolated_unlit": dark_extra}
    return out


def report(r: dict) -> list[str]:
    """The lines the run prints (short: BENCHMARKS.md keeps them verbatim)."""
    peer = r["peer"]
    base = r["variants"].get(PEERS[0][0]) if peer else None
    best = r["variants"].get(PEERS[1][0]) if peer else None
    lines = [f"{r['scene']} {r['size']}x{r['size']}, max depth {r['max_depth']}, "
             f"{r['cpus']} cores; reference: {r['reference']} (its own RMSE "
             f"{r['reference_rmse_own']:.4f}, subtracted); {r['runs']} runs, CPU s median; "
             f"load {r['load_before'][0]:.1f} -> {r['load_after'][0]:.1f}"
             + ("" if peer else f"; {r['peer_missing']}: ours alone")]
    t = r["target_rmse"]
    lines += [f"| variant | spp to RMSE {t} | CPU s | wall s | CPU / Mitsuba indep., "
              f"ldsampler | RMSE' {t / 4} (away from the light): spp, CPU s, / Mitsuba ldsampler |",
              "|---|---:|---:|---:|---|---|"]
    for name, v in r["variants"].items():
        mark = "~" if v["extrapolated"] else ""
        ratio = (f"{v['cpu_to_target'] / base['cpu_to_target']:.2f}, "
                 f"{v['cpu_to_target'] / best['cpu_to_target']:.2f}") if peer else "-"
        dark = (f"{'~' if v['extrapolated_unlit'] else ''}{v['spp_to_target_unlit']:.0f}, "
                f"{v['cpu_to_target_unlit']:.2f}"
                + (f", {v['cpu_to_target_unlit'] / best['cpu_to_target_unlit']:.2f}"
                   if peer else ""))
        lines.append(f"| {name} | {mark}{v['spp_to_target']:.0f} | {v['cpu_to_target']:.2f} | "
                     f"{v['wall_to_target']:.2f} | {ratio} | {dark} |")
    return lines


def _plain(value):
    """numpy scalars and arrays as JSON takes them."""
    return value.tolist() if hasattr(value, "tolist") else str(value)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--size", type=int, default=128)
    ap.add_argument("--runs", type=int, default=3)
    ap.add_argument("--json", type=Path)
    ap.add_argument("--quick", action="store_true",
                    help="a smoke run: 24x24, 4 and 64 spp, 2 runs, a 1024-spp reference")
    args = ap.parse_args(argv)
    if args.quick:
        # 16x the samples: the error falls 4x, well clear of the run-to-run spread of a few
        # light-edge pixels that dominate it at 24x24 (4 -> 16 spp on one run can rise)
        r = measure(24, 2, QUICK_SPPS, ref_spp=1024, ref_chunks=4)
    else:
        r = measure(args.size, args.runs)
    print("\n".join(report(r)))
    if args.json:
        args.json.write_text(json.dumps(r, indent=1, default=_plain) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
