"""The shadow-volume polygons of a caster by role, computed on the CPU exactly as the stencil pass
builds them (`raster.volumes.silhouettes`), projected and drawn over a frame for the course.

Roles, for one light: silhouette edges (multiplicity m != 0), side quads (each silhouette edge
extruded to infinity, |m| copies), near caps (every triangle, facing the light: surfaces are
two-sided, so every triangle is the near cap of its own volume) and far caps (every triangle
sent to infinity).  A closed box thus has m = 2 on each silhouette edge and two near and two far
cap layers: it counts 2, where the textbook's silhouette volume counts 1.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from PIL import Image, ImageDraw

from shadowvol.course import slides
from shadowvol.primitives import Transform, box
from shadowvol.raster.volumes.silhouettes import (
    edge_multiplicity,
    extrude,
    side_quads,
    topology_signs,
)
from shadowvol.raster.volumes.topology import Topology
from shadowvol.scene import Camera, Material, PointLight, Scene


@dataclass(frozen=True)
class Roles:
    """One caster's volume polygons for one light (homogeneous world corners, w = 0 at
    infinity).

    silhouettes : (s, 2, 3) float64, each silhouette edge once
    multiplicity: (s,) int64, its multiplicity
    sides       : (s, 4, 4) float64, one quad per silhouette edge (drawn |m| times)
    near        : (t, 3, 4) float64, the light-facing triangles (sign +1)
    near_back   : (u, 3, 4) float64, the triangles facing away (sign -1): near caps too
    far         : (t + u, 3, 4) float64, every triangle at infinity
    """

    silhouettes: np.ndarray
    multiplicity: np.ndarray
    sides: np.ndarray
    near: np.ndarray
    near_back: np.ndarray
    far: np.ndarray


def roles(obj, light4: np.ndarray) -> Roles:
    """The volume polygons of object `obj` for the homogeneous light `light4`."""
    topo = Topology.build(obj.vertices, obj.faces)
    signs = topology_signs(topo, light4)
    m = edge_multiplicity(topo, signs)
    on = np.flatnonzero(m)
    sil = topo.vertices[topo.edges[on]]
    sides = side_quads(topo, np.sign(m), light4)          # one quad per silhouette edge
    tris = topo.vertices[topo.faces]                                    # (t, 3, 3)
    homog = np.concatenate([tris, np.ones(tris.shape[:2] + (1,))], axis=2)
    far = extrude(tris.reshape(-1, 3), light4).reshape(-1, 3, 4)
    return Roles(sil, m[on], sides, homog[signs > 0], homog[signs < 0], far[signs != 0])


def one_caster_scene() -> Scene:
    """A box floating in front of the eye, a point light between them, above and to the left:
    the box's volume recedes from the eye, so its side quads and its far cap (a small polygon
    around the vanishing point) are all in the frame."""
    grey = Material(ambient=[0.25, 0.3, 0.45], diffuse=[0.35, 0.45, 0.75],
                    specular=[0.2, 0.2, 0.2], shininess=20.0)
    caster = box("box", center=(0.0, 0.0, 0.0), size=(1.0, 1.0, 1.0), material=grey,
                 transform=Transform(rotation=(20.0, 35.0, 0.0), translation=(0.3, 1.0, -1.5)))
    return Scene(camera=Camera(eye=[0.0, 1.8, 5.0], target=[0.6, 0.5, -3.0], fov_y=50.0),
                 objects=(caster,), lights=(PointLight(position=[-0.9, 2.4, 2.2]),),
                 ambient=[0.35, 0.35, 0.35], background=[0.93, 0.93, 0.95],
                 name="one caster")


def draw_roles(image: np.ndarray, scene: Scene, r: Roles, layout: slides.Layout,
               light: np.ndarray | None = None) -> np.ndarray:
    """`image` ((H, W, 3) uint8 of `scene`) with the roles drawn: side quads, far caps and
    near caps translucent in the scheme's colours, silhouette edges thick on top, and, given
    the point light's position `light` (3,), its rays to the silhouette's corners."""
    base = Image.fromarray(image).convert("RGBA")
    line = max(1, layout.px(3))
    # caps are filled without their inner triangle edges; their outline is the silhouette
    # (near) and the side quads' edge at infinity (far)
    for role, polys, alpha, outline in (
            ("side", r.sides, 70, True), ("far cap", r.far, 200, False),
            ("near cap", np.concatenate([r.near, r.near_back]), 90, False)):
        layer = Image.new("RGBA", base.size, (0, 0, 0, 0))
        draw = ImageDraw.Draw(layer)
        colour = slides.SCHEME[role]
        for poly in polys:
            px = slides.polygon_pixels(scene, poly)
            if len(px) >= 3:
                pts = [tuple(p) for p in px]
                draw.polygon(pts, fill=(*colour, alpha))
                if outline:
                    draw.line(pts + [pts[0]], fill=(*colour, 255), width=line)
        base = Image.alpha_composite(base, layer)
    draw = ImageDraw.Draw(base)
    if light is not None:   # the light's rays through the silhouette's corners, dashed
        (lp,), _ = slides.project(scene, np.append(light, 1.0)[None])
        for v in np.unique(r.silhouettes.reshape(-1, 3), axis=0):
            (vp,), _ = slides.project(scene, np.append(v, 1.0)[None])
            _dashed(draw, lp, vp, slides.SCHEME["ink"], max(1, layout.px(2)), layout.px(12))
    for a, b in r.silhouettes:
        (pa, pb), _ = slides.project(scene, np.array([[*a, 1.0], [*b, 1.0]]))
        draw.line([tuple(pa), tuple(pb)], fill=(*slides.SCHEME["silhouette"], 255),
                  width=layout.px(8))
    return np.asarray(base.convert("RGB"), np.uint8)


def _dashed(draw, a: np.ndarray, b: np.ndarray, colour, width: int, dash: int) -> None:
    n = max(1, int(np.linalg.norm(b - a) / dash))
    for k in range(0, n, 2):
        p, q = a + (b - a) * k / n, a + (b - a) * min(k + 1, n) / n
        draw.line([tuple(p), tuple(q)], fill=colour, width=width)


def draw_silhouettes(image: np.ndarray, scene: Scene, light4: np.ndarray,
                     layout: slides.Layout, objects=None) -> tuple[np.ndarray, int]:
    """`image` with the silhouette edges (seen from the light) of `objects` (indices, default
    all) drawn in the scheme's colour where the eye sees them (each edge sampled at
    EDGE_SAMPLES points, each point ray cast from the eye against the whole scene), and how
    many silhouette edges there are."""
    from raytrace.backends import make_backend

    vertices, faces, _ = scene.triangles()
    world = make_backend("embree", vertices, faces)
    img = Image.fromarray(image)
    draw = ImageDraw.Draw(img)
    eye = scene.camera.eye
    n = 0
    for i in range(len(scene.objects)) if objects is None else objects:
        obj = scene.objects[i]
        topo = Topology.build(obj.vertices, obj.faces)
        m = edge_multiplicity(topo, topology_signs(topo, light4))
        edges = topo.vertices[topo.edges[m != 0]]                       # (e, 2, 3)
        n += len(edges)
        u = (np.arange(EDGE_SAMPLES + 1) / EDGE_SAMPLES)[None, :, None]
        pts = edges[:, :1] + u * (edges[:, 1:] - edges[:, :1])          # (e, k+1, 3)
        flat = pts.reshape(-1, 3)
        d = flat - eye
        dist = np.linalg.norm(d, axis=1)
        seen = ~world.occluded(np.broadcast_to(eye, flat.shape).copy(), d / dist[:, None],
                               tmax=dist * (1 - VISIBLE_MARGIN))
        seen = seen.reshape(pts.shape[:2])
        for e in range(len(edges)):
            for k in range(EDGE_SAMPLES):
                if seen[e, k] and seen[e, k + 1]:
                    px = slides.polygon_pixels(scene, np.array([[*pts[e, k], 1.0],
                                                                [*pts[e, k + 1], 1.0]]))
                    if len(px) >= 2:
                        draw.line([tuple(px[0]), tuple(px[1])],
                                  fill=slides.SCHEME["silhouette"], width=layout.px(5))
    return np.asarray(img, np.uint8), n


EDGE_SAMPLES = 12        # visibility samples along each drawn edge
VISIBLE_MARGIN = 1e-4    # relative: a sample is seen when nothing is hit before this much of
                         # the way to it (the edge's own triangles meet the ray at the sample)
