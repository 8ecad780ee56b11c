"""The memory the witness takes for an image (`shadowvol.memory`): `raytrace.shadow_masks`,
`ground_truth` and `soft_masks`, and `raytrace masks` writing them, from the masks' own tile
(`raytrace.masks.MASK_TILE_RAYS`)."""

from __future__ import annotations

from shadowvol import memory
from shadowvol.frame import caster_words
from shadowvol.scene import Scene, hard_lights

from .masks import MASK_TILE_RAYS

# the bytes one ray's tile arrays take at their peak, the masks alone (the hit records, the
# shadow-ray arrays of a tile): `raytrace masks` on cage.toml 1024 wide, 512 to 2,048 rows,
# grows 18-21 B a pixel, and what is left at 1024 x 1024 (its tiles on 2 threads) is ~100 B a
# ray with Embree's packets, ~160 with single rays (tests/scene/test_memory_model.py; the
# 512 used before left the model 3.3x the measured growth); rounded up
MASK_RAY_BYTES = 256
# and with the ground truth's outputs (their per-ray fields too: the model of `--outputs all`
# at 1024 x 1024 is 250 MiB with 256 B a ray, below the 266 measured; 282 with 512)
TRUTH_RAY_BYTES = 512


def tiles_in_flight(width: int, truth: bool = False) -> int:
    """The masks' tiles in flight (`truth`: with ground-truth outputs): one per thread, each
    at least one row of the image."""
    return memory.tiles(width, MASK_TILE_RAYS, TRUTH_RAY_BYTES if truth else MASK_RAY_BYTES,
                        memory.threads())


def masks(scene: Scene, outputs=(), picture: bool = True, exact: int = 0) -> memory.Estimate:
    """`raytrace.shadow_masks` / `ground_truth` / `soft_masks` of `scene` and `raytrace masks`
    writing them (the .npz and, with `picture`, its PNG); `exact`: how many of the float64
    (L, H, W) exact-visibility outputs (`raytrace.exact_soft`) come too."""
    L = len(scene.lights)
    K = caster_words(len(scene.objects))
    truth = set(outputs)
    per = {"lit + coverage": L + 1,
           "ground truth": (sum(memory.field_bytes(name, L, K) for name in truth)
                            + (L + 1) * bool(truth)),
           # soft lights: lit_count uint16 and facing per light
           "lit_count": 3 * L if any(len(hard_lights(lt)) > 1 for lt in scene.lights) else 0,
           # both computed at once (float64), those asked for written (npz: twice, compressed)
           "exact visibility": (16 + 2 * 1.01 * 8 * exact) * L if exact else 0,
           # one RGB uint8 panel per light (and per output), the joined picture, its PNG;
           # the outputs' heat maps colour one panel at a time in float64
           "picture": ((L + len(truth)) * 3 * 2 + 24 * bool(truth) + memory.PNG)
           if picture else 0}
    per |= memory.written(("masks",), L, truth, float64=False, words=K)
    fixed = {"tiles in flight": tiles_in_flight(scene.width, bool(truth))}
    return memory.Estimate("the ray tracer's masks", scene.width, scene.height,
                           memory.terms(scene.width * scene.height, per, fixed))
