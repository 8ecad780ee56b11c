"""Where a frame's bytes go: per-frame files `OUT/<job>/<frame>.<suffix>`, or webdataset tar
shards `OUT/shard-NNNNNN.tar` of a fixed number of samples.  Only the parent process writes,
every file through `shadowvol.io` (atomic), so the files do not depend on which worker made
them.  An output that is a symbolic link (DVC and git-annex datasets are made of them) is
replaced by the new file, never written through: the link may point to another output.

A webdataset sample is the members `<job>/<frame>.<suffix>` of one frame (the key is the part
before the first dot: `<job>/<frame>`), members in frame order, then output order; tar headers
carry fixed times and owners (`io.tar_bytes`), so a tar's bytes are the same on every run.
"""

from __future__ import annotations

from pathlib import Path

from shadowvol.batch import formats, manifest
from shadowvol.batch.outputs import OUTPUTS
from shadowvol.io import tar_bytes, write_bytes

FORMATS = ("files", "webdataset", *formats.NAMES)  # the layouts: batch.formats


def member_name(frame_id: str, output: str) -> str:
    return f"{frame_id}.{OUTPUTS[output].suffix}"


class FileStore:
    """Per-frame files under `out`."""

    def __init__(self, out: Path):
        self.out = Path(out)

    def paths(self, spec: dict) -> dict[str, str]:
        """output name -> path relative to `out`."""
        return {name: member_name(spec["id"], name) for name in spec["outputs"]}

    def write(self, spec: dict, encoded: dict[str, bytes]) -> dict[str, dict]:
        files = {}
        for name, rel in self.paths(spec).items():
            data = encoded[name]
            write_bytes(self.out / rel, data, follow_links=False)
            files[name] = {"path": rel, "sha256": manifest.sha256(data), "bytes": len(data)}
        return files

    def verify(self, spec: dict, record: dict) -> bool:
        """The record's files are there with its hashes, and are the files `spec` wants."""
        files = record.get("files") or {}
        paths = self.paths(spec)
        if set(files) != set(paths):
            return False
        for name, rel in paths.items():
            entry = files[name]
            if entry.get("path") != rel or manifest.file_sha256(self.out / rel) != entry.get(
                    "sha256"):
                return False
        return True

    def clean(self, specs: list[dict]) -> int:
        """Remove temporary files a killed run left for these frames' files."""
        by_folder: dict[Path, set[str]] = {}
        for spec in specs:
            for rel in self.paths(spec).values():
                path = self.out / rel
                by_folder.setdefault(path.parent, set()).add(path.name)
        return sum(manifest.remove_stale_parts(folder, names)
                   for folder, names in by_folder.items())


class TarStore:
    """Webdataset shards under `out`: unit k is `shard-{k:06d}.tar`."""

    def __init__(self, out: Path):
        self.out = Path(out)

    @staticmethod
    def tar_name(unit: int) -> str:
        return f"shard-{unit:06d}.tar"

    @staticmethod
    def tar_id(unit: int) -> str:
        return f"tar/{unit:06d}"

    def write(self, unit: int, done: list[tuple[dict, dict]]) -> tuple[dict, dict[str, dict]]:
        """Write the tar of `unit` from its (spec, result) pairs in frame order (failed frames
        have no members).  Returns (the tar's record, frame id -> its files)."""
        members, files = [], {}
        for spec, result in done:
            if "error" in result:
                continue
            files[spec["id"]] = {}
            for name in spec["outputs"]:
                data = result["outputs"][name]
                member = member_name(spec["id"], name)
                members.append((member, data))
                files[spec["id"]][name] = {"tar": self.tar_name(unit), "member": member,
                                           "sha256": manifest.sha256(data), "bytes": len(data)}
        data = tar_bytes(members)
        write_bytes(self.out / self.tar_name(unit), data, follow_links=False)
        record = {"id": self.tar_id(unit), "tar": self.tar_name(unit),
                  "sha256": manifest.sha256(data), "bytes": len(data),
                  "frames": [spec["id"] for spec, _ in done]}
        return record, files

    def verify(self, unit: int, record: dict | None, frame_ids: list[str]) -> bool:
        return (record is not None and record.get("frames") == frame_ids
                and manifest.file_sha256(self.out / self.tar_name(unit)) == record.get("sha256"))

    def clean(self, units: list[int]) -> int:
        return manifest.remove_stale_parts(self.out, {self.tar_name(u) for u in units})
