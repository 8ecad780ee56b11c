"""The shadow switches in the masks and the ground truth (docs/CONVENTIONS.md, "Shadow
switches"): an object's `cast_shadows` and `receive_shadows`, a light's `shadows`.

A scene that switches no object off is traced as before, through its own backend.  One that
does is traced through `Switched`: the primary rays see every triangle, the shadow rays only
the casting objects' triangles (a backend of their own, in the same frame), with triangle ids
in and out always the scene's, so the masks' exclusion of the visible triangle by id and their
retries on slivers work unchanged.  The margins stay the whole scene's (`tolerances`), so that
switching an object off changes a pixel only where that object blocked it.  Receivers and
lights are switched on the segments (`receiving`): a pixel whose object receives no shadow, or
a light that casts none, keeps its facing test and traces no shadow ray, so it is lit exactly
where it faces the light, and blocked by nothing (no `casters` bit).
"""

from __future__ import annotations

import numpy as np

from shadowvol.scene import Scene

from .backends import Hits, NumpyBackend, TriangleBackend, make_backend


def casting(scene: Scene) -> np.ndarray:
    """(n_objects,) bool: the objects that cast shadows."""
    return np.array([o.cast_shadows for o in scene.objects], bool)


def receiving_objects(scene: Scene) -> np.ndarray:
    """(n_objects,) bool: the objects that receive shadows."""
    return np.array([o.receive_shadows for o in scene.objects], bool)


class Switched:
    """A backend over all of a scene's triangles (`full`) whose shadow queries (`occluded`,
    `first_hit`, `occluded_leaving`) see only the casting objects' triangles; everything else
    (primary rays, normals, planes, threads) is `full`'s.  Triangle ids are the scene's.

    receives : (M,) bool, per scene triangle: its object receives shadows."""

    def __init__(self, full: TriangleBackend, casters: TriangleBackend | None,
                 scene_of: np.ndarray, receives: np.ndarray):
        self._full = full
        self._casters = casters   # None: no object casts
        self._scene_of = scene_of   # (C,) int64: the scene id of each caster triangle
        self._caster_of = np.full(len(receives) + 1, -1, np.int64)   # [-1] -> -1
        self._caster_of[scene_of] = np.arange(len(scene_of))
        self.receives = receives

    def __getattr__(self, name):
        return getattr(self._full, name)

    def occluded(self, origins, directions, tmax=None, parallel=True) -> np.ndarray:
        if self._casters is None:
            return np.zeros(len(origins), bool)
        return self._casters.occluded(origins, directions, tmax, parallel=parallel)

    def first_hit(self, origins, directions, tmax=None) -> Hits:
        if self._casters is None:
            return Hits(np.full(len(origins), np.inf, np.float32),
                        np.full(len(origins), -1, np.int64))
        hits = self._casters.first_hit(origins, directions, tmax)
        return Hits(hits.t, np.where(hits.tri >= 0, self._scene_of[hits.tri], -1))

    def occluded_leaving(self, origins, directions, tmax, own) -> np.ndarray:
        if self._casters is None:
            return np.zeros(len(origins), bool)
        return self._casters.occluded_leaving(origins, directions, tmax,
                                              self._caster_of[np.asarray(own, np.int64)])


def backend_kind(tracer) -> str:
    """"numpy" or "embree": the kind of `tracer`, switched or not."""
    full = tracer._full if isinstance(tracer, Switched) else tracer
    return "numpy" if isinstance(full, NumpyBackend) else "embree"


def switched_backend(scene: Scene, tracer: TriangleBackend, origin: np.ndarray
                     ) -> TriangleBackend:
    """`tracer` (the scene's triangles minus `origin`) itself when every object casts and
    receives shadows, else a `Switched` over it with a backend of the same kind for the
    casting objects' triangles."""
    casts, receives = casting(scene), receiving_objects(scene)
    if casts.all() and receives.all():
        return tracer
    _, _, ids = scene.triangles()
    scene_of = np.flatnonzero(casts[ids]).astype(np.int64)
    casters = None
    if len(scene_of):
        casters = (tracer if casts.all() else make_backend(
            backend_kind(tracer), tracer.vertices, tracer.faces[scene_of]))
    return Switched(tracer, casters, scene_of, receives[ids])


def receiving(tracer, light, seg, hit):
    """The shadow segments `seg` (`masks._Segments`) of the hits `hit` toward the hard light
    `light`, less those of pixels whose object receives no shadow and all of them when the
    light casts none: those pixels stay lit where they face the light.  `seg` itself when
    nothing is switched off."""
    receives = tracer.receives if isinstance(tracer, Switched) else None
    if light.shadows and receives is None:
        return seg
    if not light.shadows:
        keep, keep_near = np.zeros(len(seg.rays), bool), np.zeros(len(seg.near.rays), bool)
    else:
        keep, keep_near = receives[hit.tri[seg.rays]], receives[hit.tri[seg.near.rays]]
    direction = seg.direction if seg.direction.shape[1] == 1 else seg.direction[:, keep]
    return seg._replace(rays=seg.rays[keep], start=seg.start[:, keep], direction=direction,
                        tmax=None if seg.tmax is None else seg.tmax[keep],
                        near=seg.near.where(keep_near))
