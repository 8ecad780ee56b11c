"""Exact soft shadows against counted samples (BENCHMARKS.md, "Exact soft shadows"): one run,
wall-clock seconds.

    python -m benchmarks.bench_exact_soft [WIDTH]

scenes/soft.toml at WIDTH x 3/4 WIDTH (default 96): `exact_visibility` (both outputs) against
`soft_masks` with the light's 64, 256 and 1024 stratified samples; and a closed non-convex
mesh (a noisy icosphere, 5,120 triangles) over a floor under a rect light at 48 x 48, with and
without the back-face cull of closed objects (`exact_soft._candidates`' `clear`)."""

from __future__ import annotations

import dataclasses
import os
import sys
import time

import numpy as np
import trimesh

import raytrace.exact_soft as exact_soft
from raytrace.soft import soft_masks
from shadowvol.primitives import mesh, plane
from shadowvol.scene import AreaLight, Camera, Material, Scene
from shadowvol.scenefile import load_scene


def timed(f):
    t = time.perf_counter()
    f()
    return time.perf_counter() - t


def blob_scene(size: int) -> Scene:
    ico = trimesh.creation.icosphere(subdivisions=4, radius=0.5)
    rng = np.random.default_rng(0)
    v = ico.vertices * (1 + 0.08 * rng.standard_normal((len(ico.vertices), 1))) + [0.1, 1, -0.1]
    matte = Material(diffuse=[0.8, 0.8, 0.8])
    light = AreaLight("rect", [0.0, 2.5, 0.0], normal=[0, -1, 0], size=[1.2, 1.2], samples=4)
    return Scene(camera=Camera(eye=[0, 4.5, 5.5], target=[0, 0, -0.5], fov_y=40.0),
                 objects=[plane("floor", size=[8, 8], material=matte),
                          mesh("blob", v, np.asarray(ico.faces), material=matte)],
                 lights=[light], width=size, height=size, ambient=[0, 0, 0])


def main() -> None:
    width = int(sys.argv[1]) if len(sys.argv) > 1 else 96
    print(f"load {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    scene = load_scene("scenes/soft.toml").replace(width=width, height=width * 3 // 4)
    print(f"soft.toml {scene.width}x{scene.height}: exact "
          f"{timed(lambda: exact_soft.exact_visibility(scene)):.2f} s")
    light = scene.lights[0]
    for n in (64, 256, 1024):
        counted = scene.replace(lights=[dataclasses.replace(light, samples=n)])
        print(f"  counting {n}: {timed(lambda: soft_masks(counted)):.2f} s")
    blob = blob_scene(48)
    print(f"blob ({len(blob.triangles()[1]) - 2} triangles) 48x48: exact "
          f"{timed(lambda: exact_soft.exact_visibility(blob)):.2f} s with the cull")
    plain = exact_soft._candidates
    exact_soft._candidates = lambda *a, **k: plain(*a[:8])
    try:
        print(f"  without it {timed(lambda: exact_soft.exact_visibility(blob)):.2f} s")
    finally:
        exact_soft._candidates = plain
    for n in (64, 256, 1024):
        counted = blob.replace(lights=[dataclasses.replace(blob.lights[0], samples=n)])
        print(f"  counting {n}: {timed(lambda: soft_masks(counted)):.2f} s")


if __name__ == "__main__":
    main()
