"""The 8-bit stencil meets 256 layers (shadowvol.raster.overflow.detect): a count that wraps to 0
is never returned as lit; it raises StencilOverflowError (exit status 3 from the command line).
Counts that reach 256 but do not land on a multiple of it stay right."""

from __future__ import annotations

import numpy as np
import pytest

import raytrace
from shadowvol.cli.main import main as shadowvol_main
from shadowvol.compare.maskdiff import mask_report
from shadowvol.primitives import box, mesh, plane
from shadowvol.raster.overflow import detect
from shadowvol.raster.renderer import Renderer
from shadowvol.scene import AreaLight, Camera, Material, PointLight, Scene
from shadowvol.scenefile import save_scene

SIZE = dict(width=64, height=48)


def stack(layers: int, closed: bool = False) -> Scene:
    """`layers` sheets (one mesh of disjoint quads) or thin closed slabs (one object each,
    counting 2 apiece) stacked between a floor and a light; the camera sees the floor under the
    stack, in the stack's shadow, and around it, lit."""
    z = np.linspace(1.0, 2.0, layers)
    if closed:
        casters = [box(f"slab{i}", [0, h, 0], [1.0, 0.5 / layers, 1.0]) for i, h in enumerate(z)]
    else:
        corners = np.array([[-0.5, 0, -0.5], [0.5, 0, -0.5], [0.5, 0, 0.5], [-0.5, 0, 0.5]])
        v = (corners[None] + np.stack([np.zeros_like(z), z, np.zeros_like(z)], 1)[:, None])
        f = (np.array([[0, 1, 2], [0, 2, 3]])[None] + 4 * np.arange(layers)[:, None, None])
        casters = [mesh("sheets", v.reshape(-1, 3), f.reshape(-1, 3),
                        Material(diffuse=[0.8, 0.2, 0.2]))]
    return Scene(camera=Camera(eye=[0, 0.8, 3.0], target=[0, 0, 0], fov_y=60),
                 objects=[plane("floor", size=[6, 6])] + casters,
                 lights=[PointLight([0.1, 4.0, 0.05])], **SIZE)


@pytest.mark.parametrize("layers, closed", [(256, False), (512, False)])
def test_a_count_that_wraps_to_zero_raises(ctx, layers, closed):
    """256 sheets over the floor: the count there is 256, which the 8-bit stencil reads as 0.
    render() raises, naming the light and the pixels."""
    scene = stack(layers, closed)
    lit, cov = raytrace.shadow_masks(scene)
    shadow = cov & ~lit[0]
    assert shadow.sum() > 100  # the reference has the stack's shadow
    with Renderer(scene, ctx) as r:
        for method in ("auto", "zfail"):
            with pytest.raises(detect.StencilOverflowError, match="light 0") as exc:
                r.render(method)
            assert exc.value.light == 0
            # the flagged pixels are wrapped ones: in the stack's shadow, drawn lit
            assert exc.value.pixels.sum() > 20
            assert not (exc.value.pixels & ~shadow).any()


@pytest.mark.parametrize("method", ["auto", "zfail", "zpass"])
def test_never_a_wrong_shadow_behind_128_closed_slabs(ctx, method):
    """128 closed slabs: 256 faces between the floor and the light.  Whatever the counting
    does with them (a renderer may count a closed caster once instead of twice), the frame is
    either right or refused: never a wrapped count drawn as lit."""
    scene = stack(128, closed=True)
    lit, cov = raytrace.shadow_masks(scene)
    with Renderer(scene, ctx) as r:
        try:
            res = r.render(method)
        except detect.StencilOverflowError as exc:
            assert not (exc.pixels & ~(cov & ~lit[0])).any()
            return
    rows = mask_report(res.lit, res.coverage, lit, cov)
    assert not any(row["interior"] for row in rows), rows


@pytest.mark.parametrize("layers", [255, 300])
def test_counts_past_the_limit_that_do_not_wrap_to_zero_stay_right(ctx, assert_masks_match,
                                                                    layers):
    """255 layers (the entering count saturates at exactly 255 and view rays past the stack
    cross 255 volumes: ambiguous in one counting direction, cleared by the other) and 300
    (reads 44): shadowed as they should be, no error."""
    scene = stack(layers)
    lit, cov = raytrace.shadow_masks(scene)
    with Renderer(scene, ctx) as r:
        assert r.count_bound >= detect.STENCIL_LIMIT
        for method in ("auto", "zfail"):
            res = r.render(method)
            rows = mask_report(res.lit, res.coverage, lit, cov)
            assert not any(row["interior"] for row in rows), rows


