"""A write that fails in a batch (a full disk: ENOSPC) is one line naming the file that could
not be written, whichever it was (issue 36, step 9), and no half-written file is left.  The
frames are ray traced: no GL."""

from __future__ import annotations

import errno
import json
import os

import pytest
from builders import SCENES

from shadowvol import io
from shadowvol.batch import manifest
from shadowvol.cli import status
from shadowvol.cli.main import main

JOB = {"name": "good", "scene": str(SCENES / "cage.toml"),
       "cameras": {"orbit": {"center": [0, 1, 0], "radius": 6, "frames": 2}},
       "size": [8, 6], "outputs": ["masks"], "renderer": "raytrace", "max_depth": 0}


def full_disk(*args, **kwargs):
    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))


class _FullDiskOs:
    """The manifest module's `os` on a disk that has just filled up: the journal's writes
    (`os.write` on its locked descriptor) fail, everything else is the real `os`."""

    write = staticmethod(full_disk)

    def __getattr__(self, name):
        return getattr(os, name)


@pytest.mark.parametrize("which", ["frame", "manifest"])
def test_a_full_disk_names_the_file(tmp_path, capsys, monkeypatch, which):
    jobs = tmp_path / "jobs.jsonl"
    jobs.write_text(json.dumps(JOB) + "\n")
    out = tmp_path / "out"
    if which == "frame":
        monkeypatch.setattr(io.os, "fsync", full_disk)
        wanted = out / "good" / "000000.masks.npz"
    else:
        monkeypatch.setattr(manifest, "os", _FullDiskOs())
        wanted = out / "manifest.jsonl"
    code = main(["batch", str(jobs), "-o", str(out), "--format", "files", "--no-progress"])
    err = capsys.readouterr().err
    assert code == status.BAD_INPUT
    assert err == f"error: {wanted}: cannot write: No space left on device\n", err
    assert not [p for p in out.rglob("*.part")], "a temporary file was left"
    assert not (out / "good" / "000000.masks.npz").exists() or which == "manifest"
