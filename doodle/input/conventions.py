"""Coordinate conventions: converting device poses into the project's frame and back.

Our frame (SPEC "Conventions"): right-handed, +y up, +z the performer's forward, +x the
performer's LEFT; quaternions scalar-last ``(x, y, z, w)``, world-from-body.

A convention is a fixed 3x3 basis change ``C`` (orthogonal, det +1 or -1) from its axes to
ours, applied to the world frame AND the body frame alike::

    p_ours = C p_theirs          R_ours = C R_theirs C^T

For an orthogonal ``C`` this maps the rotation about axis ``n`` by angle ``a`` to the rotation
about ``det(C) C n`` by the same angle, so on quaternions it is simply
``v' = det(C) C v`` (v the vector part) and ``w' = w``: unit length and sign continuity are
kept, and NaN rows (lost tracking) pass through as NaN.

Known conventions (:data:`CONVENTIONS`):

- ``doodle``: ours, identity.
- ``unity``: left-handed, +x right, +y up, +z forward: ``C = diag(-1, 1, 1)``
  (quaternions: ``(qx, -qy, -qz, qw)``).
- ``openvr``: right-handed, +x right, +y up, -z forward: ``C = diag(-1, 1, -1)``
  (quaternions: ``(-qx, qy, -qz, qw)``).
"""

from __future__ import annotations

import numpy as np

from doodle.core.errors import DoodleError

CONVENTIONS: dict[str, np.ndarray] = {
    "doodle": np.eye(3),
    "unity": np.diag([-1.0, 1.0, 1.0]),
    "openvr": np.diag([-1.0, 1.0, -1.0]),
}
for _c in CONVENTIONS.values():
    _c.setflags(write=False)


def convention_matrix(convention: str) -> np.ndarray:
    """The basis change ``C`` (theirs -> ours) of a named convention.

    Raises DoodleError for an unknown name, listing the known ones.
    """
    try:
        return CONVENTIONS[convention]
    except (KeyError, TypeError):
        known = ", ".join(sorted(CONVENTIONS))
        raise DoodleError(f"unknown coordinate convention {convention!r} (known: {known})") from None


def _apply(m: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``m @ v`` for every row vector of ``v`` (shape (..., 3)).

    A diagonal ``m`` multiplies elementwise, so a NaN in one component does not spread
    into the others.
    """
    if np.count_nonzero(m - np.diag(np.diag(m))) == 0:
        return v * np.diag(m)
    return v @ m.T


def _change(p, q, m: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    p = np.asarray(p, dtype=float)
    q = np.asarray(q, dtype=float)
    if p.shape[-1:] != (3,):
        raise DoodleError(f"positions must have shape (..., 3), got {p.shape}")
    if q.shape[-1:] != (4,):
        raise DoodleError(f"quaternions must have shape (..., 4), got {q.shape}")
    det = float(np.round(np.linalg.det(m)))
    q_out = np.empty_like(q)
    q_out[..., :3] = det * _apply(m, q[..., :3])
    q_out[..., 3] = q[..., 3]
    return _apply(m, p), q_out


def to_ours(p, q, convention: str) -> tuple[np.ndarray, np.ndarray]:
    """Convert positions ``p`` (..., 3) and quaternions ``q`` (..., 4, xyzw) given in
    ``convention`` into our frame. Returns new arrays ``(p, q)``; units are untouched.

    NaN values pass through as NaN. Raises DoodleError for an unknown convention or
    arrays of the wrong shape.
    """
    return _change(p, q, convention_matrix(convention))


def from_ours(p, q, convention: str) -> tuple[np.ndarray, np.ndarray]:
    """Inverse of :func:`to_ours`: express our ``p`` (..., 3) and ``q`` (..., 4) in
    ``convention``. Raises DoodleError for an unknown convention or wrong shapes.
    """
    return _change(p, q, convention_matrix(convention).T)
