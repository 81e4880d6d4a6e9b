"""The prop's up from gravity: a tilt in the hand does not change what a motion means.

A person rarely holds a figurine perfectly upright; held 15° tilted, a forward glide has a
quarter of its speed along the figurine's own up or down axis, and a jump's rise reads as
"up and forward". Whenever the prop rests, the world's up tells where the figurine's up
is: ``u = R^T ŷ`` in its own axes. Until the next rest, directions are read in the frame
``R·C`` where ``C`` is the smallest rotation taking ``ŷ`` to ``u`` — the figurine stood
upright again, its heading kept — the calibration step done implicitly at every rest.
A rest tilted further than the cap (a figurine laid down, a controller pointed at the
floor) is taken as meant and leaves the frame as it is (``C`` = identity).

:func:`level` and :func:`unrotate` use only ``+ − × ÷`` and a square root, so the same
function gives bit-identical results on numpy arrays (batch) and on Python floats (stream).
"""

from __future__ import annotations

import math

import numpy as np

IDENTITY = (0.0, 0.0, 0.0, 1.0)


def level(qx, qy, qz, qw, cos_cap: float):
    """``C = (cx, cy, cz, cw)`` standing a figurine of orientation ``q`` upright, and
    whether the tilt is within the cap (``cos(tilt) ≥ cos_cap``); works elementwise."""
    # u = R^T ŷ: the world's up in the figurine's axes (second row of R)
    ux = 2.0 * (qx * qy + qz * qw)
    uy = 1.0 - 2.0 * (qx * qx + qz * qz)
    uz = 2.0 * (qy * qz - qx * qw)
    # rotation from ŷ to u: axis ŷ × u = (uz, 0, −ux), quaternion (ŷ × u, 1 + ŷ·u) normalised
    w = 1.0 + uy
    if isinstance(w, np.ndarray):
        norm = np.sqrt(uz * uz + ux * ux + w * w)
    else:
        norm = math.sqrt(uz * uz + ux * ux + w * w)
    return (uz / norm, 0.0 * ux, -ux / norm, w / norm), uy >= cos_cap


def unrotate(cx, cy, cz, cw, ux, uy, uz):
    """``C^T u`` (u expressed in the frame turned by C), elementwise; as :func:`doodle.core.quat.rotate`
    with the conjugate quaternion, operation for operation."""
    x, y, z, w = -cx, -cy, -cz, cw
    tx = 2.0 * (y * uz - z * uy)
    ty = 2.0 * (z * ux - x * uz)
    tz = 2.0 * (x * uy - y * ux)
    return ux + w * tx + (y * tz - z * ty), uy + w * ty + (z * tx - x * tz), uz + w * tz + (x * ty - y * tx)


def resting(still: np.ndarray, alpha: int) -> np.ndarray:
    """Samples that end a run of at least ``alpha`` still samples."""
    idx = np.arange(len(still))
    last_moving = np.maximum.accumulate(np.where(still, -1, idx))
    return still & (idx - last_moving >= alpha)


def levels(q: np.ndarray, still: np.ndarray, alpha: int, cos_cap: float) -> np.ndarray:
    """Per sample, the levelling ``C`` (n, 4) from the latest resting sample *before* it
    (identity before the first rest, or where that rest was tilted past the cap)."""
    n = len(still)
    out = np.tile(np.array(IDENTITY), (n, 1))
    if n == 0:
        return out
    rest = resting(still, alpha)
    idx = np.arange(n)
    latest = np.maximum.accumulate(np.where(rest, idx, -1))
    before = np.concatenate([[-1], latest[:-1]])
    has = before >= 0
    src = q[before[has]]
    c, ok = level(src[:, 0], src[:, 1], src[:, 2], src[:, 3], cos_cap)
    cq = np.column_stack([c[0], np.zeros(len(src)), c[2], c[3]])
    cq[~ok] = IDENTITY
    out[has] = cq
    return out
