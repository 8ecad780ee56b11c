"""Exact soft shadows against counted samples (BENCHMARKS.md, "Exact soft shadows"): one run,
milliseconds per frame, wall clock and CPU.

    python -m benchmarks.bench_exact_soft [--width WIDTH] [--medians N | --light-sides |
                                           --paired DIR [--rounds N]]

Three frames under one rect light each: scenes/soft.toml at WIDTH x 3/4 WIDTH (default 96;
closed convex bodies; then by size up to its own 640 x 480, exact against the bare count), a
closed non-convex mesh (a noisy icosphere, 5,120 triangles) over a floor at 48 x 48, and the
shared bunny (69,451 triangles, open at its base) on a floor at 32 x 32.  Each:
`exact_visibility` (both outputs) with its fast path (`raytrace.arrange`) on a thread per
core and on one thread (`arrange.THREADS`), with the fast path off (every
triangle's shadow united one by one: the reference of `tests/raytrace/test_exact_fast.py`),
and counting the light's 64, 256 and 1024 stratified samples: the bare count
(`raytrace.soft.lit_counts`, what `raytrace.shadow_masks` counts an area light by: the peer
the ratios are taken against), and at 256 also the count of `raytrace masks --outputs
lit_count` (`ground_truth`, which counts the facing samples on the same rays) and
`soft_masks` (the count, then a second pass for its `facing`).  Then the bunny at 16 x 16,
32 x 32, 64 x 64, 128 x 128 and 256 x 256: exact (and pixel by pixel: no block of pixels
sharing its outline, `exact_soft.BLOCK` 0) against the bare count of 256 samples, and what
a pixel more costs each (the slope between the two largest frames), so the fixed cost of a
frame (the scene's Embree build, the objects' topology) is told apart from the per-pixel
one.  With --medians N: instead, each frame's exact visibility (on a thread per core, and
on one) and the three counts of 256 samples (each on the threads its tiles allow: one at
these sizes) called in turn N times in one process after a warm-up, the median CPU ms of
each (soft.toml at WIDTH and at its own 640 x 480, the blob 48 x 48, the bunny at 32, 64,
128 and 256) and the wall ms of the
exact visibility and the bare count: steadier on a noisy machine than one call; "paired",
the median of each exact call's CPU over the count's called just after it in the same round
(a slow minute slows both).  With
--light-sides: instead, the bunny 128 x 128 under square rect lights of side 0.125 to 2
(`light_sides`): where the exact path costs less than the count and where more.  With
--paired DIR: instead, this checkout's exact visibility against that of the `raytrace`
package in DIR (an older one: `git archive REV raytrace | tar -x -C DIR`), both in this
process (`paired`): a change of a few percent, which the medians of separate runs cannot
resolve on a shared machine."""

from __future__ import annotations

import argparse
import atexit
import contextlib
import dataclasses
import importlib
import os
import random
import shutil
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import trimesh

import raytrace.arrange as arrange
import raytrace.exact_soft as exact_soft
from benchmarks.bench_masks import BUNNY, bunny_scene
from raytrace.groundtruth import ground_truth
from raytrace.soft import lit_counts, soft_masks
from shadowvol.primitives import mesh, plane
from shadowvol.scene import AreaLight, Camera, Material, Scene
from shadowvol.scenefile import load_scene


def timed(f) -> str:
    """Milliseconds of one call: wall clock, and the CPU time of this process's threads
    (what the call costs a core of its own, when others share the machine)."""
    wall, cpu = clocked(f)
    return f"{wall:.0f} ({cpu:.0f} cpu)"


def clocked(f) -> tuple[float, float]:
    """(wall, CPU) milliseconds of one call of f."""
    t, c = time.perf_counter(), time.process_time()
    f()
    return (time.perf_counter() - t) * 1e3, (time.process_time() - c) * 1e3


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


def bunny_rect_scene(size: int) -> Scene:
    """`bench_masks.bunny_scene` (1.5 units tall) under a 1 x 1 rect light, tilted."""
    light = AreaLight("rect", [-1.0, 3.0, 1.0], normal=[0.3, -1, -0.3], size=[1.0, 1.0],
                      samples=4)
    return bunny_scene(size, size).replace(lights=(light,))


@contextlib.contextmanager
def knobs(**values):
    """`exact_soft`'s module knobs set to values for the block, then back."""
    before = {name: getattr(exact_soft, name) for name in values}
    for name, value in values.items():
        setattr(exact_soft, name, value)
    try:
        yield
    finally:
        for name, value in before.items():
            setattr(exact_soft, name, value)


