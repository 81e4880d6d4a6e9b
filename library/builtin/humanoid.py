"""The built-in humanoid and a tiny keyframe tool for the library's own clips.

:data:`STANDARD` is a Mixamo-style humanoid (22 joints, ``Hips`` … ``RightToeBase``), 1.70 m
tall in its rest pose: a T-pose (arms along ±x), feet on y = 0 (the toe End Sites touch the
ground), ``Hips`` at 0.95 m. Conventions as in the rest of the project: metres, +y up, the
character faces +z, its left is +x.

Keyframing:

* :func:`pose` — ``pose(LeftArm=(x, y, z), …)``: per joint Euler angles in degrees, read in
  the BVH channel order of the skeleton, *intrinsic Z-X-Y*: R = Rz(z)·Rx(x)·Ry(y) (the same
  as ``Rotation.from_euler("ZXY", [z, x, y], degrees=True)``). Useful signs: +x on a spine
  joint, the neck or the head bends forward; −x on an UpLeg lifts the thigh forward; +x on
  a Leg bends the knee; +z on LeftUpLeg / −z on RightUpLeg spreads the leg outwards;
  −z lowers the left arm from the T-pose, +z the right.
* :func:`aim` (minimal rotation from a rest direction to a target), :func:`arm` (upper and
  fore arm directions in the chest frame) and :func:`leg` (two-bone IK of the ankle
  relative to the hip in the pelvis frame, foot kept flat) turn intentions into angles.
* :func:`animate` — keys ``(time_s, pose, root_offset)`` → :class:`Motion`. Each joint's
  turn from one key to the next (its rotation vector) is accumulated key after key, and
  that sum is interpolated with a monotone cubic (PCHIP), component by component: between
  two keys a joint turns about (nearly) the axis of the shortest turn, a turn about one
  axis is exactly an eased angle, nothing overshoots a key, and every extreme pose eases
  in and out; a one-shot clip also
  starts and ends at rest (zero velocity at its first and last key). Interpolating Euler
  angles instead swings a limb far off the arc between two keys whose angles differ a lot
  (a forearm keyed (9, 10, 3) then (178, −124, 42) degrees), which made fists pop. A joint
  must turn less than 180° between consecutive keys (a full turn, as in a flip, takes at
  least three keys). The root offset (metres, from the rest position of ``Hips``) is
  interpolated the same way. With ``loop=True`` the last key must repeat the first; the
  curve is made periodic (velocities match across the seam) and the last frame equals the
  first. Joints that no key names stay at rest.
* :func:`pace` — timing from distance: the gap between two keys is stretched (never
  shortened) to at least the longest way a joint or end site travels from one key pose to
  the next over a maximum speed; :func:`peak_speeds` measures a motion's fastest point
  between consecutive keys, to correct the eased result (see ``make_clips.oneshot``).
* :func:`plant` — foot locking: the root's horizontal motion is rebuilt so that the support
  foot (the lower one, or the one given per frame) does not move horizontally while it
  supports, and the body is lifted or lowered so the lowest foot point touches y = 0 on
  supported frames (airborne frames keep their keyed height, blended to stay continuous).
"""

from __future__ import annotations

import warnings

import numpy as np
from scipy.interpolate import CubicHermiteSpline, PchipInterpolator
from scipy.spatial.transform import Rotation

from doodle.core import quat
from retarget.skeleton import Motion, Skeleton, end_site_positions, forward_kinematics

__all__ = ["STANDARD", "REST_HIPS", "pose", "aim", "arm", "leg", "animate", "plant", "feet_points", "pace",
           "peak_speeds", "key_travel",
           "HIP_OFFSET", "THIGH", "SHIN"]

REST_HIPS = np.array([0.0, 0.95, 0.0])
HIP_OFFSET = 0.09  # |x| of the hip joints from Hips
THIGH, SHIN = 0.42, 0.40

_ROOT_CH = ("Xposition", "Yposition", "Zposition", "Zrotation", "Xrotation", "Yrotation")
_CH = ("Zrotation", "Xrotation", "Yrotation")


