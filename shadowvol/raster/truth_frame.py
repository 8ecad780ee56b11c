"""A frame's ground truth assembled from what its passes left in the target (see `truth`)."""

from __future__ import annotations

import numpy as np

from shadowvol import fields
from shadowvol.raster import truth
from shadowvol.raster.plan import FramePlan
from shadowvol.scene import Camera


def frame_truth(renderer, plan: FramePlan, camera: Camera, lights, truth_pages, zfail, vols,
                clip) -> dict[str, np.ndarray]:
    """The ground-truth outputs of `plan` (and the facing pass's lit, as "lit"), read from the
    frame `renderer` left in its target.  truth_pages : the facing pass's (lit, facing) bits
    per page; zfail : (L, n_objects) bool, the casters counted with z-fail."""
    out: dict[str, np.ndarray] = {}
    want = set(plan.outputs) & set(fields.GROUND_TRUTH)
    if not want:
        return out
    target, geometry = renderer.target, renderer.geometry
    h, w = renderer.scene.height, renderer.scene.width
    # the depth buffer is cleared every frame: it says where geometry is (the G-buffer and
    # the facing pass's targets are written only there)
    stored = truth.read_depth(target)
    covered = stored > 0
    if want & {"depth", "distance"}:
        depth = truth.eye_depth(stored, camera)
        if "depth" in want:
            out["depth"] = depth
        if "distance" in want:
            out["distance"] = (depth * truth.ray_lengths(camera, w, h)).astype(np.float32)
    if want & {"normal", "object_id"}:
        triangle, front, _ = truth.read_surface(target, covered)
        triangle = geometry.triangle_of_key(triangle)   # a piece's key: its triangle
        out |= truth.surface_outputs(geometry, triangle, front, want)
    if "facing" in want:
        out["lit"], out["facing"] = _facing(truth_pages, len(lights), h, w, covered)
    if "casters" in want:
        casters = np.zeros((len(lights), h, w), np.uint64)
        for i, light in enumerate(lights):
            cast = out["facing"][i] & ~out["lit"][i]
            if not cast.any():
                continue
            light4 = light.homogeneous
            candidates = truth.caster_candidates(geometry.bounds,
                                                 truth.cast_points(camera, stored, cast),
                                                 light4)
            vols.prepare(light4)
            truth.count_casters(
                target, renderer._truth_pass().casters, vols, zfail[i],
                candidates, renderer.object_bounds,
                out["facing"][i], halve=plan.halve, clip_planes=clip, out=casters[i])
        out["casters"] = casters
    return out


def _facing(truth_pages, lights: int, h: int, w: int, covered: np.ndarray
            ) -> tuple[np.ndarray, np.ndarray]:
    """lit, facing (L, H, W) bool from the facing pass's bits, covered pixels only."""
    lit = np.zeros((lights, h, w), bool)
    facing = np.zeros((lights, h, w), bool)
    for i in range(lights):
        page, bit = divmod(i, truth.LIGHTS_PER_PASS)
        lit_bits, facing_bits = truth_pages[page]
        np.not_equal(lit_bits & np.uint32(1 << bit), 0, out=lit[i])
        np.not_equal(facing_bits & np.uint32(1 << bit), 0, out=facing[i])
    return lit & covered, facing & covered
