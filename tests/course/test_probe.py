"""The count probe (shadowvol.course.probe): the volume faces an eye ray crosses, summed as
z-pass and z-fail, equal the stencil the renderer reads back and the ray tracer's shadow ray,
on every shipped scene and on random pixels of random scenes.

Budget: every probed pixel agrees, except pixels within one pixel of a change of the stencil
count, where a pixel centre may lie within rounding of a volume face (as the masks' budget,
issue 3, allows at mask edges)."""

from __future__ import annotations

import numpy as np
import pytest
from builders import SCENES
from hypothesis import given, note
from strategies import profile, scenes

from shadowvol.compare.maskdiff import edge_pixels
from shadowvol.course.probe import Prober, probe
from shadowvol.raster.renderer import Renderer
from shadowvol.scene import hard_lights
from shadowvol.scenefile import load_scene

pytestmark = pytest.mark.gl

SHIPPED = sorted(p.stem for p in SCENES.glob("*.toml"))
SIZE = (48, 36)
STRIDE = 3


def count_edges(stencil: np.ndarray) -> np.ndarray:
    """(H, W) bool: pixels within one pixel of a change of the count."""
    out = np.zeros(stencil.shape, bool)
    for k in np.unique(stencil):
        out |= edge_pixels(stencil == k)
    return out


def check(ctx, scene, pixels, method="auto"):
    """Probe `pixels` ((x, y) pairs) for every light; return the mismatches away from count
    edges (they must be none) and how many were probed."""
    names = [o.name for o in scene.objects]
    with Renderer(scene, ctx) as r:
        frame = r.render(method, stencil=True)
    bad, n = [], 0
    for i in range(len(scene.lights)):
        prober = Prober(scene, i)
        edges = count_edges(frame.stencil[i])
        for x, y in pixels:
            p = prober.probe(x, y, frame.zfail[i], int(frame.stencil[i, y, x]))
            n += 1
            agree = p.predicted == p.stencil
            agree &= p.surface is None or p.zfail_sum() == len(p.shadow_hits) + p.own
            if not frame.zfail[i].any():          # z-pass everywhere: the eye is outside
                agree &= p.zpass_sum() == p.zfail_sum() or p.surface is None
            if not agree and not edges[y, x]:
                bad.append(p.explain(names))
    return bad, n


@pytest.mark.parametrize("name", SHIPPED)
def test_probe_equals_read_back_on_shipped_scenes(ctx, name):
    scene = load_scene(SCENES / f"{name}.toml").replace(width=SIZE[0], height=SIZE[1])
    # the probe counts one hard light's volumes: an area light is probed through two of its
    # samples (each a hard light, counted like a point light)
    scene = scene.replace(lights=tuple(h for lt in scene.lights for h in hard_lights(lt)[:2]))
    if not scene.lights:
        pytest.skip(f"{name} is lit only by emissive surfaces: no shadow volumes to count")
    pixels = [(x, y) for y in range(1, SIZE[1], STRIDE) for x in range(1, SIZE[0], STRIDE)]
    bad, n = check(ctx, scene, pixels)
    assert n >= len(pixels) and not bad, "\n\n".join(bad[:3])


def test_probe_explains_zpass_with_the_eye_inside(ctx):
    scene = load_scene(SCENES / "inside_shadow.toml").replace(width=SIZE[0], height=SIZE[1])
    names = [o.name for o in scene.objects]
    with Renderer(scene, ctx) as r:
        wrong = 0
        for y in range(2, SIZE[1], 6):
            for x in range(2, SIZE[0], 6):
                pz = probe(r, x, y, method="zpass")
                assert pz.predicted == pz.stencil == pz.zpass_sum()      # what z-pass drew
                pf = probe(r, x, y, method="zfail")
                assert pf.predicted == pf.stencil == pf.zfail_sum()
                if pz.surface is not None:
                    assert pf.zfail_sum() == len(pf.shadow_hits) + pf.own
                    if pz.zpass_sum() != pz.zfail_sum():
                        wrong += 1
                        assert pz.eye_inside == pz.zfail_sum() - pz.zpass_sum() > 0
                        assert "z-pass is off by" in pz.explain(names)
    assert wrong > 0


def test_probe_lists_crossings_in_order_with_their_steps(ctx):
    scene = load_scene(SCENES / "stack.toml").replace(width=SIZE[0], height=SIZE[1])
    with Renderer(scene, ctx) as r:
        frame = r.render(stencil=True)
        y, x = np.argwhere(frame.stencil[0] == 8)[0]             # under all four slabs
        p = probe(r, int(x), int(y))
    ts = [c.t for c in p.crossings]
    assert ts == sorted(ts)
    assert p.zfail_sum() == p.stencil == 8 and len(p.shadow_hits) == 8   # 2 per slab
    assert {int(o) for _, o in p.shadow_hits} == {1, 2, 3, 4}
    assert all(c.step == (c.copies if c.entering else -c.copies) for c in p.crossings)


@profile()
@given(scene=scenes())
def test_probe_on_random_pixels_of_random_scenes(ctx, scene):
    rng = np.random.default_rng(scene.width * 7919 + scene.height)
    pixels = [(int(rng.integers(scene.width)), int(rng.integers(scene.height)))
              for _ in range(12)]
    bad, _ = check(ctx, scene, pixels)
    note("\n\n".join(bad[:2]))
    assert not bad, bad[0]
