"""Calibration of the Segmenter's thresholds θ and ε from three gestures (thesis §4.2.2).

The thesis asks the user for a minimal translation-only gesture, a minimal rotation-only
gesture and their slowest deliberate motion, and sets

* ``θ = min ‖v‖ / min ‖ω‖`` over the translation and the rotation gesture, and
* ``ε = min ‖(v, ω)‖`` over the slow gesture.

A plain minimum picks up the instants where the hand starts and stops (speed zero), so the
minima here are taken over the *moving* part of each gesture: samples whose speed is at
least a quarter of that gesture's peak, then a low percentile (10 %) rather than the single
lowest sample — the same idea, robust to one noisy sample. ε uses θ's exchange rate
(``‖(v, θω)‖``) like the Segmenter, and is set to half of the slow gesture's low percentile so
that the slowest deliberate motion is still recognised as motion.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from doodle.core.errors import DoodleError
from doodle.input.frame import local_velocities
from doodle.core.model import Track
from doodle.input.segmenter import SegmenterParams, smoothed_track


def _moving_low(speed: np.ndarray, what: str, name: str) -> float:
    peak = float(speed.max()) if len(speed) else 0.0
    if not peak > 0:
        raise DoodleError(f"calibration: the {what} gesture (track {name}) does not move")
    moving = speed[speed >= 0.25 * peak]
    return float(np.percentile(moving, 10))


def _velocities(track: Track, rate: float, params: SegmenterParams):
    rows = smoothed_track(track, rate, params, f"calibration {track.name}")
    v, w = local_velocities(rows[:, 0], rows[:, 1:4], rows[:, 4:], rate)
    return np.linalg.norm(v, axis=1), np.linalg.norm(w, axis=1)


def calibrate(translation: Track, rotation: Track, slow: Track, rate: float,
              params: SegmenterParams = SegmenterParams()) -> SegmenterParams:
    """Segmenter parameters with θ and ε measured from the three calibration gestures."""
    v_t, _ = _velocities(translation, rate, params)
    _, w_r = _velocities(rotation, rate, params)
    theta = _moving_low(v_t, "translation", translation.name) / _moving_low(w_r, "rotation", rotation.name)
    v_s, w_s = _velocities(slow, rate, params)
    eps = 0.5 * _moving_low(np.sqrt(v_s**2 + (theta * w_s) ** 2), "slow", slow.name)
    return replace(params, theta=theta, eps=eps)
