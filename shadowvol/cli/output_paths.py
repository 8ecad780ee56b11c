"""The output paths a command line names, checked before any work is done.

Each kind of output has the one file format that is written for it, and a path must end in
that format's suffix: a PNG is never written into `out.jpg`, nor a mask file into `m.png`.
Two outputs of one command may not name the same file (a symbolic link and its target are
one file).  "-" (standard output), a device or a FIFO may take any output; it is written to
directly (`shadowvol.io.atomic_write`).
"""

from __future__ import annotations

import os
from pathlib import Path

from shadowvol.errors import InputError
from shadowvol.scene import shorten

SUFFIXES = {"image": ".png", "masks": ".npz", "volumes": ".png", "stencil": ".png",
            "json": ".json", "picture": ".png", "exr": ".exr", "flat": ".png", "png16": ".png"}


def check(paths: dict[str, Path], flags: dict[str, str] | None = None,
          program: str = "shadowvol") -> None:
    """Raise InputError (exit 2) for a path whose suffix is not its kind's, or for two kinds
    naming one file.  `flags` maps a kind to the option that named it (for the message);
    `program`, the command that speaks."""
    flags = flags or {}
    seen: dict[Path, str] = {}
    for kind, path in paths.items():
        flag = flags.get(kind, kind)
        stream = str(path) == "-" or _is_stream(path)
        want = SUFFIXES[kind]
        if not stream and path.suffix.lower() != want:
            raise InputError(flag, f"{str(path)!r} must end in {want} ({program} writes "
                                   f"{want[1:].upper()} there and nothing else)")
        key = Path("-") if str(path) == "-" else _resolved(path, flag)
        if key in seen:
            raise InputError(flag, f"{str(path)!r} is also the {flags.get(seen[key], seen[key])} "
                                   "output; give each output its own file")
        seen[key] = kind


def _resolved(path: Path, flag: str) -> Path:
    """The file `path` names, links followed; InputError for a loop of links."""
    try:
        return Path(path).resolve()
    except (RuntimeError, OSError) as exc:   # a loop: RuntimeError before Python 3.13
        raise InputError(flag, f"{shorten(str(path))} cannot be written: "
                               f"{getattr(exc, 'strerror', None) or 'a loop of symbolic links'}"
                         ) from None


def _is_stream(path: Path) -> bool:
    """An existing device or FIFO (what `atomic_write` streams to instead of replacing)."""
    try:
        real = Path(os.path.realpath(path))
        return real.exists() and not real.is_file() and not real.is_dir()
    except OSError:
        return False
