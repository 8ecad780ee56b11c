"""`raytrace.facingkernels`: a member turned one way from a block's points, told from its
first point and a ball about it, against each point's own test."""

from __future__ import annotations

import numpy as np
import pytest

from raytrace import polygons

pytest.importorskip("numba", reason="the block path's kernels need the `fast` extra")
FACING = 2.0 ** -20      # `exactkernels.FACING`, the points' own test


def _block(rng, side: int, pitch: float) -> np.ndarray:
    """side x side points a pitch apart on a tilted patch below the light's plane z = 2."""
    u, v = np.meshgrid(np.arange(side), np.arange(side))
    tilt = rng.normal(size=(2, 3)) * [1, 1, 0.3]
    return rng.uniform(-1, 1, 3) * [1, 1, 0.2] + pitch * (
        u.reshape(-1, 1) * tilt[0] + v.reshape(-1, 1) * tilt[1])


def _member(rng, p: np.ndarray, ball: float) -> np.ndarray:
    """A small triangle between the points p and the light, its plane passing about the ball
    about p[0]: at ball x 10^(-1..1) from it, now and then just in or out of it, or (one
    in five) facing the farthest point p[-1] from just beyond it, by under twice FACING of
    its distance (nearly edge-on from there)."""
    normal = rng.normal(size=3)
    gap = ball * (10.0 ** rng.uniform(-1, 1) if rng.random() < 0.6 else
                  1 + rng.uniform(-1e-3, 1e-3) * 10.0 ** rng.uniform(-9, 0))
    way = rng.choice([-1, 1])
    edge_on = rng.random() < 0.2
    if edge_on:
        normal, way = p[-1] - p[0], 1
    normal /= np.linalg.norm(normal)
    centre = p[0] + rng.uniform(0.3, 1.5) * np.array([0, 0, 1.0]) + rng.normal(0, 0.2, 3)
    if edge_on:
        centre -= (centre - p[0]) @ normal * normal
        gap = np.linalg.norm(p[-1] - p[0]) + rng.uniform(0, 2) * FACING * np.linalg.norm(
            centre - p[-1])
    centre -= ((centre - p[0]) @ normal - gap * way) * normal
    size = 10.0 ** rng.uniform(-3, -1)
    a = np.cross(normal, rng.normal(size=3))
    a /= np.linalg.norm(a)
    b = np.cross(normal, a)
    return centre + size * np.array([a, -a / 2 + b, -a / 2 - b])


def _each_point(corners: np.ndarray, p: np.ndarray, low_top, high_top, far_rel, reach):
    """The witness: +1 or -1 where every point's own float test (`_steady`'s, in numpy)
    turns the member that way, free and within reach; 0 where some point's does not."""
    normal = np.cross(corners[1] - corners[0], corners[2] - corners[0])
    normal /= np.linalg.norm(normal)
    h = 2.0 - corners[:, 2]
    if not (h.min() >= 0 and h.max() < low_top and h.min() < high_top):
        return 0
    span = np.linalg.norm(corners.max(axis=0) - corners.min(axis=0))
    grow = high_top / (low_top - h.max())
    r = p - corners[0]
    dist = np.sqrt((r * r).sum(axis=1))
    s = r @ normal
    turned = (np.abs(s) > FACING * dist) & (np.sign(s) == np.sign(s[0]))
    within = (far_rel + grow * (dist + span)) * (1 + 2.0 ** -30) < reach
    return int(np.sign(s[0])) if turned.all() and within.all() else 0


@pytest.mark.parametrize("seed", range(6))
def test_the_first_point_tells_only_what_every_point_tells(seed):
    """`_facing` against every point's own test (the witness, numpy): wherever it gives +1 or
    -1, each point of the block sees the member turned that way, free and within reach.
    Blocks of 2 x 2 to 4 x 4 points on tilted patches; small triangles whose planes pass
    at a tenth to ten times the ball's radius from the first point, or within a thousandth
    of it (and as little as 1e-12 of that), at either side; reaches just about the points'
    own bounds.  It gives a sign for every member clear of its margins and for none that
    some point sees edge-on or turned the other way, or out of reach (a ball or a reach
    left out of its bound fails here)."""
    kernels = polygons.kernels("facingkernels")
    rng = np.random.default_rng(seed)
    clear = 0
    for trial in range(400):
        side = 2 + trial % 3
        p = _block(rng, side, 10.0 ** rng.uniform(-4, -2))
        top = 2.0 - p[:, 2]
        rel = np.linalg.norm(p - [0, 0, 2.0], axis=1)
        low_top, high_top, far_rel, ball = kernels._tops(0, len(p), top, rel, p)
        corners = _member(rng, p, ball[0])
        h = (2.0 - corners[:, 2])[None, None]
        packed = np.zeros((1, 1, 16))
        packed[0, 0, :3], packed[0, 0, 3:6] = corners.min(axis=0), corners.max(axis=0)
        normal = np.cross(corners[1] - corners[0], corners[2] - corners[0])
        packed[0, 0, 6:9] = normal / np.linalg.norm(normal)
        packed[0, 0, 12:15] = corners[0]
        # a reach about the points' own most bound: just over it, or just under; or well
        # over it, every other trial
        span = np.linalg.norm(corners.max(axis=0) - corners.min(axis=0))
        most = far_rel + high_top / (low_top - h.max()) * (
            np.linalg.norm(p - corners[0], axis=1).max() + span)
        reach = most * 10.0 ** (rng.uniform(-1e-3, 1e-2) if trial % 2 else rng.uniform(0, 1))
        want = _each_point(corners, p, low_top, high_top, far_rel, reach)
        got, shape = kernels._facing(0, 0, packed, h, ball, low_top, high_top, far_rel, reach)
        assert got in (0, want), (seed, trial, got, want)
        if want == 0:
            continue
        assert kernels._steady(0, 0, 0, len(p), packed, shape, p, low_top, high_top,
                               far_rel, reach, False) == want
        # clear of the bound's margins (the plane beyond twice the ball, the reach 1 %
        # over the ball's farthest point's bound): told there
        d = np.linalg.norm(p[0] - corners[0])
        grow = high_top / (low_top - h.max())
        if abs((p[0] - corners[0]) @ packed[0, 0, 6:9]) > 2 * ball[0] + 1e-5 * d and \
                reach > 1.01 * (far_rel + grow * (d + ball[0] + span)):
            assert got == want, (seed, trial)
            clear += 1
    assert clear > 30, clear


def test_a_blocks_own_triangles_each_once_in_order():
    """`_distinct`: each triangle of own once, in the order first seen, however repeated."""
    kernels = polygons.kernels("facingkernels")
    rng = np.random.default_rng(3)
    for _ in range(200):
        own = rng.integers(0, rng.integers(1, 12), rng.integers(1, 17))
        owns = np.full(len(own), -1)
        n = kernels._distinct(0, len(own), own, owns)
        _, first = np.unique(own, return_index=True)
        assert owns[:n].tolist() == own[np.sort(first)].tolist()
