"""The course's gallery: `shadowvol demo -o DIR [--small]`.

Every demo is a function returning a `Picture` — an image (uint8 sRGB arrays, a title drawn
into it), a caption saying what it teaches, a line saying what it shows, and the command that
draws it on its own — and `build_gallery` runs them all.  Only `demo_command` writes files
(through `shadowvol.io`): one PNG per picture and an `index.html` showing them all.

    shadowvol demo -o gallery            # full size (each scene's own image size)
    shadowvol demo -o gallery --small    # every scene at 1/SMALL_SCALE of its size (CI)

The demos, in the order of the course:
  cage, cage_volumes   the classic shadow-volume picture, plain and with the shadow polygons
  zpass_zfail          the camera inside a shadow volume: z-pass wrong, z-fail right
  stack_stencil        the stencil buffer as a per-pixel counter (heat map)
  planar               planar projected shadows beside shadow volumes: what they cannot do
  umbra_penumbra, hard_sum   soft shadows: umbra and penumbra; the sum of N hard shadows
  shadow2d             the 2D shadow-polygon exercise
  raytree              the ray-tree exercise: every ray of one pixel to depth 2
  whitted_best         Whitted ray tracing: reflections of reflections, refraction
  compare              raster against ray traced, with the mask difference
"""

from __future__ import annotations

import html
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import raytrace
from raytrace.raytree import draw_tree, format_tree, ray_tree
from shadowvol.compare.comparison import compare
from shadowvol.compare.maskdiff import light_stats
from shadowvol.course.layout import labelled, text_strip, titled
from shadowvol.course.shadow2d import draw_shadow2d, example
from shadowvol.io import encode_srgb
from shadowvol.pictures import column, figure_pixels, heat_maps, row, tint
from shadowvol.raster.context import create_context
from shadowvol.raster.planar_pass import PlanarShadows
from shadowvol.raster.projection import view_matrix, view_projection
from shadowvol.raster.renderer import Renderer
from shadowvol.resources import data_dir
from shadowvol.scene import SceneError
from shadowvol.scenefile import load_scene

SCENES = data_dir("scenes")  # the installed example scenes, or a source checkout's scenes/
SMALL_SCALE = 4            # --small: every scene at 1/4 of its width and height
RAY_TREE_DEPTH = 2         # "sketch all rays to recursion depth 2"


@dataclass(frozen=True, eq=False)
class Picture:
    """One picture of the gallery.

    name    : file stem ("cage" -> cage.png)
    title   : drawn into the image and used as the heading
    teaches : the caption: what the picture teaches
    shows   : what is in it, panel by panel
    command : the command that draws it on its own (or the function, when none does)
    image   : (H, W, 3) uint8 sRGB, row 0 at the top, the title strip included
    text    : preformatted text shown under it in the index (the ray tree), or ""
    numbers : dict of what the demo counted (e.g. wrong pixels), for the caption and tests
    """

    name: str
    title: str
    teaches: str
    shows: str
    command: str
    image: np.ndarray
    text: str = ""
    numbers: dict = field(default_factory=dict)


# ---------------------------------------------------------------------------------------------
# Scenes
# ---------------------------------------------------------------------------------------------

