"""The numba shading of the path tracer (`raytrace.outlook.path.pathkernels`) against the numpy
reference: the same random numbers and the same arithmetic, so the same samples; and how one is
chosen.

Bit-identical wherever no power is taken (Lambertian, mirror and glass materials, every kind
of light, the background).  With a glossy lobe, cos^s is computed by libm's powf in the kernel
and by numpy's SIMD power in the reference: they differ by one float32 ulp in ~13% of cases, a
relative ~1e-7 that products carry on, so pixels agree within GLOSSY_RELATIVE, except where
that rounding flips a Russian-roulette choice and the path goes on differently
(GLOSSY_DIVERGED_FRACTION of the pixels, at most).
"""

from __future__ import annotations

import numpy as np
import pytest
from builders import ROOT, TEST_OUTPUT, cornell

pytest.importorskip("numba", reason="the numba shading needs numba: "
                    "pip install 'shadowvol[fast]'")

from raytrace.outlook.path import pathtrace  # noqa: E402
from raytrace.outlook.path.pathstate import PathWorld  # noqa: E402
from raytrace.outlook.path.pathtrace import render, shading, trace_paths  # noqa: E402
from shadowvol.errors import InputError, MissingExtra  # noqa: E402
from shadowvol.io import save_png  # noqa: E402
from shadowvol.primitives import box, plane, sphere  # noqa: E402
from shadowvol.scene import (  # noqa: E402
    AreaLight,
    Camera,
    DirectionalLight,
    Material,
    PointLight,
    Scene,
    SpotLight,
)
from shadowvol.scenefile import load_scene  # noqa: E402

GLOSSY_RELATIVE = 1e-5  # a few float32 ulps of the pixel, carried through a path's products
GLOSSY_DIVERGED_FRACTION = 0.01


def both(scene, **kwargs):
    """The numpy and the numba render of `scene`, same arguments."""
    a = render(scene, shading_name="numpy", progress=False, **kwargs)
    b = render(scene, shading_name="numba", progress=False, **kwargs)
    assert (a.shading, b.shading) == ("numpy", "numba")
    return a, b


def write_pair(name: str, a, b) -> str:
    out = TEST_OUTPUT / name
    save_png(out / "numpy.png", np.clip(a.image, 0, 1))
    save_png(out / "numba.png", np.clip(b.image, 0, 1))
    diff = np.abs(a.image - b.image).max(axis=2)
    save_png(out / "diff.png", np.repeat((diff > 0)[..., None], 3, axis=2).astype(float))
    return str(out)


def assert_identical(name: str, a, b):
    if not (np.array_equal(a.image, b.image) and np.array_equal(a.variance, b.variance)):
        out = write_pair(name, a, b)
        bad = (a.image != b.image).any(axis=2)
        pytest.fail(f"{bad.sum()} of {bad.size} pixels differ, by up to "
                    f"{np.abs(a.image - b.image).max():.3g}; images written to {out}")
    assert a.rays == b.rays


def every_light_scene() -> Scene:
    """Lambertian, mirror and glass surfaces (no glossy lobe: no power is taken), an emissive
    box, and a point, a directional, a spot and a rect area light, before a coloured
    background."""
    grey = Material(diffuse=[0.6, 0.55, 0.5], specular=[0, 0, 0])
    mirror = Material(diffuse=[0.1, 0.1, 0.1], specular=[0, 0, 0], reflectivity=0.8)
    glass = Material(diffuse=[0.02, 0.02, 0.02], specular=[0, 0, 0], reflectivity=0.05,
                     transparency=0.9, ior=1.5)
    lamp = Material(diffuse=[0.2, 0.2, 0.2], specular=[0, 0, 0], emission=[4.0, 3.0, 2.0])
    return Scene(
        camera=Camera(eye=[0.0, 2.0, 5.0], target=[0.0, 0.6, 0.0], fov_y=50.0),
        objects=[plane("floor", size=(8.0, 8.0), material=grey),
                 box("mirror", center=(-1.0, 0.5, -0.5), size=(0.8, 1.0, 0.8),
                     material=mirror),
                 sphere("glass", center=(0.7, 0.6, 0.3), radius=0.6, material=glass),
                 box("lamp", center=(0.0, 2.2, -1.0), size=(0.6, 0.1, 0.6), material=lamp)],
        lights=[PointLight(position=[-2.0, 3.0, 2.0], intensity=0.5),
                DirectionalLight(direction=[0.3, -1.0, -0.2], intensity=0.3),
                SpotLight(position=[2.0, 3.0, 1.0], direction=[-0.5, -1.0, -0.3],
                          cone_angle=30.0, intensity=0.8),
                AreaLight("rect", [0.5, 3.0, 1.5], normal=[0.0, -1.0, 0.0], size=[0.8, 0.8],
                          samples=4, intensity=0.6)],
        width=40, height=30, ambient=[0, 0, 0], background=[0.2, 0.3, 0.5])


