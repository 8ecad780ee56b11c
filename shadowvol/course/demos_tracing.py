"""The gallery's ray-tracing pictures, the exercises and the outlook (raster against ray traced,
shadow mapping against shadow volumes).  Each demo takes the `Gallery` and returns a
`Picture` (see `gallery`)."""

from __future__ import annotations

import numpy as np

import raytrace
from raytrace import exercise
from raytrace.outlook.raytree import format_tree, ray_tree
from shadowvol.compare import maskdiff
from shadowvol.compare.comparison import compare
from shadowvol.course import exercise_picture, raytree_diagram, raytree_slide, slides
from shadowvol.course.picture import Picture
from shadowvol.course.shadow2d import draw_shadow2d, example
from shadowvol.pictures import figure_pixels, tint
from shadowvol.raster.projection import view_matrix, view_projection
from shadowvol.raster.renderer import Renderer

RAY_TREE_DEPTH = 2    # "sketch all rays to recursion depth 2"
ZOOM_FRACTION = 6     # a zoomed crop shows 1/6 of the panel's width and height


def _traced(scene):
    return raytrace.render(scene, progress=False)


def whitted_best(g) -> Picture:
    L = g.layout
    scene = g.scene("whitted_best")
    w, h = L.cell(1, 1, labels=False)
    s = slides.fit(scene, w, h)
    image = slides.mark_lights(slides.supersampled(_traced, scene, w, h, L.supersample), s, L)
    title = "Whitted ray tracing: reflections of reflections, refraction"
    return Picture(
        "whitted_best", title, "raytracing",
        "Recursive ray tracing: two mirror balls facing each other reflect each other's "
        "reflections, again and again up to the recursion depth; the glass ball bends the "
        "rays by Snell's law and shows the scene behind it upside down; every hit sends shadow "
        f"rays, so the shadows are exact.  Recursion depth {scene.max_depth}.",
        "the whitted_best scene ray traced (a point and a directional light, Phong, shadow "
        "rays, reflection, refraction), the lights marked",
        f"raytrace render {g.path('whitted_best')} -o whitted_best.png",
        L.compose(title, [[("", image)]]))


def ray_tree_pixel(scene, obj_name: str, offset=(-0.35, 0.45)) -> tuple[int, int]:
    """The pixel (x, y) showing the sphere `obj_name` at `offset` (fractions of its radius,
    along the camera's right and up) from its centre: a pixel on the sphere at any size."""
    obj = next(o for o in scene.objects if o.name == obj_name)
    view = view_matrix(scene.camera)
    right, up = view[0, :3], view[1, :3]
    c = obj.analytic.center + obj.analytic.radius * (offset[0] * right + offset[1] * up)
    clip = view_projection(scene.camera, scene.size) @ np.append(c, 1.0)
    ndc = clip[:2] / clip[3]
    return (int((ndc[0] + 1) / 2 * scene.width), int((1 - ndc[1]) / 2 * scene.height))


def raytree(g) -> Picture:
    scene = g.scene("whitted")
    x, y = ray_tree_pixel(scene, "glass ball")
    tree = ray_tree(scene, x, y, max_depth=RAY_TREE_DEPTH)
    image = raytree_slide.slide(g.layout, scene, tree, (x, y), RAY_TREE_DEPTH,
                                lambda sc: raytrace.render(sc, max_depth=RAY_TREE_DEPTH,
                                                           progress=False))
    kinds = [n.kind for n in tree.walk()]
    return Picture(
        "raytree", f"The ray tree of pixel ({x}, {y}), to recursion depth {RAY_TREE_DEPTH}",
        "raytracing",
        "Whitted's recursion for one pixel: the primary ray hits the glass ball; from every "
        "hit a shadow ray goes to each light, a reflected ray and, through glass, a refracted "
        "ray, each of which does the same, down to the depth limit.  The pixel's colour is "
        "the sum of what every ray contributes.",
        "the rays over the ray-traced image, coloured by kind, the eye, reflected and "
        "refracted rays' hits numbered; beside it the tree, one box per ray (numbered as in "
        "the text below), its edges labelled S (shadow), R (reflected), T (refracted)",
        f"raytrace tree {g.path('whitted')} --pixel {x} {y} --depth {RAY_TREE_DEPTH} "
        "-o raytree.png",
        image, text=format_tree(tree, scene),
        numbers={"rays": len(kinds), "boxes": len(raytree_diagram.layout(tree)),
                 **{k: kinds.count(k) for k in sorted(set(kinds))}})


