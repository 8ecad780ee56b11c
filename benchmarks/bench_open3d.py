"""Benchmark (not a test): our exact masks against Open3D's `RaycastingScene`, in one run.

    python -m benchmarks.bench_open3d [--runs 5] [--json FILE]

The peer is the script a user would write for shadow masks with Open3D (`open3d-cpu`, the
bench extra: Embree 4 on all cores): the same pixel-centre primary rays (`raytrace.camera`)
cast with `cast_rays`, each hit offset 1e-4 of the scene's size along its camera-facing
normal, one `test_occlusions` ray per light (a segment ending 1e-4 short of a point light).
Ours: `raytrace.shadow_masks` on a backend built before the clock (and, apart, with the
build; and with embreex's single rays in place of Embree's packets, `raytrace.embree`, whose
masks must equal the packets' bit for bit: counted), the rasterizer's mask-only frame is `bench_mitsuba`'s.  The variants take turns round
by round in one process; medians of wall and CPU time (all threads).  Open3D's masks are not
exact (the offsets): the pixels where they differ from ours are counted, not judged.

Scenes: the Stanford bunny on a floor at 1280x720 (`bench_masks.bunny_scene`) under a point
and a directional light, and the turntable's first view at 640x480 under a point, a
directional and a spot light (both need ../shared/models beside the checkout; without it, the
100k procedural scene stands in and the output says so).  Without Open3D the script says so
and exits 0.
"""

from __future__ import annotations

import os
import statistics
import sys
import time

import numpy as np

from . import scenes
from .cli import bench_main, load_span
from .bench_masks import BUNNY, bunny_scene


def _lights():
    from shadowvol import DirectionalLight, PointLight, SpotLight
    return (PointLight([-3.0, 5.0, 2.0]), DirectionalLight([0.4, -1.0, -0.3]),
            SpotLight([3.0, 4.0, 3.0], [-3.0, -4.0, -3.0], cone_angle=35.0))


def bench_scenes() -> list:
    point, directional, _ = _lights()
    if scenes.models_dir() is None or not BUNNY.is_file():
        base = scenes.occluder_scene("100k", 1, 1280, 720)
        return [base.replace(lights=(point, directional), name="occluders 100k (no shared "
                                                                "meshes)")]
    bunny = bunny_scene(1280, 720)
    turntable = scenes.turntable_scene(640, 480)
    return [bunny.replace(lights=(bunny.lights[0], directional)),
            turntable.replace(lights=_lights())]


class Open3DMasks:
    """The naive Open3D masks of a scene (see the module's docstring)."""

    def __init__(self, scene):
        import open3d as o3d
        vertices, faces, _ = scene.triangles()
        self.o3d, self.scene_def = o3d, scene
        self.scene = o3d.t.geometry.RaycastingScene()
        self.scene.add_triangles(o3d.core.Tensor(vertices.astype(np.float32)),
                                 o3d.core.Tensor(faces.astype(np.uint32)))
        from raytrace.camera import RayGrid
        grid = RayGrid(scene.camera, scene.width, scene.height, np.float32)
        d = grid.directions()
        self.rays = np.ascontiguousarray(np.concatenate([grid.origins(d), d]).T)
        self.offset = 1e-4 * scene.extent

    def __call__(self):
        o3d, scene = self.o3d, self.scene_def
        hit = self.scene.cast_rays(o3d.core.Tensor(self.rays))
        t = hit["t_hit"].numpy()
        covered = np.isfinite(t)
        o, d = self.rays[covered, :3], self.rays[covered, 3:]
        p = o + t[covered, None] * d
        n = hit["primitive_normals"].numpy()[covered]
        n *= np.where((n * d).sum(axis=1) > 0, -1.0, 1.0)[:, None].astype(np.float32)
        start = p + self.offset * n
        lit = np.zeros((len(scene.lights), covered.size), bool)
        for i, light in enumerate(scene.lights):
            if hasattr(light, "position"):
                to = light.position.astype(np.float32) - start
                far = 1.0 - self.offset / np.linalg.norm(to, axis=1)
            else:
                to = np.broadcast_to(-light.direction.astype(np.float32), start.shape)
                far = np.inf
            facing = (n * to).sum(axis=1) > 0
            if hasattr(light, "cos_cutoff"):
                cos = -(to @ light.direction) / np.linalg.norm(to, axis=1)
                facing &= cos >= light.cos_cutoff
            rays = o3d.core.Tensor(np.ascontiguousarray(np.concatenate([start, to], axis=1)))
            if np.isscalar(far):
                blocked = self.scene.test_occlusions(rays).numpy()
            else:  # tfar is one number: unit segments, cut short by the largest margin
                blocked = self.scene.test_occlusions(rays, tfar=float(far.min())).numpy()
            lit[i, np.flatnonzero(covered)] = facing & ~blocked
        return lit.reshape(len(scene.lights), scene.height, scene.width), \
            covered.reshape(scene.height, scene.width)


