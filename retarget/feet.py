"""Feet that stay where they land: contact pinning with two-bone IK.

Foot skating — a planted foot sliding over the ground — is what blending clips onto a new
path produces; the thesis leaves it to future work (§5.3). Here, after sequencing:

1. contacts are detected per foot on the sequenced motion: near its lowest height and
   slower than a brisk step (1 m/s) — a looser speed bound than clip analysis uses, since
   a sliding planted foot is exactly what must be caught;
2. each contact interval gets one target: where the ankle stood, averaged horizontally over
   the interval, at its lowest height there;
3. every frame of the interval the leg (hip, knee, ankle) is bent and swung analytically so
   the ankle reaches the target (two-bone IK), with the correction faded in and out over a
   few frames at the interval's ends so nothing pops.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from doodle.core import quat
from doodle.core.filters import gaussian_filter1d, maximum_filter1d
from doodle.core.profiles import min_jerk
from retarget.analysis import foot_contacts
from retarget.skeleton import FK_BLOCK, Motion, forward_kinematics, kinematics_of


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.maximum(np.linalg.norm(v, axis=-1, keepdims=True), 1e-12)


def _angle(u: np.ndarray, v: np.ndarray) -> np.ndarray:
    return np.arccos(np.clip(np.sum(_unit(u) * _unit(v), axis=-1), -1.0, 1.0))


def two_bone_ik(motion: Motion, hip: int, knee: int, ankle: int, target: np.ndarray, weight: np.ndarray,
                world: tuple | None = None, front: np.ndarray | None = None) -> Motion:
    """The motion with the hip and knee rotated so the ankle reaches ``target`` (F, 3) where
    ``weight`` (F,) is 1 (blended towards it in between, untouched at 0). ``world``: the
    motion's forward kinematics if already known (only this leg's chain must be current).
    ``front`` (F, 3): the way the knee bends (a leg's: the body's front) wherever the chain
    is too straight to tell or bends the other way (so a knee never flips backwards)."""
    rots = motion.rotations.copy()
    _leg_ik(rots, motion, hip, knee, ankle, target, weight, world, front)
    return replace(motion, rotations=rots)


def _leg_ik(rots: np.ndarray, motion: Motion, hip: int, knee: int, ankle: int, target: np.ndarray,
            weight: np.ndarray, world: tuple | None = None, front: np.ndarray | None = None) -> None:
    """:func:`two_bone_ik` written into ``rots`` (a copy of ``motion.rotations``; only the
    leg's hip, knee and ankle are changed, so the legs of one body share one copy). Worked
    out :data:`~retarget.skeleton.FK_BLOCK` frames at a time (only the choice of bend plane
    looks along the whole motion): a long motion's temporaries stay the size of a block."""
    positions, world = forward_kinematics(motion) if world is None else world
    a, b, c = positions[:, hip], positions[:, knee], positions[:, ankle]
    # a nearly straight leg has no reliable bend plane: it keeps the one of the nearest frame
    # where the knee is clearly bent (so the knee never flips sides between frames); a leg
    # straight throughout bends about the hip's own x axis
    bent = np.empty(len(a), dtype=bool)
    for s in _blocks(len(a)):
        lab, lcb = np.linalg.norm(b[s] - a[s], axis=1), np.linalg.norm(b[s] - c[s], axis=1)
        bent[s] = np.linalg.norm(np.cross(c[s] - a[s], b[s] - a[s]), axis=1) > 0.15 * lab * lcb
    nearest = nearest_true(bent) if bent.any() else None
    parent = int(motion.skeleton.parents[hip])
    for s in _blocks(len(a)):
        _leg_ik_block(rots, world, s, a, b, c, hip, knee, ankle, parent, target[s], weight[s],
                      None if nearest is None else nearest[s], None if front is None else front[s])


def _blocks(frames: int):
    """Slices of :data:`~retarget.skeleton.FK_BLOCK` frames covering ``frames``."""
    return [slice(i, min(i + FK_BLOCK, frames)) for i in range(0, frames, FK_BLOCK)]


def _leg_ik_block(rots, world, s: slice, a, b, c, hip, knee, ankle, parent, target, weight, nearest, front) -> None:
    """:func:`_leg_ik` on the frames ``s`` (``nearest``: each one's frame whose bend plane it takes)."""
    a_, b_, c_ = a[s], b[s], c[s]
    t = c_ + (target - c_) * weight[:, None]
    lab = np.linalg.norm(b_ - a_, axis=1)
    lcb = np.linalg.norm(b_ - c_, axis=1)
    lat = np.clip(np.linalg.norm(t - a_, axis=1), 1e-4, lab + lcb - 1e-4)
    ac_ab_0 = _angle(c_ - a_, b_ - a_)
    ba_bc_0 = _angle(a_ - b_, c_ - b_)
    ac_at_0 = _angle(c_ - a_, t - a_)
    ac_ab_1 = np.arccos(np.clip((lcb**2 - lab**2 - lat**2) / (-2 * lab * lat), -1, 1))
    ba_bc_1 = np.arccos(np.clip((lat**2 - lab**2 - lcb**2) / (-2 * lab * lcb), -1, 1))
    if nearest is not None:
        axis0 = np.cross(c[nearest] - a[nearest], b[nearest] - a[nearest])
    else:
        axis0 = quat.rotate(world[:, hip][s], np.tile([1.0, 0.0, 0.0], (len(a_), 1)))
    axis0 = _unit(axis0)
    if front is not None:  # the hinge that bends the knee towards the front
        natural = np.cross(c_ - a_, front)
        ok = np.linalg.norm(natural, axis=1) > 1e-6
        natural = _unit(natural)
        wrong = ok & (np.sum(axis0 * natural, axis=1) < 0.3)
        axis0[wrong] = natural[wrong]
    axis1 = np.cross(c_ - a_, t - a_)
    axis1 = np.where(np.linalg.norm(axis1, axis=1, keepdims=True) < 1e-12, axis0, _unit(axis1))
    a_inv, b_inv = quat.conjugate(world[:, hip][s]), quat.conjugate(world[:, knee][s])
    r0 = quat.exp(quat.rotate(a_inv, axis0) * (ac_ab_1 - ac_ab_0)[:, None])
    r1 = quat.exp(quat.rotate(b_inv, axis0) * (ba_bc_1 - ba_bc_0)[:, None])
    r2 = quat.exp(quat.rotate(a_inv, axis1) * ac_at_0[:, None])
    rots[s, hip] = quat.multiply(quat.multiply(rots[s, hip], r0), r2)
    rots[s, knee] = quat.multiply(rots[s, knee], r1)
    # the foot keeps its orientation in the world (its sole stays on the ground)
    new_hip_world = quat.multiply(world[:, parent][s], rots[s, hip])
    new_knee_world = quat.multiply(new_hip_world, rots[s, knee])
    rots[s, ankle] = quat.multiply(quat.conjugate(new_knee_world), world[:, ankle][s])


def nearest_true(mask: np.ndarray) -> np.ndarray:
    """(F,) for each frame the index of the nearest frame where ``mask`` (F,) bool, not
    empty, is true (the earlier one on a tie): two neighbours found by ``searchsorted``, so
    the cost stays constant per frame at any length."""
    idx = np.flatnonzero(mask)
    frames = np.arange(len(mask))
    right = np.minimum(np.searchsorted(idx, frames), len(idx) - 1)
    left = np.maximum(right - 1, 0)
    take_left = np.abs(frames - idx[left]) <= np.abs(idx[right] - frames)
    return np.where(take_left, idx[left], idx[right])


def _intervals(mask: np.ndarray) -> list[tuple[int, int]]:
    edges = np.diff(np.concatenate([[0], mask.astype(int), [0]]))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)))


