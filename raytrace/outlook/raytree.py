"""The ray-tree exercise: every ray the Whitted tracer follows for one pixel, as a tree.

    tree = ray_tree(scene, x, y, max_depth=3)
    print(format_tree(tree))

The root is the primary ray through the centre of pixel (x, y).  Every ray that hits a surface
has, as children, one shadow ray per light (with its verdict: lit, blocked, or not traced
because the surface faces away from the light or lies outside a spot's cone), then — below the
depth limit — the reflected ray (if the material reflects) and the refracted ray (if it is
transparent; when Snell's law has no solution that ray is the total internal reflection, kind
"tir").

Nothing here decides anything about light transport: hits, normals, shadow-ray verdicts, the
offsets off the surface, reflection and refraction all come from `raytrace.outlook.whitted`'s own
functions (`World.nearest`, `surface_frame`, `shadow_rays`, `local_colour`, `secondary_rays`)
called on one ray at a time, so the tree is the renderer's, and `tree_colour(tree)` is the
pixel's colour in `raytrace.render(scene)` (up to floating-point summation order).
The picture of a tree is the course's (`shadowvol.course.raytree_slide.slide`).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from shadowvol.scene import DirectionalLight, Scene

from raytrace.camera import primary_rays

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
        node.children.append(_shadow_node(world, scene, i, light, p, n, depth, weight, obj))
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
                 weight: float, obj: np.ndarray | None = None) -> RayNode:
    """The shadow ray from the hit p, n (1, 3) on object obj (1,) to light i, with whitted's
    verdict (the shadow switches included: `whitted.shadow_rays`)."""
    rays = shadow_rays(world, light, p, n, obj)
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
    the rays and boxes in the course's picture, `raytree_slide`), and the pixel colour as the
    sum of the contributions."""
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
