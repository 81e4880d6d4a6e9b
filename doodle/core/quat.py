"""Vectorised quaternion helpers, scalar-last ``(x, y, z, w)`` like scipy's Rotation.

Arithmetic is written out component by component in a fixed order, so the per-sample
(streaming) code in :mod:`doodle.input.segmenter` can repeat it with Python floats and get
bit-identical results. The conversions (:func:`compose`, :func:`as_matrix`,
:func:`from_matrix`, :func:`from_euler`, :func:`as_euler`, :func:`magnitude`,
:func:`as_rotvec`, :func:`slerp`, :func:`slerp_keys`) give scipy's ``Rotation`` and
``Slerp`` results (``tests/test_quat.py``) without importing scipy.spatial, whose import
alone takes about 0.4 s of a compile's start-up.
"""

from __future__ import annotations

import numpy as np


def normalise(q: np.ndarray) -> np.ndarray:
    """Unit quaternions: ``q`` (..., 4) divided by its norm."""
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    norm = np.sqrt(x * x + y * y + z * z + w * w)
    return q / norm[..., None]


def unit(q) -> np.ndarray:
    """``q`` (..., 4) as float, normalised as scipy's ``Rotation.from_quat`` does it (the
    same arithmetic); a zero quaternion is a ValueError, as there."""
    q = np.asarray(q, dtype=float)
    if not q.any(axis=-1).all():
        raise ValueError("Found zero norm quaternions in `quat`.")
    return normalise(q)


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
    q = unit(q)
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
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
    """Unit quaternions (..., 4) of rotation vectors (..., 3): scipy's ``from_rotvec`` (to
    an ulp)."""
    angle = np.linalg.norm(rv, axis=-1, keepdims=True)
    half = 0.5 * angle
    scale = np.where(angle > 1e-12, np.sin(half) / np.maximum(angle, 1e-12), 0.5)
    return np.concatenate([rv * scale, np.cos(half)], axis=-1)


def compose(*qs) -> np.ndarray:
    """The product ``q1 ⊗ q2 ⊗ …`` (the last rotation applied first) of quaternions
    (..., 4), broadcast, each normalised and the result normalised after each product:
    scipy's ``(Rotation.from_quat(q1) * Rotation.from_quat(q2) * …).as_quat()``."""
    out = unit(qs[0])
    for q in qs[1:]:
        out = normalise(multiply(out, unit(q)))
    return out


def magnitude(q) -> np.ndarray:
    """Rotation angles (...,) in [0, π] of quaternions (..., 4): scipy's ``magnitude()``."""
    q = unit(q)
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    return 2.0 * np.arctan2(np.sqrt(x * x + y * y + z * z), np.abs(w))


def as_rotvec(q) -> np.ndarray:
    """Rotation vectors (..., 3), angle in [0, π], of quaternions (..., 4): scipy's
    ``as_rotvec()``, :func:`log` of the representative scipy picks (w > 0; at w = 0 the
    first non-zero of x, y, z positive)."""
    q = unit(q)
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    flip = (w < 0) | ((w == 0) & ((x < 0) | ((x == 0) & ((y < 0) | ((y == 0) & (z < 0))))))
    return log(np.where(flip[..., None], -q, q))


def as_matrix(q) -> np.ndarray:
    """Rotation matrices (..., 3, 3) of quaternions (..., 4), normalised first: scipy's
    ``as_matrix()``, the same arithmetic."""
    q = unit(q)
    x, y, z, w = q[..., 0], q[..., 1], q[..., 2], q[..., 3]
    x2, y2, z2, w2 = x * x, y * y, z * z, w * w
    xy, zw, xz, yw, yz, xw = x * y, z * w, x * z, y * w, y * z, x * w
    m = np.empty(q.shape[:-1] + (3, 3))
    m[..., 0, 0] = x2 - y2 - z2 + w2
    m[..., 1, 0] = 2 * (xy + zw)
    m[..., 2, 0] = 2 * (xz - yw)
    m[..., 0, 1] = 2 * (xy - zw)
    m[..., 1, 1] = -x2 + y2 - z2 + w2
    m[..., 2, 1] = 2 * (yz + xw)
    m[..., 0, 2] = 2 * (xz + yw)
    m[..., 1, 2] = 2 * (yz - xw)
    m[..., 2, 2] = -x2 - y2 + z2 + w2
    return m


