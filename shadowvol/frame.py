"""The frame a renderer makes, as a type (docs/CONVENTIONS.md), GL-free, numpy only: every
field declared once (`FIELDS`: name, dtype, shape, the light kinds that have it, when a mask
file holds it), the base class both renderers' results subclass (`Frame`), the one check of
the outputs asked for (`check_outputs`) and what a mask file holds (`mask_file`).  The bytes
are `shadowvol.io`'s.

Every ground-truth field is defined for every light kind: an area light is its N samples, each
a hard light, and its per-light fields reduce theirs (counts add, `casters` ORs).
"""

# No `from __future__ import annotations`: the subclasses' documentation (pdoc) reads the
# fields' types as objects, not as names to look up in the subclasses' modules.
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from shadowvol import io
from shadowvol.cameras import Calibration
from shadowvol.errors import out_of_memory_while
from shadowvol.scene import AreaLight, SceneError, shorten

__all__ = ["CASTER_WORD_BITS", "EXACT_OUTPUTS", "FIELDS", "Field", "Frame", "GROUND_TRUTH",
           "LAYERS", "MASK_ARRAYS", "MAX_OBJECT_IDS", "blank", "caster_words", "check_light_kinds",
           "check_object_ids", "check_outputs", "decode_casters", "layer_exrs", "mask_file",
           "masks_bytes", "save_masks", "shape", "soft_arrays"]

CASTER_WORD_BITS = 64     # objects per uint64 word of `casters`
MAX_OBJECT_IDS = 65535    # objects `object_id` can name: uint16, 0 is the background

# the light kinds a field exists for
EVERY = "every light"
HARD = "hard lights"      # point, spot, directional: not an area light


@dataclass(frozen=True)
class Field:
    """One array of a frame.

    dtype : its numpy dtype
    dims : its shape in terms of the lights L, the height H, the width W and the casters'
        words K = max(1, ceil(n_objects / 64)); a number is that many
    lights : the light kinds that have it (EVERY or HARD)
    stored : when a mask file holds it: "always", "asked" (a ground-truth output, when asked
        for), "layer" (an intrinsic layer, when asked for), "soft" (when some light has more
        than one sample), "exact" (the ray tracer's exact visibility of area lights,
        `raytrace.exact_soft`: when named, never in `all`, and no ground truth the rasterizer
        must produce), or "" (never: images)
    nothing : what it holds where nothing is hit
    """

    dtype: type
    dims: tuple
    lights: str = EVERY
    stored: str = "always"
    nothing: float = 0


# Every field of a frame, by name; the order is the mask file's (docs/CONVENTIONS.md).
FIELDS = {
    "image": Field(np.float32, ("H", "W", 3), stored=""),
    "image_srgb": Field(np.uint8, ("H", "W", 3), stored=""),
    "stencil": Field(np.int16, ("L", "H", "W"), lights=HARD, stored=""),
    "lit": Field(np.bool_, ("L", "H", "W")),
    "coverage": Field(np.bool_, ("H", "W")),
    "depth": Field(np.float32, ("H", "W"), stored="asked", nothing=np.inf),
    "distance": Field(np.float32, ("H", "W"), stored="asked", nothing=np.inf),
    "normal": Field(np.float32, ("H", "W", 3), stored="asked"),
    "object_id": Field(np.uint16, ("H", "W"), stored="asked"),
    "facing": Field(np.bool_, ("L", "H", "W"), stored="asked"),
    "facing_count": Field(np.uint16, ("L", "H", "W"), stored="asked"),
    "casters": Field(np.uint64, ("L", "H", "W", "K"), stored="asked"),
    "lit_count": Field(np.uint16, ("L", "H", "W"), stored="soft"),
    "samples": Field(np.int64, ("L",), stored="soft"),
    # the ray tracer's exact visibility of area lights (raytrace.exact_soft)
    "visibility_exact": Field(np.float64, ("L", "H", "W"), stored="exact"),
    "irradiance_exact": Field(np.float64, ("L", "H", "W"), stored="exact"),
    # the camera matrices and light arrays (`shadowvol.cameras.Calibration`)
    "K": Field(np.float64, (3, 3)),
    "world_to_camera": Field(np.float64, (4, 4)),
    "camera_to_world": Field(np.float64, (4, 4)),
    "light_position": Field(np.float64, ("L", 4)),
    "light_direction": Field(np.float64, ("L", 3)),
    # the intrinsic layers (docs/CONVENTIONS.md, "Intrinsic layers"): when asked for
    "albedo": Field(np.float32, ("H", "W", 3), stored="layer"),
    "ambient": Field(np.float32, ("H", "W", 3), stored="layer"),
    "direct": Field(np.float32, ("L", "H", "W", 3), stored="layer"),
    "direct_shadowed": Field(np.float32, ("L", "H", "W", 3), stored="layer"),
    "shadow_free": Field(np.float32, ("H", "W", 3), stored="layer"),
}

