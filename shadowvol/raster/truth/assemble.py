"""A frame's ground truth assembled from what its passes left in the target (see `truth`).

An area light is its samples, each a hard light of the frame's pages: its facing and lit
bits add up into `facing_count` and `lit_count`, its samples' casters OR.
"""

from __future__ import annotations

import numpy as np

from shadowvol import frame
from shadowvol.raster.truth import truth_pass
from shadowvol.raster.truth.plane_depth import plane_depths


def frame_truth(pipe, state, truth_pages, counters, object_bounds) -> dict[str, np.ndarray]:
    """The ground-truth outputs of the frame `state` (a `pipeline.FrameState`; with the facing
    pass's lit and lit_count, as "lit" and "lit_count"), read from what its passes left in
    `pipe.target`.  truth_pages : the facing pass's (lit, facing) bits per page; counters :
    a callable giving the per-caster counters (`truth_pass.CasterCounts`, made on first use);
    object_bounds : a callable giving each object's count bound (for the counters' fields)."""
    out: dict[str, np.ndarray] = {}
    want = set(state.plan.outputs) & set(frame.GROUND_TRUTH)
    if not want:
        return out
    target, geometry, camera = pipe.target, pipe.geometry, state.camera
    h, w = target.height, target.width
    # the depth buffer is cleared every frame: it says where geometry is (the G-buffer and
    # the facing pass's targets are written only there)
    stored = truth_pass.read_depth(target)
    covered = stored > 0
    if want & {"depth", "distance", "normal", "object_id"}:
        triangle, front = truth_pass.read_surface(target, covered)
        triangle = geometry.triangle_of_key(triangle)   # a piece's key: its triangle
    if want & {"depth", "distance"}:
        # exact: the pixel's ray met with its triangle's plane (`plane_depth`), the depth
        # buffer's near / d only where that plane gives none
        depth = plane_depths(geometry, camera, triangle, truth_pass.eye_depth(stored, camera))
        if "depth" in want:
            out["depth"] = depth
        if "distance" in want:
            out["distance"] = (depth * truth_pass.ray_lengths(camera, w, h)).astype(np.float32)
    if want & {"normal", "object_id"}:
        out |= truth_pass.surface_outputs(geometry, triangle, front, want)
    if "facing" in want:
        samples, lights = state.samples, state.lights
        lit_count = np.zeros((len(lights), h, w), np.uint16)
        facing_count = np.zeros((len(lights), h, w), np.uint16)
        casters = (np.zeros(frame.shape("casters", len(lights), h, w,
                                         objects=len(pipe.scene.objects)), np.uint64)
                   if "casters" in want else None)
        receiving = covered   # casters are named where the visible object receives shadows
        if casters is not None and not geometry.receives.all():
            seen = np.maximum(geometry.triangle_of_key(
                truth_pass.read_surface(target, covered)[0]), 0)
            receiving = covered & geometry.receives[geometry.triangle_objects[seen]]
        for k, hard in enumerate(state.hard):
            lit, facing = _sample_bits(truth_pages, k, covered)
            lit_count[hard.index] += lit
            facing_count[hard.index] += facing
            if casters is not None:
                _sample_casters(pipe, state, hard, stored, lit, facing & receiving, counters,
                                object_bounds, casters[hard.index])
        out["lit_count"], out["lit"] = lit_count, lit_count == samples[:, None, None]
        out["facing_count"], out["facing"] = facing_count, facing_count > 0
        if casters is not None:
            out["casters"] = casters
    return out


def _sample_casters(pipe, state, hard, stored: np.ndarray, lit: np.ndarray,
                    facing: np.ndarray, counters, object_bounds, into: np.ndarray) -> None:
    """ORs hard light `hard`'s casters into `into` (H, W, K) uint64 where it faces the pixel
    and is blocked: its own counts, under the method the frame counted it with."""
    cast = facing & ~lit
    if not cast.any():
        return
    geometry = pipe.geometry
    candidates = [j for j in truth_pass.caster_candidates(
        geometry.bounds, truth_pass.cast_points(state.camera, stored, cast), hard.light4)
        if geometry.casts[j]]
    pipe.volumes.prepare(hard.light4)
    bits = truth_pass.count_casters(pipe, counters(), hard.zfail, candidates, object_bounds(),
                                    facing, halve=state.plan.halve, clip_planes=state.clip)
    np.bitwise_or(into, bits, out=into)


def _sample_bits(truth_pages, k: int, covered: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """lit, facing (H, W) bool of the frame's hard light k from the facing pass's bits,
    covered pixels only."""
    page, bit = divmod(k, truth_pass.LIGHTS_PER_PASS)
    lit_bits, facing_bits = truth_pages[page]
    lit = (lit_bits & np.uint32(1 << bit)) != 0
    facing = (facing_bits & np.uint32(1 << bit)) != 0
    return lit & covered, facing & covered
