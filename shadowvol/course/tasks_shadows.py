"""The shadow tasks' hidden cases, their answers computed by the project's own code: the 2D
exercise (`shadowvol.course.shadow2d`), the rasterizer's silhouettes by the multiplicity rule
(`shadowvol.raster.volumes.topology`, `shadowvol.raster.volumes.silhouettes`), counting along an
eye ray (`shadowvol.course.counting`) and the planar shadow matrix
(`shadowvol.raster.planar.matrix`).

Every case list is built from fixed numbers and a seeded generator, the same on every run.
"""

from __future__ import annotations

import numpy as np

from shadowvol.course import counting
from shadowvol.course.shadow2d import example, shadow_polygons
from shadowvol.course.task import (
    Case,
    Task,
    close,
    is_number,
    judge_exact,
    judge_vector,
    num,
    show_value,
    vec,
)
from shadowvol.raster.planar.matrix import projection_matrix
from shadowvol.raster.volumes.silhouettes import edge_multiplicity, triangle_signs
from shadowvol.raster.volumes.topology import Topology


def _floats(v) -> list:
    return [float(x) for x in np.asarray(v, float).reshape(-1)]


# ---------------------------------------------------------------------------------------------
# The 2D exercise: the shadow region of a segment
# ---------------------------------------------------------------------------------------------

def region_cases() -> list[Case]:
    light, segments = example()
    fixed = [(f"the lecture's example, segment {i}", light, s[0], s[1])
             for i, s in enumerate(segments)]
    fixed += [
        ("a back-facing segment (it casts too)", (0.5, 0.5), (0.3, 0.6), (0.7, 0.6)),
        ("the light on the segment's line, outside it", (0.2, 0.5), (0.4, 0.5), (0.6, 0.5)),
        ("the light on the segment itself", (0.5, 0.5), (0.4, 0.5), (0.6, 0.5)),
        ("an end point on the square's border", (0.5, 0.2), (0.3, 0.6), (0.6, 1.0)),
        ("a shadow wrapping round two corners", (0.5, 0.5), (0.4, 0.6), (0.6, 0.6)),
        ("the light in a corner", (0.0, 0.0), (0.5, 0.2), (0.2, 0.5)),
    ]
    rng = np.random.default_rng(8)
    while len(fixed) < 26:
        L, a, b = (np.round(rng.uniform(0.05, 0.95, 2), 3) for _ in range(3))
        d = b - a
        if np.linalg.norm(d) > 0.1 and abs(d[0] * (L - a)[1] - d[1] * (L - a)[0]) > 0.02:
            fixed.append(("a segment and a light in the square", L, a, b))
    out = []
    for label, L, a, b in fixed:
        region = shadow_polygons(L, [[a, b]], back_faces=True)[0].region
        out.append(Case(label, (_floats(L), _floats(a), _floats(b)),
                        [_floats(v) for v in region]))
    return out


def _judge_region(expected, got) -> str | None:
    if not isinstance(got, list) or not all(
            isinstance(v, list) and len(v) == 2 and all(is_number(x) for x in v) for v in got):
        return f"expected a list of (x, y) vertices, got {show_value(got)}"
    if len(got) != len(expected):
        return f"{len(got)} vertices, expected {len(expected)}"
    if not expected:
        return None
    for shift in range(len(got)):
        turned = got[shift:] + got[:shift]
        if all(close(e, g) for pe, pg in zip(expected, turned) for e, g in zip(pe, pg)):
            return None
    if all(any(all(close(e, g) for e, g in zip(pe, pg)) for pg in got) for pe in expected):
        return "the right vertices, in the wrong order (the region is listed counter-clockwise)"
    return "not the expected polygon (compare the vertices)"


def _show_region_args(args) -> str:
    L, a, b = args
    return f"light L = {vec(L)}, segment a = {vec(a)}, b = {vec(b)}"


def _show_region(v) -> str:
    if isinstance(v, list) and not v:
        return "[] (no area: the light is on the segment's line)"
    return show_value(v)


