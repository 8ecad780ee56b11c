"""The one writer: PNG images (8- and 16-bit), OpenEXR images, `.npz` and `.npy` arrays, tar
archives and raw bytes, atomically; bytes only: what a frame's files hold is
`shadowvol.frame`'s (`shadowvol.frame.save_masks` writes its mask file through here).

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
import errno
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
def atomic_write(path: str | Path, follow_links: bool = True, within: str | Path | None = None):
    """Yield a binary file object that becomes `path` only once complete.

    A regular file (or a new name) is written to a temporary file beside it, fsynced and
    renamed over it: on any error, Ctrl-C or SIGTERM the temporary is removed and `path` is left
    as it was.  A symbolic link is followed: the file it points to is replaced the same way in
    its own folder, and the link stays; with `follow_links=False` the link itself is replaced
    by the file, and what it pointed to is left alone (a dataset's frames, where a link may
    point to another frame's file).  A device, a FIFO or "-" (standard output) cannot be
    replaced: the data is written straight to it.  With `within` (a folder above `path`), no
    folder between it and `path` may be a link either: a dataset's file is written in the
    dataset (a folder link would put it in another output's folder, or outside).  Errors are
    WriteError naming `path`.
    """
    shown = short_path(path)
    if shown == STDOUT:
        yield _Stream(sys.stdout.buffer, shown)
        return
    path = Path(path)
    if within is not None:
        _no_folder_link(Path(within), path, shown)
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


def linked_folder(within: str | Path, path: str | Path) -> Path | None:
    """The first folder of `path` below the folder `within` (`path` itself excluded) that is a
    symbolic link, or None."""
    folder = Path(within)
    for part in Path(path).relative_to(within).parts[:-1]:
        folder = folder / part
        if folder.is_symlink():
            return folder
    return None


def _no_folder_link(within: Path, path: Path, shown: str) -> None:
    """WriteError when a folder of `path` below `within` is a symbolic link."""
    folder = linked_folder(within, path)
    if folder is not None:
        raise WriteError(errno.ELOOP, f"{shown}: cannot write: {short_path(folder)} is a "
                                      "symbolic link, and no file of the dataset is written "
                                      "through one; make it a folder")


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


def write_bytes(path: str | Path, data: bytes, follow_links: bool = True,
                within: str | Path | None = None) -> None:
    """Write `data` to `path` atomically (see `atomic_write`)."""
    with out_of_memory_while(f"writing {path}"), atomic_write(path, follow_links, within) as f:
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


def load_masks(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """Read a mask file (never unpickles: allow_pickle=False)."""
    with np.load(path, allow_pickle=False) as data:
        return data["lit"], data["coverage"]


def load_mask_arrays(path: str | Path) -> dict[str, np.ndarray]:
    """Every array of a mask file by name (never unpickles)."""
    with np.load(path, allow_pickle=False) as data:
        return {name: data[name] for name in data.files}
