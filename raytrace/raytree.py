"""The ray-tree exercise: every ray the Whitted tracer follows for one pixel, as a tree.

    tree = ray_tree(scene, x, y, max_depth=3)
    print(format_tree(tree))
    figure = draw_tree(scene, tree, image)   # the rays over the render; side and top views

The root is the primary ray through the centre of pixel (x, y).  Every ray that hits a surface
has, as children, one shadow ray per light (with its verdict: lit, blocked, or not traced
because the surface faces away from the light or lies outside a spot's cone), then — below the
depth limit — the reflected ray (if the material reflects) and the refracted ray (if it is
transparent; when Snell's law has no solution that ray is the total internal reflection, kind
"tir").

Nothing here decides anything about light transport: hits, normals, shadow-ray verdicts, the
offsets off the surface, reflection and refraction all come from `raytrace.whitted`'s own
functions (`World.nearest`, `surface_frame`, `shadow_rays`, `local_colour`, `secondary_rays`)
called on one ray at a time, so the tree is the renderer's, and `tree_colour(tree)` is the
pixel's colour in `raytrace.render(scene)` (up to floating-point summation order).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from shadowvol.io import encode_srgb
from shadowvol.scene import DirectionalLight, Scene, SpotLight

from .camera import camera_basis, primary_rays
from .whitted import World, local_colour, secondary_rays, shadow_rays, surface_frame

PRIMARY, REFLECTED, REFRACTED, TIR, SHADOW = "primary", "reflected", "refracted", "tir", "shadow"
KINDS = (PRIMARY, REFLECTED, REFRACTED, TIR, SHADOW)

# Shadow-ray verdicts.
LIT, BLOCKED, FACES_AWAY, OUTSIDE_CONE = "lit", "blocked", "faces away", "outside cone"

# A ray that hits nothing (or a shadow ray toward a directional light) is drawn this long,
# relative to the scene's extent: it has no end point of its own.
MISS_LENGTH_RELATIVE = 0.35


@dataclass(eq=False)
class RayNode:
    """One ray of the tree.

    kind      : one of KINDS
    origin    : (3,) float64, where the ray starts (already offset off the surface it leaves)
    direction : (3,) float64, as traced: unit for primary, reflected, refracted and tir rays;
                for shadow rays the direction `shadow_rays` traces (see whitted.ShadowRays)
    depth     : generation: 0 for the primary ray, parent's + 1 for reflected / refracted / tir;
                a shadow ray has its surface's depth
    weight    : float, product of the reflectivity / transparency factors along the path: how
                much this ray's colour counts in the pixel (shadow rays: their surface's weight)
    t         : float, distance along `direction` to the hit (inf: miss; shadow rays: to the
                nearest blocker, inf when none)
    obj       : int, index of the object hit (-1: miss; shadow rays: the nearest blocker)
    obj_name  : str or None
    point     : (3,) float64 hit point, or None
    normal    : (3,) float64 shading normal at the hit, facing the ray, or None
    entering  : bool or None: the ray meets the front of the geometric normal
    local     : (3,) float64 Phong local term at the hit (whitted.local_colour), or None
    contribution : (3,) float64, what this ray adds to the pixel (see `tree_colour`); zero for
                shadow rays (their effect is inside their parent's `local`)
    light     : int or None, the light a shadow ray goes to (index into scene.lights)
    verdict   : str or None, for shadow rays: LIT, BLOCKED, FACES_AWAY or OUTSIDE_CONE (the
                last two are not traced: n·l <= 0, or outside the cone)
    end       : (3,) float64, where to draw the ray to: the hit point, the blocker, the light
                (a point or spot light) or a point MISS_LENGTH_RELATIVE · extent along the ray
    children  : list[RayNode], shadow rays first (in light order), then reflected, then
                refracted or tir
    """

    kind: str
    origin: np.ndarray
    direction: np.ndarray
    depth: int
    weight: float
    t: float = np.inf
    obj: int = -1
    obj_name: str | None = None
    point: np.ndarray | None = None
    normal: np.ndarray | None = None
    entering: bool | None = None
    local: np.ndarray | None = None
    contribution: np.ndarray = field(default_factory=lambda: np.zeros(3))
    light: int | None = None
    verdict: str | None = None
    end: np.ndarray | None = None
    children: list["RayNode"] = field(default_factory=list)

    @property
    def hit(self) -> bool:
        return self.obj >= 0

    def walk(self):
        """This node and all below it, depth first, in the order `format_tree` prints them."""
        yield self
        for c in self.children:
            yield from c.walk()


def ray_tree(scene: Scene, x: int, y: int, max_depth: int | None = None,
             backend: str = "embree") -> RayNode:
    """The ray tree of pixel (x, y) (column x from the left, row y from the top) up to
    `max_depth` reflection / refraction generations (default `scene.max_depth`)."""
    depth = scene.max_depth if max_depth is None else max_depth
    if isinstance(depth, bool) or not isinstance(depth, (int, np.integer)) or depth < 0:
        raise ValueError(f"max_depth must be a whole number >= 0, got {depth!r}")
    W, H = scene.width, scene.height
    if not (0 <= x < W and 0 <= y < H):
        raise ValueError(f"pixel ({x}, {y}) is outside the {W}x{H} image")
    world = World(scene, backend, parallel=False)
    o, d = primary_rays(scene.camera, W, H, slice(y, y + 1))
    return _trace(world, scene, o[x:x + 1], d[x:x + 1], PRIMARY, 0, 1.0, depth)


def _trace(world: World, scene: Scene, o: np.ndarray, d: np.ndarray, kind: str, depth: int,
           weight: float, max_depth: int) -> RayNode:
    """The node of one ray o, d (1, 3) and, recursively, its children."""
    t, obj, geo_n = world.nearest(o, d)
    node = RayNode(kind, o[0].copy(), d[0].copy(), depth, weight)
    if obj[0] < 0:
        node.end = o[0] + MISS_LENGTH_RELATIVE * scene.extent * d[0]
        node.contribution = weight * scene.background
        return node
    p, entering, n = surface_frame(o, d, t, geo_n)
    node.t, node.obj = float(t[0]), int(obj[0])
    node.obj_name = scene.objects[node.obj].name
    node.point, node.normal, node.entering = p[0], n[0], bool(entering[0])
    node.end = p[0]
    node.local = local_colour(world, scene, p, n, -d, obj)[0]
    refl, transp = float(world.refl[obj[0]]), float(world.transp[obj[0]])
    last = depth == max_depth
    node.contribution = (weight if last else weight * (1.0 - refl - transp)) * node.local
    for i, light in enumerate(scene.lights):
        node.children.append(_shadow_node(world, scene, i, light, p, n, depth, weight))
    if last:
        return node
    sec = secondary_rays(world, p, n, d, entering, obj)
    if len(sec.reflect_index):
        node.children.append(_trace(world, scene, sec.reflect_origin, sec.reflect_direction,
                                    REFLECTED, depth + 1, weight * refl, max_depth))
    if len(sec.refract_index):
        node.children.append(_trace(world, scene, sec.refract_origin, sec.refract_direction,
                                    TIR if sec.tir[0] else REFRACTED, depth + 1,
                                    weight * transp, max_depth))
    return node


def _shadow_node(world: World, scene: Scene, i: int, light, p, n, depth: int,
                 weight: float) -> RayNode:
    """The shadow ray from the hit p, n (1, 3) to light i, with whitted's verdict."""
    rays = shadow_rays(world, light, p, n)
    o, d = rays.origin[0].copy(), np.array(rays.direction[0])
    node = RayNode(SHADOW, o, d, depth, weight, light=i)
    if not rays.facing[0]:
        node.verdict = FACES_AWAY
    elif not rays.in_cone[0]:
        node.verdict = OUTSIDE_CONE
    else:
        node.verdict = BLOCKED if rays.blocked[0] else LIT
    if isinstance(light, DirectionalLight):
        target = o + MISS_LENGTH_RELATIVE * scene.extent * rays.to_light[0]
    else:
        target = light.position.copy()
    node.end = target
    if node.verdict == BLOCKED:
        # Which object blocks it, for the reader and the picture; the verdict itself is
        # whitted's (World.occluded), this only names the nearest object on the ray.
        t, obj, _ = world.nearest(rays.origin[:1], rays.direction[:1])
        bound = np.inf if rays.tmax is None else rays.tmax
        if obj[0] >= 0 and t[0] < bound:
            node.t, node.obj = float(t[0]), int(obj[0])
            node.obj_name = scene.objects[node.obj].name
            node.point = o + node.t * d
            node.end = node.point
    return node


def tree_colour(tree: RayNode) -> np.ndarray:
    """(3,) float64 linear RGB: the pixel's colour as the sum of every ray's contribution —
    weight · background for a miss, weight · (1 − refl − transp) · local for a hit below the
    depth limit and weight · local at it (whitted's unrolled recursion)."""
    return np.sum([node.contribution for node in tree.walk()], axis=0)


# ---------------------------------------------------------------------------------------------
# Text
# ---------------------------------------------------------------------------------------------

def _v(a) -> str:
    return "(" + ", ".join(f"{c:.3f}" for c in a) + ")"


def _describe(node: RayNode, number: int, scene: Scene) -> str:
    if node.kind == SHADOW:
        light = scene.lights[node.light]
        what = type(light).__name__.replace("Light", "").lower()
        s = f"#{number} shadow -> light {node.light} ({what}): {node.verdict}"
        if node.verdict == BLOCKED and node.obj_name is not None:
            s += f" by '{node.obj_name}' at {_v(node.point)}"
        elif node.verdict == FACES_AWAY:
            s += " (n.l <= 0, not traced)"
        elif node.verdict == OUTSIDE_CONE:
            s += " (not traced)"
        return s
    s = f"#{number} {node.kind} [depth {node.depth}, weight {node.weight:.4g}] " \
        f"o={_v(node.origin)} d={_v(node.direction)}"
    if not node.hit:
        return s + f": miss -> background, adds {_v(node.contribution)}"
    side = "entering" if node.entering else "leaving"
    return (s + f": hits '{node.obj_name}' at t={node.t:.4g}, p={_v(node.point)} ({side}); "
                f"local {_v(node.local)}, adds {_v(node.contribution)}")


def format_tree(tree: RayNode, scene: Scene) -> str:
    """The tree as indented text, one ray per line, numbered depth first (the numbers label
    the rays in `draw_tree`'s picture), and the pixel colour as the sum of the contributions."""
    lines = []
    numbers = {id(n): k for k, n in enumerate(tree.walk())}

    def visit(node: RayNode, prefix: str, tail: bool, root: bool) -> None:
        branch = "" if root else ("`- " if tail else "|- ")
        lines.append(prefix + branch + _describe(node, numbers[id(node)], scene))
        inner = prefix + ("" if root else ("   " if tail else "|  "))
        for k, child in enumerate(node.children):
            visit(child, inner, k == len(node.children) - 1, False)

    visit(tree, "", True, True)
    lines.append(f"pixel colour (linear RGB) = sum of the contributions = "
                 f"{_v(tree_colour(tree))}")
    return "\n".join(lines)


# ---------------------------------------------------------------------------------------------
# Picture
# ---------------------------------------------------------------------------------------------

COLOURS = {PRIMARY: "#ffffff", REFLECTED: "#00d0ff", REFRACTED: "#40e040", TIR: "#ff40ff",
           LIT: "#ffd000", BLOCKED: "#ff3030", FACES_AWAY: "#a0a0a0", OUTSIDE_CONE: "#a0a0a0"}


def _colour(node: RayNode) -> str:
    return COLOURS[node.verdict] if node.kind == SHADOW else COLOURS[node.kind]


def _project(scene: Scene, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Pixel coordinates (n, 2) float64 (x right, y down, pixel centres at +0.5) of world
    points (n, 3), and their eye-space depth (n,) (positive in front of the eye)."""
    right, up, back = camera_basis(scene.camera)
    rel = points - scene.camera.eye
    depth = -(rel @ back)
    half_h = np.tan(np.radians(scene.camera.fov_y) / 2.0)
    half_w = half_h * scene.aspect
    with np.errstate(divide="ignore", invalid="ignore"):
        ndc_x = (rel @ right) / (depth * half_w)
        ndc_y = (rel @ up) / (depth * half_h)
    px = (ndc_x + 1.0) / 2.0 * scene.width
    py = (1.0 - ndc_y) / 2.0 * scene.height
    return np.stack([px, py], axis=1), depth


def _clip_near(scene: Scene, a: np.ndarray, b: np.ndarray):
    """The part of segment a-b in front of the near plane, or None."""
    _, (da, db) = _project(scene, np.array([a, b]))
    near = scene.camera.near
    if da < near and db < near:
        return None
    if da < near:
        a = a + (near - da) / (db - da) * (b - a)
    elif db < near:
        b = b + (near - db) / (da - db) * (a - b)
    return a, b


def _view_axes(scene: Scene, view: str) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Orthographic views of the scene, by the camera's frame with `up` kept vertical.
    Returns the plot's horizontal and vertical axes and the direction toward the view's
    observer ((3,) unit each):
      "side": horizontal = the view direction made perpendicular to up, vertical = up, seen
              from the camera's right;
      "top" : horizontal = the camera's right, vertical = the view direction, seen from above.
    """
    up = scene.camera.up / np.linalg.norm(scene.camera.up)
    fwd = scene.camera.target - scene.camera.eye
    fwd = fwd - (fwd @ up) * up
    fwd = fwd / np.linalg.norm(fwd)
    right = np.cross(fwd, up)
    if view == "side":
        return fwd, up, right
    return right, fwd, up


VIEW_BACKGROUND = "#d8e4f2"
GLASS_TINT = np.array([0.70, 0.92, 0.98])
MIRROR_TINT = np.array([0.78, 0.78, 0.84])


def _object_colour(material) -> np.ndarray:
    """(3,) float in [0, 1]: an object's flat colour in the orthographic views — its ambient
    + diffuse colour, lightened, and tinted pale cyan by transparency and silver by
    reflectivity (glass and mirrors have almost no colour of their own)."""
    base = 0.2 + 0.6 * np.clip(material.diffuse + material.ambient, 0.0, 1.0)
    base = base + material.transparency * (GLASS_TINT - base)
    return np.clip(base + material.reflectivity * (MIRROR_TINT - base), 0.0, 1.0)


def _draw_view(ax, scene: Scene, nodes: list[RayNode], view: str, pt: float = 8.0) -> None:
    """One orthographic view (see `_view_axes`): the objects as filled silhouettes (far ones
    first), the eye, the point and spot lights, every ray coloured by kind and numbered (a hit
    at its end, a shadow ray along it), labels kept apart; the frame holds every ray and every
    object the rays meet, whole."""
    from matplotlib.collections import PolyCollection

    h_axis, v_axis, toward = _view_axes(scene, view)
    order = sorted(range(len(scene.objects)),
                   key=lambda i: float(scene.objects[i].vertices.mean(axis=0) @ toward))
    for i in order:
        obj = scene.objects[i]
        tri = obj.triangles  # (m, 3, 3)
        flat = np.stack([tri @ h_axis, tri @ v_axis], axis=-1)
        colour = _object_colour(obj.material)
        # edges in the face colour: a surface seen edge-on (a floor from the side) is a line
        ax.add_collection(PolyCollection(flat, facecolors=[colour], edgecolors=[colour],
                                         linewidths=1.0, zorder=1))
    for node in nodes:
        a, b = node.origin, node.end
        style = ":" if node.verdict in (FACES_AWAY, OUTSIDE_CONE) else "-"
        colour = "black" if node.kind == PRIMARY else _colour(node)
        ax.plot([a @ h_axis, b @ h_axis], [a @ v_axis, b @ v_axis], style, color=colour,
                lw=1.4, zorder=3)
    ax.set_facecolor(VIEW_BACKGROUND)
    eye = scene.camera.eye
    ax.plot([eye @ h_axis], [eye @ v_axis], "s", color="black", ms=pt * 0.8, zorder=4)
    anchors = [("eye", (eye @ h_axis, eye @ v_axis))]
    for i, light in enumerate(scene.lights):
        if isinstance(light, DirectionalLight):
            continue
        q = (light.position @ h_axis, light.position @ v_axis)
        ax.plot(*q, "*", color="#e0a000", mec="black", ms=pt * 1.8, zorder=4)
        kind = "spot" if isinstance(light, SpotLight) else "point"
        anchors.append((f"light {i} ({kind})", q))
    pts = [p for n in nodes for p in (n.origin, n.end)] + [eye] + \
        [l.position for l in scene.lights if not isinstance(l, DirectionalLight)]
    reach = np.ptp(np.array(pts), axis=0).max()
    hit_objects = {n.obj for n in nodes if n.obj >= 0}
    for i in hit_objects:   # objects the rays meet, whole, unless far bigger than the rays
        v = scene.objects[i].vertices
        if np.ptp(v, axis=0).max() <= reach:
            pts += [v.min(axis=0), v.max(axis=0), *v[:: max(1, len(v) // 200)]]
    pts = np.array(pts)
    hs, vs = pts @ h_axis, pts @ v_axis
    pad = 0.06 * max(np.ptp(hs), np.ptp(vs), 1e-9)
    ax.set_xlim(hs.min() - pad, hs.max() + pad)
    ax.set_ylim(vs.min() - pad, vs.max() + pad)
    ax.set_aspect("equal")
    for k, node in enumerate(nodes):
        if node.kind == SHADOW:
            q = node.origin + 0.3 * (node.end - node.origin)
        elif node.hit:
            q = node.point
            ax.plot(q @ h_axis, q @ v_axis, ".", color="black", ms=pt * 0.6, zorder=4)
        else:
            q = node.origin + 0.85 * (node.end - node.origin)
        anchors.append((f"#{k}", (q @ h_axis, q @ v_axis)))
    place_labels(ax, anchors, pt)
    ax.tick_params(labelsize=pt * 0.9)
    if view == "side":
        ax.set_title("side view (from the camera's right)", fontsize=pt * 1.2)
        ax.set_xlabel("along the view direction", fontsize=pt)
        ax.set_ylabel("up", fontsize=pt)
    else:
        ax.set_title("top view (from above)", fontsize=pt * 1.2)
        ax.set_xlabel("to the camera's right", fontsize=pt)
        ax.set_ylabel("along the view direction", fontsize=pt)


LABEL_OFFSETS = ((4, 4), (4, -14), (-22, 4), (-22, -14), (10, 14), (-30, -24), (16, -26),
                 (-34, 16))   # points, tried in order; scaled with the font


def place_labels(ax, anchors, pt: float, **style) -> None:
    """Annotate each (text, (x, y) data point) at the first of LABEL_OFFSETS whose box does
    not overlap a label already placed (the last offset when all do)."""
    fig = ax.figure
    to_px = ax.transData.transform
    scale = pt / 8.0 * fig.dpi / 72.0
    taken = []
    for text, q in anchors:
        x, y = to_px(q)
        w, h = (0.62 * len(text) + 0.4) * pt * fig.dpi / 72.0, 1.25 * pt * fig.dpi / 72.0
        choice = LABEL_OFFSETS[-1]
        for dx, dy in LABEL_OFFSETS:
            box = (x + dx * scale, y + dy * scale, w, h)
            if not any(_overlap(box, t) for t in taken):
                choice = (dx, dy)
                break
        taken.append((x + choice[0] * scale, y + choice[1] * scale, w, h))
        ax.annotate(text, q, xytext=(choice[0] * scale * 72 / fig.dpi,
                                     choice[1] * scale * 72 / fig.dpi),
                    textcoords="offset points", fontsize=pt, zorder=6, **style)


def _overlap(a, b) -> bool:
    return a[0] < b[0] + b[2] and b[0] < a[0] + a[2] and a[1] < b[1] + b[3] and b[1] < a[1] + a[3]


def draw_tree(scene: Scene, tree: RayNode, image: np.ndarray | None = None, *,
              size_px: tuple[int, int] = (1700, 580), text_px: float | None = None):
    """A matplotlib Figure of the tree, three panels: `image` ((H, W, 3) linear RGB, e.g.
    raytrace.render(scene); None: a grey frame) with every ray projected through the camera,
    coloured by kind and numbered as in `format_tree`; a side view and a top view (the scene's
    objects, the eye, the lights and the same rays, orthographic); a legend below.
    `size_px` (width, height) of the figure; `text_px` the labels' size (default 8 points)."""
    from matplotlib.figure import Figure
    from matplotlib.lines import Line2D
    from matplotlib.patheffects import withStroke


    nodes = list(tree.walk())
    outline = [withStroke(linewidth=2, foreground="black")]  # labels legible on any colour
    fig = Figure(figsize=(size_px[0] / 100, size_px[1] / 100), dpi=100, layout="constrained")
    pt = 8.0 if text_px is None else text_px * 72 / 100
    ax_img, ax_side, ax_top = fig.subplots(
        1, 3, gridspec_kw={"width_ratios": [scene.aspect, 1.0, 1.0]})
    # ---- over the image
    if image is None:
        shown = np.full((scene.height, scene.width, 3), 90, np.uint8)
    else:
        shown = encode_srgb(image)
    ax_img.imshow(shown, extent=(0, scene.width, scene.height, 0), interpolation="nearest")
    ax_img.set_xlim(0, scene.width)
    ax_img.set_ylim(scene.height, 0)
    px = _pixel(scene, tree)
    ax_img.set_title("the rays over the image",
                     fontsize=pt * 1.2)
    ax_img.set_xticks([])
    ax_img.set_yticks([])
    anchors = [("#0 (primary)", tuple(px))]
    for k, node in enumerate(nodes):
        if node.kind == PRIMARY:
            continue
        seg = _clip_near(scene, node.origin, node.end)
        if seg is None:
            continue
        xy, _ = _project(scene, np.array(seg))
        style = ":" if node.verdict in (FACES_AWAY, OUTSIDE_CONE) else "-"
        ax_img.plot(xy[:, 0], xy[:, 1], style, color=_colour(node), lw=1.6)
        if node.hit and node.kind != SHADOW:
            anchors.append((f"#{k}", tuple(xy[1])))
    ax_img.plot([px[0]], [px[1]], "o", mfc="none", mec="white", ms=pt * 1.1, mew=1.5)
    place_labels(ax_img, anchors, pt, color="white", path_effects=outline)
    # ---- orthographic views
    _draw_view(ax_side, scene, nodes, "side", pt)
    _draw_view(ax_top, scene, nodes, "top", pt)
    handles = [Line2D([], [], color="black", label="primary"),
               Line2D([], [], color=COLOURS[REFLECTED], label="reflected"),
               Line2D([], [], color=COLOURS[REFRACTED], label="refracted"),
               Line2D([], [], color=COLOURS[TIR], label="total internal reflection"),
               Line2D([], [], color=COLOURS[LIT], label="shadow ray: lit"),
               Line2D([], [], color=COLOURS[BLOCKED], label="shadow ray: blocked"),
               Line2D([], [], color=COLOURS[FACES_AWAY], ls=":",
                      label="not traced: the light is behind the surface or outside a "
                            "spot's cone")]
    fig.legend(handles=handles, loc="outside lower center",
               ncols=len(handles) if text_px is None else 3, fontsize=pt, frameon=False)
    return fig


def _pixel(scene: Scene, tree: RayNode) -> np.ndarray:
    """(2,) float64: where the primary ray pierces the image (the pixel's centre)."""
    xy, _ = _project(scene, np.array([tree.origin + tree.direction]))
    return xy[0]
