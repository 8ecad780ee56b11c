"""The deferred frame's outputs and shortcuts must not change a single lit pixel.

- `outputs=`: what is not asked for is not returned; what is asked for is the full frame's,
  bit for bit (mask-only frames shade no colour).
- Lit bits in pages of LIGHTS_PER_PAGE: a frame of more lights gives each light the mask of
  that light alone.
- Back-face culling of closed convex casters (`methods.cullable`, opt-in): only where the box is
  beyond the near plane; on these scenes masks and image identical to the frame without it
  (it is not exact everywhere: a back face that won a float32 depth tie is culled).
- Side quads kept per light (`CpuVolumes.KEPT_BYTES`, every sample of an area light): frames
  with kept volumes equal fresh ones; the kept ones fit in the budget, and a frame that needs
  more keeps its first lights rather than none.
- The sRGB image from the GPU: within one code of `io.encode_srgb`.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest
from builders import mixed_scene

from shadowvol.io import encode_srgb
from shadowvol.raster import methods
from shadowvol.raster.renderer import Renderer
from shadowvol.raster.result import OUTPUTS
from shadowvol.raster.target import LIGHTS_PER_PAGE
from shadowvol.raster.volumes.cpu import CpuVolumes
from shadowvol.scene import AreaLight, Camera


@pytest.mark.parametrize("seed", range(3))
def test_outputs_asked_for_are_the_full_frames(ctx, seed):
    with Renderer(mixed_scene(seed), ctx) as r:
        full = r.render(stencil=True, outputs=OUTPUTS)
        default = r.render()
        masks = r.render(outputs=("lit", "coverage"))
        image = r.render(outputs=("image",))
        srgb = r.render(outputs=("image_srgb",))
    assert default.stencil is None and default.image_srgb is None
    for res in (masks,):
        assert res.image is None and res.image_srgb is None
        np.testing.assert_array_equal(res.lit, full.lit)
        np.testing.assert_array_equal(res.coverage, full.coverage)
    assert image.lit is None and image.coverage is None
    np.testing.assert_array_equal(image.image, default.image)
    np.testing.assert_array_equal(default.lit, full.lit)
    np.testing.assert_array_equal(srgb.image_srgb, full.image_srgb)
    assert full.stencil.shape == full.lit.shape
    # stencil counts are 0 wherever a light is lit
    assert not (full.lit & (full.stencil != 0)).any()


def test_unknown_outputs_are_refused(ctx):
    with Renderer(mixed_scene(0), ctx) as r:
        with pytest.raises(ValueError, match="unknown output 'depht'"):
            r.render(outputs=("image", "depht"))
        with pytest.raises(TypeError):
            r.render(outputs="image")


def test_gpu_srgb_is_within_one_code_of_the_writer(ctx):
    with Renderer(mixed_scene(1), ctx) as r:
        res = r.render(outputs=("image", "image_srgb"))
    ref = encode_srgb(res.image)
    diff = np.abs(res.image_srgb.astype(int) - ref)
    assert diff.max() <= 1, diff.max()
    assert (diff > 0).mean() < 0.01


def test_more_lights_than_a_page(ctx):
    """LIGHTS_PER_PAGE + 2 lights: two shading passes; each light's mask is its own frame's."""
    n = LIGHTS_PER_PAGE + 2
    scene = mixed_scene(2, lights=n)
    with Renderer(scene, ctx) as r:
        res = r.render()
        alone = [r.render(lights=(light,)) for light in scene.lights]
        dark = r.render(lights=())
    for i, one in enumerate(alone):
        np.testing.assert_array_equal(res.lit[i], one.lit[0], err_msg=f"light {i}")
    np.testing.assert_array_equal(res.coverage, alone[0].coverage)
    # the image is the ambient plus every light's term (the second page's sum is blended onto
    # the first's: another order of float32 additions)
    terms = sum(one.image - dark.image for one in alone)
    np.testing.assert_allclose(res.image, dark.image + terms, rtol=1e-5, atol=1e-6)


@pytest.mark.parametrize("seed", range(4))
def test_back_face_culling_changes_no_pixel_here(ctx, seed, monkeypatch):
    scene = mixed_scene(seed)
    with Renderer(scene, ctx) as r:
        cull = methods.cullable(r.geometry.bounds, r.outward_convex, scene.camera,
                                r.geometry.extent)
        assert not cull[0] and cull[1:].all()   # the floor is open, boxes and spheres closed
        r.cull_back_faces = True
        culled = r.render(stencil=seed % 2 == 1)
        r.cull_back_faces = False
        plain = r.render(stencil=seed % 2 == 1)
    np.testing.assert_array_equal(culled.lit, plain.lit)
    np.testing.assert_array_equal(culled.coverage, plain.coverage)
    np.testing.assert_array_equal(culled.image, plain.image)


def test_culling_needs_the_box_beyond_the_near_plane(ctx):
    scene = mixed_scene(0)
    with Renderer(scene, ctx) as r:
        b = r.geometry.bounds[1]
        inside = Camera(eye=(b[0] + b[1]) / 2, target=[0, 0, 0])
        assert not methods.cullable(r.geometry.bounds, r.outward_convex, inside,
                                    r.geometry.extent)[1]
        # the near plane cutting the box: eye just outside it, looking in
        centre = (b[0] + b[1]) / 2
        grazing = Camera(eye=[centre[0], centre[1], b[1][2] + 0.01], target=centre)
        assert not methods.cullable(r.geometry.bounds, r.outward_convex, grazing,
                                    r.geometry.extent)[1]


def test_inward_wound_and_open_meshes_are_not_culled(ctx):
    scene = mixed_scene(0)
    inverted = replace(scene.objects[1], faces=scene.objects[1].faces[:, ::-1].copy())
    scene = scene.replace(objects=[scene.objects[0], inverted, *scene.objects[2:]])
    with Renderer(scene, ctx) as r:
        assert not r.outward_convex[0] and not r.outward_convex[1]
        assert r.outward_convex[2:].all()
        r.cull_back_faces = True
        culled = r.render()
        r.cull_back_faces = False
        plain = r.render()
    np.testing.assert_array_equal(culled.lit, plain.lit)
    np.testing.assert_array_equal(culled.image, plain.image)


def test_kept_side_quads_give_the_same_frames(ctx, monkeypatch):
    scene = mixed_scene(3)
    with Renderer(scene, ctx) as r:
        first = r.render()
        vols = r.volumes("cpu")
        built = []
        original = CpuVolumes._build
        monkeypatch.setattr(CpuVolumes, "_build",
                            lambda self, light4: built.append(1) or original(self, light4))
        moved = Camera(eye=[3, 5, 8], target=[0, 0.5, 0])
        other = r.render(camera=moved)          # the camera moves, the lights do not
        again = r.render()
        assert built == []                      # nothing rebuilt
        assert len(vols._kept) == len(scene.lights)
    with Renderer(scene, ctx) as fresh:
        fresh_other = fresh.render(camera=moved)
    np.testing.assert_array_equal(first.lit, again.lit)
    np.testing.assert_array_equal(first.image, again.image)
    np.testing.assert_array_equal(other.lit, fresh_other.lit)
    np.testing.assert_array_equal(other.image, fresh_other.image)


def _counting_builds(monkeypatch) -> list:
    built = []
    original = CpuVolumes._build
    monkeypatch.setattr(CpuVolumes, "_build",
                        lambda self, light4: built.append(1) or original(self, light4))
    return built


def test_kept_volumes_fit_in_their_budget(ctx):
    scene = mixed_scene(0, lights=1)
    lights = [np.array([0.5 * k, 7.0, 1.0, 1.0]) for k in range(11)]
    with Renderer(scene, ctx) as r:
        vols = r.volumes("cpu")
        vols.prepare(lights[0])
        one = vols._current.nbytes
        assert one > 0
        vols.KEPT_BYTES = 3 * one + one // 2
        for light4 in lights:       # one light per frame: the least recently used go
            vols.new_frame()
            vols.prepare(light4)
            assert sum(v.nbytes for v in vols._kept.values()) <= vols.KEPT_BYTES
        assert list(vols._kept) == [x.tobytes() for x in lights[-3:]]


def test_a_moving_light_leaves_little_behind(ctx):
    """A light that moves every frame: the last two frames' volumes are kept, and of the older
    ones only the most recent within KEPT_OLDER_BYTES."""
    scene = mixed_scene(0, lights=1)
    lights = [np.array([0.5 * k, 7.0, 1.0, 1.0]) for k in range(11)]
    with Renderer(scene, ctx) as r:
        vols = r.volumes("cpu")
        vols.prepare(lights[0])
        one = vols._current.nbytes
        vols.KEPT_OLDER_BYTES = 2 * one + one // 2
        for light4 in lights:
            vols.new_frame()
            vols.prepare(light4)
        assert list(vols._kept) == [x.tobytes() for x in lights[-4:]]
        vols.KEPT_OLDER_BYTES = 0
        vols.new_frame()
        vols.prepare(lights[0])        # this frame's and the last frame's light stay
        assert list(vols._kept) == [lights[-1].tobytes(), lights[0].tobytes()]


def test_a_moving_light_keeps_at_most_so_many_older_volumes(ctx):
    """However few bytes each holds (a small scene), the older lights kept number at most
    KEPT_OLDER_LIGHTS: a long run of moving lights stays bounded (each also holds GL objects)."""
    scene = mixed_scene(0, lights=1)
    with Renderer(scene, ctx) as r:
        vols = r.volumes("cpu")
        vols.KEPT_OLDER_LIGHTS = 5
        for k in range(40):
            vols.new_frame()
            for j in range(3):       # three lights a frame, all moving
                vols.prepare(np.array([0.1 * k, 7.0 + j, 1.0, 1.0]))
        assert len(vols._kept) == 5 + 2 * 3          # five older, this frame's and the last's
        newest = [np.array([0.1 * k, 7.0 + j, 1.0, 1.0]).tobytes()
                  for k in (37, 38, 39) for j in range(3)]
        assert list(vols._kept)[-8:] == newest[-8:]  # the most recent kept, in order of use


def test_a_frame_over_the_budget_keeps_its_first_lights(ctx, monkeypatch):
    scene = mixed_scene(0, lights=1)
    lights = [np.array([0.5 * k, 7.0, 1.0, 1.0]) for k in range(5)]
    with Renderer(scene, ctx) as r:
        vols = r.volumes("cpu")
        vols.prepare(lights[0])
        vols.KEPT_BYTES = 3 * vols._current.nbytes + vols._current.nbytes // 2
        built = _counting_builds(monkeypatch)
        for _ in range(3):          # five lights per frame, three fit: two rebuilt per frame
            built.clear()
            vols.new_frame()
            for light4 in lights:
                vols.prepare(light4)
                assert vols._current is not None and vols._current.buffer is not None
            assert list(vols._kept) == [x.tobytes() for x in lights[:3]]
        assert len(built) == 2


def test_an_area_lights_samples_are_kept_between_frames(ctx, monkeypatch):
    scene = mixed_scene(1, lights=1)
    light = AreaLight("rect", [0.5, 6.0, 1.0], normal=[0, -1, 0], size=[1.5, 1.0],
                      samples=16)
    scene = replace(scene, lights=(light,))
    outputs = ("image", "lit")
    with Renderer(scene, ctx) as r:
        first = r.render(outputs=outputs)
        built = _counting_builds(monkeypatch)
        again = r.render(outputs=outputs)
        assert built == []          # all 16 samples' volumes were kept
    with Renderer(scene, ctx) as fresh:
        fresh.volumes("cpu").KEPT_BYTES = 0   # nothing kept: every sample rebuilt
        built = _counting_builds(monkeypatch)
        rebuilt = fresh.render(outputs=outputs)
        assert len(built) == 16 and not fresh.volumes("cpu")._kept
    for res in (again, rebuilt):
        np.testing.assert_array_equal(res.lit_count, first.lit_count)
        np.testing.assert_array_equal(res.image, first.image)
    assert 0 < first.penumbra.sum()


def test_cross3_is_np_cross_bit_for_bit():
    from shadowvol.raster.projection import cross3
    rng = np.random.default_rng(0)
    for _ in range(2000):
        a = rng.normal(size=3) * 10.0 ** rng.uniform(-6, 6)
        b = rng.normal(size=3) * 10.0 ** rng.uniform(-6, 6)
        np.testing.assert_array_equal(cross3(a, b), np.cross(a, b))


@pytest.mark.parametrize("samples", [9, LIGHTS_PER_PAGE + 5])
def test_one_area_light_gives_the_same_frame_every_time(ctx, samples):
    """One area light of several samples (one page, and more than one): each sample is marked,
    so the unshadowed bits must be cleared every frame, though the scene has one light."""
    from shadowvol.scene import AreaLight
    scene = mixed_scene(1, lights=1)
    scene = scene.replace(lights=[AreaLight("rect", center=[0.5, 6.0, 1.0], normal=[0, -1, 0],
                                            size=[1.5, 1.0], samples=samples, seed=2)])
    with Renderer(scene, ctx) as r:
        frames = [r.render() for _ in range(3)]
        alone = sum(r.render(lights=(h,)).lit[0].astype(int) for h in scene.lights[0].hard)
    for f in frames:
        np.testing.assert_array_equal(f.lit_count[0], alone)
        np.testing.assert_array_equal(f.image, frames[0].image)
    assert 0 < frames[0].lit_count.max() and (frames[0].penumbra.any())


@pytest.mark.parametrize("numpy_has_it", [True, False])
def test_bit_count_counts_set_bits(monkeypatch, numpy_has_it):
    """An area light's lit count is the set bits of its samples in a page (`bits.bit_count`, with
    numpy's bitwise_count or the byte table where numpy has none)."""
    from shadowvol.raster import bits
    if not numpy_has_it:
        monkeypatch.delattr(np, "bitwise_count", raising=False)
    rng = np.random.default_rng(0)
    x = rng.integers(0, 2 ** 32, (37, 53), dtype=np.uint64).astype(np.uint32)
    x[0, :3] = (0, 2 ** 32 - 1, 2 ** 31)
    expected = np.array([bin(int(v)).count("1") for v in x.ravel()]).reshape(x.shape)
    np.testing.assert_array_equal(bits.bit_count(x), expected)


