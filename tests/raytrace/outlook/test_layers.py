"""The ray tracer's intrinsic layers (docs/CONVENTIONS.md, "Intrinsic layers"): both identities
to float32 rounding against `render(max_depth=0)` and the image with every light's shadows off,
the hard lights' lit · direct, and the albedo of a textured quad against its texels."""

from __future__ import annotations

import numpy as np
import pytest
from builders import mixed_scene, overlapping_shadows, switched
from layers import U32, check_albedo, check_identities, check_shadowed, textured_quad

import raytrace
from raytrace.outlook.layers import layers
from shadowvol.frame import LAYERS
from shadowvol.scene import SceneError

SCENES = {"overlapping": lambda: overlapping_shadows(60, 45), "mixed": lambda: mixed_scene(2)}


@pytest.mark.parametrize("name", list(SCENES))
def test_identities(name):
    scene = SCENES[name]()
    got = layers(scene)
    L, H, W = len(scene.lights), scene.height, scene.width
    assert tuple(got) == LAYERS
    assert got["direct"].shape == got["direct_shadowed"].shape == (L, H, W, 3)
    assert all(got[n].shape == (H, W, 3) for n in ("albedo", "ambient", "shadow_free"))
    assert all(v.dtype == np.float32 for v in got.values())
    image = raytrace.render(scene, max_depth=0, progress=False).astype(np.float32)
    free = raytrace.render(switched(scene, lights=range(L)), max_depth=0,
                           progress=False).astype(np.float32)
    check_identities(got, image, free)
    # the shadow-free layer is the image rendered with every light's shadows off, bit for bit
    assert np.array_equal(got["shadow_free"], free)
    check_shadowed(scene, got)
    # shadows there to see: some light is blocked somewhere, and it shows
    assert (got["direct_shadowed"] < got["direct"]).any()
    assert (image < free).any()


def test_a_light_without_shadows_is_its_direct_light():
    scene = switched(overlapping_shadows(40, 30), lights=(0, 3))
    got = layers(scene, ("direct", "direct_shadowed"))
    assert tuple(got) == ("direct", "direct_shadowed")
    for i in (0, 3):
        assert np.array_equal(got["direct"][i], got["direct_shadowed"][i])


def test_albedo_is_the_texel_under_the_pixel(tmp_path):
    scene, tex = textured_quad(tmp_path)
    albedo = layers(scene, ("albedo",))["albedo"]
    # float64 texture lookup rounded once to float32
    assert check_albedo(scene, tex, albedo, atol=4 * U32) > 100


def test_albedo_of_an_untextured_object_is_its_diffuse_colour():
    """Exactly the diffuse colour of the object `object_id` names, but on the pixels beside an
    object_id edge (the masks' float32 primary rays and Whitted's float64 ones may see either
    object there)."""
    scene = mixed_scene(2)
    got = layers(scene, ("albedo",))["albedo"]
    oid = raytrace.ground_truth(scene, ("object_id",)).object_id.astype(np.int64)
    diffuse = np.array([np.zeros(3)] + [o.material.diffuse for o in scene.objects], np.float32)
    padded = np.pad(oid, 1, mode="edge")
    interior = np.ones(oid.shape, bool)
    for dy, dx in ((0, 1), (2, 1), (1, 0), (1, 2)):
        interior &= padded[dy:dy + oid.shape[0], dx:dx + oid.shape[1]] == oid
    assert interior.mean() > 0.9
    assert np.array_equal(got[interior], diffuse[oid[interior]])


def test_unknown_layer_is_refused():
    with pytest.raises(SceneError, match="unknown output"):
        layers(mixed_scene(2), ("albedo", "glow"))


def test_the_layers_go_in_the_mask_file(tmp_path):
    from shadowvol.frame import save_masks

    scene = overlapping_shadows(20, 15)
    got = layers(scene)
    gt = raytrace.ground_truth(scene, ())
    save_masks(tmp_path / "m.npz", gt.lit, gt.coverage, arrays=got)
    with np.load(tmp_path / "m.npz") as f:
        for name in LAYERS:
            assert f[name].dtype == np.float32 and np.array_equal(f[name], got[name])
    with pytest.raises(ValueError, match="direct must be float32"):
        save_masks(tmp_path / "bad.npz", gt.lit, gt.coverage,
                   arrays={"direct": got["direct"][:1]})


def test_tiles_give_the_same_layers(monkeypatch):
    """Rows traced in many tiles (a tile of 2 rows and a ragged last one): the same layers,
    bit for bit, as in one tile."""
    import raytrace.outlook.layers as module

    scene = overlapping_shadows(30, 25)
    whole = layers(scene)
    monkeypatch.setattr(module, "TILE_RAYS", 60)
    for name, value in layers(scene).items():
        assert np.array_equal(value, whole[name]), name
