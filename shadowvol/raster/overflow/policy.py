"""Which hard lights a frame re-checks for stencil overflow (`overflow`), and the light bounds
kept to spare the others.

A light's bound (`detect.light_bound`) costs more than one re-check, so it is computed the
second time the light is used, with twice the slack the camera needs, and kept while later
cameras need no more slack.  An area light's samples are lights of their own here: a sample's
position never changes, so its bound is kept like a point light's.  At most `per_frame` bounds
are computed in one frame (the others are re-checked until their turn comes), so no frame pays
for 16 or 64 samples' bounds at once.
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from shadowvol.raster.overflow import detect
from shadowvol.scene import Camera, hard_lights


class LightBounds:
    """kept : light (`homogeneous` bytes) -> None (used once) or (the slack (M,) it was
    computed with, the bound, the least of that slack in each object (n_objects,))."""

    # the lights kept, the least recently used dropped past it (but never one of this frame):
    # a jittered light is new in every frame, and a batch of 10,000 such frames kept them all
    MAX_LIGHTS = 4096

    def __init__(self):
        self.kept: dict[bytes, tuple | None] = {}
        self._slack: tuple | None = None   # (camera key, `detect.world_slack`)
        self._largest: float | None = None  # max |world corner|: the float32 part of the slack

    def to_check(self, geometry, height: int, convex: Callable[[], np.ndarray],
                 camera: Camera, lights, per_frame: int) -> list[tuple[int, int]]:
        """(light, sample) indices of the hard lights of `lights` (an area light's samples;
        any other light is its own sample 0) whose bound is not known to stay below 256 for
        `camera`.  convex : () -> (n_objects,) bool, asked only when a bound is computed."""
        corners = geometry.soup_corners_f64
        if self._largest is None:
            self._largest = float(np.abs(corners).max())
        # the slack this camera needs: per object from the boxes (8 points each), and per
        # triangle (a pass over every corner) only where that does not settle it
        by_object = detect.object_slack(camera, height, geometry.bounds, self._largest)

        def needed() -> np.ndarray:
            key = (camera.eye.tobytes(), detect.pixel_slack(camera, height))
            if self._slack is None or self._slack[0] != key:   # once per camera
                self._slack = (key, detect.world_slack(camera, height, corners,
                                                         self._largest))
            return self._slack[1]

        def covers(kept) -> bool:   # the kept slack is at least what this camera needs
            return bool((by_object <= kept[2]).all() or (needed() <= kept[0]).all())

        doubled = None   # one (M,) array shared by the bounds computed in this frame
        computed = used = 0
        out = []
        for i, light in enumerate(lights):
            for k, hard in enumerate(hard_lights(light)):
                key = hard.homogeneous.tobytes()
                used += 1
                if key not in self.kept:
                    self.kept[key] = None      # seen once: re-check this frame
                    out.append((i, k))
                    continue
                kept = self.kept[key] = self.kept.pop(key)   # now the most recently used
                if kept is None or not covers(kept):
                    if computed == per_frame:   # later: re-check it meanwhile
                        out.append((i, k))
                        continue
                    computed += 1
                    if doubled is None:
                        doubled = 2.0 * needed()
                        least = np.full(len(geometry.ranges), np.inf)
                        np.minimum.at(least, geometry.object_of, doubled)
                    kept = (doubled, detect.light_bound(corners, geometry.object_of,
                                                          convex(), hard.homogeneous,
                                                          doubled), least)
                    self.kept[key] = kept
                if kept[1] >= detect.STENCIL_LIMIT:
                    out.append((i, k))
        if len(self.kept) > max(self.MAX_LIGHTS, used):
            for key in list(self.kept)[:len(self.kept) - max(self.MAX_LIGHTS, used)]:
                del self.kept[key]   # the least recently used first
        return out