def leg_of(skeleton, ankle: int) -> tuple[int, int, float]:
    """The hip and knee above ``ankle`` (-1 where the chain is shorter) and the straight leg's
    length, hip to ankle (m, from the rest offsets)."""
    knee = int(skeleton.parents[ankle])
    hip = int(skeleton.parents[knee]) if knee >= 0 else -1
    if hip < 0:
        return hip, knee, np.inf
    return hip, knee, float(np.linalg.norm(skeleton.offsets[knee]) + np.linalg.norm(skeleton.offsets[ankle]))


CONTACT_SPEED = 1.0  # m/s: a planted foot, even sliding, moves slower than a stepping one


def planted(motion: Motion, feet: list[int], positions: np.ndarray | None = None, terrain=None,
            height: float = 0.03) -> np.ndarray:
    """(F, len(feet)) bool: each foot near its lowest height above the ground and under
    CONTACT_SPEED."""
    positions = forward_kinematics(motion)[0] if positions is None else positions
    if terrain is None:
        return foot_contacts(motion, feet, speed=CONTACT_SPEED, world=positions)
    foot = positions[:, feet]
    above = foot[:, :, 1] - terrain.height(foot[:, :, [0, 2]])
    speed = np.linalg.norm(np.gradient(foot, motion.frame_time, axis=0), axis=2)
    return (above - above.min(axis=0) <= height) & (speed <= CONTACT_SPEED)


