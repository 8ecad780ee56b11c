"""Camera matrices (float64, row-major numpy) and the one GL-to-top-row flip.

The projection has an INFINITE far plane and REVERSED depth: with glClipControl's zero-to-one
depth range (set by `stencil.zero_to_one_depth` around every frame) a point at distance d along
the view axis gets depth near / d: 1 at the near plane, falling toward 0 far away, and exactly 0
for points at infinity (w = 0, the far ends of shadow volumes).  Stored in a 32-bit float depth
buffer this keeps the same RELATIVE precision at every distance (~1e-7 of d, the precision of the
float32 vertices themselves), where the classic 1 - near / d in 24 bits loses precision with the
square of the distance; shadow boundaries on surfaces nearly parallel to a volume's side (grazing
light) depend on exactly that precision.  Nearer means GREATER depth: see NEARER.
GL samples each pixel at its centre, which is the contract's ndc ((x + 0.5) / W * 2 - 1, ...);
GL rows run bottom-up, so every read-back is flipped once (`target`; `top_row_first`).

The GPU works in the float32 FRAME of the eye (`shadowvol.cameras.frame_origin`), as the ray
tracer's masks do: every position it is given -- the soup, side quads, caps' corners, lights,
the eye, clip planes -- is float64 world minus the origin, rounded once (`to_frame`, `in_frame`,
`planes_in_frame`), and the matrices are built in float64 in that frame
(`frame_view_projection`).  World-space float32 would round a vertex 1e6 from the origin by
~0.03; in the frame, only its distance from the eye sets its rounding.
"""

from __future__ import annotations

import numpy as np

from shadowvol.cameras import frame_origin, look_at_basis, pinhole
from shadowvol.scene import Camera

NEARER = ">"              # depth test passing a fragment nearer than what is stored
NEARER_OR_EQUAL = ">="
FAR_DEPTH = 0.0           # the depth buffer's clear value: nothing drawn, infinitely far


