"""The dataset layouts training code loads: `shadowvol batch --format nerfstudio|bop|coco`
(docs/formats.md).  Each job is one dataset folder `OUT/<job>/`.

A layout module has `frame(spec, arrays, scene) -> ({path: bytes}, record)`, the frame's files
(paths relative to OUT) and the JSON its index entries are made from, kept in the frame's
manifest line (`dataset`); and `index(job, entries) -> {path: bytes}`, the index files
(transforms.json, scene_*.json, annotations.json) of a job from its (spec, record) pairs in
frame order; and CASTERS, ALONE (what its frames need beside the image, masks, depth and ids:
`arrays.frame_arrays`), FOLDERS, INDEX (where its files go, for cleaning up after a kill).
The index is rebuilt at the end of every run from every manifest in OUT, never
appended to, so a killed and resumed run, or N shards, end with the bytes of one run.
"""

from __future__ import annotations

import importlib
import os
from pathlib import Path

from shadowvol.batch import manifest
from shadowvol.batch.formats import arrays, encoding
from shadowvol.io import write_bytes

NAMES = ("nerfstudio", "bop", "coco")


def layout(name: str):
    return importlib.import_module(f"shadowvol.batch.formats.{name}")


def tag(specs: list[dict], format: str) -> list[dict]:
    """Mark a layout's frame specs (so their spec hash, and the worker, know the layout)."""
    if format in NAMES:
        for spec in specs:
            spec["format"] = format
    return specs


def frame(worker, spec: dict, scene, camera, lights) -> tuple[dict[str, bytes], dict]:
    """A frame of `spec["format"]` rendered by `worker` (`batch.worker.Worker`)."""
    mod = layout(spec["format"])
    made = arrays.frame_arrays(worker, spec, scene, camera, lights, casters=mod.CASTERS,
                               alone=mod.ALONE)
    return mod.frame(spec, made, scene.replace(camera=camera, lights=lights))


class DatasetStore:
    """A layout's per-frame files under `out`, as the frame made them (their paths are in the
    frame's record: how many files a frame has depends on its scene)."""

    def __init__(self, out: Path, format: str):
        self.out, self.format = Path(out), format

    def write(self, spec: dict, encoded: dict[str, bytes]) -> dict[str, dict]:
        files = {}
        for rel, data in encoded.items():
            write_bytes(self.out / rel, data, follow_links=False)
            files[rel] = {"path": rel, "sha256": manifest.sha256(data), "bytes": len(data)}
        return files

    def verify(self, spec: dict, record: dict) -> bool:
        files = record.get("files") or {}
        return bool(files) and "dataset" in record and all(
            manifest.file_sha256(self.out / e.get("path", "")) == e.get("sha256")
            for e in files.values())

    def clean(self, specs: list[dict]) -> int:
        """Remove temporary files a killed run left for these frames' files and the index."""
        mod = layout(self.format)
        folders: dict[Path, set[str] | None] = {}
        for spec in specs:
            job = self.out / spec["job"]
            for sub in mod.FOLDERS:
                folders.setdefault(job / sub, set()).add(encoding.frame_stem(spec))
            for rel in mod.INDEX:
                names = folders.setdefault((job / rel).parent, set())
                if names is not None:
                    names.add(Path(rel).name)
            if spec["index"] == 0:
                folders.update({job / sub: None for sub in getattr(mod, "FIRST", ())})
        return sum(_remove_parts(folder, stems) for folder, stems in folders.items())


def _remove_parts(folder: Path, stems: set[str] | None) -> int:
    """Remove `.NAME.XXXXXXXX.part` files (`io.atomic_write`) whose NAME is in `stems` or
    starts with one of them and a "." or "_" (every one when `stems` is None)."""
    removed = 0
    try:
        entries = list(os.scandir(folder))
    except (FileNotFoundError, NotADirectoryError):
        return 0
    for entry in entries:
        if entry.name.startswith(".") and entry.name.endswith(".part"):
            target = entry.name[1:-len(".part")].rsplit(".", 1)[0]
            if stems is None or any(target == s or target.startswith((s + ".", s + "_"))
                                    for s in stems):
                try:
                    os.unlink(entry.path)
                    removed += 1
                except FileNotFoundError:
                    pass
    return removed


def write_index(out: Path, format: str, specs: list[dict], hashes: dict[str, str]) -> None:
    """Rebuild every job's index files from the made frames that every manifest in `out`
    records for `specs` (made from the same spec, in this layout), in frame order."""
    records = manifest.read(out)
    jobs: dict[str, list] = {}
    for spec in specs:
        record = records.get(spec["id"])
        ok = (record is not None and record.get("spec") == hashes[spec["id"]]
              and record.get("format") == format and "dataset" in record)
        jobs.setdefault(spec["job"], [])
        if ok:
            jobs[spec["job"]].append((spec, record["dataset"]))
    mod = layout(format)
    for job, entries in jobs.items():
        for rel, data in mod.index(job, entries).items():
            write_bytes(Path(out) / rel, data, follow_links=False)
