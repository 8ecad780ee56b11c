"""The intrinsic layers in the batch (docs/CONVENTIONS.md, "Intrinsic layers"): a job's
`outputs` names them, `--format files` writes each a float32 .npy of the frame, from either
renderer, and `shadow_free = ambient + Σ direct` holds in the files (the image identity is
checked on the float images in tests/raster/test_layers_raster.py and tests/raytrace/
test_layers.py: a job's image is an 8-bit PNG)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from builders import SCENES
from layers import identity_tolerance

import shadowvol.batch as batch
from raytrace.outlook.layers import layers
from shadowvol.frame import LAYERS
from shadowvol.scene import Camera
from shadowvol.scenefile import load_scene

CAMERA = {"eye": [4.2, 3.4, 5.2], "target": [-0.6, 1.0, -0.8]}


def _job(renderer: str) -> dict:
    return {"name": f"cage-{renderer}", "scene": str(SCENES / "cage.toml"), "size": [32, 24],
            "renderer": renderer, "cameras": [CAMERA], "outputs": ["image", "masks", *LAYERS],
            **({"max_depth": 0} if renderer == "raytrace" else {})}


def _files(out) -> dict[str, np.ndarray]:
    record = json.loads((out / "manifest.jsonl").read_text().splitlines()[0])
    assert set(record["files"]) == {"image", "masks", *LAYERS}
    return {n: np.load(out / record["files"][n]["path"]) for n in LAYERS}


@pytest.mark.parametrize("renderer", [pytest.param("shadowvol", marks=pytest.mark.gl),
                                      "raytrace"])
def test_a_job_writes_the_layers(tmp_path, renderer):
    out = tmp_path / "out"
    assert batch.run([_job(renderer)], out, progress=False).status == 0
    got = _files(out)
    scene = load_scene(SCENES / "cage.toml")
    L = len(scene.lights)
    assert got["direct"].shape == got["direct_shadowed"].shape == (L, 24, 32, 3)
    assert all(v.dtype == np.float32 for v in got.values())
    total = got["ambient"]
    for part in got["direct"]:
        total = (total + part).astype(np.float32)
    tol = identity_tolerance([got["ambient"], *got["direct"], got["shadow_free"]])
    assert (np.abs(total.astype(np.float64) - got["shadow_free"]) <= tol).all()
    assert (got["direct_shadowed"] <= got["direct"]).all()
    if renderer == "raytrace":   # the job's frame is the scene seen from its camera
        frame = scene.replace(camera=Camera(**CAMERA, fov_y=scene.camera.fov_y),
                              width=32, height=24)
        want = layers(frame)
        for n in LAYERS:
            assert np.array_equal(got[n], want[n]), n
