"""The memory `Renderer.render` takes for a frame, and its files (`shadowvol.memory`): the
rasterizer's own estimate, from its own numbers (`target.BYTES_PER_PIXEL`,
`target.LIGHTS_PER_PAGE`), GL-free to compute (no context is made)."""

from __future__ import annotations

import math

from shadowvol import memory
from shadowvol.frame import FIELDS, GROUND_TRUTH, LAYERS, caster_words
from shadowvol.raster.target import BYTES_PER_PIXEL, LIGHTS_PER_PAGE, SURFACE_BYTES_PER_PIXEL
from shadowvol.scene import Scene, hard_lights


def render(scene: Scene, outputs=("image", "lit", "coverage"), *, gl_in_host: bool = True,
           written=("png",), stencil: bool = False, volumes: bool = False) -> memory.Estimate:
    """`Renderer.render` of `scene` and the files `written` ("png", "exr", "png16", "masks",
    "stencil", "volumes").  `gl_in_host`: the GL keeps its frame in this process's memory (a
    software renderer, `shadowvol.memory.SOFTWARE_GL`)."""
    L = len(scene.lights)
    samples = sum(len(hard_lights(lt)) for lt in scene.lights)
    pages = max(1, math.ceil(samples / LIGHTS_PER_PAGE))
    outputs = set(outputs)
    t = {"GL frame" + ("" if gl_in_host else " (GPU)"): BYTES_PER_PIXEL * gl_in_host,
         # target: RGBA and RGB float32, bits float32 and uint32 read-back staging, allocated
         # once
         "read-back staging": 16 + 12 + 4 + 4,
         "lit bits (uint32 per page)": 4 * pages,
         "coverage": (4 + 1) if "coverage" in outputs or "lit" in outputs else 0,
         "image float32": 12 if "image" in outputs else 0,
         # lit_count uint16 and lit bool per light, one bool mask and one uint32 temporary
         "lit_count + lit": (3 * L + 1 + 4) if "lit" in outputs else 0,
         "image_srgb": 6 if "image_srgb" in outputs else 0}
    truth = outputs & set(GROUND_TRUTH)
    K = caster_words(len(scene.objects))
    if truth:
        # depth read (float32), its float64 quotient and the depth, the covered mask
        t["depth"] = 4 + 8 + 4 + 1
        if "distance" in truth:
            t["distance"] = 8 + 4 + 4      # ray lengths float64, the product, the float32
        if truth & {"normal", "object_id", "casters"}:
            # G-buffer read RGBA32F, the key int64 (where + astype), triangle, front, the
            # per-pixel triangle index, then normal float32 x3 and its float64 rows
            t["surface read"] = 16 + 8 + 8 + 8 + 1 + 8
            t["normal"] = (12 + 24) if "normal" in truth else 0
            t["object_id"] = (2 + 8) if "object_id" in truth else 0
        if truth & {"facing", "facing_count", "casters"}:
            # the counts (uint16) and their bools, a sample's unmasked bits
            t["facing + its lit"] = 2 * L + 2 * L + 2 * L + 8
        if "casters" in truth:
            t["casters"] = 8 * L * K + 16 * K   # the result, a sample's words and their OR
    if stencil:
        t["stencil counts"] = 4 * L + 4
    if volumes:
        # its frame's image, the RGBA read (a copy of the staging), its RGB copy
        t["volume view"] = 12 + 16 + 12
    t |= memory.written(written, L, truth, float64=False, stencil=stencil, words=K)
    asked_layers = outputs & set(LAYERS)
    if asked_layers:   # `layers`: the arrays, their float32 copies and the mask file's bytes,
        # a frame's image, and a twin renderer's frame (one twin at a time)
        each = sum(12 * (L if FIELDS[n].dims[0] == "L" else 1) for n in asked_layers)
        t["intrinsic layers"] = each * (3 if "masks" in written else 2) + 12
        if asked_layers & {"direct", "direct_shadowed", "albedo"}:
            t["twin renderer's frame"] = BYTES_PER_PIXEL * gl_in_host
    if memory.surfaced(scene):
        t["G-buffer UVs and colours"] = SURFACE_BYTES_PER_PIXEL * gl_in_host
    # the texels: the model's sRGB codes (3 B), the upload's RGBA copy of one texture at a
    # time (4 B) and the storage buffer (4 B, in this process on a software GL)
    fixed = {"textures": memory.texels(scene) * (3 + 4 + 4 * gl_in_host)}
    return memory.Estimate("the rasterizer", scene.width, scene.height,
                           memory.terms(scene.width * scene.height, t, fixed))