def tir(g) -> Picture:
    L = g.layout
    w, h = L.cell(1, 1, labels=False, side=L.px(760))
    rays = exercise.solve_tir()
    img = figure_pixels(exercise_picture.tir_figure(rays, width_px=w, height_px=h,
                                                    text_px=L.px(32)))
    text = exercise.tir_text(rays)
    note = L.note(_wrap(text, 40), L.px(760), h)
    title = "Total internal reflection: from glass into air"
    return Picture(
        "tir", title, "raytracing",
        "Snell's law n1 sin θ1 = n2 sin θ2 bends a ray leaving glass away from the normal.  "
        f"Past the critical angle, asin(1/{exercise.GLASS_IOR:g}) = "
        f"{exercise.critical_angle():.1f}°, sin θ2 would exceed 1: no refracted ray exists "
        "and all the light is reflected back into the glass.  The ray tracer's refract() "
        "returns that reflection, which is why glass balls show bright rims.",
        "four rays inside glass meeting the surface at one point at 20°, 35°, 45° and 60°: two "
        "refracted out, two totally reflected; the critical angle dash-dotted",
        "raytrace exercise tir -o tir.png",
        L.compose(title, [[("", img)]], side=note), text=text,
        numbers={"tir": [r.angle for r in rays if r.tir],
                 "critical": exercise.critical_angle()})


def shadow2d(g) -> Picture:
    L = g.layout
    side_w = L.px(700)
    w, h = L.cell(1, 1, labels=False, legend=True, side=side_w)
    size = min(w, h)
    img = draw_shadow2d(*example(), size_px=size, title="", font_px=L.px(28))
    note = L.note([
        "Six segments and a point light L",
        "in the unit square.",
        "Each casting segment's shadow",
        "is bounded by the segment and",
        "the two rays from L through its",
        "ends, cut off at the border.",
        "Every shadow polygon's normal",
        "points out of the shadow.",
        "",
        "Two-sided: back-facing segments",
        "(1 and 5) cast too, as a lone",
        "wall does.  Segment 4 is edge-on:",
        "no area, no shadow.  Where",
        "regions overlap the grey is",
        "darker: a stencil would count 2.",
    ], side_w, size)
    title = "The 2D exercise: shadow polygons of segments"
    return Picture(
        "shadow2d", title, "exercises",
        "Shadow polygons in 2D: every segment casts a shadow region bounded by the segment and "
        "two rays from the point light L through its ends, cut off at the unit square; the "
        "segments are two-sided, so back-facing ones cast as well as front-facing ones "
        "(the course's closed outlines let only front faces cast: `--front-only`).  Each "
        "shadow polygon has a normal pointing out of the shadow; where regions overlap, a "
        "stencil would count 2.",
        "segments (blue) with their outward normals, shadow polygons (red, dashed) with "
        "theirs, the shadow regions shaded, a segment seen edge-on and two back-facing ones",
        f"shadowvol shadow2d --example -o shadow2d.png --size {size}",
        L.compose(title, [[("", img)]], side=note,
                  legend=[("segment, its normal", (31, 119, 180)),
                          ("shadow polygon, its normal", (214, 39, 40)),
                          ("light L", slides.SCHEME["light"])]))


def ray_plane(g) -> Picture:
    L = g.layout
    side_w = L.px(900)
    w, h = L.cell(1, 1, labels=False, side=side_w)
    s = exercise.solve_plane()
    img = figure_pixels(exercise_picture.plane_figure(s, width_px=min(w, h), height_px=h,
                                                      text_px=L.px(32)))
    text = exercise.plane_text(s)
    note = L.note(_wrap(text, 56), side_w, h)
    title = "Exercise: a ray against a plane"
    return Picture(
        "ray_plane", title, "exercises",
        "The ray (5,1) + λ(−1,3) against the plane through (2,2) with normal (1,−1): in Hesse "
        "normal form n0·x = d the ray's λ is (d − n0·o) / (n0·r), here "
        f"λ = {s.lam:g}, the point ({s.hit[0]:g}, {s.hit[1]:g}).  The ray tracer intersects "
        "every plane and every triangle's plane this way.",
        "the plane (a line in 2D) with its normal at a, the ray from o along r, the hit",
        "raytrace exercise plane -o ray_plane.png",
        L.compose(title, [[("", img)]], side=note), text=text,
        numbers={"lambda": s.lam, "hit": tuple(s.hit)})


