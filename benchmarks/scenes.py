"""The benchmark's procedural scenes: a ground plane and icospheres, at four sizes.

Every size has the same layout (a 14 x 14 floor, spheres scattered over it by a seeded generator,
the same camera), only the number and subdivision of the spheres change, so that frame times
across sizes differ by triangle count, not by what is on screen.  Closed spheres are the common
case for shadow volumes (each silhouette edge has multiplicity 2, see
`shadowvol.raster.volumes.silhouettes`).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from shadowvol import Camera, DirectionalLight, Material, PointLight, Scene, SpotLight
from shadowvol.primitives import Transform, mesh, plane, sphere

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
                   height: int = 720, spheres: int | None = None) -> Scene:
    """The scene of `size` (a key of SIZES) with `lights` point lights (1..4), or one "spot" or
    one "directional" light, at `width` x `height`.  `spheres`: only the first that many of
    the size's spheres (the same places and sizes; named `occluders-SIZE-SPHERES`)."""
    count, subdivisions = SIZES[size]
    kept = count if spheres is None else spheres
    if not 0 <= kept <= count:
        raise ValueError(f"spheres must be 0..{count} for size {size!r}, got {spheres}")
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
    return Scene(camera=CAMERA, objects=[plane("floor", size=[14, 14])] + balls[:kept],
                 lights=light_list, width=width, height=height,
                 name=f"occluders-{size}" + ("" if spheres is None else f"-{spheres}"))


def many_casters_scene(count: int, width: int = 64, height: int = 48) -> Scene:
    """A floor and `count` small seeded icosahedra (20 triangles each, closed: every one a
    caster) under the benchmark camera, one point light: a frame's cost per object."""
    rng = np.random.default_rng(count)
    balls = [sphere(f"ball{i}", [rng.uniform(-4, 4), rng.uniform(0.6, 2.5),
                                 rng.uniform(-4, 3)], 0.1, Material(), subdivisions=0)
             for i in range(count)]
    return Scene(camera=CAMERA, objects=[plane("floor", size=[14, 14])] + balls,
                 lights=[PointLight(POINT_LIGHTS[0])], width=width, height=height,
                 name=f"casters-{count}")


def triangle_count(scene: Scene) -> int:
    return sum(len(o.faces) for o in scene.objects)


# ---------------------------------------------------------------------------------------------
# The shared meshes (../shared/models beside the checkout, or beside its parent for a nested
# worktree): the overflow check's real meshes and the turntable
# ---------------------------------------------------------------------------------------------

def models_dir() -> Path | None:
    root = Path(__file__).resolve().parents[1]
    for base in (root.parent, root.parent.parent):
        if (base / "shared" / "models" / "bunny.obj").is_file():
            return base / "shared" / "models"
    return None


MESHES = ("bunny", "teapot", "spot", "suzanne", "lampshade")


def read_obj(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """The shared models' plain OBJ (`v x y z`, `f a b c`, 1-based): vertices (n, 3) float64,
    faces (m, 3) int64."""
    v, f = [], []
    for line in path.read_text().splitlines():
        if line.startswith("v "):
            v.append([float(x) for x in line.split()[1:4]])
        elif line.startswith("f "):
            f.append([int(x.split("/")[0]) - 1 for x in line.split()[1:4]])
    return np.array(v), np.array(f, np.int64)


def _placed(name: str, height: float, at, material: Material):
    v, f = read_obj(models_dir() / f"{name}.obj")
    scale = height / float(np.ptp(v[:, 1]))
    lo, hi = v.min(axis=0) * scale, v.max(axis=0) * scale
    offset = np.array([at[0] - (lo[0] + hi[0]) / 2, -lo[1], at[1] - (lo[2] + hi[2]) / 2])
    return mesh(name, v, f, material, Transform(scale=scale, translation=offset))


def model_scene(name: str, width: int = 1280, height: int = 720) -> Scene:
    """One shared mesh, about 1.5 units tall, on a 6 x 6 floor, one point light."""
    obj = _placed(name, 1.5, (0.0, 0.0), Material(diffuse=[0.8, 0.7, 0.6]))
    return Scene(camera=Camera(eye=[0.8, 1.6, 3.6], target=[0.0, 0.65, 0.0], fov_y=40.0),
                 objects=(plane("floor", size=[6.0, 6.0]), obj),
                 lights=(PointLight([-2.0, 4.0, 2.5]),), width=width, height=height,
                 name=f"model-{name}")


def turntable_scene(width: int = 640, height: int = 480) -> Scene:
    """The five shared meshes on a floor, three point lights (the turntable's scene)."""
    spots = [(-1.6, 0.0), (1.6, 0.0), (0.0, -1.6), (0.0, 1.6), (0.0, 0.0)]
    rng = np.random.default_rng(1)
    objects = [plane("floor", size=[8.0, 8.0])]
    for name, at in zip(MESHES, spots):
        objects.append(_placed(name, 1.0, at, Material(diffuse=rng.uniform(0.4, 0.9, 3))))
    lights = [PointLight([-3.0, 5.0, 2.0], intensity=0.6), PointLight([3.0, 4.0, 3.0],
                                                                      intensity=0.5),
              PointLight([0.5, 6.0, -3.0], intensity=0.4)]
    return Scene(camera=turntable_cameras(1)[0], objects=objects, lights=lights, width=width,
                 height=height, name="turntable")


def turntable_cameras(views: int = 36) -> list[Camera]:
    """`views` cameras on a circle around the turntable scene, every 360 / views degrees."""
    out = []
    for k in range(views):
        a = 2 * np.pi * k / views
        out.append(Camera(eye=[5.0 * np.sin(a), 3.0, 5.0 * np.cos(a)], target=[0.0, 0.4, 0.0],
                          fov_y=45.0))
    return out