# The ground-truth outputs a frame may carry, by name, in this order (docs/CONVENTIONS.md).
GROUND_TRUTH = tuple(name for name, f in FIELDS.items() if f.stored == "asked")
# The ray tracer's exact outputs (`raytrace masks --outputs`): named only, never in `all`.
EXACT_OUTPUTS = tuple(name for name, f in FIELDS.items() if f.stored == "exact")
# The intrinsic layers a frame may carry, by name, in this order (docs/CONVENTIONS.md).
LAYERS = tuple(name for name, f in FIELDS.items() if f.stored == "layer")
# The arrays a mask file may hold beside `lit` and `coverage`: name -> (dtype, dims).
MASK_ARRAYS = {name: (f.dtype, f.dims) for name, f in FIELDS.items()
               if f.stored and name not in ("lit", "coverage")}


@dataclass(frozen=True, eq=False, kw_only=True)
class Frame:
    """One frame, as both renderers return it; each array is None unless asked for.  What a
    frame derives from its arrays (docs/CONVENTIONS.md): the cast and the attached shadow, the
    umbra and the penumbra, the visibility, and its arrays by their mask-file names.

    lit : (L, H, W) bool, per light: every sample reaches the pixel
    coverage : (H, W) bool, geometry visible at the pixel centre
    lit_count : (L, H, W) uint16, per light how many of its samples reach the pixel
    samples : (L,) int64, N per light (1 for a point, spot or directional light)
    depth, distance, normal, object_id, facing, facing_count, casters : the ground truth of
        docs/CONVENTIONS.md, as `FIELDS` declares them
    albedo, ambient, direct, direct_shadowed, shadow_free : the intrinsic layers of
        docs/CONVENTIONS.md, float32, as `FIELDS` declares them
    calibration : the camera matrices and light arrays (`shadowvol.cameras.Calibration`)
    """

    lit: np.ndarray | None = None
    coverage: np.ndarray | None = None
    lit_count: np.ndarray | None = None
    samples: np.ndarray | None = None
    depth: np.ndarray | None = None
    distance: np.ndarray | None = None
    normal: np.ndarray | None = None
    object_id: np.ndarray | None = None
    facing: np.ndarray | None = None
    facing_count: np.ndarray | None = None
    casters: np.ndarray | None = None
    albedo: np.ndarray | None = None
    ambient: np.ndarray | None = None
    direct: np.ndarray | None = None
    direct_shadowed: np.ndarray | None = None
    shadow_free: np.ndarray | None = None
    calibration: Calibration | None = None

    @property
    def cast(self) -> np.ndarray:
        """(L, H, W) bool: some sample facing the pixel is blocked (lit_count <
        facing_count; hard lights: facing & ~lit); `casters.any(-1)` exactly."""
        if self.facing_count is not None and self.lit_count is not None:
            return self.lit_count < self.facing_count
        return self.facing & ~self.lit

    @property
    def attached(self) -> np.ndarray:
        """(L, H, W) bool: covered, but no sample faces the pixel (needs facing, coverage)."""
        return self.coverage[None] & ~self.facing

    @property
    def umbra(self) -> np.ndarray:
        """(L, H, W) bool: some sample faces the pixel and none reaches it (needs facing,
        lit_count)."""
        return self.facing & (self.lit_count == 0)

    @property
    def penumbra(self) -> np.ndarray:
        """(L, H, W) bool: some samples reach the pixel, not all (0 < lit_count < N)."""
        return (self.lit_count > 0) & (self.lit_count < self.samples[:, None, None])

    @property
    def visibility(self) -> np.ndarray:
        """(L, H, W) float32: lit_count / N."""
        return (self.lit_count / self.samples[:, None, None]).astype(np.float32)

    def arrays(self) -> dict[str, np.ndarray]:
        """The ground truth and intrinsic layers computed, the counts when some light has more than one sample,
        and the calibration, by their mask-file names (`save_masks`)."""
        out = {name: getattr(self, name) for name in GROUND_TRUTH + LAYERS
               if getattr(self, name) is not None}
        return out | soft_arrays(self.lit_count, self.samples) | self.calibration.arrays()


