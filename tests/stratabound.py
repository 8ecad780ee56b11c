"""The bound a stratified sample layout puts on |lit_count - N V| (docs/CONVENTIONS.md, "Area
lights: exact visibility", the sampled counts judged by it), for each area-light layout of
`shadowvol.arealights`, and random area-light scenes to check both renderers against it.

Every layout maps an nu x nv grid of equal cells of the unit square onto the light, area-
preserving, one sample per cell.  A cell whose image the visible region's outline does not meet
is wholly visible or wholly hidden, and its sample is counted right; a cell it meets is off by
less than 1.  So |lit_count - N V| <= the number of cells the outline meets inside the light
(the light's own outline bounds the cells and crosses none).  `strata_bound` counts an upper
bound of them from the outline's straight pieces:

* rect (affine map): a straight piece from a to b crosses each grid line at most once, so it
  visits at most 1 + (|du| / cell_u + 1) + (|dv| / cell_v + 1) cells.
* polygon (ear-clipped triangles; u picks triangle k by its share s_k of the area, then the
  square-root map with rho = sqrt of u's stretch, t = v): inside triangle k (corners a, b, c)
  the cells' sides are segments parallel to bc (rho constant: rho = 1 - the barycentric of a)
  and segments through a (t constant: t = c's barycentric / (b's + c's), the central
  projection from a onto bc).  A straight piece crosses each at most once, and rho^2 and t
  are monotone along it, so inside triangle k it visits at most
  1 + (s_k nu |rho1^2 - rho0^2| + 1) + (nv |t1 - t0| + 1) cells.  A column of cells that
  straddles two triangles (u = e_k, e_k nu not whole) maps to two separate pieces, which may
  be one hidden and one visible with no outline in either: its nv cells all count.
* disk (Shirley-Chiu's concentric map, a = 2u - 1, b = 2v - 1): the inverse map is a = r/R,
  b = (4/pi) phi r / R on the sectors |x| >= |y| (a and b swapped on the others); it is
  continuous, and on each sector |grad a| <= 1/R, |grad b| <= (1 + 4/pi)/R (|phi| <= pi/4).
  So along the outline each of u, v moves at most L = (1 + 4/pi) / (2R) per unit of length:
  points taken every h along a piece, with L h <= 1/5 of a cell, leave no part of the pulled-
  back curve more than 1/5 of a cell from one of them, and the cells within 1/5 of a cell of
  them hold every cell it meets.  They are counted.
"""

from __future__ import annotations

import math

import numpy as np
from hypothesis import strategies as st

from shadowvol.arealights import grid_shape, triangulate

# Coordinates in the light's plane are float64 of the light's size (~1): a point of the
# outline on the light's own edge is so within a few roundings.
ON_EDGE = 1e-12


def layout(light) -> tuple[int, int]:
    """(nu, nv) of an area light's stratified grid, as `shadowvol.lights.AreaLight` builds it."""
    nu, nv = grid_shape(light.samples)
    if light.shape == "rect" and light.size[1] > light.size[0]:
        nu, nv = nv, nu
    return nu, nv


def outline_segments(shapely, region) -> np.ndarray:
    """(m, 2, 2): every straight piece of the rings of `region` (a shapely geometry)."""
    out = []
    for ring in shapely.get_rings(shapely.get_parts(region)):
        xy = shapely.get_coordinates(ring)
        out.append(np.stack([xy[:-1], xy[1:]], axis=1))
    return np.concatenate(out) if out else np.zeros((0, 2, 2))


def _on_box_edge(seg: np.ndarray, w: float, h: float) -> np.ndarray:
    a, b = seg[:, 0], seg[:, 1]
    close = lambda x, y: np.abs(x - y) <= ON_EDGE * max(w, h)  # noqa: E731
    return ((close(np.abs(a[:, 0]), w) & close(a[:, 0], b[:, 0]))
            | (close(np.abs(a[:, 1]), h) & close(a[:, 1], b[:, 1])))


def rect_bound(seg: np.ndarray, framed, nu: int, nv: int) -> float:
    w, h = framed.hull.max(axis=0)
    d = np.abs(seg[:, 1] - seg[:, 0])[~_on_box_edge(seg, w, h)]
    return float((3 + d[:, 0] * nu / (2 * w) + d[:, 1] * nv / (2 * h)).sum())