def _timed(fns: dict, runs: int) -> dict:
    """Wall and CPU ms of each function, taking turns, after one warm-up round."""
    out = {k: {"wall": [], "cpu": []} for k in fns}
    for r in range(runs + 1):
        for k, fn in fns.items():
            w, c = time.perf_counter(), time.process_time()
            fn()
            if r:
                out[k]["wall"].append((time.perf_counter() - w) * 1e3)
                out[k]["cpu"].append((time.process_time() - c) * 1e3)
    return {k: {m: statistics.median(v[m]) for m in ("wall", "cpu")} for k, v in out.items()}


def _built(scene, queries: str):
    """`scene_backend(scene)` with Embree's `queries` ($SHADOWVOL_EMBREE while it is built)."""
    from raytrace.masks import scene_backend
    before = os.environ.get("SHADOWVOL_EMBREE")
    os.environ["SHADOWVOL_EMBREE"] = queries
    try:
        return scene_backend(scene)
    finally:
        if before is None:
            del os.environ["SHADOWVOL_EMBREE"]
        else:
            os.environ["SHADOWVOL_EMBREE"] = before


def measure(scene, runs: int) -> dict:
    from raytrace import shadow_masks
    from raytrace.masks import scene_backend
    peer = Open3DMasks(scene)
    backend, single = scene_backend(scene), _built(scene, "single")
    ours_lit, ours_cov = shadow_masks(scene, backend)
    single_lit, single_cov = shadow_masks(scene, single)
    lit, cov = peer()
    times = _timed({"raytrace.shadow_masks (built backend)": lambda: shadow_masks(scene, backend),
                    "the same, embreex's single rays": lambda: shadow_masks(scene, single),
                    "raytrace.shadow_masks (with its build)": lambda: shadow_masks(scene),
                    "Open3D (built scene)": peer,
                    "Open3D (with its build)": lambda: Open3DMasks(scene)()}, runs)
    return {"scene": scene.name, "triangles": sum(len(o.faces) for o in scene.objects),
            "size": [scene.width, scene.height], "lights": len(scene.lights), "ms": times,
            "pixels_differing": int((lit != ours_lit).sum() + (cov != ours_cov).sum()),
            "single_rays_differing": int((single_lit != ours_lit).sum() +
                                         (single_cov != ours_cov).sum())}


def main(argv=None) -> int:
    try:
        import open3d
    except ImportError as exc:
        print(f"skipped: Open3D is not installed or does not load ({exc}); "
              "pip install open3d-cpu (the bench extra)")
        return 0

    def run(args) -> dict:
        return {"runs": args.runs, "scenes": [measure(s, args.runs) for s in bench_scenes()],
                "open3d": open3d.__version__}

    return bench_main(argv, "bench_open3d", __doc__, run, report)


def report(result: dict, args) -> str:
    """The table of a run: ms median wall / CPU a scene, and the masks' agreement."""
    rows = result["scenes"]
    lines = [f"Open3D {result['open3d']}, {args.runs} rounds; {load_span(result)}; "
             "ms median wall / CPU (all threads)",
             "| scene | triangles | size | lights | " + " | ".join(rows[0]["ms"]) +
             " | pixels differing | single rays vs packets |",
             "|---|---:|---|---:|" + "---:|" * (len(rows[0]["ms"]) + 2)]
    for r in rows:
        cells = " | ".join(f"{v['wall']:.0f} / {v['cpu']:.0f}" for v in r["ms"].values())
        lines.append(f"| {r['scene']} | {r['triangles']:,} | {r['size'][0]}x{r['size'][1]} | "
                     f"{r['lights']} | {cells} | {r['pixels_differing']:,} | "
                     f"{r['single_rays_differing']:,} |")
    return "\n".join(lines)


if __name__ == "__main__":
    sys.exit(main())
