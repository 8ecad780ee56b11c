"""`compare`: its arithmetic on masks built by hand, its picture, its JSON and exit codes, and
zero interior mismatches on every scene in scenes/ (at reduced size)."""

from __future__ import annotations

import json

import numpy as np
import pytest
from builders import ROOT
from PIL import Image

from shadowvol.cli.main import main as shadowvol_main
from shadowvol.compare import maskdiff
from shadowvol.compare.comparison import NOT_ASKED, POINT_LIGHT_NA, compare
from shadowvol.pictures import GAP
from shadowvol.scenefile import load_scene

SCENE_FILES = sorted(p for p in (ROOT / "scenes").iterdir() if p.suffix in (".toml", ".json"))
SMALL = dict(width=160, height=120)


# ---- the arithmetic, on masks built by hand ---------------------------------------------------

def hand_masks():
    """12 x 12: the bottom row uncovered in both; the reference lights columns 0-5 (rows 0-10).
    The raster shadows a 3x3 block inside the lit part (rows 2-4, columns 1-3: 9 mismatches, of
    which only the centre (3, 2) is away from every edge: the block's own border is an edge of
    the raster's mask) and lights one pixel of the reference's shadow next to its edge (7, 6)."""
    cov = np.ones((12, 12), bool)
    cov[11] = False
    ref = np.zeros((12, 12), bool)
    ref[:11, :6] = True
    got = ref.copy()
    got[2:5, 1:4] = False
    got[7, 6] = True
    return got, cov, ref, cov.copy()


def test_counts_and_iou_by_hand():
    got, got_cov, ref, ref_cov = hand_masks()
    stats = maskdiff.light_stats(got, got_cov, ref, ref_cov)
    assert stats["mismatched"] == 10
    assert stats["interior"] == 1
    # shadows: reference 11 x 6 = 66 pixels; raster 66 - 1 + 9 = 74; both 65; either 75
    assert stats["iou"] == pytest.approx(65 / 75, abs=1e-15)
    # the budget report of the mask tests counts the same
    rows = maskdiff.mask_report(got[None], got_cov, ref[None], ref_cov)
    assert rows == [{"what": "coverage", "total": 0, "interior": 0},
                    {"what": "light 0", "total": 10, "interior": 1}]


def test_interior_needs_a_pixel_away_from_every_edge():
    got, cov, ref, _ = hand_masks()
    near = maskdiff.near_edges(got, cov, ref, cov)
    assert not near[3, 2]                      # the block's centre
    assert near[2, 1] and near[4, 3]            # the block's border: an edge of the raster
    assert near[7, 6] and near[0, 5]            # next to the reference's lit/shadow edge
    assert near[10, 0] and not near[8, 0]      # next to the coverage edge (row 11)
    assert not near[0, 0]                      # the image border is no edge by itself


def test_iou_without_shadows_is_one():
    lit = np.ones((4, 4), bool)
    cov = np.ones((4, 4), bool)
    assert maskdiff.shadow_iou(lit, cov, lit, cov) == 1.0
    assert maskdiff.shadow_iou(lit, cov, ~lit, cov) == 0.0


def test_diff_colours():
    got, got_cov, ref, ref_cov = hand_masks()
    got_cov = got_cov.copy()
    got_cov[11, 11] = True  # the raster sees geometry the ray tracer does not
    p = maskdiff.diff_panel(got, got_cov, ref, ref_cov)
    expect = {(0, 0): maskdiff.BOTH_LIT, (0, 11): maskdiff.BOTH_SHADOWED,
              (3, 2): maskdiff.SHADOWED_ONLY_IN_GOT, (7, 6): maskdiff.SHADOWED_ONLY_IN_REF,
              (11, 0): maskdiff.UNCOVERED, (11, 11): maskdiff.COVERAGE_DIFFERS}
    for (y, x), colour in expect.items():
        assert tuple(p[y, x]) == colour, (y, x)
    assert len({c for _, c in maskdiff.LEGEND}) == len(maskdiff.LEGEND) == 6  # all distinct
    # every pixel has one of the legend's colours
    legend = np.array([c for _, c in maskdiff.LEGEND], np.uint8)
    assert (p[:, :, None, :] == legend).all(axis=-1).any(axis=-1).all()


# ---- real scenes ------------------------------------------------------------------------------

@pytest.mark.parametrize("path", SCENE_FILES, ids=lambda p: p.name)
def test_every_scene_has_no_interior_mismatch(ctx, path):
    c = compare(load_scene(path).replace(**SMALL), ctx=ctx)
    assert len(c.lights) == len(load_scene(path).lights)
    for light in c.lights:
        assert light.interior == 0, c.table()
        assert light.iou > 0.97, c.table()
        # the numbers are those of the masks it returns
        i = light.index
        assert light.mismatched == int((c.raster_lit[i] != c.ref_lit[i]).sum())
        assert light.pyrender_note == NOT_ASKED and light.pyrender_mismatched is None
    assert not c.exceeds(0)
    assert set(c.times_ms) == {"raster_setup", "raster", "raytrace"}
    assert all(t > 0 for t in c.times_ms.values())


