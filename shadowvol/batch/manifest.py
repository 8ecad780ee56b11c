"""OUT/manifest.jsonl: one JSON line per frame (its id, files and their sha256, camera and
light parameters, renderer, versions, seconds, or its error), and per webdataset tar one line
with the tar's sha256.

While a run goes, each line is appended as soon as its files are written (a journal: a run
killed at any point keeps every line before the kill, and at worst half of the last one, which
the next run cuts off).  At the end the run rewrites the file atomically with one line per frame,
in job-file order, so a killed and resumed run ends with the same manifest, timings aside, as an
uninterrupted one.  A shard `I/N` (N > 1) writes `manifest.shard-I-of-N.jsonl`, so that shards
on a shared file system never write one file; a later run without --shard reads them all,
checks every file against them and writes `manifest.jsonl`.
"""

from __future__ import annotations

import errno
import fcntl
import hashlib
import json
import os
import stat
from pathlib import Path
from typing import NamedTuple

from shadowvol.errors import InputError, out_of_memory_while, short_path
from shadowvol.io import WriteError, atomic_write, linked_folder, write_bytes

MANIFEST = "manifest.jsonl"


def manifest_name(shard: tuple[int, int]) -> str:
    index, count = shard
    return MANIFEST if count == 1 else f"manifest.shard-{index}-of-{count}.jsonl"


def sha256(data: bytes) -> str:
    return hashlib.sha256(data).hexdigest()


def file_sha256(path: Path) -> str | None:
    """The sha256 of a regular file's bytes; None when it is not there or not a regular file
    (a FIFO, a device: never read)."""
    digest = hashlib.sha256()
    try:  # opened without blocking: a FIFO (or a device) is no regular file, and is not read
        fd = os.open(path, os.O_RDONLY | os.O_NONBLOCK | os.O_CLOEXEC)
    except (FileNotFoundError, IsADirectoryError, NotADirectoryError):
        return None
    with open(fd, "rb") as f:
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            return None
        os.set_blocking(fd, True)
        while chunk := f.read(1 << 20):
            digest.update(chunk)
    return digest.hexdigest()


def _lines(path: Path):
    try:
        text = path.read_bytes()
    except FileNotFoundError:
        return
    for line in text.split(b"\n"):
        if not line.strip():
            continue
        try:
            record = json.loads(line)
        except (json.JSONDecodeError, UnicodeDecodeError):
            continue  # the half line a killed run left, or one being written by a shard now
        if isinstance(record, dict) and isinstance(record.get("id"), str):
            yield record


def read(out: str | Path, own: str = MANIFEST) -> dict[str, dict]:
    """The latest record of each id in every manifest of `out` (the shards' first, then `own`,
    whose records win)."""
    out = Path(out)
    names = sorted(p.name for p in out.glob("manifest*.jsonl") if p.name != own) + [own]
    records: dict[str, dict] = {}
    for name in names:
        for record in _lines(out / name):
            records[record["id"]] = record
    return records


class Line(NamedTuple):
    """Where `Journal.add` wrote a record: its line's offset and length in the journal."""

    offset: int
    length: int


class Journal:
    """Appends records to a manifest, one line each, written as they come.  Made before the run
    touches anything in OUT: it holds an exclusive lock on the manifest from then until
    `close`, so a second run of the same share into the same folder is refused before it
    removes, reads or writes a file (shards have manifests of their own).  The manifest is
    opened without following a link: a manifest that is a symbolic link is refused (the run's
    journal and lock are never another file's), and so is anything but a regular file."""

    def __init__(self, path: str | Path):
        self.path = Path(path)
        self.path.parent.mkdir(parents=True, exist_ok=True)
        self._fd = _open_locked(self.path)
        self._held = [self._fd]   # the manifest's files, each locked, until `close`
        self._cut_partial_line()

    def _cut_partial_line(self) -> None:
        size = os.fstat(self._fd).st_size
        data = os.pread(self._fd, size, 0) if size else b""
        if data and not data.endswith(b"\n"):
            os.ftruncate(self._fd, data.rfind(b"\n") + 1)

    def add(self, record: dict) -> "Line":
        """Append `record`; returns where its line is, which `finish` takes in its place (a
        run that keeps the Line, not the record, keeps a few bytes a frame in memory)."""
        line = encode(record)
        data = memoryview(line)
        try:
            # the lock is held: nothing else writes, so the line lands at the present end
            offset = os.lseek(self._fd, 0, os.SEEK_END)
            while data:   # O_APPEND: each write lands at the end
                data = data[os.write(self._fd, data):]
        except OSError as exc:  # a full disk: name the manifest, not only "[Errno 28]"
            raise WriteError(exc.errno, f"{short_path(self.path)}: cannot write: "
                                        f"{exc.strerror or exc}") from None
        return Line(offset, len(line))

    def finish(self, records: list) -> None:
        """Replace the manifest with `records` (dicts, or the Lines `add` returned: read back
        from the journal one at a time, never all at once) atomically.  The new file is locked
        before it takes the manifest's name, so a second run never finds the manifest
        unlocked while this one runs; both locks are held until `close`."""
        with out_of_memory_while(f"writing {self.path}"), \
                atomic_write(self.path, follow_links=False) as f:
            for record in records:
                if isinstance(record, Line):   # the journal's own descriptor: the old file
                    f.write(os.pread(self._fd, record.length, record.offset))
                else:
                    f.write(encode(record))
            kept = os.dup(f.fileno())
            self._held.append(kept)
            fcntl.flock(kept, fcntl.LOCK_EX | fcntl.LOCK_NB)

    def close(self) -> None:
        while self._held:
            os.close(self._held.pop())   # and the lock with it


