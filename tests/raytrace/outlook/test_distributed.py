"""Distributed ray tracing in the Whitted renderer: each generalisation against the limit case it
generalises (spp 1 is the pixel centre, roughness 0 the mirror, aperture 0 the pinhole), the
antialiased edge against its exact coverage, the samplers against their densities, seeds, the
scene-file keys and the command line."""

from __future__ import annotations

import math

import numpy as np
import pytest
from builders import SCENES, square_light, square_over_floor

import raytrace.outlook.whitted as whitted
from raytrace.camera import primary_rays
from raytrace.outlook.sampling import glossy, phong_exponent, pixel_offsets, stratified
from shadowvol.cameras import calibration, project
from shadowvol.cli.raytrace import main
from shadowvol.primitives import plane, sphere
from shadowvol.scene import Camera, Material, Object, PointLight, Scene, SceneError
from shadowvol.scenefile import load_scene, save_scene, scene_from_dict

BG = np.array([0.1, 0.2, 0.4])
INK = np.array([1.0, 0.9, 0.2])
CAMERA = Camera(eye=[0.0, 0.0, 4.0], target=[0.0, 0.0, 0.0], fov_y=40.0)
FLAT = Material(ambient=list(INK), diffuse=[0, 0, 0], specular=[0, 0, 0])  # colour = INK


def flat_scene(objects, size=24, camera=CAMERA, lights=()) -> Scene:
    """Ambient-only objects (colour exactly INK) on BG: a pixel's box-filtered value is
    BG + (INK - BG) · the fraction of its square the objects cover."""
    return Scene(camera=camera, objects=objects, lights=list(lights), width=size, height=size,
                 ambient=[1, 1, 1], background=list(BG), max_depth=2)


TRIANGLE = np.array([[-2.0, -1.9, 0.0], [1.3, -0.4, 0.0], [-0.35, 2.2, 0.0]])


def triangle_scene(size=24, camera=CAMERA) -> Scene:
    return flat_scene([Object("tri", TRIANGLE, [[0, 1, 2]], FLAT)], size, camera)


def mirror_scene(roughness: float, size=24) -> Scene:
    """A mirror ball reflecting a lit, coloured floor and the background."""
    mirror = Material(ambient=[0, 0, 0], diffuse=[0.05] * 3, specular=[0, 0, 0],
                      reflectivity=0.9, roughness=roughness)
    floor = Material(ambient=[0.3, 0.1, 0.1], diffuse=[0.6, 0.5, 0.2], specular=[0, 0, 0])
    objects = [sphere("ball", center=[0.0, 0.0, 0.0], radius=1.0, material=mirror),
               plane("floor", point=[0, -1, 0], normal=[0, 1, 0], size=[8, 8], material=floor)]
    camera = Camera(eye=[0.0, 0.6, 3.5], target=[0.0, -0.2, 0.0], fov_y=45.0)
    return flat_scene(objects, size, camera, [PointLight([2.0, 3.0, 2.0])])


def coverage(scene: Scene) -> np.ndarray:
    """(H, W) exact fraction of each pixel's square covered by TRIANGLE: the pixel clipped by
    the projected triangle's three half-planes (straight lines stay straight in the image)."""
    cal = calibration(scene)
    tri = project(cal.K, cal.world_to_camera, TRIANGLE)
    (ax, ay), (bx, by) = tri[1] - tri[0], tri[2] - tri[0]
    if ax * by - ay * bx < 0:
        tri = tri[::-1]
    out = np.zeros((scene.height, scene.width))
    for y in range(scene.height):
        for x in range(scene.width):
            poly = [(x, y), (x + 1, y), (x + 1, y + 1), (x, y + 1)]
            for a, b in zip(tri, np.roll(tri, -1, axis=0)):
                poly = _clip(poly, a, b)
            out[y, x] = _area(poly)
    return out


def _clip(poly, a, b):
    """Sutherland-Hodgman: the part of polygon `poly` left of the line a -> b."""
    def side(p):
        return (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])
    out = []
    for p, q in zip(poly, poly[1:] + poly[:1]):
        sp, sq = side(p), side(q)
        if sp >= 0:
            out.append(p)
        if (sp >= 0) != (sq >= 0):
            s = sp / (sp - sq)
            out.append((p[0] + s * (q[0] - p[0]), p[1] + s * (q[1] - p[1])))
    return out


def _area(poly) -> float:
    if len(poly) < 3:
        return 0.0
    x, y = np.array(poly).T
    return 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))


def rms(a, b) -> float:
    return float(np.sqrt(np.mean((a - b) ** 2)))


# ---- spp 1 is today's image ---------------------------------------------------------------

