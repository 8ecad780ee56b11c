"""`--format istd`: the triplets read back from their PNGs are bit-identical outside the mask
and A <= C inside it; the masks are the `lit`, `lit_count` and `facing_count` outputs of the
same frames; the renderers' float images agree with the same rule; a frame whose mirrors show
a shadow is refused; the CLI writes the layout and a rerun changes nothing."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest
from builders import ROOT, SCENES, job_lines, output_files, write_jobs
from PIL import Image

from shadowvol import batch
from shadowvol.batch.datasets.istd import check_pair, mattes, shadowless
from shadowvol.checks import SceneError
from shadowvol.scenefile import load_scene

pytestmark = pytest.mark.gl

SOFT = {"name": "soft", "scene": str(SCENES / "soft.toml"), "size": [32, 24],
        "cameras": [{"eye": [0.0, 4.2, 6.4], "target": [0.0, 0.4, -0.2]}]}


def _lines():
    lines = job_lines(frames=2, size=(48, 36))
    return lines + [SOFT, dict(SOFT, name="soft-traced", renderer="raytrace")]


@pytest.fixture(scope="module")
def made(tmp_path_factory):
    folder = tmp_path_factory.mktemp("istd")
    lines = _lines()
    jobs = write_jobs(folder / "jobs.jsonl", lines)
    summary = batch.run(jobs, folder / "istd", format="istd", progress=False)
    assert summary.status == 0, summary.errors
    truth = write_jobs(folder / "truth.jsonl", [
        dict(job, outputs=["masks", "facing_count"]) for job in lines])
    assert batch.run(truth, folder / "files", progress=False).status == 0
    return jobs, folder / "istd", folder / "files", lines


def _png(path) -> np.ndarray:
    return np.asarray(Image.open(path))


def _frames(lines):
    for job in lines:
        count = len(job["cameras"]) if isinstance(job["cameras"], list) else \
            job["cameras"]["orbit"]["frames"]
        for index in range(count):
            yield job["name"], index


def test_a_and_c_are_bit_identical_outside_the_mask(made):
    _, istd, _, lines = made
    for job, index in _frames(lines):
        name = f"{index:06d}.png"
        A, B, C = (_png(istd / job / folder / name) for folder in "ABC")
        assert A.shape == C.shape == B.shape + (3,) and B.dtype == np.uint8
        outside, inside = B == 0, B > 0
        assert np.abs(A[outside].astype(int) - C[outside]).max(initial=0) == 0, (job, index)
        assert (A[inside] <= C[inside]).all(), (job, index)
        assert inside.any() and (A[inside] < C[inside]).any(), (job, index)  # a real shadow


def test_masks_are_the_frames_lit_and_facing_counts(made):
    _, istd, files, lines = made
    soft_mattes = 0
    for job, index in _frames(lines):
        stem = f"{index:06d}"
        with np.load(files / job / f"{stem}.masks.npz") as npz:
            lit, coverage = npz["lit"], npz["coverage"]
            lit_count = npz["lit_count"] if "lit_count" in npz.files else lit.astype(np.uint16)
        facing = np.load(files / job / f"{stem}.facing_count.npy").astype(np.int64)
        blocked = facing - lit_count
        want = np.where(facing > 0, np.ceil(255.0 * blocked / np.maximum(facing, 1)), 0)
        got = np.stack([_png(istd / job / "B_light" / f"{stem}_{i:02d}.png")
                        for i in range(len(lit))])
        assert np.array_equal(got, want.astype(np.uint8)), (job, index)
        hard = facing.max(axis=(1, 2)) <= 1
        for i in np.flatnonzero(hard):   # a hard light: 255 exactly at its cast shadow
            cast = (facing[i] > 0) & ~lit[i]
            assert np.array_equal(got[i] == 255, cast) and not (got[i] % 255).any()
        attached = coverage[None] & (facing == 0)
        assert not got[attached].any() and not got[:, ~coverage].any()
        soft_mattes += int(((got > 0) & (got < 255)).sum())
        B = _png(istd / job / "B" / f"{stem}.png")
        assert np.array_equal(B, got.max(axis=0)), (job, index)
        index_file = json.loads((istd / job / "istd.json").read_text())
        record = next(f for f in index_file["frames"] if f["image_id"] == index)
        assert record["mask_pixels"] == int((B > 0).sum())
    assert soft_mattes > 0   # the area light's penumbra is a soft matte


def test_mattes_round_up_and_refuse_inconsistent_counts():
    facing = np.array([[[0, 1, 1, 144, 144, 1000, 1000]]])
    lit = np.array([[[0, 1, 0, 72, 0, 999, 1]]])
    assert mattes(lit, facing).tolist() == [[[0, 0, 255, 128, 255, 1, 255]]]
    with pytest.raises(ValueError, match="lit_count exceeds facing_count"):
        mattes(np.array([[[2]]]), np.array([[[1]]]))


def test_a_pair_that_breaks_the_rule_is_refused():
    free = np.full((2, 3, 3), 0.5, np.float32)
    mask = np.array([[0, 255, 0], [0, 0, 7]], np.uint8)
    shadowed = free.copy()
    shadowed[0, 1] = shadowed[1, 2] = 0.25
    check_pair(shadowed, free, mask)   # darker inside the mask: fine
    drift = shadowed.copy()
    drift[1, 0, 2] = np.nextafter(np.float32(0.5), np.float32(0))   # one ulp outside
    with pytest.raises(SceneError, match="max_depth: .* at 1 pixels outside"):
        check_pair(drift, free, mask)
    brighter = shadowed.copy()
    brighter[0, 1] = 0.75
    with pytest.raises(ValueError, match="brighter"):
        check_pair(brighter, free, mask)


def _float_pair(render, scene):
    """(image, shadow-free image, combined matte) of `scene` by `render(scene, lights)`."""
    image, lit_count, facing = render(scene, scene.lights)
    free, _, _ = render(scene, shadowless(scene.lights))
    return image, free, mattes(lit_count, facing).max(axis=0)


def _check_float(image, free, mask):
    outside = mask == 0
    assert image.dtype == free.dtype and np.issubdtype(image.dtype, np.floating)
    assert np.array_equal(image[outside], free[outside])   # bit for bit
    assert (image[~outside] <= free[~outside]).all() and (image < free).any()


@pytest.mark.parametrize("name", ["cage.toml", "soft.toml"])
def test_float_images_of_both_renderers_are_identical_outside_the_mask(ctx, name):
    import raytrace
    from shadowvol.raster.renderer import Renderer

    scene = load_scene(SCENES / name).replace(width=40, height=30)

    def traced(scene, lights):
        s = scene.replace(lights=lights)
        gt = raytrace.ground_truth(s, outputs=("facing_count",))
        return raytrace.render(s, max_depth=0, progress=False), gt.lit_count, gt.facing_count

    with Renderer(scene, ctx) as r:
        def raster(scene, lights):
            out = r.render(lights=lights, outputs=("image", "lit", "facing_count"))
            return out.image, out.lit_count, out.facing_count
        _check_float(*_float_pair(raster, scene))
    _check_float(*_float_pair(traced, scene))


def test_a_mirror_that_shows_a_shadow_is_refused(tmp_path):
    job = {"name": "mirror", "scene": str(SCENES / "whitted.toml"), "size": [32, 24],
           "renderer": "raytrace", "max_depth": 3,
           "cameras": [{"eye": [0.0, 1.5, 6.0], "target": [0.0, 0.8, 0.0]}]}
    jobs = write_jobs(tmp_path / "jobs.jsonl", [job])
    summary = batch.run(jobs, tmp_path / "out", format="istd", progress=False)
    assert summary.status == 2 and summary.rendered == 0
    record = json.loads((tmp_path / "out" / "manifest.jsonl").read_text().splitlines()[-1])
    assert "max_depth" in record["error"] and "\n" not in record["error"]
    assert not (tmp_path / "out" / "mirror" / "A").exists()
    direct = write_jobs(tmp_path / "direct.jsonl", [dict(job, max_depth=0)])
    assert batch.run(direct, tmp_path / "direct", format="istd", progress=False).status == 0


def test_the_cli_writes_the_layout_and_a_rerun_changes_nothing(made, tmp_path):
    jobs, reference, _, _ = made
    out = tmp_path / "out"
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    command = [sys.executable, "-m", "shadowvol", "batch", str(jobs), "-o", str(out),
               "--format", "istd"]
    for _ in range(2):
        done = subprocess.run(command, env=env,
                              capture_output=True, text=True)
        assert done.returncode == 0, done.stderr
        want, got = output_files(reference), output_files(out)
        assert sorted(got) == sorted(want)
        assert [k for k in want if got[k] != want[k]] == []
    records = [json.loads(line) for line in (out / "manifest.jsonl").read_text().splitlines()]
    assert all(r.get("format") == "istd" for r in records if "files" in r)
