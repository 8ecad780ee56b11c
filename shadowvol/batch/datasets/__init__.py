"""The dataset layouts training code loads: `shadowvol batch --format
nerfstudio|bop|coco|istd|soba|soba-lights` (docs/formats.md).  Each job is one dataset folder `OUT/<job>/`.

A layout's module has `frame(spec, arrays, scene) -> ({path: bytes}, record)`, the frame's
files (paths relative to OUT) and the JSON its index entries are made from, kept in the frame's
manifest line (`dataset`); and `index(job, entries) -> {path: bytes}`, the index files
(transforms.json, scene_*.json, annotations.json, istd.json) of a job from its (spec, record) pairs in
frame order; what its frames need beside the image, masks, depth and ids (`arrays.frame_arrays`)
and where its files go are fields of its row in `batch.layouts`.  The index is rebuilt at the
end of every run from every manifest in OUT, never appended to, so a killed and resumed run, or
N shards, end with the bytes of one run.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

from shadowvol.batch import manifest
from shadowvol.batch.datasets import encoding
from shadowvol.batch.store import Unit, Written, made, put
from shadowvol.batch.spec import FrameSpec
from shadowvol.scene import Scene, SceneError
from shadowvol.scenefile import load_scene


class DatasetStore:
    """A layout's per-frame files under `out`, as the frame made them (their paths are in the
    frame's record: how many files a frame has depends on its scene); units of one frame.
    `scenes` (key -> path or Scene): the run's, for a layout whose index is of the whole
    dataset (`Layout.dataset_index`)."""

    def __init__(self, out: Path, layout, scenes: dict | None = None):
        self.out, self.layout = Path(out), layout
        self.scenes = scenes or {}
        self._loaded: dict[str, Scene | None] = {}

    def scene_of(self, key: str) -> Scene | None:
        """The run's scene of `key`, loaded once here; None when it cannot be (its frames
        failed for that reason and are in no index)."""
        if key not in self._loaded:
            source = self.scenes.get(key, key)
            try:
                self._loaded[key] = source if isinstance(source, Scene) else load_scene(source)
            except (SceneError, OSError):
                self._loaded[key] = None
        return self._loaded[key]

    def _root(self, spec: FrameSpec) -> Path:
        return self.out / (spec.job if self.layout.root is None else self.layout.root(spec))

    def write(self, unit: Unit, results: Sequence[dict]) -> Written:
        return Written({spec.id: {rel: put(self.out, rel, data)
                                  for rel, data in result["encoded"].items()}
                        for spec, result in zip(unit.frames, results) if "error" not in result})

    def verify(self, unit: Unit, old: dict[str, dict]) -> list[dict] | None:
        records = made(unit, old, self.layout.name)
        for record in records:
            files = (record or {}).get("files") or {}
            if not files or "dataset" not in record or not all(
                    manifest.file_sha256(self.out / e.get("path", "")) == e.get("sha256")
                    for e in files.values()):
                return None
        return records

    def clean(self, units: Sequence[Unit]) -> int:
        """Remove temporary files a killed run left for these frames' files and the index."""
        layout = self.layout
        folders: dict[Path, set[str] | None] = {}
        for spec in (spec for unit in units for spec in unit.frames):
            job = self._root(spec)
            for sub in layout.folders:
                folders.setdefault(job / sub, set()).add(encoding.frame_stem(spec))
            for rel in layout.index_files:
                names = folders.setdefault((job / rel).parent, set())
                if names is not None:
                    names.add(Path(rel).name)
            if spec.index == 0 and layout.dataset_index is None:
                folders.update({job / sub: None for sub in layout.first})
        if units and layout.dataset_index is not None:   # what the dataset's index writes
            for rel in layout.first:
                if Path(rel).suffix:
                    names = folders.setdefault((self.out / rel).parent, set())
                    if names is not None:
                        names.add(Path(rel).name)
                else:
                    folders[self.out / rel] = None
        return sum(_remove_parts(folder, stems) for folder, stems in folders.items()
                   if not manifest.outside(self.out, folder))

    def finish(self, specs: list[FrameSpec], hashes: dict[str, str]) -> None:
        """Rebuild every job's index files (or the dataset's, `Layout.dataset_index`) from the
        made frames that every manifest in OUT records for `specs` (made from the same spec, in
        this layout), in frame order."""
        records = manifest.read(self.out)
        if self.layout.dataset_index is not None:
            done = {spec.id: records[spec.id]["dataset"] for spec in specs
                    if _made(records.get(spec.id), hashes[spec.id], self.layout.name)}
            for rel, data in self.layout.dataset_index(specs, done, self.scene_of).items():
                put(self.out, rel, data)
            return
        jobs: dict[str, list] = {}
        for spec in specs:
            record = records.get(spec.id)
            jobs.setdefault(spec.job, [])
            if _made(record, hashes[spec.id], self.layout.name):
                jobs[spec.job].append((spec, record["dataset"]))
        for job, entries in jobs.items():
            for rel, data in self.layout.index(job, entries).items():
                put(self.out, rel, data)


def _made(record: dict | None, spec_hash: str, layout: str) -> bool:
    """The record says its frame was made from this spec in this layout."""
    return (record is not None and record.get("spec") == spec_hash
            and record.get("format") == layout and "dataset" in record)


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