def soft_arrays(lit_count: np.ndarray | None, samples: np.ndarray | None
                ) -> dict[str, np.ndarray]:
    """`lit_count` and `samples` by name when some light has more than one sample (a mask
    file of hard lights alone stays as it was), else nothing."""
    if samples is None or lit_count is None or not (np.asarray(samples) > 1).any():
        return {}
    return {"lit_count": np.asarray(lit_count, FIELDS["lit_count"].dtype),
            "samples": np.asarray(samples, FIELDS["samples"].dtype)}


# ---- the outputs asked for -------------------------------------------------------------------

def check_outputs(outputs, offered: tuple[str, ...] = GROUND_TRUTH, default=(), *,
                  objects: int | None = None, key: str = "outputs") -> tuple[str, ...]:
    """The outputs asked for, checked, in `offered`'s order (the fields of `FIELDS` a renderer
    makes): `outputs` a sequence of names (a string is a TypeError, not its letters), None for
    `default`.  SceneError (a ValueError) naming `key` for a name not offered, and with
    `objects` (the scene's) for an `object_id` that cannot name them all."""
    if outputs is None:
        outputs = default
    if isinstance(outputs, str):
        raise TypeError(f"outputs must be a sequence of names, e.g. ({outputs!r},)")
    outputs = tuple(outputs)
    unknown = [o for o in outputs if o not in offered]
    if unknown:
        raise SceneError(key, f"unknown output {shorten(unknown[0])} (one of: "
                              f"{', '.join(offered)})")
    if objects is not None and "object_id" in outputs:
        check_object_ids(objects)
    return tuple(o for o in offered if o in outputs)


def check_light_kinds(outputs, lights) -> None:
    """ValueError for an output asked of a light kind that does not have it (`Field.lights`:
    the stencil counts are per hard light, not for an area light)."""
    for name in outputs:
        if FIELDS[name].lights == HARD and any(isinstance(lt, AreaLight) for lt in lights):
            raise ValueError(f"{name} is per hard light: not for area lights")


def check_object_ids(objects: int) -> None:
    """SceneError when `objects` objects do not fit in `object_id`."""
    if objects > MAX_OBJECT_IDS:
        raise SceneError("objects", f"object_id counts up to {MAX_OBJECT_IDS} objects, and this "
                                    f"scene has {objects}")


# ---- the fields' arrays ----------------------------------------------------------------------

