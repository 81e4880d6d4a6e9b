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
  a speed proportional to ``V_e^{α L_w}`` (α = 1.5, ``V_e`` the mean joint speed, made
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
from scipy.interpolate import PchipInterpolator
from scipy.ndimage import gaussian_filter1d
from scipy.sparse import csr_matrix

from doodle.core import quat
from doodle.core.quat import make_continuous
from retarget.analysis import Stages, foot_contacts, guess_roles, partition
from retarget.feet import two_bone_ik
from retarget.skeleton import Motion, forward_kinematics

ALPHA_WEIGHT = 1.5
OVERSAMPLE = 4  # retimed output has 4× a 30 fps clip's frame rate: frames at most 1/120 s apart
EDIT_SMOOTHING = 0.05  # s: pose edits are low-passed over this much clip time
RATE_SMOOTHING = 0.04  # s: the playback rate's changes are smoothed over this much clip time
MAX_SPEEDUP = 3.0  # Weight retiming plays no frame more than 3× faster (or slower) than the clip


def _bones(motion: Motion, mode: str) -> np.ndarray:
    """Joints a motion scale acts on — never the root nor joints above the pelvis: they
    carry the character's place and facing (scaling them would slide a walk and turn a
    flip into one and a half)."""
    roles = guess_roles(motion.skeleton)
    pelvis = roles.get("pelvis", 0)
    carriers = {0, pelvis} if motion.skeleton.parents[pelvis] < 0 else set(range(pelvis + 1))
    if mode == "full" or not {"pelvis", "chest", "head"} <= set(roles):
        chosen = range(len(motion.skeleton))
    else:
        parts = partition(motion.skeleton, roles["pelvis"], roles["chest"], roles["head"])
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
                 keep_contacts: bool = True, smooth: bool = True) -> Motion:
    """Eq. 5.1 over frames [start, end), cohesion (eq. 5.2) after it, the edit smoothed
    (:func:`smooth_edit`) and contacts restored."""
    if c == 1.0 or end - start < 2:
        return motion
    end = min(end, motion.frames)
    bones = _bones(motion, mode)
    rots, trans = motion.rotations.copy(), motion.translations.copy()
    q0 = np.broadcast_to(rots[start, bones], (end - start, len(bones), 4))
    r = quat.multiply(q0, quat.conjugate(rots[start:end, bones]))  # q(ts) q(t)^-1
    rots[start:end, bones] = quat.multiply(quat.conjugate(_slerp_identity(r, c)), q0)
    trans[start:end, bones] = trans[start, bones] + c * (trans[start:end, bones] - trans[start, bones])
    if end < motion.frames:  # cohesion: the change at the end fades out over the rest
        last = end - 1
        w = 1.0 - (np.arange(end, motion.frames) - last) / max(motion.frames - 1 - last, 1)
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


def _restore_contacts(before: Motion, after: Motion, world=None) -> Motion:
    """``after`` with the feet that touched the ground in ``before`` back where they stood
    (``world``: ``forward_kinematics(after)`` if the caller has it)."""
    roles = guess_roles(before.skeleton)
    feet = [roles[k] for k in ("left_foot", "right_foot") if k in roles]
    if not feet:
        return after
    old = forward_kinematics(before)[0]
    contact = foot_contacts(before, feet, world=old)
    world = world or forward_kinematics(after)  # the legs are separate chains: one pass serves both
    for k, ankle in enumerate(feet):
        if not contact[:, k].any():
            continue
        knee = int(before.skeleton.parents[ankle])
        hip = int(before.skeleton.parents[knee]) if knee >= 0 else -1
        if hip < 0:
            continue
        target = old[:, ankle]  # where it stood, not only how high: a planted foot neither lifts nor slides
        after = two_bone_ik(after, hip, knee, ankle, target, contact[:, k].astype(float), world=world)
    return after


def retime(motion: Motion, clip_to_out, oversample: int = 1) -> Motion:
    """The motion re-sampled after mapping clip time t to output time ``clip_to_out(t)``
    (non-decreasing on the clip's frame times), at ``oversample`` times its frame rate —
    so a stage squeezed into a few frames keeps its shape.

    Both the inverse time map (monotone cubic) and the poses (Catmull–Rom spline through the
    frames; quaternions sign-continuous, then normalised) are interpolated smoothly: linear
    interpolation would play a slowed clip as straight pieces with a velocity kink at every
    original frame, which is a train of jerk spikes."""
    if motion.frames < 2:
        return motion
    t = np.arange(motion.frames) * motion.frame_time
    out = np.maximum.accumulate(np.asarray(clip_to_out(t), dtype=float))
    out = out - out[0]
    if out[-1] <= 0:
        return motion
    out = out + np.arange(motion.frames) * 1e-9  # strictly increasing for the inverse
    step = motion.frame_time / oversample
    n = int(np.floor(out[-1] / step + 1e-9)) + 1
    new_t = np.minimum(np.arange(n) * step, out[-1])
    clip_t = np.clip(PchipInterpolator(out, t)(new_t), 0.0, t[-1])
    poses = _catmull_rom(np.concatenate([motion.translations, make_continuous(motion.rotations)], axis=2),
                         clip_t / motion.frame_time)
    rots = poses[..., 3:] / np.linalg.norm(poses[..., 3:], axis=-1, keepdims=True)
    return replace(motion, translations=np.ascontiguousarray(poses[..., :3]), rotations=rots, frame_time=step)


