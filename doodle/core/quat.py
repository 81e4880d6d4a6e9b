"""Vectorised quaternion helpers, scalar-last ``(x, y, z, w)`` like scipy's Rotation.

Arithmetic is written out component by component in a fixed order, so the per-sample
(streaming) code in :mod:`doodle.input.segmenter` can repeat it with Python floats and get
bit-identical results.
"""

from __future__ import annotations

import numpy as np


def normalise(q: np.ndarray) -> np.ndarray:
    """Unit quaternions, rows of ``q`` (n, 4) divided by their norm."""
    x, y, z, w = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    norm = np.sqrt(x * x + y * y + z * z + w * w)
    return q / norm[:, None]


def hemisphere_signs(q: np.ndarray) -> np.ndarray:
    """±1 per row so that ``signs[..., None] * q`` has no sign flips between neighbours.

    Row i is flipped relative to row i-1 when their dot product is negative (q and -q are
    the same rotation; smoothing and differences need a continuous representative). ``q``
    is (n, 4), or (n, ..., 4) for several sequences along axis 0 (one per joint, say).
    """
    if len(q) == 0:
        return np.ones(q.shape[:-1])
    a, b = q[1:], q[:-1]
    dot = a[..., 0] * b[..., 0] + a[..., 1] * b[..., 1] + a[..., 2] * b[..., 2] + a[..., 3] * b[..., 3]
    flips = np.concatenate([np.zeros((1,) + dot.shape[1:], dtype=bool), dot < 0])
    return np.where(np.cumsum(flips, axis=0) % 2 == 1, -1.0, 1.0)


def make_continuous(q: np.ndarray) -> np.ndarray:
    """``q`` with signs chosen so consecutive rows (along axis 0) are in the same hemisphere."""
    return q * hemisphere_signs(q)[..., None]


def multiply(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Hamilton product ``a ⊗ b`` row by row (the rotation b, then a)."""
    ax, ay, az, aw = a[..., 0], a[..., 1], a[..., 2], a[..., 3]
    bx, by, bz, bw = b[..., 0], b[..., 1], b[..., 2], b[..., 3]
    out = np.empty(np.broadcast_shapes(a.shape, b.shape))
    out[..., 0] = aw * bx + ax * bw + ay * bz - az * by
    out[..., 1] = aw * by - ax * bz + ay * bw + az * bx
    out[..., 2] = aw * bz + ax * by - ay * bx + az * bw
    out[..., 3] = aw * bw - ax * bx - ay * by - az * bz
    return out


def conjugate(q: np.ndarray) -> np.ndarray:
    return q * np.array([-1.0, -1.0, -1.0, 1.0])


def rotate(q: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Rotate vectors ``u`` (..., 3) by unit quaternions ``q`` (..., 4)."""
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    ux, uy, uz = u[..., 0], u[..., 1], u[..., 2]
    tx = 2.0 * (y * uz - z * uy)
    ty = 2.0 * (z * ux - x * uz)
    tz = 2.0 * (x * uy - y * ux)
    out = np.empty(np.broadcast_shapes(q.shape[:-1], u.shape[:-1]) + (3,))
    out[..., 0] = ux + w * tx + (y * tz - z * ty)
    out[..., 1] = uy + w * ty + (z * tx - x * tz)
    out[..., 2] = uz + w * tz + (x * ty - y * tx)
    return out


def front(q: np.ndarray) -> np.ndarray:
    """The local +z axis (..., 3) of quaternions ``q`` (..., 4), not necessarily unit, in the
    world: ``scipy.spatial.transform.Rotation.from_quat(q).apply([0, 0, 1])`` to the bit —
    ``q`` normalised, then the third column of its rotation matrix, in scipy's order of
    operations (``tests/test_startup.py`` compares them) — without importing scipy. A zero
    quaternion is a ValueError, as there."""
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    norm = np.sqrt(x * x + y * y + z * z + w * w)
    if np.any(norm == 0):
        raise ValueError("Found zero norm quaternions in `quat`.")
    x, y, z, w = x / norm, y / norm, z / norm, w / norm
    return np.stack([2 * (x * z + y * w), 2 * (y * z - x * w), -x * x - y * y + z * z + w * w], axis=-1)


def rotate_inverse(q: np.ndarray, u: np.ndarray) -> np.ndarray:
    """Express world vectors ``u`` in the local frames ``q`` (``R^T u``)."""
    return rotate(conjugate(q), u)


def log(q: np.ndarray) -> np.ndarray:
    """Rotation vectors (..., 3) of unit quaternions, the angle ``2·atan2(|v|, w)``: taken
    along a sign-continuous sequence it runs past π instead of wrapping."""
    v = q[..., :3]
    s = np.linalg.norm(v, axis=-1, keepdims=True)
    angle = 2.0 * np.arctan2(s, q[..., 3:4])
    return np.where(s > 1e-12, v / np.maximum(s, 1e-12) * angle, 2.0 * v)


def exp(rv: np.ndarray) -> np.ndarray:
    """Unit quaternions (..., 4) of rotation vectors (..., 3)."""
    angle = np.linalg.norm(rv, axis=-1, keepdims=True)
    half = 0.5 * angle
    scale = np.where(angle > 1e-12, np.sin(half) / np.maximum(angle, 1e-12), 0.5)
    return np.concatenate([rv * scale, np.cos(half)], axis=-1)
