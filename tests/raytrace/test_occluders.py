"""`occluders._topology`: a closed, consistently wound surface found, and every way to miss
being one refused (the quick test on the welded ids, `_closed`, must agree with the whole)."""

from __future__ import annotations

import numpy as np
import pytest
import trimesh

from raytrace.occluders import _closed, _topology


def _ball():
    ico = trimesh.creation.icosphere(subdivisions=2)
    return ico.vertices[ico.faces], np.asarray(ico.faces) * 7 + 3   # welded ids, not compact


def test_a_closed_ball_has_a_topology():
    corners, welded = _ball()
    points, edges, sides = _topology(corners, welded)
    assert _closed(welded)
    assert len(points) == len(np.unique(welded)) and len(edges) == 3 * len(welded) // 2
    assert (sides[:, 0] != sides[:, 1]).all()


@pytest.mark.parametrize("broken", ["a face missing", "a face flipped", "a face twice",
                                    "an edge of one corner"])
def test_every_other_surface_has_none(broken):
    corners, welded = _ball()
    if broken == "a face missing":
        corners, welded = corners[1:], welded[1:]
    elif broken == "a face flipped":
        welded = welded.copy()
        welded[0] = welded[0, ::-1]
    elif broken == "a face twice":
        corners, welded = np.concatenate([corners, corners[:1]]), np.r_[welded, welded[:1]]
    else:
        welded = welded.copy()
        welded[0, 1] = welded[0, 0]
    assert not _closed(welded)
    assert _topology(corners, welded) is None
