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


def save_masks(path: str | Path, lit: np.ndarray, coverage: np.ndarray,
               light_samples=None) -> None:
    """Write a mask file as CONVENTIONS.md defines it: `lit` (L, H, W) bool, `coverage` (H, W).

    light_samples : optional, per light an (N, 3) float64 array of its sample positions
    (`shadowvol.scene.light_samples`) or None (a directional light), written as
    `light_samples_<i>`."""
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
    buf = io.BytesIO()
    np.savez_compressed(buf, lit=lit, coverage=coverage, **extra)
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
