"""The Time and Weight signatures of a clip (thesis §5.4.3, Figs. 5.13–5.16), measured.

All measures are taken on one end effector — the clip's *most moving* hand or foot: the one
whose path (world positions) is the longest over the clip — resampled at :data:`RATE` by a
cubic spline and low-passed over :data:`SMOOTH` seconds, so a 30 fps clip and its 120 fps
stylisation compare:

* **peak speed** (m/s): the effector's highest speed;
* **execution** (s): the length of its main burst — the frames around the peak speed where its
  speed stays at or above half the peak (full width at half maximum);
* **extent** (m): the diameter of its path — the largest distance between two of its positions
  over the clip;
* **impact sharpness** (m/s²): how hard it stops — the fastest fall of its speed between the
  peak and the next minimum of speed (the stop that ends the strike, the bow, the wave).

The thesis's figures show these signatures qualitatively: Sudden — a short, fast execution
(after a longer anticipation); Sustained — a longer, slower, even one; Strong — a wider
movement and a sharper impact; Light — a narrower, softer one. :func:`shows` says whether a
styled clip shows its quality's signature against its neutral clip.

**Fastest joint**: no joint of a stylised clip should move faster than the fastest hands and
feet of real motion capture (:data:`FASTEST`, calibrated by ``python -m bench.stylize_signatures``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from doodle.core.filters import gaussian_filter1d
from doodle.core.profiles import FASTEST  # noqa: F401 (the animation stages read it from here)
from doodle.core.splines import CubicSpline
from retarget.analysis import guess_roles
from retarget.skeleton import Motion, forward_kinematics

RATE = 120.0  # Hz: effector paths are compared at this rate
SMOOTH = 1 / 30  # s: ... low-passed over this much time (one frame of a 30 fps clip)
HALF = 0.5  # the execution burst: speed at least this share of the peak
END_ROLES = ("right_hand", "left_hand", "right_foot", "left_foot")


@dataclass(frozen=True)
class Signature:
    """One clip's measures on ``effector`` (a joint index)."""

    effector: int
    peak_speed: float  # m/s
    execution: float  # s
    extent: float  # m
    sharpness: float  # m/s²
    fastest: float  # m/s: the fastest joint between two frames (any joint)

    def ratios(self, neutral: "Signature") -> dict:
        """Each measure relative to the neutral clip's."""
        return {k: getattr(self, k) / max(getattr(neutral, k), 1e-9)
                for k in ("peak_speed", "execution", "extent", "sharpness")}


def effector_path(motion: Motion, joint: int, world: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(times, positions) of the joint resampled at :data:`RATE` and smoothed over :data:`SMOOTH`."""
    p = (forward_kinematics(motion)[0] if world is None else world)[:, joint]
    t = np.arange(motion.frames) * motion.frame_time
    tt = np.arange(0.0, t[-1] + 1e-9, 1.0 / RATE)
    return tt, gaussian_filter1d(CubicSpline(t, p)(tt), SMOOTH * RATE, axis=0, mode="nearest")


def speed_profile(motion: Motion, joint: int, world: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(times, speeds) of the joint, as :func:`effector_path` samples it."""
    tt, p = effector_path(motion, joint, world)
    return tt, np.linalg.norm(np.gradient(p, tt, axis=0), axis=1)


def most_moving(motion: Motion, world: np.ndarray | None = None) -> int:
    """The hand or foot whose path is the longest over the clip."""
    world = forward_kinematics(motion)[0] if world is None else world
    roles = guess_roles(motion.skeleton)
    ends = [roles[k] for k in END_ROLES if k in roles] or [len(motion.skeleton) - 1]
    return max(ends, key=lambda j: float(np.linalg.norm(np.diff(world[:, j], axis=0), axis=1).sum()))


def burst(speed: np.ndarray, share: float = HALF) -> tuple[int, int, int]:
    """(start, peak, end) samples of the main burst: around the peak, speed ≥ ``share`` of it."""
    k = int(np.argmax(speed))
    low = speed < share * speed[k]
    before, after = np.flatnonzero(low[:k]), np.flatnonzero(low[k:])
    return (int(before[-1]) + 1 if len(before) else 0), k, (k + int(after[0]) if len(after) else len(speed))


def impact_sharpness(tt: np.ndarray, speed: np.ndarray) -> float:
    """The fastest fall of speed (m/s²) from the peak to the next minimum of speed."""
    k = int(np.argmax(speed))
    acc = np.gradient(speed, tt)
    rising = np.flatnonzero(acc[k + 1:] >= 0)
    stop = k + 1 + int(rising[0]) if len(rising) else len(speed)
    return float(max(-acc[k:stop].min(), 0.0)) if stop > k else 0.0


def extent(points: np.ndarray, most: int = 400) -> float:
    """The diameter of a path (the largest distance between two of its points)."""
    step = max(1, int(np.ceil(len(points) / most)))
    p = points[::step]
    return float(np.sqrt(((p[:, None] - p[None]) ** 2).sum(axis=-1).max()))


def fastest_joint(motion: Motion, world: np.ndarray | None = None) -> float:
    """The fastest any joint moves between two frames (m/s)."""
    world = forward_kinematics(motion)[0] if world is None else world
    if motion.frames < 2:
        return 0.0
    return float(np.linalg.norm(np.diff(world, axis=0), axis=2).max() / motion.frame_time)


def signature(motion: Motion, effector: int | None = None) -> Signature:
    """The clip's measures on ``effector`` (default: its most moving hand or foot)."""
    world = forward_kinematics(motion)[0]
    j = most_moving(motion, world) if effector is None else effector
    tt, p = effector_path(motion, j, world)
    speed = np.linalg.norm(np.gradient(p, tt, axis=0), axis=1)
    a, _, b = burst(speed)
    return Signature(j, float(speed.max()), (b - a) / RATE, extent(p), impact_sharpness(tt, speed),
                     fastest_joint(motion, world))


# What each quality's signature is, as the thesis's figures show it: measure -> direction
# against the neutral clip (+1 more, -1 less).
SIGNATURES = {
    "sudden": {"peak_speed": +1, "execution": -1},
    "sustained": {"peak_speed": -1, "execution": +1},
    "strong": {"extent": +1, "sharpness": +1},
    "light": {"extent": -1, "sharpness": -1},
}
THESIS = {
    "sudden": "short, fast execution after a longer anticipation; accelerates into it",
    "sustained": "long, slow, even execution; anticipation shorter",
    "strong": "wider movement, larger speed variation, sharp impact; body sinks",
    "light": "narrower movement, uniform speed, soft ending; body rises",
}


def quality(lt: float, lw: float) -> str:
    """The quality a single modifier gives (Time or Weight at a time)."""
    if lt:
        return "sudden" if lt > 0 else "sustained"
    return "strong" if lw > 0 else "light"


def shows(neutral: Signature, styled: Signature, name: str, bound: float = FASTEST) -> bool:
    """Whether ``styled`` shows the signature of quality ``name`` against ``neutral`` — every
    measure of it moved the right way — with no joint faster than ``bound``."""
    r = styled.ratios(neutral)
    return all((r[k] > 1.0) if d > 0 else (r[k] < 1.0) for k, d in SIGNATURES[name].items()) and \
        styled.fastest <= bound