def _catmull_rom(frames: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Frames (F, ...) at fractional frame indices ``f``: the Catmull–Rom spline through
    them (C¹, passes through every frame, ends clamped), as one sparse matrix product —
    four weights per output row."""
    last = len(frames) - 1
    f = np.clip(f, 0.0, last)
    k = np.minimum(np.floor(f).astype(int), max(last - 1, 0))
    u = f - k
    u2, u3 = u * u, u * u * u
    weights = np.stack([0.5 * (-u + 2 * u2 - u3), 0.5 * (2 - 5 * u2 + 3 * u3),
                        0.5 * (u + 4 * u2 - 3 * u3), 0.5 * (u3 - u2)], axis=1)
    cols = np.clip(k[:, None] + np.arange(-1, 3)[None], 0, last)
    rows = np.repeat(np.arange(len(f)), 4)
    w = csr_matrix((weights.ravel(), (rows, cols.ravel())), shape=(len(f), len(frames)))
    return (w @ frames.reshape(len(frames), -1)).reshape((len(f),) + frames.shape[1:])


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


def _time_poses(motion: Motion, stages: Stages, lt: float) -> Motion:
    """Time's motion scale: preparation and anticipation scaled down fully by 1/(3|L_t| + 1)."""
    c = 1.0 / (3 * abs(lt) + 1.0)
    m = motion_scale(motion, 0, max(stages.preparation, 1), c, "full", keep_contacts=False, smooth=False)
    return motion_scale(m, stages.preparation, max(stages.anticipation, stages.preparation + 1), c, "full",
                        keep_contacts=False, smooth=False)


def _time_map(stages: Stages, frame_time: float, lt: float):
    """Time's retiming (eq. 5.3): anticipation and execution rates for ``L_t``."""
    ant = 1.0 / (1.0 - 0.5 * lt) if lt >= 0 else 0.5 * lt + 1.0
    exe = (1.0 / (2 * lt + 1.0), 1.0 - 0.4 * lt) if lt >= 0 else (1.0 - 2 * lt, 1.0 - 0.4 * lt)
    return stage_retiming(stages, frame_time, {"anticipation": (ant, 1.0), "execution": exe})


def _weight_poses(motion: Motion, stages: Stages, lw: float) -> Motion:
    """Weight's partial motion scale of the whole clip and its Vertical-shape shift."""
    c = 1.0 + lw if lw > 0 else 1.0 / (1.0 - lw)
    m = motion_scale(motion, 0, motion.frames, c, "partial", keep_contacts=False, smooth=False)
    return reshape(m, stages.anticipation, stages.execution, 0.1 * lw, "vertical")


def _weight_times(world: np.ndarray, times: np.ndarray, lw: float) -> np.ndarray:
    """Output time of each frame once Weight has retimed a motion — joint positions
    ``world`` (F, J, 3) — whose frames already play at ``times``: speed ∝ ``V_e^{α L_w}``,
    the duration kept (eq. 5.4–5.5)."""
    dt = np.maximum(np.diff(times), 1e-9)
    speed = np.linalg.norm(np.diff(world, axis=0), axis=2).mean(axis=1) / dt
    v = np.concatenate([speed[:1], speed]) / max(speed.mean(), 1e-9)
    if lw < 0:
        v = np.clip(v / max(v.max(), 1e-9), 0.05, 1.0)
    else:
        v = np.maximum(v, 0.05)
    rate = np.clip(np.power(v[1:], ALPHA_WEIGHT * lw), 1 / MAX_SPEEDUP, MAX_SPEEDUP)  # clip s per output s
    dt_out = dt / rate
    dt_out *= (times[-1] - times[0]) / max(dt_out.sum(), 1e-9)
    return times[0] + np.concatenate([[0.0], np.cumsum(dt_out)])


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

    Both modifiers' pose edits (motion scales, reshaping) act on the clip's own frames; the
    feet are put back on the ground once; Weight's retiming reads speeds as they play after
    Time's; the two time maps are composed and the clip resampled once. Quaternions come
    back sign-continuous per joint. ``L_t = L_w = 0`` returns the clip itself."""
    lt, lw = float(np.clip(lt, -1.0, 1.0)), float(np.clip(lw, -1.0, 1.0))
    if (lt == 0.0 and lw == 0.0) or motion.frames < 2:
        return motion, stages
    t = np.arange(motion.frames) * motion.frame_time
    m, times = motion, t
    if lt:
        m = _time_poses(m, stages, lt)
        times = _time_map(stages, motion.frame_time, lt)(t)
    if lw:
        m = _weight_poses(m, stages, lw)
    m = smooth_edit(motion, m)
    world = forward_kinematics(m)
    if lw:  # speeds read before the feet are put back: the contact IK barely moves anything
        times = _weight_times(world[0], times, lw)
    m = _restore_contacts(motion, m, world)
    times = _smooth_rate(times, motion.frame_time)
    out = retime(m, lambda _: times, oversample=_oversample(m))
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
    clip by ``1 + L_w`` or ``1/(1 − L_w)`` and shifts the posture by ``0.1 L_w``."""
    lt, lw = float(np.clip(lt, -1.0, 1.0)), float(np.clip(lw, -1.0, 1.0))
    m = motion
    if lt:
        c = 1.0 / (3 * abs(lt) + 1.0)
        m = motion_scale(m, 0, max(stages.anticipation, 1), c, "full")
    if lw:
        m = motion_scale(m, 0, m.frames, 1.0 + lw if lw > 0 else 1.0 / (1.0 - lw), "partial")
        m = reshape(m, stages.anticipation, stages.execution, 0.1 * lw, "vertical")
    return m


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