REACH = 0.35  # m: a pinned foot left farther behind than this by the body takes a new spot ...
OVERREACH = 0.01  # m: ... or one its hip is this much farther from than the leg is long ...
FLAT_RISE = 0.01  # m: ... while the clips keep its ankle within this of its height at landing ...
STRETCHED = 0.2  # s: ... for this long (a step's toe-off stretches the leg for a moment)
STEP_LEAST = 0.05  # m: a foot moved less than this to a new spot is not given a step
LOWEST = 0.2  # m: the most the pelvis is lowered for a foot on lower ground (a deep knee bend)


def pin_feet(motion: Motion, feet: list[int], fade: int = 3, terrain=None, contacts: np.ndarray | None = None,
             standing: list[float] | None = None, sole: float = 0.0, ground_y: np.ndarray | None = None,
             in_place: bool = False, rolls: np.ndarray | None = None) -> Motion:
    """The motion with each foot held still over each of its contact intervals.

    ``contacts`` (F, len(feet)): where the foot stands — the sequenced clips' own contacts
    (:func:`retarget.sequence.contact_states`); without them, found on the motion
    (:func:`planted`). A foot stands where it landed (its place at the interval's first
    frame) on the ground: ``standing`` (m, per foot) is its ankle's height above the
    ground when standing flat (default: its lowest height in the interval) and ``sole``
    how high its lowest joint or end site then is (a skeleton's foot joints sit inside the
    foot, above the sole: Bandai's 2–4 cm), so a foot the
    clips or a style held up is put down. On uneven ``terrain`` every foot keeps, at every
    frame, the height above the ground under it that it had above the ground under the
    root (a swinging foot clears a rise, a standing one stands on its own ground), and
    where a leg cannot reach its spot the pelvis is lowered: its height comes from the
    ground under the feet, not under the root (``ground_y``, per frame: the ground the root
    was put on). Pins fade in and out over ``fade`` frames. ``in_place``: ``motion``'s own
    arrays are changed rather than copied (a motion nothing else holds: just sequenced).
    ``rolls`` (F, len(feet)): where a foot turns on its toes in place (a jump's push-off and
    landing, :func:`retarget.sequence.roll_states`): held where it is over the ground with
    the stance next to it, its height (a rising or falling heel) left to the clips."""
    legs = {0}  # the joints read here: root, each foot's subtree (toes, end sites), knee, hip and pelvis
    for a in feet:
        legs.update(motion.skeleton.subtree(a))
        j = a
        for _ in range(3):
            j = int(motion.skeleton.parents[j])
            legs.add(j % len(motion.skeleton))  # (a root hip's parent is read as joint -1)
            if j < 0:
                break
    if contacts is None:
        original_world = forward_kinematics(motion)
        contacts = planted(motion, feet, original_world[0], terrain)
    else:  # only the legs' positions: a long motion's (F, J, 7) never made
        original_world = kinematics_of(motion, legs)
    clears = [_clearance(motion, original_world, a, terrain) - sole for a in feet]  # the soles as the clips put them
    original = original_world[0]
    del original_world  # the rotations are not needed again (``original`` is let go below)
    rolls = np.zeros_like(contacts) if rolls is None else rolls & ~contacts
    rise = None
    if terrain is not None:  # the ground under each foot relative to the ground under the root,
        # but not in the air (both feet off: the feet go with the body)
        under_root = terrain.height(original[:, 0][:, [0, 2]]) if ground_y is None else ground_y
        aloft = ~(contacts | rolls).any(axis=1)
        rise = [np.where(aloft, 0.0, terrain.height(original[:, a][:, [0, 2]]) - under_root) for a in feet]
        rise = [gaussian_filter1d(r, 1.0, mode="nearest") for r in rise]  # eased into and out of a flight
    in_air = _aloft(original, feet, contacts | rolls, terrain, standing)  # the body, not only the feet
    targets, weights, helds = [], [], []
    for k, ankle in enumerate(feet):
        hip, _, leg = leg_of(motion.skeleton, ankle)
        target, weight, held = _pins(original[:, ankle], contacts[:, k], fade, terrain,
                                     None if standing is None else standing[k], None if rise is None else rise[k],
                                     motion.fps, aloft=in_air, clear=clears[k],
                                     hip=original[:, hip] if hip >= 0 else None, leg=leg, roll=rolls[:, k],
                                     toe=_toe(motion.skeleton, original, ankle))
        targets.append(target)
        weights.append(weight)
        helds.append(held)
    motion = _lower_to_reach(motion, original, feet, targets, weights, in_place)
    world = kinematics_of(motion, legs)
    front = _front(motion, world[0], feet)
    rots = None  # the legs share one copy of the rotations (each changes only its own joints)
    for k, ankle in enumerate(feet):
        hip, knee, _ = leg_of(motion.skeleton, ankle)
        if hip < 0 or not weights[k].any():
            continue
        rots = (motion.rotations if in_place else motion.rotations.copy()) if rots is None else rots
        _leg_ik(rots, motion, hip, knee, ankle, targets[k], weights[k], world=world, front=front)
    motion = motion if rots is None else replace(motion, rotations=rots)
    if terrain is not None:  # the foot laid along the slope under it
        motion = _soles_on_ground(motion, original, feet, terrain, ground_y)
        rots = motion.rotations
    del original
    world = None  # freed before the next is made
    world = kinematics_of(motion, legs)
    # a copy made here is changed in place (_leg_ik reads only rots and world of it), the caller's never
    rots = rots if rots is not None and rots is motion.rotations else None
    rots = motion.rotations if in_place and rots is None else rots
    for k, ankle in enumerate(feet):  # a standing foot's lowest point (heel, toes) on the ground
        hip, knee, _ = leg_of(motion.skeleton, ankle)
        if hip < 0 or not helds[k].any():
            continue
        gap = _clearance(motion, world, ankle, terrain) - sole
        target = world[0][:, ankle] - np.outer(gap, [0.0, 1.0, 0.0])
        rots = motion.rotations.copy() if rots is None else rots
        _leg_ik(rots, motion, hip, knee, ankle, target, helds[k] ** 4, world=world,  # only a stance: not a lifting foot
                front=front)
    return motion if rots is None else replace(motion, rotations=rots)


