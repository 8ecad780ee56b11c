"""The checks every value of the scene model passes, and the one error they raise.

`SceneError` names the key path and the problem on one line (a file's keys and values may hold
line breaks; a wrong value is quoted to `MAX_QUOTE` characters).  `vec` and `num` keep every
number inside the float32 range the renderers use.  Below `shadowvol.scene` and
`shadowvol.lights`, which both build on it; `shadowvol.scene` re-exports the public names.
"""

from __future__ import annotations

import math

import numpy as np

from shadowvol.errors import MAX_MESSAGE, one_line, short_path

# The float32 range the renderers use: every number of a scene has |x| <= MAX_MAGNITUDE, and
# every length that must be positive (near, radius, sizes, scale) is >= MIN_POSITIVE, so that
# x, 1/x, x*x and sums of a few squares are all normal float32 numbers (float32 ends at 3.4e38
# and its normal numbers at 1.2e-38).  A world 1e6 or 1e9 wide is far inside this.
MAX_MAGNITUDE = 1e18
MIN_POSITIVE = 1e-18
# Messages quote a bad value only up to this many characters (a wrong 1e6-element list is not
# echoed whole), and a SceneError's key is cut to one line of at most this length (its problem
# and file to `shadowvol.errors.MAX_MESSAGE`).
MAX_QUOTE = 80
# How far from orthonormal the rotation of a rigid 4x4 matrix (a camera pose) may be: the
# largest |R^T R - I| entry.  Poses computed in float32 elsewhere reach ~1e-7; a scale or a
# shear of 1e-6 is refused.  The matrix is used as given (not re-orthonormalised).
RIGID_TOLERANCE = 1e-6


def shorten(value, limit: int = MAX_QUOTE) -> str:
    """repr(value), cut to about `limit` characters ("… (N items)" for a long list); a numpy
    array or number as the list or number a file would hold, never "array([...])"."""
    text = repr(value.tolist() if isinstance(value, (np.ndarray, np.generic)) else value)
    if len(text) <= limit:
        return text
    more = f" ({len(value)} items)" if isinstance(value, (list, tuple, np.ndarray)) else ""
    return text[:limit] + "…" + more


class SceneError(ValueError):
    """Bad scene input: names the file (when known), the key and the problem."""

    def __init__(self, key: str, problem: str, file: str | None = None):
        # one line, whatever the input: keys and values from a file may hold line breaks
        key, problem = one_line(key, MAX_QUOTE), one_line(problem, MAX_MESSAGE)
        file = None if file is None else one_line(short_path(file), MAX_MESSAGE)
        self.key, self.problem, self.file = key, problem, file
        parts = [part for part in (file, key) if part]
        super().__init__(": ".join(parts + [problem]))

    def in_file(self, file: str) -> "SceneError":
        return SceneError(self.key, self.problem, file)

    def under(self, prefix: str) -> "SceneError":
        key = f"{prefix}.{self.key}" if self.key else prefix
        return SceneError(key, self.problem, self.file)


def reject_unknown_keys(table, allowed, key: str = "") -> None:
    """Raise SceneError naming the first key of `table` that is not in `allowed`; `key` is the
    table's own key path ("" at the top level), so the error names `key.unknown`."""
    unknown = sorted(str(name) for name in set(table) - set(allowed))
    if unknown:
        prefix = f"{key}." if key else ""
        raise SceneError(f"{prefix}{unknown[0]}",
                         f"unknown key (allowed here: {', '.join(sorted(allowed))})")


def is_number(x) -> bool:
    """A real number, strictly: int or float (numpy's too), never a bool or a string."""
    return (isinstance(x, (int, float, np.integer, np.floating))
            and not isinstance(x, (bool, np.bool_)))


def _numbers(value) -> bool:
    """`value` is a numeric array or a flat list/tuple of real numbers (`is_number`)."""
    if isinstance(value, np.ndarray):
        return value.dtype.kind in "iuf"
    return isinstance(value, (list, tuple)) and all(is_number(x) for x in value)


def vec(value, key: str, n: int = 3, *, positive: bool = False) -> np.ndarray:
    """A read-only float64 vector of length `n` from `value` (a list, tuple or array of real
    numbers: no strings, no booleans), or a SceneError naming `key`."""
    if not _numbers(value):
        raise SceneError(key, f"expected {n} numbers, got {shorten(value)}")
    try:
        arr = np.array(value, dtype=np.float64)
    except OverflowError:   # an integer past float64 (1e400)
        raise SceneError(key, f"{shorten(value)} is beyond the float32 range the renderers use "
                              f"(|x| <= {MAX_MAGNITUDE:g})") from None
    if arr.shape != (n,):
        raise SceneError(key, f"expected {n} numbers, got {shorten(value)}")
    if not np.all(np.isfinite(arr)):
        raise SceneError(key, f"non-finite number in {shorten(value)}")
    if np.any(np.abs(arr) > MAX_MAGNITUDE):
        raise SceneError(key, f"{shorten(value)} is beyond the float32 range the renderers use "
                              f"(|x| <= {MAX_MAGNITUDE:g})")
    if positive and np.any(arr <= 0):
        raise SceneError(key, f"must be positive, got {shorten(value)}")
    if positive and np.any(arr < MIN_POSITIVE):
        raise SceneError(key, f"{shorten(value)} is too small for float32 (at least "
                              f"{MIN_POSITIVE:g})")
    arr.setflags(write=False)
    return arr