def _build() -> Skeleton:
    joints = [  # name, parent, offset
        ("Hips", None, REST_HIPS),
        ("Spine", "Hips", (0, 0.10, 0)),
        ("Spine1", "Spine", (0, 0.12, 0)),
        ("Spine2", "Spine1", (0, 0.12, 0)),
        ("Neck", "Spine2", (0, 0.15, 0)),
        ("Head", "Neck", (0, 0.10, 0)),
    ]
    for side, s in (("Left", 1.0), ("Right", -1.0)):
        joints += [
            (f"{side}Shoulder", "Spine2", (0.05 * s, 0.10, 0)),
            (f"{side}Arm", f"{side}Shoulder", (0.13 * s, 0, 0)),
            (f"{side}ForeArm", f"{side}Arm", (0.28 * s, 0, 0)),
            (f"{side}Hand", f"{side}ForeArm", (0.25 * s, 0, 0)),
        ]
    for side, s in (("Left", 1.0), ("Right", -1.0)):
        joints += [
            (f"{side}UpLeg", "Hips", (HIP_OFFSET * s, -0.05, 0)),
            (f"{side}Leg", f"{side}UpLeg", (0, -THIGH, 0)),
            (f"{side}Foot", f"{side}Leg", (0, -SHIN, 0)),
            (f"{side}ToeBase", f"{side}Foot", (0, -0.06, 0.13)),
        ]
    names = tuple(j[0] for j in joints)
    parents = np.array([-1 if p is None else names.index(p) for _, p, _ in joints])
    offsets = np.array([o for _, _, o in joints], dtype=float)
    channels = tuple(_ROOT_CH if p is None else _CH for _, p, _ in joints)
    ends = {names.index("Head"): np.array([0, 0.16, 0.0]),
            names.index("LeftHand"): np.array([0.18, 0, 0.0]),
            names.index("RightHand"): np.array([-0.18, 0, 0.0]),
            names.index("LeftToeBase"): np.array([0, -0.02, 0.06]),
            names.index("RightToeBase"): np.array([0, -0.02, 0.06])}
    return Skeleton(names, parents, offsets, channels, ends)


STANDARD: Skeleton = _build()


# --------------------------------------------------------------------------- angles

def pose(**joints) -> dict[str, tuple[float, float, float]]:
    """Joint → (x, y, z) Euler degrees (intrinsic Z-X-Y, see the module docstring)."""
    out = {}
    for name, angles in joints.items():
        STANDARD.index(name)  # KeyError for unknown joints
        a = tuple(float(v) for v in angles)
        if len(a) != 3:
            raise ValueError(f"{name}: expected (x, y, z) degrees")
        out[name] = a
    return out


def _euler(rot: Rotation) -> tuple[float, float, float]:
    with warnings.catch_warnings():  # gimbal lock: any of the equivalent triples will do (keys
        warnings.simplefilter("ignore", UserWarning)  # are interpolated as quaternions)
        z, x, y = rot.as_euler("ZXY", degrees=True)
    # of the two equivalent solutions, keep the one with the smaller y and z twists (a
    # knee bent 105° reads (105, 0, 0), not (75, 180, -180)): keys interpolate sensibly
    wrap = lambda a: (a + 180.0) % 360.0 - 180.0  # noqa: E731
    alt = (wrap(180.0 - x), wrap(y + 180.0), wrap(z + 180.0))
    if abs(alt[1]) + abs(alt[2]) < abs(wrap(y)) + abs(wrap(z)) - 1e-9:
        return tuple(float(a) for a in alt)
    return (float(x), float(y), float(z))


def _from_euler(e) -> Rotation:
    return Rotation.from_euler("ZXY", [e[2], e[0], e[1]], degrees=True)


