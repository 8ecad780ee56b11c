"""Benchmark (not a test): our mask-only frames against Mitsuba 3's JIT ray tracer (an optional
peer: `pip install '.[bench]'`), and against our own ray tracer, on the same scenes.

    python -m benchmarks.bench_mitsuba [--runs N] [--sizes bunny,100k,1M]

Mitsuba 3 (`llvm_ad_rgb`: Dr.Jit compiles the rays' work to LLVM and runs it on every core)
gets the same masks the way a Mitsuba user would: the scene's triangles as `mi.Mesh`es in the
eye's frame (float32, as ours), one primary ray per pixel centre (`raytrace.camera.
primary_rays`, float32), `ray_intersect` with `RayFlags.Minimal` (position and geometric
normal), the visible side's normal against the light, and `ray_test` of `spawn_ray_to(light)`
where it faces the light.  Its clock starts with the rays as numpy arrays (made once, like a
camera) and stops with the lit mask and the coverage back in numpy; the kernels are compiled
in two warm-up runs first (Dr.Jit caches them), so what is timed is a warm frame.  The
variants take turns round by round: ours (`Renderer.render(outputs=("lit", "coverage"))`),
`raytrace.shadow_masks` on a prebuilt Embree backend, Mitsuba.  Pixels differing from
`raytrace.shadow_masks` are counted for both (Mitsuba's shadow rays start at its own offset
from the surface, so edges and grazing pixels may differ).

In the same rounds, the least GL work any exact shadow-volume frame of the scene must do
(`plain.DepthFloor`, every triangle unculled to depth) and any exact mask-only frame
(`plain.MaskFloor`: the same draw also storing one byte of bits a pixel, and those read back),
and from instrumented frames after them our volume pass: where mask floor + volume pass is
already slower than Mitsuba, no mask-only frame by shadow volumes beats it on this machine (the
headline's bound, per scene).

After the rounds, the CPU time each of ours and Mitsuba spends on a frame (`cpu_per_frame`:
process CPU time, every thread, during the call and in the 100 ms after it returns, each call
from a settled machine): Dr.Jit's worker threads keep running after a call has returned its
masks (their spin before they sleep), work a frame's wall time does not show but the next
thing the cores run pays for.

Without Mitsuba installed it prints why and exits 0.
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

from . import frame_timing, plain, scenes
from .report.ratios import mask_bound_ms

VARIANT = "llvm_ad_rgb"


def _scene(name: str, width: int, height: int):
    if name == "bunny":
        return None if scenes.models_dir() is None else scenes.model_scene("bunny", width,
                                                                           height)
    return scenes.occluder_scene(name, 1, width, height)


class MitsubaMasks:
    """The masks of `scene`'s first light (a point light) with Mitsuba 3; `()` returns
    (lit (H, W) bool, coverage (H, W) bool), row 0 at the top."""

    def __init__(self, scene):
        import drjit as dr
        import mitsuba as mi

        from raytrace.camera import primary_rays
        from shadowvol.cameras import frame_origin

        mi.set_variant(VARIANT)
        self.dr, self.mi = dr, mi
        origin = frame_origin(scene.camera)
        shapes = {"type": "scene"}
        for i, o in enumerate(scene.objects):
            v = np.asarray(o.vertices, np.float64) - origin
            f = np.asarray(o.faces, np.uint32)
            m = mi.Mesh(f"object{i}", vertex_count=len(v), face_count=len(f),
                        has_vertex_normals=False, has_vertex_texcoords=False)
            params = mi.traverse(m)
            params["vertex_positions"] = mi.Float(np.ascontiguousarray(v, np.float32).ravel())
            params["faces"] = mi.UInt32(np.ascontiguousarray(f).ravel())
            params.update()
            shapes[f"object{i}"] = m
        self.scene = mi.load_dict(shapes)
        camera = scene.camera
        framed = replace(camera, eye=camera.eye - origin, target=camera.target - origin)
        o, d = primary_rays(framed, scene.width, scene.height, dtype=np.float32)
        self.origins, self.directions = np.ascontiguousarray(o.T), np.ascontiguousarray(d.T)
        first = scene.lights[0] if scene.lights else None
        self.light = (np.asarray(first.position, np.float64) - origin
                      if hasattr(first, "position") else None)
        self.lights, self.origin = scene.lights, origin
        self.shape = (scene.height, scene.width)

    def __call__(self) -> tuple[np.ndarray, np.ndarray]:
        dr, mi = self.dr, self.mi
        ray = mi.Ray3f(mi.Point3f(*self.origins), mi.Vector3f(*self.directions))
        si = self.scene.ray_intersect(ray, ray_flags=mi.RayFlags.Minimal, coherent=True)
        hit = si.is_valid()
        light = mi.Point3f(*[float(x) for x in self.light])
        # the visible side's normal: the geometric normal turned toward the eye
        side = dr.sign(dr.dot(si.n, -ray.d))
        facing = hit & (dr.dot(si.n, light - si.p) * side > 0)
        blocked = self.scene.ray_test(si.spawn_ray_to(light), active=facing)
        lit = facing & ~blocked
        dr.eval(lit, hit)
        return (np.array(lit, bool).reshape(self.shape),
                np.array(hit, bool).reshape(self.shape))


    def all_lights(self) -> tuple[np.ndarray, np.ndarray]:
        """The masks of every light (point, spot or directional): lit (L, H, W) bool and
        coverage (H, W) bool, the way `()` makes the first's (a spot light's cone: the angle
        between its axis and the point; a directional light: `spawn_ray` along −direction)."""
        dr, mi = self.dr, self.mi
        ray = mi.Ray3f(mi.Point3f(*self.origins), mi.Vector3f(*self.directions))
        si = self.scene.ray_intersect(ray, ray_flags=mi.RayFlags.Minimal, coherent=True)
        hit = si.is_valid()
        side = dr.sign(dr.dot(si.n, -ray.d))
        lit = []
        for light in self.lights:
            if hasattr(light, "position"):
                at = mi.Point3f(*[float(x) for x in np.asarray(light.position) - self.origin])
                toward = at - si.p
                shadow = si.spawn_ray_to(at)
            else:
                toward = mi.Vector3f(*[float(-x) for x in light.direction])
                shadow = si.spawn_ray(toward)
            facing = hit & (dr.dot(si.n, toward) * side > 0)
            if hasattr(light, "cos_cutoff"):
                axis = mi.Vector3f(*[float(x) for x in light.direction])
                facing &= -dr.dot(axis, dr.normalize(toward)) >= light.cos_cutoff
            lit.append(facing & ~self.scene.ray_test(shadow, active=facing))
        dr.eval(hit, *lit)
        return (np.stack([np.array(m, bool).reshape(self.shape) for m in lit]),
                np.array(hit, bool).reshape(self.shape))


def cpu_per_frame(fn, runs: int, after: float = 0.1) -> dict:
    """{"during": stats, "after": stats} of `runs` calls of `fn`: the process's CPU time (all
    threads) while the call runs and in the `after` seconds that follow it (sleeping), in ms.
    Each call starts `after` seconds after the previous one's window, so no call pays for
    another's tail."""
    during, tail = [], []
    for _ in range(runs):
        time.sleep(after)
        t0 = time.process_time()
        fn()
        t1 = time.process_time()
        time.sleep(after)
        t2 = time.process_time()
        during.append(t1 - t0)
        tail.append(t2 - t1)
    return {"during": frame_timing.stats(during), "after": frame_timing.stats(tail)}