def _aloft(positions: np.ndarray, feet: list[int], contacts: np.ndarray, terrain,
           standing: list[float] | None) -> np.ndarray:
    """(F,) the body in the air: no foot in contact and every ankle higher than
    :data:`STEP_LIFT` above its standing height (default: its lowest over the contacts) —
    a jump's or a run's flight, not two feet the cross-fades' votes leave out of contact for
    a frame while they stand."""
    up = ~contacts.any(axis=1)
    for k, a in enumerate(feet):
        height = positions[:, a, 1] - _ground(terrain, positions[:, a][:, [0, 2]])
        base = standing[k] if standing is not None else (
            float(height[contacts[:, k]].min()) if contacts[:, k].any() else float(height.min()))
        up &= height > base + STEP_LIFT
    return up


def _front(motion: Motion, positions: np.ndarray, feet: list[int]) -> np.ndarray | None:
    """(F, 3) the body's front from its hips (left hip minus right, turned a right angle
    about the vertical; +x is left), or None without two legs."""
    if len(feet) != 2:
        return None
    hips = [int(motion.skeleton.parents[int(motion.skeleton.parents[a])]) for a in feet]
    if min(hips) < 0:
        return None
    across = positions[:, hips[0]] - positions[:, hips[1]]
    return _unit(np.cross(across, np.array([0.0, 1.0, 0.0])))


