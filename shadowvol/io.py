"""The one writer: PNG images (8- and 16-bit), OpenEXR images, mask files, tar archives and
raw bytes, atomically.

Renderers return arrays; the CLI, batch jobs and the course call these.  Every file goes
through `atomic_write`: the data goes to a temporary file beside the target, which replaces the
target only once it is complete, so an error or Ctrl-C never leaves half a file.  Arrays have
row 0 at the top (docs/CONVENTIONS.md).  The encoders (`png_bytes`, `npz_bytes`, `tar_bytes`)
are deterministic: the same arrays give the same bytes, whenever and wherever they are written
(no timestamps, owners or modes from the machine), which is what lets `shadowvol batch` check a
file against its recorded sha256.
"""

from __future__ import annotations

import contextlib
import io
import os
import struct
import sys
import tarfile
import tempfile
import zipfile
import zlib
from pathlib import Path

import numpy as np
from PIL import Image

from shadowvol import signals
from shadowvol.errors import out_of_memory_while, short_path

# Values encoded at a time by `encode_srgb` and `png16_bytes`: the float64 temporaries of the
# curve stay this small (a few MiB) whatever the image, so encoding adds only its output to
# the memory an image needs (`shadowvol.memory`).
ENCODE_CHUNK = 1 << 18


def _srgb_curve(linear: np.ndarray, scale: float, dtype) -> np.ndarray:
    """The IEC 61966-2-1 transfer curve of `linear` (clipped to 0..1), times `scale`, rounded
    to `dtype`, computed ENCODE_CHUNK values at a time (the same values as all at once)."""
    linear = np.asarray(linear)
    out = np.empty(linear.shape, dtype)
    flat_in, flat_out = linear.reshape(-1), out.reshape(-1)
    for at in range(0, flat_in.size, ENCODE_CHUNK):
        c = np.clip(np.asarray(flat_in[at:at + ENCODE_CHUNK], dtype=np.float64), 0.0, 1.0)
        s = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)
        flat_out[at:at + ENCODE_CHUNK] = np.round(s * scale)
    return out


def encode_srgb(linear: np.ndarray) -> np.ndarray:
    """(H, W, 3) float linear RGB -> (H, W, 3) uint8 sRGB (IEC 61966-2-1 transfer curve)."""
    return _srgb_curve(linear, 255.0, np.uint8)


class WriteError(OSError):
    """A file could not be written; the message names the path the caller gave."""

    def __str__(self) -> str:
        return self.strerror  # without OSError's "[Errno N]" prefix


STDOUT = "-"


@contextlib.contextmanager
def atomic_write(path: str | Path, follow_links: bool = True):
    """Yield a binary file object that becomes `path` only once complete.

    A regular file (or a new name) is written to a temporary file beside it, fsynced and
    renamed over it: on any error, Ctrl-C or SIGTERM the temporary is removed and `path` is left
    as it was.  A symbolic link is followed: the file it points to is replaced the same way in
    its own folder, and the link stays; with `follow_links=False` the link itself is replaced
    by the file, and what it pointed to is left alone (a dataset's frames, where a link may
    point to another frame's file).  A device, a FIFO or "-" (standard output) cannot be
    replaced: the data is written straight to it.  Errors are WriteError naming `path`.
    """
    shown = short_path(path)
    if shown == STDOUT:
        yield _Stream(sys.stdout.buffer, shown)
        return
    path = Path(path)
    if path.is_symlink() and follow_links:
        path = Path(os.path.realpath(path))
    if not path.is_symlink() and path.exists() and not path.is_file() and not path.is_dir():
        # a device or a FIFO
        try:
            with open(path, "wb", buffering=0) as raw:
                yield _Stream(raw, shown)
        except OSError as exc:
            raise WriteError(exc.errno, f"{shown}: cannot write: {exc.strerror}") from None
        return
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part", dir=path.parent)
    except FileExistsError as exc:  # a file where a folder of the path should be
        raise WriteError(exc.errno, f"{shown}: cannot write: {exc.filename} is not a "
                                    "folder") from None
    except OSError as exc:
        raise WriteError(exc.errno, f"{shown}: cannot write: {exc.strerror}") from None
    try:
        with os.fdopen(fd, "wb") as f:
            yield f
            f.flush()
            os.fsync(f.fileno())
        # mkstemp creates the file 0600; give the output the mode a plain open() would have.
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        signals.raise_pending()  # an interrupt swallowed on its way up: no finished file
        os.replace(tmp, path)
    except BaseException as exc:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        if isinstance(exc, OSError) and not isinstance(exc, WriteError):
            raise WriteError(exc.errno, f"{shown}: cannot write: {exc.strerror or exc}") \
                from None
        raise


