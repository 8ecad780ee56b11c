"""`raytrace masks --outputs visibility_exact,irradiance_exact`: the arrays in the NPZ equal the
API's; a sphere light, a bad polygon light and a missing shapely each exit 2 in one line,
writing nothing."""

from __future__ import annotations

import sys

import numpy as np
import pytest

from raytrace.exact_soft import exact_visibility
from shadowvol.cli.raytrace import main
from shadowvol.io import load_mask_arrays
from shadowvol.scenefile import load_scene

SCENE = """
[image]
width = 24
height = 18
[camera]
eye = [0.0, 4.0, 6.0]
target = [0.0, 0.0, 0.0]
fov_y = 45.0
[[lights]]
{light}
samples = 16
[[lights]]
type = "point"
position = [1.0, 3.0, 1.0]
[[objects]]
type = "plane"
size = [6.0, 6.0]
[[objects]]
type = "box"
size = [0.5, 0.5, 0.5]
center = [0.0, 1.0, 0.0]
"""
POLYGON = 'type = "polygon"\nvertices = [{}]'
# an L-shaped hexagon, counter-clockwise seen from below: it emits down onto the floor
L_SHAPE = "[1, 3, -1], [1, 3, 1], [-1, 3, 1], [-1, 3, 0], [0, 3, 0], [0, 3, -1]"


def _scene(tmp_path, light: str):
    path = tmp_path / "s.toml"
    path.write_text(SCENE.format(light=light))
    return path


@pytest.mark.parametrize("light", [
    'type = "rect"\ncenter = [0, 3, 0]\nnormal = [0, -1, 0]\nsize = [1.5, 1.0]',
    'type = "disk"\ncenter = [0, 3, 0]\nnormal = [0, -1, 0]\nradius = 0.7',
    POLYGON.format(L_SHAPE)])
def test_masks_hold_the_exact_outputs(tmp_path, light):
    path = _scene(tmp_path, light)
    out = tmp_path / "m.npz"
    assert main(["masks", str(path), "-o", str(out), "--no-png",
                 "--outputs", "irradiance_exact,depth,visibility_exact"]) == 0
    arrays = load_mask_arrays(out)
    found = exact_visibility(load_scene(path))
    for name, want in (("visibility_exact", found.visibility),
                       ("irradiance_exact", found.irradiance)):
        assert arrays[name].dtype == np.float64 and arrays[name].shape == (2, 18, 24)
        np.testing.assert_array_equal(arrays[name], want)
    v = arrays["visibility_exact"]
    assert 0 < v[0].mean() < 1 and ((v[0] > 0) & (v[0] < 1)).any()   # a penumbra
    # the point light: 1 exactly where lit
    np.testing.assert_array_equal(v[1], arrays["lit"][1].astype(np.float64))
    assert "visibility_exact" not in load_mask_arrays(_all(tmp_path, path))


def _all(tmp_path, path):
    out = tmp_path / "all.npz"
    assert main(["masks", str(path), "-o", str(out), "--no-png", "--outputs", "all"]) == 0
    return out


@pytest.mark.parametrize("light, message", [
    ('type = "sphere"\ncenter = [0, 3, 0]\nradius = 0.3', "lights[0].type: a sphere light"),
    (POLYGON.format("[1, 3, -1], [1, 3, 1], [-1, 3.2, 1], [-1, 3, -1]"),
     "lights[0].vertices: not planar"),
    (POLYGON.format("[2, 3, -1], [-1, 3, 1], [1, 3, 1], [-1, 3, -1]"),
     "lights[0].vertices: edges 0 and 2 cross"),
    (POLYGON.format("[1, 3, -1], [1, 3, 1]"), "lights[0].vertices: expected a list of at least 3"),
    (POLYGON.format("[1, 3, -1], [1, 3, 1], [1, 3, 3]"), "lights[0].vertices: the polygon has no"),
])
def test_bad_lights_exit_2_in_one_line(tmp_path, capsys, light, message):
    path = _scene(tmp_path, light)
    out = tmp_path / "m.npz"
    assert main(["masks", str(path), "-o", str(out), "--outputs", "visibility_exact"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith(f"error: {path}: {message}") and "\n" not in err, err
    assert not out.exists()


def test_missing_shapely_names_the_extra(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "shapely", None)   # import shapely raises ImportError
    path = _scene(tmp_path, POLYGON.format(L_SHAPE))
    out = tmp_path / "m.npz"
    assert main(["masks", str(path), "-o", str(out), "--outputs", "visibility_exact"]) == 2
    err = capsys.readouterr().err.strip()
    assert "pip install 'shadowvol[exact]'" in err and "\n" not in err, err
    assert not out.exists()