def measure(names, width: int, height: int, runs: int) -> dict:
    try:
        import mitsuba  # noqa: F401
    except ImportError:
        return {"skipped": "Mitsuba 3 is not installed (pip install '.[bench]')"}
    from raytrace import shadow_masks
    from raytrace.masks import scene_backend
    from shadowvol import Renderer
    from shadowvol.raster.platform.context import make_current

    out = {"variant": VARIANT, "size": [width, height], "runs": runs, "scenes": [],
           "load_before": os.getloadavg()}
    for name in names:
        scene = _scene(name, width, height)
        if scene is None:
            out["scenes"].append({"scene": name, "skipped": "the shared meshes are missing"})
            continue
        t0 = time.perf_counter()
        peer = MitsubaMasks(scene)
        build = time.perf_counter() - t0
        t0 = time.perf_counter()
        peer()
        first = time.perf_counter() - t0          # compiling the kernels
        peer()
        backend = scene_backend(scene, "embree")
        with Renderer(scene) as r, plain.PlainFrame(r.ctx, scene) as flat, \
                plain.DepthFloor(r.ctx, flat) as depth_floor, \
                plain.MaskFloor(r.ctx, flat) as mask_floor:
            for _ in range(2):   # warm: programs, kernels, first-touch memory
                r.render(outputs=("lit", "coverage"))
                depth_floor()
                mask_floor()
            fns = {"ours, masks only": lambda: r.render(outputs=("lit", "coverage")),
                   "raytrace.shadow_masks": lambda: shadow_masks(scene, backend),
                   "Mitsuba 3": peer,
                   "depth floor": depth_floor, "mask floor": mask_floor}
            times = {k: [] for k in fns}
            for rnd in range(runs):
                order = list(fns.items())
                for k, fn in (order if rnd % 2 == 0 else order[::-1]):
                    make_current(r.ctx)
                    t = time.perf_counter()
                    fn()
                    times[k].append(time.perf_counter() - t)
            make_current(r.ctx)
            # the volume pass of the same frames, glFinish-bracketed (instrumented frames)
            volume = frame_timing.phase_times(r, "auto", "cpu", runs,
                                        outputs=("lit", "coverage"))["volume pass"]
            cpu = {"ours, masks only": cpu_per_frame(fns["ours, masks only"], runs),
                   "Mitsuba 3": cpu_per_frame(peer, runs)}
            make_current(r.ctx)
            ours = r.render(outputs=("lit", "coverage")).lit[0]
        ref_lit, _ = shadow_masks(scene, backend)
        mi_lit, mi_cov = peer()
        out["scenes"].append({
            "scene": scene.name, "triangles": int(sum(len(o.faces) for o in scene.objects)),
            "mitsuba_build_s": build, "mitsuba_first_s": first,
            "ms": {k: frame_timing.stats(v) for k, v in times.items()} | {"volume pass": volume},
            "cpu_ms": cpu,
            "differing_ours": int((ours != ref_lit[0]).sum()),
            "differing_mitsuba": int((mi_lit != ref_lit[0]).sum())})
    out["load_after"] = os.getloadavg()
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--runs", type=int, default=9)
    ap.add_argument("--sizes", default="bunny,100k,1M")
    ap.add_argument("--width", type=int, default=1280)
    ap.add_argument("--height", type=int, default=720)
    ap.add_argument("--json", type=Path)
    args = ap.parse_args(argv)
    r = measure(args.sizes.split(","), args.width, args.height, args.runs)
    if args.json:
        args.json.write_text(json.dumps(r, indent=2) + "\n")
    if "skipped" in r:
        print(f"skipped: {r['skipped']}")
        return 0
    print(f"{r['size'][0]}x{r['size'][1]}, one point light, {r['runs']} rounds interleaved "
          f"(every other one in reverse order); Mitsuba {r['variant']}; load average "
          f"{r['load_before'][0]:.1f} before, {r['load_after'][0]:.1f} after")
    print()
    print("| scene | triangles | ours, masks only (ms) | raytrace.shadow_masks (ms) | "
          "Mitsuba 3 (ms) | ours / Mitsuba | target | mask floor + volume pass (ms) | "
          "bound / Mitsuba | pixels differing from shadow_masks: "
          "ours, Mitsuba | Mitsuba: scene build, first (compiling) run (s) |")
    print("|---|---:|---:|---:|---:|---:|---|---:|---:|---|---|")
    for s in r["scenes"]:
        if "skipped" in s:
            print(f"| {s['scene']} | skipped: {s['skipped']} | | | | | | | | | |")
            continue
        ms = s["ms"]
        ratio = ms["ours, masks only"]["median"] / ms["Mitsuba 3"]["median"]
        cells = " | ".join(f"{ms[k]['median']:.1f} ({ms[k]['min']:.1f}-{ms[k]['max']:.1f})"
                           for k in ("ours, masks only", "raytrace.shadow_masks", "Mitsuba 3"))
        bound = mask_bound_ms(ms)
        print(f"| {s['scene']} | {s['triangles']:,} | {cells} | {ratio:.2f} | < 1: "
              f"{'met' if ratio < 1 else 'not met'} | {bound:.1f} | "
              f"{bound / ms['Mitsuba 3']['median']:.2f} | {s['differing_ours']}, "
              f"{s['differing_mitsuba']} | {s['mitsuba_build_s']:.2f}, "
              f"{s['mitsuba_first_s']:.2f} |")
    print()
    print("CPU time a frame (ms, medians; during the call + in the 100 ms after it returns):")
    print()
    print("| scene | ours: during + after | Mitsuba 3: during + after |")
    print("|---|---|---|")
    for s in r["scenes"]:
        if "cpu_ms" in s:
            print(f"| {s['scene']} | " + " | ".join(
                f"{c['during']['median']:.1f} + {c['after']['median']:.1f}"
                for c in (s["cpu_ms"]["ours, masks only"], s["cpu_ms"]["Mitsuba 3"])) + " |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