def _clearance(motion: Motion, world, ankle: int, terrain) -> np.ndarray:
    """(F,) how far a foot's lowest point (its joints and end sites) is above the ground
    under it (negative: into the ground)."""
    from retarget.skeleton import end_site_positions

    joints = motion.skeleton.subtree(ankle)
    ends = end_site_positions(motion, world, joints)
    points = [world[0][:, j] for j in joints] + [ends[j] for j in joints if j in ends]
    return np.min([p[:, 1] - _ground(terrain, p[:, [0, 2]]) for p in points], axis=0)


def _soles_on_ground(motion: Motion, original: np.ndarray, feet: list[int], terrain, ground_y=None) -> Motion:
    """Each foot pitched about its ankle so its toes keep the height above the ground under
    them that they had above the ground under the root (a foot on a slope lies along it)."""
    world = forward_kinematics(motion)
    positions, rotations = world
    under_root = terrain.height(original[:, 0][:, [0, 2]]) if ground_y is None else ground_y
    rots = motion.rotations.copy()
    parents = motion.skeleton.parents
    for ankle in feet:
        toes = motion.skeleton.children(ankle)
        if not toes:
            continue
        toe = toes[0]
        v = positions[:, toe] - positions[:, ankle]
        length = np.maximum(np.linalg.norm(v, axis=1), 1e-9)
        want = terrain.height(positions[:, toe][:, [0, 2]]) + original[:, toe, 1] - under_root
        pitch = np.arcsin(np.clip((want - positions[:, ankle, 1]) / length, -0.7, 0.7))
        flat = np.linalg.norm(v[:, [0, 2]], axis=1)
        heading = v[:, [0, 2]] / np.maximum(flat, 1e-9)[:, None]
        new = np.column_stack([heading[:, 0] * np.cos(pitch), np.sin(pitch), heading[:, 1] * np.cos(pitch)])
        axis = np.cross(_unit(v), new)
        angle = np.arcsin(np.clip(np.linalg.norm(axis, axis=1), 0.0, 1.0))
        delta = quat.exp(_unit(axis) * angle[:, None])
        turned = quat.multiply(delta, rotations[:, ankle])
        rots[:, ankle] = quat.multiply(quat.conjugate(rotations[:, int(parents[ankle])]), turned)
    return replace(motion, rotations=rots)


def _ground(terrain, xz: np.ndarray) -> np.ndarray:
    return np.zeros(len(xz)) if terrain is None else terrain.height(xz)


STEP_SPEED = 3.0  # m/s: a foot's step to a new spot takes at least its length / this (swinging feet
# peak at 4–5 m/s in real walks)
STEP_LIFT = 0.05  # m: a foot moved to a new spot lifted less than this is shuffled (steps lift the
# ankle 9–14 cm): it is given a step
STEP_APEX = (0.04, 0.10)  # m: the apex of a given step, half its length, within these