def _wrap(text: str, width: int) -> list[str]:
    import textwrap
    out = []
    for line in text.splitlines():
        out += textwrap.wrap(line, width, subsequent_indent="    ") or [""]
    return out


# ---------------------------------------------------------------------------------------------
# Outlook: raster against ray traced, shadow mapping against shadow volumes
# ---------------------------------------------------------------------------------------------

def crop_window(where: np.ndarray, cw: int, ch: int) -> tuple[int, int]:
    """(x, y) top-left of the cw x ch window holding the most True pixels of `where` (H, W)."""
    h, w = where.shape
    s = np.pad(np.cumsum(np.cumsum(where.astype(np.int64), 0), 1), ((1, 0), (1, 0)))
    sums = s[ch:, cw:] - s[:-ch, cw:] - s[ch:, :-cw] + s[:-ch, :-cw]
    y, x = np.unravel_index(int(np.argmax(sums)), sums.shape)
    return int(x), int(y)


def centred_window(where: np.ndarray, cw: int, ch: int) -> tuple[int, int]:
    """(x, y) top-left of a cw x ch window over the cluster of `crop_window`, moved so that
    the True pixels of `where` inside it are at its centre (kept inside the image): a lone
    mismatch sits in the middle of the zoom, not at its corner."""
    x, y = crop_window(where, cw, ch)
    ys, xs = np.nonzero(where[y:y + ch, x:x + cw])
    if len(xs) == 0:
        return x, y
    h, w = where.shape
    cx, cy = x + float(xs.mean()), y + float(ys.mean())
    return (int(np.clip(round(cx - cw / 2), 0, w - cw)),
            int(np.clip(round(cy - ch / 2), 0, h - ch)))


