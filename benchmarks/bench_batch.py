"""Benchmark (not a test): `shadowvol batch` throughput and the cost of its machinery.

    python -m benchmarks.bench_batch [--models DIR] [--frames 36] [--width 640 --height 480]
                                     [--rounds 3] [--no-ray] [--json out.json]

The scene: the five shared meshes (../shared/models beside the checkout, or $SHADOWVOL_MODELS,
or --models: bunny, teapot, Suzanne, Spot, lamp shade, ~84k triangles) in a row on a floor,
three lights (point, directional, spot), a turntable of 36 views at 640x480, image + masks.
`measure()` returns a dict; it times, each from a fresh output folder, every variant once per
round for `--rounds` rounds, interleaved (medians, min-max, and the 2-worker / 1-worker ratio
of each round):

* 1 worker (this process), 2 worker processes, 2 shards run in parallel as two `shadowvol batch
  --shard I/2` commands, and Ray with 2 actors (a local ray.init(num_cpus=2), its start-up
  timed apart): frames/s of the whole run, start-up included, as a user sees it;
* the bare loop: the same frames by one Renderer with nothing written, and the batch
  machinery per frame (manifest line, sha256, atomic write), from the 1-worker manifest and a
  micro-benchmark of the journal, as a fraction of a frame.

When the models folder is absent it returns {"skipped": reason} and says so.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
MODELS = Path(os.environ.get("SHADOWVOL_MODELS", ROOT.parent / "shared" / "models"))
NAMES = ("bunny", "teapot", "suzanne", "spot", "lampshade")


def _bounds(path: Path) -> tuple[np.ndarray, np.ndarray]:
    import trimesh

    v = np.asarray(trimesh.load(str(path), process=False).vertices)
    return v.min(axis=0), v.max(axis=0)


def write_scene(folder: Path, models: Path, width: int, height: int) -> Path:
    """The benchmark scene as a scene file (meshes by absolute path, each scaled to 1.2 units
    and stood on the floor along x)."""
    lines = ['name = "models"', "ambient = [0.15, 0.15, 0.15]", "",
             f"[image]\nwidth = {width}\nheight = {height}\n",
             "[camera]\neye = [0.0, 2.5, 6.0]\ntarget = [0.0, 0.5, 0.0]\nfov_y = 50.0\n",
             '[[lights]]\ntype = "point"\nposition = [1.5, 3.5, 2.0]\nintensity = 0.6\n',
             '[[lights]]\ntype = "directional"\ndirection = [-0.4, -1.0, -0.3]\n'
             'intensity = 0.4\n',
             '[[lights]]\ntype = "spot"\nposition = [-2.0, 3.5, 1.5]\n'
             'direction = [0.5, -1.0, -0.4]\ncone_angle = 40.0\nintensity = 0.5\n',
             '[[objects]]\nname = "floor"\ntype = "plane"\npoint = [0.0, 0.0, 0.0]\n'
             'normal = [0.0, 1.0, 0.0]\nsize = [10.0, 10.0]\n']
    for i, name in enumerate(NAMES):
        path = models / f"{name}.obj"
        lo, hi = _bounds(path)
        scale = 1.2 / float((hi - lo).max())
        centre = (lo + hi) / 2 * scale
        x = -3.0 + 1.5 * i
        translation = [x - centre[0], -lo[1] * scale, -centre[2]]
        lines.append(f'[[objects]]\nname = "{name}"\ntype = "mesh"\n'
                     f"path = {json.dumps(str(path))}\n"
                     f"transform = {{ scale = {scale!r}, translation = "
                     f"[{', '.join(repr(float(t)) for t in translation)}] }}\n")
    scene = folder / "models.toml"
    scene.write_text("\n".join(lines))
    return scene


def write_jobs(folder: Path, scene: Path, frames: int) -> Path:
    job = {"name": "models-turntable", "scene": str(scene),
           "cameras": {"orbit": {"center": [0.0, 0.5, 0.0], "radius": 6.0, "elevation": 25.0,
                                 "frames": frames}},
           "outputs": ["image", "masks"]}
    path = folder / "turntable.jsonl"
    path.write_text(json.dumps(job) + "\n")
    return path


def _records(out: Path, name: str = "manifest.jsonl") -> list[dict]:
    return [json.loads(line) for line in (out / name).read_text().splitlines()]


def _cpu() -> float:
    """CPU seconds used so far by this process and its finished children."""
    me = resource.getrusage(resource.RUSAGE_SELF)
    kids = resource.getrusage(resource.RUSAGE_CHILDREN)
    return me.ru_utime + me.ru_stime + kids.ru_utime + kids.ru_stime


def _autogroup() -> bool | None:
    """Whether Linux shares the CPU between sessions (then all of this session's processes
    together get one session's share while other sessions are busy)."""
    try:
        return Path("/proc/sys/kernel/sched_autogroup_enabled").read_text().strip() == "1"
    except OSError:
        return None


def _env() -> dict:
    paths = [str(ROOT)] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]
    return dict(os.environ, PYTHONPATH=os.pathsep.join(paths))