def test_zpass_inside_a_shadow_volume_is_over_budget(ctx):
    """The camera of inside_shadow.toml stands in the slab's shadow: z-pass counts wrongly over
    whole regions, so compare must find interior mismatches (and z-fail none)."""
    scene = load_scene(ROOT / "scenes" / "inside_shadow.toml").replace(**SMALL)
    zpass = compare(scene, method="zpass", ctx=ctx)
    worst = max(l.interior for l in zpass.lights)
    assert worst > 100, zpass.table()
    assert zpass.exceeds(worst - 1) and not zpass.exceeds(worst)
    assert min(l.iou for l in zpass.lights) < 0.9


def test_picture_layout(ctx):
    scene = load_scene(ROOT / "scenes" / "stack.toml").replace(width=64, height=48)
    c = compare(scene, ctx=ctx)
    pic = c.picture()
    L, H, W = c.raster_lit.shape
    assert L == 2
    assert pic.dtype == np.uint8 and pic.shape[1] == 3 * W + 2 * GAP
    tops = []
    for i in range(L):  # the difference panel sits in column 3, row i, under its title strip
        panel = maskdiff.diff_panel(c.raster_lit[i], c.raster_coverage, c.ref_lit[i],
                                    c.ref_coverage)
        x = 2 * (W + GAP)
        found = [y for y in range(pic.shape[0] - H + 1)
                 if np.array_equal(pic[y:y + H, x:x + W], panel)]
        assert found, f"light {i}'s difference panel is not in the picture"
        tops.append(found[0])
    assert 0 < tops[0] < tops[1] - H


def test_pyrender_column(ctx):
    """whitted.toml has a point light (pyrender cannot shadow it) and a directional one."""
    scene = load_scene(ROOT / "scenes" / "whitted.toml").replace(width=64, height=48)
    c = compare(scene, pyrender=True, ctx=ctx)
    point, directional = c.lights
    assert point.kind == "point" and point.pyrender_note == POINT_LIGHT_NA
    assert point.pyrender_mismatched is None and c.pyrender_images[0] is None
    assert directional.pyrender_note == ""
    assert directional.pyrender_mismatched >= directional.pyrender_interior >= 0
    assert c.pyrender_images[1].shape == (48, 64, 3)
    assert c.picture().shape[1] == 4 * 64 + 3 * GAP
    assert "pyrender" in c.times_ms
    assert POINT_LIGHT_NA in c.table()


# ---- the command ------------------------------------------------------------------------------

def test_command_json_and_exit_codes(ctx, tmp_path, capsys):
    scene = ROOT / "scenes" / "inside_shadow.toml"
    out, js = tmp_path / "cmp.png", tmp_path / "cmp.json"
    args = ["compare", str(scene), "-o", str(out), "--json", str(js), "--size", "96x72"]
    assert shadowvol_main(args + ["--max-interior", "0"]) == 0
    table = capsys.readouterr().out
    assert "interior" in table and "shadow IoU" in table
    data = json.loads(js.read_text())
    assert (data["scene"], data["width"], data["height"], data["method"]) == \
        ("inside_shadow", 96, 72, "auto")
    assert len(data["lights"]) == len(load_scene(scene).lights)
    for light in data["lights"]:
        assert light["interior"] == 0 and 0.0 <= light["iou"] <= 1.0
        assert light["pyrender"] == NOT_ASKED
    assert Image.open(out).size[0] == 3 * 96 + 2 * GAP

    # z-pass with the eye in a shadow volume: over any small budget -> 1
    assert shadowvol_main(args + ["--method", "zpass", "--max-interior", "0"]) == 1
    worst = max(l["interior"] for l in json.loads(js.read_text())["lights"])
    assert worst > 0
    assert shadowvol_main(args + ["--method", "zpass", "--max-interior", str(worst)]) == 0
    capsys.readouterr()


def test_command_bad_input(tmp_path, capsys):
    out = tmp_path / "cmp.png"
    assert shadowvol_main(["compare", str(tmp_path / "missing.toml"), "-o", str(out)]) == 2
    assert "error:" in capsys.readouterr().err
    for bad in (["--size", "0x10"], ["--size", "ten"], ["--max-interior", "-1"]):
        with pytest.raises(SystemExit) as exc:
            shadowvol_main(["compare", str(ROOT / "scenes" / "cage.toml"), "-o", str(out), *bad])
        assert exc.value.code == 2
    assert not out.exists()