class Gallery:
    """What every demo needs: the scenes folder, the size, one GL context (call `release()`)."""

    def __init__(self, small: bool = False, scenes: Path = SCENES, ctx=None):

        self.small = small
        self.scenes = Path(scenes)
        if not self.scenes.is_dir():
            raise SceneError("--scenes", f"no scenes folder at {self.scenes} (pass --scenes DIR)")
        self._own_ctx = ctx is None
        self.ctx = create_context() if ctx is None else ctx

    def scene(self, name: str):
        """scenes/<name>.toml, at 1/SMALL_SCALE of its size with --small."""

        scene = load_scene(self.scenes / f"{name}.toml")
        if self.small:
            scene = scene.replace(width=max(1, scene.width // SMALL_SCALE),
                                  height=max(1, scene.height // SMALL_SCALE))
        return scene

    def path(self, name: str) -> str:
        """How a command names the scene file: scenes/<name>.toml in a checkout."""
        folder = "scenes" if self.scenes == SCENES else str(self.scenes)
        return f"{folder}/{name}.toml"

    def release(self) -> None:
        if self._own_ctx and self.ctx is not None:
            self.ctx.release()
        self.ctx = None


# ---------------------------------------------------------------------------------------------
# The demos
# ---------------------------------------------------------------------------------------------

def cage_pictures(g: Gallery) -> list[Picture]:
    """The classic picture, plain and with the shadow polygons drawn."""

    scene = g.scene("cage")
    with Renderer(scene, g.ctx) as r:
        plain = encode_srgb(r.render().image)
        volumes = encode_srgb(r.volume_view())
    cmd = f"shadowvol render {g.path('cage')} -o cage.png"
    return [
        Picture("cage", "Shadow volumes: a point light inside a cage",
                "Exact hard shadows from a stencil count: a yellow point light inside a green "
                "cage throws the pattern of its 24 windows onto the floor and the walls; every "
                "pixel is lit exactly when no geometry lies between it and the light.",
                "the cage scene rendered with stencil shadow volumes",
                cmd, titled(plain, "Shadow volumes: a point light inside a cage", g.small)),
        Picture("cage_volumes", "The shadow polygons that made it",
                "Each silhouette edge of the cage, seen from the light, is extruded away from "
                "it to infinity: these quads (orange) bound the shadow volumes; a point is in "
                "shadow when a ray from the eye crosses more front than back quads to reach it.",
                "the same frame with the shadow-volume polygons drawn translucent and outlined "
                "(orange sides; green near and violet far caps where z-fail needs them)",
                cmd + " --volumes cage_volumes.png",
                titled(volumes, "The shadow polygons that made it", g.small)),
    ]


def zpass_zfail(g: Gallery) -> Picture:
    """Z-pass against z-fail with the eye inside a shadow volume, against the ray tracer."""


    scene = g.scene("inside_shadow")
    with Renderer(scene, g.ctx) as r:
        zpass = r.render("zpass")
        zfail = r.render("zfail")
    ref_lit, ref_cov = raytrace.shadow_masks(scene)
    reference = raytrace.render(scene, max_depth=0, progress=False)
    wrong = np.zeros(ref_cov.shape, bool)
    for i in range(len(scene.lights)):
        wrong |= zpass.lit[i] != ref_lit[i]
    stats = {m: [light_stats(res.lit[i], res.coverage, ref_lit[i], ref_cov)
                 for i in range(len(scene.lights))] for m, res in (("zpass", zpass),
                                                                  ("zfail", zfail))}
    numbers = {f"{m}_{k}": int(sum(s[k] for s in rows))
               for m, rows in stats.items() for k in ("mismatched", "interior")}
    numbers["marked"] = int(wrong.sum())
    zp, zf = encode_srgb(zpass.image), encode_srgb(zfail.image)
    panels = [[labelled(zp, "z-pass (counts from the eye)", g.small),
               labelled(zf, "z-fail (counts from infinity)", g.small)],
              [labelled(encode_srgb(reference), "ray traced reference", g.small),
               labelled(tint(zp, wrong), f"z-pass wrong: {numbers['marked']} pixels (red)",
                        g.small)]]
    title = "Z-pass against z-fail, the camera inside a shadow volume"
    return Picture(
        "zpass_zfail", title,
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
        titled(column([row(p) for p in panels]), title, g.small), numbers=numbers)


def stack_stencil(g: Gallery) -> Picture:
    """The stencil counts of overlapping volumes as a heat map."""

    scene = g.scene("stack")
    with Renderer(scene, g.ctx) as r:
        result = r.render(stencil=True)
    heat = heat_maps(result.stencil, encode_srgb(result.image), with_legend=True)
    title = "The stencil buffer as a per-pixel counter"
    labels = [f"light {i}: {type(l).__name__.replace('Light', '').lower()}"
              for i, l in enumerate(scene.lights)]
    label_row = row([text_strip(t, scene.width, g.small) for t in labels])
    return Picture(
        "stack_stencil", title,
        "The stencil buffer counts, per pixel, the shadow volumes around the visible point: "
        "+1 for every front face of a volume crossed, -1 for every back face.  Four staggered "
        "slabs make the volumes overlap; each closed slab counts 2 (its top and its bottom lie "
        "between the point and the light).  A pixel is lit only where the count is 0.",
        "one heat map per light (the point light above, the directional light): count 0 shows "
        "the image darkened, 1, 2, ... go from yellow to violet",
        f"shadowvol render {g.path('stack')} -o stack.png --stencil stack_stencil.png",
        titled(np.concatenate([label_row, heat]), title, g.small),
        numbers={"max_count": int(result.stencil.max())})


def planar(g: Gallery) -> Picture:
    """Planar projected shadows beside shadow volumes, and what the projection misses."""

    scene = g.scene("planar")
    with Renderer(scene, g.ctx) as r, PlanarShadows(r) as p:
        projected = p.render()
        volumes = r.render()
    missing = (projected.lit & ~volumes.lit).any(axis=0)
    extra = (volumes.lit & ~projected.lit).any(axis=0)
    pv, vv = encode_srgb(projected.image), encode_srgb(volumes.image)
    receiver = scene.objects[projected.receiver].name
    title = "Planar projected shadows (Blinn 1988) against shadow volumes"
    panels = [labelled(pv, f"projected onto the {receiver}", g.small),
              labelled(vv, "shadow volumes", g.small),
              labelled(tint(pv, missing), f"missing in the projection: {int(missing.sum())} px",
                       g.small)]
    return Picture(
        "planar", title,
        "A matrix squashes every object from the light onto the floor's plane; where it lands "
        "(the stencil keeps it on the floor and counts each pixel once) the light is left out, "
        "and that is the floor's shadow, exactly.  But only the floor's: the ball's shadow on the box and the cage's shadow "
        "on its own inside are missing, because a projection onto one plane cannot shadow "
        "other objects or an object itself.  Shadow volumes do both.",
        "projected shadows; shadow volumes; the projected-shadow image with the pixels that "
        "shadow volumes shadow and the projection leaves lit tinted red",
        "shadowvol demo (shadowvol.course.gallery.planar: shadowvol.raster.planar_pass.PlanarShadows beside "
        f"Renderer.render on {g.path('planar')})",
        titled(row(panels), title, g.small),
        numbers={"missing": int(missing.sum()), "extra": int(extra.sum())})


def shadow2d(g: Gallery) -> Picture:
    """The 2D exercise's example."""

    size = 800 // (2 if g.small else 1)
    title = "The 2D exercise: shadow polygons of segments"
    return Picture(
        "shadow2d", title,
        "Shadow polygons in 2D: every segment facing the point light L casts a shadow region "
        "bounded by the segment and two rays from L through its ends, cut off at the unit "
        "square.  Each shadow polygon has a normal pointing out of the shadow; where regions "
        "overlap, a stencil would count 2.",
        "segments (blue) with their outward normals, shadow polygons (red, dashed) with "
        "theirs, the shadow regions shaded, a segment seen edge-on and a back-facing one",
        f"shadowvol shadow2d --example -o shadow2d.png --size {size}",
        titled(draw_shadow2d(*example(), size_px=size), title, g.small))


def ray_tree_pixel(scene, obj_name: str, offset=(-0.35, 0.45)) -> tuple[int, int]:
    """The pixel (x, y) showing the sphere `obj_name` at `offset` (fractions of its radius,
    along the camera's right and up) from its centre: a pixel on the sphere at any size."""

    obj = next(o for o in scene.objects if o.name == obj_name)
    view = view_matrix(scene.camera)
    right, up = view[0, :3], view[1, :3]
    c = obj.analytic.center + obj.analytic.radius * (offset[0] * right + offset[1] * up)
    clip = view_projection(scene.camera, scene.aspect) @ np.append(c, 1.0)
    ndc = clip[:2] / clip[3]
    return (int((ndc[0] + 1) / 2 * scene.width), int((1 - ndc[1]) / 2 * scene.height))


def raytree(g: Gallery) -> Picture:
    """The ray tree of a pixel on the glass ball of scenes/whitted.toml, depth 2."""

    scene = g.scene("whitted")
    x, y = ray_tree_pixel(scene, "glass ball")
    tree = ray_tree(scene, x, y, max_depth=RAY_TREE_DEPTH)
    fig = draw_tree(scene, tree, raytrace.render(scene, progress=False))
    if g.small:
        fig.set_dpi(50)
    kinds = [n.kind for n in tree.walk()]
    title = f"The ray tree of pixel ({x}, {y}), to recursion depth {RAY_TREE_DEPTH}"
    return Picture(
        "raytree", title,
        "Whitted's recursion for one pixel: the primary ray hits the glass ball; from every "
        "hit a shadow ray goes to each light, a reflected ray and, through glass, a refracted "
        "ray, each of which does the same, down to the depth limit.  The pixel's colour is "
        "the sum of what every ray contributes.",
        "the rays over the ray-traced image, in a side and a top view, coloured by kind and "
        "numbered as in the tree below",
        f"raytrace tree {g.path('whitted')} --pixel {x} {y} --depth {RAY_TREE_DEPTH} "
        "-o raytree.png",
        titled(figure_pixels(fig), title, g.small), text=format_tree(tree, scene),
        numbers={"rays": len(kinds), **{k: kinds.count(k) for k in sorted(set(kinds))}})


def whitted_best(g: Gallery) -> Picture:
    """Whitted ray tracing: mirror spheres facing each other, a glass sphere."""


    scene = g.scene("whitted_best")
    image = encode_srgb(raytrace.render(scene, progress=False))
    title = "Whitted ray tracing: reflections of reflections, refraction"
    return Picture(
        "whitted_best", title,
        "Recursive ray tracing: two mirror balls facing each other reflect each other's "
        "reflections, again and again up to the recursion depth; the glass ball bends the "
        "rays by Snell's law and shows the scene behind it upside down; every hit sends shadow "
        f"rays, so the shadows are exact.  Recursion depth {scene.max_depth}.",
        "the whitted_best scene ray traced (a point and a directional light, Phong, shadow "
        "rays, reflection, refraction)",
        f"raytrace render {g.path('whitted_best')} -o whitted_best.png",
        titled(image, title, g.small))


def compare_picture(g: Gallery) -> Picture:
    """Raster against ray traced on the cage scene."""

    scene = g.scene("cage")
    c = compare(scene, ctx=g.ctx)
    title = "Raster against ray traced: the cage"
    light = c.lights[0]
    return Picture(
        "compare", title,
        "The same scene twice: shadow volumes on the GPU and the ray tracer's shadow rays, "
        "compared pixel by pixel.  They may differ only on shadow edges, where a pixel centre "
        f"lies within rounding of a boundary; here {light.mismatched} pixels differ, "
        f"{light.interior} away from an edge (shadow IoU {light.iou:.4f}).",
        "per light: the rasterizer's image, the ray tracer's image (direct light), and the "
        "difference of their masks (white both lit, grey both shadowed, red / blue shadowed "
        "in one only)",
        f"shadowvol compare {g.path('cage')} -o compare.png",
        titled(c.picture(), title, g.small),
        numbers={"mismatched": sum(l.mismatched for l in c.lights),
                 "interior": sum(l.interior for l in c.lights)})


def soft_pictures(g: Gallery) -> list[Picture]:
    """Umbra and penumbra, and a soft shadow as the sum of hard ones (`soft_gallery`)."""
    from shadowvol.course.soft_gallery import hard_sum, umbra_penumbra

    return [umbra_penumbra(g), hard_sum(g)]


DEMOS = (cage_pictures, zpass_zfail, stack_stencil, planar, soft_pictures, shadow2d, raytree,
         whitted_best, compare_picture)


def build_gallery(small: bool = False, scenes: Path = SCENES, ctx=None,
                  progress=None) -> list[Picture]:
    """Every demo's pictures, in the course's order.  `progress(name, seconds)` is called after
    each demo when given."""
    g = Gallery(small, scenes, ctx)
    pictures = []
    try:
        for demo in DEMOS:
            start = time.perf_counter()
            made = demo(g)
            pictures += made if isinstance(made, list) else [made]
            if progress:
                progress(demo.__name__, time.perf_counter() - start)
    finally:
        g.release()
    return pictures


# ---------------------------------------------------------------------------------------------
# index.html
# ---------------------------------------------------------------------------------------------

_STYLE = """
body { font-family: sans-serif; max-width: 1400px; margin: 2em auto; padding: 0 1em;
       color: #222; }
figure { margin: 2.5em 0; }
img { max-width: 100%; border: 1px solid #ccc; }
figcaption p { margin: 0.4em 0; }
.shows, .command { color: #555; font-size: 0.92em; }
pre { background: #f4f4f4; padding: 0.8em; overflow-x: auto; font-size: 0.85em; }
"""


def index_html(pictures: list[Picture], small: bool) -> str:
    """The gallery page: every picture (relative links), its caption, what it shows and the
    command that draws it."""
    e = html.escape
    size = f"at 1/{SMALL_SCALE} size (--small)" if small else "at full size"
    parts = ["<!DOCTYPE html>", '<html lang="en">', "<head>", '<meta charset="utf-8">',
             "<title>shadowvol: the course gallery</title>", f"<style>{_STYLE}</style>",
             "</head>", "<body>", "<h1>Shadows and ray tracing: the gallery</h1>",
             f"<p>Made by <code>shadowvol demo -o DIR{' --small' if small else ''}</code>, "
             f"{e(size)}.  Each picture says what it teaches, what it shows and the command "
             "that draws it on its own.</p>"]
    for p in pictures:
        parts += [f'<figure id="{e(p.name)}">', f"<h2>{e(p.title)}</h2>",
                  f'<img src="{e(p.name)}.png" alt="{e(p.title)}" '
                  f'width="{p.image.shape[1]}" height="{p.image.shape[0]}">',
                  "<figcaption>", f"<p>{e(p.teaches)}</p>",
                  f'<p class="shows">Shows: {e(p.shows)}.</p>',
                  f'<p class="command">Command: <code>{e(p.command)}</code></p>',
                  "</figcaption>"]
        if p.text:
            parts.append(f"<pre>{e(p.text)}</pre>")
        parts.append("</figure>")
    parts += ["</body>", "</html>", ""]
    return "\n".join(parts)