def _pins(ankle: np.ndarray, contact: np.ndarray, fade: int, terrain, standing: float | None,
          rise: np.ndarray | None = None, fps: float = 30.0, aloft: np.ndarray | None = None,
          clear: np.ndarray | None = None, hip: np.ndarray | None = None, leg: float = np.inf,
          roll: np.ndarray | None = None, toe: np.ndarray | None = None):
    """One foot's targets (F, 3), weights (F,) and standing weights (F,): held at its landing
    spot over each contact interval (a new spot once the body has left it more than
    :data:`REACH` behind, or once its ``hip`` (F, 3) stays farther from it than the ``leg``
    reaches — by :data:`OVERREACH`, for :data:`STRETCHED`, while the clips keep the foot flat,
    and the clips' foot :data:`STEP_LEAST` or more away: a large performer came to a stand
    out of a walk with a foot 31 cm behind where the stand puts it, held there, and the Kick
    after it rose onto its hop with that foot out of reach, hanging 4–6 cm above the floor
    for half a second; a walk's toe-off stretches the leg only for a moment) — a spot within
    :data:`STEP_LEAST` of the one before is that one (the same footprint: not a slide of a few
    cm in one frame); between two spots, a foot that the blended clips shuffle along the floor
    (lifted less than :data:`STEP_LIFT`) or fling there (faster than :data:`STEP_SPEED`) steps
    instead — lifted in an arc, over at least the time a step of that length takes (borrowed
    from the stances either side) — unless the body is in the air in between (``aloft``,
    :func:`_aloft`: a jump's or a run's flight), where the foot goes with the body (a back
    flip travelling 3 m had its feet dragged along a step's low arc under it, the legs bent
    down out of the flip and snapping back at 17 m/s); on uneven ground (``rise``: the ground under the foot above the ground under the root)
    raised by the ground under it elsewhere. ``clear`` (per frame, how far the foot's lowest
    point is above the ground as the clips have it): an ankle the clips put lower than
    standing is raised no higher than puts that point on the floor (raised to the standing
    height, a foot landing heel or toes first was held up in the air), and a pin fading in
    as the foot lands out of a flight (``aloft``) lowers it no more than that (a toes-first
    landing pulled down to the standing height put its toes through the floor, and the body
    lifted out of it over the frames around left the landing feet hovering: a back flip's
    flight a frame longer than any real one). ``roll`` (F,): frames the foot turns on its toes
    beside a stance: held with it over the ground, at the height the clips give it (not a
    standing foot) — by its toes (``toe``, (F, 3): where the clips put the toe joint), so that
    the heel rises or comes down about them."""
    frames = len(ankle)
    follow = ankle.copy()
    if rise is not None:
        follow[:, 1] += rise
    height = ankle[:, 1] - _ground(terrain, ankle[:, [0, 2]]) + (0.0 if rise is None else rise)
    roll = np.zeros(frames, dtype=bool) if roll is None else roll.copy()
    for a, b in _intervals(roll):  # the body travelling farther than a foot is held behind it: the feet go with it
        if np.linalg.norm(ankle[a:b, [0, 2]] - ankle[a, [0, 2]], axis=1).max() > REACH:
            roll[a:b] = False
    pins = []  # [first, stop, spot (3,)]
    for s, e in _intervals(contact | roll):
        while s < e:
            spot = ankle[s, [0, 2]]
            away = np.linalg.norm(ankle[s:e, [0, 2]] - spot, axis=1) > REACH
            if hip is not None:  # held out of the leg's reach, the clips' foot flat, for a while
                out = (ankle[s:e, 1] <= ankle[s, 1] + FLAT_RISE) & \
                      (np.linalg.norm(hip[s:e] - ankle[s], axis=1) > leg + OVERREACH)
                n = max(int(round(STRETCHED * fps)), 1)
                held_out = np.zeros(len(out), dtype=bool)  # out of reach for the last n frames
                for a, b in _intervals(out):
                    held_out[a + n - 1:b] = True
                # ... where the clips' foot is far enough to step to (nearer, it would slide)
                held_out &= np.linalg.norm(ankle[s:e, [0, 2]] - spot, axis=1) >= STEP_LEAST
                away |= np.maximum.accumulate(held_out)
            stop = max(s + int(np.argmax(away)) if away.any() else e, s + 1)
            if pins and np.linalg.norm(pins[-1][2][[0, 2]] - spot) < STEP_LEAST:
                spot = pins[-1][2][[0, 2]]  # (nearly) where it stood before: the same footprint, not a slide
            low = float(height[s:stop].min())
            base = low if standing is None else standing
            on = np.array([spot[0], _ground(terrain, spot[None])[0] + base, spot[1]])
            pins.append([s, stop, on])  # (a heel or toe rolling is kept by pin_feet's sole pass)
            s = stop
    steps = []
    for a, b in zip(pins, pins[1:]):
        length = float(np.linalg.norm((b[2] - a[2])[[0, 2]]))
        lo, hi = a[1], b[0]  # the gap: frames [lo, hi) between the two stances
        lifted = float((height[lo:hi] - a[2][1]).max()) if hi > lo else 0.0
        need = int(np.ceil(length / STEP_SPEED * fps)) + 1
        flying = aloft is not None and bool(aloft[lo:hi].any())
        if length < STEP_LEAST or flying or (lifted >= STEP_LIFT and hi - lo >= need):
            continue
        while hi - lo < need and (a[1] - a[0] > 1 or b[1] - b[0] > 1):
            if a[1] - a[0] > 1 and (hi - lo) % 2 == 0:
                a[1] -= 1
                lo -= 1
            elif b[1] - b[0] > 1:
                b[0] += 1
                hi += 1
            else:
                a[1] -= 1
                lo -= 1
        steps.append((lo, hi, a[2], b[2], length))
    pin, held = follow.copy(), np.zeros(frames)
    landing = np.zeros(frames, dtype=bool)  # fading in: coming down onto its spot out of a flight
    for s, stop, on in pins:
        pin[s:stop] = on
        if roll[s:stop].any():  # on its toes: held by them, the heel as the clips have it
            pin[s:stop, 1] = np.where(roll[s:stop], follow[s:stop, 1], on[1])
            if toe is not None:
                pin[s:stop, [0, 2]] = toe[s, [0, 2]] - (toe[s:stop] - ankle[s:stop])[:, [0, 2]]
        held[s:stop] = 1.0
        # held at the spot while fading in and out, over more frames the farther the foot is
        # from where the clips put it (it moves there no faster than a step)
        gap_in = np.linalg.norm((pin[s] - follow[max(s - 1, 0)])[[0, 2]])
        gap_out = np.linalg.norm((pin[stop - 1] - follow[min(stop, frames - 1)])[[0, 2]])
        for n, sign, edge in ((_fade(gap_in, fade, fps), -1, s), (_fade(gap_out, fade, fps), 1, stop - 1)):
            # coming down out of a flight (not a contact the cross-fades' votes flicker on for a frame)
            lands = sign < 0 and aloft is not None and int(aloft[max(edge - n - 3, 0):edge].sum()) >= 3
            for k in range(1, n + 1):
                w = 1.0 - k / (n + 1)
                f = edge + sign * k
                if 0 <= f < frames and w > held[f]:  # in the air: the correction fades, the foot flies on
                    pin[f] = follow[f] + (pin[edge] - follow[edge]) if aloft is not None and aloft[f] else pin[edge]
                    held[f] = w
                    landing[f] = lands
    stance = np.where(roll, 0.0, held)
    for lo, hi, a, b, length in steps:  # a step in an arc from one spot to the next
        u = (np.arange(lo, hi) - lo + 1) / (hi - lo + 1)
        pin[lo:hi] = a + np.outer(min_jerk(np.clip((u - 0.15) / 0.7, 0.0, 1.0)), b - a)  # up, across, down
        pin[lo:hi, 1] += np.clip(length / 2, *STEP_APEX) * np.sin(np.pi * u)
        held[lo:hi] = 1.0
        stance[lo:hi] = 0.0
    sunk = np.zeros(frames, dtype=bool)
    if clear is not None and rise is not None:
        clear = clear + rise  # as the foot follows the ground under it
    if standing is not None:  # an ankle the clips (a style) put lower than standing on the floor: raised
        floor = _ground(terrain, follow[:, [0, 2]]) + standing
        sunk = follow[:, 1] < floor - 0.02
        up = np.where(sunk, floor - follow[:, 1], 0.0)
        if clear is not None:  # … no higher than puts its lowest point on the floor (a foot not flat)
            up = np.minimum(up, np.maximum(-clear, 0.0))
            clear = clear + up
        follow[:, 1] += up
    # fading in and out, the foot is over its spot before it is down on it (and off it only
    # once lifted): horizontally it eases faster than vertically, so it does not land sliding
    across, down = _smooth(np.minimum(1.0, 1.5 * held)), _smooth(held)
    target = follow + (pin - follow) * np.column_stack([across, down, across])
    if clear is not None:  # landing on its spot, no lower than its lowest point on the floor
        fading = landing & (stance > 0.0) & (stance < 1.0)
        target[:, 1] = np.where(fading, np.maximum(target[:, 1], follow[:, 1] - np.maximum(clear, 0.0)), target[:, 1])
    weight = np.ones(frames) if rise is not None else ((held > 0) | sunk).astype(float)
    return target, weight, stance


