"""Keyframe the library's own built-in clips on :data:`STANDARD` and write them.

Run ``PYTHONPATH=. python3 library/builtin/make_clips.py`` from the repository root: it
writes ``library/builtin/clips/<action>.bvh`` (30 fps, metres) and
``library/builtin/clips.toml`` (clips, stage ends, cycle lengths, skeleton roles and the
interactions) — to be merged into ``library.toml``. Everything here is hand-keyed; no
motion capture is used.

One-shot clips are built from named keys: rest → *prep* → *antic* (anticipation, the
extreme pose opposite to the action) → *exec* (the action's extreme) → *follow*
(follow-through) → rest. The frames of those four keys are the stage ends written to the
manifest. Cyclic clips (Idle, the walks) are generated procedurally with a key per frame,
the feet moved by :func:`leg` and then locked to the ground by :func:`plant`.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

if __package__ in (None, ""):
    sys.path.insert(0, str(Path(__file__).resolve().parents[2]))

from library.builtin.humanoid import HIP_OFFSET, animate, arm, leg, pace, peak_speeds, plant, pose  # noqa: E402
from retarget.analysis import cycle_length  # noqa: E402
from retarget.bvh import write_bvh  # noqa: E402
from retarget.skeleton import Motion  # noqa: E402

FPS = 30
HERE = Path(__file__).resolve().parent

DOWN, UP, FWD, BACK = (0, -1, 0), (0, 1, 0), (0, 0, 1), (0, 0, -1)


def v(*a):
    a = np.asarray(a, float)
    return a / np.linalg.norm(a)


def L(x, y, z):
    """A direction for the left side (x as given)."""
    return v(x, y, z)


def R(x, y, z):
    """The mirror direction for the right side (x negated)."""
    return v(-x, y, z)


NEUTRAL = {
    **arm("Left", L(0.2, -1, 0.02), L(0.12, -1, 0.2)),
    **arm("Right", R(0.2, -1, 0.02), R(0.12, -1, 0.2)),
    **leg("Left", (0, -0.80, 0.0)),
    **leg("Right", (0, -0.80, 0.0)),
}


def P(*parts, **joints):
    """NEUTRAL overridden by the dictionaries in ``parts`` and the joints given."""
    out = dict(NEUTRAL)
    for p in parts:
        out.update(p)
    out.update(pose(**joints))
    return out


def arms(left_up, left_fore, right_up=None, right_fore=None):
    """Both arms; the right mirrors the left when not given (directions as for the left)."""
    right_up = left_up if right_up is None else right_up
    right_fore = left_fore if right_fore is None else right_fore
    return {**arm("Left", L(*left_up), L(*left_fore)), **arm("Right", R(*right_up), R(*right_fore))}


def crouch(depth, fwd=0.0, spread=0.0):
    """Both feet under the hips, the pelvis ``depth`` m lower (knees bend)."""
    return {**leg("Left", (spread, -0.80 + depth, -fwd)), **leg("Right", (-spread, -0.80 + depth, -fwd))}


def peel(side):
    """A foot about to leave the ground: the heel up 7 cm, the toes still on the spot where
    they stood (the foot rolls over them instead of sliding off)."""
    return leg(side, (0, -0.727, 0.05), 25)


# --------------------------------------------------------------------------- one-shots

class Clip:
    def __init__(self, motion: Motion, stages=None, cyclic=False):
        self.motion, self.stages, self.cyclic = motion, stages, cyclic


V_MAX = 10.0  # m/s: the fastest any joint of a built-in clip moves (real mocap: ≤ 10.3 Bandai, ≤ 12.2
# DeepMimic); the compile pipeline may retime and stylise a clip faster still, hence the margin


def oneshot(keys, marks, support=None, airborne=None):
    """keys: (time, pose, root_offset) with the first and last at rest; marks: the times of
    the four stage-ending keys. ``airborne``: (t0, t1) during which no foot supports;
    ``support``: list of (t0, t1, side) windows, side 'left' / 'right' / 'both' / 'air'.

    The keys' times are a minimum: :func:`pace` stretches every gap the joints cannot cross
    at :data:`V_MAX`, then gaps whose planted motion still peaks faster are stretched by
    the excess; the marks and windows move with their keys."""
    keys = sorted(keys, key=lambda k: k[0])
    old = np.array([k[0] for k in keys], float)
    new = np.array([k[0] for k in pace(keys, V_MAX)], float)
    for _ in range(8):
        when = lambda t: float(np.interp(t, old, new))  # noqa: E731
        m = _planted([(when(t), p, r) for t, p, r in keys], support, airborne, when)
        peaks = peak_speeds(m, new)
        if peaks.max() <= V_MAX:
            break
        gaps = np.diff(new) * np.maximum(peaks / V_MAX * 1.03, 1.0)
        new = new[0] + np.concatenate([[0.0], np.cumsum(gaps)])
    stages = [int(round(when(t) * FPS)) for t in marks]
    return Clip(m, stages)


def _planted(keys, support, airborne, when) -> Motion:
    m = animate(keys, FPS)
    sup = np.full(m.frames, 2)
    for t0, t1, side in (support or []):
        sup[int(round(when(t0) * FPS)):int(round(when(t1) * FPS)) + 1] = \
            {"left": 0, "right": 1, "both": 2, "air": -1}[side]
    if airborne:
        t0, t1 = airborne
        sup[int(round(when(t0) * FPS)) + 1:int(round(when(t1) * FPS))] = -1
    return plant(m, sup)


def clip_idle():
    period = 3.0
    keys = []
    for i in range(0, 7):
        ph = i / 6
        b = np.sin(2 * np.pi * ph)  # breathing
        keys.append((ph * period, P(arms((0.2 + 0.02 * b, -1, 0.02), (0.12 + 0.02 * b, -1, 0.2)),
                                    crouch(0.005 * (1 - np.cos(2 * np.pi * ph))),
                                    Spine=(1 - 1.5 * b, 0, 0), Spine1=(-1.2 * b, 0, 0), Spine2=(-1.5 * b, 0, 0),
                                    Neck=(1.5 * b, 0, 0), Head=(1.0 * b, 3 * np.sin(np.pi * ph) ** 2, 0),
                                    LeftShoulder=(0, 0, 2 * b), RightShoulder=(0, 0, -2 * b)), None))
    m = plant(animate(keys, FPS, loop=True))
    return Clip(m, [7, 22, 45, 68], cyclic=True)


def gait(period, direction, stride, lift=0.11, duty=0.56, height=0.80, arm_swing=25.0, back=False):
    """A procedural cycle: each ankle sweeps ``stride`` m along ``direction`` (in the pelvis
    frame) during stance and swings back; the feet are then locked by :func:`plant`."""
    frames = int(round(period * FPS))
    keys = []
    d = np.asarray(direction, float)
    lateral = abs(d[0]) > 0.5
    for i in range(frames + 1):
        ph = (i / frames + 0.25) % 1.0  # start mid-stance: the loop seam falls where all is smooth
        p = dict()
        for side, off in (("Left", 0.0), ("Right", 0.5)):
            s = (ph + off) % 1.0
            if s < duty:  # stance: from +stride/2 to -stride/2 along d
                u = 0.5 - s / duty
                up = 0.0
            else:
                w = (s - duty) / (1 - duty)
                u = -0.5 + (0.5 - 0.5 * np.cos(np.pi * w))
                up = lift * np.sin(np.pi * w) ** 1.5
            pos = d * u * stride
            if lateral:  # side steps: feet stay apart; left foot at x >= -0.04 rel. hip
                shift = 0.06 if side == "Left" else -0.06
                pos = pos + np.array([shift * np.sign(d[0]), 0, 0])
            r2 = pos[0] ** 2 + pos[2] ** 2
            y = -np.sqrt(max(height ** 2 - r2, 0.3)) + up
            pitch = 0.0
            if not lateral and s >= duty:
                w = (s - duty) / (1 - duty)
                pitch = 20 * np.sin(np.pi * w) * (1 - w) * (-1 if back else 1)
            p.update(leg(side, (pos[0], y, pos[2]), foot_pitch=pitch))
        # arms swing against the legs (left arm with the right leg)
        a = np.sin(2 * np.pi * ph) * (1 if not back else -1)
        if lateral:
            p.update(arms((0.25, -1, 0.0), (0.18, -1, 0.15)))
            p["Spine"] = (2, 0, 3 * np.sin(4 * np.pi * ph))
        else:
            sw = np.radians(arm_swing) * a
            p.update(arms((0.18, -np.cos(sw), np.sin(sw)), (0.12, -np.cos(sw + 0.35), np.sin(sw + 0.35)),
                          (0.18, -np.cos(-sw), np.sin(-sw)), (0.12, -np.cos(-sw + 0.35), np.sin(-sw + 0.35))))
            p["Spine"] = (4 if not back else 1, -5 * a, 0)
            p["Spine2"] = (0, -4 * a, 0)
            p["Head"] = (0, 5 * a, 0)
        keys.append((i / FPS, p, None))
    m = plant(animate(keys, FPS, loop=True))
    q = frames // 4
    return Clip(m, [q, 2 * q, 3 * q, frames - 1], cyclic=True)


def clip_walk():
    return gait(1.1, (0, 0, 1), 0.72)


def clip_walk_back():
    return gait(1.2, (0, 0, -1), 0.5, back=True, height=0.79)


def _ease(w, w0=0.1, w1=0.85):
    """Smoothstep from 0 (before ``w0``) to 1 (after ``w1``)."""
    x = np.clip((np.asarray(w, float) - w0) / (w1 - w0), 0.0, 1.0)
    return x * x * (3 - 2 * x)


def side_step(sign, period=1.5, step=0.45, swing=0.32, closed=0.16, lift=0.08):
    """Side steps to the character's left (``sign`` = 1) or right (−1): the leading foot steps
    ``step`` m out, then the trailing foot closes to ``closed`` m from it, one after the
    other (each swing ``swing`` of the cycle, both feet down in between); the pelvis moves
    steadily and sinks a little as the stance widens. A swinging foot rises before it moves
    and moves no more in its last 15 % (it is set down straight), so a foot on the ground
    never slides. The cycle is ``period`` s and travels ``step`` m: two steps."""
    frames = int(round(period * FPS))
    lead, trail = ("Left", "Right") if sign > 0 else ("Right", "Left")
    keys, support = [], []
    for i in range(frames + 1):
        ph = i / frames + 0.41  # start in double support: the loop seam falls where all is smooth
        cyc, f = np.floor(ph), ph % 1.0
        w_lead, w_trail = f / swing, (f - 0.5) / swing
        out = {lead: step * (cyc + _ease(w_lead)) + closed / 2,  # along the way, from the start
               trail: step * (cyc + _ease(w_trail)) - closed / 2}
        up = {lead: lift * np.sin(np.pi * np.clip(w_lead, 0, 1)) ** 2,
              trail: lift * np.sin(np.pi * np.clip(w_trail, 0, 1)) ** 2}
        pelvis = step * (ph + 0.25 - 0.475 * swing)  # steady, on average midway between the feet
        spread = (out[lead] - out[trail] - closed) / step  # 0 closed … 1 widest
        depth = 0.775 + 0.015 * spread
        p = {}
        for side in ("Left", "Right"):
            hip = HIP_OFFSET if side == "Left" else -HIP_OFFSET
            x = sign * (out[side] - pelvis) - hip
            p.update(leg(side, (x, -depth + up[side], 0.0)))
        p.update(arms((0.25, -1, 0.0), (0.18, -1, 0.15)))
        p["Spine"] = (2, 0, -3 * sign * (spread - 0.5))  # the chest leans a little towards the lead foot
        keys.append((i / FPS, p, (sign * pelvis, 0.0, 0.0)))
        swinging = 0 < f < swing and lead or 0.5 < f < 0.5 + swing and trail or None
        stand = {None: 2, "Left": 1, "Right": 0}[swinging]
        support.append(stand)
    m = plant(animate(keys, FPS, loop=True), support)
    q = frames // 4
    return Clip(m, [q, 2 * q, 3 * q, frames - 1], cyclic=True)


def clip_side_left():
    return side_step(1)


def clip_side_right():
    return side_step(-1)


def clip_jump():
    keys = [
        (0.0, P(), (0, 0, 0)),
        (0.25, P(crouch(0.08), arms((0.2, -1, 0.2), (0.1, -1, 0.4)), Spine=(8, 0, 0)), (0, 0, 0)),  # prep
        (0.55, P(crouch(0.30, fwd=0.08), arms((0.15, -0.8, -0.6), (0.1, -0.7, -0.7)), Spine=(25, 0, 0),
                 Spine1=(8, 0, 0), Neck=(-10, 0, 0)), (0, 0, 0)),  # antic: deep crouch, arms back
        (0.72, P(leg("Left", (0, -0.81, -0.05), 35), leg("Right", (0, -0.81, -0.05), 35),
                 arms((0.2, 0.9, 0.5), (0.15, 1, 0.4)), Spine=(-5, 0, 0)), (0, 0, 0.0)),  # take-off
        (0.95, P(crouch(0.22, fwd=-0.15), arms((0.3, 0.6, 0.8), (0.2, 0.4, 0.9)), Spine=(10, 0, 0)),
         (0, 0.40, 0.45)),  # apex: exec
        (1.18, P(leg("Left", (0, -0.79, 0.05), 25), leg("Right", (0, -0.79, 0.05), 25),
                 arms((0.3, 0.2, 0.9), (0.2, 0.0, 1.0)), Spine=(5, 0, 0)), (0, 0.0, 0.9)),  # touch down
        (1.40, P(crouch(0.30, fwd=0.08), arms((0.25, -0.3, 0.9), (0.2, -0.5, 0.8)), Spine=(28, 0, 0)),
         (0, 0, 0.9)),  # follow: absorb
        (2.0, P(), (0, 0, 0.9)),
    ]
    return oneshot(keys, [0.25, 0.55, 0.95, 1.40], airborne=(0.72, 1.18))


def clip_punch():
    guard = arms((0.3, -0.6, 0.6), (-0.35, 0.7, 0.5), (0.3, -0.6, 0.5), (-0.35, 0.8, 0.5))
    feet = {}  # feet stay where they stand: no slide
    keys = [
        (0.0, P(), None),
        (0.3, P(guard, feet), None),
        (0.55, P(guard, feet, arms((0.3, -0.6, 0.6), (-0.35, 0.7, 0.5), (0.4, -0.5, -0.6), (-0.1, 0.6, 0.6)),
                 Spine=(3, -25, 0), Spine1=(0, -10, 0)), None),  # wind-up: right elbow back
        (0.68, P(guard, feet, arms((0.3, -0.6, 0.6), (-0.35, 0.7, 0.5), (-0.1, 0.05, 1), (-0.1, 0.08, 1)),
                 Spine=(8, 25, 0), Spine1=(3, 12, 0)), None),  # strike
        (0.9, P(guard, feet, arms((0.3, -0.6, 0.6), (-0.35, 0.7, 0.5), (0.0, -0.1, 1), (-0.2, 0.3, 0.9)),
                Spine=(5, 15, 0), Spine1=(2, 6, 0)), None),  # follow-through / retract
        (1.5, P(), None),
    ]
    return oneshot(keys, [0.3, 0.55, 0.68, 0.9])


def clip_kick():
    keys = [
        (0.0, P(), None),
        (0.3, P(arms((0.6, -0.7, 0.1), (0.5, -0.5, 0.4)), peel("Right")), None),  # shift weight, heel up
        (0.55, P(arms((0.7, -0.3, 0.3), (0.5, 0.2, 0.6), (0.6, -0.4, -0.4), (0.5, -0.3, 0.3)),
                 leg("Left", (0, -0.76, 0)), leg("Right", (0, -0.55, -0.35), 30), Spine=(-5, 0, 0)), None),
        (0.72, P(arms((0.7, -0.2, -0.3), (0.6, 0.0, 0.2), (0.6, -0.6, 0.6), (0.4, -0.5, 0.7)),
                 leg("Left", (0, -0.78, 0)), leg("Right", (0, -0.25, 0.75), 50), Spine=(-12, 0, 0)), None),
        (0.95, P(arms((0.6, -0.5, 0.1), (0.5, -0.3, 0.4)), leg("Left", (0, -0.78, 0)),
                 leg("Right", (0, -0.55, 0.35), 20), Spine=(-4, 0, 0)), None),
        (1.25, P(arms((0.4, -0.8, 0.05), (0.3, -0.8, 0.25)), leg("Left", (0, -0.79, 0)),
                 leg("Right", (0, -0.755, 0.0))), None),  # the foot above its spot, set down straight
        (1.6, P(), None),
    ]
    return oneshot(keys, [0.3, 0.55, 0.72, 0.95], support=[(0.0, 9.0, "left")])


def clip_stomp():
    keys = [
        (0.0, P(), None),
        (0.25, P(arms((0.4, -1, 0), (0.3, -1, 0.2)), peel("Left"), Spine=(3, 0, 0)), None),  # heel up
        (0.6, P(arms((0.5, -0.6, 0), (0.4, -0.3, 0.3)),
                leg("Left", (0, -0.45, 0.15), -10), Spine=(-6, 0, 0)), None),  # knee high
        (0.72, P(arms((0.3, -1, 0.2), (0.2, -1, 0.4)), crouch(0.08), Spine=(12, 0, 0), Neck=(10, 0, 0)), None),
        (0.95, P(arms((0.3, -1, 0.2), (0.2, -1, 0.4)), crouch(0.12), Spine=(15, 0, 0), Neck=(12, 0, 0)), None),
        (1.5, P(), None),
    ]
    return oneshot(keys, [0.25, 0.6, 0.72, 0.95], support=[(0.0, 9.0, "right")])


def clip_raise_one_arm():
    keys = [
        (0.0, P(), None),
        (0.2, P(arm("Right", R(0.4, -1, 0.1), R(0.3, -1, 0.3))), None),
        (0.4, P(arm("Right", R(0.2, -1, -0.2), R(0.1, -1, 0.1)), Spine=(0, 0, 3)), None),
        (0.85, P(arm("Right", R(0.15, 1, 0.1), R(0.1, 1, 0.05)), Spine=(0, 0, -5), Head=(-10, 0, 0)), None),
        (1.3, P(arm("Right", R(0.25, 1, 0.15), R(0.2, 1, 0.1)), Spine=(0, 0, -4), Head=(-8, 0, 0)), None),
        (2.0, P(), None),
    ]
    return oneshot(keys, [0.2, 0.4, 0.85, 1.3])


def clip_raise_arms():
    keys = [
        (0.0, P(), None),
        (0.2, P(arms((0.3, -1, 0.1), (0.25, -1, 0.3))), None),
        (0.45, P(arms((0.2, -1, -0.3), (0.1, -1, -0.2)), crouch(0.04), Spine=(5, 0, 0)), None),
        (0.9, P(arms((0.3, 1, 0.05), (0.25, 1, 0.0)), Spine=(-6, 0, 0), Head=(-12, 0, 0)), None),
        (1.35, P(arms((0.4, 1, 0.1), (0.3, 1, 0.05)), Spine=(-4, 0, 0), Head=(-8, 0, 0)), None),
        (2.0, P(), None),
    ]
    return oneshot(keys, [0.2, 0.45, 0.9, 1.35])


def clip_greet():
    up = lambda x: arm("Right", R(0.9, 0.2, 0.2), R(x, 1, 0.15))  # noqa: E731
    keys = [
        (0.0, P(), None),
        (0.25, P(arm("Right", R(0.4, -0.8, 0.2), R(0.3, -0.6, 0.6))), None),
        (0.45, P(arm("Right", R(0.5, -0.5, 0.1), R(0.2, -0.2, 0.7)), Spine=(0, 0, 2)), None),
        (0.75, P(up(0.5), Spine=(0, 0, -4), Head=(0, -5, 0)), None),
        (0.95, P(up(-0.3), Spine=(0, 0, -4)), None),
        (1.15, P(up(0.5), Spine=(0, 0, -4)), None),
        (1.35, P(up(-0.3), Spine=(0, 0, -4)), None),
        (1.55, P(up(0.4), Spine=(0, 0, -3)), None),
        (2.2, P(), None),
    ]
    return oneshot(keys, [0.25, 0.45, 0.75, 1.55])


def clip_dismiss():
    keys = [
        (0.0, P(), None),
        (0.25, P(arm("Right", R(0.3, -0.8, 0.4), R(0.2, -0.3, 0.9))), None),
        (0.5, P(arm("Right", R(0.3, -0.7, 0.5), R(0.5, 0.5, -0.3)), Spine=(-3, 10, 0), Head=(-5, 15, 0)), None),
        (0.7, P(arm("Right", R(-0.2, -0.5, 0.8), R(-0.6, -0.1, 0.8)), Spine=(2, -12, 0), Head=(0, -30, 0)), None),
        (0.95, P(arm("Right", R(-0.1, -0.7, 0.6), R(-0.3, -0.6, 0.7)), Spine=(0, -10, 0), Head=(0, -35, 0)), None),
        (1.6, P(), None),
    ]
    return oneshot(keys, [0.25, 0.5, 0.7, 0.95])


def clip_stop():
    keys = [
        (0.0, P(), None),
        (0.2, P(arm("Right", R(0.3, -0.9, 0.3), R(0.2, -0.5, 0.8))), None),
        (0.4, P(arm("Right", R(0.3, -0.6, -0.2), R(0.2, 0.5, 0.2)), Spine=(-3, 0, 0)), None),
        (0.6, P(arm("Right", R(0.1, 0.1, 1), R(0.05, 0.25, 1), ), RightHand=(0, 0, 80), Spine=(4, 0, 0),
                Head=(5, 0, 0)), None),
        (1.2, P(arm("Right", R(0.1, 0.15, 1), R(0.05, 0.3, 1)), RightHand=(0, 0, 75), Spine=(3, 0, 0)), None),
        (1.8, P(), None),
    ]
    return oneshot(keys, [0.2, 0.4, 0.6, 1.2])


def clip_get_angry():
    """Anger at a glance: the shoulders hunch up, the fists come up to the chest with a knee,
    then are shaken down hard as the right foot stamps and the body leans forward glaring
    (twice), and stay clenched and tense before the body lets go."""
    hunch = dict(LeftShoulder=(0, 0, 12), RightShoulder=(0, 0, -12))  # shoulders raised
    high = arms((0.3, -0.7, 0.4), (-0.3, 0.8, 0.4))  # fists up in front of the chest, elbows bent
    down = arms((-0.08, -1, 0.12), (-0.12, -1, 0.3))  # fists shaken down by the thighs (the raised
    # shoulders tilt the arms out), arms nearly straight
    mid = arms((0.25, -0.9, 0.25), (0.05, -0.2, 0.95))  # fists back up to the belly
    glare = dict(Spine=(14, 0, 0), Spine1=(6, 0, 0), Neck=(12, 0, 0), Head=(-14, 0, 0))  # lean in, head forward
    lift = leg("Right", (0, -0.58, 0.0))  # knee up for the stamp
    stamp = {**crouch(0.05), **leg("Right", (0, -0.75, 0.0))}
    keys = [
        (0.0, P(), None),
        (0.3, P(mid, peel("Right"), LeftShoulder=(0, 0, 5), RightShoulder=(0, 0, -5), Spine=(4, 0, 0)), None),  # prep
        (0.6, P(high, lift, hunch, Spine=(-4, 0, 0), Neck=(-4, 0, 0), Head=(-6, 0, 0)), None),  # antic: gather
        (0.8, P(down, stamp, hunch, glare), None),  # exec: fists down, stamp
        (1.0, P(mid, stamp, hunch, glare), None),
        (1.2, P(down, stamp, hunch, {**glare, "Spine": (16, 0, 0)}), None),  # shaken down again
        (1.7, P(arms((0.0, -1, 0.15), (-0.05, -1, 0.35)), crouch(0.03), hunch, glare), None),  # follow: tense, glaring
        (2.4, P(), None),
    ]
    return oneshot(keys, [0.3, 0.6, 0.8, 1.7], support=[(0.0, 0.8, "left")])


def clip_despair():
    keys = [
        (0.0, P(), None),
        (0.3, P(arms((0.3, -0.6, 0.6), (0.1, 0.3, 0.8)), Head=(-10, 0, 0)), None),
        (0.6, P(arms((0.6, 0.5, 0.4), (0.3, 0.9, 0.2)), Spine=(-8, 0, 0), Head=(-25, 0, 0)), None),  # look up
        (1.1, P(crouch(0.25), arms((0.4, 0.1, 0.8), (-0.3, 0.8, 0.3)), Spine=(25, 0, 0), Spine1=(10, 0, 0),
                Neck=(15, 0, 0), Head=(20, 0, 0)), None),  # hands to the head, slump
        (1.7, P(crouch(0.28), arms((0.4, 0.0, 0.8), (-0.3, 0.7, 0.4)), Spine=(30, 0, 0), Spine1=(10, 0, 0),
                Neck=(15, 0, 0), Head=(25, 0, 0)), None),
        (2.5, P(), None),
    ]
    return oneshot(keys, [0.3, 0.6, 1.1, 1.7])


def clip_duck():
    cover = arms((0.5, 0.3, 0.7), (-0.3, 0.8, 0.4))
    keys = [
        (0.0, P(), None),
        (0.2, P(arms((0.3, -0.8, 0.3), (0.2, -0.3, 0.7))), None),
        (0.35, P(arms((0.3, -0.8, 0.3), (0.2, -0.3, 0.7)), Spine=(-4, 0, 0), Head=(-8, 0, 0)), (0, 0.0, 0)),
        (0.6, P(crouch(0.42, fwd=0.05), cover, Spine=(40, 0, 0), Spine1=(10, 0, 0), Neck=(20, 0, 0)), None),
        (1.1, P(crouch(0.40, fwd=0.05), cover, Spine=(35, 0, -5), Spine1=(10, 0, 0), Neck=(20, 0, 0)), None),
        (1.8, P(), None),
    ]
    return oneshot(keys, [0.2, 0.35, 0.6, 1.1])


def clip_dodge():
    keys = [
        (0.0, P(), None),
        (0.2, P(arms((0.3, -0.8, 0.3), (0.2, -0.3, 0.7))), None),
        (0.4, P(arms((0.3, -0.8, 0.3), (0.2, -0.3, 0.7)), crouch(0.03), Spine=(0, 0, 6), Spine1=(0, 0, 4)), None),
        (0.6, P(crouch(0.12), arms((0.6, -0.5, 0.4), (0.3, 0.3, 0.6), (0.7, -0.4, 0.1), (0.5, -0.2, 0.4)),
                Spine=(8, 0, -22), Spine1=(3, 0, -12), Neck=(0, 0, -8)), None),
        (0.95, P(crouch(0.10), arms((0.6, -0.5, 0.4), (0.3, 0.3, 0.6), (0.7, -0.4, 0.1), (0.5, -0.2, 0.4)),
                 Spine=(6, 0, -18), Spine1=(3, 0, -10), Neck=(0, 0, -6)), None),
        (1.6, P(), None),
    ]
    return oneshot(keys, [0.2, 0.4, 0.6, 0.95])


def clip_block():
    shield = arms((0.35, 0.1, 0.9), (-0.5, 0.85, 0.2), (0.35, -0.2, 0.9), (-0.5, 0.6, 0.3))
    keys = [
        (0.0, P(), None),
        (0.2, P(arms((0.3, -0.8, 0.3), (0.2, -0.3, 0.7))), None),
        (0.35, P(arms((0.4, -0.8, -0.1), (0.3, -0.5, 0.3)), Spine=(-3, 0, 0)), None),
        (0.5, P(shield, crouch(0.06), Spine=(10, 0, 0), Neck=(8, 0, 0)), None),
        (1.0, P(shield, crouch(0.08), Spine=(6, 0, 0), Neck=(6, 0, 0)), None),
        (1.6, P(), None),
    ]
    return oneshot(keys, [0.2, 0.35, 0.5, 1.0])


def clip_throw():
    feet = {}  # feet stay where they stand: no slide
    keys = [
        (0.0, P(), None),
        (0.3, P(feet, arm("Right", R(0.6, -0.6, 0.3), R(0.2, 0.4, 0.6))), None),
        (0.7, P(feet, arm("Right", R(0.8, 0.3, -0.4), R(0.1, 0.9, -0.5)), arm("Left", L(0.4, 0.1, 0.9), L(0.2, 0.2, 1)),
                Spine=(-8, -25, 0), Spine1=(-4, -10, 0)), None),  # wind up, ball behind the head
        (0.86, P(feet, arm("Right", R(-0.1, 0.2, 1), R(-0.1, -0.1, 1)), arm("Left", L(0.6, -0.8, -0.2), L(0.4, -0.6, 0.2)),
                 Spine=(15, 25, 0), Spine1=(6, 10, 0)), None),  # release forward
        (1.1, P(feet, arm("Right", R(-0.3, -0.7, 0.6), R(-0.3, -0.9, 0.3)), arm("Left", L(0.6, -0.8, -0.2), L(0.4, -0.6, 0.2)),
                Spine=(22, 30, 0), Spine1=(8, 10, 0)), None),
        (1.8, P(), None),
    ]
    return oneshot(keys, [0.3, 0.7, 0.86, 1.1])


def clip_pick_up():
    reach = arms((0.15, -0.6, 0.8), (0.05, -0.7, 0.7))
    keys = [
        (0.0, P(), None),
        (0.3, P(arms((0.25, -1, 0.3), (0.15, -1, 0.5)), Head=(15, 0, 0)), None),  # look down
        (0.5, P(arms((0.25, -0.9, -0.2), (0.2, -1, 0.0)), Spine=(-3, 0, 0), Head=(20, 0, 0)), None),
        (1.0, P(crouch(0.38, fwd=0.08), reach, Spine=(45, 0, 0), Spine1=(10, 0, 0), Neck=(-10, 0, 0)), None),
        (1.5, P(crouch(0.05), arms((0.2, -0.7, 0.7), (0.0, 0.3, 0.9)), Spine=(8, 0, 0)), None),  # lift, hold
        (2.1, P(), None),
    ]
    return oneshot(keys, [0.3, 0.5, 1.0, 1.5])


def clip_cast_fireball():
    keys = [
        (0.0, P(), None),
        (0.25, P(arms((0.4, -0.6, 0.5), (0.1, 0.0, 0.9))), None),
        (0.65, P(arms((0.5, -0.5, -0.5), (0.1, 0.1, -0.3), (0.5, -0.6, -0.5), (0.1, 0.2, -0.3)), crouch(0.08),
                 Spine=(-6, 20, 0), Spine1=(-3, 8, 0)), None),  # gather the ball at the hip
        (0.85, P(arms((0.05, 0.2, 1), (0.0, 0.25, 1)),  Spine=(15, 0, 0), Spine1=(5, 0, 0)), None),  # push
        (1.2, P(arms((0.1, 0.1, 1), (0.05, 0.1, 1)),  Spine=(12, 0, 0)), None),
        (1.9, P(), None),
    ]
    return oneshot(keys, [0.25, 0.65, 0.85, 1.2])


def clip_yell():
    keys = [
        (0.0, P(), None),
        (0.3, P(arms((0.35, -0.9, 0.1), (0.3, -0.8, 0.3)), Spine=(-3, 0, 0)), None),
        (0.6, P(arms((0.5, -0.7, -0.2), (0.4, -0.6, 0.0)), Spine=(-10, 0, 0), Neck=(-10, 0, 0), Head=(-15, 0, 0)),
         None),  # big breath, head back
        (0.85, P(arms((0.6, -0.6, 0.3), (0.3, 0.5, 0.6)), crouch(0.06), Spine=(15, 0, 0), Neck=(15, 0, 0),
                 Head=(-10, 0, 0)), None),  # yell forward
        (1.6, P(arms((0.6, -0.6, 0.3), (0.3, 0.45, 0.6)), crouch(0.07), Spine=(17, 0, 0), Neck=(15, 0, 0),
                Head=(-8, 0, 0)), None),
        (2.2, P(), None),
    ]
    return oneshot(keys, [0.3, 0.6, 0.85, 1.6])


def clip_uppercut():
    guard = arms((0.3, -0.6, 0.6), (-0.35, 0.7, 0.5), (0.3, -0.6, 0.5), (-0.35, 0.8, 0.5))
    feet = {}  # feet stay where they stand: no slide
    keys = [
        (0.0, P(), None),
        (0.25, P(guard, feet), None),
        (0.35, P(guard, feet, arms((0.3, -0.6, 0.6), (-0.35, 0.7, 0.5), (0.0, 0.1, 1), (0.0, 0.1, 1)),
                 Spine=(5, 15, 0)), None),  # jab with the right
        (0.5, P(guard, feet, arms((0.3, -0.6, 0.6), (-0.35, 0.7, 0.5),
                (0.3, -0.9, -0.1), (0.2, -0.2, 0.9)), Spine=(12, -15, 8)), None),  # dip, fist low
        (0.68, P(guard, feet, arms((0.3, -0.6, 0.6), (-0.35, 0.7, 0.5), (0.1, -0.2, 1), (0.0, 1, 0.3)),
                 Spine=(-8, 20, -3), Head=(-5, 0, 0)), None),  # uppercut
        (0.9, P(guard, feet, arms((0.3, -0.6, 0.6), (-0.35, 0.7, 0.5), (0.2, -0.4, 0.8), (0.05, 0.9, 0.4)),
                Spine=(-3, 12, 0)), None),
        (1.5, P(), None),
    ]
    return oneshot(keys, [0.25, 0.5, 0.68, 0.9])


def clip_crescent_kick():
    keys = [
        (0.0, P(), None),
        (0.3, P(arms((0.6, -0.7, 0.1), (0.5, -0.5, 0.4)), peel("Right")), None),
        (0.55, P(arms((0.8, -0.3, 0.2), (0.6, 0.0, 0.4)), leg("Left", (0, -0.77, 0)),
                 leg("Right", (0.30, -0.40, 0.45), 20), Spine=(-5, -10, 0)), None),  # leg across, low
        (0.8, P(arms((0.8, -0.2, 0.0), (0.6, 0.1, 0.2)), leg("Left", (0, -0.77, 0)),
                leg("Right", (-0.35, -0.05, 0.55), 40), Spine=(-10, 10, 0)), None),  # arc out and high
        (1.0, P(arms((0.7, -0.5, 0.1), (0.5, -0.3, 0.3)), leg("Left", (0, -0.78, 0)),
                leg("Right", (-0.35, -0.50, 0.2), 20), Spine=(-4, 5, 0)), None),
        (1.3, P(arms((0.4, -0.8, 0.05), (0.3, -0.8, 0.25)), leg("Left", (0, -0.79, 0)),
                leg("Right", (0, -0.755, 0.0))), None),  # the foot above its spot, set down straight
        (1.7, P(), None),
    ]
    return oneshot(keys, [0.3, 0.55, 0.8, 1.0], support=[(0.0, 9.0, "left")])


def _flip(sign):
    """A standing (back) flip. The body turns about the hips: it takes off already leaning
    into the turn and tucks at once (knees to the chest: the feet close to the axis), so the
    turn is quick without the extended limbs sweeping fast; the flight lasts 0.64 s."""
    tuck = {**crouch(0.40, fwd=-0.35), **arms((0.2, -0.3, 0.9), (-0.2, -0.8, 0.4))}
    half = {**crouch(0.22, fwd=-0.15), **arms((0.2, 0.2, 0.9), (0.0, -0.4, 0.9))}
    keys = [
        (0.0, P(), (0, 0, 0)),
        (0.2, P(crouch(0.06), arms((0.3, -0.9, 0.2), (0.2, -0.8, 0.4))), (0, 0, 0)),
        (0.5, P(crouch(0.30, fwd=0.05), arms((0.2, -0.6, -0.8) if sign > 0 else (0.2, -0.5, 0.8),
                                             (0.1, -0.6, -0.8) if sign > 0 else (0.1, -0.3, 0.9)),
                Spine=(25 if sign > 0 else 10, 0, 0)), (0, 0, 0)),
        (0.72, P(leg("Left", (0, -0.81, -0.05), 35), leg("Right", (0, -0.81, -0.05), 35),
                 arms((0.2, 0.7, 0.7), (0.2, 0.7, 0.7)), Hips=(sign * 35, 0, 0)), (0, 0.05, sign * 0.05)),  # take off
        (0.90, P(half, Spine=(20, 0, 0), Neck=(10, 0, 0), Hips=(sign * 105, 0, 0)), (0, 0.50, sign * 0.20)),
        (1.08, P(tuck, Spine=(30, 0, 0), Neck=(20, 0, 0), Hips=(sign * 190, 0, 0)), (0, 0.62, sign * 0.38)),
        (1.26, P(half, Spine=(20, 0, 0), Neck=(10, 0, 0), Hips=(sign * 270, 0, 0)), (0, 0.42, sign * 0.55)),
        (1.44, P(crouch(0.10, fwd=0.05), arms((0.6, 0.3, 0.6), (0.6, 0.3, 0.6)), Hips=(sign * 330, 0, 0)),
         (0, 0.0, sign * 0.7)),  # land, still turning: the crouch absorbs the rest
        (1.7, P(crouch(0.30, fwd=0.08), arms((0.6, 0.0, 0.6), (0.5, 0.0, 0.8)), Spine=(25, 0, 0),
                Hips=(sign * 360, 0, 0)), (0, 0, sign * 0.7)),
        (2.3, P(Hips=(sign * 360, 0, 0)), (0, 0, sign * 0.7)),
    ]
    return oneshot(keys, [0.2, 0.5, 1.08, 1.7], airborne=(0.72, 1.44))


def clip_flip():
    return _flip(1)


def clip_back_flip():
    return _flip(-1)


def clip_dance():
    keys = [(0.0, P(), None),
            (0.25, P(crouch(0.06), arms((0.5, -0.7, 0.3), (0.3, 0.5, 0.6))), None)]
    t = 0.25
    for i in range(6):
        s = 1 if i % 2 == 0 else -1
        t += 0.3
        keys.append((t, P(crouch(0.10 if i % 2 else 0.02), arms((0.6, 0.2 * s + 0.2, 0.4), (0.3, 0.9, 0.3),
                                                                 (0.6, -0.2 * s + 0.2, 0.4), (0.3, 0.9, 0.3)),
                          Spine=(3, 12 * s, 6 * s), Spine1=(0, 6 * s, 3 * s), Head=(0, -10 * s, 5 * s)), None))
    t += 0.35
    keys.append((t, P(arms((0.4, 1, 0.2), (0.3, 1, 0.1)), Spine=(-6, 0, 0), Head=(-10, 0, 0)), None))
    keys.append((t + 0.6, P(), None))
    return oneshot(keys, [0.25, keys[2][0], keys[-3][0], t])


def clip_slap():
    feet = {}  # feet stay where they stand: no slide
    keys = [
        (0.0, P(), None),
        (0.25, P(feet, arm("Right", R(0.5, -0.7, 0.3), R(0.4, -0.2, 0.7))), None),
        (0.55, P(feet, arm("Right", R(1, 0.3, -0.1), R(1, 0.4, 0.3)), Spine=(0, -25, 0), Spine1=(0, -10, 0)), None),
        (0.7, P(feet, arm("Right", R(-0.4, 0.1, 0.9), R(-0.9, 0.15, 0.4)), Spine=(5, 25, 0), Spine1=(0, 10, 0)), None),
        (0.9, P(feet, arm("Right", R(-0.6, -0.3, 0.6), R(-0.8, -0.5, 0.2)), Spine=(5, 30, 0), Spine1=(0, 12, 0)), None),
        (1.5, P(), None),
    ]
    return oneshot(keys, [0.25, 0.55, 0.7, 0.9])


def clip_slapped():
    keys = [
        (0.0, P(), None),
        (0.5, P(Head=(0, -3, 0)), None),
        (0.68, P(Head=(0, -5, 0)), None),
        (0.8, P(arms((0.5, -0.8, -0.2), (0.4, -0.7, 0.0)), Spine=(-4, 20, 6), Spine1=(0, 10, 4), Neck=(0, 15, 8),
                Head=(-5, 35, 10)), None),  # the head snaps to its left
        (1.2, P(arm("Right", R(0.3, -0.5, 0.7), R(-0.6, 0.7, 0.3)), Spine=(-2, 12, 3), Neck=(0, 10, 4),
                Head=(0, 20, 5)), None),  # hand to the cheek
        (1.9, P(), None),
    ]
    return oneshot(keys, [0.5, 0.68, 0.8, 1.2])


def clip_kiss():
    """A kiss for a partner facing the character about 0.5 m away: the hips stay back, the
    upper body leans in from them, the head tilts and reaches forward with the chin a little
    up, and the hands reach out towards the partner's shoulders; the chest stays clear of
    the partner (the reach is the head's and the hands')."""
    hips_back = {**leg("Left", (0.0, -0.79, 0.06)), **leg("Right", (0.0, -0.79, 0.06))}
    reach = arms((0.4, -0.6, 0.55), (-0.05, 0.95, 0.25))  # hands up, 0.3 m out: towards the partner's shoulders
    lean = dict(Spine=(20, 0, 0), Spine1=(6, 0, 0), Neck=(20, 0, 0))
    keys = [
        (0.0, P(), None),
        (0.35, P(arms((0.3, -0.8, 0.4), (0.2, -0.4, 0.8)), Head=(4, 0, 0)), None),  # prep: hands start to lift
        (0.6, P(arms((0.3, -0.6, 0.6), (0.2, 0.0, 1)), Spine=(-2, 0, 0), Head=(-4, 0, 0)), None),  # antic: a breath
        (1.1, P(reach, hips_back, lean, Head=(-10, 6, -16)), None),  # exec: lean in, head tilted
        (1.8, P(reach, hips_back, lean, Head=(-10, 7, -18)), None),  # hold
        (2.2, P(arms((0.3, -0.7, 0.5), (0.2, -0.2, 0.9)), Spine=(4, 0, 0), Head=(2, 3, -6)), None),  # hands down in front
        (2.7, P(), None),
    ]
    return oneshot(keys, [0.35, 0.6, 1.1, 1.8])


# --------------------------------------------------------------------------- output

CLIPS = [  # action, file stem, maker
    ("Idle", "idle", clip_idle), ("Walk", "walk", clip_walk), ("Walk Back", "walk_back", clip_walk_back),
    ("Side Walk Left", "side_walk_left", clip_side_left), ("Side Walk Right", "side_walk_right", clip_side_right),
    ("Jump", "jump", clip_jump), ("Punch", "punch", clip_punch), ("Kick", "kick", clip_kick),
    ("Stomp", "stomp", clip_stomp), ("Raise One Arm", "raise_one_arm", clip_raise_one_arm),
    ("Raise Arms", "raise_arms", clip_raise_arms), ("Greet", "greet", clip_greet),
    ("Dismiss", "dismiss", clip_dismiss), ("Stop", "stop", clip_stop), ("Get Angry", "get_angry", clip_get_angry),
    ("Despair", "despair", clip_despair), ("Duck", "duck", clip_duck), ("Dodge", "dodge", clip_dodge),
    ("Block", "block", clip_block), ("Throw", "throw", clip_throw), ("Pick up", "pick_up", clip_pick_up),
    ("Cast Fireball", "cast_fireball", clip_cast_fireball), ("Yell", "yell", clip_yell),
    ("Uppercut Jab", "uppercut_jab", clip_uppercut), ("Crescent Kick", "crescent_kick", clip_crescent_kick),
    ("Flip", "flip", clip_flip), ("Back Flip", "back_flip", clip_back_flip), ("Dance", "dance", clip_dance),
    ("Slap", "slap", clip_slap), ("Slapped", "slapped", clip_slapped), ("Kiss", "kiss", clip_kiss),
]
INTERACTION_ONLY = {"Slap", "Slapped", "Kiss"}  # not (yet) actions of library.toml
INTERACTIONS = [("Slap", ["Slap", "Slapped"])]


def build(names=None) -> dict[str, Clip]:
    return {a: make() for a, _, make in CLIPS if names is None or a in names}


def _toml_str(s: str) -> str:
    return '"' + s.replace("\\", "\\\\").replace('"', '\\"') + '"'


def main(argv=None) -> int:
    out = HERE / "clips"
    out.mkdir(exist_ok=True)
    lines = ["# Generated by library/builtin/make_clips.py: the built-in clips, keyframed on the",
             "# standard humanoid (library/builtin/humanoid.py). Merge into library.toml.", "",
             "[skeleton]", 'pelvis = "Hips"', 'chest = "Spine2"', 'head = "Head"', 'left_foot = "LeftFoot"',
             'right_foot = "RightFoot"', 'left_hand = "LeftHand"', 'right_hand = "RightHand"', ""]
    for action, stem, make in CLIPS:
        clip = make()
        path = out / f"{stem}.bvh"
        write_bvh(path, clip.motion, unit=1.0, precision=4)
        lines += ["[[actions]]", f"name = {_toml_str(action)}"]
        if action in INTERACTION_ONLY:
            lines.append("# an interaction clip: not an action of library.toml yet (give it an expression)")
        lines.append(f'clips = ["clips/{stem}.bvh"]')
        lines.append(f"stages = [{', '.join(str(s) for s in clip.stages)}]")
        if clip.cyclic and cycle_length(clip.motion, period=clip.motion.frames - 1) > 0.01:
            lines.append(f"cycle_length = {max(cycle_length(clip.motion, period=clip.motion.frames - 1), 1e-4):.4f}")
        lines.append("")
        print(f"{action:16s} {clip.motion.frames:4d} frames  {path.stat().st_size / 1024:5.1f} KB  stages {clip.stages}")
    for name, acts in INTERACTIONS:
        lines += ["[[interactions]]", f"name = {_toml_str(name)}",
                  "actions = [" + ", ".join(_toml_str(a) for a in acts) + "]", ""]
    lines += ["# Kiss is a one-character clip for now: an interaction needs at least two actions,",
              "# e.g. Kiss performed by both characters.", "[[interactions]]", 'name = "Kiss"',
              'actions = ["Kiss", "Kiss"]', ""]
    (HERE / "clips.toml").write_text("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