def _on_polygon_edge(seg: np.ndarray, outline: np.ndarray) -> np.ndarray:
    """(m,) bool: the piece lies along one of the polygon's edges."""
    p, q = outline, np.roll(outline, -1, axis=0)
    e = q - p
    length = np.linalg.norm(e, axis=1)
    tol = ON_EDGE * np.abs(outline).max()

    def off(x):  # (m, k) distance of points x (m, 2) from each edge's line
        return np.abs(e[None, :, 0] * (x[:, None, 1] - p[None, :, 1])
                      - e[None, :, 1] * (x[:, None, 0] - p[None, :, 0])) / length
    return ((off(seg[:, 0]) <= tol) & (off(seg[:, 1]) <= tol)).any(axis=1)


def polygon_bound(seg: np.ndarray, framed, nu: int, nv: int) -> float:
    outline = framed.outline
    seg = seg[~_on_polygon_edge(seg, outline)]
    if len(seg) == 0:
        return 0.0
    tris = outline[triangulate(outline)]
    a, b, c = tris[:, 0], tris[:, 1], tris[:, 2]
    area = np.abs((b[:, 0] - a[:, 0]) * (c[:, 1] - a[:, 1])
                  - (b[:, 1] - a[:, 1]) * (c[:, 0] - a[:, 0]))
    share = area / area.sum()
    edges = np.cumsum(share)[:-1]
    straddling = int(np.sum(np.abs(edges * nu - np.round(edges * nu)) > 1e-9))
    total = float(straddling * nv)
    for k in range(len(tris)):
        lam0, lam1 = _barycentric(seg[:, 0], tris[k]), _barycentric(seg[:, 1], tris[k])
        t0, t1 = _clip_to_triangle(lam0, lam1)
        inside = t1 > t0
        if not inside.any():
            continue
        l0 = lam0 + t0[:, None] * (lam1 - lam0)
        l1 = lam0 + t1[:, None] * (lam1 - lam0)
        l0, l1 = l0[inside], l1[inside]
        rho0, rho1 = 1 - l0[:, 0], 1 - l1[:, 0]
        with np.errstate(divide="ignore", invalid="ignore"):
            tau0 = l0[:, 2] / (l0[:, 1] + l0[:, 2])
            tau1 = l1[:, 2] / (l1[:, 1] + l1[:, 2])
        dtau = np.where(np.isfinite(tau0) & np.isfinite(tau1), np.abs(tau1 - tau0), 1.0)
        total += float((3 + share[k] * nu * np.abs(rho1 ** 2 - rho0 ** 2) + nv * dtau).sum())
    return total


def _barycentric(x: np.ndarray, tri: np.ndarray) -> np.ndarray:
    """(m, 3) barycentrics of points x (m, 2) in triangle tri (3, 2) (order a, b, c)."""
    a, b, c = tri
    m = np.array([b - a, c - a]).T
    lb_lc = np.linalg.solve(m, (x - a).T).T
    return np.column_stack([1 - lb_lc.sum(axis=1), lb_lc])


