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

    @property
    def latency(self) -> float:
        return self.at - self.end


@dataclass(frozen=True)
class Replayed:
    """What a replay heard and ended with."""

    found: list  # Recognised, in the order they were decided
    costs: np.ndarray  # s of processing per frame (all tracks' samples at one time step)
    result: dict  # per track (tokens, segments): the whole file decided, as doodle recognize says


def replay(doodle: Doodle, compiled, params: SegmenterParams = SegmenterParams(), speed: float | None = None,
           on_action=None, clock=time.perf_counter, sleep=time.sleep, threshold: float = 2.0,
           automata: dict | None = None) -> Replayed:
    """Stream ``doodle`` through the one Recognizer (:class:`grammar.recognizer.Live`) with
    the library ``compiled``: learned shapes, interactions across tracks and behaviour
    states as :func:`grammar.recognizer.recognize` applies them. ``speed`` 1 is real time,
    2 twice as fast, None as fast as possible; ``on_action(Recognised)`` is called as each
    action is decided (an interaction's roles once more, with its name, when the
    interaction is decided; a refused action is not an action). ``automata`` (the
    Matcher's tables per track) may be given to skip compiling them."""
    from grammar.contexter import InteractionSegment, Refused
    from grammar.recognizer import Live

    tracks = doodle.tracks
    live = Live(compiled, [tr.name for tr in tracks], doodle.rate, params, threshold, doodle.source, automata)
    found: list[Recognised] = []

    def report(heard, now):
        for h in heard:
            s = h.segment
            if s.action == "unknown" or isinstance(s, Refused):
                continue
            t = doodle.track(h.track).t
            role = (s.interaction, s.role) if isinstance(s, InteractionSegment) else ("", 0)
            r = Recognised(h.track, s.action, float(t[min(s.start, len(t) - 1)]),
                           float(t[min(max(s.end - 1, s.start), len(t) - 1)]), float(now), s.exact, s.distance, *role)
            found.append(r)
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
        tick = time.perf_counter()
        step = live.push(float(now), [(tr.p[i], tr.q[i], bool(tr.valid[i])) for tr in tracks])
        costs[i] = time.perf_counter() - tick
        report(step.heard, now)
    report(live.close().heard, float(times[-1]))
    return Replayed(found, costs, live.result)
