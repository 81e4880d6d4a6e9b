"""Laban stylisation (thesis §5.4): operators, and the Time and Weight modifiers built on them.

Operators (§5.4.2), on any skeleton with the pelvis/chest/head partition (§5.4.1):

* **motion scale** (eq. 5.1) over a frame range: each bone's rotation relative to the
  range's first frame is slerped towards that frame's by a factor (positions likewise),
  *partially* (spine and primary bones only) or *fully* (every bone); frames after the
  range take the change at its end and fade it out to the clip's end (cohesion, eq. 5.2);
  feet that touched the ground keep their height (IK, two-bone, instead of FABRIK);
* **retiming** (eq. 5.3): a map from clip time to output time built stage by stage,
  ``f_i(t) = f_{i-1}(end_{i-1}) + a_i (t − start_i)^{b_i}``;
* **reshaping**: a rotation shift on the spine about its local x axis (Vertical shape —
  sinking forward, rising back) or on the primary bones about their local z axis
  (Horizontal shape — spreading, enclosing), during the execution stage.

Modifiers (§5.4.3):

* **Time** ``L_t ∈ [−1, 1]`` (Sudden > 0, Sustained < 0): preparation and anticipation
  scaled down fully by ``c = 1/(3|L_t| + 1)``; anticipation retimed by ``1/(1 − 0.5 L_t)``
  (Sudden: longer) or ``1 + 0.5 L_t`` (Sustained: shorter); execution by
  ``a = 1/(1 + 2 L_t)``, ``b = 1 − 0.4 L_t`` (Sudden: shorter, accelerating) or
  ``a = 1 − 2 L_t``, ``b = 1 − 0.4 L_t`` (Sustained: longer, decelerating). The thesis's
  formulas use t in seconds within each stage.
* **Weight** ``L_w ∈ [−1, 1]`` (Strong > 0, Light < 0): the whole clip scaled partially
  by ``c = 1 + L_w`` (Strong) or ``1/(1 − L_w)`` (Light); then retimed so the clip plays at
  a speed proportional to ``V_e^{α L_w}`` (α = 1.5 for Strong, as the thesis; 0.5 for
  Light, where 1.5 would play the slowest frames fastest; ``V_e`` the mean joint speed, made
  relative to its mean and kept in [0.05, 1] for Light; the rate capped at 3× either way
  so no bone turns further between two frames than interpolation can follow) — amplifying
  speed variations for Strong, flattening them for Light — with the duration kept
  (eq. 5.4–5.5); and a
  Vertical-shape shift of ``0.1 L_w`` rad (Strong sinks, Light rises).
* Combined: Time before Weight. ``L_t = L_w = 0`` returns the clip unchanged.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from doodle.core import quat
from doodle.core.filters import gaussian_filter1d, maximum_filter1d
from doodle.core.quat import make_continuous
from doodle.core.splines import PchipInterpolator
from retarget.analysis import Stages, foot_contacts, guess_roles, partition, pelvis_of
from retarget.effort_signature import FASTEST, RATE, burst, most_moving, speed_profile
from retarget.feet import leg_of, two_bone_ik
from retarget.qa import Limits, check, foot_points, planted_moves
from retarget.sequence import rise_least
from retarget.skeleton import Motion, body_points, end_site_positions, forward_kinematics, per_motion

ALPHA_WEIGHT = 1.5
ALPHA_LIGHT = 0.5  # Light: speed as played ∝ V_e^(1 − 0.5|L_w|) — flattened, never inverted (α ≥ 1 would make the slowest frames the fastest)
OVERSAMPLE = 4  # retimed output has 4× a 30 fps clip's frame rate: frames at most 1/120 s apart
EDIT_SMOOTHING = 0.05  # s: pose edits are low-passed over this much clip time
RATE_SMOOTHING = 0.04  # s: the playback rate's changes are smoothed over this much clip time
MAX_SPEEDUP = 3.0  # Weight retiming plays no frame more than 3× faster (or slower) than the clip
PIN_FADE = 0.2  # s: a planted foot's pin eases in and out over at least this much output time ...
PIN_SPEED = 0.5  # m/s: ... and no faster than this pulls the foot to where it stood
BURST_SHARE = 0.3  # the execution Time retimes: the effector's speed at least this share of its peak
SUSTAINED_CAP = 0.7  # Sustained: the effector outside the execution no faster than this share of its peak in it
SPEED_MARGIN = 0.8  # retiming keeps every joint under this share of FASTEST between clip frames ...
SPEED_BOUND = 0.95  # ... and the output's, measured after every edit (contact IK too), under this share
PLANTED_SPEED = 0.8 * Limits().slide  # m/s: a flat foot played no faster than its neutral or than this
TRAVEL_SMOOTHING = 0.5  # s: Weight widens the acting hand or foot's path less the body's travel, low-passed over this
END_REST = 0.1  # s: a burst ending this close to the clip's end is its return to rest, not its execution
STAGE_EASE = 0.2  # s: with Time, Weight keeps each stage's duration, its correction eased over this much clip time
WIDEN = 0.5  # Weight scales the acting hand or foot's path by 1 + this × L_w (Strong) or 1/(1 − this × L_w) (Light)
FOOT_CLEAR = 0.1  # m: an acting foot's path widens sideways only as it lifts this far off its floor
JUMP_CLEAR = 0.1  # m: in a flight both soles rise at least this far off the floor (less: a shuffle, a heel raised)
JUMP_AIR = 0.2  # s: ... for at least this long (less: a running stride's flight phase, 0.1-0.15 s)
FLIGHT_EASE = 0.1  # s: around a flight, the playback may slow by one more frame time per this much clip time


def _bones(motion: Motion, mode: str) -> np.ndarray:
    """Joints a motion scale acts on — never the root nor joints above the pelvis: they
    carry the character's place and facing (scaling them would slide a walk and turn a
    flip into one and a half)."""
    roles = guess_roles(motion.skeleton)
    pelvis = roles.get("pelvis", 0)
    carriers = {0, pelvis} if motion.skeleton.parents[pelvis] < 0 else set(range(pelvis + 1))
    if mode == "full" or not {"pelvis", "chest", "head"} <= set(roles):
        chosen = range(len(motion.skeleton)) if mode != "limbs" else []
    else:
        parts = partition(motion.skeleton, roles["pelvis"], roles["chest"], roles["head"])
        if mode == "limbs":  # the primary bones' children: upper arms (under clavicles), shins (under thighs)
            chosen = [c for p in parts["primary"] for c in motion.skeleton.children(p) if c not in parts["spine"]]
        else:
            chosen = parts["spine"] + parts["primary"]
    return np.array([b for b in chosen if b not in carriers], dtype=int)


def _slerp_identity(q: np.ndarray, w) -> np.ndarray:
    """slerp(identity, q, w) for quaternions (F, ..., 4) in time order: the rotation scaled
    by w (a scalar or one weight per frame). The quaternions are made sign-continuous first,
    so a rotation passing half a turn keeps growing (angle past π) instead of jumping."""
    rv = quat.log(make_continuous(q))
    w = np.asarray(w, dtype=float).reshape((-1,) + (1,) * (rv.ndim - 1))
    return quat.exp(rv * w)


def motion_scale(motion: Motion, start: int, end: int, c: float, mode: str = "partial",
                 keep_contacts: bool = True, smooth: bool = True, fade_end: int | None = None,
                 bones: np.ndarray | None = None) -> Motion:
    """Eq. 5.1 over frames [start, end), cohesion (eq. 5.2) after it — the change at ``end``
    fading out by ``fade_end`` (default the clip's end) —, the edit smoothed
    (:func:`smooth_edit`) and contacts restored. ``bones``: the joints scaled, instead of
    those ``mode`` chooses."""
    if c == 1.0 or end - start < 2:
        return motion
    end = min(end, motion.frames)
    bones = _bones(motion, mode) if bones is None else np.asarray(bones, dtype=int)
    rots, trans = motion.rotations.copy(), motion.translations.copy()
    q0 = np.broadcast_to(rots[start, bones], (end - start, len(bones), 4))
    r = quat.multiply(q0, quat.conjugate(rots[start:end, bones]))  # q(ts) q(t)^-1
    rots[start:end, bones] = quat.multiply(quat.conjugate(_slerp_identity(r, c)), q0)
    trans[start:end, bones] = trans[start, bones] + c * (trans[start:end, bones] - trans[start, bones])
    if end < motion.frames:  # cohesion: the change at the end fades out over the rest
        last = end - 1
        stop = motion.frames if fade_end is None else int(np.clip(fade_end, end, motion.frames))
        w = np.clip(1.0 - (np.arange(end, motion.frames) - last) / max(stop - 1 - last, 1), 0.0, 1.0)
        delta = quat.multiply(rots[last, bones], quat.conjugate(motion.rotations[last, bones]))
        delta = np.where(delta[:, 3:4] < 0, -delta, delta)
        fade = quat.exp(quat.log(delta)[None] * w[:, None, None])
        rots[end:, bones] = quat.multiply(fade, rots[end:, bones])
        trans[end:, bones] += w[:, None, None] * (trans[last, bones] - motion.translations[last, bones])[None]
    out = replace(motion, rotations=rots, translations=trans)
    if smooth:
        out = smooth_edit(motion, out, bones)
    return _restore_contacts(motion, out) if keep_contacts else out


def smooth_edit(original: Motion, edited: Motion, bones: np.ndarray | None = None) -> Motion:
    """The edit (edited pose relative to the original, per bone and frame) low-passed over
    ``EDIT_SMOOTHING`` seconds: a motion scale switches on and off at its range's ends,
    and a step in a bone's velocity there is a jerk spike the clip never had."""
    sigma = EDIT_SMOOTHING / original.frame_time
    if original.frames < 3 or sigma < 0.3:
        return edited
    bones = np.arange(len(original.skeleton)) if bones is None else bones
    orig_q, orig_t = original.rotations[:, bones], original.translations[:, bones]
    delta = quat.log(make_continuous(quat.multiply(edited.rotations[:, bones], quat.conjugate(orig_q))))
    delta = gaussian_filter1d(delta, sigma, axis=0, mode="nearest")
    shift = gaussian_filter1d(edited.translations[:, bones] - orig_t, sigma, axis=0, mode="nearest")
    rots, trans = edited.rotations.copy(), edited.translations.copy()
    rots[:, bones] = quat.multiply(quat.exp(delta), orig_q)
    trans[:, bones] = orig_t + shift
    return replace(edited, rotations=rots, translations=trans)


def _restore_contacts(before: Motion, after: Motion, world=None, clip_frames: np.ndarray | None = None) -> Motion:
    """``after`` with the feet that stood on the floor in ``before`` back where they stood.

    A foot is planted where it is in contact (:func:`~retarget.analysis.foot_contacts`) or flat
    on the floor (``retarget.qa.planted_moves``: a foot turning on its ball, or creeping, is not
    in contact by the first reading but still on the floor, and a pin let go there would drag
    it). On each run of planted frames the ankle follows the neutral's ankle, as ``after``
    plays the clip — at its height, the foot turned as there —, less the neutral's own slides:
    where the neutral's stillest foot point moves faster than :data:`PLANTED_SPEED`, that
    step is left out (the foot stays put, and keeps the offset to the end of the run). So a
    planted foot neither lifts nor slides, however the clip is retimed (the retiming keeps a
    creeping foot as slow: :func:`_planted_least`). The pin eases in and out over
    :data:`PIN_FADE` seconds of ``after`` either side (longer where it pulls the foot farther,
    at most :data:`PIN_SPEED`), while the foot is off the floor. ``clip_frames``: the
    (fractional) frame of ``before`` each frame of ``after`` shows (default: the same frames);
    ``world``: ``forward_kinematics(after)`` if the caller has it."""
    roles = guess_roles(before.skeleton)
    feet = [roles[k] for k in ("left_foot", "right_foot") if k in roles]
    if not feet or before.frames < 2:
        return after
    old, old_rot = forward_kinematics(before)
    f = np.arange(after.frames, dtype=float) if clip_frames is None else np.asarray(clip_frames, dtype=float)
    f = np.clip(f, 0, before.frames - 1)
    nearest = np.clip(np.rint(f).astype(int), 0, before.frames - 1)
    world = world or forward_kinematics(after)  # the legs are separate chains: one pass serves both
    frames = np.arange(after.frames)
    clip = np.arange(before.frames)
    flat, step = _own_planted_moves(before)
    for k, ankle in enumerate(feet):
        hip, knee, _ = leg_of(before.skeleton, ankle)
        planted = _own_contacts(before, ankle).copy()
        slid = np.zeros((before.frames - 1, 2))
        if flat.shape[1] == len(feet):
            planted |= flat[:, k]
            fast = np.linalg.norm(step[:, k], axis=1) > PLANTED_SPEED * before.frame_time
            slid = np.where((fast & planted[1:] & planted[:-1])[:, None], step[:, k], 0.0)
        if hip < 0 or not planted.any():
            continue
        ankle_at = np.stack([np.interp(f, clip, old[:, ankle, i]) for i in range(3)], axis=1)  # as ``after`` plays it
        weight, pull, target = np.zeros(after.frames), np.zeros(after.frames), np.zeros((after.frames, 3))
        for a, b in _runs(planted):  # runs of clip frames
            held = np.zeros((before.frames, 2))  # the neutral's slides in this run, left out
            held[a + 1:b] = np.cumsum(slid[a:b - 1], axis=0)
            held[b:] = held[b - 1]
            place = ankle_at.copy()
            place[:, [0, 2]] -= np.stack([np.interp(f, clip, held[:, i]) for i in range(2)], axis=1)
            on = np.flatnonzero((nearest >= a) & (nearest < b))
            if not len(on):
                continue
            s, e = on[0], on[-1] + 1  # the run's output frames
            gap = np.linalg.norm(world[0][[s, e - 1], ankle] - place[[s, e - 1]], axis=1)  # how far the pin pulls
            fade = np.maximum(PIN_FADE, gap / PIN_SPEED) / after.frame_time
            d = np.maximum(s - frames, frames - (e - 1))
            f_ = np.where(frames < s, fade[0], fade[1])
            w = np.where(d <= 0, 1.0, np.where(d < f_, 0.5 + 0.5 * np.cos(np.pi * np.maximum(d, 0) / f_), 0.0))
            weight = np.maximum(weight, w)  # between two stances the pin glides from one place to the next
            pull += w
            target += w[:, None] * place
        target = target / np.maximum(pull, 1e-9)[:, None]
        target[:, 1] = ankle_at[:, 1]
        if weight.any():
            turned = world[1].copy()  # the foot as it stood in ``before``: its toes neither swing nor slide
            turned[:, ankle] = quat.slerp(world[1][:, ankle], _at(old_rot[:, ankle], f), weight)
            after = two_bone_ik(after, hip, knee, ankle, target, weight, world=(world[0], turned))
    return after


@per_motion
def _own_planted_moves(motion: Motion) -> tuple[np.ndarray, np.ndarray]:
    """``retarget.qa.planted_moves`` of a neutral clip on its own kinematics: read by every
    styling of the clip, several times each (worked out once per clip; read-only)."""
    flat, step = planted_moves(motion, forward_kinematics(motion))
    flat.flags.writeable = False
    step.flags.writeable = False
    return flat, step


@per_motion
def _own_contacts(motion: Motion, ankle: int) -> np.ndarray:
    """(F,) a neutral clip's foot contacts of one foot (once per clip; read-only)."""
    return foot_contacts(motion, [ankle], world=forward_kinematics(motion)[0])[:, 0]


def _at(q: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Quaternions (F, 4) at fractional frames ``f``: slerped between the two nearest."""
    q = make_continuous(q)
    k = np.clip(np.floor(f).astype(int), 0, len(q) - 1)
    n = np.minimum(k + 1, len(q) - 1)
    return quat.slerp(q[k], q[n], np.clip(f - k, 0.0, 1.0))


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """[start, end) of each run of True."""
    edges = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)))


def retime(motion: Motion, clip_to_out, oversample: int = 1) -> Motion:
    """The motion re-sampled after mapping clip time t to output time ``clip_to_out(t)``
    (non-decreasing on the clip's frame times), at ``oversample`` times its frame rate —
    so a stage squeezed into a few frames keeps its shape.

    Both the inverse time map (monotone cubic) and the poses (Catmull–Rom spline through the
    frames; quaternions sign-continuous, then normalised) are interpolated smoothly: linear
    interpolation would play a slowed clip as straight pieces with a velocity kink at every
    original frame, which is a train of jerk spikes."""
    return _retimed(motion, clip_to_out, oversample)[0]


def sliding_share(motion: Motion, frame_time: float | None = None) -> float:
    """The share of time a flat foot slides (``retarget.qa.check``), measured on the motion
    resampled (as :func:`retime` does) at ``frame_time`` — a stylised clip's — when given: at
    120 fps a landing the 30 fps clip shows in one frame is seen touching down, so a neutral
    clip and its styles are compared at the same rate."""
    if frame_time is not None and frame_time < motion.frame_time * 0.99:
        motion = retime(motion, lambda t: t, oversample=int(round(motion.frame_time / frame_time)))
    return len(check(motion).sliding) / max(motion.frames, 1)


def _retimed(motion: Motion, clip_to_out, oversample: int = 1) -> tuple[Motion, np.ndarray]:
    """:func:`retime`, and the clip time each output frame shows."""
    t = np.arange(motion.frames) * motion.frame_time
    if motion.frames < 2:
        return motion, t
    out = np.maximum.accumulate(np.asarray(clip_to_out(t), dtype=float))
    out = out - out[0]
    if out[-1] <= 0:
        return motion, t
    out = out + np.arange(motion.frames) * 1e-9  # strictly increasing for the inverse
    step = motion.frame_time / oversample
    n = int(np.floor(out[-1] / step + 1e-9)) + 1
    new_t = np.minimum(np.arange(n) * step, out[-1])
    clip_t = np.clip(PchipInterpolator(out, t)(new_t), 0.0, t[-1])
    poses = _catmull_rom(np.concatenate([motion.translations, make_continuous(motion.rotations)], axis=2),
                         clip_t / motion.frame_time)
    rots = poses[..., 3:] / np.linalg.norm(poses[..., 3:], axis=-1, keepdims=True)
    return replace(motion, translations=np.ascontiguousarray(poses[..., :3]), rotations=rots, frame_time=step), clip_t


def _catmull_rom(frames: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Frames (F, ...) at fractional frame indices ``f``: the Catmull–Rom spline through
    them (C¹, passes through every frame, ends clamped): four weighted frames per output."""
    last = len(frames) - 1
    f = np.clip(f, 0.0, last)
    k = np.minimum(np.floor(f).astype(int), max(last - 1, 0))
    u = f - k
    u2, u3 = u * u, u * u * u
    weights = np.stack([0.5 * (-u + 2 * u2 - u3), 0.5 * (2 - 5 * u2 + 3 * u3),
                        0.5 * (u + 4 * u2 - 3 * u3), 0.5 * (u3 - u2)], axis=1)
    cols = np.clip(k[:, None] + np.arange(-1, 3)[None], 0, last)
    flat = frames.reshape(len(frames), -1)
    out = weights[:, :1] * flat[cols[:, 0]]
    for tap in range(1, 4):
        out += weights[:, tap:tap + 1] * flat[cols[:, tap]]
    return out.reshape((len(f),) + frames.shape[1:])


def _oversample(motion: Motion) -> int:
    """Oversampling that brings a retimed clip's frames to at most 1/120 s apart."""
    return max(1, int(np.ceil(motion.frame_time * 30 * OVERSAMPLE - 1e-9)))


def stage_retiming(stages: Stages, frame_time: float, rates: dict) -> callable:
    """Eq. 5.3: clip time → output time, stage by stage; ``rates[stage] = (a, b)``."""
    bounds = stages.bounds()

    def f(t: np.ndarray) -> np.ndarray:
        out = np.zeros_like(t)
        offset = 0.0
        for name, (s, e) in bounds.items():
            s_t, e_t = s * frame_time, e * frame_time
            a, b = rates.get(name, (1.0, 1.0))
            inside = (t >= s_t) & (t <= e_t)
            out[inside] = offset + a * np.power(t[inside] - s_t, b)
            offset += a * np.power(max(e_t - s_t, 0.0), b)
        return out

    return f


def reshape(motion: Motion, start: int, end: int, angle: float, shape: str = "vertical", fade: int = 4) -> Motion:
    """Rotation shift on the spine about local x (vertical: sinking > 0, rising < 0) or the
    primary bones about local z (horizontal: spreading > 0, enclosing < 0) over frames
    [start, end), eased in and out over ``fade`` frames."""
    if angle == 0.0 or end <= start:
        return motion
    roles = guess_roles(motion.skeleton)
    if not {"pelvis", "chest", "head"} <= set(roles):
        return motion
    parts = partition(motion.skeleton, roles["pelvis"], roles["chest"], roles["head"])
    bones = [b for b in parts["spine"] if b != roles["pelvis"]] if shape == "vertical" else parts["primary"]
    axis = np.array([1.0, 0.0, 0.0]) if shape == "vertical" else np.array([0.0, 0.0, 1.0])
    w = np.zeros(motion.frames)
    w[start:end] = 1.0
    for k in range(1, fade + 1):
        if start - k >= 0:
            w[start - k] = 1 - k / (fade + 1)
        if end - 1 + k < motion.frames:
            w[end - 1 + k] = 1 - k / (fade + 1)
    rots = motion.rotations.copy()
    share = angle / max(len(bones), 1) if shape == "vertical" else angle
    for b in bones:
        name = motion.skeleton.names[b]
        sign = -1.0 if shape == "horizontal" and ("left" in name.lower() or name.endswith("_L")) else 1.0
        rots[:, b] = quat.multiply(rots[:, b], quat.exp(np.outer(w * share * sign, axis)))
    return replace(motion, rotations=rots)


def _execution(motion: Motion, stages: Stages, world: np.ndarray | None = None) -> tuple[int, int, int]:
    """(anticipation start, execution start, execution end) in clip frames. The execution is
    the burst of the clip's most moving hand or foot (:func:`~retarget.effort_signature.most_moving`)
    around its peak speed, where its speed is at least :data:`BURST_SHARE` of the peak — the
    stages may put it elsewhere, the effector does not —, unless that burst runs into the
    clip's last :data:`END_REST` seconds: that is the return to rest, which blends into the
    next action (a Dance's arms coming down, made Sudden, whipped into it at 16 m/s); then
    the burst before it. The anticipation ends where the
    execution starts, and starts where the stages say if their anticipation ends within one
    execution's length of it, else one execution's length earlier."""
    j = most_moving(motion, world)
    tt, v = speed_profile(motion, j, world)
    s, _, e = burst(v, BURST_SHARE)
    if e >= len(v) - END_REST * RATE and v[:s].max(initial=0.0) > 0:  # the clip's return to rest: not it
        s, _, e = burst(np.where(np.arange(len(v)) < s, v, 0.0), BURST_SHARE)
    start, end = (int(np.clip(round(x / RATE / motion.frame_time), 0, motion.frames - 1)) for x in (s, e))
    end = max(end, start + 2)
    span = end - start
    fits = abs(stages.anticipation - start) <= span and stages.preparation < start
    return (stages.preparation if fits else max(0, start - span)), start, min(end, motion.frames)


def _time_poses(motion: Motion, spans: tuple[int, int, int], lt: float, effector: int) -> Motion:
    """Time's motion scale: the anticipation scaled down fully by 1/(3|L_t| + 1), the change
    fading out over the execution (so the execution still reaches its neutral pose) — the
    legs only when a foot acts (``effector``, a kick): a supporting leg's step scaled down
    drags its foot over the floor instead of lifting it."""
    ant, start, end = spans
    c = 1.0 / (3 * abs(lt) + 1.0)
    return motion_scale(motion, ant, max(start, ant + 1), c, "full", keep_contacts=False, smooth=False,
                        fade_end=end, bones=_acting(motion, "full", effector))


def _time_rates(motion: Motion, spans: tuple[int, int, int], lt: float, speed: np.ndarray) -> np.ndarray:
    """Time's playback rate (clip seconds per output second) over each clip frame interval:
    1 outside the anticipation and execution (and, Sudden, the strokes that repeat the
    execution, :func:`_repeated_strokes`, played as fast as it is on average); the
    anticipation at ``1 − 0.5 L_t`` (Sudden: longer) or ``1/(1 + 0.5 L_t)`` (Sustained:
    shorter); the execution ``1 + 2 L_t`` times as fast on average, accelerating from ⅔ to
    4⁄3 of that (Sudden), or ``1 + 2|L_t|`` times as long, evened out — slow parts played
    relatively faster, ``∝ (v̄/v)^{|L_t|/2}`` of the effector's speed ``v`` — and nowhere
    faster than the neutral (Sustained) (eq. 5.3's intent, without its power law's stop at
    the execution's start)."""
    ant, start, end = spans
    rate = np.ones(motion.frames - 1)
    rate[ant:start] = 1.0 - 0.5 * lt if lt >= 0 else 1.0 / (1.0 + 0.5 * lt)
    n = max(end - start, 1)
    u = (np.arange(n) + 0.5) / n
    if lt > 0:
        rate[start:end] = (1 + 2 * lt) * (1 + (2 / 3) * lt * (u[: len(rate[start:end])] - 0.5))
        for a, b in _repeated_strokes(speed, start, end):
            rate[a:b] = 1 + 2 * lt
    else:
        v = np.maximum(speed[start:end], 0.1 * speed.max() + 1e-9)
        r = np.power(v.mean() / v, 0.5 * abs(lt))
        r *= (1.0 / (1 + 2 * abs(lt))) / (1.0 / np.mean(1.0 / r))
        rate[start:end] = np.minimum(r, 1.0)[: len(rate[start:end])]
        rate = _below_execution(rate, speed, start, end)
    return rate


def _repeated_strokes(speed: np.ndarray, start: int, end: int) -> list[tuple[int, int]]:
    """The strokes that repeat the execution after it, as ``[start, end)`` clip frames, for
    Sudden to quicken: a wave's swings after the arm is raised, a dance's moves after its
    first, a jab after an uppercut — the effector's later bursts of speed at least
    :data:`BURST_SHARE` of the execution's peak, as the execution itself is found. The last
    of them is the return to rest (the arm lowered, blending into the next action: left at
    its pace, as :func:`_execution` leaves it), and the pauses between them keep theirs
    (quick strokes, not a fast-forward). Without this a Sudden wave raised its arm quickly
    and then waved at the neutral pace, where Sustained slows every stroke
    (:func:`_below_execution`)."""
    if end <= start or end >= len(speed):
        return []
    moving = speed >= BURST_SHARE * float(speed[start:end].max())
    moving[:end] = False
    return [(int(a), int(b)) for a, b in _runs(moving)[:-1]]


def _below_execution(rate: np.ndarray, speed: np.ndarray, start: int, end: int) -> np.ndarray:
    """Sustained's rates with the effector nowhere outside the execution faster, as played,
    than :data:`SUSTAINED_CAP` of its fastest inside it: an anticipation played faster, or a
    second burst left at its own pace, would otherwise be the clip's fastest and
    widest-at-half-peak movement, and the slowed execution no longer its main one."""
    played = rate * speed
    cap = SUSTAINED_CAP * played[start:end].max() if end > start else np.inf
    outside = np.ones(len(rate), dtype=bool)
    outside[start:end] = False
    rate[outside] = np.minimum(rate[outside], cap / np.maximum(speed[outside], 1e-9))
    return rate


def _weight_poses(motion: Motion, spans: tuple[int, int, int], lw: float, effector: int) -> Motion:
    """Weight's partial motion scale of the whole clip (spine and primary bones by ``1 + L_w``
    or ``1/(1 − L_w)``; the legs only when a foot acts — ``effector``, a kick —: a step's
    swing scaled would land the foot elsewhere), the acting hand or foot's path widened or
    narrowed (:func:`_widen`) and the Vertical-shape shift over the execution."""
    c = 1.0 + lw if lw > 0 else 1.0 / (1.0 - lw)
    m = motion_scale(motion, 0, motion.frames, c, "partial", keep_contacts=False, smooth=False,
                     bones=_acting(motion, "partial", effector))
    k = 1.0 + WIDEN * lw if lw > 0 else 1.0 / (1.0 - WIDEN * lw)
    m = _widen(m, effector, k, forward_kinematics(motion)[0])
    return reshape(m, spans[1], spans[2], 0.1 * lw, "vertical")


def _widen(motion: Motion, effector: int, k: float, neutral: np.ndarray) -> Motion:
    """The effector's path as the neutral clip makes it (``neutral``: its joint positions) —
    in the world, less the body's travel (the pelvis's ground-plane path low-passed over
    :data:`TRAVEL_SMOOTHING`) — scaled by ``k`` about its mean, reached by two-bone IK on the
    limb from where ``motion`` puts its shoulder or hip (as far as the limb reaches). The
    neutral's path, not ``motion``'s: the partial motion scale before this turns the chest
    further, which swings a straight arm sideways (a punch's reach shrinks); the world's, not
    the shoulder's: a strike's sway and lean into it are part of the movement that widens.

    A foot (a kick) widens about its floor, not its mean: its height above its lowest point is
    scaled by ``k`` (a Strong kick goes higher, a Light one lower; :func:`_above_floor` keeps
    its toes out of the floor), and sideways its path widens or narrows only as it lifts off
    (fully :data:`FOOT_CLEAR` above the floor). Scaled about the mean, a
    foot below it is pushed into the floor, where it dragged through the kick's wind-up and
    then snapped up (Crescent Kick Strong: held at the floor while the neutral lifted 0.25 m,
    then up at 9 m/s)."""
    parents = motion.skeleton.parents
    mid = int(parents[effector])
    top = int(parents[mid]) if mid >= 0 else -1
    base = int(parents[top]) if top >= 0 else -1
    if base < 0 or k == 1.0:
        return motion
    world = forward_kinematics(motion)
    p = world[0]
    pelvis = pelvis_of(motion.skeleton)
    sigma = TRAVEL_SMOOTHING / motion.frame_time
    travel = gaussian_filter1d(neutral[:, pelvis], sigma, axis=0, mode="nearest") * [1.0, 0.0, 1.0]
    rel = neutral[:, effector] - travel
    centre = rel.mean(axis=0)
    moved = gaussian_filter1d(p[:, pelvis], sigma, axis=0, mode="nearest") * [1.0, 0.0, 1.0]
    target = moved + centre + k * (rel - centre)
    if effector in _leg_bones(motion):
        floor = float(rel[:, 1].min())
        lift = np.clip((rel[:, 1] - floor) / FOOT_CLEAR, 0.0, 1.0)
        side = moved + rel + ((k - 1.0) * lift * lift * (3.0 - 2.0 * lift))[:, None] * (rel - centre)
        up = floor + k * (rel[:, 1] - floor)
        target = np.concatenate([side[:, :1], up[:, None], side[:, 2:]], axis=1)
    target[:, 1] = np.maximum(target[:, 1], min(p[:, effector, 1].min(), target[:, 1].max()))  # a foot no lower than it went
    return two_bone_ik(motion, top, mid, effector, target, np.ones(motion.frames), world=world)


def _sole(motion: Motion, world: tuple[np.ndarray, np.ndarray], ankle: int) -> np.ndarray:
    """(F,) the lowest point of a foot — its ankle, toes and their End Sites — as the animation
    check reads it (``retarget.qa.foot_points``)."""
    return foot_points(motion, world[0], end_site_positions(motion, world), ankle)[..., 1].min(axis=1)


@per_motion
def _soles(motion: Motion) -> np.ndarray:
    """(F,) a neutral clip's lower foot's lowest point per frame (its 2nd percentile is the
    clip's floor, as the check reads it); empty without two feet. Once per clip, read-only."""
    roles = guess_roles(motion.skeleton)
    feet = [roles[k] for k in ("left_foot", "right_foot") if k in roles]
    if len(feet) < 2:
        return np.zeros(0)
    world = forward_kinematics(motion)
    out = np.min([_sole(motion, world, a) for a in feet], axis=0)
    out.flags.writeable = False
    return out


def _above_floor(edited: Motion, motion: Motion, effector: int) -> Motion:
    """The ``edited`` clip with its kicking foot (``effector`` on a leg) lifted where the edits
    put any point of it below the neutral clip's (``motion``'s) floor: scaled, a wind-up or a
    narrowed path swung the toes through the floor — and the standing foot then read as
    hovering above a floor that low for the whole clip (Kick and Crescent Kick with Time).
    Raised by the depth, low-passed over :data:`EDIT_SMOOTHING`, by IK on the leg."""
    roles = guess_roles(edited.skeleton)
    parents = edited.skeleton.parents
    soles = _soles(motion)
    if effector not in (roles.get("left_foot"), roles.get("right_foot")) or not soles.size \
            or parents[parents[effector]] < 0:
        return edited
    world = forward_kinematics(edited)
    depth = np.maximum(float(np.percentile(soles, 2)) - _sole(edited, world, effector), 0.0)
    if depth.max() <= 1e-4:
        return edited
    sigma = EDIT_SMOOTHING / edited.frame_time
    lift = np.maximum(gaussian_filter1d(maximum_filter1d(depth, int(2 * sigma) + 1), sigma, mode="nearest"), depth)
    target = world[0][:, effector] + lift[:, None] * [0.0, 1.0, 0.0]
    knee = int(parents[effector])
    return two_bone_ik(edited, int(parents[knee]), knee, effector, target, np.ones(edited.frames), world=world)


def _acting(motion: Motion, mode: str, effector: int) -> np.ndarray:
    """The bones ``mode`` scales (:func:`_bones`), less the legs unless ``effector`` is on one."""
    legs = _leg_bones(motion)
    keep = legs if effector not in legs else set()
    return np.array([b for b in _bones(motion, mode) if b not in keep], dtype=int)


def _leg_bones(motion: Motion) -> set:
    """The legs: the pelvis's children off the spine, and everything under them."""
    roles = guess_roles(motion.skeleton)
    if not {"pelvis", "chest", "head"} <= set(roles):
        return set()
    spine = partition(motion.skeleton, roles["pelvis"], roles["chest"], roles["head"])["spine"]
    legs, stack = set(), [c for c in motion.skeleton.children(roles["pelvis"]) if c not in spine]
    while stack:
        b = stack.pop()
        legs.add(b)
        stack.extend(motion.skeleton.children(b))
    return legs


def _weight_times(world: np.ndarray, times: np.ndarray, lw: float, frame_time: float,
                  keep: tuple[int, ...] = ()) -> np.ndarray:
    """Output time of each frame once Weight has retimed a motion — joint positions
    ``world`` (F, J, 3), clip frames ``frame_time`` apart — whose frames already play at
    ``times``: speed ∝ ``V_e^{α L_w}``, the duration kept (eq. 5.4–5.5).

    ``keep``: clip frames where stages meet (Time's anticipation and execution, when Time
    retimed them) whose stages keep the durations ``times`` gave them — Weight then shapes the
    speed within each stage, and how long each takes stays Time's. Retimed over the whole clip
    instead, Strong squeezes the execution further and Light stretches it back: Sudden Light
    came out no faster than the neutral clip (peak speed up and execution shorter in none of
    the nine held-out Bandai one-shots). The per-stage correction is eased over
    :data:`STAGE_EASE` of clip time, so that the playback rate does not jump where stages meet."""
    dt = np.maximum(np.diff(times), 1e-9)
    speed = np.linalg.norm(np.diff(world, axis=0), axis=2).mean(axis=1) / dt
    v = np.concatenate([speed[:1], speed]) / max(speed.mean(), 1e-9)
    if lw < 0:
        v = np.clip(v / max(v.max(), 1e-9), 0.05, 1.0)
    else:
        v = np.maximum(v, 0.05)
    alpha = ALPHA_WEIGHT if lw > 0 else ALPHA_LIGHT
    rate = np.clip(np.power(v[1:], alpha * lw), 1 / MAX_SPEEDUP, MAX_SPEEDUP)  # clip s per output s
    dt_out = dt / rate
    if keep:
        cuts = sorted({0, len(dt), *(int(np.clip(k, 0, len(dt))) for k in keep)})
        undo = np.zeros(len(dt))  # log of each stage's correction back to its duration
        for a, b in zip(cuts[:-1], cuts[1:]):
            if b > a:
                undo[a:b] = np.log(dt[a:b].sum() / max(dt_out[a:b].sum(), 1e-12))
        dt_out *= np.exp(gaussian_filter1d(undo, STAGE_EASE / frame_time, mode="nearest"))
    dt_out *= (times[-1] - times[0]) / max(dt_out.sum(), 1e-9)
    return times[0] + np.concatenate([[0.0], np.cumsum(dt_out)])


def _bounded(times: np.ndarray, least: np.ndarray, keep_duration: bool,
             most: np.ndarray | None = None) -> np.ndarray:
    """The time map with each clip frame interval lasting at least ``least`` (s) — so no
    joint outruns the bound there (:func:`_least`) —: the frames it would play too fast
    take longer (``keep_duration``: the others shorter, so the clip keeps its length); and at
    most ``most`` (s; a flight at its own pace, :func:`_flight`) unless ``least`` says more."""
    dt = np.maximum(np.diff(times), 1e-9)
    total = dt.sum()
    hi = np.full(len(dt), np.inf) if most is None else np.maximum(most, least)
    for _ in range(6):
        dt = np.clip(dt, least, hi)
        free = (dt > least * (1 + 1e-6)) & (dt < hi * (1 - 1e-6))
        if not keep_duration or not free.any():
            break
        spare = total - dt[~free].sum()
        if spare <= 0:
            break
        dt[free] *= spare / dt[free].sum()
    return times[0] + np.concatenate([[0.0], np.cumsum(dt)])


@per_motion
def _flight(motion: Motion) -> np.ndarray:
    """(F − 1,) the clip frame intervals in the air: both soles off the clip's floor at either
    end, as the animation check reads it, in a run where they rise :data:`JUMP_CLEAR` or more
    (not a DeepMimic punch's shuffle) for :data:`JUMP_AIR` or longer (not a running stride's
    flight phase), with its take-off and landing. Time and Weight play them no slower than the clip's own
    pace: how long a body stays up is gravity's, not the mover's — slowed, a Sustained or Light
    jump, flip or back flip hung in the air (soles up for longer than any real jump: 11 of 200
    styled built-in one-shots failed the animation check so). Sudden may still play a flight
    quicker (a snappier, lower-looking jump; kept so that a jumping kick shows its Time)."""
    soles = _soles(motion)
    if not soles.size or motion.frames < 2:
        return np.zeros(max(motion.frames - 1, 0), dtype=bool)
    lowest = soles - np.percentile(soles, 2)
    up = np.zeros(motion.frames, dtype=bool)
    for a, b in _runs(lowest > Limits().hover):  # off the floor as the check reads it, and a jump's height
        up[max(a - 1, 0):b + 1] = lowest[a:b].max() >= JUMP_CLEAR and (b - a) * motion.frame_time >= JUMP_AIR
    return up[1:] | up[:-1]


def _flight_most(air: np.ndarray, frame_time: float) -> np.ndarray:
    """Per clip frame interval, the longest it may play: a flight (``air``, :func:`_flight`)
    at its own pace, the intervals around it slower by at most one more frame time per
    :data:`FLIGHT_EASE` of clip time away from it — no step in the playback rate where a
    slowed take-off meets the flight (a jerk)."""
    if not air.any():
        return np.full(len(air), np.inf)
    away = np.abs(np.arange(len(air))[:, None] - np.flatnonzero(air)[None]).min(axis=1) * frame_time
    return frame_time * (1.0 + away / FLIGHT_EASE)


def _least(points: np.ndarray) -> np.ndarray:
    """Per clip frame interval of the body's points (F, P, 3, ``retarget.skeleton.body_points``:
    the End Sites too, which the animation check counts), the least time
    it may take for none to move faster than ``SPEED_MARGIN × FASTEST``."""
    return np.linalg.norm(np.diff(points, axis=0), axis=2).max(axis=1) / (SPEED_MARGIN * FASTEST)


def _planted_least(motion: Motion) -> np.ndarray:
    """Per clip frame interval, the least time it may take so a foot flat on the floor in the
    neutral clip (``retarget.qa.planted_moves``) at either end of it — shuffling, turning on
    its ball, landing — moves no faster than in the neutral, or than :data:`PLANTED_SPEED`:
    played faster, a foot creeping over the floor, or landing, slides."""
    flat, step = _own_planted_moves(motion)
    if not flat.size:
        return np.zeros(max(motion.frames - 1, 0))
    least = np.minimum(motion.frame_time, np.linalg.norm(step, axis=2) / PLANTED_SPEED)
    return np.where(flat[1:] | flat[:-1], least, 0.0).max(axis=1)


def _rise_least(motion: Motion, world: np.ndarray) -> np.ndarray:
    """Per clip frame interval, the least time it may take so that, where both feet stand flat
    on the floor in the neutral clip, the pelvis of the edited clip (joint positions ``world``)
    rises no faster than ``retarget.sequence.RISE_MARGIN`` × the animation check's limit, or
    than in the neutral clip (:func:`retarget.sequence.rise_least`)."""
    return rise_least(_own_planted_moves(motion)[0], world[:, pelvis_of(motion.skeleton), 1], motion.frame_time)


def _too_fast(out: Motion, clip_t: np.ndarray, clip_frame_time: float, clip_frames: int) -> np.ndarray:
    """Per clip frame interval, how many times faster than ``SPEED_BOUND × FASTEST`` the
    fastest point of the output ``out`` (``body_points``; its frames showing clip times
    ``clip_t``) moves while it plays that interval (≤ 1 where none does)."""
    points = body_points(out)
    v = np.linalg.norm(np.diff(points, axis=0), axis=2).max(axis=1) / out.frame_time / (SPEED_BOUND * FASTEST)
    k = np.clip((0.5 * (clip_t[1:] + clip_t[:-1]) / clip_frame_time).astype(int), 0, clip_frames - 2)
    over = np.zeros(clip_frames - 1)
    np.maximum.at(over, k, v)
    return over


def _smooth_rate(times: np.ndarray, frame_time: float) -> np.ndarray:
    """The time map with its playback rate smoothed over about ``RATE_SMOOTHING`` seconds
    (in the log domain, the duration kept): eq. 5.3 changes rate abruptly where stages
    meet, and a step in playback speed is a spike of jerk that no performer would make."""
    dt = np.maximum(np.diff(times), 1e-9)
    if len(dt) < 3 or RATE_SMOOTHING <= 0:
        return times
    log_rate = gaussian_filter1d(np.log(dt), RATE_SMOOTHING / frame_time, mode="nearest")
    dt = np.exp(log_rate) * (times[-1] - times[0]) / np.exp(log_rate).sum()
    return times[0] + np.concatenate([[0.0], np.cumsum(dt)])


def stylize_staged(motion: Motion, stages: Stages, lt: float = 0.0, lw: float = 0.0) -> tuple[Motion, Stages]:
    """Time then Weight (§5.4.3), and the stages moved with the motion.

    Both modifiers' pose edits (motion scales, reshaping) act on the clip's own frames; Time's
    playback rates (:func:`_time_rates`) act on the execution burst of the clip's most moving
    hand or foot (:func:`_execution`); Weight's retiming reads speeds as they play after
    Time's; the two time maps are composed, bounded so no joint outruns real motion capture
    (:func:`_bounded`), and the clip resampled once; then the feet that stood in the neutral
    clip are put back where they stood (:func:`_restore_contacts`, on the output frames).
    Quaternions come back sign-continuous per joint. ``L_t = L_w = 0`` returns the clip itself."""
    lt, lw = float(np.clip(lt, -1.0, 1.0)), float(np.clip(lw, -1.0, 1.0))
    if (lt == 0.0 and lw == 0.0) or motion.frames < 2:
        return motion, stages
    t = np.arange(motion.frames) * motion.frame_time
    neutral_world = forward_kinematics(motion)[0]
    spans = _execution(motion, stages, neutral_world) if motion.frames >= 4 else (0, 0, motion.frames)
    m, times = motion, t
    j = most_moving(motion, neutral_world)  # the acting hand or foot
    if lt:
        m = _time_poses(m, spans, lt, j)
        tt, v = speed_profile(m, j)  # as the anticipation scaled down leaves it
        speed = np.interp(t[:-1] + 0.5 * motion.frame_time, tt, v)
        rate = _time_rates(motion, spans, lt, speed)
        times = np.concatenate([[0.0], np.cumsum(motion.frame_time / rate)])
    if lw:
        m = _weight_poses(m, spans, lw, j)
    m = smooth_edit(motion, m)
    if (lt or lw) and motion.frames >= 4:
        m = _above_floor(m, motion, j)
    world = forward_kinematics(m)
    if lw:
        times = _weight_times(world[0], times, lw, motion.frame_time, spans if lt else ())
    times = _smooth_rate(times, motion.frame_time)
    least = np.maximum.reduce([_least(body_points(m, world)), _planted_least(motion), _rise_least(motion, world[0])])
    most = _flight_most(_flight(motion), motion.frame_time)
    for _ in range(5):  # the output measured as it plays — spline, contact IK and all — and slowed where too fast
        times = _bounded(times, least, keep_duration=not lt, most=most)
        out, clip_t = _retimed(m, lambda _: times, oversample=_oversample(m))
        out = _restore_contacts(motion, out, clip_frames=clip_t / motion.frame_time)
        over = _too_fast(out, clip_t, motion.frame_time, motion.frames)
        if over.max() <= 1.0:
            break
        least = np.maximum(least, np.diff(times) * maximum_filter1d(np.maximum(over, 1.0), 3) * 1.02)
    ends = np.array([stages.preparation, stages.anticipation, stages.execution, stages.follow_through])
    at = np.interp(np.minimum(ends, motion.frames - 1) * motion.frame_time, t, times) - times[0]
    new = np.minimum(np.maximum.accumulate(np.rint(at / out.frame_time).astype(int)), out.frames)
    out = replace(out, rotations=make_continuous(out.rotations))
    return out, Stages(*(int(k) for k in new), out.frames)


def time_modifier(motion: Motion, stages: Stages, lt: float) -> tuple[Motion, Stages]:
    """Sudden (L_t > 0) or Sustained (L_t < 0); returns the motion and its new stages."""
    return stylize_staged(motion, stages, lt, 0.0)


def weight_modifier(motion: Motion, stages: Stages, lw: float) -> Motion:
    """Strong (L_w > 0) or Light (L_w < 0), duration kept."""
    return stylize_staged(motion, stages, 0.0, lw)[0]


def stylize(motion: Motion, stages: Stages, lt: float = 0.0, lw: float = 0.0) -> Motion:
    """Time then Weight (§5.4.3): :func:`stylize_staged` without the stages."""
    return stylize_staged(motion, stages, lt, lw)[0]


def preferred(motion: Motion, stages: Stages, lt: float = 0.0, lw: float = 0.0) -> Motion:
    """The combination the thesis's user study preferred (§5.4.3, §5.5): motion scale and
    reshaping without the modifiers' own retiming — the timing comes from the gesture
    (``doodle compile --style preferred`` retimes one-shots by the hand, §5.3.3). Time
    scales preparation and anticipation down by ``1/(3|L_t| + 1)``; Weight scales the whole
    clip by ``1 + L_w`` or ``1/(1 − L_w)`` and shifts the posture by ``0.1 L_w``; then the
    feet that stood in the neutral clip are put back where they stood, as
    :func:`stylize_staged` does."""
    lt, lw = float(np.clip(lt, -1.0, 1.0)), float(np.clip(lw, -1.0, 1.0))
    m = motion
    if lt:
        c = 1.0 / (3 * abs(lt) + 1.0)
        m = motion_scale(m, 0, max(stages.anticipation, 1), c, "full", keep_contacts=False)
    if lw:
        m = motion_scale(m, 0, m.frames, 1.0 + lw if lw > 0 else 1.0 / (1.0 - lw), "partial", keep_contacts=False)
        m = reshape(m, stages.anticipation, stages.execution, 0.1 * lw, "vertical")
    return _restore_contacts(motion, m) if m is not motion else m


def cyclic(motion: Motion, lw: float = 0.0) -> Motion:
    """Weight on a cyclic clip (a walk): its pace comes from the hand's travel, so there is
    no retiming and no Time; the upper body (spine, arms, head) swings ``1 + L_w`` (Strong) or
    ``1/(1 − L_w)`` (Light) times as far about each bone's mean pose over the cycle — not
    about frame 0, so the stride stays symmetric and the loop closes — and the posture sinks
    or rises by ``0.1 L_w``. The legs are left alone: their stride is what the clip's
    distance per cycle and the feet's contacts rest on."""
    lw = float(np.clip(lw, -1.0, 1.0))
    if lw == 0.0 or motion.frames < 3:
        return motion
    c = 1.0 + lw if lw > 0 else 1.0 / (1.0 - lw)
    bones = _upper_body(motion)
    rots, trans = motion.rotations.copy(), motion.translations.copy()
    q = make_continuous(rots[:, bones])
    mean = q.mean(axis=0)
    mean /= np.linalg.norm(mean, axis=-1, keepdims=True)
    mean = np.broadcast_to(mean, q.shape)
    rel = quat.multiply(quat.conjugate(mean), q)  # each frame relative to the mean pose
    rots[:, bones] = quat.multiply(mean, _slerp_identity(rel, c))
    centre = trans[:, bones].mean(axis=0)
    trans[:, bones] = centre + c * (trans[:, bones] - centre)
    out = reshape(replace(motion, rotations=rots, translations=trans), 0, motion.frames, 0.1 * lw, "vertical", fade=0)
    return out


def _upper_body(motion: Motion) -> np.ndarray:
    """Bones a cycle's Weight acts on: every one :func:`_bones` would scale fully, less the
    legs (the pelvis's children off the spine, and everything under them)."""
    bones = set(_bones(motion, "full").tolist())
    roles = guess_roles(motion.skeleton)
    if {"pelvis", "chest", "head"} <= set(roles):
        spine = partition(motion.skeleton, roles["pelvis"], roles["chest"], roles["head"])["spine"]
        stack = [c for c in motion.skeleton.children(roles["pelvis"]) if c not in spine]
        while stack:
            b = stack.pop()
            bones.discard(b)
            stack.extend(motion.skeleton.children(b))
    return np.array(sorted(bones), dtype=int)

