"""The benchmark's procedural scenes: a ground plane and icospheres, at four sizes.

Every size has the same layout (a 14 x 14 floor, spheres scattered over it by a seeded generator,
the same camera), only the number and subdivision of the spheres change, so that frame times
across sizes differ by triangle count, not by what is on screen.  Closed spheres are the common
case for shadow volumes (each silhouette edge has multiplicity 2, see `shadowvol.raster.silhouettes`).
"""

from __future__ import annotations

import numpy as np

from shadowvol.primitives import plane, sphere
from shadowvol.scene import (
    Camera,
    DirectionalLight,
    Material,
    PointLight,
    Scene,
    SpotLight,
)

# label -> (spheres, icosphere subdivisions): 20 * 4^s triangles per sphere, plus the floor's 2
SIZES = {
    "1k": (12, 1),     # 962 triangles
    "10k": (8, 3),     # 10,242
    "100k": (20, 4),   # 102,402
    "1M": (48, 5),     # 983,042
}
# Point lights, in the order lights are added (1, 2 or 4 of them).
POINT_LIGHTS = ([2.0, 6.0, 3.0], [-3.0, 5.0, 2.0], [0.5, 7.0, -3.0], [4.0, 4.5, -1.0])
# The peer comparison's lights (pyrender has no point-light shadows): a spot at the first point
# light's position, and a directional light from about the same side.
SPOT = dict(position=[2.0, 6.0, 3.0], direction=[-0.3, -1.0, -0.5], cone_angle=45.0)
DIRECTIONAL = dict(direction=[-0.3, -1.0, -0.4])
CAMERA = Camera(eye=[0.0, 4.0, 9.0], target=[0.0, 0.8, 0.0])


def occluder_scene(size: str, lights: int | str = 1, width: int = 1280,
                   height: int = 720) -> Scene:
    """The scene of `size` (a key of SIZES) with `lights` point lights (1..4), or one "spot" or
    one "directional" light, at `width` x `height`."""
    count, subdivisions = SIZES[size]
    rng = np.random.default_rng(0)
    # keep the total shadowed area about the same at every count: radius ~ 1/sqrt(count)
    scale = float(np.sqrt(20.0 / count))
    balls = [sphere(f"ball{i}",
                    [rng.uniform(-4, 4), rng.uniform(0.6, 2.5), rng.uniform(-4, 3)],
                    rng.uniform(0.3, 0.6) * scale, Material(diffuse=rng.uniform(0.3, 0.9, 3)),
                    subdivisions=subdivisions) for i in range(count)]
    if lights == "spot":
        light_list = [SpotLight(**SPOT)]
    elif lights == "directional":
        light_list = [DirectionalLight(**DIRECTIONAL)]
    else:
        light_list = [PointLight(p) for p in POINT_LIGHTS[:int(lights)]]
    return Scene(camera=CAMERA, objects=[plane("floor", size=[14, 14])] + balls,
                 lights=light_list, width=width, height=height,
                 name=f"occluders-{size}")


def triangle_count(scene: Scene) -> int:
    return sum(len(o.faces) for o in scene.objects)