def reference(scene: Scene) -> None:
    """`exact_visibility` with its fast paths off: no outline unions, no windings, no
    block's shared outline."""
    with knobs(MANY_PIECES=1 << 62, WINDING_PIECES=1 << 62, BLOCK=0):
        exact_soft.exact_visibility(scene)


def pixel_by_pixel(scene: Scene) -> None:
    """`exact_visibility` with no block's shared outline (`exact_soft.BLOCK` 0)."""
    with knobs(BLOCK=0):
        exact_soft.exact_visibility(scene)


def one_thread(scene: Scene) -> None:
    threads, arrange.THREADS = arrange.THREADS, 1
    try:
        exact_soft.exact_visibility(scene)
    finally:
        arrange.THREADS = threads


def frame(name: str, scene: Scene) -> None:
    triangles = len(scene.triangles()[1])
    print(f"{name} ({triangles} triangles) {scene.width}x{scene.height}, ms per frame:")
    print(f"  exact: {timed(lambda: exact_soft.exact_visibility(scene))}", flush=True)
    print(f"  exact, one thread: {timed(lambda: one_thread(scene))}", flush=True)
    print(f"  exact, pixel by pixel: {timed(lambda: pixel_by_pixel(scene))}", flush=True)
    print(f"  exact, fast path off: {timed(lambda: reference(scene))}", flush=True)
    for n in (64, 256, 1024):
        counted = with_samples(scene, n)
        print(f"  counting {n}: {timed(lambda: lit_counts(counted))}", flush=True)
    counted = with_samples(scene, 256)
    print(f"  counting 256, raytrace masks' (ground_truth): "
          f"{timed(lambda: ground_truth(counted, ()))}", flush=True)
    print(f"  counting 256, soft_masks (and its facing pass): "
          f"{timed(lambda: soft_masks(counted))}", flush=True)


def with_samples(scene: Scene, n: int) -> Scene:
    """`scene` with its (first) area light's samples set to n."""
    return scene.replace(lights=[dataclasses.replace(scene.lights[0], samples=n)])


def per_pixel(sizes=(16, 32, 64, 128, 256)) -> None:
    """The bunny's frame cost against its size: exact, exact pixel by pixel and the bare count
    of 256 samples (CPU ms), and the CPU a pixel more costs each between the two largest
    frames."""
    print("bunny by frame size, CPU ms a frame (exact / pixel by pixel / counting 256):")
    cost = {}
    for n in sizes:
        scene = bunny_rect_scene(n)
        counted = with_samples(scene, 256)
        cost[n] = (clocked(lambda: exact_soft.exact_visibility(scene))[1],
                   clocked(lambda: pixel_by_pixel(scene))[1],
                   clocked(lambda: lit_counts(counted))[1])
        print(f"  {n}x{n}: {cost[n][0]:.0f} / {cost[n][1]:.0f} / {cost[n][2]:.0f}", flush=True)
    a, b = sizes[-2:]
    more = b * b - a * a
    slope = [(cost[b][k] - cost[a][k]) / more for k in (0, 1, 2)]
    print(f"  a pixel more ({a}x{a} -> {b}x{b}): exact {slope[0]:.3f} ms, pixel by pixel "
          f"{slope[1]:.3f} ms, counting 256 {slope[2]:.3f} ms "
          f"({slope[0] / max(slope[2], 1e-9):.1f}x)")


def soft_by_size(widths=(96, 192, 320, 640)) -> None:
    """scenes/soft.toml at each of `widths` (up to its own 640x480): exact and the bare count
    of 256 samples (CPU ms, the median of three calls each in turn): the goal at the size a
    user renders it."""
    print("soft.toml by frame size, CPU ms a frame (exact / counting 256, the median of 3):")
    for w in widths:
        scene = _soft(w)
        counted = with_samples(scene, 256)
        calls = (lambda: exact_soft.exact_visibility(scene), lambda: lit_counts(counted))
        got = [[clocked(call)[1] for call in calls] for _ in range(3)]
        a, b = np.median(got, axis=0)
        print(f"  {w}x{w * 3 // 4}: {a:.0f} / {b:.0f} = {a / b:.2f}x", flush=True)


