"""`shadowvol.batch.run`: jobs -> frames -> this run's share -> what is not already made ->
workers (this process, a process pool, or Ray actors) -> files and the manifest.

The frames of a job file are numbered in file order; they are cut into units (a frame, or in
the webdataset layout the frames of one tar), and `--shard I/N` takes the I-th of N contiguous
runs of units, so N shards together make exactly the files of one unsharded run, with no
coordination.  A unit is skipped when the manifests in OUT say it was made from the same spec
(`job_frames.spec_hash`) and its files are there with the recorded sha256; everything else is
made again, and written atomically.
"""

from __future__ import annotations

import dataclasses
import hashlib
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from shadowvol import memory
from shadowvol.batch import egl, job_frames, layouts, local, manifest
from shadowvol.batch.jobs import Job, JobError, check_jobs, read_jobs
from shadowvol.batch.layouts import LAYOUTS
from shadowvol.batch.sources import SOURCES
from shadowvol.batch.store import Unit
from shadowvol.batch.spec import FrameSpec
from shadowvol.errors import BAD_INPUT, InputError, OK, require
from shadowvol.scene import Scene

DEFAULT_SAMPLES_PER_TAR = 1000


@dataclass
class Summary:
    """What a run did.  `status` is the exit status: OK when every frame of its share was made
    (now or before), else the worst of the failures' (BAD_INPUT for bad jobs and scenes,
    RENDER_FAILED for frames that failed to render)."""

    frames: int = 0
    rendered: int = 0
    skipped: int = 0
    failed: int = 0
    bad_jobs: int = 0
    seconds: float = 0.0
    status: int = OK
    manifest: Path | None = None
    errors: list[str] = field(default_factory=list)

    def line(self) -> str:
        rate = self.rendered / self.seconds if self.seconds > 0 else 0.0
        text = (f"batch: {self.frames} frames: {self.rendered} rendered, {self.skipped} "
                f"already made, {self.failed} failed; {self.seconds:.1f} s "
                f"({rate:.2f} frames/s)")
        if self.bad_jobs:
            text += f"; {self.bad_jobs} bad job{'s' * (self.bad_jobs > 1)}"
        return text + f"; manifest {self.manifest}"


def parse_shard(text: str) -> tuple[int, int]:
    """'I/N' -> (I, N) with 0 <= I < N."""
    try:
        index, count = (int(x) for x in str(text).split("/"))
    except ValueError:
        raise InputError("--shard", f"expected I/N (e.g. 0/4), got {text!r}") from None
    if not 0 <= index < count:
        raise InputError("--shard", f"I/N needs 0 <= I < N, got {text!r}")
    return index, count


