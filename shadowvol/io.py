"""The one writer: PNG images, mask files, tar archives and raw bytes, atomically.

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
import tarfile
import tempfile
import zipfile
from pathlib import Path

import numpy as np
from PIL import Image


def encode_srgb(linear: np.ndarray) -> np.ndarray:
    """(H, W, 3) float linear RGB -> (H, W, 3) uint8 sRGB (IEC 61966-2-1 transfer curve)."""
    c = np.clip(np.asarray(linear, dtype=np.float64), 0.0, 1.0)
    s = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1 / 2.4) - 0.055)
    return np.round(s * 255.0).astype(np.uint8)


@contextlib.contextmanager
def atomic_write(path: str | Path):
    """Yield a binary file object; on success it atomically becomes `path`, on any error (or
    KeyboardInterrupt) the partial file is removed and `path` is left as it was."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".part", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            yield f
            f.flush()
            os.fsync(f.fileno())
        # mkstemp creates the file 0600; give the output the mode a plain open() would have.
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)
        raise


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


def write_bytes(path: str | Path, data: bytes) -> None:
    """Write `data` to `path` atomically (see `atomic_write`)."""
    with atomic_write(path) as f:
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


def masks_bytes(lit: np.ndarray, coverage: np.ndarray) -> bytes:
    """A mask file as CONVENTIONS.md defines it: `lit` (L, H, W) bool, `coverage` (H, W)."""
    lit = np.asarray(lit)
    coverage = np.asarray(coverage)
    if lit.dtype != bool or lit.ndim != 3 or coverage.dtype != bool or \
            coverage.shape != lit.shape[1:]:
        raise ValueError(f"masks must be lit (L, H, W) bool and coverage (H, W) bool, got "
                         f"{lit.dtype}{lit.shape} and {coverage.dtype}{coverage.shape}")
    return npz_bytes(lit=lit, coverage=coverage)


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
    arr = np.asarray(image)
    if np.issubdtype(arr.dtype, np.floating):
        arr = encode_srgb(arr)
    data = png_bytes(arr)
    with atomic_write(path) as f:
        f.write(data)


def save_masks(path: str | Path, lit: np.ndarray, coverage: np.ndarray) -> None:
    """Write a mask file as CONVENTIONS.md defines it: `lit` (L, H, W) bool, `coverage` (H, W)."""
    write_bytes(path, masks_bytes(lit, coverage))


def load_masks(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """Read a mask file (never unpickles: allow_pickle=False)."""
    with np.load(path, allow_pickle=False) as data:
        return data["lit"], data["coverage"]
