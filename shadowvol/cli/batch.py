"""`shadowvol batch`: render a JSONL job file into a dataset folder (`shadowvol.batch`)."""

from __future__ import annotations

import argparse
import sys

from shadowvol.batch.runner import DEFAULT_SAMPLES_PER_TAR, parse_shard, run
from shadowvol.batch.layouts import LAYOUTS
from shadowvol.cli import options, status

EPILOG = """\
A job file has one JSON object a line: a scene file, cameras (a list, an orbit/turntable or a
path of key poses), optional light overrides, size, outputs, renderer (shadowvol or raytrace),
seed; README.md "Datasets" and scenes/turntable.jsonl show one.  OUT gets OUT/<job>/<frame>.png
and .masks.npz (or, with --format webdataset, OUT/shard-NNNNNN.tar) and OUT/manifest.jsonl: per
frame its id, files and their sha256, camera and lights, renderer, versions, seconds, or its
error.  Run it again and it makes only what is missing or does not match the manifest: a run
killed at any point, then rerun, ends with the same files.  A bad job or frame is recorded and
the others go on; the exit status is 0 only when every frame was made.

""" + status.EPILOG


def add_parser(subparsers) -> argparse.ArgumentParser:
    p = options.command(
        subparsers, "batch", help="render a job file into a dataset (local pool, shards or Ray)",
        description="Render every frame of JOBS into OUT, resumably and deterministically: the "
                    "same files whatever the workers, shards or Ray actors that made them.",
        epilog=EPILOG)
    p.add_argument("jobs", metavar="JOBS", help="the job file (.jsonl)")
    options.output(p, "OUT", "the dataset folder")
    p.add_argument("--workers", type=int, default=1, metavar="N",
                   help="worker processes on this machine (spawned, each with one GL context "
                        "and a renderer per scene, cores/N threads each), or Ray actors with "
                        "--ray (default: 1, in this process)")
    p.add_argument("--shard", default="0/1", metavar="I/N",
                   help="make only shard I of N (for Slurm arrays, GNU parallel, ...): the "
                        "N shards together make exactly the files of one run; each writes "
                        "OUT/manifest.shard-I-of-N.jsonl, and a run without --shard afterwards "
                        "checks them all and writes OUT/manifest.jsonl")
    p.add_argument("--ray", nargs="?", const=True, default=None, metavar="ADDRESS",
                   help="render on Ray actors (pip install 'shadowvol[ray]'): a local Ray "
                        "without ADDRESS, else the cluster at ADDRESS (e.g. auto)")
    p.add_argument("--gpus-per-worker", type=float, default=0, metavar="G",
                   help="with --ray: the GPUs each actor asks Ray for (e.g. 1 on a GPU "
                        "cluster, with --egl-device auto); default 0")
    p.add_argument("--egl-device", default=None, metavar="auto|N",
                   help="the EGL device each worker renders on: an index, or auto (the EGL "
                        "device of the worker's first visible CUDA device, by "
                        "EGL_NV_device_cuda, else 0); CUDA_VISIBLE_DEVICES alone does not "
                        "choose an EGL device")
    p.add_argument("--format", choices=tuple(LAYOUTS), default="files",
                   help="files: OUT/<job>/<frame>.<suffix> (default); webdataset: tar shards "
                        "of --samples-per-tar frames, keys <job>/<frame>; nerfstudio, bop, "
                        "coco, istd (shadow-removal triplets), soba, soba-lights (instance "
                        "shadows): OUT/<job>/ in that dataset layout (docs/formats.md)")
    p.add_argument("--samples-per-tar", type=int, default=DEFAULT_SAMPLES_PER_TAR, metavar="N",
                   help=f"frames per webdataset tar (default {DEFAULT_SAMPLES_PER_TAR})")
    p.add_argument("--progress", action=argparse.BooleanOptionalAction, default=None,
                   help="a progress bar with frames/s and ETA (default: only on a terminal)")
    options.memory_budget(p)
    p.set_defaults(func=command)
    return p


def command(args) -> int:
    summary = run(args.jobs, args.output, workers=args.workers, shard=parse_shard(args.shard),
                  ray=args.ray, egl_device=args.egl_device, format=args.format,
                  samples_per_tar=args.samples_per_tar, progress=args.progress,
                  gpus_per_worker=args.gpus_per_worker, memory_budget=args.memory_budget)
    for line in summary.errors[:10]:
        print(f"error: {line}", file=sys.stderr)
    if len(summary.errors) > 10:
        print(f"error: ... and {len(summary.errors) - 10} more (see {summary.manifest})",
              file=sys.stderr)
    print(summary.line(), file=sys.stderr)
    return summary.status