def _one_run(label: str, jobs: Path, out: Path, frames: int) -> dict:
    """One run of `label` into the fresh folder `out`: seconds, and CPU seconds per frame of
    this process and its children (None for Ray, whose actors are not our children)."""
    import shadowvol.batch as batch

    cpu, start = _cpu(), time.perf_counter()
    if label == "shards_2":
        shards = [subprocess.Popen([sys.executable, "-m", "shadowvol", "batch", str(jobs), "-o",
                                    str(out), "--shard", f"{i}/2"], env=_env(),
                                   stderr=subprocess.DEVNULL) for i in (0, 1)]
        assert [p.wait() for p in shards] == [0, 0]
    else:
        kwargs = {"workers_1": {}, "workers_2": {"workers": 2},
                  "ray_2": {"workers": 2, "ray": True}}[label]
        summary = batch.run(jobs, out, progress=False, **kwargs)
        assert summary.status == 0 and summary.rendered == frames, summary.errors
    seconds = time.perf_counter() - start
    return {"seconds": seconds,
            "cpu_s_per_frame": None if label == "ray_2" else (_cpu() - cpu) / frames}


# a fixed single-threaded CPU job (zlib over 1 MB of numbers, no GL, no threads): what the
# machine itself gives two processes at once
_PROBE = """
import time, zlib
data = bytes(range(256)) * 4096
t = time.perf_counter()
for _ in range(%d):
    zlib.compress(data, 6)
print(time.perf_counter() - t)
"""
PROBE_LOOPS = 300


def _probe() -> dict:
    """The machine's own scaling: the probe job alone, then two copies at once; the throughput
    of the pair over the one (2.0 on two free, independent cores).  No program of two
    processes scales better on this machine at that moment."""
    code = _PROBE % PROBE_LOOPS

    def run(n: int) -> list[float]:
        procs = [subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE,
                                  text=True) for _ in range(n)]
        return [float(p.communicate()[0]) for p in procs]

    alone = run(1)[0]
    pair = run(2)
    return {"alone_s": alone, "pair_s": pair, "scaling": 2 * alone / max(pair)}


def _summary(runs: list[dict], frames: int) -> dict:
    seconds = [r["seconds"] for r in runs]
    median = statistics.median(seconds)
    cpu = [r["cpu_s_per_frame"] for r in runs if r["cpu_s_per_frame"] is not None]
    return {"seconds": median, "min_s": min(seconds), "max_s": max(seconds),
            "frames_per_s": frames / median, "runs": runs,
            "cpu_s_per_frame": statistics.median(cpu) if cpu else None,
            "cores": statistics.median(r["cpu_s_per_frame"] * frames / r["seconds"]
                                       for r in runs) if cpu else None}


def _variants(ray: bool, result: dict) -> tuple[list[str], object]:
    """The run variants, and the ray module when Ray is asked for and installed (else a
    "skipped" entry in `result`)."""
    labels = ["workers_1", "workers_2", "shards_2"]
    if not ray:
        return labels, None
    try:
        import ray as ray_module
    except ImportError:
        result["ray_2"] = {"skipped": "ray is not installed (pip install 'shadowvol[ray]')"}
        return labels, None
    return labels + ["ray_2"], ray_module


def _rounds(labels: list[str], ray_module, jobs: Path, tmp: Path, frames: int,
            rounds: int) -> tuple[dict[str, list[dict]], list[float], list[dict]]:
    """Every variant once per round, each round starting with the next one: the runs per
    variant, Ray's start-up times and the machine's scaling probe of each round."""
    runs: dict[str, list[dict]] = {label: [] for label in labels}
    ray_init, probes = [], []
    for r in range(rounds):
        probes.append(_probe())
        for label in labels[r % len(labels):] + labels[:r % len(labels)]:
            out = tmp / f"{label}-{r}"
            if label == "ray_2":  # up only for its own run: its daemons would load the others
                start = time.perf_counter()
                ray_module.init(num_cpus=2, include_dashboard=False, log_to_driver=False)
                ray_init.append(time.perf_counter() - start)
                try:
                    runs[label].append(_one_run(label, jobs, out, frames))
                finally:
                    ray_module.shutdown()
            else:
                runs[label].append(_one_run(label, jobs, out, frames))
    return runs, ray_init, probes