LOCK_TRIES = 8   # a run finishing replaces its manifest: open and lock again, a few times


def _refused(path: Path, problem: str) -> InputError:
    return InputError("-o", f"{short_path(path)}{problem}")


def _open_locked(path: Path) -> int:
    """A descriptor of the manifest at `path` (made when missing), locked; InputError when a
    run holds it, or when it is a link or not a regular file."""
    for _ in range(LOCK_TRIES):
        try:
            fd = os.open(path, os.O_RDWR | os.O_APPEND | os.O_CREAT | os.O_NOFOLLOW
                         | os.O_CLOEXEC, 0o666)
        except OSError as exc:
            if exc.errno == errno.ELOOP:
                raise _refused(path, " is a symbolic link: a run's manifest (its journal and "
                                     "lock) is never written through a link; replace the link "
                                     "with a copy of its file, or remove it") from None
            raise _refused(path, f": cannot be opened: {exc.strerror}") from None
        if not stat.S_ISREG(os.fstat(fd).st_mode):
            os.close(fd)
            raise _refused(path, " is not a regular file: it cannot be a run's manifest")
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(fd)
            raise _refused(path, ": another run is writing it now; wait for it, or give this "
                                 "one another folder or shard") from None
        try:   # the file locked is still the manifest (a run that finished may have replaced it)
            now = os.stat(path, follow_symlinks=False)
            held = os.fstat(fd)
            if (now.st_dev, now.st_ino) == (held.st_dev, held.st_ino):
                return fd
        except FileNotFoundError:
            pass
        os.close(fd)
    raise _refused(path, ": another run is writing it now (it keeps being replaced); wait "
                         "for it")


def encode(record: dict | bytes) -> bytes:
    """A record as its manifest line (a line already encoded, as it is)."""
    if isinstance(record, bytes):
        return record
    return (json.dumps(record, separators=(",", ":"), allow_nan=False) + "\n").encode()


def rewrite(path: str | Path, records: list[dict]) -> None:
    """Replace the manifest at `path` with `records`, atomically (a link there is replaced, never
    written through)."""
    write_bytes(path, b"".join(encode(r) for r in records), follow_links=False)


def remove_stale_parts(folder: Path, names: set[str], within: Path | None = None) -> int:
    """Remove the temporary files `shadowvol.io.atomic_write` left in `folder` for targets named
    in `names` (a run killed mid-write leaves `.NAME.XXXXXXXX.part`).  Only those: a shard
    running beside this one has its own targets and its temporary files are left alone.  With
    `within` (the output folder), nothing is removed in a folder reached through a link below
    it: that is not the dataset's."""
    if within is not None and outside(within, folder):
        return 0
    removed = 0
    try:
        entries = list(os.scandir(folder))
    except FileNotFoundError:
        return 0
    for entry in entries:
        if entry.name.startswith(".") and entry.name.endswith(".part"):
            target = entry.name[1:-len(".part")].rsplit(".", 1)[0]
            if target in names:
                try:
                    os.unlink(entry.path)
                    removed += 1
                except FileNotFoundError:
                    pass
    return removed


def outside(within: Path, folder: Path) -> bool:
    """`folder` (below `within`) is reached through a symbolic link: not the dataset's."""
    return linked_folder(within, Path(folder) / "_") is not None