def caster_words(objects: int) -> int:
    """K, the uint64 words of `casters` per pixel for a scene of `objects` objects: object j
    is bit j mod 64 of word j div 64."""
    return max(1, -(-objects // CASTER_WORD_BITS))


def shape(name: str, lights: int, height: int, width: int, flat: bool = False,
          objects: int = 0) -> tuple[int, ...]:
    """The shape of field `name` in a frame of `lights` lights, (H, W) pixels and `objects`
    objects; `flat`: the pixels as one axis, row-major (H * W)."""
    sizes = {"L": lights, "H": height, "W": width, "K": caster_words(objects)}
    dims = FIELDS[name].dims
    out = [sizes.get(d, d) for d in dims]
    if flat:
        at = dims.index("H")
        out[at:at + 2] = [height * width]
    return tuple(out)


def blank(name: str, shape: tuple[int, ...]) -> np.ndarray:
    """A new array of field `name`'s dtype and `shape`, holding its value for nothing hit."""
    return np.full(shape, FIELDS[name].nothing, FIELDS[name].dtype)


def decode_casters(casters: np.ndarray, objects: int) -> np.ndarray:
    """(..., K) uint64 `casters` -> (..., objects) bool, element j: scene.objects[j] casts
    (numpy alone: the words' bytes, little-endian, unpacked lowest bit first)."""
    bits = np.unpackbits(np.ascontiguousarray(casters, "<u8").view(np.uint8), axis=-1,
                         bitorder="little")
    return bits[..., :objects].astype(bool)


def layer_exrs(image_path: str | Path, frame: "Frame") -> dict[Path, np.ndarray]:
    """The EXR files of the intrinsic layers `frame` holds, beside the image's EXR
    `image_path` (X.exr): X-albedo.exr, X-ambient.exr, X-shadow_free.exr, and per light i
    X-direct-i.exr and X-direct_shadowed-i.exr, each (H, W, 3) float32; none when the image
    goes to standard output ("-")."""
    path = Path(image_path)
    out = {}
    if str(image_path) == "-":
        return out
    for name in LAYERS:
        value = getattr(frame, name)
        if value is None:
            continue
        if FIELDS[name].dims[0] == "L":
            out |= {path.with_name(f"{path.stem}-{name}-{i}.exr"): v for i, v in enumerate(value)}
        else:
            out[path.with_name(f"{path.stem}-{name}.exr")] = value
    return out


# ---- the mask file ---------------------------------------------------------------------------

def mask_file(lit: np.ndarray, coverage: np.ndarray, arrays: dict[str, np.ndarray] | None = None,
              light_samples=None) -> dict[str, np.ndarray]:
    """The arrays of a mask file as docs/CONVENTIONS.md defines it, checked, in the file's
    order: `lit` (L, H, W) bool, `coverage` (H, W), and

    arrays : more arrays by name: the ground-truth outputs and the camera and light arrays
        (`shadowvol.cameras.Calibration.arrays()`), each of the dtype and shape `MASK_ARRAYS`
        gives it (ValueError otherwise, and for a name it does not know);
    light_samples : per light an (N, 3) float64 array of its sample positions
        (`shadowvol.scene.light_samples`) or None (a directional light), written as
        `light_samples_<i>`."""
    extra = {}
    for i, samples in enumerate(light_samples or ()):
        if samples is not None:
            samples = np.asarray(samples, np.float64)
            if samples.ndim != 2 or samples.shape[1] != 3:
                raise ValueError(f"light_samples[{i}] must be (N, 3), got {samples.shape}")
            extra[f"light_samples_{i}"] = samples
    if lit is None or coverage is None:
        raise ValueError("a mask file needs lit and coverage, got None (a frame rendered "
                         "without them? save_masks(path, frame) says which)")
    lit = np.asarray(lit)
    coverage = np.asarray(coverage)
    if lit.dtype != bool or lit.ndim != 3 or coverage.dtype != bool or \
            coverage.shape != lit.shape[1:]:
        raise ValueError(f"masks must be lit (L, H, W) bool and coverage (H, W) bool, got "
                         f"{lit.dtype}{lit.shape} and {coverage.dtype}{coverage.shape}")
    sizes = dict(zip("LHW", lit.shape))
    for name, value in (arrays or {}).items():
        if name not in MASK_ARRAYS:
            raise ValueError(f"a mask file holds no array {name!r} (known: "
                             f"{', '.join(MASK_ARRAYS)})")
        dtype, dims = MASK_ARRAYS[name]
        value = np.asarray(value)
        # K, the casters' words: the array's own (at least 1)
        words = {"K": max(1, value.shape[-1]) if value.ndim == len(dims) else 1}
        want = tuple(sizes.get(n, words.get(n, n)) for n in dims)
        if value.dtype != dtype or value.shape != want:
            raise ValueError(f"{name} must be {np.dtype(dtype)}{want}, got "
                             f"{value.dtype}{value.shape}")
        extra[name] = value
    return {"lit": lit, "coverage": coverage, **extra}


def masks_bytes(lit: np.ndarray, coverage: np.ndarray,
                arrays: dict[str, np.ndarray] | None = None, light_samples=None) -> bytes:
    """A mask file (`mask_file`) as `.npz` bytes: the same arrays give the same bytes
    (`shadowvol.io.npz_bytes`)."""
    return io.npz_bytes(**mask_file(lit, coverage, arrays, light_samples))


def save_masks(path: str | Path, lit, coverage: np.ndarray | None = None,
               arrays: dict[str, np.ndarray] | None = None, light_samples=None) -> None:
    """Write a mask file (`masks_bytes`) through `shadowvol.io`'s atomic writer.

    `save_masks(path, frame)` writes a frame of either renderer whole: its `lit` and
    `coverage`, the camera matrices and light arrays, the ground truth it holds and an area
    light's counts (`Frame.arrays`; `arrays=` adds more); `save_masks(path, lit, coverage)`
    the masks alone, with what `arrays=` names."""
    if isinstance(lit, Frame):
        frame = lit
        missing = [name for name in ("lit", "coverage") if getattr(frame, name) is None]
        if missing:
            raise ValueError(f"the frame has no {' and no '.join(missing)}: it was rendered "
                             f"with outputs= leaving {'them' if len(missing) > 1 else 'it'} "
                             f"out; add {', '.join(map(repr, missing))} to outputs")
        lit, coverage, arrays = frame.lit, frame.coverage, frame.arrays() | (arrays or {})
    with out_of_memory_while(f"writing {path}"):
        io.write_bytes(path, masks_bytes(lit, coverage, arrays, light_samples))
