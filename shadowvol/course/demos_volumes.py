"""The gallery's shadow pictures: shadows, planar shadows, shadow volumes, the stencil counter,
z-pass and z-fail.  Each demo takes the `Gallery` and returns a `Picture` (see `gallery`)."""

from __future__ import annotations

import numpy as np

import raytrace
from raytrace.backends import make_backend
from raytrace.camera import primary_rays
from raytrace.tolerances import surface_offset
from shadowvol.compare.maskdiff import light_stats
from shadowvol.course import counting, slides, volume_roles
from shadowvol.course.picture import Picture
from shadowvol.io import encode_srgb
from shadowvol.pictures import figure_pixels, tint
from shadowvol.raster.planar.draw import PlanarShadows
from shadowvol.raster.renderer import Renderer

CAGE_EXPOSURE = 1.6   # the cage is lit by one dim yellow light: shown brighter on a projector


def _raster(g, scene, w, h, cover: bool = False, **render):
    """(h, w, 3) uint8: the supersampled frame of `scene` at panel size w x h (see
    `slides.fit` for `cover`)."""
    def frame(s):
        with Renderer(s, g.ctx) as r:
            return r.render(**render).image
    return slides.supersampled(frame, scene, w, h, g.layout.supersample, cover)


def _masks(g, scene, w, h, method="auto"):
    """The one-sample-per-pixel frame of `scene` at w x h (for masks and counts)."""
    s = slides.fit(scene, w, h)
    with Renderer(s, g.ctx) as r:
        return s, r.render(method)


def cage(g) -> list[Picture]:
    L = g.layout
    scene = g.scene("cage")
    w, h = L.cell(2, 1)
    s = slides.fit(scene, w, h, cover=True)

    def bright(sc):
        with Renderer(sc, g.ctx) as r:
            return r.render().image * CAGE_EXPOSURE
    plain = slides.mark_lights(slides.supersampled(bright, scene, w, h, L.supersample,
                                                   cover=True), s, L)
    cage_index = next(i for i, o in enumerate(s.objects) if o.name == "cage")
    edges, n_edges = volume_roles.draw_silhouettes(plain, s, s.lights[0].homogeneous, L,
                                                   objects=[cage_index])
    title = "Shadow volumes: a point light inside a cage"
    cmd = f"shadowvol render {g.path('cage')} -o cage.png"
    return [
        Picture("cage", title, "shadows",
                "Exact hard shadows from a stencil count: a point light L inside a green cage "
                "throws the pattern of its 24 windows onto the floor and the walls; a pixel is "
                "lit exactly when no geometry lies between its surface point and the light.  "
                "On the right, the cage's silhouette edges as seen from L: the edges between a "
                "triangle facing L and one facing away, which are all the stencil pass extrudes "
                f"({n_edges} of the cage's edges).",
                f"left: the cage rendered with shadow volumes (exposure x{CAGE_EXPOSURE}), L "
                "marked; right: the same with the silhouette edges from L drawn in red",
                cmd + " (the silhouettes: shadowvol.course.volume_roles.draw_silhouettes)",
                L.compose(title, [[("shadow volumes, L marked", plain),
                                   (f"silhouette edges seen from L ({n_edges})", edges)]],
                          legend=[("light L", slides.SCHEME["light"]),
                                  ("silhouette edge", slides.SCHEME["silhouette"])]),
                numbers={"silhouette_edges": n_edges}),
    ]