def from_matrix(m) -> np.ndarray:
    """Unit quaternions (..., 4) of rotation matrices (..., 3, 3): scipy's ``from_matrix``
    — a matrix that is not orthogonal (Gram matrix off the identity by more than 1e-12)
    replaced by the nearest rotation (SVD), then the largest of the trace and the diagonal
    chooses the formula. A determinant ≤ 0 is a ValueError."""
    m = np.array(m, dtype=float)
    shape = m.shape[:-2]
    m = m.reshape(-1, 3, 3)
    if np.any(np.linalg.det(m) <= 0):
        raise ValueError("Non-positive determinant (left-handed or null coordinate frame) in rotation matrix.")
    eye = np.eye(3)
    bent = (np.abs(m @ np.transpose(m, (0, 2, 1)) - eye) > 1e-12 + 1e-5 * eye).any(axis=(1, 2))  # np.isclose's test
    if bent.any():
        u, _, vt = np.linalg.svd(m[bent])
        m[bent] = u @ vt
    mt = np.transpose(m, (0, 2, 1))
    sym, skew = m + mt, m - mt
    diagonal = np.arange(3)
    trace = m[:, 0, 0] + m[:, 1, 1] + m[:, 2, 2]
    vector = np.stack([skew[:, 2, 1], skew[:, 0, 2], skew[:, 1, 0]], axis=1)
    candidates = np.empty((len(m), 4, 4))  # row i: the formula when m[i, i] is the largest, row 3: the trace
    candidates[:, :3, :3] = sym
    candidates[:, diagonal, diagonal] += (1 - trace)[:, None]
    candidates[:, :3, 3] = vector
    candidates[:, 3, :3] = vector
    candidates[:, 3, 3] = 1 + trace
    choice = np.argmax(np.concatenate([m[:, diagonal, diagonal], trace[:, None]], axis=1), axis=1)
    return normalise(candidates[np.arange(len(m)), choice]).reshape(shape + (4,))


_AXIS = {"X": 0, "Y": 1, "Z": 2}


def _axes(order: str, lengths: tuple) -> list[int]:
    if len(order) not in lengths or any(c not in _AXIS for c in order):
        raise ValueError(f"expected an intrinsic order of {' or '.join(map(str, lengths))} axes "
                         f"from X, Y, Z (e.g. 'ZXY'), got {order!r}")
    return [_AXIS[c] for c in order]


def from_euler(order: str, angles, degrees: bool = False) -> np.ndarray:
    """Quaternions (..., 4) of intrinsic rotations about the axes of ``order`` (1 to 3 of
    "X", "Y", "Z"; "ZXY": R = Rz(a)·Rx(b)·Ry(c)) by ``angles`` (..., len(order)): the
    rotations of scipy's ``Rotation.from_euler(order, angles, degrees)``."""
    axes = _axes(order, (1, 2, 3))
    angles = np.asarray(angles, dtype=float)
    half = (np.radians(angles) if degrees else angles) * 0.5
    sin, cos = np.sin(half), np.cos(half)
    q = np.zeros(angles.shape[:-1] + (4,))
    q[..., axes[0]] = sin[..., 0]
    q[..., 3] = cos[..., 0]
    for n in range(1, len(axes)):
        # q ← q ⊗ (sin·axis, cos): the Hamilton product with an elementary rotation
        a = axes[n]
        b, c = (a + 1) % 3, (a + 2) % 3
        s, co = sin[..., n], cos[..., n]
        x = q.copy()
        q[..., a] = x[..., a] * co + x[..., 3] * s
        q[..., b] = x[..., b] * co + x[..., c] * s
        q[..., c] = x[..., c] * co - x[..., b] * s
        q[..., 3] = x[..., 3] * co - x[..., a] * s
    return q