def _clip_to_triangle(lam0: np.ndarray, lam1: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The parameter interval [t0, t1] of each segment lam0 -> lam1 (barycentrics) inside the
    triangle (every barycentric >= 0); t1 <= t0 where it misses."""
    t0, t1 = np.zeros(len(lam0)), np.ones(len(lam0))
    d = lam1 - lam0
    for j in range(3):
        with np.errstate(divide="ignore", invalid="ignore"):
            t = -lam0[:, j] / d[:, j]
        entering = d[:, j] > 0
        leaving = d[:, j] < 0
        t0 = np.where(entering, np.maximum(t0, t), t0)
        t1 = np.where(leaving, np.minimum(t1, t), t1)
        t1 = np.where((d[:, j] == 0) & (lam0[:, j] < 0), -1.0, t1)
    return t0, t1


def inverse_concentric(xy: np.ndarray, radius: float) -> np.ndarray:
    """(m, 2) uv in [0, 1]^2 of disk points xy (m, 2): the inverse of
    `shadowvol.arealights.disk_points`' concentric map."""
    x, y = xy[:, 0] / radius, xy[:, 1] / radius
    r = np.hypot(x, y)
    first = np.abs(x) >= np.abs(y)
    with np.errstate(divide="ignore", invalid="ignore"):
        a1 = np.sign(x) * r
        b1 = a1 * (4 / math.pi) * np.arctan(y / x)
        b2 = np.sign(y) * r
        a2 = b2 * (4 / math.pi) * np.arctan(x / y)
    a = np.where(first, a1, a2)
    b = np.where(first, b1, b2)
    a, b = np.nan_to_num(a), np.nan_to_num(b)
    return np.column_stack([(a + 1) / 2, (b + 1) / 2])


def disk_bound(seg: np.ndarray, framed, nu: int, nv: int) -> float:
    R = framed.radius
    seg = seg[~_on_box_edge(seg, R, R)]
    if len(seg) == 0:
        return 0.0
    lip = (1 + 4 / math.pi) / (2 * R)           # uv per unit of length, either coordinate
    cell = min(1 / nu, 1 / nv)
    step = cell / 5 / lip
    points = []
    for a, b in seg:
        k = max(1, int(math.ceil(np.linalg.norm(b - a) / step)))
        points.append(a + (b - a) * (np.arange(k + 1) / k)[:, None])
    xy = np.concatenate(points)
    r = np.hypot(xy[:, 0], xy[:, 1])
    near = r < R + step                          # a piece dipping into the disk between two
    xy = xy[near] * np.minimum(1, R / np.maximum(r[near], 1e-300))[:, None]   # points outside
    uv = inverse_concentric(xy, R)
    pad = 2 * cell / 5                           # the point's own 1/5, the clamp's 1/5
    cells = set()
    for du in (-pad, 0.0, pad):
        for dv in (-pad, 0.0, pad):
            i = np.clip(np.floor((uv[:, 0] + du) * nu), 0, nu - 1).astype(np.int64)
            j = np.clip(np.floor((uv[:, 1] + dv) * nv), 0, nv - 1).astype(np.int64)
            cells.update((j * nu + i).tolist())
    return float(len(cells))


def strata_bound(shapely, region, framed, light) -> float:
    """The most |lit_count - N V| can be for `light`'s stratified layout with visible region
    `region` (in the frame of `framed`, `raytrace.exact_soft.visible_regions`)."""
    seg = outline_segments(shapely, region)
    nu, nv = layout(light)
    if light.shape == "rect":
        return rect_bound(seg, framed, nu, nv)
    if light.shape == "polygon":
        return polygon_bound(seg, framed, nu, nv)
    return disk_bound(seg, framed, nu, nv)


# The random scenes: a floor (y = 0) under an area light at height ~2.5, seen from above.
SHAPES = ("rect", "polygon", "disk")
CASTERS = ("closed", "open", "non-manifold", "contact")


def bound_scene(kind: str, samples: int, seed: int, casters=CASTERS, behind: bool = False,
                far: bool = False, size=(32, 24)):
    """A random scene of `kind`'s light with `samples` stratified samples over a floor, and
    casters: a box turned about every axis (closed, convex), a lone triangle (open), three
    triangles on one edge (non-manifold), a box standing on the floor (a contact shadow).
    behind: the light low and steep, partly below the floor's plane (the floor's points see
    only the part above it).  far: everything moved 1e4 along x and z."""
    from shadowvol.primitives import Transform, box, mesh, plane
    from shadowvol.scene import AreaLight, Camera, Material, Scene

    matte = Material(ambient=[0.0, 0.0, 0.0], diffuse=[0.8, 0.8, 0.8], specular=[0, 0, 0])
    rng = np.random.default_rng(seed)
    if behind:
        tilt = rng.uniform(55, 75) * math.pi / 180
        turn = rng.uniform(0, 2 * math.pi)
        normal = [math.sin(tilt) * math.cos(turn), -math.cos(tilt), math.sin(tilt) * math.sin(turn)]
        centre = [-1.6 * math.cos(turn), rng.uniform(0.2, 0.4), -1.6 * math.sin(turn)]
    else:
        normal = [rng.uniform(-0.3, 0.3), -1.0, rng.uniform(-0.3, 0.3)]
        centre = [rng.uniform(-0.5, 0.5), 2.5, rng.uniform(-0.5, 0.5)]
    kw = dict(samples=samples, seed=seed, pattern="stratified")
    if kind == "rect":
        light = AreaLight("rect", centre, normal=normal, size=rng.uniform(0.6, 1.4, 2), **kw)
    elif kind == "disk":
        light = AreaLight("disk", centre, normal=normal, radius=rng.uniform(0.3, 0.7), **kw)
    else:
        light = AreaLight("polygon", None, vertices=_polygon(rng, centre, normal), **kw)
    objects = [plane("floor", point=[0, 0, 0], size=[8.0, 8.0], material=matte)]
    lift = 0.0 if not behind else -0.6
    if "closed" in casters:
        objects.append(box("box", size=rng.uniform(0.2, 0.6, 3), material=matte,
                           transform=Transform(rotation=rng.uniform(0, 60, 3), translation=[
                               rng.uniform(-1, 1), rng.uniform(0.6, 1.5) + lift,
                               rng.uniform(-1, 1)])))
    if "open" in casters:
        lone = [0, 1.0 + lift, 0] + rng.uniform(-0.8, 0.8, (3, 3)) * [1, 0.3, 1]
        objects.append(mesh("lone", lone, [[0, 1, 2]], matte))
    if "non-manifold" in casters:
        spine = np.array([[0, 1.4 + lift, -0.3], [0, 1.4 + lift, 0.3]]) + \
            [rng.uniform(-1, 1), 0, 0]
        fins = np.vstack([spine, spine.mean(0) + rng.uniform(-0.5, 0.5, (3, 3)) * [1, 0.3, 1]])
        objects.append(mesh("fins", fins, [[0, 1, 2], [0, 1, 3], [1, 0, 4]], matte))
    if "contact" in casters:
        height = rng.uniform(0.2, 0.5)
        objects.append(box("block", center=[0, height / 2, 0], size=[0.4, height, 0.3],
                           material=matte, transform=Transform(
                               rotation=[0, rng.uniform(0, 90), 0],
                               translation=[rng.uniform(-1, 1), 0, rng.uniform(-1, 1)])))
    camera = Camera(eye=[0.0, 4.5, 5.5], target=[0.0, 0.0, -0.5], fov_y=45.0)
    scene = Scene(camera=camera, objects=objects, lights=[light], width=size[0],
                  height=size[1], ambient=[0.0, 0.0, 0.0], name=f"{kind}-{seed}")
    return _moved(scene, np.array([1e4, 0.0, 1e4])) if far else scene


def _moved(scene, offset: np.ndarray):
    """`scene` moved by offset: objects, camera and the light (a polygon's corners; the
    samples' layout in the light's frame stays as it was)."""
    import dataclasses

    light = scene.lights[0]
    light = (dataclasses.replace(light, vertices=light.vertices + offset, center=None)
             if light.shape == "polygon" else
             dataclasses.replace(light, center=light.center + offset))
    return scene.replace(
        objects=[dataclasses.replace(o, vertices=o.vertices + offset) for o in scene.objects],
        lights=[light], camera=dataclasses.replace(scene.camera, eye=scene.camera.eye + offset,
                                                   target=scene.camera.target + offset))


def _polygon(rng, centre, normal) -> np.ndarray:
    """A random simple polygon of 3..7 corners (star-shaped about the centre, so convex or
    not), counter-clockwise seen from the side `normal` points to."""
    from shadowvol.planes import default_plane_axes

    m = int(rng.integers(3, 8))
    angles = np.linspace(0, 2 * math.pi, m, endpoint=False) + rng.uniform(-0.3, 0.3, m) * \
        (2 * math.pi / m) / 2
    radii = rng.uniform(0.35, 0.8, m)
    n = np.asarray(normal, float) / np.linalg.norm(normal)
    u, v = default_plane_axes(n)
    return np.asarray(centre) + (radii * np.cos(angles))[:, None] * u + \
        (radii * np.sin(angles))[:, None] * v


def judged(scene, counts: np.ndarray, light_index: int = 0):
    """(error, bound) (k,) at the pixels where light `light_index` has a visible region:
    |counts - N V| and `strata_bound` there, V the exact visibility."""
    from raytrace.exact_soft import exact_visibility, visible_regions
    from raytrace.lightshapes import shapely_module

    shapely = shapely_module()
    light = scene.lights[light_index]
    regions, framed = visible_regions(scene, light_index)
    where = np.argwhere(regions != None)  # noqa: E711 (an object array)
    v = exact_visibility(scene).visibility[light_index][tuple(where.T)]
    error = np.abs(counts[tuple(where.T)] - light.samples * v)
    bound = np.array([strata_bound(shapely, regions[y, x], framed, light) for y, x in where])
    return error, bound, where


# |count - N V| is a difference of a whole count and N times a float64 fraction of areas of
# coordinates ~1 (a few 1e-16 each): far below this, per sample.
ROUNDING = 1e-11


@st.composite
def bound_scenes(draw):
    """`bound_scene`s of every shape, 16, 64 or 256 samples, any casters, below the floor or
    not, far or not."""
    casters = draw(st.sets(st.sampled_from(CASTERS), min_size=1))
    return bound_scene(draw(st.sampled_from(SHAPES)), draw(st.sampled_from([16, 64, 256])),
                       draw(st.integers(0, 10 ** 6)), tuple(sorted(casters)),
                       behind=draw(st.booleans()), far=draw(st.booleans()))


def check_within_bound(scene, counts, who: str, one_pixel: bool = False) -> int:
    """Assert |counts - N V| <= the layout's bound at every pixel with a visible region;
    return how many pixels the outline crossed (bound > 0).  one_pixel (the rasterizer's
    counts): a pixel past the bound passes where CONVENTIONS' one-pixel rule lets the count
    differ from the per-sample float64 witness (`exact.count_witness`: the pixel is within one
    pixel of a sample's hard edge, or a GL vertex tie, and the count inside the witness's
    bracket) and the witness's own count is within the bound."""
    error, bound, where = judged(scene, counts)
    n = scene.lights[0].samples
    over = error > bound + n * ROUNDING
    if one_pixel and over.any():
        from exact import gl_vertex_ties
        from raytrace.exact_soft import exact_visibility
        ties, v = gl_vertex_ties(scene), exact_visibility(scene).visibility[0]
        for k in np.flatnonzero(over):   # up to the first the rule does not allow
            (y, x), b = where[k], bound[k]
            over[k] = not _one_pixel_allows(scene, counts, y, x, b, ties, n * v[y, x])
            if over[k]:
                break
    note = " (the one-pixel rule asked up to the first it refuses)" if one_pixel else ""
    assert not over.any(), (f"{who}, {scene.name} ({scene.lights[0].shape}, N = {n}): "
                            f"{int(over.sum())} pixels past the bound{note}, e.g. "
                            f"{where[over][:3].tolist()}: error {error[over][:3]}, "
                            f"bound {bound[over][:3]}")
    return int((bound > 0).sum())


def _one_pixel_allows(scene, counts, y: int, x: int, bound: float, ties, nv: float) -> bool:
    """The one-pixel rule at pixel (y, x): the witness on the 5 x 5 window about it (the
    bracket at its centre needs its 3 x 3 neighbours' samples); ties: `gl_vertex_ties`, nv:
    N V there."""
    from exact import count_witness

    rows = slice(max(0, y - 2), y + 3)
    cols = slice(max(0, x - 2), x + 3)
    cy, cx = y - rows.start, x - cols.start
    w = count_witness(scene, rows, cols, skip=ties[rows, cols])[0]
    return (bool(w["free"][cy, cx]) and w["low"][cy, cx] <= counts[y, x] <= w["high"][cy, cx]
            and abs(w["exact"][cy, cx] - nv) <= bound + scene.lights[0].samples * ROUNDING)


def mean_errors(kind: str, counts_of, seed: int = 5, size=(24, 18)) -> tuple[list, float]:
    """The mean |lit_count / N - V| over the penumbra (where the outline crosses the light)
    of `kind`'s scene at N = 16, 64, 256, 1024, counts_of(scene) -> (H, W) lit_count, and the
    fitted slope of its log against log N."""
    means = []
    for n in (16, 64, 256, 1024):
        scene = bound_scene(kind, n, seed, size=size)
        error, bound, _ = judged(scene, np.asarray(counts_of(scene), np.float64))
        means.append(float(error[bound > 0].mean() / n))
    slope = float(np.polyfit(np.log([16, 64, 256, 1024]), np.log(means), 1)[0])
    return means, slope