def planar(g) -> Picture:
    L = g.layout
    scene = g.scene("planar")
    w, full_h = L.cell(3, 1, legend=True)
    h = min(full_h, round(w * 3 / 4))      # the scene's 4:3; the text goes under it

    def projected_image(sc):
        with Renderer(sc, g.ctx) as r, PlanarShadows(r) as p:
            return p.render().image
    pv = slides.supersampled(projected_image, scene, w, h, L.supersample)
    vv = _raster(g, scene, w, h)
    s = slides.fit(scene, w, h)
    with Renderer(s, g.ctx) as r, PlanarShadows(r) as p:
        projected = p.render()
        volumes = r.render()
    missing = (projected.lit & ~volumes.lit).any(axis=0)
    extra = (volumes.lit & ~projected.lit).any(axis=0)
    receiver = s.objects[projected.receiver].name
    pv, vv = slides.mark_lights(pv, s, L), slides.mark_lights(vv, s, L)
    title = "Planar projected shadows (Blinn 1988) against shadow volumes"
    return Picture(
        "planar", title, "planar",
        "A matrix squashes every object from the light onto the floor's plane; where it lands "
        "(the stencil keeps it on the floor and counts each pixel once) the light is left out, "
        "and that is the floor's shadow, exactly.  But only the floor's: the ball's shadow on "
        "the box and the cage's shadow on its own inside are missing, because a projection "
        "onto one plane cannot shadow other objects or an object itself.  Shadow volumes do "
        f"both ({int(missing.sum())} pixels missing in the projection).",
        "projected shadows; shadow volumes; the projected-shadow image with the pixels that "
        "shadow volumes shadow and the projection leaves lit tinted red",
        f"shadowvol planar {g.path('planar')} -o planar.png",
        L.compose(title, [[(f"projected onto the {receiver}", pv), ("shadow volumes", vv),
                           (f"missing in the projection: {int(missing.sum())} px",
                            tint(pv, missing))]],
                  below=L.note([
                      "Blinn's matrix M = (P·L) I − L Pᵀ (4×4, P the floor's plane, L the "
                      "light) sends every vertex",
                      "along its ray from L onto the floor: drawn dark, that is the floor's "
                      "shadow, exact.",
                      "It cannot shadow anything but that one plane: the ball's shadow on the "
                      "box and the",
                      "cage's shadow inside itself are missing (red).  Shadow volumes get "
                      "both right."],
                      L.width - 2 * L.margin, full_h - h - L.margin),
                  legend=[("light L", slides.SCHEME["light"]),
                          ("shadowed by volumes, lit by the projection",
                           slides.SCHEME["error"])]),
        numbers={"missing": int(missing.sum()), "extra": int(extra.sum())})


def one_caster(g) -> Picture:
    L = g.layout
    scene = volume_roles.one_caster_scene()
    side_w = L.px(640)
    w, h = L.cell(1, 1, legend=True, labels=False, side=side_w)
    s = slides.fit(scene, w, h)
    img = _raster(g, scene, w, h)
    r = volume_roles.roles(s.objects[0], s.lights[0].homogeneous)
    img = slides.mark_lights(volume_roles.draw_roles(img, s, r, L, s.lights[0].position), s, L)
    m = sorted(set(np.abs(r.multiplicity).tolist()))
    note = L.note([
        "One box, one point light L.",
        f"Silhouette edges (red): {len(r.silhouettes)} of the",
        "18 triangle edges, where a face",
        "toward L meets one facing away.",
        "Side quads (orange): each edge",
        "extruded from L to infinity,",
        f"drawn {'/'.join(map(str, m))}x (multiplicity).",
        f"Near caps (green): all {len(r.near) + len(r.near_back)} triangles,",
        f"{len(r.near)} facing L, {len(r.near_back)} facing away.",
        "Far caps (violet): the same",
        "triangles sent to infinity.",
        "",
        "Two-sided: every triangle casts,",
        "so the box counts 2.  The",
        "textbook volume (sides once,",
        "lit faces near, dark faces far)",
        "counts 1.",
    ], side_w, h)
    title = "The shadow volume of one box, by role"
    legend = [(k, slides.SCHEME[k]) for k in ("silhouette", "side", "near cap", "far cap")]
    return Picture(
        "one_caster", title, "volumes",
        "A shadow volume is bounded by polygons of three roles: the side quads, extruded from "
        "the silhouette edges away from the light to infinity (homogeneous w = 0), and the "
        "caps that close it, near (on the occluder) and far (at infinity).  The far cap is "
        "the small polygon around the vanishing point of the rays from L.  Z-pass needs only "
        "the sides; z-fail needs the caps too.",
        "one box lit by a point light, with its volume's polygons drawn translucent by role "
        "(computed on the CPU by the same functions the stencil pass uses), the light's rays "
        "to the silhouette's corners dashed",
        "shadowvol demo (shadowvol.course.volume_roles.roles and draw_roles on "
        "volume_roles.one_caster_scene())",
        L.compose(title, [[("", img)]], legend=[*legend, ("light L", slides.SCHEME["light"])],
                  side=note),
        numbers={"silhouettes": len(r.silhouettes), "multiplicity": m,
                 "near": len(r.near) + len(r.near_back), "far": len(r.far)})


