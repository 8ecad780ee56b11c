"""The process of `shadowvol course render`: the Whitted tracer driven by a student's
ray-sphere intersection and shadow test.

    python -m shadowvol.course.render_runner < job.json

The job (JSON on stdin): {"workspace", "scene" (a scene file), "width", "height", "out" (an
.npy path)}.  The tracer (`raytrace.outlook.whitted`) is the project's; in this process only, its
spheres are met by the student's `ray_sphere.intersect` and its shadow rays ask the student's
`shadow_ray.in_shadow` about the spheres (planes and meshes stay the tracer's).  A function
that is missing, raises NotImplementedError or fails on a first test call is left to the
tracer, and a line on stdout says so.  The grader's time limit applies (`course render
--timeout`): this runs in its own process for that.
"""

from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import numpy as np

from raytrace.outlook import whitted
from shadowvol.scene import Sphere
from shadowvol.scenefile import load_scene

# The shadow ray of a directional light runs to a point this far along its direction.
FAR_AWAY = 1e6


def _student(workspace: Path, module: str, function: str, probe: tuple):
    """The student's function, or None (with the reason) when it cannot be used."""
    path = workspace / f"{module}.py"
    if not path.is_file():
        return None, f"{module}.py is missing"
    try:
        spec = importlib.util.spec_from_file_location(f"student_{module}", path)
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        fn = getattr(mod, function)
        fn(*probe)
    except NotImplementedError:
        return None, f"{module}.{function} is not written yet"
    except Exception as exc:  # noqa: BLE001 - the student's, whatever it raises
        return None, f"{module}.{function} fails ({type(exc).__name__}: {exc})"
    return fn, None


def _lambda(value) -> float:
    return np.inf if value is None else float(value)


def install(intersect, in_shadow) -> None:
    """Patch the tracer, in this process: `intersect` for every ray-sphere test, `in_shadow`
    for the spheres on every shadow ray (either may be None: the tracer's stays)."""
    if intersect is not None:
        def ray_sphere(o, d, center, radius, t_min=0.0):
            c, r = [float(x) for x in center], float(radius)
            lam = np.array([_lambda(intersect(a.tolist(), b.tolist(), c, r))
                            for a, b in zip(o, d)])
            return np.where(lam > t_min, lam, np.inf)
        whitted.ray_sphere = ray_sphere
    if in_shadow is not None:
        original = whitted.World.occluded

        def occluded(self, o, d, tmax):
            spheres = [(shape.center.tolist(), float(shape.radius))
                       for _, shape in self.analytic if isinstance(shape, Sphere)]
            kept = self.analytic
            self.analytic = [(i, s) for i, s in kept if not isinstance(s, Sphere)]
            try:
                blocked = original(self, o, d, tmax)
            finally:
                self.analytic = kept
            reach = FAR_AWAY if tmax is None else tmax
            for k in np.flatnonzero(~blocked):
                to = d[k] / np.linalg.norm(d[k])
                blocked[k] = bool(in_shadow(o[k].tolist(), to.tolist(),
                                            (o[k] + reach * d[k]).tolist(), spheres))
            return blocked
        whitted.World.occluded = occluded


def main() -> int:
    job = json.load(sys.stdin)
    workspace = Path(job["workspace"])
    intersect, why_i = _student(workspace, "ray_sphere", "intersect",
                                ((0.0, 0.0, -5.0), (0.0, 0.0, 1.0), (0.0, 0.0, 0.0), 1.0))
    in_shadow, why_s = _student(workspace, "shadow_ray", "in_shadow",
                                ((0.0, 1.0, 0.0), (0.0, 1.0, 0.0), (0.0, 5.0, 0.0),
                                 [((0.0, 0.0, 0.0), 1.0)]))
    for why in (why_i, why_s):
        if why:
            print(f"note: {why}: the tracer's own is used")
    install(intersect, in_shadow)
    scene = load_scene(job["scene"]).replace(width=job["width"], height=job["height"])
    image = whitted.render(scene, progress=False)
    np.save(job["out"], image)
    return 0


if __name__ == "__main__":
    sys.exit(main())