def test_spp_1_is_the_pixel_centre_image_bit_for_bit():
    scene = load_scene(SCENES / "whitted.toml").replace(width=64, height=48)
    world = whitted.World(scene, parallel=False)
    o, d = primary_rays(scene.camera, scene.width, scene.height)
    classic = whitted.trace(world, scene, o, d, scene.max_depth).reshape(48, 64, 3)
    for kwargs in ({}, {"spp": 1, "seed": 7, "pixel_filter": "tent"}):
        assert np.array_equal(whitted.render(scene, progress=False, **kwargs), classic)


def test_cli_spp_1_writes_the_same_bytes(tmp_path):
    text = (SCENES / "whitted.toml").read_text().replace("width = 640", "width = 48") \
        .replace("height = 480", "height = 36")
    path = tmp_path / "w.toml"
    path.write_text(text)
    base = ["render", str(path), "--no-progress"]
    assert main(base + ["-o", str(tmp_path / "a.png")]) == 0
    assert main(base + ["-o", str(tmp_path / "b.png"), "--spp", "1", "--seed", "9"]) == 0
    assert (tmp_path / "a.png").read_bytes() == (tmp_path / "b.png").read_bytes()
    aa = base + ["--spp", "4", "--filter", "tent", "--seed", "3"]
    assert main(aa + ["-o", str(tmp_path / "c.png")]) == 0
    assert main(aa + ["-o", str(tmp_path / "d.png")]) == 0
    assert (tmp_path / "c.png").read_bytes() == (tmp_path / "d.png").read_bytes()
    assert (tmp_path / "c.png").read_bytes() != (tmp_path / "a.png").read_bytes()


@pytest.mark.parametrize("extra, message", [(["--spp", "0"], "--spp: must be >= 1"),
                                            (["--seed", "-1"], "--seed: must be >= 0")])
def test_cli_refuses_bad_sampling(tmp_path, capsys, extra, message):
    assert main(["render", str(SCENES / "whitted.toml"), "-o", str(tmp_path / "x.png")]
                + extra) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "x.png").exists()


# ---- antialiasing -------------------------------------------------------------------------

def test_antialiased_edge_converges_to_the_exact_coverage():
    scene = triangle_scene()
    exact = BG + (INK - BG) * coverage(scene)[..., None]
    errors = [rms(whitted.render(scene, spp=n, seed=1, progress=False), exact)
              for n in (1, 4, 16, 64)]
    # stratified samples of an edge: the error falls about as spp^-3/4 (a factor 2.8 per 4x)
    assert all(b < 0.6 * a for a, b in zip(errors, errors[1:])), errors
    interior = coverage(scene) == 1.0
    image = whitted.render(scene, spp=16, seed=1, progress=False)
    assert np.allclose(image[interior], INK, rtol=0, atol=1e-15)  # no bleeding: box filter


def test_tent_filter_converges_and_blurs_wider_than_the_box():
    scene = triangle_scene(size=16)
    ref = whitted.render(scene, spp=1024, seed=99, pixel_filter="tent", progress=False)
    errors = [rms(whitted.render(scene, spp=n, seed=2, pixel_filter="tent", progress=False),
                  ref) for n in (4, 16, 64)]
    assert all(b < 0.7 * a for a, b in zip(errors, errors[1:])), errors
    box = whitted.render(scene, spp=1024, seed=99, progress=False)
    blurred = lambda im: np.count_nonzero(np.abs(im - BG).sum(-1) > 1e-9)  # noqa: E731
    assert blurred(ref) > blurred(box)  # the tent reaches one pixel past the box


def test_same_seed_same_image_whatever_the_threads(monkeypatch):
    scene = mirror_scene(0.3).replace(camera=Camera(eye=[0.0, 0.6, 3.5],
                                                    target=[0.0, -0.2, 0.0], aperture=0.05))
    monkeypatch.setattr(whitted, "TILE_RAYS", 24 * 4 * 5)  # five rows a tile: five tiles
    monkeypatch.setattr(whitted, "cpu_threads", lambda: 4)
    a = whitted.render(scene, spp=4, seed=5, progress=False)
    assert np.array_equal(a, whitted.render(scene, spp=4, seed=5, progress=False))
    assert not np.array_equal(a, whitted.render(scene, spp=4, seed=6, progress=False))
    monkeypatch.setattr(whitted, "cpu_threads", lambda: 1)
    assert np.array_equal(a, whitted.render(scene, spp=4, seed=5, progress=False))


