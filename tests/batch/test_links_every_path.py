"""Every path every layout writes: a rerun never writes through a symbolic link (to another
output, or to a file outside the dataset), and a second run into a folder that a run holds
changes nothing of it (docs/robustness.md, "Outputs").

The paths are taken from what each layout wrote, never from a hand list: frames, index files
(transforms.json, annotations.json, scene_*.json), BOP's models and camera.json, tars.  The
manifest is the run's journal and lock: a link there is refused (status 2, one line) and
nothing is touched; a link anywhere else is replaced by the real file."""

from __future__ import annotations

import fcntl
import os
import re
import shutil
import signal
import subprocess
import sys
import time

import pytest
from builders import ROOT, job_lines, write_jobs

from shadowvol import batch
from shadowvol.batch import manifest
from shadowvol.errors import InputError

pytestmark = pytest.mark.gl

LAYOUTS = ("files", "webdataset", "nerfstudio", "bop", "coco", "istd", "soba", "soba-lights")
MANIFEST = "manifest.jsonl"


def _run(jobs, out, layout: str):
    return batch.run(jobs, out, format=layout, progress=False, samples_per_tar=1)


def _tree(out) -> dict[str, bytes | str]:
    """Every entry under `out` (hidden ones too): a link as its target, a file as its bytes."""
    found = {}
    for folder, _, names in os.walk(out):
        for name in names:
            path = os.path.join(folder, name)
            rel = os.path.relpath(path, out)
            found[rel] = ("-> " + os.readlink(path)) if os.path.islink(path) else \
                open(path, "rb").read()
    return found


@pytest.fixture(scope="module")
def references(tmp_path_factory):
    """layout -> (jobs, OUT) of one complete run of 2 tiny frames in it, made once."""
    made = {}

    def reference(layout: str):
        if layout not in made:
            folder = tmp_path_factory.mktemp(f"reference-{layout}")
            jobs = write_jobs(folder / "jobs.jsonl",
                              job_lines(frames=2, size=(40, 30), raytrace=False))
            summary = _run(jobs, folder / "out", layout)
            assert (summary.status, summary.rendered) == (0, 2), summary.errors
            made[layout] = (jobs, folder / "out")
        return made[layout]
    return reference


@pytest.fixture
def made(references, tmp_path):
    """layout -> (jobs, OUT, {path: bytes}): a copy of the layout's reference run to spoil."""
    def make(layout: str):
        jobs, reference = references(layout)
        out = tmp_path / "out"
        shutil.copytree(reference, out, symlinks=True)
        return jobs, out, _tree(out)
    return make


def _outputs(tree: dict) -> list[str]:
    return sorted(p for p in tree if p != MANIFEST)


def _plant(out, path: str, target) -> None:
    os.unlink(out / path)
    os.symlink(target, out / path)


@pytest.mark.parametrize("layout", LAYOUTS)
def test_a_link_to_another_output_at_every_path_is_replaced(made, layout):
    jobs, out, first = made(layout)
    paths = _outputs(first)
    assert len(paths) >= 2, paths
    for links in (paths[0::2], paths[1::2]):    # every path is a link once, to a real output
        targets = [p for p in paths if p not in links]
        aimed = {}
        for path in links:
            aimed[path] = next(t for t in targets if first[t] != first[path])
            _plant(out, path, os.path.relpath(out / aimed[path], (out / path).parent))
        summary = _run(jobs, out, layout)
        assert summary.status == 0, summary.errors
        now = _tree(out)
        for path, target in aimed.items():
            assert now[target] == first[target], f"{target} was written through {path}"
            assert not (out / path).is_symlink(), f"{path} is still a link"
        assert {p: now[p] for p in paths} == {p: first[p] for p in paths}


@pytest.mark.parametrize("layout", LAYOUTS)
def test_a_link_to_a_file_outside_at_every_path_is_replaced(made, tmp_path, layout):
    jobs, out, first = made(layout)
    outside = tmp_path / "outside"
    outside.mkdir()
    paths = _outputs(first)
    for k, path in enumerate(paths):
        (outside / f"{k}").write_bytes(f"not the dataset's: {path}\n".encode())
        _plant(out, path, outside / f"{k}")
    summary = _run(jobs, out, layout)
    assert summary.status == 0, summary.errors
    for k, path in enumerate(paths):
        assert (outside / f"{k}").read_bytes() == f"not the dataset's: {path}\n".encode(), \
            f"the file outside was written through {path}"
    assert {p: v for p, v in _tree(out).items() if p != MANIFEST} == \
        {p: first[p] for p in paths}


@pytest.mark.parametrize("layout", LAYOUTS)
def test_a_manifest_that_is_a_link_is_refused_before_anything_is_touched(made, tmp_path,
                                                                         layout):
    jobs, out, first = made(layout)
    outside = tmp_path / "elsewhere.jsonl"
    outside.write_bytes(first[MANIFEST])
    for target in (_outputs(first)[0], outside):
        (out / MANIFEST).unlink()
        os.symlink(target, out / MANIFEST)
        before = _tree(out)
        with pytest.raises(InputError, match="manifest.jsonl is a symbolic link"):
            _run(jobs, out, layout)
        assert _tree(out) == before
        assert outside.read_bytes() == first[MANIFEST]


