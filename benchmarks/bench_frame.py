"""Benchmark (not a test): the cost of shadows per frame.

At 1280x720 with ~100k triangles (a floor and 20 icospheres of 5,120 triangles each):

1. one point light: the shadowed frame with read-back (image + lit mask) against the plain
   unshadowed Phong frame of the same scene on the same context (the same passes without the
   volume pass; `Renderer.render(shadows=False)`), for CPU and GPU silhouettes and each method;
2. one spot light: our shadowed frame against pyrender's shadow-mapped frame of the same scene
   (pyrender has no point-light shadows), each with read-back.

Medians of REPEAT frames after WARMUP frames.  Run:  python benchmarks/bench_frame.py
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from shadowvol.context import create_context, make_current
from shadowvol.primitives import plane, sphere
from shadowvol.renderer import Renderer
from shadowvol.scene import Camera, Material, PointLight, Scene, SpotLight

WARMUP = 2
REPEAT = 11


def bench_scene(light, width=1280, height=720) -> Scene:
    rng = np.random.default_rng(0)
    balls = [sphere(f"ball{i}", [rng.uniform(-4, 4), rng.uniform(0.6, 2.5), rng.uniform(-4, 3)],
                    rng.uniform(0.3, 0.6), Material(diffuse=rng.uniform(0.3, 0.9, 3)),
                    subdivisions=4) for i in range(20)]
    return Scene(camera=Camera(eye=[0, 4, 9], target=[0, 0.8, 0]),
                 objects=[plane("floor", size=[14, 14])] + balls, lights=[light],
                 width=width, height=height)


def median_seconds(frame, repeat=REPEAT) -> float:
    for _ in range(WARMUP):
        frame()
    times = []
    for _ in range(repeat):
        t = time.perf_counter()
        frame()
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=REPEAT)
    ap.add_argument("--no-pyrender", action="store_true", help="skip the pyrender comparison")
    args = ap.parse_args(argv)

    point = bench_scene(PointLight([2.0, 6.0, 3.0]))
    n_tri = sum(len(o.faces) for o in point.objects)
    print(f"{point.width}x{point.height}, {n_tri} triangles, llvmpipe/EGL; medians of "
          f"{args.repeat} frames")
    ctx = create_context()
    print(f"renderer: {ctx.info['GL_RENDERER']}")
    with Renderer(point, ctx) as r:
        plain = median_seconds(lambda: r.render(shadows=False), args.repeat)
        print(f"  unshadowed Phong frame            {plain * 1e3:8.1f} ms")
        for sil in ("cpu", "gpu"):
            for method in ("auto", "zpass", "zfail"):
                t = median_seconds(lambda: r.render(method, sil), args.repeat)
                print(f"  shadowed, {sil} silhouettes, {method:5s}  {t * 1e3:8.1f} ms   "
                      f"{t / plain:5.2f}x unshadowed")

    spot = point.replace(lights=(SpotLight([2.0, 6.0, 3.0], [-0.3, -1.0, -0.5],
                                           cone_angle=45.0),))
    with Renderer(spot, ctx) as r:
        ours = median_seconds(lambda: r.render("auto", "cpu"), args.repeat)
    print(f"  spot light, shadowed (auto, cpu)  {ours * 1e3:8.1f} ms")
    if not args.no_pyrender:
        # pyrender through the project's bridge (its NumPy 2 / EGL shims live there only)
        from shadowvol import pyrender_bridge as pb

        pr_scene = pb.to_pyrender(spot)
        flags = pb._flags(shadows=True)
        with pb._offscreen(spot.width, spot.height) as pr:
            theirs = median_seconds(lambda: pr.render(pr_scene, flags=flags), args.repeat)
        make_current(ctx)
        print(f"  spot light, pyrender shadow map   {theirs * 1e3:8.1f} ms   "
              f"ours / pyrender = {ours / theirs:5.2f}")
    ctx.release()


if __name__ == "__main__":
    main()
