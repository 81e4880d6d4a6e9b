"""Performers who move a prop differently: the style grid recognition is measured on.

:mod:`doodle.synth.strokes` plays one token per stroke, each stroke starting and stopping at rest —
the way the recogniser was built, so it reads those back every time. People do not move
like that. This module renders *gestures* as a person plays them with a figurine: each
gesture is a few **movements** (a movement ends where the hand stops, e.g. where it
reverses); a movement passes through its waypoints in one smooth motion, its corners
rounded, slowing where the path bends (the two-thirds power law, Lacquaniti, Terzuolo &
Viviani 1983) inside a bell-shaped speed profile over the whole movement (minimum jerk over
the power-law time, Flash & Hogan 1985; Viviani & Flash 1995). On top of that, a
:class:`Style` varies what differs between people and devices:

* ``size`` (the movement's extent ×0.5–×2) and ``tempo`` (its durations ×0.6–×1.6);
* ``pause`` between actions (0.15–0.8 s), or ``0`` for continuous flow from one action
  into the next (the hand never rests);
* ``rate``: the device's sample rate (90, 120, 144 Hz);
* ``tilt``: the prop held tilted in the hand (degrees, about a random horizontal axis);
* ``wobble``: a slow (0.3–0.8 Hz) wobble of the hand about random axes (degrees; a third of
  it while resting, when the figurine sits on the table);
* ``jitter``: white tracking noise on position (m std; orientation ``jitter/0.1`` rad);
* ``bob``: walks bobbed up and down by this height per step (m, a step every 7.5 cm × size);
* ``arc``: how a jump is drawn, from 0 "straight up, over, down" to 1 "forward through the
  top" (a parabola).

Gestures are in the figurine's frame (+x LEFT, +y UP, +z FRONT) in units of 10 cm × size;
the built-in actions' gestures (:data:`GESTURES`) were written from what the actions are —
how one would play a kick, a greeting, a pick-up with a toy — following the direction
groups their expressions require. :func:`perform` renders a list of action names as a
one-track :class:`~doodle.core.model.Doodle`; everything is seeded.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields, replace

import numpy as np

from doodle.core import quat
from doodle.core.model import Doodle, Track
from doodle.core.profiles import min_jerk

UNIT = 0.1  # metres per gesture unit at size 1
STEP = 0.075  # metres travelled per step of a bobbed walk at size 1


@dataclass(frozen=True)
class Style:
    """How one performer moves (see the module docstring for each field)."""

    size: float = 1.0
    tempo: float = 1.0
    pause: float = 0.4
    rate: float = 90.0
    tilt: float = 0.0
    wobble: float = 0.0
    jitter: float = 0.0005
    bob: float = 0.0
    arc: float = 0.5

    def label(self) -> str:
        """What differs from the default style, e.g. ``size×2 tilt 15°``."""
        base, parts = Style(), []
        units = {"size": "×", "tempo": "×"}
        for f in fields(self):
            value = getattr(self, f.name)
            if value == getattr(base, f.name):
                continue
            if f.name in units:
                parts.append(f"{f.name}{units[f.name]}{value:g}")
            elif f.name in ("tilt", "wobble"):
                parts.append(f"{f.name} {value:g}°")
            elif f.name in ("jitter", "bob"):
                parts.append(f"{f.name} {value * 1000:g} mm")
            elif f.name == "rate":
                parts.append(f"{value:g} Hz")
            elif f.name == "pause":
                parts.append("flow" if value == 0 else f"pause {value:g} s")
            else:
                parts.append(f"{f.name} {value:g}")
        return " ".join(parts) or "default"


def style_grid() -> list[Style]:
    """One style per varied factor and value, the others at their defaults, plus a few
    performers who combine several (the grid of the recognition benchmark)."""
    axes = {
        "size": (0.5, 0.7, 1.4, 2.0),
        "tempo": (0.6, 0.8, 1.3, 1.6),
        "pause": (0.0, 0.15, 0.25, 0.8),
        "rate": (60.0, 120.0, 144.0),
        "tilt": (10.0, 15.0, 20.0),
        "wobble": (2.0, 3.5, 5.0),
        "jitter": (0.0003, 0.001),
        "bob": (0.004, 0.007, 0.01),
        "arc": (0.0, 0.25, 0.75, 1.0),
    }
    grid = [Style()] + [replace(Style(), **{k: v}) for k, values in axes.items() for v in values]
    grid += [
        Style(size=2.0, tempo=1.6, tilt=15.0, wobble=3.0, jitter=0.001, bob=0.007, arc=1.0),
        Style(size=0.5, tempo=0.6, pause=0.15, rate=144.0, tilt=20.0, wobble=2.0, bob=0.004, arc=0.0),
        Style(size=1.4, tempo=1.3, pause=0.0, rate=120.0, tilt=10.0, wobble=5.0, jitter=0.001, bob=0.01, arc=0.75),
    ]
    return grid


# --- gestures -----------------------------------------------------------------------------

@dataclass(frozen=True)
class Gesture:
    """One action as played: movements (waypoint lists from the gesture's start, in units),
    their durations (s at tempo 1), and whether the hand bobs along them (a walk)."""

    movements: tuple
    durations: tuple
    walk: bool = False


def _g(durations, *movements, walk=False) -> Gesture:
    if movements and isinstance(movements[0], str):  # a drawn arc: "jump" or "flip"
        return Gesture(movements, tuple(durations), walk)
    return Gesture(tuple(tuple(tuple(float(c) for c in p) for p in m) for m in movements), tuple(durations), walk)


O = (0, 0, 0)

GESTURES: dict[str, Gesture] = {
    "Idle": _g((), ),
    "Walk": _g((1.4,), (O, (0, 0, 1.5)), walk=True),
    "Walk Back": _g((1.3,), (O, (0, 0, -1.2)), walk=True),
    "Side Walk Left": _g((1.2,), (O, (1.2, 0, 0)), walk=True),
    "Side Walk Right": _g((1.2,), (O, (-1.2, 0, 0)), walk=True),
    "Jump": _g((0.9,), "jump"),
    "Stomp": _g((0.35, 0.22), (O, (0, 0.6, 0)), ((0, 0.6, 0), O)),
    "Punch": _g((0.3, 0.22, 0.3), (O, (0, 0, -0.4)), ((0, 0, -0.4), (0, 0, 0.6)), ((0, 0, 0.6), O)),
    "Kick": _g((0.3, 0.4, 0.4), (O, (0, 0, -0.4)), ((0, 0, -0.4), (0, 0, 0.2), (0, 0.5, 0.6)),
               ((0, 0.5, 0.6), (0, 0.1, 0.55), O)),
    "Block": _g((0.35, 0.35), (O, (-0.4, 0.4, 0)), ((-0.4, 0.4, 0), O)),
    "Raise One Arm": _g((0.35, 0.35), (O, (0.5, 0, 0)), ((0.5, 0, 0), O)),
    "Raise Arms": _g((0.3, 0.3, 0.3, 0.3), (O, (0, 0.5, 0)), ((0, 0.5, 0), O), (O, (0, 0.5, 0)), ((0, 0.5, 0), O)),
    "Despair": _g((0.8,), (O, (0, -0.5, 0))),
    "Get Angry": _g((0.25, 0.3, 0.25), (O, (-0.35, 0, 0)), ((-0.35, 0, 0), (0.35, 0, 0)), ((0.35, 0, 0), O)),
    "Dodge": _g((0.3, 0.3, 0.3, 0.3), (O, (0.35, 0.35, 0)), ((0.35, 0.35, 0), (0, 0.7, 0)),
                ((0, 0.7, 0), (-0.35, 0.35, 0)), ((-0.35, 0.35, 0), O)),
    "Dismiss": _g((0.25, 0.25, 0.25, 0.25), (O, (0, 0, 0.4)), ((0, 0, 0.4), O), (O, (0, 0, 0.4)), ((0, 0, 0.4), O)),
    "Duck": _g((0.3, 0.35, 0.35), (O, (0, 0.3, 0)), ((0, 0.3, 0), (0, -0.3, 0)), ((0, -0.3, 0), (0.4, -0.3, 0))),
    "Cast Fireball": _g((0.3, 0.55), (O, (0, 0, -0.4)), ((0, 0, -0.4), (0, 0.35, -0.4), (0, 0.45, 0.1), (0, 0.2, 0.6))),
    "Back Flip": _g((0.5, 0.8), (O, (0, 0.5, 0), (0, 0.7, -0.3), (0, 0.7, -0.6)),
                    ((0, 0.7, -0.6), (0, 1.2, -0.6), (0, 1.4, -0.9), (0, 1.4, -1.2), (0, 1.1, -1.5), (0, 0, -1.5))),
    "Flip": _g((1.0,), (O, (0, 0.4, -0.3), (0, 0.9, -0.1), (0, 1.0, 0.3), (0, 0.6, 0.6), (0, 0, 0.6))),
    "Yell": _g((0.18,) * 6, (O, (0, 0.3, 0)), ((0, 0.3, 0), O), (O, (0, 0.3, 0)), ((0, 0.3, 0), O),
               (O, (0, 0.3, 0)), ((0, 0.3, 0), O)),
    "Uppercut Jab": _g((0.5, 0.3, 0.6, 0.2), (O, (0, 0, 0.3), (0, 0.3, 0.6), (0, 0.6, 0.6), (0, 0.8, 0.3)),
                       ((0, 0.8, 0.3), (0, 0.1, 0.3)),
                       ((0, 0.1, 0.3), (0, 0.5, 0.3), (0, 0.7, 0), (0, 0.7, -0.3), (0, 0.4, -0.6), (0, 0, -0.6)),
                       ((0, 0, -0.6), (0, 0.3, -0.6))),
    "Stop": _g((0.3, 0.3, 0.3, 0.3), (O, (0, 0, -0.3)), ((0, 0, -0.3), (0, 0, 0.3)), ((0, 0, 0.3), (0, 0.4, 0.3)),
               ((0, 0.4, 0.3), (0, 0, 0.3))),
    "Crescent Kick": _g((0.5, 0.3, 0.35), (O, (-0.4, 0, 0), (-0.7, 0.35, 0)), ((-0.7, 0.35, 0), (-0.7, -0.1, 0)),
                        ((-0.7, -0.1, 0), (0, -0.1, 0))),
    "Pick up": _g((0.7, 0.3, 0.35), (O, (0, 0.3, 0), (0, 0.3, 0.3), (0, 0, 0.6), (0, -0.4, 0.6)),
                  ((0, -0.4, 0.6), (0, 0, 0.6)), ((0, 0, 0.6), O)),
    "Greet": _g((0.3, 0.25, 0.3, 0.3), (O, (0, 0.4, 0)), ((0, 0.4, 0), (-0.3, 0.4, 0)), ((-0.3, 0.4, 0), (0.3, 0.4, 0)),
                ((0.3, 0.4, 0), (0.3, 0, 0))),
    "Throw": _g((0.5, 0.3, 0.3), (O, (0, 0.4, 0), (0, 0.4, 0.5)), ((0, 0.4, 0.5), (0, 0.4, 0)), ((0, 0.4, 0), O)),
    "Dance": _g((0.3,) * 8, (O, (0, 0.4, 0)), ((0, 0.4, 0), (0, 0.4, 0.4)), ((0, 0.4, 0.4), (0, 0.4, 0)),
                ((0, 0.4, 0), (0.4, 0.4, 0)), ((0.4, 0.4, 0), (-0.4, 0.4, 0)), ((-0.4, 0.4, 0), (0.4, 0.4, 0)),
                ((0.4, 0.4, 0), (0.4, 0.8, 0)), ((0.4, 0.8, 0), (0.4, 0.0, 0))),
}

MAIN_EXAMPLE = ("Idle", "Side Walk Left", "Walk", "Jump", "Walk", "Stomp", "Idle")  # thesis Fig. 4.7


def _jump_path(arc: float, length: float = 0.6, height: float = 0.5, points: int = 41) -> np.ndarray:
    """Waypoints of a forward jump: ``arc`` 0 is up, over, down; 1 a parabola."""
    u = np.linspace(0.0, 1.0, points)
    parabola = np.column_stack([0 * u, 4 * height * u * (1 - u), length * u])
    # the box path: up (first 30 % of u), over (40 %), down (30 %)
    up, over = np.clip(u / 0.3, 0, 1), np.clip((u - 0.3) / 0.4, 0, 1)
    down = np.clip((u - 0.7) / 0.3, 0, 1)
    box = np.column_stack([0 * u, height * (up - down), length * over])
    return (1 - arc) * box + arc * parabola


# --- rendering ----------------------------------------------------------------------------

def _round_corners(points: np.ndarray, roundness: float = 0.25, dense: int = 200) -> np.ndarray:
    """The polyline through ``points`` sampled densely by arc length, corners rounded by a
    Gaussian of ``roundness`` × the shortest leg (ends kept in place)."""
    legs = np.linalg.norm(np.diff(points, axis=0), axis=1)
    s = np.concatenate([[0.0], np.cumsum(legs)])
    if s[-1] <= 0:
        return np.repeat(points[:1], dense, axis=0)
    u = np.linspace(0.0, s[-1], dense)
    path = np.column_stack([np.interp(u, s, points[:, k]) for k in range(3)])
    short = legs[legs > 1e-9].min() if len(points) > 2 else 0.0
    sigma = roundness * short / (s[-1] / (dense - 1))
    if sigma >= 1.0:
        r = int(3 * sigma)
        kernel = np.exp(-0.5 * (np.arange(-r, r + 1) / sigma) ** 2)
        kernel /= kernel.sum()
        padded = np.concatenate([2 * path[:1] - path[r:0:-1], path, 2 * path[-1:] - path[-2:-r - 2:-1]])
        path = np.column_stack([np.convolve(padded[:, k], kernel, mode="valid") for k in range(3)])
    return path


def _movement_timing(path: np.ndarray, tau: np.ndarray) -> np.ndarray:
    """Positions along a dense path at normalised times ``tau``: minimum jerk over a time
    that runs slower where the path bends (speed ∝ curvature^(−1/3))."""
    d = np.diff(path, axis=0)
    ds = np.linalg.norm(d, axis=1)
    total = ds.sum()
    if total <= 0:
        return np.repeat(path[:1], len(tau), axis=0)
    turn = np.zeros(len(ds))
    unit = d / np.maximum(ds[:, None], 1e-12)
    turn[1:] = np.arccos(np.clip(np.einsum("ij,ij->i", unit[1:], unit[:-1]), -1, 1))
    curvature = turn / np.maximum(ds, 1e-12)
    weight = ds * (curvature + 2.0 / total) ** (1.0 / 3.0)  # time per step under the power law
    w = np.concatenate([[0.0], np.cumsum(weight)]) / weight.sum()
    idx = np.interp(min_jerk(tau), w, np.arange(len(path)))
    lo = np.minimum(idx.astype(int), len(path) - 2)
    f = (idx - lo)[:, None]
    return path[lo] * (1 - f) + path[lo + 1] * f


@dataclass(frozen=True)
class _Piece:
    start: float
    duration: float
    path: np.ndarray | None  # dense path in figurine units (None: rest)
    walk: bool = False


def _pieces(actions, style: Style, rng: np.random.Generator):
    """Every movement and rest of a performance on one timeline, with the action each
    belongs to: (pieces, [(action, start s, end s)])."""
    pieces, spans, t = [], [], 0.0
    pause = style.pause
    for k, name in enumerate(actions):
        gesture = GESTURES[name]
        begin = t
        if name == "Idle":
            rest = max(0.8, 2 * pause) * (0.85 + 0.3 * rng.random())
            pieces.append(_Piece(t, rest, None))
            t += rest
            spans.append((name, begin, t))
            continue
        if gesture.movements == ("jump",):
            moves = [(_jump_path(style.arc), gesture.durations[0])]
        else:
            moves = [(_round_corners(np.array(m)), d) for m, d in zip(gesture.movements, gesture.durations)]
        for j, (path, duration) in enumerate(moves):
            duration *= style.tempo * (0.9 + 0.2 * rng.random()) * math.sqrt(style.size)
            pieces.append(_Piece(t, duration, path, gesture.walk))
            t += duration
            if j < len(moves) - 1:  # the hand stops where the movement ends
                hold = 0.025 * style.tempo * rng.random()
                pieces.append(_Piece(t, hold, None))
                t += hold
        spans.append((name, begin, t))
        if k < len(actions) - 1 and pause > 0 and actions[k + 1] != "Idle" and name != "Idle":
            rest = pause * (0.85 + 0.3 * rng.random())
            pieces.append(_Piece(t, rest, None))
            t += rest
    return pieces, spans, t


def _wobble(t: np.ndarray, degrees: float, rng: np.random.Generator) -> np.ndarray:
    """Rotation vectors (n, 3) of a slow hand wobble: two sinusoids of 0.3–0.8 Hz."""
    if degrees <= 0:
        return np.zeros((len(t), 3))
    out = np.zeros((len(t), 3))
    for _ in range(2):
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        f, phase = rng.uniform(0.3, 0.8), rng.uniform(0, 2 * math.pi)
        out += np.outer(np.sin(2 * math.pi * f * t + phase), axis) * math.radians(degrees) / 2
    return out


def perform(actions, style: Style = Style(), seed: int = 0, name: str = "c0") -> tuple[Doodle, list]:
    """A one-track doodle of a performer playing ``actions`` (built-in action names) in
    ``style``, and the intended ``(action, start s, end s)`` of each."""
    unknown = [a for a in actions if a not in GESTURES]
    if unknown:
        raise ValueError(f"no gesture for {unknown}; known: {', '.join(GESTURES)}")
    rng = np.random.default_rng(seed)
    pieces, spans, total = _pieces(list(actions), style, rng)
    n = int(total * style.rate) + 1
    t = np.arange(n) / style.rate
    t[1:-1] += rng.uniform(-0.1, 0.1, n - 2) / style.rate
    heading = rng.uniform(-math.pi, math.pi)  # the performer faces any way in the room
    yaw = np.array([0.0, math.sin(heading / 2), 0.0, math.cos(heading / 2)])
    scale = UNIT * style.size
    p = np.zeros((n, 3))  # figurine-frame displacement from the start, metres
    moving = np.zeros(n)
    here = np.zeros(3)
    for piece in pieces:
        inside = (t >= piece.start) & (t < piece.start + piece.duration)
        if piece is pieces[-1]:
            inside |= t >= piece.start
        if piece.path is None:
            p[inside] = here
            continue
        tau = np.clip((t[inside] - piece.start) / piece.duration, 0, 1)
        along = (_movement_timing(piece.path, tau) - piece.path[0]) * scale  # movements continue from here
        if piece.walk and style.bob > 0:  # a little hop per step
            travelled = np.concatenate([[0], np.cumsum(np.linalg.norm(np.diff(along, axis=0), axis=1))])
            steps = max(1, round(travelled[-1] / (STEP * style.size)))  # it lands at the end
            along[:, 1] += style.bob * np.abs(np.sin(math.pi * steps * travelled / max(travelled[-1], 1e-12)))
        p[inside] = here + along
        moving[inside] = np.sin(math.pi * tau) ** 2
        here = here + (piece.path[-1] - piece.path[0]) * scale
    # orientation: heading, the prop's tilt in the hand, the wobble, noise
    tilt_axis = rng.normal(size=3)
    tilt_axis[1] = 0.0
    tilt_axis /= max(np.linalg.norm(tilt_axis), 1e-9)
    tilt = quat.exp(np.tile(tilt_axis * math.radians(style.tilt), (n, 1)))
    wobble = _wobble(t, style.wobble, rng) * (1 / 3 + 2 / 3 * moving)[:, None]
    noise = rng.normal(0.0, style.jitter / 0.1, (n, 3))
    q = quat.multiply(quat.multiply(np.tile(yaw, (n, 1)), tilt), quat.exp(wobble + noise))
    world = quat.rotate(np.tile(yaw, (n, 1)), p) + np.array([0.0, 1.0, 0.0])
    world += rng.normal(0.0, style.jitter, (n, 3))
    track = Track(name, t, world, quat.make_continuous(q), np.ones(n, dtype=bool))
    return Doodle((track,), float(style.rate), "vive-controller", f"<performer {style.label()}>"), spans


def perform_two(first, second, style: Style = Style(), seed: int = 0) -> Doodle:
    """A two-track doodle of two performers, each playing its own built-in actions in
    ``style``: ``first`` on track c0, ``second`` on c1 (its performer drawn from ``seed`` +
    1000), sampled on the first one's clock (the second holds its last pose if it ends
    sooner, and is cut if it lasts longer)."""
    one, _ = perform(first, style, seed)
    other, _ = perform(second, style, seed + 1000, name="c1")
    a, b = one.tracks[0], other.tracks[0]
    k = np.minimum(np.arange(len(a.t)), len(b.t) - 1)
    c1 = Track("c1", a.t, b.p[k], b.q[k], np.ones(len(a.t), dtype=bool))
    return Doodle((a, c1), one.rate, one.device, f"<performers {style.label()}>")
