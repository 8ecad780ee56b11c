"""The 2D shadow-polygon exercise: hand-worked cases, degenerate cases, and a witness check
against the direct definition of shadow (does L -> X cross the segment?)."""

import argparse

import numpy as np
import pytest

from shadowvol.cli import shadow2d as shadow2d_cli
from shadowvol.course import shadow2d as s2
from shadowvol.course.shadow2d import BACK, CONTAINS_LIGHT, EDGE_ON, FRONT

EXACT = 1e-12        # hand-worked numbers are exact up to float rounding
MARGIN = 1e-7        # sample points this close to a region's boundary are not judged


def shoelace(poly):
    x, y = np.asarray(poly).T
    return 0.5 * float(np.sum(x * np.roll(y, -1) - np.roll(x, -1) * y))


def test_hand_worked_front_facing_segment():
    # L = (0.5, 0.2) below the horizontal segment a = (0.4, 0.5) -> b = (0.6, 0.5).
    # d = b - a = (0.2, 0), outward normal n = (d_y, -d_x)/|d| = (0, -1): points down, at L,
    # n . (L - a) = (0, -1) . (0.1, -0.3) = 0.3 > 0, so the segment is front-facing.
    # Ray L -> b: direction (0.1, 0.3); from b it reaches y = 1 after t = 0.5/0.3 = 5/3,
    # x = 0.6 + 0.1 * 5/3 = 23/30 (the right side x = 1 only after t = 4).
    # Ray L -> a: direction (-0.1, 0.3); reaches y = 1 at x = 0.4 - 1/6 = 7/30.
    # Region CCW: a, b, (23/30, 1), (7/30, 1); no corner in between.
    # Trapezoid area = (0.2 + 16/30) / 2 * 0.5 = 11/60.
    (sh,) = s2.shadow_polygons([0.5, 0.2], [[[0.4, 0.5], [0.6, 0.5]]])
    assert sh.facing == FRONT
    np.testing.assert_allclose(sh.region, [[0.4, 0.5], [0.6, 0.5], [23 / 30, 1], [7 / 30, 1]],
                               atol=EXACT)
    assert shoelace(sh.region) == pytest.approx(11 / 60, abs=EXACT)
    cap, ray_b, ray_a = sh.polygons
    assert (cap.kind, ray_b.kind, ray_a.kind) == ("occluder", "ray", "ray")
    np.testing.assert_allclose([cap.start, cap.end, cap.normal], [[0.4, 0.5], [0.6, 0.5], [0, -1]],
                               atol=EXACT)
    # Ray from b, direction (1, 3)/sqrt(10): right normal (3, -1)/sqrt(10), out to the right.
    np.testing.assert_allclose([ray_b.start, ray_b.end], [[0.6, 0.5], [23 / 30, 1]], atol=EXACT)
    np.testing.assert_allclose(ray_b.normal, np.array([3, -1]) / np.sqrt(10), atol=EXACT)
    # Ray back to a runs (7/30, 1) -> (0.4, 0.5), direction (1, -3): right normal (-3, -1)/sqrt(10).
    np.testing.assert_allclose([ray_a.start, ray_a.end], [[7 / 30, 1], [0.4, 0.5]], atol=EXACT)
    np.testing.assert_allclose(ray_a.normal, np.array([-3, -1]) / np.sqrt(10), atol=EXACT)


def test_hand_worked_region_wraps_a_corner():
    # L = (0.5, 0.5), segment a = (0.6, 0.75) -> b = (0.75, 0.6): d = (0.15, -0.15),
    # n = (-1, -1)/sqrt(2), n . (L - a) = (-1, -1) . (-0.1, -0.25) / sqrt(2) > 0: front-facing.
    # Ray L -> b, direction (0.25, 0.1): hits x = 1 after t = 1 at (1, 0.7) (y = 1 only at t = 4).
    # Ray L -> a, direction (0.1, 0.25): hits y = 1 after t = 1 at (0.7, 1).
    # Between them the border passes the corner (1, 1).  Shoelace of
    # (0.6,0.75) (0.75,0.6) (1,0.7) (1,1) (0.7,1): terms -0.2025 -0.075 +0.3 +0.3 -0.075 = 0.2475,
    # area 0.12375.
    (sh,) = s2.shadow_polygons([0.5, 0.5], [[[0.6, 0.75], [0.75, 0.6]]])
    assert sh.facing == FRONT
    np.testing.assert_allclose(sh.region,
                               [[0.6, 0.75], [0.75, 0.6], [1, 0.7], [1, 1], [0.7, 1]], atol=EXACT)
    assert shoelace(sh.region) == pytest.approx(0.12375, abs=EXACT)