def cross3(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """np.cross of two (3,) float64 vectors, the same products and differences (bit for bit),
    without np.cross's per-call axis handling (tens of microseconds, many times a frame)."""
    return np.array([a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                     a[0] * b[1] - a[1] * b[0]])


def view_matrix(camera: Camera) -> np.ndarray:
    """(4, 4) float64 world -> eye space; right-handed, the camera looks down -z.  Rows the
    camera's basis (`cameras.look_at_basis`: the columns of the camera_to_world every frame
    carries), so a frame's camera_to_world read back as its camera gives this matrix again."""
    m = np.eye(4)
    m[0, :3], m[1, :3], m[2, :3] = look_at_basis(camera)
    m[:3, 3] = -m[:3, :3] @ camera.eye
    return m


def infinite_projection(camera: Camera, size: tuple[float, float]) -> np.ndarray:
    """(4, 4) float64 perspective of `camera` for an image of size (W, H) pixels, with the far
    plane at infinity and reversed depth, for the zero-to-one clip depth range.

    From the camera's K (`cameras.pinhole`): ndc x = (2 fx / W) X + 2 cx / W - 1 and
    ndc y = (2 fy / H) Y + 1 - 2 cy / H of the eye-space point's X = x / -z, Y = y / -z, so GL's
    pixel centre (x + 0.5, y + 0.5), rows from the top, is where K puts it; a look-at camera's
    fx = fy = (H / 2) / tan(fov_y / 2), cx = W / 2, cy = H / 2 give the usual symmetric one.
    clip z = near * w, clip w = -z_eye: depth = near / -z_eye, in (0, 1] for z_eye <= -near
    (nearer is clipped: z > w), and exactly 0 for a point at infinity (w = 0).
    """
    width, height = size
    fx, fy, cx, cy = pinhole(camera, width, height)
    m = np.zeros((4, 4))
    m[0, 0] = 2.0 * fx / width
    m[0, 2] = 1.0 - 2.0 * cx / width
    m[1, 1] = 2.0 * fy / height
    m[1, 2] = 2.0 * cy / height - 1.0
    m[2, 3] = camera.near
    m[3, 2] = -1.0
    return m


def view_projection(camera: Camera, size: tuple[float, float]) -> np.ndarray:
    """(4, 4) float64 world -> clip space of an image of size (W, H)."""
    return infinite_projection(camera, size) @ view_matrix(camera)


def frame_camera(camera: Camera, origin: np.ndarray) -> Camera:
    """`camera` with its eye and target (or its matrix's translation) expressed in the frame
    of `origin` (3,) float64."""
    return camera.translated(-origin)


def frame_view_projection(camera: Camera, size: tuple[float, float]
                          ) -> tuple[np.ndarray, np.ndarray]:
    """(4, 4) float64 frame -> clip space for `camera` and an image of size (W, H), and its
    frame origin (3,) float64."""
    origin = frame_origin(camera)
    return view_projection(frame_camera(camera, origin), size), origin


def in_frame(points4: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """Homogeneous world points (..., 4) float64 -> the frame of `origin`: x - w·origin (a
    point at infinity, w = 0, is a direction and stays as it is)."""
    points4 = np.asarray(points4, np.float64)
    out = points4.copy()
    out[..., :3] -= points4[..., 3:] * origin
    return out


def in_frame32(points4: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """`in_frame` rounded to float32 once (the subtraction in float64, written as float32
    without a float64 copy)."""
    points4 = np.asarray(points4, np.float64)
    out = np.empty(points4.shape, np.float32)
    np.subtract(points4[..., :3], points4[..., 3:] * origin, out=out[..., :3],
                casting="unsafe")
    out[..., 3] = points4[..., 3]
    return out


def to_frame(points: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """World points (..., 3) float64 -> float32 in the frame of `origin`: subtracted in
    float64, rounded once.  What both renderers' triangles are."""
    points = np.asarray(points, np.float64)
    out = np.empty(points.shape, np.float32)
    np.subtract(points, origin, out=out, casting="unsafe")   # in float64, rounded once
    return out


def planes_in_frame(planes: np.ndarray, origin: np.ndarray) -> np.ndarray:
    """Planes (k, 4) float64 (n, d), n . x + d w >= 0, of world points -> the same planes of
    the points' frame coordinates x' = x - w·origin: d' = d + n . origin."""
    out = np.array(planes, np.float64)
    out[:, 3] += out[:, :3] @ origin
    return out


def gl_matrix(m: np.ndarray) -> bytes:
    """Bytes of a (4, 4) matrix for a GLSL `mat4` uniform (column-major float32).  float32 is
    what GLSL computes in; the product is formed in float64 first so it is rounded once."""
    return np.ascontiguousarray(m.T, dtype=np.float32).tobytes()


def near_rectangle(camera: Camera, size: tuple[float, float]) -> np.ndarray:
    """(4, 3) float64: the corners of the near-plane rectangle in world space (the view
    frustum's cross-section at distance `near`) of an image of size (W, H), counter-clockwise
    seen from the eye."""
    width, height = size
    fx, fy, cx, cy = pinhole(camera, width, height)
    side, up, back = look_at_basis(camera)
    n = camera.near
    x0, x1 = (0.0 - cx) / fx * n, (width - cx) / fx * n          # right of the axis
    y0, y1 = (cy - height) / fy * n, cy / fy * n                  # above the axis
    centre = camera.eye - back * n
    return np.array([centre + side * x0 + up * y0, centre + side * x1 + up * y0,
                     centre + side * x1 + up * y1, centre + side * x0 + up * y1])


def top_row_first(pixels: np.ndarray) -> np.ndarray:
    """GL read-back (row 0 at the bottom) -> row 0 at the top.  The one flip (CONVENTIONS.md)."""
    return np.ascontiguousarray(pixels[::-1])
