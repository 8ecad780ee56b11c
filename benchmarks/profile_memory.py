"""Where the peak RSS of one frame comes from: VmRSS and VmHWM after each step of building the
scene and rendering one frame of it, and the peak within each step.

    python -m benchmarks.profile_memory --size 1M

The renderer's steps (the scene's geometry and its topologies, the uploads, the silhouettes and
side quads, each pass, the read-backs) are wrapped for the one frame, in this process: each
wrapper resets VmHWM to VmRSS (/proc/self/clear_refs) when it starts, so the peak it prints is
that step's own.  The process's true peak (VmHWM as `benchmarks.run`'s memory section reads
it) is the largest of them.  tracemalloc (--python) adds the Python heap's peak per step (numpy
arrays included; GL buffers are the driver's, not Python's: on llvmpipe a buffer is host
memory, so every array kept after its upload is a second copy).
"""

from __future__ import annotations

import argparse
import contextlib
import sys
import time
import tracemalloc

from . import scenes

MB = 2 ** 20


def status(key: str) -> float:
    for line in open("/proc/self/status"):
        if line.startswith(key + ":"):
            return int(line.split()[1]) / 1024
    return float("nan")


class Steps:
    """The peak of each step: a stack of the steps open, each with the highest VmHWM seen
    while it was open (a nested step's reset of VmHWM passes its peak up first)."""

    def __init__(self, python: bool):
        self.stack: list[list] = []
        self.rows: list[tuple] = []
        self.python = python
        self.peak = 0.0

    def _seen(self) -> float:
        hwm = status("VmHWM")
        self.peak = max(self.peak, hwm)
        for frame in self.stack:
            frame[1] = max(frame[1], hwm)
        return hwm

    def _reset(self) -> None:
        self._seen()
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")

    @contextlib.contextmanager
    def step(self, name: str):
        self._reset()
        if self.python:
            tracemalloc.reset_peak()
        before = status("VmRSS")
        frame = [name, before]
        self.stack.append(frame)
        t0 = time.perf_counter()
        try:
            yield
        finally:
            seconds = time.perf_counter() - t0
            self._seen()
            self.stack.pop()
            py = tracemalloc.get_traced_memory() if self.python else (0, 0)
            self.rows.append((len(self.stack), name, before, status("VmRSS"), frame[1],
                              py[0] / MB, py[1] / MB, seconds))
            self._reset()

    def wrap(self, owner, attr: str, name: str | None = None):
        """Time `owner.attr` as a step (nothing if it has no such attribute: an older
        checkout, profiled for comparison)."""
        original = getattr(owner, attr, None)
        if original is None:
            return
        label = name or f"{getattr(owner, '__name__', owner)}.{attr}"

        def wrapped(*args, **kwargs):
            with self.step(label):
                return original(*args, **kwargs)

        setattr(owner, attr, wrapped)

    def print(self) -> None:
        head = f"{'step':<52} {'RSS before':>10} {'after':>8} {'peak':>8}"
        if self.python:
            head += f" {'py now':>8} {'py peak':>8}"
        print(head + f" {'s':>6}")
        # the same step repeated under one parent (one per object) as one row: the first's
        # RSS before, the last's after, the highest peak, the summed time
        rows: list[list] = []
        open_rows: dict[tuple, list] = {}
        for row in self.rows:
            depth = row[0]
            open_rows = {k: v for k, v in open_rows.items() if k[0] <= depth}
            last = open_rows.get(row[:2])
            if last is None:
                rows.append(list(row) + [1])
                open_rows[row[:2]] = rows[-1]
            else:
                last[3], last[4], last[5] = row[3], max(last[4], row[4]), row[5]
                last[6], last[7], last[8] = max(last[6], row[6]), last[7] + row[7], last[8] + 1
        for depth, name, before, after, peak, py_now, py_peak, seconds, n in rows:
            name = name + (f" (x{n})" if n > 1 else "")
            line = f"{'  ' * depth + name:<52} {before:>10.0f} {after:>8.0f} {peak:>8.0f}"
            if self.python:
                line += f" {py_now:>8.0f} {py_peak:>8.0f}"
            print(line + f" {seconds:>6.2f}")
        print(f"process peak (VmHWM since exec, as run.py reads it): {self.peak:.0f} MB")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--size", default="1M", choices=list(scenes.SIZES))
    ap.add_argument("--python", action="store_true", help="tracemalloc the Python heap too "
                    "(slower; its own bookkeeping adds to the RSS)")
    ap.add_argument("--masks", action="store_true", help="profile raytrace.shadow_masks "
                    "instead of the frame")
    args = ap.parse_args(argv)
    steps = Steps(args.python)
    if args.python:
        tracemalloc.start()
    print(f"after imports: VmRSS {status('VmRSS'):.0f} MB, VmHWM {status('VmHWM'):.0f} MB")
    with steps.step("scene build (benchmarks/scenes.py)"):
        scene = scenes.occluder_scene(args.size, 1, 1280, 720)
    if args.masks:
        from raytrace import shadow_masks
        with steps.step("raytrace.shadow_masks"):
            shadow_masks(scene)
        steps.print()
        return 0

    from shadowvol.raster import geometry, passes, programs, renderer, target
    from shadowvol.raster.overflow import detect
    from shadowvol.raster.platform import context
    from shadowvol.raster.volumes import cpu, silhouettes, topology

    steps.wrap(context, "create_context")
    renderer.create_context = context.create_context
    steps.wrap(geometry.SceneGeometry, "__init__", "SceneGeometry (soup, normals, uploads)")
    steps.wrap(topology.Topology, "build", "Topology.build (one object)")
    steps.wrap(geometry.SceneGeometry, "_soup_buffer", "soup buffer upload")
    steps.wrap(geometry.SceneGeometry, "_frame_corners", "frame corners (float32, kept)")
    steps.wrap(target.Target, "__init__", "Target (G-buffer)")
    steps.wrap(programs.ScenePrograms, "__init__", "ScenePrograms")
    steps.wrap(cpu.CpuVolumes, "__init__", "CpuVolumes")
    steps.wrap(cpu.CpuVolumes, "_build", "silhouettes + side quads + upload")
    for name in ("topology_signs", "edge_multiplicity", "side_quads", "quads_to_triangles"):
        steps.wrap(silhouettes, name)
        setattr(cpu, name, getattr(silhouettes, name))
    steps.wrap(cpu.CpuVolumes, "_framed", "side triangles to the frame")
    steps.wrap(detect, "count_bound", "overflow bound (count_bound)")
    steps.wrap(geometry.SceneGeometry, "move_to")
    steps.wrap(geometry.SceneGeometry, "set_view")
    for name in ("geometry_pass", "count_signed", "mark_unshadowed", "shade"):
        steps.wrap(passes, name)
    for name in ("read_bits", "read_image"):
        steps.wrap(target.Target, name)
    with steps.step("Renderer(scene)"):
        r = renderer.Renderer(scene)
    with steps.step("render() (first frame)"):
        r.render()
    with steps.step("render() (second frame, same camera)"):
        r.render()
    steps.print()
    r.release()
    return 0


if __name__ == "__main__":
    sys.exit(main())
