"""Replaying a recorded doodle as if it were live: every sample of every track through the
streaming Recognizer (:class:`grammar.recognizer.Live`), in time order, at real speed, faster, or as fast as it
goes — each action reported when the stream recognises it, with how long after the
gesture's end that was (the recognition latency a performer would feel).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from doodle.core.model import Doodle
from doodle.input.segmenter import SegmenterParams


@dataclass(frozen=True)
class Recognised:
    track: str
    action: str
    start: float  # s, the segment's first sample
    end: float  # s, its last sample
    at: float  # s of stream time when the stream had recognised it
    exact: bool
    distance: float | None
    interaction: str = ""  # the interaction it is a role of, when it is one
    role: int = 0
    final: bool = True  # False: provisional (the action as the tokens so far stand, not decided yet)

    @property
    def latency(self) -> float:
        return self.at - self.end


@dataclass(frozen=True)
class Replayed:
    """What a replay heard and ended with."""

    found: list  # Recognised, in the order they were decided
    costs: np.ndarray  # s of processing per frame (all tracks' samples at one time step)
    result: dict  # per track (tokens, segments): the whole file decided, as doodle recognize says
    provisional: list = ()  # Recognised (final False), in the order they were shown


def replay(doodle: Doodle, compiled, params: SegmenterParams = SegmenterParams(), speed: float | None = None,
           on_action=None, clock=time.perf_counter, sleep=time.sleep, threshold: float = 2.0,
           automata: dict | None = None) -> Replayed:
    """Stream ``doodle`` through the one Recognizer (:class:`grammar.recognizer.Live`) with
    the library ``compiled``: learned shapes, interactions across tracks and behaviour
    states as :func:`grammar.recognizer.recognize` applies them. ``speed`` 1 is real time,
    2 twice as fast, None as fast as possible; ``on_action(Recognised)`` is called as each
    action is decided (an interaction's roles once more, with its name, when the
    interaction is decided; a refused action is not an action) — and before that, as soon
    as it is provisional (``Recognised.final`` False: what the tokens so far say, see
    :class:`grammar.recognizer.Live`). At a speed, a frame processed when the next is due
    already leaves the provisional actions to the next frame on time, so that a replay
    fallen behind (deciding an action can take a few tenths of a second) catches up before
    it shows them. ``automata`` (the Matcher's tables per track) may be given to skip
    compiling them."""
    from grammar.contexter import InteractionSegment, Refused
    from grammar.recognizer import Live

    tracks = doodle.tracks
    live = Live(compiled, [tr.name for tr in tracks], doodle.rate, params, threshold, doodle.source, automata)
    found: list[Recognised] = []
    provisional: list[Recognised] = []

    def report(heard, now):
        for h in heard:
            s = h.segment
            if s.action == "unknown" or isinstance(s, Refused):
                continue
            t = doodle.track(h.track).t
            role = (s.interaction, s.role) if isinstance(s, InteractionSegment) else ("", 0)
            r = Recognised(h.track, s.action, float(t[min(s.start, len(t) - 1)]),
                           float(t[min(max(s.end - 1, s.start), len(t) - 1)]), float(now), s.exact, s.distance, *role,
                           final=h.final)
            (found if h.final else provisional).append(r)
            if on_action:
                on_action(r)

    times = tracks[0].t
    costs = np.empty(len(times))
    start_wall = clock()
    for i, now in enumerate(times):
        if speed:
            wait = start_wall + now / speed - clock()
            if wait > 0:
                sleep(wait)
        # behind the clock (the next frame due already): provisional actions wait for a frame on time
        labels = not speed or i + 1 == len(times) or clock() < start_wall + times[i + 1] / speed
        tick = time.perf_counter()
        step = live.push(float(now), [(tr.p[i], tr.q[i], bool(tr.valid[i])) for tr in tracks], labels)
        costs[i] = time.perf_counter() - tick
        report(step.provisional, now)
        report(step.heard, now)
    report(live.close().heard, float(times[-1]))
    return Replayed(found, costs, live.result, provisional)


@dataclass(frozen=True)
class Latencies:
    """How soon a replay named what it found (:func:`latencies`)."""

    final: list  # per action ending a movement: s from the gesture's end until it was decided
    named: list  # ... until its name was first shown, provisional or final
    agree: list  # per provisional label: whether the final action covering most of it names it (None: none)
    pauses: int  # actions that are pauses (all their tokens stills: Idle), not counted


def latencies(doodle: Doodle, replayed: Replayed) -> Latencies:
    """The latency a performer feels: per final action that ends a movement, how long after
    the gesture ended it was decided, and how long until its name was first on screen
    (provisional or final). A gesture ends where the hand comes to rest after the action's
    segment — the first pause from its end on — or where the next action begins, if sooner.
    A pause (Idle) is left out: it is named once it is a pause whatever follows."""
    finals = {}
    for r in replayed.found:
        finals.setdefault((r.track, r.start), r)  # an interaction's roles repeat the action
    named, agree = {}, []
    for p in replayed.provisional:
        over = [(min(f.end, p.end) - max(f.start, p.start), k) for k, f in finals.items()
                if f.track == p.track and f.start <= p.end and p.start <= f.end]
        if not over:
            agree.append(None)
            continue
        key = max(over)[1]
        agree.append(finals[key].action == p.action)
        if finals[key].action == p.action:
            named[key] = min(named.get(key, np.inf), p.at)
    moving = {k: f for k, f in finals.items() if not _pause(doodle, replayed, f)}
    ends = {k: _gesture_end(doodle, replayed, f, finals.values()) for k, f in moving.items()}
    return Latencies([f.at - ends[k] for k, f in moving.items()],
                     [min(named.get(k, np.inf), f.at) - ends[k] for k, f in moving.items()],
                     agree, len(finals) - len(moving))


def _samples(t: np.ndarray, r: Recognised) -> tuple[int, int]:
    return int(np.searchsorted(t, r.start)), int(np.searchsorted(t, r.end, side="right"))


def _pause(doodle: Doodle, replayed: Replayed, f: Recognised) -> bool:
    a, b = _samples(doodle.track(f.track).t, f)
    return all(k.name == "T_STILL" for k in replayed.result[f.track][0] if k.start < b and k.end > a)


def _gesture_end(doodle: Doodle, replayed: Replayed, f: Recognised, finals) -> float:
    t = doodle.track(f.track).t
    after = _samples(t, f)[1]  # the first sample after the segment
    rest = min((k.start for k in replayed.result[f.track][0] if k.name == "T_STILL" and k.start >= after),
               default=len(t))
    nxt = min((_samples(t, o)[0] for o in finals if o.track == f.track and o.start > f.end), default=len(t))
    return float(t[max(min(rest, nxt), after) - 1])