def num(value, key: str, *, low: float | None = None, high: float | None = None,
        low_open: bool = False) -> float:
    """A finite float from `value` within [low, high] (low excluded if `low_open`)."""
    if not is_number(value):
        raise SceneError(key, f"expected a number, got {shorten(value)}")
    try:
        x = float(value)
    except OverflowError:   # an integer past float64 (1e400)
        raise SceneError(key, f"{shorten(value)} is beyond the float32 range the renderers use "
                              f"(|x| <= {MAX_MAGNITUDE:g})") from None
    if not math.isfinite(x):
        raise SceneError(key, f"non-finite number {value!r}")
    if abs(x) > MAX_MAGNITUDE:
        raise SceneError(key, f"{shorten(value)} is beyond the float32 range the renderers use "
                              f"(|x| <= {MAX_MAGNITUDE:g})")
    if low is not None and (x <= low if low_open else x < low):
        raise SceneError(key, f"must be {'>' if low_open else '>='} {low}, got {value!r}")
    if low == 0.0 and low_open and x < MIN_POSITIVE:
        raise SceneError(key, f"{value!r} is too small for float32 (at least {MIN_POSITIVE:g})")
    if high is not None and x > high:
        raise SceneError(key, f"must be <= {high}, got {value!r}")
    return x


def flag(value, key: str) -> bool:
    """A switch: true or false exactly (no 0, 1 or string), or a SceneError naming `key`."""
    if not isinstance(value, (bool, np.bool_)):
        raise SceneError(key, f"expected true or false, got {shorten(value)}")
    return bool(value)


def _matrix4(value, key: str) -> np.ndarray:
    """A (4, 4) float64 array of finite numbers inside the float32 range, last row exactly
    0 0 0 1 (affine), from 4 lists of 4 real numbers or a (4, 4) array; else a SceneError."""
    if isinstance(value, np.ndarray):
        ok = value.dtype.kind in "iuf" and value.shape == (4, 4)
    else:
        ok = (isinstance(value, (list, tuple)) and len(value) == 4
              and all(_numbers(row) and len(row) == 4 for row in value))
    if not ok:
        got = (f"an array of shape {value.shape} ({value.dtype})"
               if isinstance(value, np.ndarray) else shorten(value))
        raise SceneError(key, f"expected a 4x4 matrix (4 rows of 4 numbers), got {got}")
    try:
        m = np.array(value, dtype=np.float64)
    except OverflowError:   # an integer past float64 (1e400)
        raise SceneError(key, f"{shorten(value)} is beyond the float32 range the renderers use "
                              f"(|x| <= {MAX_MAGNITUDE:g})") from None
    if not np.all(np.isfinite(m)):
        raise SceneError(key, f"non-finite number in {shorten(value)}")
    if np.any(np.abs(m) > MAX_MAGNITUDE):
        raise SceneError(key, f"{shorten(value)} is beyond the float32 range the renderers use "
                              f"(|x| <= {MAX_MAGNITUDE:g})")
    if not np.array_equal(m[3], [0.0, 0.0, 0.0, 1.0]):
        raise SceneError(key, f"not rigid: the last row must be [0, 0, 0, 1], got "
                              f"{m[3].tolist()}")
    return m


def rigid_matrix(value, key: str) -> np.ndarray:
    """A read-only (4, 4) float64 rigid transform (rotation and translation; last row exactly
    0 0 0 1) from `value`, 4 lists of 4 real numbers or a (4, 4) array, or a SceneError naming
    `key`: wrong shape, non-finite, beyond the float32 range, a scale, shear or mirror."""
    m = _matrix4(value, key)
    r = m[:3, :3]
    error = float(np.abs(r.T @ r - np.eye(3)).max())
    if error > RIGID_TOLERANCE:
        raise SceneError(key, f"not rigid: the rotation part is not orthonormal (|R^T R - I| "
                              f"= {error:.3g} > {RIGID_TOLERANCE:g}; no scale or shear)")
    if np.linalg.det(r) < 0:
        raise SceneError(key, "not rigid: the rotation part is a mirror (determinant < 0)")
    return frozen(m)


def similarity_matrix(value, key: str) -> tuple[np.ndarray, float]:
    """(the read-only (4, 4) float64 matrix, its scale s) of a similarity transform: s R and a
    translation, R a rotation (`RIGID_TOLERANCE` on R^T R - I), s > 0 the same on every axis;
    else a SceneError naming `key` (shape, non-finite, last row not 0 0 0 1, a shear, a scale
    that differs between axes, a mirror or a zero scale).  An object pose may scale; a camera
    pose may not (`rigid_matrix`)."""
    m = _matrix4(value, key)
    r = m[:3, :3]
    det = float(np.linalg.det(r))
    if not det > 0:
        raise SceneError(key, "not a pose: the 3x3 part is a mirror or flat (determinant "
                              f"{det:.3g} <= 0)")
    s = det ** (1.0 / 3.0)
    if not MIN_POSITIVE <= s <= MAX_MAGNITUDE:
        raise SceneError(key, f"not a pose: its scale {s:.3g} is outside the float32 range")
    rotation = r / s
    error = float(np.abs(rotation.T @ rotation - np.eye(3)).max())
    if error > RIGID_TOLERANCE:
        raise SceneError(key, f"not a pose: the 3x3 part is not a rotation times one scale "
                              f"(|R^T R - I| = {error:.3g} > {RIGID_TOLERANCE:g} with R = the "
                              f"3x3 part / {s:.6g}: a shear, or a scale that differs between "
                              "axes; use transform = { scale = [...] } for that)")
    return frozen(m), s


def unit(v: np.ndarray, key: str) -> np.ndarray:
    length = float(np.linalg.norm(v))
    if length == 0.0 or not math.isfinite(length):
        raise SceneError(key, "must be a non-zero direction")
    out = v / length
    out.setflags(write=False)
    return out


def frozen(arr: np.ndarray) -> np.ndarray:
    """`arr`, made read-only in place (the model's arrays are never written after checking)."""
    arr.setflags(write=False)
    return arr