def _check_same_outputs(jobs: Path, tmp: Path, frames: int, rounds: int) -> None:
    """The same outputs whichever way they were made (the shards' once merged)."""
    import shadowvol.batch as batch

    ref = [(r["id"], r["files"]) for r in _records(tmp / "workers_1-0")]
    for label in ("workers_2", "ray_2"):
        for r in range(rounds):
            if (tmp / f"{label}-{r}" / "manifest.jsonl").exists():
                assert [(x["id"], x["files"]) for x in _records(tmp / f"{label}-{r}")] == ref, \
                    label
    merged = batch.run(jobs, tmp / "shards_2-0", progress=False)
    assert merged.skipped == frames and [(r["id"], r["files"]) for r in
                                         _records(tmp / "shards_2-0")] == ref


def _per_frame(scene, tmp: Path, rounds: int) -> dict:
    """The bare loop (one Renderer, the 1-worker run's cameras, nothing encoded or written)
    against the batch's own per-frame seconds and a micro-benchmark of the journal."""
    from shadowvol import Camera, Renderer
    from shadowvol.batch import manifest

    cameras = [r["camera"] for r in _records(tmp / "workers_1-0")]
    with Renderer(scene) as renderer:
        renderer.render()  # warm-up
        bare = []
        for cam in cameras:
            t = time.perf_counter()
            renderer.render(camera=Camera(**cam))
            bare.append(time.perf_counter() - t)
    frame = statistics.median(bare)
    records = [x for r in range(rounds) for x in _records(tmp / f"workers_1-{r}")]
    render = statistics.median(r["seconds"]["render"] for r in records)
    encode = statistics.median(r["seconds"]["encode"] for r in records)
    write = statistics.median(r["seconds"]["write"] for r in records)  # sha256 + atomic writes
    journal = manifest.Journal(tmp / "journal-bench.jsonl")
    t = time.perf_counter()
    for r in records * 10:
        journal.add(r)
    line = (time.perf_counter() - t) / (len(records) * 10)
    journal.close()
    return {"bare_render_s": frame, "batch_render_s": render, "encode_s": encode,
            "write_and_hash_s": write, "manifest_line_s": line,
            "machinery_fraction": (write + line) / frame,
            "machinery_and_encoding_fraction": (write + line + encode) / frame}