def test_scenes_that_cannot_overflow_take_no_extra_pass(ctx, monkeypatch):
    """The bound: 2 per closed convex object, the triangle count for anything else.  Below 256
    the check never runs, so the normal frame is unchanged."""
    def must_not_run(*args, **kwargs):
        raise AssertionError("the overflow check ran")

    monkeypatch.setattr(detect, "find_wrapped", must_not_run)
    scene = stack(100, closed=True)  # 100 boxes: bound 2 + 200
    with Renderer(scene, ctx) as r:
        assert r.count_bound == 202
        r.render()
    assert detect.object_bound(*_icosphere()) == 2


def _icosphere():
    from shadowvol.primitives import sphere

    ball = sphere("ball", [0, 0, 0], 1.0, subdivisions=3)
    return ball.vertices, ball.faces


def test_the_command_line_reports_it_with_status_3(tmp_path, capsys):
    save_scene(stack(256), tmp_path / "stack.json")
    code = shadowvol_main(["render", str(tmp_path / "stack.json"), "-o", str(tmp_path / "x.png")])
    err = capsys.readouterr().err
    assert code == 3 and err.startswith("error: stencil overflow: light 0")
    assert not (tmp_path / "x.png").exists()


def test_closed_convex_classification():
    """The overflow bound's convexity test (numpy, on the welded topology): 2 only for one
    closed, consistently wound, locally convex body, whichever way it is wound."""
    from shadowvol import primitives
    from shadowvol.raster.volumes.topology import Topology

    box = primitives.box("b", size=[1, 2, 3], transform=primitives.Transform(rotation=[10, 33, 71]))
    v, f = box.vertices, box.faces
    assert detect.is_closed_convex(Topology.build(v, f))
    assert detect.is_closed_convex(Topology.build(v, f[:, ::-1]))        # wound inward
    assert not detect.is_closed_convex(Topology.build(v, f[:-1]))        # open: a face missing
    flipped = f.copy()
    flipped[0] = flipped[0, ::-1]
    assert not detect.is_closed_convex(Topology.build(v, flipped))       # inconsistent winding
    two = np.concatenate([v, v + 10.0])
    assert not detect.is_closed_convex(Topology.build(two, np.concatenate([f, f + len(v)])))
    dented = v.copy()
    top = int(np.argmax(v[:, 1]))
    dented[top] -= 0.6 * (v[top] - v.mean(axis=0))                       # push a corner inward
    assert not detect.is_closed_convex(Topology.build(dented, f))
    # seam duplicates weld: an unwelded icosphere is still one convex body
    vi, fi = _icosphere()
    assert detect.is_closed_convex(Topology.build(vi[fi].reshape(-1, 3),
                                                    np.arange(3 * len(fi)).reshape(-1, 3)))


@pytest.mark.parametrize("layers", [40, 255, 256, 512])
def test_the_light_bound_bounds_the_counts(ctx, layers):
    """`light_bound` >= every stencil count (z-fail: the true counts, unhalved), and it sees the
    stack: at least `layers`; 256 sheets and more keep the re-check (the second frame too)."""
    scene = stack(layers)
    with Renderer(scene, ctx) as r:
        g = r.geometry
        slack = detect.world_slack(scene.camera, scene.height, g.soup_corners_f64)
        bound = detect.light_bound(g.soup_corners_f64, g.object_of, r.convex,
                                     scene.lights[0].homogeneous, slack)
        assert bound >= layers
        if layers < 256:
            counts = r.render("zfail", stencil=True).stencil.astype(np.int64) & 0xFF  # 0..255
            assert counts.max() <= bound
        else:
            for _ in range(2):   # the first frame re-checks, the second uses the light bound
                with pytest.raises(detect.StencilOverflowError):
                    r.render()