def test_back_facing_segment_casts_reversed_or_not_at_all():
    # The same segment as the first case listed the other way round: d = (-0.2, 0), n = (0, 1)
    # points away from L = (0.5, 0.2), n . (L - a) = -0.3 < 0: back-facing.
    seg = [[[0.6, 0.5], [0.4, 0.5]]]
    (two_sided,) = s2.shadow_polygons([0.5, 0.2], seg)
    assert two_sided.facing == BACK
    # As a two-sided occluder it casts the same shadow, and its shadow polygon runs b -> a so that
    # the normal (0, -1) still points at the light, out of the shadow.
    np.testing.assert_allclose(two_sided.region,
                               [[0.4, 0.5], [0.6, 0.5], [23 / 30, 1], [7 / 30, 1]], atol=EXACT)
    np.testing.assert_allclose(two_sided.polygons[0].normal, [0, -1], atol=EXACT)
    (front_only,) = s2.shadow_polygons([0.5, 0.2], seg, back_faces=False)
    assert front_only.facing == BACK and not front_only.casts
    assert front_only.polygons == () and front_only.region.shape == (0, 2)


def test_edge_on_segment_has_zero_area_shadow():
    # L = (0.5, 0.5) lies on the line y = 0.5 of the segment (0.6, 0.5) - (0.8, 0.5), outside it:
    # n . (L - a) = 0.  The segment hides only the line from (0.8, 0.5) to (1, 0.5): zero area,
    # reported as no shadow polygons and an empty region, whichever way the segment is listed.
    for seg in ([[0.6, 0.5], [0.8, 0.5]], [[0.8, 0.5], [0.6, 0.5]]):
        (sh,) = s2.shadow_polygons([0.5, 0.5], [seg])
        assert sh.facing == EDGE_ON
        assert sh.polygons == () and sh.region.shape == (0, 2)
    # A diagonal one: L = (0.2, 0.2) on the line y = x of (0.5, 0.5) - (0.7, 0.7).
    (sh,) = s2.shadow_polygons([0.2, 0.2], [[[0.7, 0.7], [0.5, 0.5]]])
    assert sh.facing == EDGE_ON and not sh.casts


@pytest.mark.parametrize("segment", [
    [[0.3, 0.5], [0.7, 0.5]],   # L in the middle of the segment
    [[0.5, 0.5], [0.9, 0.9]],   # L on the start point
    [[0.1, 0.9], [0.5, 0.5]],   # L on the end point
])
def test_light_on_the_segment_has_zero_area_shadow(segment):
    # L = (0.5, 0.5) on the closed segment: both "rays" lie on the segment's own line, so every
    # point off that line sees L without crossing the segment.
    (sh,) = s2.shadow_polygons([0.5, 0.5], [segment])
    assert sh.facing == CONTAINS_LIGHT
    assert sh.polygons == () and sh.region.shape == (0, 2)
    # The witness agrees: no point of a grid off the line is occluded.
    g = np.stack(np.meshgrid(np.linspace(0.01, 0.99, 40), np.linspace(0.013, 0.993, 40)),
                 -1).reshape(-1, 2)
    assert not s2.occluded(g, [0.5, 0.5], [segment]).any()


def test_nearly_edge_on_segment_casts_a_thin_wedge():
    # L one micro-unit below the line of (0.6, 0.5) - (0.8, 0.5): a genuine, thin shadow.
    (sh,) = s2.shadow_polygons([0.5, 0.5 - 1e-6], [[[0.6, 0.5], [0.8, 0.5]]])
    assert sh.facing == FRONT and len(sh.polygons) == 3
    # Similar triangles: the wedge at x = 1 is 1e-6 * (0.5/0.1 - 0.5/0.3) high, the region is
    # the part beyond the segment; its area is well below 1e-6 but positive.
    assert 0 < shoelace(sh.region) < 1e-6