@pytest.mark.parametrize("lights", [1, 3, LIGHTS_PER_PAGE + 2, "area"])
def test_the_srgb_image_from_the_shading_pass_is_the_srgb_passs(ctx, lights, monkeypatch):
    """Without the float image, a frame of one page writes the 8-bit image in its shading pass
    (no float colour, no sRGB pass, the background's code cleared): byte for byte the image
    the sRGB pass encodes from the float colour, background pixels included; a frame of more
    than one page still goes through the float colour."""
    from shadowvol.raster import passes
    scene = mixed_scene(4, 3 if lights == "area" else lights)
    if lights == "area":
        scene = scene.replace(lights=[AreaLight("rect", [0.5, 6.0, 1.0], normal=[0, -1, 0],
                                                size=[1.0, 0.8], samples=9)])
    scene = scene.replace(background=np.array([0.05, 0.3, 0.6]))
    encodes = []
    original = passes.encode_srgb
    monkeypatch.setattr(passes, "encode_srgb",
                        lambda *a, **k: encodes.append(1) or original(*a, **k))
    with Renderer(scene, ctx) as r:
        both = r.render(outputs=("image", "image_srgb", "lit", "coverage"))
        assert len(encodes) == 1
        alone = r.render(outputs=("image_srgb", "lit", "coverage"))
    one_page = lights == "area" or lights <= LIGHTS_PER_PAGE
    assert len(encodes) == (1 if one_page else 2)
    np.testing.assert_array_equal(alone.image_srgb, both.image_srgb)
    np.testing.assert_array_equal(alone.lit, both.lit)
    assert (~both.coverage).any() and both.coverage.any()
    background = both.image_srgb[~both.coverage]
    assert (background == background[0]).all() and background[0].tolist() != [0, 0, 0]