class _Stream:
    """A file object over a stream that cannot be renamed into place (stdout, a device)."""

    def __init__(self, raw, shown: str):
        self._raw, self._shown = raw, shown

    def write(self, data: bytes) -> int:
        try:
            return self._raw.write(data)
        except OSError as exc:
            raise WriteError(exc.errno, f"{self._shown}: cannot write: {exc.strerror}") from None

    def flush(self) -> None:
        self._raw.flush()


def png_bytes(image: np.ndarray) -> bytes:
    """PNG of an (H, W, 3|4) uint8 image or an (H, W) bool/uint8 image."""
    arr = np.asarray(image)
    if arr.dtype == bool:
        arr = arr.astype(np.uint8) * 255
    if arr.dtype != np.uint8:
        raise TypeError(f"png_bytes wants uint8 or bool pixels, got {arr.dtype}")
    buf = io.BytesIO()
    Image.fromarray(arr).save(buf, format="PNG")
    return buf.getvalue()


def png16_bytes(linear: np.ndarray) -> bytes:
    """A 16-bit RGB PNG of an (H, W, 3) float linear RGB image, sRGB-encoded (clipped to 0..1,
    rounded to 0..65535, with an sRGB chunk), row 0 at the top.  Written here because Pillow
    writes 16 bits per channel only for grey images."""
    linear = np.asarray(linear)
    if linear.ndim != 3 or linear.shape[2] != 3:
        raise ValueError(f"png16_bytes wants an (H, W, 3) image, got shape {linear.shape}")
    pixels = _srgb_curve(linear, 65535.0, ">u2")
    h, w = pixels.shape[:2]
    rows = np.zeros((h, 1 + 6 * w), np.uint8)  # filter type 0 (None) first on each row
    rows[:, 1:] = pixels.reshape(h, -1).view(np.uint8)

    def chunk(kind: bytes, data: bytes) -> bytes:
        return (struct.pack(">I", len(data)) + kind + data
                + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF))

    return (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 16, 2, 0, 0, 0))
            + chunk(b"sRGB", b"\0") + chunk(b"IDAT", zlib.compress(rows.tobytes(), 6))
            + chunk(b"IEND", b""))


def save_png16(path: str | Path, image: np.ndarray) -> None:
    """Write an (H, W, 3) float linear RGB image as a 16-bit sRGB PNG (`png16_bytes`)."""
    with out_of_memory_while(f"writing {path}"):
        data = png16_bytes(image)
        with atomic_write(path) as f:
            f.write(data)


# OpenEXR's ZIP compression packs this many scanlines in a block.
EXR_ZIP_LINES = 16