def zoom(image: np.ndarray, x: int, y: int, cw: int, ch: int, w: int, h: int) -> np.ndarray:
    """The crop (x, y, cw, ch) of `image` enlarged to (h, w) by repeating pixels (every pixel
    a visible square)."""
    crop = image[y:y + ch, x:x + cw]
    ys = (np.arange(h) * ch // h)
    xs = (np.arange(w) * cw // w)
    return crop[ys][:, xs]


def _frame(image: np.ndarray, x: int, y: int, cw: int, ch: int, px: int) -> np.ndarray:
    out = image.copy()
    c = slides.SCHEME["eye"]
    out[y:y + px, x:x + cw] = c
    out[y + ch - px:y + ch, x:x + cw] = c
    out[y:y + ch, x:x + px] = c
    out[y:y + ch, x + cw - px:x + cw] = c
    return out


BAND = (0, 190, 215)       # the ±1 px band along every mask edge: where the two may differ
BAND_WEIGHT = 0.55
EDGE_ZOOM = 12             # the compare slide's crop: 1/12 of the panel, one square per pixel


def band_panel(diff: np.ndarray, band: np.ndarray) -> np.ndarray:
    """The mask difference `diff` ((H, W, 3) uint8, maskdiff's colours) with the ±1 px band
    `band` ((H, W) bool) tinted cyan where both agree (lit: pale, shadowed: dark); a
    mismatch keeps its own red or blue."""
    agree = band & ((diff == maskdiff.BOTH_LIT) | (diff == maskdiff.BOTH_SHADOWED)).all(axis=2)
    return tint(diff, agree, np.array(BAND, np.uint8), BAND_WEIGHT)


def pixel_grid(zoomed: np.ndarray, cw: int, ch: int, colour=(150, 150, 150)) -> np.ndarray:
    """`zoom`'s picture of a cw x ch crop with a thin line between neighbouring pixels."""
    out = zoomed.copy()
    h, w = out.shape[:2]
    ys, xs = np.arange(h) * ch // h, np.arange(w) * cw // w
    out[np.flatnonzero(np.diff(ys)) + 1] = colour
    out[:, np.flatnonzero(np.diff(xs)) + 1] = colour
    return out


def compare_picture(g) -> Picture:
    L = g.layout
    scene = g.scene("cage")
    side_w = L.px(540)
    w, h = L.cell(2, 2, legend=True, side=side_w + L.margin)   # a margin at both ends
    s = slides.fit(scene, w, h)
    c = compare(s, ctx=g.ctx)
    light = c.lights[0]
    got, ref = (c.raster_lit[0], c.raster_coverage), (c.ref_lit[0], c.ref_coverage)
    diff = maskdiff.diff_panel(*got, *ref)
    band = maskdiff.near_edges(*got, *ref)
    bad = c.raster_lit[0] != c.ref_lit[0]
    n = {"size": (w, h), "pixels": w * h, "band": int(band.sum()),
         "band_differ": int((bad & band).sum()), "interior_px": int((~band).sum()),
         "interior": light.interior}
    cw, ch = max(2, w // EDGE_ZOOM), max(2, h // EDGE_ZOOM)
    # the zoom goes where the masks differ most, or, when they agree everywhere, where the
    # band is densest: the pixels where they could have differed
    x, y = centred_window(bad, cw, ch) if bad.any() else crop_window(band, cw, ch)
    ours = slides.mark_lights(slides.supersampled(
        lambda sc: _raster_image(g, sc), scene, w, h, L.supersample), s, L)
    ref_image = slides.mark_lights(slides.supersampled(
        lambda sc: raytrace.render(sc, max_depth=0, progress=False), scene, w, h,
        L.supersample), s, L)
    shown = band_panel(diff, band)
    px = max(1, L.px(4))
    side = _compare_note(L, side_w, 2 * h + 2 * L.label_h + L.margin, light, n)
    title = "Raster against ray traced: the cage, pixel by pixel"
    return Picture(
        "compare", title, "outlook",
        "The same scene twice: shadow volumes on the GPU and the ray tracer's shadow rays, "
        "compared pixel by pixel.  They may differ only on the ±1 px band along shadow and "
        "coverage edges, where a pixel centre may lie within rounding of a boundary; here "
        f"{light.mismatched} pixels differ, {n['band_differ']} of the band's {n['band']} and "
        f"{light.interior} of the {n['interior_px']} away from an edge: the interior "
        f"difference is {light.interior} (shadow IoU {light.iou:.4f}).  The zoom enlarges the "
        "part of the frame where the band is densest (or the mismatches, when there are any), "
        "one square per pixel.",
        "top: the rasterizer's image, the ray tracer's (direct light); bottom: the difference "
        "of their masks with the ±1 px band along every edge tinted cyan, and the boxed part "
        "of it enlarged with a line between pixels; at the side the counts",
        f"shadowvol compare {g.path('cage')} -o compare.png",
        L.compose(title, [[("raster (shadow volumes)", _frame(ours, x, y, cw, ch, px)),
                           ("ray traced (shadow rays)", ref_image)],
                          [(f"masks differ: {light.mismatched} px", _frame(
                              shown, x, y, cw, ch, px)),
                           (f"an edge, x{EDGE_ZOOM}: {int(bad[y:y + ch, x:x + cw].sum())} px "
                            "differ", pixel_grid(zoom(shown, x, y, cw, ch, w, h), cw, ch))]],
                  side=side,
                  legend=[("lit", maskdiff.BOTH_LIT), ("shadowed", maskdiff.BOTH_SHADOWED),
                          ("±1 px band", BAND),
                          ("shadow: raster only", maskdiff.SHADOWED_ONLY_IN_GOT),
                          ("shadow: ray tracer only", maskdiff.SHADOWED_ONLY_IN_REF),
                          ("coverage differs", maskdiff.COVERAGE_DIFFERS)]),
        numbers={"mismatched": sum(l.mismatched for l in c.lights),
                 "interior": sum(l.interior for l in c.lights), **{
                     k: v for k, v in n.items() if k != "interior"}})


def _compare_note(L, width: int, height: int, light, n: dict) -> np.ndarray:
    """The compare slide's side: the verdict, large, over what was measured."""
    head = L.text(f"interior: {light.interior} px differ", width, px=40,
                  height=L.px(64))
    body = L.note([
        "Where could they differ?",
        "Only on the ±1 px band (cyan):",
        "pixels within one pixel of a",
        "shadow or coverage edge, where",
        "a pixel centre may lie within",
        "rounding of the boundary.",
        "",
        f"Measured at {n['size'][0]} × {n['size'][1]} px:",
        f"  band: {n['band']:,} px,",
        f"      {n['band_differ']} differ",
        f"  interior: {n['interior_px']:,} px,",
        f"      {light.interior} differ",
        f"  shadow IoU {light.iou:.4f}",
        "",
        "Away from the edges the stencil",
        "count and the shadow ray agree",
        "on every pixel: the interior",
        f"difference is {light.interior}.",
    ], width, max(1, height - head.shape[0]))
    return np.concatenate([head, body])


def _raster_image(g, scene):
    with Renderer(scene, g.ctx) as r:
        return r.render().image


def shadow_mapping(g) -> Picture:
    """pyrender's shadow map against our shadow volumes on the stack's directional light."""
    from shadowvol.compare.pyrender_peer import pyrender_shadow_masks, render_pyrender

    L = g.layout
    scene = g.scene("stack")
    scene = scene.replace(lights=(scene.lights[1],))
    w, h = L.cell(2, 2, legend=True)
    s = slides.fit(scene, w, h)
    ref_lit, ref_cov = raytrace.shadow_masks(s)
    with Renderer(s, g.ctx) as r:
        ours_lit = r.render().lit
    pr_lit, pr_cov = pyrender_shadow_masks(s)
    pr_bad = (pr_lit[0] != ref_lit[0]) & ref_cov
    our_bad = (ours_lit[0] != ref_lit[0]) & ref_cov
    near = maskdiff.near_edges(pr_lit[0], pr_cov, ref_lit[0], ref_cov)
    pr_image = render_pyrender(s)
    ours = slides.supersampled(lambda sc: _raster_image(g, sc), scene, w, h, L.supersample)
    cw, ch = max(2, w // ZOOM_FRACTION), max(2, h // ZOOM_FRACTION)
    x, y = crop_window(pr_bad, cw, ch)
    px = max(1, L.px(4))
    pr_t, our_t = tint(pr_image, pr_bad), tint(ours, our_bad)
    mark = lambda im: slides.mark_lights(im, s, L)
    numbers = {"pyrender_wrong": int(pr_bad.sum()), "pyrender_interior": int(
        (pr_bad & ~near).sum()), "ours_wrong": int(our_bad.sum())}
    title = "Shadow mapping (pyrender) against shadow volumes (ours)"
    return Picture(
        "shadow_mapping", title, "outlook",
        "A shadow map stores, per texel, the depth of the nearest surface seen from the light; "
        "a point is shadowed when it lies farther from the light than its texel says.  Its "
        "texels are bigger than the screen's pixels and the comparison needs a depth bias, so "
        "shadow edges come out blocky or blurred and shadows detach from their casters "
        f"(peter-panning): pyrender gets {numbers['pyrender_wrong']} pixels wrong against the "
        f"ray tracer, {numbers['pyrender_interior']} of them away from an edge.  Shadow "
        f"volumes test every pixel exactly: ours get {numbers['ours_wrong']} wrong.",
        "top: pyrender's shadow-mapped image and ours (the stack under its directional "
        "light); bottom: the boxed part of each enlarged, the pixels whose shadow disagrees "
        "with the ray tracer's tinted red",
        f"shadowvol compare {g.path('stack')} --pyrender -o cmp.png (both lights; this picture "
        "keeps the directional one)",
        L.compose(title, [[(f"pyrender shadow map: {numbers['pyrender_wrong']} px wrong",
                            mark(_frame(pr_t, x, y, cw, ch, px))),
                           (f"shadow volumes: {numbers['ours_wrong']} px wrong",
                            mark(_frame(our_t, x, y, cw, ch, px)))],
                          [(f"pyrender, zoom x{ZOOM_FRACTION}", zoom(pr_t, x, y, cw, ch, w, h)),
                           (f"ours, zoom x{ZOOM_FRACTION}", zoom(our_t, x, y, cw, ch, w, h))]],
                  legend=[("shadow differs from the ray tracer's", slides.SCHEME["error"]),
                          ("zoomed part", slides.SCHEME["eye"])]),
        numbers=numbers)
