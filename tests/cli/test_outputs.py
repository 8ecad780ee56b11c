"""Where outputs go: symbolic links followed, streams written directly, errors that name the
path the user gave (docs/robustness.md, "Outputs")."""

from __future__ import annotations

import os
import subprocess
import sys
import threading

import pytest
from builders import ROOT, SCENES

from shadowvol.cli.main import main as shadowvol_main
from shadowvol.io import WriteError, atomic_write
from shadowvol.scenefile import load_scene, save_scene

PNG = b"\x89PNG\r\n\x1a\n"


@pytest.fixture
def small(tmp_path):
    path = tmp_path / "cage.json"
    save_scene(load_scene(SCENES / "cage.toml").replace(width=32, height=24), path)
    return path


@pytest.mark.gl
def test_a_symlink_is_followed_not_replaced(small, tmp_path):
    (tmp_path / "real").mkdir()
    target = tmp_path / "real" / "x.png"
    target.write_bytes(b"old")
    link = tmp_path / "link.png"
    link.symlink_to(target)
    assert shadowvol_main(["render", str(small), "-o", str(link)]) == 0
    assert link.is_symlink() and os.readlink(link) == str(target)
    assert target.read_bytes().startswith(PNG)
    assert sorted(p.name for p in (tmp_path / "real").iterdir()) == ["x.png"]


@pytest.mark.gl
def test_a_link_and_its_target_are_one_file(small, tmp_path, capsys):
    (tmp_path / "x.png").write_bytes(b"old")
    (tmp_path / "y.png").symlink_to(tmp_path / "x.png")
    assert shadowvol_main(["render", str(small), "-o", str(tmp_path / "x.png"), "--volumes",
                           str(tmp_path / "y.png")]) == 2
    assert "is also the -o output" in capsys.readouterr().err
    assert (tmp_path / "x.png").read_bytes() == b"old"


@pytest.mark.gl
def test_standard_output_and_a_fifo_are_written_directly(small, tmp_path):
    done = subprocess.run([sys.executable, "-m", "shadowvol", "render", str(small), "-o", "-"],
                          cwd=ROOT, capture_output=True, timeout=120)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith(PNG)
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    got = []
    reader = threading.Thread(target=lambda: got.append(fifo.read_bytes()))
    reader.start()
    assert shadowvol_main(["render", str(small), "-o", str(fifo)]) == 0
    reader.join(timeout=60)
    assert got and got[0].startswith(PNG)
    assert fifo.exists() and not fifo.is_file()  # still the FIFO, not replaced by a file


def test_a_write_error_names_the_path_given(tmp_path):
    (tmp_path / "out").write_text("a file, not a folder")
    with pytest.raises(WriteError) as info:
        with atomic_write(tmp_path / "out" / "x.png") as f:
            f.write(b"data")
    assert str(info.value) == (f"{tmp_path / 'out' / 'x.png'}: cannot write: "
                               f"{tmp_path / 'out'} is not a folder")
    assert ".part" not in str(info.value)
