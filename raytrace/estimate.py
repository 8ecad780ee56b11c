"""The memory the witness takes for an image (`shadowvol.memory`): `raytrace.shadow_masks`,
`ground_truth` and `soft_masks`, and `raytrace masks` writing them, from the masks' own tile
(`raytrace.masks.MASK_TILE_RAYS`)."""

from __future__ import annotations

from shadowvol import memory
from shadowvol.frame import caster_words
from shadowvol.scene import Scene, hard_lights

from .masks import MASK_TILE_RAYS

# the bytes one ray's tile arrays take at their peak (the hit records, the shadow-ray arrays of
# a tile, a few dozen float64 values a ray): a bound from the measured growth less the
# per-pixel terms (100-400 B a ray), rounded up
MASK_RAY_BYTES = 512


def tiles_in_flight(width: int) -> int:
    """The masks' tiles in flight: one per thread, each at least one row of the image."""
    return memory.tiles(width, MASK_TILE_RAYS, MASK_RAY_BYTES, memory.threads())


def masks(scene: Scene, outputs=(), picture: bool = True) -> memory.Estimate:
    """`raytrace.shadow_masks` / `ground_truth` / `soft_masks` of `scene` and `raytrace masks`
    writing them (the .npz and, with `picture`, its PNG)."""
    L = len(scene.lights)
    K = caster_words(len(scene.objects))
    truth = set(outputs)
    per = {"lit + coverage": L + 1,
           "ground truth": (sum(memory.field_bytes(name, L, K) for name in truth)
                            + (L + 1) * bool(truth)),
           # soft lights: lit_count uint16 and facing per light
           "lit_count": 3 * L if any(len(hard_lights(lt)) > 1 for lt in scene.lights) else 0,
           # one RGB uint8 panel per light (and per output), the joined picture, its PNG;
           # the outputs' heat maps colour one panel at a time in float64
           "picture": ((L + len(truth)) * 3 * 2 + 24 * bool(truth) + memory.PNG)
           if picture else 0}
    per |= memory.written(("masks",), L, truth, float64=False, words=K)
    fixed = {"tiles in flight": tiles_in_flight(scene.width)}
    return memory.Estimate("the ray tracer's masks", scene.width, scene.height,
                           memory.terms(scene.width * scene.height, per, fixed))