def as_euler(q, order: str, degrees: bool = False) -> np.ndarray:
    """Intrinsic Euler angles (..., 3) in ``order`` (three different axes, e.g. "ZXY") of
    quaternions (..., 4) of any length but zero: scipy's ``as_euler(order, degrees)`` with
    its branches (Bernardes & Viollet 2022) — angles in [-π, π], the middle one in
    [-π/2, π/2]; at gimbal lock (middle angle within 1e-7 rad of ±π/2) the last angle is 0
    and the first carries the turn — without its warning."""
    axes = _axes(order, (3,))
    if len(set(axes)) != 3:
        raise ValueError(f"expected three different axes, got {order!r}")
    q = np.asarray(q, dtype=float)
    k, j, i = axes  # the paper's extrinsic sequence: the intrinsic one reversed
    odd = (i - j) * (j - k) * (k - i) < 0
    qt = q.reshape(-1, 4).T
    w, qi, qj, qk = qt[3], qt[i], qt[j], qt[k]
    if odd:
        qk = -qk
    a, b, c, d = w - qj, qi + qk, qj + w, qk - qi  # the angles depend on their ratios only: no normalising
    ab, cd = np.sqrt(a * a + b * b), np.sqrt(c * c + d * d)  # hypots (np.hypot is 7× slower)
    if not (ab + cd).all():
        raise ValueError("Found zero norm quaternions in `quat`.")
    out = np.empty((3, len(w)))  # one row per angle: contiguous work
    first, middle, last = out
    np.arctan2(cd, ab, out=middle)
    middle *= 2
    half_sum, half_diff = np.arctan2(b, a), np.arctan2(d, c)
    np.add(half_sum, half_diff, out=first)
    np.subtract(half_sum, half_diff, out=last)
    zero = np.abs(middle) <= 1e-7
    locked = zero | (np.abs(middle - np.pi) <= 1e-7)
    if locked.any():
        first[locked] = 2 * np.where(zero, half_sum, half_diff)[locked]
        last[locked] = 0.0
    if odd:
        np.negative(first, out=first)
    middle -= np.pi / 2
    ends = out[::2]
    np.add(ends, 2 * np.pi, out=ends, where=ends < -np.pi)
    np.subtract(ends, 2 * np.pi, out=ends, where=ends > np.pi)
    if degrees:
        np.rad2deg(out, out=out)
    return np.ascontiguousarray(out.T).reshape(q.shape[:-1] + (3,))


def slerp(a, b, w) -> np.ndarray:
    """Rotations (..., 4) the fraction ``w`` (...,) of the way from ``a`` to ``b`` (..., 4,
    broadcast) along the shorter arc, at constant angular speed: ``a ⊗ exp(w·log(a⁻¹ ⊗ b))``,
    as scipy's ``Slerp`` computes it between two keys."""
    a, b = unit(a), unit(b)
    step = as_rotvec(normalise(multiply(conjugate(a), b)))
    return normalise(multiply(a, exp(step * np.asarray(w, dtype=float)[..., None])))


def slerp_keys(times, q, new_times) -> np.ndarray:
    """Rotations at ``new_times`` (T,) slerped between keyed rotations ``q`` (K, ..., 4) at
    strictly increasing ``times`` (K,), K ≥ 2 — several sequences at once along the middle
    axes: scipy's ``Slerp(times, Rotation.from_quat(q))(new_times).as_quat()`` per
    sequence. A time outside ``times`` is a ValueError."""
    times = np.asarray(times, dtype=float)
    new_times = np.asarray(new_times, dtype=float)
    q = np.asarray(q, dtype=float)
    if times.ndim != 1 or len(times) < 2 or len(times) != len(q):
        raise ValueError("expected at least two keys, one time per key")
    delta = np.diff(times)
    if np.any(delta <= 0):
        raise ValueError("Times must be in strictly increasing order.")
    if np.any((new_times < times[0]) | (new_times > times[-1])):
        raise ValueError(f"Interpolation times must be within [{times[0]}, {times[-1]}], both inclusive.")
    ind = np.maximum(np.searchsorted(times, new_times) - 1, 0)
    alpha = (new_times - times[ind]) / delta[ind]
    return slerp(q[ind], q[ind + 1], alpha.reshape(alpha.shape + (1,) * (q.ndim - 2)))
