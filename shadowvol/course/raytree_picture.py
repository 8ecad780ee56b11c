"""The picture of a ray tree (`raytrace.raytree`): the rays over the render, a side view and a
top view, coloured by kind and numbered as `format_tree` prints them.

    tree = ray_tree(scene, x, y, max_depth=3)
    figure = draw_tree(scene, tree, image)   # a matplotlib Figure; no backend is chosen

The ray tracer computes the tree; only the drawing lives here, with the course's pictures.
"""

from __future__ import annotations

import numpy as np

from raytrace.camera import camera_basis
from raytrace.raytree import (
    BLOCKED,
    FACES_AWAY,
    LIT,
    OUTSIDE_CONE,
    PRIMARY,
    REFLECTED,
    REFRACTED,
    SHADOW,
    TIR,
    RayNode,
)
from shadowvol.io import encode_srgb
from shadowvol.scene import DirectionalLight, Scene, SpotLight

COLOURS = {PRIMARY: "#ffffff", REFLECTED: "#00d0ff", REFRACTED: "#40e040", TIR: "#ff40ff",
           LIT: "#ffd000", BLOCKED: "#ff3030", FACES_AWAY: "#a0a0a0", OUTSIDE_CONE: "#a0a0a0"}


def _colour(node: RayNode) -> str:
    return COLOURS[node.verdict] if node.kind == SHADOW else COLOURS[node.kind]


def project(scene: Scene, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
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


def clip_near(scene: Scene, a: np.ndarray, b: np.ndarray):
    """The part of segment a-b in front of the near plane, or None."""
    _, (da, db) = project(scene, np.array([a, b]))
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
        seg = clip_near(scene, node.origin, node.end)
        if seg is None:
            continue
        xy, _ = project(scene, np.array(seg))
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
    xy, _ = project(scene, np.array([tree.origin + tree.direction]))
    return xy[0]
