"""Smooth profiles shared by the performers, the effort generator and the animation stages, and
the fastest real movement they are held to."""

from __future__ import annotations

import numpy as np

ORIENTATION_LEVER = 0.1  # metres: position-scale / angle-scale ratio for tremor and noise
FASTEST = 12.0  # m/s: real hands and feet reach 10–12 (DeepMimic run 12.2, spinkick 11.1; Bandai dash 10.2)


def min_jerk(tau: np.ndarray) -> np.ndarray:
    """Minimum-jerk profile ``10τ³ − 15τ⁴ + 6τ⁵`` (Flash & Hogan 1985), τ clipped to [0, 1]."""
    tau = np.clip(np.asarray(tau, dtype=float), 0.0, 1.0)
    return tau**3 * (10.0 + tau * (-15.0 + 6.0 * tau))