def _toe(skeleton, positions: np.ndarray, ankle: int) -> np.ndarray | None:
    """(F, 3) where the clips put a foot's toe joint (its first child), None for a foot without one."""
    below = skeleton.children(ankle)
    return positions[:, below[0]] if len(below) else None


def _fade(gap: float, fade: int, fps: float) -> int:
    """Frames a pin fades in or out over: at least ``fade``, more for a foot that has farther
    to go (no faster than :data:`STEP_SPEED`), at most three times as many."""
    return int(np.clip(np.ceil(gap / STEP_SPEED * fps), fade, 3 * fade))


def _smooth(x: np.ndarray) -> np.ndarray:
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3 - 2 * x)


def _lower_to_reach(motion: Motion, positions: np.ndarray, feet: list[int], targets: list, weights: list,
                    in_place: bool = False) -> Motion:
    """The root lowered, eased, wherever a pinned foot's spot is out of its straight leg's
    reach (a foot on ground lower than the root's, a style that lifted the body)."""
    need = np.zeros(motion.frames)
    for ankle, target, weight in zip(feet, targets, weights):
        hip, knee, length = leg_of(motion.skeleton, ankle)
        if hip < 0:
            continue
        leg = 0.98 * length
        goal = positions[:, ankle] + (target - positions[:, ankle]) * weight[:, None]
        across = np.linalg.norm((goal - positions[:, hip])[:, [0, 2]], axis=1)
        down = positions[:, hip, 1] - goal[:, 1]
        reach = np.sqrt(np.maximum(leg**2 - np.minimum(across, leg) ** 2, 0.0))
        need = np.maximum(need, np.where((weight > 0) & (across < 0.9 * leg), down - reach, 0.0))
    if not need.any():
        return motion
    need = np.maximum(gaussian_filter1d(maximum_filter1d(np.minimum(need, LOWEST), 5), 1.5), np.minimum(need, LOWEST))
    trans = motion.translations if in_place else motion.translations.copy()
    trans[:, 0, 1] -= need
    return replace(motion, translations=trans)