def _minimal(a, b) -> Rotation:
    a = np.asarray(a, float) / np.linalg.norm(a)
    b = np.asarray(b, float) / np.linalg.norm(b)
    axis = np.cross(a, b)
    s, c = np.linalg.norm(axis), float(a @ b)
    if s < 1e-9:
        if c > 0:
            return Rotation.identity()
        perp = np.cross(a, [0, 0, 1.0]) if abs(a[2]) < 0.9 else np.cross(a, [0, 1.0, 0])
        return Rotation.from_rotvec(np.pi * perp / np.linalg.norm(perp))
    return Rotation.from_rotvec(axis / s * np.arctan2(s, c))


def aim(rest_dir, target_dir) -> tuple[float, float, float]:
    """Euler degrees of the smallest rotation taking ``rest_dir`` to ``target_dir``."""
    return _euler(_minimal(rest_dir, target_dir))


def arm(side: str, upper, fore=None, hand=None) -> dict[str, tuple[float, float, float]]:
    """Angles pointing the upper arm along ``upper`` and the forearm along ``fore`` (both in
    the chest frame, shoulders at rest); ``hand`` (default: along the forearm) likewise."""
    s = 1.0 if side == "Left" else -1.0
    rest = np.array([s, 0, 0.0])
    fore = upper if fore is None else fore
    r1 = _minimal(rest, upper)
    r2 = _minimal(rest, fore)
    # twist the forearm rotation so that the elbow bends in the plane of upper and fore
    local2 = r1.inv() * r2
    out = {f"{side}Arm": _euler(r1), f"{side}ForeArm": _euler(local2)}
    if hand is not None:
        out[f"{side}Hand"] = _euler(r2.inv() * _minimal(rest, hand))
    return out


def leg(side: str, ankle, foot_pitch: float = 0.0, foot_yaw: float = 0.0) -> dict[str, tuple[float, float, float]]:
    """Two-bone IK: the ankle at ``ankle`` (x, y, z metres, relative to the hip joint, in the
    pelvis frame); the foot stays parallel to the pelvis' ground plane, then pitched by
    ``foot_pitch`` degrees (+ = toes down) and turned by ``foot_yaw``."""
    tx, ty, tz = (float(v) for v in ankle)
    d = min(np.sqrt(tx * tx + ty * ty + tz * tz), THIGH + SHIN - 1e-4)
    d = max(d, abs(THIGH - SHIN) + 0.05)
    knee = np.pi - np.arccos(np.clip((THIGH ** 2 + SHIN ** 2 - d * d) / (2 * THIGH * SHIN), -1, 1))
    beta = np.arccos(np.clip((THIGH ** 2 + d * d - SHIN ** 2) / (2 * THIGH * d), -1, 1))
    roll = np.arctan2(tx, -ty)
    theta = np.arctan2(tz, np.hypot(tx, ty))
    alpha = -(theta + beta)
    r_hip = Rotation.from_euler("ZX", [roll, alpha])
    r_knee = Rotation.from_euler("X", knee)
    r_foot = (r_hip * r_knee).inv() * Rotation.from_euler("YX", [np.radians(foot_yaw), np.radians(foot_pitch)])
    return {f"{side}UpLeg": _euler(r_hip), f"{side}Leg": _euler(r_knee), f"{side}Foot": _euler(r_foot)}


# --------------------------------------------------------------------------- animation