def test_cornell_box_is_bit_identical():
    a, b = both(cornell(24), spp=3, seed=11)
    assert_identical("pathkernels-cornell", a, b)
    assert a.image.max() > 0.05  # something was lit


def test_every_light_kind_mirror_glass_and_background_bit_identical():
    scene = every_light_scene()
    a, b = both(scene, spp=4, seed=2)
    assert_identical("pathkernels-every-light", a, b)
    # the scene exercises what it says: the background shows, and the delta lights light it
    # (the image without them is darker)
    assert np.isclose(a.image, scene.background, rtol=1e-6).all(axis=2).any()
    dark = render(scene.replace(lights=[]), spp=4, seed=2, shading_name="numba",
                  progress=False)
    assert a.image.mean() > 1.2 * dark.image.mean()


def test_whitted_scene_agrees_to_float32_rounding():
    """Glossy Phong everywhere, a mirror and a glass sphere, a point and a directional light:
    the one difference is the power in the glossy lobe (see the module docstring)."""
    scene = load_scene(ROOT / "scenes" / "whitted.toml").replace(width=40, height=30)
    a, b = both(scene, spp=4, seed=5)
    diff = np.abs(a.image - b.image).max(axis=2)
    scale = np.maximum(np.abs(a.image).max(axis=2), 1e-3)
    diverged = diff > GLOSSY_RELATIVE * scale
    if diverged.mean() > GLOSSY_DIVERGED_FRACTION:
        out = write_pair("pathkernels-whitted", a, b)
        pytest.fail(f"{diverged.sum()} of {diverged.size} pixels differ by more than "
                    f"{GLOSSY_RELATIVE} relative (budget {GLOSSY_DIVERGED_FRACTION:.0%}); "
                    f"images written to {out}")
    assert abs(a.rays - b.rays) <= GLOSSY_DIVERGED_FRACTION * a.rays


def test_radiance_leaving_points_is_bit_identical():
    """`trace_paths` (radiosity's check uses it through `radiance_leaving`) from arbitrary
    rays, with Russian roulette from the first bounce."""
    world = PathWorld(cornell(8))
    rng = np.random.default_rng(0)
    o = np.tile([278.0, 273.0, -200.0], (500, 1)) + rng.normal(scale=20.0, size=(500, 3))
    d = rng.normal(size=(500, 3)) + [0.0, 0.0, 2.0]
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    La, ra = trace_paths(world, o, d, np.random.default_rng(1), rr_start=1,
                         shading_name="numpy")
    Lb, rb = trace_paths(world, o, d, np.random.default_rng(1), rr_start=1,
                         shading_name="numba")
    assert La.shape == Lb.shape == (500, 3) and ra == rb
    np.testing.assert_array_equal(La, Lb)
    assert (La > 0).any(axis=1).mean() > 0.5


def test_shading_is_chosen_by_argument_then_environment(monkeypatch):
    monkeypatch.delenv(pathtrace.SHADING_ENV, raising=False)
    assert shading() == "numba"  # auto: numba imports here
    for value in ("numpy", "numba", " NumPy ", "auto", ""):
        monkeypatch.setenv(pathtrace.SHADING_ENV, value)
        assert shading() == ("numpy" if "numpy" in value.lower() else "numba")
    assert shading("numpy") == "numpy"  # the argument wins
    monkeypatch.setenv(pathtrace.SHADING_ENV, "cuda")
    with pytest.raises(InputError, match="SHADOWVOL_PATHTRACE: unknown path-tracer shading "
                                         "'cuda'"):
        render(cornell(4), spp=1)
    with pytest.raises(InputError, match="shading: unknown"):
        shading("fortran")


def test_without_numba_auto_is_numpy_and_numba_is_a_missing_extra(monkeypatch):
    monkeypatch.setattr(pathtrace, "_kernels", lambda: None)
    monkeypatch.delenv(pathtrace.SHADING_ENV, raising=False)
    assert shading() == "numpy"
    assert render(cornell(4), spp=1, progress=False).shading == "numpy"
    monkeypatch.setenv(pathtrace.SHADING_ENV, "numba")
    with pytest.raises(MissingExtra, match=r"pip install 'shadowvol\[fast\]'"):
        render(cornell(4), spp=1)