def strip_stack() -> Scene:
    """`stack(10)` with each sheet split into 50 strips: 1,000 triangles (a scene bound of
    1,000), still 10 layers."""
    scene = stack(10)
    tiles = []
    for k in range(50):
        x0, x1 = -0.5 + k / 50, -0.5 + (k + 1) / 50
        tiles.append(np.array([[x0, 0, -0.5], [x1, 0, -0.5], [x1, 0, 0.5], [x0, 0, 0.5]]))
    z = np.linspace(1.0, 2.0, 10)
    v = np.concatenate([t + [0, h, 0] for h in z for t in tiles])
    f = (np.array([[0, 1, 2], [0, 2, 3]])[None] + 4 * np.arange(len(v) // 4)[:, None, None])
    return scene.replace(objects=[scene.objects[0], mesh("strips", v, f.reshape(-1, 3))])


def test_the_light_bound_skips_the_recheck_of_shallow_stacks(ctx, monkeypatch):
    """A 1,000-triangle mesh (scene bound 1,000) of 10 layers: the first frame re-checks, later
    frames do not; the masks are the same either way."""
    scene = strip_stack()
    calls = []
    original = detect.find_wrapped
    monkeypatch.setattr(detect, "find_wrapped",
                        lambda *a, **k: calls.append(1) or original(*a, **k))
    with Renderer(scene, ctx) as r:
        assert r.count_bound >= 256
        first = r.render()
        n_first = len(calls)
        second = r.render()
        third = r.render(camera=Camera(eye=[0.3, 0.9, 3.2], target=[0, 0, 0], fov_y=60))
    assert n_first >= 1 and len(calls) == n_first
    np.testing.assert_array_equal(first.lit, second.lit)
    assert third.lit.any()


def test_the_light_bound_of_a_directional_light(ctx):
    from shadowvol.scene import DirectionalLight
    scene = stack(30).replace(lights=[DirectionalLight([0.05, -1.0, 0.02])])
    with Renderer(scene, ctx) as r:
        g = r.geometry
        slack = detect.world_slack(scene.camera, scene.height, g.soup_corners_f64)
        bound = detect.light_bound(g.soup_corners_f64, g.object_of, r.convex,
                                     scene.lights[0].homogeneous, slack)
        counts = r.render("zfail", stencil=True).stencil
    assert 30 <= bound < 256 and 0 <= counts.min() and counts.max() <= bound


@pytest.mark.parametrize("seed", range(4))
def test_the_light_bound_bounds_random_counts(ctx, seed):
    """Random open sheets and closed boxes around a point light (some across the light's axis
    planes, some beside it): every true count (z-fail, unhalved) is within the bound."""
    rng = np.random.default_rng(seed)
    light = np.array([rng.uniform(-0.5, 0.5), 3.0, rng.uniform(-0.5, 0.5)])
    objects = [plane("floor", size=[8, 8])]
    for i in range(12):
        c = light + rng.uniform([-2, -2.5, -2], [2, -0.3, 2])
        if i % 3 == 0:
            objects.append(box(f"b{i}", c, rng.uniform(0.2, 0.8, 3)))
        else:
            quad = rng.uniform(-0.6, 0.6, (4, 3)) + c
            objects.append(mesh(f"q{i}", quad, np.array([[0, 1, 2], [0, 2, 3]])))
    scene = Scene(camera=Camera(eye=[0, 2.0, 6.0], target=[0, 0.8, 0], fov_y=60),
                  objects=objects, lights=[PointLight(light)], **SIZE)
    with Renderer(scene, ctx) as r:
        g = r.geometry
        slack = detect.world_slack(scene.camera, scene.height, g.soup_corners_f64)
        bound = detect.light_bound(g.soup_corners_f64, g.object_of, r.convex,
                                     scene.lights[0].homogeneous, slack)
        counts = r.render("zfail", stencil=True).stencil
    assert counts.min() >= 0 and counts.max() <= bound < 256


def _area(samples: int = 4) -> AreaLight:
    return AreaLight("rect", [0.1, 4.0, 0.05], normal=[0, -1, 0], size=[0.4, 0.3],
                     samples=samples)


def test_an_area_lights_samples_keep_their_light_bounds(ctx, monkeypatch):
    """The shallow stack of strips under a 4-sample rect light: the first frame re-checks
    every sample; each later frame computes one sample's `light_bound` (10 layers: far below
    256; `Renderer.BOUNDS_PER_FRAME`) and re-checks the samples still without one, so the
    frames re-check 4, 3, 2, 1, then none; the counts are the same every time."""
    scene = strip_stack().replace(lights=[_area()])
    calls = []
    original = detect.find_wrapped
    monkeypatch.setattr(detect, "find_wrapped",
                        lambda *a, **k: calls.append(1) or original(*a, **k))
    rechecked = []
    with Renderer(scene, ctx) as r:
        assert r.count_bound >= 256 and r.BOUNDS_PER_FRAME == 1
        first = r.render()
        rechecked.append(len(calls))
        frames = []
        for _ in range(5):
            frames.append(r.render())
            rechecked.append(len(calls) - sum(rechecked))
        assert len(r._light_bounds) == 4
        assert all(kept[1] < 256 for kept in r._light_bounds.values())
    assert rechecked == [4, 3, 2, 1, 0, 0]
    assert 0 < first.penumbra.sum() and (first.lit_count == 0).any()
    for frame in frames:
        np.testing.assert_array_equal(frame.lit_count, first.lit_count)


def test_a_moving_light_leaves_at_most_max_lights_bounds_behind(ctx, monkeypatch):
    """A jittered light is a new light in every frame: the bounds kept for lights are capped
    (`LightBounds.MAX_LIGHTS`, least recently used dropped, never one of this frame), where a
    10,000-frame jittered batch kept one entry a frame; a light that comes back stays kept."""
    from shadowvol.raster.overflow.policy import LightBounds

    monkeypatch.setattr(LightBounds, "MAX_LIGHTS", 8, raising=False)
    scene = strip_stack()
    steady = scene.lights[0]
    rng = np.random.default_rng(0)
    with Renderer(scene.replace(width=16, height=12), ctx) as r:
        assert r.count_bound >= 256
        for _ in range(30):
            moved = PointLight(position=steady.position + rng.uniform(-0.05, 0.05, 3))
            r.render(outputs=("lit",), lights=(steady, moved))
        assert len(r._light_bounds) == 8
        assert steady.homogeneous.tobytes() in r._light_bounds
        assert r._light_bounds[steady.homogeneous.tobytes()] is not None  # its bound, kept
        many = tuple(PointLight(position=steady.position + [0.01 * i, 0, 0]) for i in range(12))
        r.render(outputs=("lit",), lights=many)   # more lights in one frame than the cap
        assert len(r._light_bounds) == 12


def test_an_area_light_over_256_sheets_raises_in_every_frame(ctx):
    """256 sheets under a 4-sample rect light: every sample's bound reaches 256, so the
    per-sample bounds (one more each frame from the second on) still leave every sample
    re-checked."""
    scene = stack(256).replace(lights=[_area()])
    with Renderer(scene, ctx) as r:
        for _ in range(1 + 4 * r.BOUNDS_PER_FRAME):
            with pytest.raises(detect.StencilOverflowError, match="light 0"):
                r.render()
        assert len(r._light_bounds) == 4
        assert all(kept is not None and kept[1] >= 256 for kept in r._light_bounds.values())


@pytest.mark.parametrize("seed", range(3))
def test_the_slack_of_an_object_covers_each_of_its_triangles(seed):
    """`object_slack` (from the object's box) >= `world_slack` of every triangle in it, for
    eyes outside, inside and far from the boxes: the per-frame test it makes may pass only when
    the exact per-triangle test would."""
    rng = np.random.default_rng(seed)
    objects = [mesh(f"m{i}", rng.uniform(-1, 1, (30, 3)) * rng.uniform(0.1, 3.0) +
                    rng.uniform(-5, 5, 3), rng.integers(0, 30, (40, 3))) for i in range(6)]
    corners = np.concatenate([o.triangles for o in objects])
    object_of = np.repeat(np.arange(len(objects)), [len(o.faces) for o in objects])
    bounds = np.array([[o.vertices.min(axis=0), o.vertices.max(axis=0)] for o in objects])
    largest = float(np.abs(corners).max())
    for eye in [*rng.uniform(-6, 6, (20, 3)), objects[0].vertices.mean(axis=0), [1e4, 0, 0]]:
        camera = Camera(eye=eye, target=np.asarray(eye) + [0.0, 0.0, -1.0],
                        fov_y=float(rng.uniform(20, 90)))
        exact = detect.world_slack(camera, 240, corners)
        coarse = detect.object_slack(camera, 240, bounds, largest)
        assert (coarse[object_of] >= exact).all()
        np.testing.assert_array_equal(exact, detect.world_slack(camera, 240, corners, largest))


def test_an_orbiting_camera_keeps_the_light_bound_without_a_pass_over_every_corner(
        ctx, monkeypatch):
    """The strip stack seen from cameras on a circle: from the third frame on the kept bound
    is accepted by the objects' boxes alone (no per-triangle slack, no re-check), and the masks
    are those of fresh renderers that re-check every frame; a camera three times as far needs
    the per-triangle slack again."""
    scene = strip_stack()
    passes_over_corners, rechecks = [], []
    slack, find = detect.world_slack, detect.find_wrapped
    monkeypatch.setattr(detect, "world_slack",
                        lambda *a, **k: passes_over_corners.append(1) or slack(*a, **k))
    monkeypatch.setattr(detect, "find_wrapped",
                        lambda *a, **k: rechecks.append(1) or find(*a, **k))
    cameras = [Camera(eye=[3.0 * np.sin(a), 2.0, 3.0 * np.cos(a)], target=[0, 1.2, 0],
                      fov_y=50) for a in np.linspace(0, 2 * np.pi, 8, endpoint=False)]
    with Renderer(scene, ctx) as r:
        assert r.count_bound >= 256
        r.render(camera=cameras[0])
        r.render(camera=cameras[0])      # the bound is computed here
        before = len(passes_over_corners), len(rechecks)
        lits = [r.render(camera=cam).lit for cam in cameras[1:]]
        assert (len(passes_over_corners), len(rechecks)) == before
        far = Camera(eye=3.0 * cameras[1].eye, target=[0, 1.2, 0], fov_y=50)
        r.render(camera=far)
        assert len(passes_over_corners) > before[0]
    for cam, lit in zip(cameras[1:], lits):
        with Renderer(scene.replace(camera=cam), ctx) as fresh:
            np.testing.assert_array_equal(fresh.render().lit, lit)