def _key_values(keys) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Times (K,), quaternions (K, J, 4) and root offsets (K, 3) of the keys."""
    keys = sorted(keys, key=lambda k: k[0])
    times = np.array([k[0] for k in keys], float)
    if len(keys) < 2 or np.any(np.diff(times) <= 0):
        raise ValueError("need at least two keys at increasing times")
    n = len(STANDARD)
    eul = np.zeros((len(keys), n, 3))
    root = np.zeros((len(keys), 3))
    for i, (_, p, off) in enumerate(keys):
        for name, a in (p or {}).items():
            eul[i, STANDARD.index(name)] = a
        if off is not None:
            root[i] = off
    quats = quat.from_euler("ZXY", eul[..., [2, 0, 1]].reshape(-1, 3), degrees=True).reshape(len(keys), n, 4)
    return times, quats, root


def _turns(quats: np.ndarray) -> np.ndarray:
    """(K, J, 3): each joint's turns (local rotation vectors, the short way) summed from the
    first key: the k-th minus the (k−1)-th is the turn from key k−1 to key k."""
    k, n = quats.shape[:2]
    steps = (Rotation.from_quat(quats[:-1].reshape(-1, 4)).inv()
             * Rotation.from_quat(quats[1:].reshape(-1, 4))).as_rotvec().reshape(k - 1, n, 3)
    return np.concatenate([np.zeros((1, n, 3)), np.cumsum(steps, axis=0)])


def _turned(quats: np.ndarray, turns: np.ndarray) -> np.ndarray:
    """Quaternions ``quats`` (…, 4) turned on by local rotation vectors ``turns`` (…, 3)."""
    shape = turns.shape[:-1]
    q = Rotation.from_quat(quats.reshape(-1, 4)) * Rotation.from_rotvec(turns.reshape(-1, 3))
    return q.as_quat().reshape(*shape, 4)


def _monotone(times: np.ndarray, values: np.ndarray, still_ends: bool):
    """PCHIP through ``values`` (K, D); with ``still_ends`` zero velocity at both ends."""
    slopes = PchipInterpolator(times, values, axis=0).derivative()(times)
    if still_ends:
        slopes[[0, -1]] = 0.0
    return CubicHermiteSpline(times, values, slopes, axis=0)


def _motion(quats: np.ndarray, root: np.ndarray, fps: float) -> Motion:
    quats = quats / np.linalg.norm(quats, axis=-1, keepdims=True)
    translations = np.broadcast_to(STANDARD.offsets, (len(quats), len(STANDARD), 3)).copy()
    translations[:, 0] = REST_HIPS + root
    return Motion(STANDARD, translations, quats, 1.0 / fps)


def animate(keys, fps: float = 30, loop: bool = False) -> Motion:
    """Interpolate keys ``(time_s, pose, root_offset)`` (root_offset: metres from the rest
    Hips position, or None for zero) into a :class:`Motion` sampled at ``fps``."""
    times, quats, root = _key_values(keys)
    k, n = quats.shape[:2]
    turns = _turns(quats)
    frames = int(round((times[-1] - times[0]) * fps)) + 1
    t = times[0] + np.arange(frames) / fps
    t[-1] = min(t[-1], times[-1])
    values = np.concatenate([turns.reshape(k, -1), root], axis=1)
    if loop:
        period = times[-1] - times[0]
        base = values[:-1]
        tt = np.concatenate([times[:-1] - period, times[:-1], times[:-1] + period, [times[-1] + period]])
        drift = values[-1] - values[0]  # e.g. a root that travels
        vv = np.concatenate([base - drift, base, base + drift, [values[-1] + drift]])
        curve = PchipInterpolator(tt, vv, axis=0)
    else:
        curve = _monotone(times, values, still_ends=True)
    out = curve(t)
    seg = np.clip(np.searchsorted(times, t, side="right") - 1, 0, k - 2)  # the key each frame turns on from
    rot = _turned(quats[seg], out[:, : n * 3].reshape(frames, n, 3) - turns[seg])
    return _motion(rot, out[:, n * 3:], fps)


def _points(motion: Motion) -> np.ndarray:
    """(F, P, 3): every joint and end site, as :func:`retarget.qa.check` measures them."""
    world = forward_kinematics(motion)
    ends = end_site_positions(motion, world)
    return np.concatenate([world[0]] + [e[:, None] for e in ends.values()], axis=1)


def key_travel(keys, samples: int = 12) -> np.ndarray:
    """(K−1,): the longest path (m) any joint or end site travels from each key pose to the
    next, the two poses blended along the shortest arcs (root offsets linearly)."""
    times, quats, root = _key_values(keys)
    turns = _turns(quats)
    s = np.linspace(0.0, 1.0, samples + 1)[:, None, None]
    out = []
    for i in range(len(times) - 1):
        q = _turned(np.broadcast_to(quats[i], (samples + 1, *quats.shape[1:])), s * (turns[i + 1] - turns[i]))
        r = root[i] * (1 - s[:, 0]) + root[i + 1] * s[:, 0]
        pts = _points(_motion(q, r, 30.0))
        out.append(np.linalg.norm(np.diff(pts, axis=0), axis=2).sum(axis=0).max())
    return np.array(out)


def pace(keys, vmax: float, ease: float = 1.0) -> list:
    """The keys retimed so that no point travels from one key pose to the next faster than
    ``vmax`` m/s on average (× ``ease``: a point that stops at both keys peaks at 1.5 times
    its mean speed, one that flows through them at about its mean): gaps only grow."""
    keys = sorted(keys, key=lambda k: k[0])
    times = np.array([k[0] for k in keys], float)
    gaps = np.maximum(np.diff(times), ease * key_travel(keys) / vmax)
    new = times[0] + np.concatenate([[0.0], np.cumsum(gaps)])
    return [(float(t), p, r) for t, (_, p, r) in zip(new, keys)]


def peak_speeds(motion: Motion, times) -> np.ndarray:
    """(K−1,): the fastest point (m/s, frame to frame) between each pair of key ``times``."""
    pts = _points(motion)
    speed = np.linalg.norm(np.diff(pts, axis=0), axis=2).max(axis=1) / motion.frame_time
    mid = (np.arange(len(speed)) + 0.5) * motion.frame_time + float(times[0])
    seg = np.clip(np.searchsorted(np.asarray(times, float), mid) - 1, 0, len(times) - 2)
    return np.array([speed[seg == i].max(initial=0.0) for i in range(len(times) - 1)])


FOOT_POINTS = {side: [STANDARD.index(f"{side}Foot"), STANDARD.index(f"{side}ToeBase")] for side in ("Left", "Right")}


def feet_points(motion: Motion, world=None) -> np.ndarray:
    """(F, 2, 3, 3): for each foot (left, right) the ankle, toe base and toe tip positions."""
    world = forward_kinematics(motion) if world is None else world
    ends = end_site_positions(motion, world)
    pos = world[0]
    out = []
    for side in ("Left", "Right"):
        a, t = FOOT_POINTS[side]
        out.append(np.stack([pos[:, a], pos[:, t], ends[t]], axis=1))
    return np.stack(out, axis=1)


def plant(motion: Motion, support=None, ground: bool = True) -> Motion:
    """Foot locking (see the module docstring). ``support``: per frame 0 (left), 1 (right),
    2 (both: the lower one locks), −1 (airborne); default: the lower foot every frame."""
    f = motion.frames
    pts = feet_points(motion)
    low = pts[..., 1].min(axis=2)  # (F, 2) lowest point per foot
    if support is None:
        support = np.full(f, 2)
    support = np.asarray(support).copy()
    lock = np.where(support == 2, np.argmin(low, axis=1), support)
    ankle = pts[:, :, 0]  # (F, 2, 3)
    corr = np.zeros((f, 3))
    for k in range(1, f):
        corr[k] = corr[k - 1]
        s = lock[k]
        if s >= 0:
            prev = lock[k - 1] if lock[k - 1] >= 0 else s
            s_ref = s if prev == s else s
            d = ankle[k, s_ref] - ankle[k - 1, s_ref]
            corr[k, [0, 2]] -= d[[0, 2]]
    if ground:
        lift = np.where(lock >= 0, -low.min(axis=1), np.nan)
        if np.all(np.isnan(lift)):
            lift[:] = 0.0
        idx = np.arange(f)
        ok = ~np.isnan(lift)
        lift = np.interp(idx, idx[ok], lift[ok])  # airborne frames: blend between the contacts
        corr[:, 1] = lift
    tr = motion.translations.copy()
    tr[:, 0] += corr
    return Motion(motion.skeleton, tr, motion.rotations, motion.frame_time)
