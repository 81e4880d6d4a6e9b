"""Local (moving-frame) velocities of a doodle (thesis §4.1.1, with SPEC's corrections).

For sample i with world-from-figurine rotation ``R_i`` and position ``p_i``:

* local linear velocity ``v_i = R_i^T (p_i - p_{i-1}) / dt_i`` (m/s, figurine axes);
* local angular velocity ``ω_i = log(q_{i-1}^{-1} q_i) / dt_i`` (rad/s, figurine axes) — the
  relative rotation's axis times its angle, from quaternions, never from Euler differences.

:func:`local_velocities` is the vectorised form; :func:`local_velocity` repeats the same
arithmetic on Python floats for one sample (the streaming Segmenter), bit for bit.
``math.atan2`` is used in both so no SIMD variant of ``arctan2`` can differ in the last bit.
"""

from __future__ import annotations

import math

import numpy as np

from doodle.core import quat


def _angles(s: np.ndarray, w: np.ndarray) -> np.ndarray:
    return 2.0 * np.fromiter(map(math.atan2, s.tolist(), w.tolist()), float, count=len(s))


def local_velocities(t: np.ndarray, p: np.ndarray, q: np.ndarray, rate: float) -> tuple[np.ndarray, np.ndarray]:
    """``(v, ω)``, each (n-1, 3), for samples 1..n-1 of unit, sign-continuous ``q``.

    A non-positive time step (possible only after smoothing wildly jittered clocks) falls
    back to the nominal ``1/rate``.
    """
    dt = t[1:] - t[:-1]
    dt = np.where(dt > 0, dt, 1.0 / rate)
    v = quat.rotate_inverse(q[1:], p[1:] - p[:-1]) / dt[:, None]
    r = quat.multiply(quat.conjugate(q[:-1]), q[1:])
    r = np.where(r[:, 3:4] < 0, -r, r)
    rx, ry, rz = r[:, 0], r[:, 1], r[:, 2]
    s = np.sqrt(rx * rx + ry * ry + rz * rz)
    safe = np.where(s > 0, s, 1.0)
    f = np.where(s > 0, _angles(s, r[:, 3]) / safe / dt, 0.0)
    w = r[:, :3] * f[:, None]
    return v, w


def local_velocity(prev: tuple, cur: tuple, rate: float) -> tuple[float, float, float, float, float, float]:
    """``(vx, vy, vz, ωx, ωy, ωz)`` between two samples ``(t, px, py, pz, qx, qy, qz, qw)``."""
    t0, px0, py0, pz0, ax, ay, az, aw = prev
    t1, px1, py1, pz1, bx, by, bz, bw = cur
    dt = t1 - t0
    if not dt > 0:
        dt = 1.0 / rate
    ux, uy, uz = px1 - px0, py1 - py0, pz1 - pz0
    # rotate (ux, uy, uz) by the conjugate of q_i, as quat.rotate does
    x, y, z, w = -bx, -by, -bz, bw
    tx = 2.0 * (y * uz - z * uy)
    ty = 2.0 * (z * ux - x * uz)
    tz = 2.0 * (x * uy - y * ux)
    vx = (ux + w * tx + (y * tz - z * ty)) / dt
    vy = (uy + w * ty + (z * tx - x * tz)) / dt
    vz = (uz + w * tz + (x * ty - y * tx)) / dt
    # r = conj(q_{i-1}) ⊗ q_i, as quat.multiply does
    ax, ay, az = -ax, -ay, -az
    rx = aw * bx + ax * bw + ay * bz - az * by
    ry = aw * by - ax * bz + ay * bw + az * bx
    rz = aw * bz + ax * by - ay * bx + az * bw
    rw = aw * bw - ax * bx - ay * by - az * bz
    if rw < 0:
        rx, ry, rz, rw = -rx, -ry, -rz, -rw
    s = math.sqrt(rx * rx + ry * ry + rz * rz)
    if s > 0:
        f = 2.0 * math.atan2(s, rw) / s / dt
        return vx, vy, vz, rx * f, ry * f, rz * f
    return vx, vy, vz, 0.0, 0.0, 0.0
