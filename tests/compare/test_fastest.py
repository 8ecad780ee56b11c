"""shadowvol.compare.fastest: which renderer makes a masks-only request (the cost model's rule,
deterministic, every branch), and that both renderers' masks are the float64 brute force's
(tests/exact.py) away from ties, so that the choice changes tie pixels only."""

from __future__ import annotations

import numpy as np
import pytest
from builders import SCENES
from exact import exact_ties, gl_vertex_ties, lost_bound

from shadowvol.compare import fastest
from shadowvol.compare.maskdiff import mask_report
from shadowvol.frame import mask_file
from shadowvol.scene import light_samples
from shadowvol.scenefile import load_scene

LLVMPIPE = "llvmpipe (LLVM 15.0.6, 256 bits)"
GPU = "NVIDIA GeForce RTX 4090/PCIe/SSE2"
# (triangles, pixels, hard lights) of benchmarks.bench_fastest's scenes where one renderer was
# clearly faster (after a warm-up), and that renderer
MEASURED = [((83_681, 307_200, 3), "raytrace"),     # the turntable: 117-120 ms against 253-256
            ((1_306, 307_200, 144), "shadowvol"),   # soft.toml: 340 ms against 2,116-2,777
            ((962, 921_600, 4), "shadowvol"),       # 1k, 4 lights: 45 ms against 169-267
            ((2_574, 307_200, 2), "shadowvol")]     # whitted.toml: 20 ms against 47-72


@pytest.mark.parametrize("asked", ["shadowvol", "raytrace"])
def test_a_renderer_named_is_the_one_used(asked):
    for gl, queries in ((LLVMPIPE, "packets"), (GPU, "single"), (None, None)):
        choice = fastest.choose(asked, 1000, 100, 1, gl, queries)
        assert (choice.renderer, choice.asked) == (asked, asked)
        assert choice.describe().endswith(f"({asked}: asked for by name)")


def test_an_unknown_renderer_is_refused():
    with pytest.raises(ValueError, match="unknown renderer 'rays'"):
        fastest.choose("rays", 1000, 100, 1, LLVMPIPE, "packets")


def test_auto_without_gl_or_without_embree_or_on_a_gpu():
    assert fastest.choose("auto", 10**6, 10**6, 4, None, "packets").renderer == "raytrace"
    assert fastest.choose("auto", 10, 10, 1, LLVMPIPE, None).renderer == "shadowvol"
    gpu = fastest.choose("auto", 10, 10**6, 144, GPU, "packets")
    assert gpu.renderer == "shadowvol" and GPU in gpu.reason


@pytest.mark.parametrize("sizes, faster", MEASURED)
def test_auto_on_a_software_gl_takes_the_model_s_cheaper_renderer(sizes, faster):
    choice = fastest.choose("auto", *sizes, LLVMPIPE, "packets", first=False)
    raster, rays = fastest.costs(*sizes, "packets", first=False)
    assert (choice.raster_ms, choice.raytrace_ms) == (raster, rays)
    assert choice.renderer == ("raytrace" if rays < raster else "shadowvol") == faster
    assert f"{raster:.0f} ms rasterized, {rays:.0f} ms ray traced" in choice.reason
    # deterministic: the same inputs, the same choice
    assert fastest.choose("auto", *sizes, LLVMPIPE, "packets", first=False) == choice


def test_a_fresh_process_pays_the_packets_kernels_and_single_rays_cost_more():
    sizes = (83_681, 307_200, 3)
    warm, first = (fastest.costs(*sizes, "packets", first=f) for f in (False, True))
    assert first[1] - warm[1] == pytest.approx(fastest.RAYS_FIRST_MS["packets"])
    assert first[0] - warm[0] == pytest.approx(fastest.RASTER_FIRST_MS)
    assert fastest.choose("auto", *sizes, LLVMPIPE, "packets").renderer == "shadowvol"
    single = fastest.costs(*sizes, "single", first=False)
    assert single[1] > warm[1] and single[0] == warm[0]


def test_more_of_anything_costs_more():
    base = (10_000, 100_000, 2)
    for k in range(3):
        more = list(base)
        more[k] *= 2
        assert all(m > b for m, b in zip(fastest.costs(*more), fastest.costs(*base)))


# ---- both renderers' masks: the float64 answer away from ties ----------------------------------

@pytest.mark.gl
@pytest.mark.parametrize("name", ["stack", "whitted", "cage"])
def test_both_renderers_give_the_float64_masks_but_at_ties(ctx, name):
    """The ray tracer equals the float64 brute force wherever the brute force is not a tie;
    the rasterizer too, but within one pixel of a mask edge (GL's 1/64-px vertex precision:
    the shadow-edge ties) and where the visible surface is a GL tie; so the two differ only
    there, and their mask files hold the same camera and light arrays."""
    scene = load_scene(SCENES / f"{name}.toml").replace(width=64, height=48)
    ex_lit, ex_cov, tie = exact_ties(scene, lost_bound(scene))
    made = {r: fastest.masks(scene, r, ctx) for r in ("shadowvol", "raytrace")}
    lit, cov, _ = made["raytrace"]
    assert not ((lit != ex_lit) & ~tie).any()
    assert not ((cov != ex_cov) & ~tie.any(axis=0)).any()
    lit, cov, _ = made["shadowvol"]
    free = ~gl_vertex_ties(scene)
    report = mask_report(lit & free, cov & free, ex_lit & free, ex_cov & free)
    assert sum(r["interior"] for r in report) == 0, report
    assert ex_cov.any() and (ex_cov[None] & ~ex_lit).any() and ex_lit.any()   # a real test
    files = {r: mask_file(*m, light_samples=[light_samples(lt) for lt in scene.lights])
             for r, m in made.items()}
    assert files["shadowvol"].keys() == files["raytrace"].keys()
    for key, value in files["shadowvol"].items():
        if key not in ("lit", "coverage"):
            np.testing.assert_array_equal(value, files["raytrace"][key], err_msg=key)


@pytest.mark.gl
def test_an_area_light_s_counts_come_from_either_renderer(ctx):
    scene = load_scene(SCENES / "soft.toml").replace(width=32, height=24)
    made = {r: fastest.masks(scene, r, ctx)[2] for r in ("shadowvol", "raytrace")}
    for arrays in made.values():
        assert {"lit_count", "samples", "K"} <= set(arrays)
    np.testing.assert_array_equal(made["shadowvol"]["samples"], made["raytrace"]["samples"])
    differ = made["shadowvol"]["lit_count"] != made["raytrace"]["lit_count"]
    assert differ.mean() < 0.05   # the counts' own witness: tests/raster/test_soft_witness_raster


def test_a_scene_s_sizes_and_this_machine_s_queries():
    scene = load_scene(SCENES / "soft.toml")
    assert fastest.scene_sizes(scene) == (1306, 640 * 480, 144)   # the rect light's samples
    assert fastest.ray_queries() in ("packets", "single")
    auto = fastest.choose_for(scene, "auto", LLVMPIPE)
    assert auto == fastest.choose("auto", 1306, 640 * 480, 144, LLVMPIPE, fastest.ray_queries())
    assert fastest.choose_for(scene, "raytrace", None).renderer == "raytrace"