def test_segment_ending_on_the_border_gives_a_zero_length_ray():
    # L = (0.5, 0.2), a = (0.7, 0.5), b = (1, 0.5) on the right side: the ray from b has zero
    # length.  The ray L -> a, direction (0.2, 0.3), leaves through x = 1 after t = 0.3/0.2 = 1.5
    # at y = 0.5 + 0.45 = 0.95 (y = 1 only at t = 5/3), so the region is the triangle
    # a, b, (1, 0.95), with the repeated vertex b dropped; area 0.3 * 0.45 / 2 = 0.0675.
    (sh,) = s2.shadow_polygons([0.5, 0.2], [[[0.7, 0.5], [1.0, 0.5]]])
    ray_b = sh.polygons[1]
    np.testing.assert_array_equal(ray_b.start, ray_b.end)
    # Its normal comes from the ray's direction (0.5, 0.3): right perpendicular (0.3, -0.5).
    np.testing.assert_allclose(ray_b.normal, np.array([0.3, -0.5]) / np.hypot(0.3, 0.5),
                               atol=EXACT)
    np.testing.assert_allclose(sh.region, [[0.7, 0.5], [1, 0.5], [1, 0.95]], atol=EXACT)
    assert shoelace(sh.region) == pytest.approx(0.0675, abs=EXACT)


def test_border_exit_corner_parameters_agree_from_both_sides():
    # A ray leaving exactly through the corner (1, 1) gets s = 2 whichever side is chosen.
    p, s = s2.border_exit(np.array([[0.5, 0.5], [0.0, 0.5], [0.5, 0.0]]),
                          np.array([[1.0, 1.0], [-1.0, 0.0], [0.0, -1.0]]))
    np.testing.assert_allclose(p, [[1, 1], [0, 0.5], [0.5, 0]], atol=EXACT)
    np.testing.assert_allclose(s, [2.0, 3.5, 0.5], atol=EXACT)


def test_regions_agree_with_the_direct_definition_of_shadow():
    # Seeded random scenes: a point well inside a region must be occluded by that segment, a
    # point well outside must not be; every region is CCW and convex; every shadow polygon's
    # normal is unit, perpendicular, and points out of its region.
    rng = np.random.default_rng(4)
    grid = np.stack(np.meshgrid(np.linspace(0.005, 0.995, 60), np.linspace(0.007, 0.997, 60)),
                    -1).reshape(-1, 2)
    for _ in range(30):
        light = rng.uniform(0.05, 0.95, 2)
        segs = rng.uniform(0, 1, (6, 2, 2))
        shadows = s2.shadow_polygons(light, segs)
        occ = s2.occluded(grid, light, segs)
        for sh in shadows:
            assert sh.casts
            assert shoelace(sh.region) > 0
            surely_in = s2.inside_convex(grid, sh.region, -MARGIN)
            maybe_in = s2.inside_convex(grid, sh.region, MARGIN)
            assert np.all(occ[surely_in, sh.index])
            assert not np.any(occ[~maybe_in, sh.index])
            for poly in sh.polygons:
                assert np.linalg.norm(poly.normal) == pytest.approx(1.0, abs=EXACT)
                edge = poly.end - poly.start
                if np.linalg.norm(edge) > 1e-3:
                    assert abs(edge @ poly.normal) < 1e-9
                    mid = (poly.start + poly.end) / 2
                    step = 1e-4 * poly.normal
                    assert not s2.inside_convex([mid + step], sh.region)[0]
                    assert s2.inside_convex([mid - step], sh.region)[0]