def exr_bytes(image: np.ndarray) -> bytes:
    """An OpenEXR file of an (H, W, 3) float linear RGB image: scanlines, ZIP-compressed,
    32-bit float channels B, G, R (EXR lists channels alphabetically), row 0 at the top.
    Written here (the format's single-part scanline layout is short) so that no extra
    package is needed to write one; the tests read it back with the OpenEXR package."""
    arr = np.asarray(image, dtype="<f4")
    if arr.ndim != 3 or arr.shape[2] != 3:
        raise ValueError(f"exr_bytes wants an (H, W, 3) image, got shape {arr.shape}")
    h, w = arr.shape[:2]

    def attr(name: str, kind: str, value: bytes) -> bytes:
        return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(value)) + value

    # per channel: name, pixel type 2 (FLOAT), pLinear 0, 3 reserved bytes, sampling 1 x 1
    channels = b"".join(c.encode() + b"\0" + struct.pack("<iB3xii", 2, 0, 1, 1) for c in "BGR")
    window = struct.pack("<iiii", 0, 0, w - 1, h - 1)
    header = (struct.pack("<ii", 20000630, 2)  # the magic number, version 2, single-part scanline
              + attr("channels", "chlist", channels + b"\0")
              + attr("compression", "compression", b"\3")  # ZIP_COMPRESSION
              + attr("dataWindow", "box2i", window)
              + attr("displayWindow", "box2i", window)
              + attr("lineOrder", "lineOrder", b"\0")  # INCREASING_Y
              + attr("pixelAspectRatio", "float", struct.pack("<f", 1.0))
              + attr("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0))
              + attr("screenWindowWidth", "float", struct.pack("<f", 1.0)) + b"\0")
    planar = np.ascontiguousarray(arr[:, :, ::-1].transpose(0, 2, 1))  # (H, B|G|R, W)
    blocks = []
    for y in range(0, h, EXR_ZIP_LINES):
        raw = np.frombuffer(planar[y:y + EXR_ZIP_LINES].tobytes(), np.uint8)
        # OpenEXR's ZIP: the bytes split into even and odd halves, then delta-coded + 128
        split = np.concatenate([raw[0::2], raw[1::2]])
        delta = split.copy()
        delta[1:] = (split[1:].astype(np.int16) - split[:-1] + 128).astype(np.uint8)
        packed = zlib.compress(delta.tobytes(), 6)
        if len(packed) >= len(raw):  # OpenEXR stores a block that does not shrink as it is
            packed = raw.tobytes()
        blocks.append(struct.pack("<ii", y, len(packed)) + packed)
    first = len(header) + 8 * len(blocks)
    offsets, at = [], first
    for block in blocks:
        offsets.append(at)
        at += len(block)
    return header + struct.pack(f"<{len(blocks)}Q", *offsets) + b"".join(blocks)


def save_exr(path: str | Path, image: np.ndarray) -> None:
    """Write an (H, W, 3) float linear RGB image as OpenEXR (`exr_bytes`), atomically."""
    with out_of_memory_while(f"writing {path}"):
        data = exr_bytes(image)
        with atomic_write(path) as f:
            f.write(data)


# The ground-truth outputs a frame may carry, by name, in this order (docs/CONVENTIONS.md).
GROUND_TRUTH = ("depth", "distance", "normal", "object_id", "facing", "facing_count", "casters")


class GroundTruthFrame:
    """What a frame of either renderer derives from its arrays, as docs/CONVENTIONS.md defines
    it: the cast and the attached shadow, the umbra and the penumbra, and its arrays by their
    mask-file names.  Mixed into both renderers' results, which hold `lit`, `coverage`,
    `lit_count`, `samples`, `calibration` and the GROUND_TRUTH outputs (None where not asked
    for)."""

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

    def arrays(self) -> dict[str, np.ndarray]:
        """The ground truth computed, the counts when some light has more than one sample,
        and the calibration, by their mask-file names (`save_masks`)."""
        out = {name: getattr(self, name) for name in GROUND_TRUTH
               if getattr(self, name) is not None}
        return out | soft_arrays(self.lit_count, self.samples) | self.calibration.arrays()


def soft_arrays(lit_count: np.ndarray | None, samples: np.ndarray | None
                ) -> dict[str, np.ndarray]:
    """`lit_count` and `samples` by name when some light has more than one sample (a mask
    file of hard lights alone stays as it was), else nothing."""
    if samples is None or lit_count is None or not (np.asarray(samples) > 1).any():
        return {}
    return {"lit_count": np.asarray(lit_count, np.uint16),
            "samples": np.asarray(samples, np.int64)}


# The arrays a mask file may hold beside `lit` and `coverage` (docs/CONVENTIONS.md): name ->
# (dtype, shape), the shape in terms of the lights L, the height H, the width W and the
# casters' words K = max(1, ceil(n_objects / 64)) (taken from the array itself).
MASK_ARRAYS = {
    "depth": (np.float32, ("H", "W")),
    "distance": (np.float32, ("H", "W")),
    "normal": (np.float32, ("H", "W", 3)),
    "object_id": (np.uint16, ("H", "W")),
    "facing": (np.bool_, ("L", "H", "W")),
    "facing_count": (np.uint16, ("L", "H", "W")),
    "casters": (np.uint64, ("L", "H", "W", "K")),
    "lit_count": (np.uint16, ("L", "H", "W")),
    "samples": (np.int64, ("L",)),
    # the ray tracer's exact visibility of area lights (raytrace.exact_soft)
    "visibility_exact": (np.float64, ("L", "H", "W")),
    "irradiance_exact": (np.float64, ("L", "H", "W")),
    "K": (np.float64, (3, 3)),
    "world_to_camera": (np.float64, (4, 4)),
    "camera_to_world": (np.float64, (4, 4)),
    "light_position": (np.float64, ("L", 4)),
    "light_direction": (np.float64, ("L", 3)),
}


def write_bytes(path: str | Path, data: bytes, follow_links: bool = True) -> None:
    """Write `data` to `path` atomically (see `atomic_write`)."""
    with out_of_memory_while(f"writing {path}"), atomic_write(path, follow_links) as f:
        f.write(data)


# zip and tar members carry a time stamp; a fixed one makes the archives reproducible
# (1980-01-01, the earliest time a zip entry can hold)
_FIXED_ZIP_TIME = (1980, 1, 1, 0, 0, 0)
_FIXED_TAR_MTIME = 315532800


def npz_bytes(**arrays: np.ndarray) -> bytes:
    """A compressed `.npz` of `arrays`, readable by `np.load`, without numpy's time stamps (the
    same arrays give the same bytes).  Never pickles: object arrays are refused."""
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as archive:
        for name, value in arrays.items():
            info = zipfile.ZipInfo(f"{name}.npy", date_time=_FIXED_ZIP_TIME)
            info.compress_type = zipfile.ZIP_DEFLATED
            info.external_attr = 0o644 << 16
            with archive.open(info, "w", force_zip64=True) as member:
                np.lib.format.write_array(member, np.asanyarray(value), allow_pickle=False)
    return buf.getvalue()


def npy_bytes(array: np.ndarray) -> bytes:
    """A `.npy` of `array` (no time stamp: the same array gives the same bytes; never pickles)."""
    buf = io.BytesIO()
    np.lib.format.write_array(buf, np.asanyarray(array), allow_pickle=False)
    return buf.getvalue()


def masks_bytes(lit: np.ndarray, coverage: np.ndarray,
                arrays: dict[str, np.ndarray] | None = None, light_samples=None) -> bytes:
    """A mask file as docs/CONVENTIONS.md defines it: `lit` (L, H, W) bool, `coverage` (H, W),
    and

    arrays : more arrays by name: the ground-truth outputs and the camera and light arrays
        (`shadowvol.cameras.Calibration.arrays()`), each of the dtype and shape `MASK_ARRAYS`
        gives it (ValueError otherwise, and for a name it does not know);
    light_samples : per light an (N, 3) float64 array of its sample positions
        (`shadowvol.scene.light_samples`) or None (a directional light), written as
        `light_samples_<i>`.
    The same arrays give the same bytes (`npz_bytes`)."""
    extra = {}
    for i, samples in enumerate(light_samples or ()):
        if samples is not None:
            samples = np.asarray(samples, np.float64)
            if samples.ndim != 2 or samples.shape[1] != 3:
                raise ValueError(f"light_samples[{i}] must be (N, 3), got {samples.shape}")
            extra[f"light_samples_{i}"] = samples
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
        dtype, shape = MASK_ARRAYS[name]
        value = np.asarray(value)
        # K, the casters' words: the array's own (at least 1)
        words = {"K": max(1, value.shape[-1]) if value.ndim == len(shape) else 1}
        want = tuple(sizes.get(n, words.get(n, n)) for n in shape)
        if value.dtype != dtype or value.shape != want:
            raise ValueError(f"{name} must be {np.dtype(dtype)}{want}, got "
                             f"{value.dtype}{value.shape}")
        extra[name] = value
    return npz_bytes(lit=lit, coverage=coverage, **extra)


def tar_bytes(members: list[tuple[str, bytes]]) -> bytes:
    """An uncompressed POSIX tar of (name, data) members in the given order, with fixed time
    stamps, owners and modes (the same members give the same bytes)."""
    buf = io.BytesIO()
    with tarfile.open(fileobj=buf, mode="w", format=tarfile.PAX_FORMAT) as archive:
        for name, data in members:
            info = tarfile.TarInfo(name)
            info.size = len(data)
            info.mtime = _FIXED_TAR_MTIME
            info.mode = 0o644
            info.uid = info.gid = 0
            info.uname = info.gname = ""
            archive.addfile(info, io.BytesIO(data))
    return buf.getvalue()


def save_png(path: str | Path, image: np.ndarray) -> None:
    """Write an image: uint8 pixels as they are, float pixels as linear RGB encoded to sRGB."""
    with out_of_memory_while(f"writing {path}"):
        arr = np.asarray(image)
        if np.issubdtype(arr.dtype, np.floating):
            arr = encode_srgb(arr)
        data = png_bytes(arr)
        with atomic_write(path) as f:
            f.write(data)


def save_masks(path: str | Path, lit: np.ndarray, coverage: np.ndarray,
               arrays: dict[str, np.ndarray] | None = None, light_samples=None) -> None:
    """Write a mask file (`masks_bytes`), atomically."""
    with out_of_memory_while(f"writing {path}"):
        write_bytes(path, masks_bytes(lit, coverage, arrays, light_samples))


def load_masks(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """Read a mask file (never unpickles: allow_pickle=False)."""
    with np.load(path, allow_pickle=False) as data:
        return data["lit"], data["coverage"]


def load_mask_arrays(path: str | Path) -> dict[str, np.ndarray]:
    """Every array of a mask file by name (never unpickles)."""
    with np.load(path, allow_pickle=False) as data:
        return {name: data[name] for name in data.files}
