"""What a renderer knows of its objects' meshes (`overflow`), each computed once, when first
asked: which are closed and convex, which of those are wound outward, each one's bound on its
own stencil count, and the bound of the casting objects' counts together."""

from __future__ import annotations

from functools import cached_property

import numpy as np

from shadowvol.raster.overflow import detect
from shadowvol.raster.geometry import SceneGeometry


class ObjectFacts:
    """The per-object facts of one `SceneGeometry`'s topologies (see `Renderer`'s properties
    of the same names)."""

    def __init__(self, geometry: SceneGeometry):
        self.geometry = geometry

    @cached_property
    def convex(self) -> np.ndarray:
        """(n_objects,) bool: closed convex meshes (`detect.is_closed_convex`)."""
        return np.array([detect.is_closed_convex(t) for t in self.geometry.topologies], bool)

    @cached_property
    def outward_convex(self) -> np.ndarray:
        """(n_objects,) bool: closed convex meshes wound outward (`overflow.
        convex_orientation`), whose back faces `methods.cullable` may cull."""
        return np.array([detect.convex_orientation(t) == 1
                         for t in self.geometry.topologies], bool)

    @cached_property
    def object_bounds(self) -> np.ndarray:
        """(n_objects,) int64: `detect.topology_bound` of each object, at most how many of
        its triangles one segment can cross (a bound on its own count)."""
        return np.array([2 if convex else len(t.faces)
                         for convex, t in zip(self.convex, self.geometry.topologies)], np.int64)

    @cached_property
    def count_bound(self) -> int:
        """`detect.count_bound` of the casting objects: below 256 no count can wrap."""
        return detect.count_bound(
            t for t, casts in zip(self.geometry.topologies, self.geometry.casts) if casts)
