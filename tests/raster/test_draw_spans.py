"""A frame's draws are runs of triangles, not objects: the soup's spans
(`SceneGeometry.spans`) and the volumes' runs (`volumes.builder.runs_of`) are computed in numpy, and
the number of draw calls of a frame does not grow with the number of objects.

Witnesses: the spans against the set of triangle keys a draw must cover, built triangle by
triangle in plain Python (every triangle of the chosen objects but the holes, then the pieces
of their huge triangles); the runs against merging the ranges one at a time.
"""

from __future__ import annotations

from types import SimpleNamespace

import moderngl
import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from shadowvol.primitives import plane, sphere
from shadowvol.raster.geometry import SceneGeometry
from shadowvol.raster.renderer import Renderer
from shadowvol.raster.volumes.builder import runs_of
from shadowvol.scene import Camera, Material, PointLight, Scene


def _runs_of_keys(keys: list[int]) -> list[tuple[int, int]]:
    """(first, count) of the maximal runs of consecutive integers in sorted `keys`."""
    out: list[list[int]] = []
    for k in keys:
        if out and out[-1][0] + out[-1][1] == k:
            out[-1][1] += 1
        else:
            out.append([k, 1])
    return [(f, c) for f, c in out]


@st.composite
def soups(draw):
    """A soup's object ranges, holes (cut huge triangles) and their pieces, and a sorted
    choice of objects."""
    counts = draw(st.lists(st.integers(0, 6), min_size=1, max_size=12))
    firsts = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
    total = int(sum(counts))
    holes = sorted(draw(st.sets(st.integers(0, max(total - 1, 0)), max_size=total)
                        if total else st.just(set())))
    # every hole cut into 1..3 pieces, in the hole's order
    piece_of = [h for h in holes for _ in range(draw(st.integers(1, 3)))]
    objects = sorted(draw(st.sets(st.integers(0, len(counts) - 1))))
    owner = np.repeat(np.arange(len(counts), dtype=np.int32), counts)
    geometry = SimpleNamespace(
        range_first=firsts, range_count=np.asarray(counts, np.int64),
        holes=np.asarray(holes, np.int64), piece_of=np.asarray(piece_of, np.int64),
        triangle_objects=owner, triangle_count=total)
    return geometry, counts, objects


@settings(max_examples=300, deadline=None)
@given(soups(), st.booleans(), st.sampled_from(["list", "array", "range"]))
def test_spans_are_the_runs_of_the_keys_to_draw(soup, pieces, kind):
    geometry, counts, objects = soup
    if kind == "range":   # every object, as the geometry pass asks
        objects = list(range(len(counts)))
    keys = []
    for i in objects:
        first = int(geometry.range_first[i])
        keys += [t for t in range(first, first + counts[i]) if t not in set(geometry.holes)]
    if pieces:
        keys += [geometry.triangle_count + k for k, t in enumerate(geometry.piece_of)
                 if geometry.triangle_objects[t] in objects]
    chosen = {"list": objects, "array": np.asarray(objects, np.int64),
              "range": range(len(counts))}[kind]
    spans = SceneGeometry.spans(geometry, chosen, pieces=pieces)
    assert spans == _runs_of_keys(sorted(keys))
    assert all(isinstance(f, int) and isinstance(c, int) for f, c in spans)


def test_spans_of_a_range_are_those_of_its_list():
    counts = [3, 0, 2, 4]
    geometry = SimpleNamespace(
        range_first=np.array([0, 3, 3, 5]), range_count=np.array(counts),
        holes=np.array([4], np.int64), piece_of=np.array([4, 4], np.int64),
        triangle_objects=np.repeat(np.arange(4, dtype=np.int32), counts), triangle_count=9)
    assert (SceneGeometry.spans(geometry, range(4))
            == SceneGeometry.spans(geometry, [0, 1, 2, 3])
            == [(0, 4), (5, 6)])   # the soup's last run goes on into the pieces


@settings(max_examples=300, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 40), st.integers(0, 5)), max_size=20))
def test_runs_merge_the_ranges_that_continue_each_other(ranges):
    expected: list[list[int]] = []
    for first, count in ranges:   # one at a time, in their order
        if not count:
            continue
        if expected and expected[-1][0] + expected[-1][1] == first:
            expected[-1][1] += count
        else:
            expected.append([first, count])
    table = np.array(ranges, np.int64).reshape(-1, 2)
    assert runs_of(table[:, 0], table[:, 1]) == [tuple(r) for r in expected]


def _scene(n: int) -> Scene:
    rng = np.random.default_rng(n)
    balls = [sphere(f"ball{i}", [rng.uniform(-4, 4), rng.uniform(0.6, 2.5), rng.uniform(-4, 3)],
                    0.15, Material(), subdivisions=0) for i in range(n)]
    return Scene(camera=Camera(eye=[0, 4, 9], target=[0, 0.8, 0]),
                 objects=[plane("floor", size=[14, 14])] + balls,
                 lights=[PointLight([2, 6, 3])], width=64, height=48)


def test_a_frame_draws_as_many_times_with_many_objects(monkeypatch):
    """The mask-only and the full frame of 300 casters make as many draw calls as those of 3
    (CPU and GPU silhouettes): one per pass and run, none per object."""
    calls = []
    original = moderngl.VertexArray.render

    def counted(self, *args, **kwargs):
        calls.append(1)
        return original(self, *args, **kwargs)

    monkeypatch.setattr(moderngl.VertexArray, "render", counted)
    for silhouettes in ("cpu", "gpu"):
        for outputs in (("lit", "coverage"), ("image", "lit", "coverage")):
            made = []
            for n in (3, 300):
                with Renderer(_scene(n)) as r:
                    r.check_overflow = False   # its re-check is a pass of its own
                    # the same mask-only path for both (300 casters' counts do not fit
                    # beside the bits in the stencil: `Renderer._masks_fit_stencil`)
                    r.masks_in_stencil = False
                    r.render("zpass", silhouettes, outputs=outputs)   # programs, bounds
                    calls.clear()
                    r.render("zpass", silhouettes, outputs=outputs)
                    made.append(len(calls))
            assert made[0] == made[1], (silhouettes, outputs, made)