@pytest.mark.parametrize("layout", ("files", "nerfstudio", "bop", "coco"))
def test_a_folder_that_is_a_link_is_refused_and_what_it_points_to_is_left(made, tmp_path,
                                                                          layout):
    """A folder of the dataset that is a link (to another of its folders, else to an empty one
    outside) would put files where they do not belong: the write is refused, status 2, and
    no temporary-looking file there is removed as the run's own."""
    jobs, out, first = made(layout)
    folders = sorted(os.path.relpath(f, out) for f, _, _ in os.walk(out) if f != str(out))
    assert folders
    for k, folder in enumerate(folders):
        others = [g for g in folders if g != folder and not g.startswith(folder + os.sep)
                  and not folder.startswith(g + os.sep)]
        for target in [out / g for g in others[:1]] + [tmp_path / f"outside-{k}"]:
            os.rename(out / folder, tmp_path / "moved")
            os.symlink(target, out / folder)
            if not target.exists():   # outside: what the run would take for its temporaries
                target.mkdir()
                for name in os.listdir(tmp_path / "moved"):
                    (target / f".{name}.planted.part").write_bytes(b"not the dataset's")
            before = _tree(target)
            with pytest.raises(OSError, match=re.escape(f"{folder} is a symbolic link")):
                _run(jobs, out, layout)
            assert _tree(target) == before, f"written through the folder link {folder}"
            os.unlink(out / folder)
            os.rename(tmp_path / "moved", out / folder)

def _env() -> dict:
    return dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(ROOT)] + [p for p in os.environ.get("PYTHONPATH", "").split(os.pathsep) if p]))


def test_the_cli_refuses_a_manifest_link_in_one_line(made):
    jobs, out, first = made("coco")
    (out / MANIFEST).unlink()
    os.symlink("cage-turntable/annotations.json", out / MANIFEST)
    done = subprocess.run([sys.executable, "-m", "shadowvol", "batch", str(jobs), "-o",
                           str(out), "--format", "coco"], env=_env(), capture_output=True,
                          text=True, timeout=120)
    assert done.returncode == 2, done.stderr
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "manifest.jsonl is a symbolic link" in lines[0], done.stderr
    assert (out / "cage-turntable" / "annotations.json").read_bytes() == \
        first["cage-turntable/annotations.json"]


def _temporaries(out, tree: dict) -> None:
    """A `.part` beside every output, as a run writing them all at once would have."""
    for k, path in enumerate(_outputs(tree)):
        folder, name = os.path.split(out / path)
        with open(os.path.join(folder, f".{name}.run{k:05d}.part"), "wb") as f:
            f.write(b"half a file of the running run")


@pytest.mark.parametrize("layout", LAYOUTS)
def test_a_refused_second_run_changes_nothing_of_the_running_one(made, layout):
    jobs, out, first = made(layout)
    _temporaries(out, first)
    with open(out / MANIFEST, "ab") as held:   # as the running run's journal holds it
        fcntl.flock(held, fcntl.LOCK_EX | fcntl.LOCK_NB)
        before = _tree(out)
        with pytest.raises(InputError, match="another run is writing"):
            _run(jobs, out, layout)
        assert _tree(out) == before


def test_a_second_cli_run_beside_a_running_one_is_refused_and_the_first_ends_well(tmp_path):
    jobs = write_jobs(tmp_path / "jobs.jsonl", job_lines(frames=60, size=(40, 30),
                                                         raytrace=False))
    out = tmp_path / "out"
    command = [sys.executable, "-m", "shadowvol", "batch", str(jobs), "-o", str(out)]
    first = subprocess.Popen(command, env=_env(), stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while first.poll() is None and b'{"id"' not in _read(out / MANIFEST):
            assert time.monotonic() < deadline, "the first run made no frame in 120 s"
            time.sleep(0.01)
        first.send_signal(signal.SIGSTOP)   # it holds its lock while the second one runs
        assert first.poll() is None, "the first run ended before it was stopped: make it longer"
        planted = out / "cage-turntable" / ".000059.png.inflight.part"
        planted.write_bytes(b"the running run's temporary")
        second = subprocess.run(command, env=_env(), capture_output=True, text=True,
                                timeout=120)
    finally:
        first.send_signal(signal.SIGCONT)
    assert second.returncode == 2, second.stderr
    lines = second.stderr.strip().splitlines()
    assert len(lines) == 1 and "another run is writing" in lines[0], second.stderr
    assert planted.exists(), "the refused run removed the running run's temporary"
    assert planted.read_bytes() == b"the running run's temporary"
    assert first.wait(timeout=300) == 0, first.stderr.read()


def _read(path) -> bytes:
    try:
        return path.read_bytes()
    except FileNotFoundError:
        return b""


def test_a_finished_manifest_stays_locked_until_the_run_closes_it(tmp_path):
    """The manifest is replaced at the end of a run, before the index files are written: the
    new file is locked before it takes the name, so no second run starts in between."""
    path = tmp_path / MANIFEST
    journal = manifest.Journal(path)
    journal.add({"id": "a/000000"})
    journal.finish([{"id": "a/000000"}])
    try:
        with pytest.raises(InputError, match="another run is writing"):
            manifest.Journal(path)
    finally:
        journal.close()
    manifest.Journal(path).close()
    assert path.read_bytes() == b'{"id":"a/000000"}\n'