def measure(models: Path = MODELS, frames: int = 36, width: int = 640, height: int = 480,
            ray: bool = True, rounds: int = 3) -> dict:
    """Every run variant once per round, interleaved (each round starts with the next variant,
    so that a drift of the machine's load falls on all of them); medians over the rounds, and
    the 2-worker / 1-worker ratio of each round."""
    if not all((models / f"{n}.obj").is_file() for n in NAMES):
        return {"skipped": f"the shared models are missing: {models} does not hold "
                           f"{', '.join(n + '.obj' for n in NAMES)} (set $SHADOWVOL_MODELS or "
                           f"--models)"}
    from shadowvol import load_scene

    tmp = Path(tempfile.mkdtemp(prefix="bench_batch-"))
    scene_path = write_scene(tmp, models, width, height)
    jobs = write_jobs(tmp, scene_path, frames)
    scene = load_scene(scene_path)
    result = {"frames": frames, "size": [width, height], "lights": len(scene.lights),
              "triangles": int(sum(len(o.faces) for o in scene.objects)),
              "cores": len(os.sched_getaffinity(0)), "load_before": os.getloadavg()[0],
              "autogroup": _autogroup(), "rounds": rounds}
    labels, ray_module = _variants(ray, result)
    runs, ray_init, probes = _rounds(labels, ray_module, jobs, tmp, frames, rounds)
    for label in labels:
        result[label] = _summary(runs[label], frames)
    if ray_init:
        result["ray_init_s"] = statistics.median(ray_init)
    scaling = [p["scaling"] for p in probes]
    result["probe"] = {"scaling": statistics.median(scaling), "min": min(scaling),
                       "max": max(scaling), "runs": probes}
    # 2 workers can at best use what the machine gives two processes, at the 1-worker frame's
    # CPU cost: (probe scaling) / (cores 1 worker already uses) times its frames
    result["ceiling_workers_2"] = result["probe"]["scaling"] / result["workers_1"]["cores"]
    _check_same_outputs(jobs, tmp, frames, rounds)
    result["per_frame"] = _per_frame(scene, tmp, rounds)
    w1 = result["workers_1"]["frames_per_s"]
    result["speedup_workers_2"] = result["workers_2"]["frames_per_s"] / w1
    result["speedup_shards_2"] = result["shards_2"]["frames_per_s"] / w1
    per_round = [a["seconds"] / b["seconds"] for a, b in zip(runs["workers_1"],
                                                              runs["workers_2"])]
    result["speedup_workers_2_per_round"] = {"median": statistics.median(per_round),
                                             "min": min(per_round), "max": max(per_round)}
    if "frames_per_s" in result.get("ray_2", {}):
        result["ray_vs_pool"] = result["ray_2"]["frames_per_s"] / \
            result["workers_2"]["frames_per_s"]
    result["load_after"] = os.getloadavg()[0]
    shutil.rmtree(tmp, ignore_errors=True)
    return result


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--models", type=Path, default=MODELS)
    ap.add_argument("--frames", type=int, default=36)
    ap.add_argument("--width", type=int, default=640)
    ap.add_argument("--height", type=int, default=480)
    ap.add_argument("--no-ray", action="store_true", help="leave out the Ray runs")
    ap.add_argument("--rounds", type=int, default=3,
                    help="rounds of every variant, interleaved (default 3)")
    ap.add_argument("--json", type=Path, help="also write the results here")
    args = ap.parse_args(argv)
    r = measure(args.models, args.frames, args.width, args.height, ray=not args.no_ray,
                rounds=args.rounds)
    if "skipped" in r:
        print(f"skipped: {r['skipped']}", file=sys.stderr)
        return 0
    if args.json:
        args.json.write_text(json.dumps(r, indent=2) + "\n")
    print(f"{r['frames']}-view turntable, {r['triangles']:,} triangles, {r['lights']} lights, "
          f"{r['size'][0]}x{r['size'][1]}, image + masks, {r['cores']} cores; load average "
          f"{r['load_before']:.1f} before, {r['load_after']:.1f} after")
    print()
    print("| run | seconds | frames/s | vs 1 worker | CPU s per frame | cores it got |")
    print("|---|---:|---:|---:|---:|---:|")
    for label, what in (("workers_1", "1 worker"), ("workers_2", "2 workers"),
                        ("shards_2", "2 shards in parallel"), ("ray_2", "Ray, 2 actors")):
        x = r.get(label, {})
        if "frames_per_s" in x:
            cpu = x["cpu_s_per_frame"]
            used = "" if cpu is None else f"{x['cores']:.2f}"
            cpu = "" if cpu is None else f"{cpu:.2f}"
            print(f"| {what} | {x['seconds']:.1f} | {x['frames_per_s']:.2f} | "
                  f"{x['frames_per_s'] / r['workers_1']['frames_per_s']:.2f}x | {cpu} | {used} |")
    p = r["per_frame"]
    print()
    spread = ", ".join(f"{what} {r[label]['min_s']:.1f}-{r[label]['max_s']:.1f}"
                       for label, what in (("workers_1", "1 worker"), ("workers_2", "2 workers"),
                                           ("shards_2", "2 shards"), ("ray_2", "Ray"))
                       if "frames_per_s" in r.get(label, {}))
    q = r["speedup_workers_2_per_round"]
    print(f"medians of {r['rounds']} rounds, the variants interleaved; seconds min-max: "
          f"{spread}; 2 workers / 1 worker in each round: median {q['median']:.2f}x "
          f"({q['min']:.2f}-{q['max']:.2f})")
    pr = r["probe"]
    print(f"the machine's own 2-process scaling (a single-threaded zlib job alone, then two "
          f"copies at once, once per round): {pr['scaling']:.2f}x ({pr['min']:.2f}-"
          f"{pr['max']:.2f}); 1 worker already uses {r['workers_1']['cores']:.2f} cores, so 2 "
          f"workers can reach at most {pr['scaling']:.2f} / {r['workers_1']['cores']:.2f} = "
          f"{r['ceiling_workers_2']:.2f}x one (with frames of the same CPU cost; target 1.6x)")
    if "ray_init_s" in r:
        print(f"Ray start-up (not in the Ray row): {r['ray_init_s']:.1f} s; Ray / pool: "
              f"{r['ray_vs_pool']:.2f}")
    print(f"per frame: bare render {p['bare_render_s'] * 1e3:.0f} ms (batch's render "
          f"{p['batch_render_s'] * 1e3:.0f} ms), encoding PNG + NPZ {p['encode_s'] * 1e3:.1f} ms, "
          f"sha256 + atomic writes {p['write_and_hash_s'] * 1e3:.1f} ms, manifest line "
          f"{p['manifest_line_s'] * 1e6:.0f} us: machinery {p['machinery_fraction']:.1%} of a "
          f"frame ({p['machinery_and_encoding_fraction']:.1%} with encoding)")
    return 0


if __name__ == "__main__":
    sys.exit(main())