def share(units: int, shard: tuple[int, int]) -> range:
    """The units of shard (I, N): the I-th of N contiguous, nearly equal runs."""
    index, count = shard
    return range(units * index // count, units * (index + 1) // count)


def _digest(value, h) -> None:
    if isinstance(value, np.ndarray):
        h.update(str((value.dtype.str, value.shape)).encode())
        h.update(np.ascontiguousarray(value).tobytes())
    elif dataclasses.is_dataclass(value):
        h.update(type(value).__name__.encode())
        for f in dataclasses.fields(value):
            _digest(getattr(value, f.name), h)
    elif isinstance(value, (tuple, list)):
        h.update(b"[%d" % len(value))
        for item in value:
            _digest(item, h)
    else:
        h.update(repr(value).encode())


def scene_digest(scene: str | Scene) -> str:
    """sha256 of a scene file's bytes, or of a Scene's data; "missing" for no such file."""
    if isinstance(scene, Scene):
        h = hashlib.sha256()
        _digest(scene, h)
        return h.hexdigest()
    return manifest.file_sha256(Path(scene)) or "missing"


def _jobs(jobs) -> list[Job | JobError]:
    if isinstance(jobs, (str, Path)):
        return read_jobs(jobs)
    if isinstance(jobs, dict):
        jobs = [jobs]
    return check_jobs(list(jobs))


def _bar(total: int, progress: bool | None):
    if progress is False or (progress is None and not sys.stderr.isatty()):
        return None
    try:
        tqdm = require("tqdm", "the progress bar", "tqdm").tqdm
    except ImportError:
        if progress:
            raise
        return None
    return tqdm(total=total, unit="frame", desc="batch", file=sys.stderr, smoothing=0.1)


def run(jobs, out, *, workers: int = 1, shard: tuple[int, int] | str = (0, 1), ray=None,
        egl_device=None, format: str = "files",
        samples_per_tar: int = DEFAULT_SAMPLES_PER_TAR, progress: bool | None = None,
        start_method: str = "spawn", gpus_per_worker: float = 0,
        memory_budget: int | str | None = None) -> Summary:
    """Render `jobs` (a JSONL file, or job dicts, see `batch.jobs`) into the folder `out`.

    workers      : processes on this machine (1: this process), or Ray actors with `ray`
    shard        : (I, N) or "I/N": make only this shard's share
    ray          : None (local), True (ray.init() with no address) or a cluster address
    egl_device   : None, "auto" or an EGL device index (`batch.egl`)
    format       : the name of a layout of `batch.layouts`, as `--format` takes it: "files"
                   (OUT/<job>/<frame>.<suffix>), "webdataset" (OUT/shard-*.tar), or a dataset,
                   "nerfstudio", "bop", "coco", ... (`batch.datasets`)
    progress     : a tqdm bar on stderr; None: only when stderr is a terminal
    start_method : "spawn" or "forkserver" ("fork" is allowed, and fails clearly in a process
                   that has made a GL context)
    gpus_per_worker : with `ray`, the GPUs each actor asks Ray for (Ray then sets the actor's
                   CUDA_VISIBLE_DEVICES, which egl_device="auto" follows)
    memory_budget : the memory the run's frames may take at once (`shadowvol.memory.budget`:
                   bytes or "12GiB"; default SHADOWVOL_MEMORY_BUDGET or 3/4 of the machine),
                   shared by the workers; a frame over its worker's share is recorded as an
                   error (status 2) and not rendered
    Returns a Summary; a bad job or frame is recorded in the manifest and the others go on.
    """
    began = time.perf_counter()
    shard = _checked(workers, shard, format, samples_per_tar, memory_budget, egl_device, ray)
    layout = LAYOUTS[format]   # the user's word is the flag's, --format; from here on, a layout
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise InputError("-o", f"{str(out)!r} is not a folder")
    entries = _jobs(jobs)
    plan = _Plan(entries, layout, samples_per_tar, shard)
    own = manifest.manifest_name(shard)
    out.mkdir(parents=True, exist_ok=True)
    # the lock first: a run refused here has touched nothing of the one that holds it
    journal = manifest.Journal(out / own)
    try:
        store = layout.make_store(out, plan.scenes)
        done: dict[str, dict | manifest.Line]
        done, unit_lines, todo = _already_made(plan, manifest.read(out, own), store)
        # temporary files a killed run left, for any file of this share (made or not)
        store.clean([plan.units[u] for u in plan.mine])
        manifest.remove_stale_parts(out, {own})
        summary = Summary(frames=plan.frames(plan.mine),
                          skipped=plan.frames(plan.mine) - plan.frames(todo),
                          manifest=out / own)
        _record_bad_jobs(entries, journal, done, summary)
        specs = [s for u in todo for s in plan.units[u].frames]
        bar = _bar(len(specs), progress)
        results = _results(specs, plan.scenes, workers, ray, egl_device, start_method,
                           gpus_per_worker, memory_budget)
        _make(plan, todo, results, journal, done, unit_lines, summary, store, bar)
        # the final manifest: one line per frame of this share, in job-file order, then the
        # units' own lines (the tars)
        ordered = [done[f"job/{job.name}"] for job in entries if isinstance(job, JobError)]
        ordered += [done[s.id] for u in plan.mine for s in plan.units[u].frames
                    if s.id in done]
        ordered += [r for u in plan.mine for r in unit_lines.get(u, ())]
        journal.finish(ordered)
        store.finish(plan.specs, plan.hashes)   # the index files, from every manifest in OUT
    finally:
        journal.close()
    summary.seconds = time.perf_counter() - began
    return summary


def _checked(workers, shard, layout, samples_per_tar, memory_budget, egl_device, ray
             ) -> tuple[int, int]:
    """The shard as (I, N); InputError for an argument that cannot run, before any work."""
    if isinstance(shard, str):
        shard = parse_shard(shard)
    if isinstance(workers, bool) or not isinstance(workers, int) or workers < 1:
        raise InputError("--workers", f"must be a whole number >= 1, got {workers!r}")
    if layout not in LAYOUTS:
        raise InputError("--format", f"must be one of {', '.join(LAYOUTS)}, got {layout!r}")
    if isinstance(samples_per_tar, bool) or not isinstance(samples_per_tar, int) or \
            samples_per_tar < 1:
        raise InputError("--samples-per-tar", f"must be a whole number >= 1, got "
                                              f"{samples_per_tar!r}")
    memory.budget(memory_budget)  # a bad budget is an error now, not one per frame
    if egl.parse(egl_device) is not None and not ray:
        egl.choose(egl_device)  # a bad index is an error naming this machine's devices, now
    return shard


def _record_bad_jobs(entries, journal, done, summary) -> None:
    """A job that cannot run gets one manifest line (status 2); the others go on."""
    for job in entries:
        if isinstance(job, JobError):
            record = {"id": f"job/{job.name}", "job": job.name, "source": job.source,
                      "error": job.error, "status": BAD_INPUT}
            journal.add(record)
            done[record["id"]] = record
            summary.bad_jobs += 1
            summary.status = max(summary.status, BAD_INPUT)
            summary.errors.append(f"{job.source}: {job.error}")


def _make(plan, todo, results, journal, done, unit_lines, summary, store, bar) -> None:
    """Record the frames as their results come (in any order, in `done` by frame id); a unit
    is written once all of its frames are in (a frame's at once; a tar's when its last frame
    comes), and its own lines kept in `unit_lines`."""
    unit_of = {s.id: u for u in todo for s in plan.units[u].frames}
    waiting: dict[int, dict[str, dict]] = {u: {} for u in todo}  # unit -> id -> result
    for result in results:
        u = unit_of[result["id"]]
        waiting[u][result["id"]] = result
        unit = plan.units[u]
        if len(waiting[u]) == len(unit.frames):
            got = waiting.pop(u)
            made = [got[s.id] for s in unit.frames]
            start = time.perf_counter()
            written = store.write(unit, made)
            seconds = round(time.perf_counter() - start, 6)
            for spec, made_one in zip(unit.frames, made):
                _record(journal, done, summary, spec, made_one, plan.hashes,
                        written.files.get(spec.id), store.layout.name, seconds)
            # a tar's own lines, kept as where they are (`manifest.Line`), as a frame's are
            unit_lines[u] = tuple(journal.add(record) for record in written.records)
        if bar is not None:
            bar.update()
    if bar is not None:
        bar.close()


class _Plan:
    """Every frame of the job file in order (`specs`), their spec hashes, the scenes they need
    (key -> path or Scene), the units (a frame, or a tar's frames) and this shard's share."""

    def __init__(self, entries, layout, samples_per_tar: int, shard: tuple[int, int]):
        self.scenes: dict[str, str | Scene] = {}
        digests: dict[str, str] = {}
        self.specs: list[FrameSpec] = []
        for place, job in enumerate(entries):
            if isinstance(job, Job):
                key = job.scene if isinstance(job.scene, str) else f"<Scene {id(job.scene)}>"
                if key not in self.scenes:
                    self.scenes[key], digests[key] = job.scene, scene_digest(job.scene)
                self.specs.extend(layouts.tag(job_frames.specs(job, key), layout, place))
        self.hashes = {s.id: job_frames.spec_hash(s, digests[s.scene]) for s in self.specs}
        per_unit = layout.frames_per_unit(samples_per_tar)
        self.units = [Unit(k, tuple(part), tuple(self.hashes[s.id] for s in part))
                      for k, part in enumerate(self.specs[i:i + per_unit]
                                               for i in range(0, len(self.specs), per_unit))]
        self.mine = share(len(self.units), shard)

    def frames(self, units) -> int:
        return sum(len(self.units[u].frames) for u in units)


def _already_made(plan: _Plan, old: dict[str, dict], store
                  ) -> tuple[dict[str, dict], dict[int, tuple], list[int]]:
    """(the frame records of this share's units that are made and check out, by id; those
    units' own lines (a tar's), by unit; the units to make)."""
    kept: dict[str, dict] = {}
    unit_lines: dict[int, tuple] = {}
    todo: list[int] = []
    for u in plan.mine:
        records = store.verify(plan.units[u], old)
        if records is None:
            todo.append(u)
            continue
        frame_ids = {s.id for s in plan.units[u].frames}
        kept.update((r["id"], r) for r in records if r["id"] in frame_ids)
        unit_lines[u] = tuple(r for r in records if r["id"] not in frame_ids)
    return kept, unit_lines, todo


def _record(journal, done, summary, spec, result, hashes, files, layout: str,
            write_seconds: float) -> None:
    """Append a frame's manifest line: its files, or its error."""
    base = {"id": spec.id, "job": spec.job, "frame": spec.index,
            "spec": hashes[spec.id], "renderer": spec.renderer}
    if "error" in result:
        record = {**base, "error": result["error"], "status": result["status"]}
        summary.failed += 1
        summary.status = max(summary.status, result["status"])
        summary.errors.append(f"{spec.id}: {result['error']}")
    else:
        seconds = dict(result["seconds"], write=write_seconds)
        record = {**base, "format": layout,   # the layout's name, under the flag's word
                  "files": files, "camera": result["camera"], "lights": result["lights"],
                  "size": result["size"], "seed": spec.seed,
                  **SOURCES[spec.renderer].options(spec),
                  "versions": result["versions"], "device": result["device"],
                  "worker": result["worker"],
                  **({"objects": result["objects"]} if "objects" in result else {}),
                  "seconds": seconds, **({"dataset": result["dataset"]} if "dataset" in result
                                         else {})}
        summary.rendered += 1
    done[spec.id] = journal.add(record)  # where its line is: memory stays flat, however long


def _results(specs, scenes, workers, ray, egl_device, start_method, gpus_per_worker, budget):
    if not specs:
        return iter(())
    if ray:
        import shadowvol.batch.ray

        address = None if ray is True else ray
        return shadowvol.batch.ray.results(local.chunks(specs, workers), scenes, actors=workers,
                                          address=address, egl_device=egl_device,
                                          num_gpus=gpus_per_worker, budget=budget)
    if workers == 1 and start_method == "spawn":
        return local.in_process(local.chunks(specs, 1), scenes, egl_device, budget)
    return local.pool(local.chunks(specs, workers), scenes, workers, egl_device, start_method,
                      budget)
