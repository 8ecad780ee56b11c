"""Where a frame's bytes go: the `Store` protocol, over units, and the stores of the plain
layouts: per-frame files `OUT/<job>/<frame>.<suffix>` (`FileStore`), or webdataset tar shards
`OUT/shard-NNNNNN.tar` of a fixed number of samples (`TarStore`); the dataset layouts' store is
`datasets.DatasetStore`, and which layout has which store is the table in `batch.layouts`.

A unit is what a store writes, checks and cleans as one: a frame, or the frames of one tar.
Every store has the same three calls over units: `write(unit, results)`, `verify(unit, old)`,
`clean(units)`, and `finish(specs, hashes)` at the end of a run (the index files).  Only the
parent process writes, every byte through `put` (`shadowvol.io`, atomic), so the files do not
depend on which worker made them.  An output that is a symbolic link (DVC and git-annex datasets
are made of them) is replaced by the new file, never written through: the link may point to
another output, or out of the dataset.

A webdataset sample is the members `<job>/<frame>.<suffix>` of one frame (the key is the part
before the first dot: `<job>/<frame>`), members in frame order, then output order; tar headers
carry fixed times and owners (`io.tar_bytes`), so a tar's bytes are the same on every run.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Protocol

from shadowvol.batch import manifest
from shadowvol.batch.outputs import OUTPUTS
from shadowvol.batch.spec import FrameSpec
from shadowvol.io import tar_bytes, write_bytes


@dataclass(frozen=True)
class Unit:
    """A frame, or the frames of one tar: `index` (its place among the run's units), its frame
    specs in frame order and their spec hashes (`job_frames.spec_hash`)."""

    index: int
    frames: tuple[FrameSpec, ...]
    hashes: tuple[str, ...]


@dataclass(frozen=True)
class Written:
    """What `Store.write` wrote: frame id -> its files (as the manifest records them; failed
    frames have none), and the unit's own records (a tar's line)."""

    files: dict[str, dict] = field(default_factory=dict)
    records: tuple[dict, ...] = ()


class Store(Protocol):
    """The one interface of every layout's files, made as `Store(out, layout)` with the
    layout's row of `batch.layouts` (kept as `layout`)."""

    layout: object

    def write(self, unit: Unit, results: Sequence[dict]) -> Written:
        """Write the unit from its frames' results (in frame order; a result with "error"
        writes nothing of its frame)."""

    def verify(self, unit: Unit, old: dict[str, dict]) -> list[dict] | None:
        """The records of `old` (the manifests' latest, by id) that show the unit made from
        the same specs in this layout, with its files there and of the recorded sha256; None
        when it must be made again."""

    def clean(self, units: Sequence[Unit]) -> int:
        """Remove the temporary files a killed run left for these units' files."""

    def finish(self, specs: list[FrameSpec], hashes: dict[str, str]) -> None:
        """After the run's manifest is written: what the layout makes of every frame."""


def put(out: Path, rel: str, data: bytes) -> dict:
    """Write `data` to OUT/`rel` (atomically, replacing a link, never through it; a folder of
    `rel` that is a link is refused), and return its manifest entry."""
    write_bytes(Path(out) / rel, data, follow_links=False, within=out)
    return {"path": rel, "sha256": manifest.sha256(data), "bytes": len(data)}


def made(unit: Unit, old: dict[str, dict], layout: str) -> list[dict | None]:
    """Each frame's record in `old` when it says the frame was made from the same spec in
    this layout, else None."""
    found = []
    for spec, spec_hash in zip(unit.frames, unit.hashes):
        record = old.get(spec.id)
        ok = record is not None and "error" not in record and \
            record.get("spec") == spec_hash and record.get("format", "files") == layout
        found.append(record if ok else None)
    return found


def member_name(frame_id: str, output: str) -> str:
    return f"{frame_id}.{OUTPUTS[output].suffix}"


class FileStore:
    """Per-frame files under `out`, one per output: units of one frame."""

    def __init__(self, out: Path, layout):
        self.out, self.layout = Path(out), layout

    @staticmethod
    def paths(spec: FrameSpec) -> dict[str, str]:
        """output name -> path relative to `out`."""
        return {name: member_name(spec.id, name) for name in spec.outputs}

    def write(self, unit: Unit, results: Sequence[dict]) -> Written:
        return Written({spec.id: {name: put(self.out, rel, result["encoded"][name])
                                  for name, rel in self.paths(spec).items()}
                        for spec, result in zip(unit.frames, results) if "error" not in result})

    def verify(self, unit: Unit, old: dict[str, dict]) -> list[dict] | None:
        """The record's files are there with its hashes, and are the files the spec wants."""
        records = made(unit, old, self.layout.name)
        for spec, record in zip(unit.frames, records):
            files = (record or {}).get("files") or {}
            paths = self.paths(spec)
            if record is None or set(files) != set(paths):
                return None
            for name, rel in paths.items():
                if files[name].get("path") != rel or manifest.file_sha256(
                        self.out / rel) != files[name].get("sha256"):
                    return None
        return records

    def clean(self, units: Sequence[Unit]) -> int:
        by_folder: dict[Path, set[str]] = {}
        for unit in units:
            for spec in unit.frames:
                for rel in self.paths(spec).values():
                    path = self.out / rel
                    by_folder.setdefault(path.parent, set()).add(path.name)
        return sum(manifest.remove_stale_parts(folder, names, within=self.out)
                   for folder, names in by_folder.items())

    def finish(self, specs: list[FrameSpec], hashes: dict[str, str]) -> None:
        pass   # per-frame files have no index


class TarStore:
    """Webdataset shards under `out`: unit k is `shard-{k:06d}.tar`."""

    def __init__(self, out: Path, layout):
        self.out, self.layout = Path(out), layout

    @staticmethod
    def tar_name(unit: int) -> str:
        return f"shard-{unit:06d}.tar"

    @staticmethod
    def tar_id(unit: int) -> str:
        return f"tar/{unit:06d}"

    def write(self, unit: Unit, results: Sequence[dict]) -> Written:
        """The tar of `unit` (failed frames have no members)."""
        members, files = [], {}
        name = self.tar_name(unit.index)
        for spec, result in zip(unit.frames, results):
            if "error" in result:
                continue
            files[spec.id] = {}
            for output in spec.outputs:
                data = result["encoded"][output]
                member = member_name(spec.id, output)
                members.append((member, data))
                files[spec.id][output] = {"tar": name, "member": member,
                                             "sha256": manifest.sha256(data),
                                             "bytes": len(data)}
        entry = put(self.out, name, tar_bytes(members))
        record = {"id": self.tar_id(unit.index), "tar": name, "sha256": entry["sha256"],
                  "bytes": entry["bytes"], "frames": [spec.id for spec in unit.frames]}
        return Written(files, (record,))

    def verify(self, unit: Unit, old: dict[str, dict]) -> list[dict] | None:
        records = made(unit, old, self.layout.name)
        tar = old.get(self.tar_id(unit.index))
        fine = all(records) and tar is not None and \
            tar.get("frames") == [spec.id for spec in unit.frames] and \
            manifest.file_sha256(self.out / self.tar_name(unit.index)) == tar.get("sha256")
        return [*records, tar] if fine else None

    def clean(self, units: Sequence[Unit]) -> int:
        return manifest.remove_stale_parts(self.out, {self.tar_name(u.index) for u in units},
                                           within=self.out)

    def finish(self, specs: list[FrameSpec], hashes: dict[str, str]) -> None:
        pass   # the tars are the whole dataset
