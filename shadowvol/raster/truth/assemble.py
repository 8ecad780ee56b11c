"""A frame's ground truth assembled from what its passes left in the target (see `truth`).

An area light is its samples, each a hard light of the frame's pages: its facing and lit
bits add up into `facing_count` and `lit_count`, its samples' casters OR.
"""

from __future__ import annotations

import numpy as np

from shadowvol import frame
from shadowvol.raster import methods
from shadowvol.raster.truth import truth_pass
from shadowvol.raster.plan import FramePlan
from shadowvol.raster.truth.plane_depth import plane_depths
from shadowvol.scene import Camera


def frame_truth(renderer, plan: FramePlan, camera: Camera, lights, hard, truth_pages, vols,
                clip) -> dict[str, np.ndarray]:
    """The ground-truth outputs of `plan` (and the facing pass's lit and lit_count, as "lit"
    and "lit_count"), read from the frame `renderer` left in its target.  hard : the frame's
    (light index, hard light) pairs, in the pages' order; truth_pages : the facing pass's
    (lit, facing) bits per page."""
    out: dict[str, np.ndarray] = {}
    want = set(plan.outputs) & set(frame.GROUND_TRUTH)
    if not want:
        return out
    target, geometry = renderer.target, renderer.geometry
    h, w = renderer.scene.height, renderer.scene.width
    # the depth buffer is cleared every frame: it says where geometry is (the G-buffer and
    # the facing pass's targets are written only there)
    stored = truth_pass.read_depth(target)
    covered = stored > 0
    if want & {"depth", "distance", "normal", "object_id"}:
        triangle, front, _ = truth_pass.read_surface(target, covered)
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
        samples = np.array([sum(1 for i, _ in hard if i == k) for k in range(len(lights))],
                           np.int64)
        lit_count = np.zeros((len(lights), h, w), np.uint16)
        facing_count = np.zeros((len(lights), h, w), np.uint16)
        casters = (np.zeros(frame.shape("casters", len(lights), h, w,
                                         objects=len(renderer.scene.objects)), np.uint64)
                   if "casters" in want else None)
        receiving = covered   # casters are named where the visible object receives shadows
        if casters is not None and not geometry.receives.all():
            seen = np.maximum(geometry.triangle_of_key(truth_pass.read_surface(target, covered)[0]), 0)
            receiving = covered & geometry.receives[geometry.triangle_objects[seen]]
        for k, (i, light) in enumerate(hard):
            lit, facing = _sample_bits(truth_pages, k, covered)
            lit_count[i] += lit
            facing_count[i] += facing
            if casters is not None:
                _sample_casters(renderer, plan, camera, stored, light, lit, facing & receiving,
                                vols, clip, casters[i])
        out["lit_count"], out["lit"] = lit_count, lit_count == samples[:, None, None]
        out["facing_count"], out["facing"] = facing_count, facing_count > 0
        if casters is not None:
            out["casters"] = casters
    return out


def _sample_casters(renderer, plan: FramePlan, camera: Camera, stored: np.ndarray, light,
                    lit: np.ndarray, facing: np.ndarray, vols, clip, into: np.ndarray) -> None:
    """ORs hard light `light`'s casters into `into` (H, W, K) uint64 where it faces the
    pixel and is blocked: its own counts, under the method the frame counted it with."""
    cast = facing & ~lit
    if not cast.any():
        return
    geometry = renderer.geometry
    light4 = light.homogeneous
    choice = methods.choose(plan.method, geometry.bounds, camera, renderer.scene.size,
                            light4, geometry.extent)
    candidates = [j for j in truth_pass.caster_candidates(
        geometry.bounds, truth_pass.cast_points(camera, stored, cast), light4) if geometry.casts[j]]
    vols.prepare(light4)
    bits = truth_pass.count_casters(renderer.target, renderer._truth_pass().casters, vols, choice,
                               candidates, renderer.object_bounds, facing, halve=plan.halve,
                               clip_planes=clip)
    np.bitwise_or(into, bits, out=into)


def _sample_bits(truth_pages, k: int, covered: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """lit, facing (H, W) bool of the frame's hard light k from the facing pass's bits,
    covered pixels only."""
    page, bit = divmod(k, truth_pass.LIGHTS_PER_PASS)
    lit_bits, facing_bits = truth_pages[page]
    lit = (lit_bits & np.uint32(1 << bit)) != 0
    facing = (facing_bits & np.uint32(1 << bit)) != 0
    return lit & covered, facing & covered