def test_stratified_layouts_fill_every_stratum():
    rng = np.random.default_rng(0)
    for spp, m in ((16, 4), (5, 5)):
        u = stratified(rng, 3, spp)
        assert u.shape == (3, spp, 2) and ((u >= 0) & (u < 1)).all()
        if spp == 16:  # a 4 x 4 grid: one sample per cell
            cells = np.floor(u * m).astype(int) @ [1, m]
        else:  # N-rooks: one sample per column and per row
            cells = np.floor(u[..., 0] * m).astype(int)
            assert (np.sort(np.floor(u[..., 1] * m), axis=1) == np.arange(m)).all()
        assert (np.sort(cells, axis=1) == np.arange(spp)).all()
    assert (stratified(rng, 2, 1, centre=True) == 0.5).all()
    # jittered, not a regular grid: uniform inside each stratum (variance 1/12)
    inside = (stratified(rng, 4000, 16) * 4) % 1.0
    assert inside.mean() == pytest.approx(0.5, abs=0.01)
    assert inside.var() == pytest.approx(1 / 12, abs=0.005)
    assert stratified(rng, 4000, 1).var() == pytest.approx(1 / 12, abs=0.005)  # lens, gloss


def test_tent_warp_has_the_tent_density():
    u = (np.arange(200000) + 0.5) / 200000
    x = pixel_offsets(np.stack([u, u], -1), "tent")[:, 0] - 0.5  # offset from the centre
    assert x.min() >= -1 and x.max() <= 1 and abs(x.mean()) < 1e-9
    # the tent's CDF at -1/2 is 1/8, its variance 1/6
    assert np.mean(x < -0.5) == pytest.approx(0.125, abs=1e-4)
    assert np.mean(x * x) == pytest.approx(1 / 6, abs=1e-4)
    assert pixel_offsets(np.array([0.5, 0.5]), "tent") == pytest.approx([0.5, 0.5])


# ---- glossy reflection --------------------------------------------------------------------

def test_glossy_lobe_has_the_phong_density():
    rng = np.random.default_rng(3)
    k = 200000
    mirror = np.tile([0.0, 0.0, 1.0], (k, 1))
    for r in (0.2, 0.6, 1.0):
        d = glossy(mirror, mirror, np.full(k, r), rng.random((k, 2)))
        e = phong_exponent(r)
        assert np.allclose(np.linalg.norm(d, axis=1), 1.0)
        # the pdf ∝ cos^e about the mirror direction: E[cos] = (e + 1) / (e + 2)
        assert d[:, 2].mean() == pytest.approx((e + 1) / (e + 2), abs=3e-3)
        assert abs(d[:, 0].mean()) < 5e-3 and abs(d[:, 1].mean()) < 5e-3
    assert (phong_exponent(1.0), phong_exponent(0.5)) == (0.0, 6.0)  # r = 1: uniform
    grazing = np.tile([1.0, 0.0, 0.0], (k, 1))
    up = np.tile([0.0, 0.0, 1.0], (k, 1))
    folded = glossy(grazing, up, np.full(k, 0.5), rng.random((k, 2)))
    assert (folded[:, 2] >= 0).all()  # every ray leaves on the side it came from


def test_roughness_zero_is_the_mirror_and_small_roughness_converges_to_it():
    mirror = whitted.render(mirror_scene(0.0), spp=4, seed=1, progress=False)
    no_key = mirror_scene(0.0)
    assert np.array_equal(mirror, whitted.render(no_key, spp=4, seed=1, progress=False))
    errors = [rms(whitted.render(mirror_scene(r), spp=4, seed=1, progress=False), mirror)
              for r in (0.2, 0.05, 0.0125, 0.003)]
    assert all(b < 0.7 * a for a, b in zip(errors, errors[1:])), errors
    tiny = whitted.render(mirror_scene(1e-7), spp=4, seed=1, progress=False)
    assert np.count_nonzero(np.abs(tiny - mirror).max(-1) > 1e-5) <= 2  # an edge flip at most


def test_glossy_is_a_blur_not_a_loss_of_energy():
    sharp = whitted.render(mirror_scene(0.0), spp=64, seed=1, progress=False)
    rough = whitted.render(mirror_scene(0.2), spp=64, seed=1, progress=False)
    assert rough.mean() == pytest.approx(sharp.mean(), rel=0.03)


# ---- depth of field -----------------------------------------------------------------------

def lens(aperture, focus=None):
    return Camera(eye=[0.0, 0.0, 4.0], target=[0.0, 0.0, 0.0], fov_y=40.0, aperture=aperture,
                  focus_distance=focus)