def textbook_counts(scene) -> tuple[np.ndarray, np.ndarray]:
    """The textbook's stencil count of `scene`'s first light, ray traced: for each pixel
    centre's visible point, how many objects the segment to the light crosses (a closed
    occluder counts once).  Returns counts (H, W) int16 and coverage (H, W) bool."""
    vertices, faces, ids = scene.triangles()
    world = make_backend("embree", vertices, faces)
    o, d = primary_rays(scene.camera, scene.width, scene.height)
    hit = world.closest_hit(o, d)
    covered = hit.tri >= 0
    p = o[covered] + hit.t[covered, None] * d[covered]
    tri = vertices[faces[hit.tri[covered]]]
    n = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    n /= np.linalg.norm(n, axis=1, keepdims=True)
    n *= -np.sign(np.einsum("ij,ij->i", n, d[covered]))[:, None]     # toward the eye
    light = scene.lights[0].homogeneous
    to = light[:3] - light[3] * p
    dist = np.linalg.norm(to, axis=1) if light[3] else np.full(len(p), np.inf)
    to /= np.linalg.norm(to, axis=1, keepdims=True)
    start = p + surface_offset(scene) * n
    count = np.zeros(len(p), np.int16)
    for k, obj in enumerate(scene.objects):
        crosses = make_backend("embree", obj.vertices, obj.faces).occluded(
            start, to, tmax=np.where(np.isfinite(dist), dist, 1e30))
        count += crosses.astype(np.int16)
    out = np.zeros(scene.width * scene.height, np.int16)
    out[covered] = count
    return out.reshape(scene.height, scene.width), covered.reshape(scene.height, scene.width)


def count_picture(counts: np.ndarray, base: np.ndarray, samples: int) -> np.ndarray:
    """(H*s, W*s) counts over the (H, W, 3) uint8 lit image -> (H, W, 3) uint8: count 0 shows
    the image, k >= 1 the scheme's colour for k, box-filtered down from the samples."""
    colours = np.zeros(counts.shape + (3,), np.float64)
    up = np.repeat(np.repeat(base.astype(np.float64), samples, 0), samples, 1)
    colours[:] = up
    for k in np.unique(counts):
        if k != 0:
            colours[counts == k] = 0.25 * up[counts == k] + 0.75 * np.array(
                slides.count_colour(int(k)))
    return np.round(slides.downsample(colours, samples)).astype(np.uint8)


def stack_stencil(g) -> Picture:
    L = g.layout
    scene = g.scene("stack")
    scene = scene.replace(lights=(scene.lights[0],))     # the point light alone
    w, h = L.cell(2, 1, legend=True)
    ss = L.supersample
    big = slides.fit(scene, w, h, ss)
    with Renderer(big, g.ctx) as r:
        frame = r.render(stencil=True)
    ours = frame.stencil[0].astype(np.int16)
    base = encode_srgb(slides.downsample(frame.image, ss))
    textbook, _ = textbook_counts(big)
    s = slides.fit(scene, w, h)
    # the counts that occur, one sample per pixel (the picture's legend lists exactly these)
    with Renderer(s, g.ctx) as r:
        one = r.render(stencil=True).stencil[0]
    tb_one, cov = textbook_counts(s)
    # the legend lists exactly the counts drawn (the supersampled ones)
    occur = sorted(set(np.unique(ours).tolist()) | set(np.unique(textbook).tolist()))
    double = int(((one == 2 * tb_one) & cov).sum())
    panels = [slides.mark_lights(count_picture(textbook, base, ss), s, L),
              slides.mark_lights(count_picture(ours, base, ss), s, L)]
    title = "The stencil buffer as a per-pixel counter: textbook and two-sided"
    share = double / max(int(cov.sum()), 1)
    numbers = {"ours": sorted(np.unique(one).tolist()),
               "textbook": sorted(np.unique(tb_one).tolist()),
               "drawn": occur, "odd_ours": int(((one % 2) != 0).sum()),
               "double_share": share, "max_count": int(one.max())}
    return Picture(
        "stack_stencil", title, "stencil",
        "The stencil buffer counts, per pixel, the shadow-volume faces between the eye and the "
        "visible point: +1 for each front face, -1 for each back face.  A pixel is lit only "
        "where the count is 0.  The textbook builds one volume per closed occluder from its "
        "silhouette, so a point under k slabs counts k (left, ray traced: the objects the "
        "segment to the light crosses).  Our surfaces are two-sided: every triangle casts, so "
        "a closed slab counts 2, once for its top and once for its bottom (right, the stencil "
        f"read back): the same shadow, twice the count, at {100 * share:.1f}% of the "
        "covered pixels" + (f"; {numbers['odd_ours']} pixel(s) on edges where volume faces "
                            "meet read an odd count." if numbers["odd_ours"] else "."),
        "four staggered slabs under one point light; count 0 shows the lit image, each count "
        "that occurs its own colour; left the textbook count, right our stencil",
        f"shadowvol render {g.path('stack')} -o stack.png --stencil stack_stencil.png "
        "(ours, for both lights)",
        L.compose(title, [[("textbook: one closed occluder counts 1", panels[0]),
                           ("ours, two-sided: every triangle counts, a slab 2", panels[1])]],
                  legend=[("0 lit", (235, 235, 235))] +
                         [(str(k), slides.count_colour(k)) for k in occur if k != 0]),
        numbers=numbers)


