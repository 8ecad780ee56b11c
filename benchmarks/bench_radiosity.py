"""Benchmark (not a test): radiosity against the path tracer, object by object, on the Cornell box.

    python -m benchmarks.bench_radiosity [--size 64] [--spp 256] [--seeds 0 1 2]
                                         [--level L] [--rays K] [--tol T] [--cache /tmp/x]

Two measures per object:
* `image`: the mean over the object's pixels (pixel centres) of radiosity's interpolated
  display, of its flat display, and of the path tracer at `spp` (un-jittered, so both images
  sample the same points; its image is cached in `--cache` by (size, spp, seed));
* `area`: the area-weighted mean of the solution over the object's camera-side patches, against
  one path-traced reference for all seeds, `points` points spread uniformly over the object's
  area (`radiance_leaving`; cached in `--cache` by points).
Differences are relative, radiosity over path tracer minus 1, summed over channels.  The light
is listed separately (it is its emission plus what it reflects).  Radiosity runs at its
defaults unless told otherwise, once per seed, and its time is reported.

`measure()` returns the table as a dict; run as a script it prints it, and the JSON with
`--json`.
"""

from __future__ import annotations

import argparse
import json
import math
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
CORNELL = ROOT / "scenes" / "cornell.toml"
BOX_CENTRE = np.array([278.0, 274.4, 279.6])  # the Cornell box's centre, mm


def object_ids(scene) -> np.ndarray:
    """(H*W,) int: the object each pixel centre sees, -1 for the background."""
    from raytrace.backends import make_backend
    from raytrace.camera import primary_rays

    vertices, faces, ids = scene.triangles()
    o, d = primary_rays(scene.camera, scene.width, scene.height)
    hits = make_backend("embree", vertices, faces).closest_hit(o, d)
    return np.where(hits.tri >= 0, ids[np.maximum(hits.tri, 0)], -1)


def path_reference(scene, spp: int, seed: int, cache: Path | None) -> np.ndarray:
    """(H*W, 3) the path tracer at pixel centres, from the cache when it holds it."""
    from raytrace.outlook.path import pathtrace

    path = None if cache is None else cache / f"pt-{scene.width}-{spp}-{seed}.npy"
    if path is not None and path.exists():
        return np.load(path)
    image = pathtrace.render(scene, spp=spp, seed=seed, jitter=False, progress=False).image
    image = image.reshape(-1, 3)
    if path is not None:
        cache.mkdir(parents=True, exist_ok=True)
        np.save(path, image)
    return image


def camera_side(obj, points: np.ndarray, normals: np.ndarray) -> np.ndarray:
    """Normals (k, 3) flipped toward the face the camera's side sees: walls face the box's
    centre, blocks face away from their own centre."""
    toward = points - obj.vertices.mean(axis=0) if "block" in obj.name else BOX_CENTRE - points
    return normals * np.where((toward * normals).sum(axis=1) >= 0.0, 1.0, -1.0)[:, None]


def path_areas(scene, points: int, cache: Path | None, seed: int = 1000) -> dict:
    """{name: (mean (3,), standard error (3,))}: `points` path-traced points spread uniformly
    over each object's area, looking at its camera-side face (cached by points and seed)."""
    from raytrace.outlook.path.pathtrace import PathWorld, radiance_leaving

    path = None if cache is None else cache / f"pt-area-{points}-{seed}.json"
    if path is not None and path.exists():
        return {k: tuple(np.array(x) for x in v) for k, v in json.loads(path.read_text()).items()}
    world, rng = PathWorld(scene), np.random.default_rng(seed)
    out = {}
    for obj in scene.objects:
        tri = obj.triangles
        cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        area = np.linalg.norm(cross, axis=1)
        sums, squares = np.zeros(3), np.zeros(3)
        for first in range(0, points, 50000):
            m = min(50000, points - first)
            j = rng.choice(len(tri), m, p=area / area.sum())
            r, u = np.sqrt(rng.random(m)), rng.random(m)
            c = tri[j]
            p = ((1 - r)[:, None] * c[:, 0] + (r * (1 - u))[:, None] * c[:, 1]
                 + (r * u)[:, None] * c[:, 2])
            L, _ = radiance_leaving(world, p, camera_side(obj, p, cross[j] / area[j, None]), rng)
            sums += L.sum(axis=0)
            squares += (L * L).sum(axis=0)
        mean = sums / points
        out[obj.name] = (mean, np.sqrt(np.maximum(squares / points - mean ** 2, 0.0) / points))
    if path is not None:
        cache.mkdir(parents=True, exist_ok=True)
        path.write_text(json.dumps({k: [v.tolist() for v in vs] for k, vs in out.items()}))
    return out


