"""`compare` on area lights: per-sample counts, their numbers and their picture."""

from __future__ import annotations

import json

import numpy as np
import pytest
from builders import square_light, square_over_floor

import raytrace
from shadowvol.cli.main import main as shadowvol_main
from shadowvol.compare import compare
from shadowvol.compare.maskdiff import count_edges, count_stats
from shadowvol.scene import PointLight
from shadowvol.scenefile import save_scene


def test_counts_reported_per_area_light(ctx):
    scene = square_over_floor(square_light(16), size=64)
    scene = scene.replace(lights=scene.lights + (PointLight([0.5, 3.0, 0.5]),))
    c = compare(scene, ctx=ctx)
    area, point = c.lights
    assert area.samples == 16 and area.kind == "rect"
    assert area.counts_interior == 0 and area.counts_differ <= 2, c.table()
    assert point.counts_differ is None and point.samples == 1
    np.testing.assert_array_equal(c.ref_counts[0], raytrace.soft_masks(scene).lit_count[0])
    assert c.raster_counts.dtype == np.uint16 and c.ref_counts.shape == (2, 64, 64)
    assert "16 samples: counts differ at" in c.table()
    assert c.to_dict()["lights"][0]["counts"]["interior"] == 0
    assert "counts" not in c.to_dict()["lights"][1]
    # one row per light, and one more for the area light's visibility
    picture = c.picture()
    assert picture.shape[0] > 3 * 64 and picture.dtype == np.uint8


def test_count_stats_find_a_wrong_count_off_the_edges():
    """A count off by one in the middle of a uniform region is interior; on an edge it is not."""
    cov = np.ones((9, 9), bool)
    ref = np.full((9, 9), 4, np.uint16)
    ref[:, 6:] = 2  # an edge at column 5/6
    no_edges = np.zeros((9, 9), bool)
    got = ref.copy()
    got[4, 2] = 3
    stats = count_stats(got, cov, ref, cov, no_edges)
    # the wrong pixel is an edge of got's count, as a sample's edge there would be: it is
    # the raster's count image, not the reference's, that shows it
    assert count_edges(got)[4, 2] and stats["counts_differ"] == 1
    assert stats["counts_largest"] == 1
    wide = ref.copy()
    wide[3:6, 1:4] = 3  # a 3x3 block off by one: its centre is on no edge of got's count
    stats = count_stats(wide, cov, ref, cov, no_edges)
    assert stats["counts_interior"] == 1 and stats["counts_differ"] == 9


def test_command_line_json_has_the_counts(tmp_path):
    scene = square_over_floor(square_light(4), size=32)
    save_scene(scene, tmp_path / "s.json")
    out = tmp_path / "cmp.png"
    assert shadowvol_main(["compare", str(tmp_path / "s.json"), "-o", str(out), "--json",
                     str(tmp_path / "n.json"), "--max-interior", "0"]) == 0
    numbers = json.loads((tmp_path / "n.json").read_text())
    assert numbers["lights"][0]["samples"] == 4
    assert numbers["lights"][0]["counts"]["interior"] == 0


def test_pyrender_refuses_area_lights_plainly():
    from shadowvol.compare.pyrender_peer import _pr_light

    with pytest.raises(ValueError, match="pyrender has no area lights"):
        _pr_light(square_light(4), np.zeros((1, 3, 3)))
