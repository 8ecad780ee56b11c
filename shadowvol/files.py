"""Writing results to disk: PNG images and mask files, atomically.

Renderers return arrays; only the command-line tools call these.  Every writer goes through
`atomic_write`, so an error or Ctrl-C never leaves a half-written file behind: the data goes to a
temporary file beside the target, which replaces the target only once it is complete.
Arrays here have row 0 at the TOP (CONVENTIONS.md).
"""

from __future__ import annotations

import contextlib
import io
import os
import tempfile
from pathlib import Path

import numpy as np


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
    from PIL import Image

    arr = np.asarray(image)
    if arr.dtype == bool:
        arr = arr.astype(np.uint8) * 255
    if arr.dtype != np.uint8:
        raise TypeError(f"png_bytes wants uint8 or bool pixels, got {arr.dtype}")
    buf = io.BytesIO()
    Image.fromarray(arr).save(buf, format="PNG")
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
    lit = np.asarray(lit)
    coverage = np.asarray(coverage)
    if lit.dtype != bool or lit.ndim != 3 or coverage.dtype != bool or \
            coverage.shape != lit.shape[1:]:
        raise ValueError(f"masks must be lit (L, H, W) bool and coverage (H, W) bool, got "
                         f"{lit.dtype}{lit.shape} and {coverage.dtype}{coverage.shape}")
    buf = io.BytesIO()
    np.savez_compressed(buf, lit=lit, coverage=coverage)
    with atomic_write(path) as f:
        f.write(buf.getvalue())


def load_masks(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """Read a mask file (never unpickles: allow_pickle=False)."""
    with np.load(path, allow_pickle=False) as data:
        return data["lit"], data["coverage"]


def masks_image(lit: np.ndarray, coverage: np.ndarray) -> np.ndarray:
    """A picture of the masks: one panel per light side by side, (H, L*W + gaps, 3) uint8.
    Lit = white, covered but shadowed = mid grey, not covered = black."""
    panels = []
    for mask in lit:
        panel = np.zeros(mask.shape + (3,), np.uint8)
        panel[coverage] = 96
        panel[mask & coverage] = 255
        panels.append(panel)
    if not panels:
        panels = [np.where(coverage[..., None], 96, 0).astype(np.uint8).repeat(3, axis=2)]
    return join(panels, axis=1, colour=(200, 40, 40))


def join(images: list[np.ndarray], axis: int, gap: int = 4,
         colour: tuple[int, int, int] = (255, 255, 255)) -> np.ndarray:
    """(H, W, 3) uint8 images side by side (axis=1, equal heights) or one above another
    (axis=0, equal widths), with `gap` pixels of `colour` between neighbours."""
    shape = list(images[0].shape)
    shape[axis] = gap
    spacer = np.full(shape, colour, np.uint8)
    parts = [images[0]]
    for image in images[1:]:
        parts += [spacer, image]
    return np.concatenate(parts, axis=axis)


def exr_bytes(image: np.ndarray) -> bytes:
    """An OpenEXR file of an (H, W, 3) float linear RGB image: scanline, uncompressed, 32-bit
    float channels B, G, R (EXR lists channels alphabetically), row 0 at the top."""
    import struct

    arr = np.asarray(image, dtype="<f4")
    if arr.ndim != 3 or arr.shape[2] != 3:
        raise ValueError(f"exr_bytes wants an (H, W, 3) image, got shape {arr.shape}")
    h, w = arr.shape[:2]

    def attr(name: str, kind: str, value: bytes) -> bytes:
        return name.encode() + b"\0" + kind.encode() + b"\0" + struct.pack("<i", len(value)) + value

    channels = b"".join(c.encode() + b"\0" + struct.pack("<iB3xii", 2, 0, 1, 1) for c in "BGR")
    window = struct.pack("<iiii", 0, 0, w - 1, h - 1)
    header = (struct.pack("<ii", 20000630, 2)
              + attr("channels", "chlist", channels + b"\0")
              + attr("compression", "compression", b"\0")
              + attr("dataWindow", "box2i", window)
              + attr("displayWindow", "box2i", window)
              + attr("lineOrder", "lineOrder", b"\0")
              + attr("pixelAspectRatio", "float", struct.pack("<f", 1.0))
              + attr("screenWindowCenter", "v2f", struct.pack("<ff", 0.0, 0.0))
              + attr("screenWindowWidth", "float", struct.pack("<f", 1.0)) + b"\0")
    line_bytes = 3 * 4 * w
    first = len(header) + 8 * h
    offsets = struct.pack(f"<{h}Q", *(first + y * (8 + line_bytes) for y in range(h)))
    planar = np.ascontiguousarray(arr[:, :, ::-1].transpose(0, 2, 1))  # (H, B|G|R, W)
    lines = b"".join(struct.pack("<ii", y, line_bytes) + planar[y].tobytes() for y in range(h))
    return header + offsets + lines


def save_exr(path: str | Path, image: np.ndarray) -> None:
    """Write an (H, W, 3) float linear RGB image as OpenEXR (see `exr_bytes`), atomically."""
    data = exr_bytes(image)
    with atomic_write(path) as f:
        f.write(data)
