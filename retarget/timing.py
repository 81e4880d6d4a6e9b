"""When a one-shot clip plays inside its segment: the time it needs so no joint moves faster
than a person's (lent by the stands around it, or its ends trimmed), and a jump's flight —
the frames with both feet off, played at their own pace, over which the root travels.

Works on :class:`retarget.sequence.Placed` clips, before the timeline is sequenced.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from retarget.feet import _intervals
from retarget.sequence import FASTEST, Placed, shortest


ROOM = 0.6  # at most this share of a neighbouring stand (half of a walk) is lent to an action that needs the time


def speed_limit(piece: Placed, travel: float) -> float:
    """How fast (m/s) a one-shot clip's joints may move in its own frame once retimed: a
    person's fastest (:data:`retarget.sequence.FASTEST`) less, for a jump, the speed its
    root travels at over the flight (``travel`` metres over the clip's flight time)."""
    flight = flight_times(piece)
    if flight is None:
        return FASTEST
    return float(max(FASTEST - travel / max(flight[1] - flight[0], 1e-9), FASTEST / 2))


def flight_times(piece) -> tuple[float, float] | None:
    """A jump's flight (clip seconds, within the range it plays), None for other clips: it
    plays at its own pace (a flight lasts what gravity gives it)."""
    if not piece.span.jumping or piece.contacts is None:
        return None
    air = flight(piece.contacts)
    if len(air) < 2:
        return None
    ft = piece.motion.frame_time
    end = (piece.motion.frames - 1) * ft if piece.clip_out is None else piece.clip_out
    lo, hi = max(piece.clip_in, (air[0] - 0.5) * ft), min(end, (air[-1] + 0.5) * ft)
    return (lo, hi) if hi > lo else None


def make_room(pieces: list, t: np.ndarray, limits: list, stages: list) -> list:
    """One-shot actions given the time they need: a clip that cannot be played in its
    segment without a joint going faster than its limit (:func:`retarget.sequence.shortest`:
    a hop performed in half a second, a jump's whole wind-up and landing) starts earlier and
    ends later, in the stands either side (up to :data:`ROOM` of each) or the walks (half
    that: a running jump) — and where they are too short, plays less of its preparation and
    of its return to rest (never of its anticipation, execution or follow-through) rather
    than whipping through."""
    pieces = list(pieces)
    for k, pc in enumerate(pieces):
        if not pc.fitted:
            continue
        need = 1.1 * shortest(pc.motion, pc.clip_in, pc.clip_out, limits[k], flight_times(pc))
        short = need - (pc.span.t1 - pc.span.t0)
        if short <= 0:
            continue
        lend = []
        for j in (k - 1, k + 1):
            n = pieces[j] if 0 <= j < len(pieces) else None
            ok = n is not None and not n.span.jumping and n.cycles > 0  # a stand, or a walk (a running jump)
            share = ROOM if ok and n.span.in_place else ROOM / 2
            lend.append(share * (n.span.t1 - n.span.t0) if ok else 0.0)
        before = min(lend[0], max(short / 2, short - lend[1]))
        after = min(lend[1], short - before)
        span = pc.span
        if before > 0:
            prev = pieces[k - 1].span
            cut = span.t0 - before
            i = int(np.clip(np.searchsorted(t, cut), prev.i0 + 1, span.i0))
            pieces[k - 1] = replace(pieces[k - 1], span=replace(prev, t1=cut, i1=i))
            span = replace(span, t0=cut, i0=i)
        if after > 0:
            nxt = pieces[k + 1].span
            cut = span.t1 + after
            i = int(np.clip(np.searchsorted(t, cut), span.i1, nxt.i1 - 1))
            pieces[k + 1] = replace(pieces[k + 1], span=replace(nxt, t0=cut, i0=i))
            span = replace(span, t1=cut, i1=i)
        pc = replace(pc, span=span)
        pieces[k] = trimmed(pc, stages[k], limits[k]) if short > before + after + 1e-9 else pc
    return pieces


def trimmed(piece, stages, limit: float):
    """A one-shot clip's range cut, from its ends inwards — the preparation from the start,
    the return to rest from the end, turn about — until it can play in its span within
    ``limit`` (or only anticipation to follow-through is left)."""
    ft = piece.motion.frame_time
    lo, hi = piece.clip_in, (piece.motion.frames - 1) * ft if piece.clip_out is None else piece.clip_out
    first, last = max(lo, stages.preparation * ft), min(hi, stages.follow_through * ft)
    duration = piece.span.t1 - piece.span.t0
    while 1.1 * shortest(piece.motion, lo, hi, limit, flight_times(piece)) > duration and (lo < first or hi > last):
        if lo < first and (hi <= last or lo - piece.clip_in <= (piece.clip_out or hi) - hi):
            lo = min(first, lo + ft)
        else:
            hi = max(last, hi - ft)
    return replace(piece, clip_in=lo, clip_out=hi)


def flight(contacts: np.ndarray) -> np.ndarray:
    """The clip frames of its flight: the longest run with neither foot on the ground."""
    runs = _intervals(~contacts.any(axis=1))
    if not runs:
        return np.zeros(0, dtype=int)
    a, b = max(runs, key=lambda r: r[1] - r[0])
    return np.arange(a, b)


def in_flight(piece):
    """A jump with its travel (``execution`` of its span) over the clip's flight — from the
    frame both feet leave the ground to the frame one lands — as fractions of the range of
    the clip it plays, so the root travels while the body is in the air and stands still
    on the ground before and after; (``ramps``) the push-off before the flight and the
    landing after it (:func:`crouches`), over which it gathers and sheds its speed; its
    feet standing only where the body does not move over them (:func:`push_off_contacts`),
    and turning on their toes where it does (:func:`push_off_rolls`). Other pieces as they
    are."""
    times = flight_times(piece) if piece.span.jumping else None
    if times is None:
        return piece
    low = crouches(piece, times)
    if piece.pace is not None:  # retimed unevenly: the span's fractions at those clip times
        u, clip_times = piece.pace
        a, b, c, d = (float(np.interp(x, clip_times, u)) for x in (low[0], *times, low[1]))
    else:
        end = (piece.motion.frames - 1) * piece.motion.frame_time if piece.clip_out is None else piece.clip_out
        length = max(end - piece.clip_in, 1e-9)
        a, b, c, d = ((x - piece.clip_in) / length for x in (low[0], *times, low[1]))
    span = replace(piece.span, execution=(b, c), ramps=(max(b - a, 0.0), max(d - c, 0.0)))
    contacts = push_off_contacts(piece.contacts, piece.motion.frame_time, times, low)
    return replace(piece, span=span, contacts=contacts,
                   rolls=push_off_rolls(contacts, piece.motion.frame_time, times, low))


def push_off_rolls(contacts: np.ndarray, frame_time: float, times: tuple[float, float],
                   low: tuple[float, float]) -> np.ndarray:
    """(clip frames, feet) bool: where a jump's foot turns on its toes without standing — from
    the stance at the crouch it springs from to the take-off, and from the landing to the
    stance at the crouch that absorbs it (``contacts`` as :func:`push_off_contacts` left them,
    flight ``times`` and crouches ``low`` in clip seconds). The body gathers or sheds its speed
    over the ground there; the toes stay where they are."""
    a, b, first_air, last_air = _push_off_frames(len(contacts), frame_time, times, low)
    window = np.zeros(len(contacts), dtype=bool)
    window[a:first_air] = True
    window[last_air + 1:b + 1] = True
    return window[:, None] & ~contacts


def push_off_contacts(contacts: np.ndarray, frame_time: float, times: tuple[float, float],
                      low: tuple[float, float]) -> np.ndarray:
    """A jump's contacts (clip frames, feet) with its flight at ``times`` and the bottoms of
    its crouches at ``low`` (clip seconds, :func:`crouches`), less every touch between a
    crouch and the flight that is not part of the stance at the crouch: over the push-off
    and the landing the body gathers and sheds its speed along the ground, and a foot read
    on the floor there for a moment — a toe brushing it as the heel rises or comes down,
    the foot's own speed dipping for a frame — would be held at one spot while the body
    moves on, and snap back after. The stance the body springs from, and the one it lands
    into, keep their frames."""
    out = contacts.copy()
    a, b, take_off, last_air = _push_off_frames(len(out), frame_time, times, low)
    for k in range(out.shape[1]):
        for lo, hi in _intervals(out[:, k]):  # [lo, hi) runs of standing
            if a < lo and hi <= take_off or last_air <= lo and hi - 1 < b:
                out[lo:hi, k] = False
    return out


def _push_off_frames(frames: int, frame_time: float, times: tuple[float, float],
                     low: tuple[float, float]) -> tuple[int, int, int, int]:
    """Clip frames of a jump's crouches (``low``, s) and of its flight's first and last
    frames (``times``, s, half a frame outside them: :func:`flight_times`)."""
    last = frames - 1
    a, b = (int(np.clip(np.rint(x / frame_time), 0, last)) for x in low)
    first_air = int(np.clip(np.ceil(times[0] / frame_time - 1e-9), 0, last))
    last_air = int(np.clip(np.floor(times[1] / frame_time + 1e-9), 0, last))
    return a, b, first_air, last_air


def crouches(piece, times: tuple[float, float]) -> tuple[float, float]:
    """Clip seconds where a jump with its flight at ``times`` (:func:`flight_times`) starts
    to push off and where its landing ends: the bottom of the crouch the pelvis springs up
    from before the take-off, and of the crouch that absorbs the landing after it — each the
    nearest low of the pelvis, within the range of the clip that plays. The feet push the
    body along the ground from the one and brake it until the other. The pelvis's height is its
    own translation, as the sequenced clip places it (``retarget.sequence.pose_at``)."""
    motion = piece.motion
    ft = motion.frame_time
    height = motion.translations[:, piece.pelvis, 1]
    first = int(np.ceil(piece.clip_in / ft - 1e-9))
    last = motion.frames - 1 if piece.clip_out is None else int(np.floor(piece.clip_out / ft + 1e-9))
    lo = int(np.clip(np.ceil(times[0] / ft), first, last))
    while lo > first and height[lo - 1] < height[lo]:
        lo -= 1
    hi = int(np.clip(np.floor(times[1] / ft), first, last))
    while hi < last and height[hi + 1] < height[hi]:
        hi += 1
    return min(lo * ft, times[0]), max(hi * ft, times[1])