def test_front_faces_of_a_closed_outline_cast_the_whole_shadow():
    # A CCW box with the light outside: outside the box, the union of the front-facing edges'
    # regions equals the union of all edges' regions.
    light = [0.2, 0.3]
    box = s2.polygon_segments([[0.5, 0.5], [0.7, 0.5], [0.7, 0.7], [0.5, 0.7]])
    facing = s2.classify(light, box)
    assert list(facing) == [FRONT, BACK, BACK, FRONT]
    grid = np.stack(np.meshgrid(np.linspace(0.003, 0.997, 80), np.linspace(0.005, 0.995, 80)),
                    -1).reshape(-1, 2)
    outside = ~s2.inside_convex(grid, [[0.5, 0.5], [0.7, 0.5], [0.7, 0.7], [0.5, 0.7]], MARGIN)

    def union(shadows, tol):
        return np.any([s2.inside_convex(grid, sh.region, tol) for sh in shadows if sh.casts],
                      axis=0)
    all_edges = s2.shadow_polygons(light, box)
    front = s2.shadow_polygons(light, box, back_faces=False)
    assert sum(sh.casts for sh in front) == 2
    assert not np.any(union(all_edges, -MARGIN) & outside & ~union(front, MARGIN))
    assert np.any(union(front, -MARGIN) & outside)


def test_bad_input_is_rejected():
    with pytest.raises(ValueError, match="zero length"):
        s2.shadow_polygons([0.5, 0.5], [[[0.2, 0.2], [0.2, 0.2]]])
    with pytest.raises(ValueError, match="inside the unit square"):
        s2.shadow_polygons([0.5, 0.5], [[[0.2, 0.2], [1.2, 0.2]]])
    with pytest.raises(ValueError, match="outside the unit square"):
        s2.shadow_polygons([1.5, 0.5], [[[0.2, 0.2], [0.3, 0.2]]])


def _pixel(size, x, y):
    # draw_shadow2d's axes fill [0.06, 0.94] of the figure and show [-0.03, 1.03].
    fx = 0.06 + 0.88 * (x + 0.03) / 1.06
    fy = 0.06 + 0.88 * (y + 0.03) / 1.06
    return int(round((1 - fy) * size)), int(round(fx * size))


def test_picture_shades_the_region():
    size = 300
    img = s2.draw_shadow2d([0.5, 0.2], [[[0.4, 0.5], [0.6, 0.5]]], size_px=size)
    assert img.shape == (size, size, 3) and img.dtype == np.uint8
    shadow = img[_pixel(size, 0.5, 0.85)].astype(int)
    lit = img[_pixel(size, 0.15, 0.6)].astype(int)
    assert np.all(lit == 255)
    assert np.all(shadow < 230) and np.ptp(shadow) < 10     # grey


def _run(argv, capsys):
    ap = argparse.ArgumentParser()
    shadow2d_cli.add_parser(ap.add_subparsers())
    args = ap.parse_args(["shadow2d", *argv])
    code = args.func(args)
    return code, capsys.readouterr()


def test_cli_reads_a_file_prints_the_polygons_and_writes_the_picture(tmp_path, capsys):
    src = tmp_path / "two.toml"
    src.write_text('light = [0.5, 0.2]\nsegments = [[0.4, 0.5, 0.6, 0.5]]\n'
                   'polygons = [[[0.1, 0.1], [0.2, 0.1], [0.15, 0.15]]]\n')
    out = tmp_path / "pic.png"
    code, cap = _run([str(src), "--segment", "0.6", "0.5", "0.8", "0.5", "-o", str(out),
                      "--size", "200"], capsys)
    assert code == 0
    assert "segment 0: (0.4000, 0.5000) -> (0.6000, 0.5000)" in cap.out
    assert "(0.7667, 1.0000)" in cap.out and "(0.2333, 1.0000)" in cap.out
    assert "segment 4: (0.6000, 0.5000) -> (0.8000, 0.5000)" in cap.out
    from PIL import Image
    assert Image.open(out).size == (200, 200)


def test_cli_command_line_only_and_errors(capsys):
    code, cap = _run(["--light", "0.5", "0.5", "--segment", "0.6", "0.5", "0.8", "0.5"], capsys)
    assert code == 0 and "edge-on" in cap.out and "zero-area" in cap.out
    code, cap = _run(["--light", "0.5", "0.5"], capsys)
    assert code == 2 and "no segments" in cap.err
    code, cap = _run(["--polygon", "0.1", "0.1", "0.2"], capsys)
    assert code == 2 and "pairs" in cap.err