def clamp_to_ground(motion: Motion, terrain=None, in_place: bool = False) -> Motion:
    """The motion raised, frame by frame, so no joint or End Site of the body (a helper root
    above the pelvis does not count) is below the ground (``terrain``; flat y = 0 when
    None); the lift is eased in and out over a few frames. ``in_place``: ``motion``'s
    translations are changed rather than copied (a motion nothing else holds)."""
    from retarget.analysis import pelvis_of
    from retarget.skeleton import end_site_positions

    helper = pelvis_of(motion.skeleton) != 0  # a helper root on the floor does not count

    def below(part: Motion) -> np.ndarray:  # (n,) how far each frame's lowest point is under the ground
        world = forward_kinematics(part)
        body = world[0][:, 1:] if helper else world[0]
        points = np.concatenate([body] + [end[:, None] for end in end_site_positions(part, world).values()], axis=1)
        ground = 0.0 if terrain is None else terrain.height(points[:, :, [0, 2]])
        return np.maximum(0.0, np.max(ground - points[:, :, 1], axis=1))

    # frame by frame, so in blocks of frames: a long motion's forward kinematics is never whole
    lift = np.concatenate([below(motion.slice(a, a + FK_BLOCK)) for a in range(0, motion.frames, FK_BLOCK)]
                          or [np.zeros(0)])
    if not lift.any():
        return motion
    lift = np.maximum(gaussian_filter1d(maximum_filter1d(lift, 5), 1.5), lift)
    trans = motion.translations if in_place else motion.translations.copy()
    trans[:, 0, 1] += lift
    return replace(motion, translations=trans)