def solution_areas(scene, solution) -> dict:
    """{name: (3,)}: the solution's area-weighted mean over each object's camera-side face."""
    mesh, T = solution.mesh, solution.mesh.triangles
    centres = mesh.vertices[mesh.faces].mean(axis=1)
    out = {}
    for k, obj in enumerate(scene.objects):
        sel = np.flatnonzero(mesh.tri_object == k)
        n = camera_side(obj, centres[sel], mesh.normal[sel])
        patch = np.where((n * mesh.normal[sel]).sum(axis=1) > 0.0, sel, sel + T)
        a = mesh.area[sel]
        out[obj.name] = (a[:, None] * solution.radiance[patch]).sum(axis=0) / a.sum()
    return out


def measure(size: int = 64, spp: int = 256, seeds=(0, 1, 2), points: int = 400000,
            cache: Path | None = Path("/tmp/shadowvol-radiosity-bench"), **settings) -> dict:
    """Per seed: radiosity's time and, per object, the image and area means (see the module
    docstring).  `settings` go to `radiosity.solve` (level, rays_per_patch, tol, shots)."""
    from raytrace.outlook import radiosity
    from shadowvol.scenefile import load_scene

    scene = load_scene(CORNELL).replace(width=size, height=size)
    ids = object_ids(scene)
    reference = path_areas(scene, points, cache) if points else {}
    result = {"size": size, "spp": spp, "settings": settings, "seeds": {}}
    for seed in seeds:
        t = time.perf_counter()
        sol = radiosity.solve(scene, seed=seed, **settings)
        seconds = time.perf_counter() - t
        smooth = radiosity.display(scene, sol).reshape(-1, 3)
        flat = radiosity.display(scene, sol, interpolate=False).reshape(-1, 3)
        pt = path_reference(scene, spp, seed, cache)
        areas = solution_areas(scene, sol)
        rows = {}
        for k, obj in enumerate(scene.objects):
            px = ids == k
            row = {"pixels": int(px.sum())}
            if px.any():
                ref = pt[px].mean(axis=0).sum()
                row["image_smooth"] = smooth[px].mean(axis=0).sum() / ref - 1.0
                row["image_flat"] = flat[px].mean(axis=0).sum() / ref - 1.0
            if obj.name in reference:
                rad, (ref, se) = areas[obj.name], reference[obj.name]
                row["area"] = rad.sum() / ref.sum() - 1.0
                row["area_se"] = math.sqrt((se ** 2).sum()) / ref.sum()
            rows[obj.name] = row
        result["seeds"][seed] = {"seconds": seconds, "patches": sol.mesh.patches,
                                 "summary": radiosity.summary(sol), "objects": rows}
    return result


def table(result: dict) -> str:
    """The result as a plain text table: per object and seed, the relative differences in %."""
    seeds = list(result["seeds"])
    names = list(next(iter(result["seeds"].values()))["objects"])
    lines = [f"radiosity {result['settings'] or 'defaults'} vs path tracer "
             f"{result['spp']} spp at {result['size']}^2"]
    for key in ("image_smooth", "image_flat", "area"):
        lines.append(f"{key:>14}: " + "  ".join(f"seed {s:>2}" for s in seeds))
        for name in names:
            cells = []
            for s in seeds:
                v = result["seeds"][s]["objects"][name].get(key)
                cells.append("    --" if v is None else f"{100 * v:+6.2f}%")
            lines.append(f"{name:>14}: " + "  ".join(cells))
    lines.append("seconds: " + "  ".join(f"{result['seeds'][s]['seconds']:.1f}" for s in seeds))
    return "\n".join(lines)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=64)
    ap.add_argument("--spp", type=int, default=256)
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2])
    ap.add_argument("--points", type=int, default=400000)
    ap.add_argument("--level", type=int)
    ap.add_argument("--rays", type=int)
    ap.add_argument("--tol", type=float)
    ap.add_argument("--shots", type=int)
    ap.add_argument("--cache", type=Path, default=Path("/tmp/shadowvol-radiosity-bench"))
    ap.add_argument("--json", action="store_true")
    a = ap.parse_args(argv)
    settings = {k: v for k, v in (("level", a.level), ("rays_per_patch", a.rays),
                                  ("tol", a.tol), ("shots", a.shots)) if v is not None}
    result = measure(a.size, a.spp, tuple(a.seeds), a.points, a.cache, **settings)
    print(json.dumps(result, indent=1, default=float) if a.json else table(result))


if __name__ == "__main__":
    main()