def test_aperture_zero_is_the_pinhole_and_small_apertures_converge_to_it():
    scene = mirror_scene(0.0)
    pinhole = whitted.render(scene, spp=4, seed=2, progress=False)
    cam = scene.camera

    def with_aperture(a):
        c = Camera(eye=cam.eye, target=cam.target, up=cam.up, fov_y=cam.fov_y, aperture=a,
                   focus_distance=1.0)
        return whitted.render(scene.replace(camera=c), spp=4, seed=2, progress=False)

    assert np.array_equal(with_aperture(0.0), pinhole)
    errors = [rms(with_aperture(a), pinhole) for a in (0.2, 0.05, 0.0125)]
    assert all(b < 0.7 * a for a, b in zip(errors, errors[1:])), errors
    tiny = with_aperture(1e-9)
    assert np.count_nonzero(np.abs(tiny - pinhole).max(-1) > 1e-5) <= 2


def test_the_plane_in_focus_stays_sharp_and_the_rest_blurs():
    sharp = whitted.render(triangle_scene(), spp=16, seed=4, progress=False)
    focused = whitted.render(triangle_scene(camera=lens(0.3)), spp=16, seed=4, progress=False)
    # every lens ray of a pixel sample meets the same point of the plane at the focus distance
    assert np.count_nonzero(np.abs(focused - sharp).max(-1) > 1e-9) <= 2
    blurred = whitted.render(triangle_scene(camera=lens(0.3, focus=2.0)), spp=16, seed=4,
                             progress=False)
    assert rms(blurred, sharp) > 5 * max(rms(focused, sharp), 1e-3)


# ---- soft shadows -------------------------------------------------------------------------

def test_soft_shadows_are_the_area_light_samples_averaged_over_the_pixel():
    scene = square_over_floor(square_light(4), size=24)
    one = whitted.render(scene, progress=False)
    many = whitted.render(scene, spp=64, seed=0, progress=False)
    # the box filter averages each pixel's soft shadow: locally the same light, less alias
    assert many.mean() == pytest.approx(one.mean(), rel=0.02)
    assert rms(many, one) < 0.1 * float(one.mean())


# ---- scene-file keys ----------------------------------------------------------------------

def scene_dict(camera=None, material=None) -> dict:
    return {"camera": {"eye": [0, 0, 4], "target": [0, 0, 0], **(camera or {})},
            "objects": [{"type": "sphere", "center": [0, 0, 0], "radius": 1,
                         "material": {"reflectivity": 0.5, **(material or {})}}]}


@pytest.mark.parametrize("camera, material, message", [
    ({"aperture": -0.1}, None, "camera.aperture: must be >= 0.0, got -0.1"),
    ({"aperture": math.nan}, None, "camera.aperture: non-finite number nan"),
    ({"aperture": 1e300}, None, "camera.aperture: 1e+300 is beyond the float32 range"),
    ({"aperture": "wide"}, None, "camera.aperture: expected a number"),
    ({"focus_distance": 0}, None, "camera.focus_distance: must be > 0.0, got 0"),
    ({"focus_distance": -2.0}, None, "camera.focus_distance: must be > 0.0"),
    ({"focus_distance": math.inf}, None, "camera.focus_distance: non-finite number inf"),
    (None, {"roughness": 1.5}, "objects[0].material.roughness: must be <= 1.0, got 1.5"),
    (None, {"roughness": -0.01}, "objects[0].material.roughness: must be >= 0.0"),
    (None, {"roughness": math.nan}, "objects[0].material.roughness: non-finite number nan"),
    (None, {"roughness": True}, "objects[0].material.roughness: expected a number"),
])
def test_bad_lens_and_roughness_keys_are_one_line_errors(camera, material, message):
    with pytest.raises(SceneError) as err:
        scene_from_dict(scene_dict(camera, material))
    assert message in str(err.value) and "\n" not in str(err.value)


@pytest.mark.parametrize("suffix", [".toml", ".json"])
def test_save_scene_writes_the_new_keys_back(tmp_path, suffix):
    scene = scene_from_dict(scene_dict({"aperture": 0.125, "focus_distance": 3.5},
                                       {"roughness": 0.25}))
    assert scene.camera.focus == 3.5
    save_scene(scene, tmp_path / f"s{suffix}")
    back = load_scene(tmp_path / f"s{suffix}")
    assert (back.camera.aperture, back.camera.focus_distance) == (0.125, 3.5)
    assert back.objects[0].material.roughness == 0.25
    plain = scene_from_dict(scene_dict())
    assert plain.camera.focus == 4.0  # default: the distance to the target
    save_scene(plain, tmp_path / f"p{suffix}")
    text = (tmp_path / f"p{suffix}").read_text()
    assert "aperture" not in text and "roughness" not in text and "focus" not in text