def counting_side_view(g) -> Picture:
    L = g.layout
    w, h = L.cell(1, 1, labels=False)
    fig, results = counting.diagram(w, h, L.px(32))
    img = figure_pixels(fig)
    title = "Counting along one eye ray: z-pass and z-fail"
    (out_tb, out_ours), (in_tb, in_ours) = results
    return Picture(
        "counting", title, "zpass",
        "A cut through the scene: the eye ray to P crosses volume faces.  Z-pass adds +1 for "
        "each face it enters and -1 for each it leaves between the eye and P; z-fail counts "
        "the faces behind P, out to infinity, the other way round (+1 leaving, -1 entering).  "
        f"With the eye outside every volume both give {out_tb.zpass} (textbook) and "
        f"{out_ours.zpass} (ours, two-sided).  With the eye inside the volume, z-pass misses "
        f"the face the eye never crossed and says {in_tb.zpass}: P is wrongly lit; z-fail "
        f"still says {in_tb.zfail} ({in_ours.zfail} ours).",
        "left: eye outside; right: eye inside the box's shadow volume; each crossing labelled "
        "with its textbook / our step, the sums below",
        "shadowvol demo (shadowvol.course.counting.diagram)",
        L.compose(title, [[("", img)]]),
        numbers={"outside": (out_tb.zpass, out_tb.zfail, out_ours.zpass, out_ours.zfail),
                 "inside": (in_tb.zpass, in_tb.zfail, in_ours.zpass, in_ours.zfail)})


def zpass_zfail(g) -> Picture:
    L = g.layout
    scene = g.scene("inside_shadow")
    w, h = L.cell(2, 2)
    s, zpass = _masks(g, scene, w, h, "zpass")
    _, zfail = _masks(g, scene, w, h, "zfail")
    ref_lit, ref_cov = raytrace.shadow_masks(s)
    wrong = (zpass.lit != ref_lit).any(axis=0)
    stats = {m: [light_stats(res.lit[i], res.coverage, ref_lit[i], ref_cov)
                 for i in range(len(s.lights))] for m, res in (("zpass", zpass),
                                                              ("zfail", zfail))}
    numbers = {f"{m}_{k}": int(sum(x[k] for x in rows))
               for m, rows in stats.items() for k in ("mismatched", "interior")}
    numbers["marked"] = int(wrong.sum())
    zp = _raster(g, scene, w, h, method="zpass")
    zf = _raster(g, scene, w, h, method="zfail")

    def traced(sc):
        return raytrace.render(sc, max_depth=0, progress=False)
    ref = slides.supersampled(traced, scene, w, h, L.supersample)
    mark = lambda im: slides.mark_lights(im, s, L)
    title = "Z-pass against z-fail, the camera inside a shadow volume"
    return Picture(
        "zpass_zfail", title, "zpass",
        "Z-pass counts the volume faces between the eye and the surface, which is right only "
        "when the eye itself is in no volume.  Here it stands under the slab, inside its "
        "shadow volume, so every count is off: lit ground turns dark and the shadow turns "
        f"lit ({numbers['marked']} pixels wrong, {numbers['zpass_interior']} of them away "
        "from any edge).  Z-fail counts the faces behind the surface, out to infinity, closed "
        f"by caps: it agrees with the ray tracer ({numbers['zfail_mismatched']} pixels "
        f"differ, {numbers['zfail_interior']} away from edges).",
        "top: z-pass, z-fail; bottom: the ray tracer's image (direct light), z-pass with the "
        "pixels whose mask disagrees with the ray tracer's tinted red",
        f"shadowvol render {g.path('inside_shadow')} --method zpass -o zpass.png (and "
        f"--method zfail); shadowvol compare {g.path('inside_shadow')} --method zpass "
        "-o cmp.png counts the error",
        L.compose(title, [[("z-pass (counts from the eye)", mark(zp)),
                           ("z-fail (counts from infinity)", mark(zf))],
                          [("ray traced reference", mark(ref)),
                           (f"z-pass wrong: {numbers['marked']} pixels (red)",
                            mark(tint(zp, wrong)))]]),
        numbers=numbers)