# ---------------------------------------------------------------------------------------------
# Silhouette edges by the multiplicity rule
# ---------------------------------------------------------------------------------------------

TETRA = ([(0, 0, 0), (1, 0, 0), (0, 1, 0), (0, 0, 1)], [(0, 2, 1), (0, 1, 3), (0, 3, 2),
                                                          (1, 2, 3)])
CUBE_V = [(x, y, z) for x in (0, 1) for y in (0, 1) for z in (0, 1)]
CUBE_F = [(0, 1, 3), (0, 3, 2), (4, 6, 7), (4, 7, 5), (0, 4, 5), (0, 5, 1), (2, 3, 7),
          (2, 7, 6), (0, 2, 6), (0, 6, 4), (1, 5, 7), (1, 7, 3)]
TRI = ([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [(0, 1, 2)])
OCTA_V = [(1, 0, 0), (-1, 0, 0), (0, 1, 0), (0, -1, 0), (0, 0, 1), (0, 0, -1)]
OCTA_F = [(0, 2, 4), (2, 1, 4), (1, 3, 4), (3, 0, 4), (2, 0, 5), (1, 2, 5), (3, 1, 5),
          (0, 3, 5)]


def silhouette_cases() -> list[Case]:
    flipped = TETRA[1][:3] + [(1, 3, 2)]
    fixed = [
        ("one triangle, the light on its counter-clockwise side", *TRI, (0.2, 0.3, 5)),
        ("one triangle seen from its back (clockwise side)", *TRI, (0.2, 0.3, -5)),
        ("the light in the triangle's plane", *TRI, (3, 2, 0)),
        ("a closed tetrahedron", *TETRA, (3, 2, 1.5)),
        ("a tetrahedron with one triangle wound the other way", TETRA[0], flipped, (3, 2, 1.5)),
        ("a cube, the light off a corner", CUBE_V, CUBE_F, (2.5, 3.5, 4.5)),
        ("a cube, the light in front of one face", CUBE_V, CUBE_F, (0.5, 0.5, 4)),
        ("an open mesh: two triangles of a square", [(0, 0, 0), (1, 0, 0), (1, 1, 0),
                                                     (0, 1, 0)], [(0, 1, 2), (0, 2, 3)],
         (2, -1, 3)),
        ("a non-manifold edge (three triangles on it)", [(0, 0, 0), (1, 0, 0), (0, 1, 0),
                                                         (0, 0, 1), (0.5, -1, 0.5)],
         [(0, 1, 2), (0, 1, 3), (1, 0, 4)], (0.3, 0.4, 2.2)),
    ]
    rng = np.random.default_rng(9)
    for _ in range(5):
        fixed.append(("an octahedron", OCTA_V, OCTA_F, tuple(np.round(rng.uniform(-4, 4, 3), 2))))
    return [Case(label, ([_floats(v) for v in vs], [list(map(int, f)) for f in fs],
                         _floats(light)), _silhouette(vs, fs, light))
            for label, vs, fs, light in fixed]


def _silhouette(vertices, faces, light) -> list:
    """The rasterizer's multiplicities, as sorted [[a, b], m] pairs of the caller's indices."""
    topo = Topology.build(np.asarray(vertices, float), np.asarray(faces, np.int64))
    original = np.empty(len(topo.remap), np.int64)
    original[topo.remap] = np.arange(len(topo.remap))     # the cases weld nothing
    signs = triangle_signs(topo.vertices, topo.faces, np.append(np.asarray(light, float), 1.0))
    m = edge_multiplicity(topo, signs)
    out = []
    for (a, b), count in zip(topo.edges, m):
        if count:
            i, j = int(original[a]), int(original[b])
            out.append([[min(i, j), max(i, j)], int(count) * (1 if i < j else -1)])
    return sorted(out)


def _judge_silhouette(expected, got) -> str | None:
    if not isinstance(got, dict) or "pairs" not in got:
        return f"expected a dict {{(a, b): m}}, got {show_value(got)}"
    try:
        have = {tuple(k): m for k, m in got["pairs"]}
    except (TypeError, ValueError):
        return "expected a dict {(a, b): m} with edges (a, b) as keys"
    have = {k: m for k, m in have.items() if m != 0}
    want = {tuple(k): m for k, m in expected}
    for key, m in want.items():
        if key not in have:
            return f"the edge {key} is missing (multiplicity {m:+d})"
        if have[key] != m:
            return f"the edge {key} has multiplicity {show_value(have[key])}, expected {m:+d}"
    for key in have:
        if key not in want:
            return f"the edge {key} is no silhouette edge (multiplicity 0)" + \
                ("" if len(key) == 2 and key[0] < key[1] else ": keys are (a, b) with a < b")
    return None


def _show_mesh(args) -> str:
    vs, fs, light = args
    return f"vertices {vec(vs)}, triangles {vec(fs)}, light {vec(light)}"


def _show_silhouette(v) -> str:
    if isinstance(v, dict) and "pairs" in v:
        v = v["pairs"]
    if isinstance(v, list):
        return "{" + ", ".join(f"{tuple(k)}: {m:+d}" if isinstance(m, int) else
                               f"{k}: {show_value(m)}" for k, m in v) + "}"
    return show_value(v)


# ---------------------------------------------------------------------------------------------
# Counting along an eye ray: z-pass and z-fail
# ---------------------------------------------------------------------------------------------

def count_cases() -> list[Case]:
    light, box = counting.LIGHT, counting.BOX
    fixed = [(f"the lecture's scene: {name}", light, box, eye, p)
             for name, eye, p in counting.CASES]
    fixed += [
        ("the eye inside the volume, the point lit", light, box, (1.2, 2.0), (-3.0, 0.0)),
        ("the eye above the occluder, looking through it", light, box, (1.2, 5.0), (1.3, 0.0)),
        ("a ray passing beside the volume", light, box, (-3.0, 2.0), (-1.0, 0.0)),
        ("the eye a hair above P, the ray on into the far cap", light, box, (2.0, 0.01),
         (2.0048, 0.0)),
        ("the point lit, the volume behind it", light, box, (-4.0, 0.5), (-1.0, 0.3)),
        ("a triangle, the eye below it", (1.0, 8.0), [(0.0, 3.0), (2.0, 3.5), (0.5, 4.5)],
         (1.0, 1.0), (3.0, 0.0)),
    ]
    rng = np.random.default_rng(10)
    while len(fixed) < 18:
        centre = rng.uniform([-1, 2.5], [2, 4])
        k = int(rng.integers(3, 7))
        angles = np.sort(rng.uniform(0, 2 * np.pi, k))
        poly = np.round(centre + rng.uniform(0.3, 1.0) * np.stack(
            [np.cos(angles), np.sin(angles)], axis=1), 3)
        L = np.round(rng.uniform([-2, 5.5], [3, 8]), 3)
        eye, p = np.round(rng.uniform([-5, 0.5], [5, 6]), 3), np.round(
            [rng.uniform(-4, 5), 0.0], 3)
        if _fair_count(L, poly, eye, p):
            fixed.append(("a convex polygon", L, poly, eye, p))
    out = []
    for label, L, poly, eye, p in fixed:
        L, poly, eye, p = (np.asarray(v, float) for v in (L, poly, eye, p))
        c = counting.counts(counting.crossings(eye, p, counting.textbook_volume(L, poly)))
        out.append(Case(label, (_floats(L), [_floats(v) for v in poly], _floats(eye),
                                _floats(p)), [int(c.zpass), int(c.zfail)]))
    return out


def _fair_count(L, poly, eye, p, margin: float = 1e-2) -> bool:
    """A case whose counts no rounding can change: the eye, P and L outside the polygon, no
    vertex (and so no side) within `margin` of the eye ray's line, no side ray along it."""
    d = p - eye
    line = np.abs(d[0] * (poly[:, 1] - eye[1]) - d[1] * (poly[:, 0] - eye[0])) / np.linalg.norm(d)
    edges = np.roll(poly, -1, 0) - poly
    inside = [bool(np.all(edges[:, 0] * (q - poly)[:, 1] - edges[:, 1] * (q - poly)[:, 0] > 0))
              for q in (L, eye, p)]
    rays = poly - L
    turn = np.abs(d[0] * rays[:, 1] - d[1] * rays[:, 0]) / (
        np.linalg.norm(d) * np.linalg.norm(rays, axis=1))
    return line.min() > margin and not any(inside) and turn.min() > margin


def _show_count_args(args) -> str:
    L, poly, eye, p = args
    return f"light {vec(L)}, polygon {vec(poly)}, eye {vec(eye)}, point P {vec(p)}"


def _show_counts(v) -> str:
    if isinstance(v, list) and len(v) == 2:
        return f"z-pass {show_value(v[0])}, z-fail {show_value(v[1])}"
    return show_value(v)


def _judge_counts(expected, got) -> str | None:
    if not isinstance(got, list) or len(got) != 2:
        return f"expected a pair (zpass, zfail), got {show_value(got)}"
    for what, e, g in (("z-pass", expected[0], got[0]), ("z-fail", expected[1], got[1])):
        if judge_exact(e, g):
            return f"the {what} count is {show_value(g)}, expected {e}"
    return None


# ---------------------------------------------------------------------------------------------
# The planar shadow matrix
# ---------------------------------------------------------------------------------------------

def planar_cases() -> list[Case]:
    fixed = [
        ("the floor y = 0, a point light above it", (0, 0, 0), (0, 1, 0), (0, 2, 0, 1)),
        ("a point light below the plane", (0, 0, 0), (0, 1, 0), (1, -3, 2, 1)),
        ("a directional light", (0, 0, 0), (0, 1, 0), (1, 2, 0.5, 0)),
        ("a normal that is not unit length", (1, 2, 3), (0, 0, 5), (2, 1, 9, 1)),
        ("a tilted wall", (2, 0, 0), (-1, 0.5, 0.2), (0, 1, 1, 1)),
    ]
    rng = np.random.default_rng(11)
    while len(fixed) < 12:
        point, normal = np.round(rng.uniform(-2, 2, 3), 3), np.round(rng.normal(size=3), 3)
        light = np.append(np.round(rng.uniform(-5, 5, 3), 3), float(rng.integers(0, 2)))
        unit = normal / np.linalg.norm(normal)
        plane = np.append(unit, -unit @ point)
        if np.linalg.norm(normal) > 0.3 and abs(plane @ light) > 0.3:
            fixed.append(("a plane and a light in 3D", point, normal, light))
    return [Case(label, (_floats(pt), _floats(n), _floats(L)),
                 [_floats(row) for row in projection_matrix(pt, n, L)])
            for label, pt, n, L in fixed]


def _judge_matrix(expected, got) -> str | None:
    if not isinstance(got, list) or len(got) != 4 or not all(isinstance(r, list) for r in got):
        return f"expected 4 rows of 4 numbers, got {show_value(got)}"
    for i, (e, g) in enumerate(zip(expected, got)):
        why = judge_vector(e, g, f"row {i}")
        if why:
            return why
    return None


def _show_planar_args(args) -> str:
    point, normal, L = args
    return f"plane through {vec(point)} with normal {vec(normal)}, light {vec(L)}"


def _show_matrix(v) -> str:
    if isinstance(v, list) and all(isinstance(r, list) for r in v):
        return "[" + "; ".join(" ".join(num(x) for x in r) for r in v) + "]"
    return show_value(v)


TASKS = [
    Task("shadow_region", "shadow_region", "the 2D shadow polygons", 10, region_cases,
         _judge_region, _show_region_args, _show_region),
    Task("silhouette", "silhouette_edges", "silhouette edges seen from a light", 15,
         silhouette_cases, _judge_silhouette, _show_mesh, _show_silhouette),
    Task("zcount", "counts", "z-pass and z-fail along an eye ray", 15, count_cases,
         _judge_counts, _show_count_args, _show_counts),
    Task("planar", "projection_matrix", "the planar shadow matrix (Blinn 1988)", 10,
         planar_cases, _judge_matrix, _show_planar_args, _show_matrix),
]