def _soft(width: int) -> Scene:
    """scenes/soft.toml `width` wide (its own: 640x480)."""
    return load_scene("scenes/soft.toml").replace(width=width, height=width * 3 // 4)


def _frames(width: int, bunny_sizes, own: bool = True) -> list[tuple[str, Scene]]:
    """(name, scene): soft.toml `width` wide and, with `own`, at its own 640x480, the blob
    48x48, and the bunny at each of `bunny_sizes` where its mesh is at hand."""
    frames = [(f"soft.toml {width}x{width * 3 // 4}", _soft(width))]
    frames += [("soft.toml 640x480 (its own size)", _soft(640))] if own else []
    frames += [("blob 48x48", blob_scene(48))]
    if BUNNY.is_file():
        frames += [(f"bunny {k}x{k}", bunny_rect_scene(k)) for k in bunny_sizes]
    return frames


def medians(width: int, n: int, bunny_sizes=(32, 64, 128, 256), own: bool = True) -> None:
    """`--medians n`: see the module."""
    print(f"exact / counting 256 (the bare count), median CPU ms of {n} calls each in turn; "
          "then raytrace masks' count and soft_masks':")
    frames = _frames(width, bunny_sizes, own)
    for name, scene in frames:
        counted = with_samples(scene, 256)
        calls = (lambda: exact_soft.exact_visibility(scene), lambda: lit_counts(counted),
                 lambda: one_thread(scene), lambda: ground_truth(counted, ()),
                 lambda: soft_masks(counted))
        for call in calls:
            call()
        times, walls = [[] for _ in calls], [[] for _ in calls]
        for _ in range(n):
            for call, got, wall in zip(calls, times, walls):
                w, c = clocked(call)
                got.append(c)
                wall.append(w)
        (ma, mb, m1, mg, ms), (a, b) = [float(np.median(t)) for t in times], times[:2]
        wa, wb = float(np.median(walls[0])), float(np.median(walls[1]))
        pair = float(np.median(np.array(a) / np.array(b)))    # each call's with its count's
        print(f"  {name}: {ma:.0f} / {mb:.0f} = {ma / mb:.2f}x (exact {min(a):.0f}-{max(a):.0f}, "
              f"counted {min(b):.0f}-{max(b):.0f}; paired {pair:.2f}x; wall {wa:.0f} / {wb:.0f}"
              f" = {wa / wb:.2f}x); exact on one thread {m1:.0f} ({m1 / mb:.2f}x); raytrace "
              f"masks' count {mg:.0f} ({ma / mg:.2f}x), soft_masks' {ms:.0f} ({ma / ms:.2f}x)",
              flush=True)


def light_sides(size: int = 128, sides=(0.125, 0.25, 0.5, 0.75, 1.0, 2.0), calls: int = 5,
                make=None) -> None:
    """`--light-sides`: the bunny at size x size (`make(size)`: another frame) under square
    rect lights of each side (the frame's light is 1 x 1): the penumbra's share of the frame
    (pixels with 0 < V < 1), and the median CPU ms of the exact visibility and of the bare
    count of 256 samples, called in turn `calls` times in one process.  The count costs the
    same under any light; the exact path pays for each penumbra pixel, more for a larger
    light (its pyramid holds more triangles, its outline more edges)."""
    make = make or bunny_rect_scene
    print(f"{size}x{size} by the light's side, median CPU ms of {calls} calls each in turn "
          "(exact / counting 256):")
    base = make(size)
    for side in sides:
        scene = base.replace(lights=[dataclasses.replace(base.lights[0], size=[side, side])])
        counted = with_samples(scene, 256)
        exact = exact_soft.exact_visibility(scene).visibility[0]
        lit_counts(counted)
        penumbra = float(((exact > 0) & (exact < 1)).mean())
        times = ([], [])
        for _ in range(calls):
            times[0].append(clocked(lambda: exact_soft.exact_visibility(scene))[1])
            times[1].append(clocked(lambda: lit_counts(counted))[1])
        a, b = (float(np.median(t)) for t in times)
        print(f"  side {side:g}: penumbra {penumbra:.1%} of the frame, {a:.0f} / {b:.0f} = "
              f"{a / b:.2f}x", flush=True)


def other_exact_soft(root: str):
    """The `exact_soft` module of the `raytrace` package in the directory `root`, imported
    beside this checkout's as `raytrace_paired` (a copy in a temporary directory, removed at
    exit, its numba kernels compiled afresh on the first call; the package imports its own
    modules relatively, and this checkout's `shadowvol`)."""
    source = Path(root) / "raytrace"
    if not (source / "exact_soft.py").is_file():
        raise SystemExit(f"--paired {root}: no raytrace/exact_soft.py there")
    where = tempfile.mkdtemp(prefix="paired-")
    atexit.register(shutil.rmtree, where, True)
    shutil.copytree(source, Path(where) / "raytrace_paired",
                    ignore=shutil.ignore_patterns("__pycache__"))
    sys.path.insert(0, where)
    for name in [m for m in sys.modules if m.split(".")[0] == "raytrace_paired"]:
        del sys.modules[name]                    # an earlier DIR's
    return importlib.import_module("raytrace_paired.exact_soft")


def paired(other, rounds: int = 21, bunny_sizes=(64, 128, 256), width: int = 96,
           own: bool = True) -> None:
    """`--paired DIR`: `other` (`other_exact_soft`'s module, the old) against this checkout's
    `exact_soft` (the new) on soft.toml, the blob 48x48 and the bunny at `bunny_sizes`: each
    frame's two calls in a random order each round, then the bare count of 256 samples, after
    a call each; the median CPU ms of each, the median of the rounds' new / old (and its
    quartiles: the same code paired with itself gives ~0.98-1.0x over 21 rounds here), each
    one's median ratio to its round's count, and whether V and the irradiance are the same
    bytes (else their largest differences)."""
    print(f"this checkout (new) against {other.__name__} (old), {rounds} rounds, median CPU ms "
          "(paired: the median of the rounds' ratios):")
    frames = _frames(width, bunny_sizes, own)
    order = random.Random(1)
    for name, scene in frames:
        counted = with_samples(scene, 256)
        was, now = other.exact_visibility(scene), exact_soft.exact_visibility(scene)
        lit_counts(counted)
        dv = float(np.abs(now.visibility - was.visibility).max(initial=0.0))
        de = float(np.abs(now.irradiance - was.irradiance).max(initial=0.0))
        calls = {"old": lambda: other.exact_visibility(scene),
                 "new": lambda: exact_soft.exact_visibility(scene),
                 "count": lambda: lit_counts(counted)}
        times = {key: [] for key in calls}
        for _ in range(rounds):
            turn = order.sample(["old", "new"], 2) + ["count"]
            for key in turn:
                times[key].append(clocked(calls[key])[1])
        t = {key: np.array(v) for key, v in times.items()}
        ratio = t["new"] / t["old"]
        q1, q3 = np.percentile(ratio, [25, 75])
        same = "the same bytes" if dv == de == 0 else f"|dV| <= {dv:.1e}, |dE| <= {de:.1e}"
        print(f"  {name}: old {np.median(t['old']):.0f}, new {np.median(t['new']):.0f}, count "
              f"{np.median(t['count']):.0f}; new / old {np.median(ratio):.3f}x ({q1:.3f}-"
              f"{q3:.3f}); exact / count, old {np.median(t['old'] / t['count']):.3f}x, new "
              f"{np.median(t['new'] / t['count']):.3f}x; {same}", flush=True)


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.bench_exact_soft",
                                 description=__doc__.split("\n\n")[0])
    ap.add_argument("--width", type=int, default=96, help="soft.toml's width (default 96)")
    ap.add_argument("--medians", type=int, default=0, metavar="N",
                    help="each frame's exact and counted-256 CPU ms as the median of N calls")
    ap.add_argument("--paired", metavar="DIR",
                    help="instead, this checkout's exact visibility against DIR's raytrace")
    ap.add_argument("--rounds", type=int, default=21, help="--paired's rounds (default 21)")
    ap.add_argument("--light-sides", action="store_true",
                    help="instead, the bunny 128x128 under rect lights of six sizes")
    args = ap.parse_args(argv)
    width = args.width
    print(f"load {os.getloadavg()[0]:.2f} on {os.cpu_count()} cores")
    if args.paired:
        paired(other_exact_soft(args.paired), args.rounds, width=width)
        print(f"load {os.getloadavg()[0]:.2f}")
        return
    if args.light_sides:
        light_sides() if BUNNY.is_file() else print(f"bunny: {BUNNY} missing")
        print(f"load {os.getloadavg()[0]:.2f}")
        return
    if args.medians:
        medians(width, args.medians)
        print(f"load {os.getloadavg()[0]:.2f}")
        return
    # warm up first (imports, GEOS, the kernels' compilation), so the first frame's times are
    # its own
    tiny = load_scene("scenes/soft.toml").replace(width=8, height=6)
    exact_soft.exact_visibility(tiny)
    lit_counts(tiny)
    ground_truth(tiny, ())
    soft_masks(tiny)
    frame("soft.toml", _soft(width))
    soft_by_size()
    frame("blob", blob_scene(48))
    if BUNNY.is_file():
        frame("bunny", bunny_rect_scene(32))
        per_pixel()
    else:
        print(f"bunny: {BUNNY} missing")
    print(f"load {os.getloadavg()[0]:.2f}")


if __name__ == "__main__":
    main()
