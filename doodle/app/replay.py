"""Replaying a recorded doodle as if it were live: every sample of every track through the
streaming Segmenter and Matcher, in time order, at real speed, faster, or as fast as it
goes — each action reported when the stream recognises it, with how long after the
gesture's end that was (the recognition latency a performer would feel).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from doodle.core.model import Doodle
from doodle.input.segmenter import Segmenter, SegmenterParams


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


def replay(doodle: Doodle, automaton, params: SegmenterParams = SegmenterParams(), speed: float | None = None,
           on_action=None, clock=time.perf_counter, sleep=time.sleep,
           shapes=None, compiled=None, threshold: float = 2.0) -> tuple[list[Recognised], np.ndarray]:
    """Stream ``doodle``; returns what was recognised and the processing time of every
    frame (all tracks' samples at one time step), in seconds. ``automaton`` is the
    Matcher's tables, or a dict of them by track name
    (:func:`doodle.app.pipeline.track_automata`); with ``shapes`` (a
    :class:`grammar.shapes.ShapeSet`) learned actions are re-decided by their shapes as in
    :func:`doodle.app.pipeline.recognize`. ``speed`` 1 is real time, 2 twice as fast, None as
    fast as possible; ``on_action(Recognised)`` is called as each action is recognised.
    With ``compiled`` (the library) and several tracks, interactions are recognised across
    the tracks as they are read (:class:`grammar.contexter.LiveContexter`): each role is
    reported once more, with the interaction's name, when the interaction is decided."""
    from grammar.matcher import Matcher
    from grammar.shapes import Refiner

    tracks = doodle.tracks
    segmenters = [Segmenter(doodle.rate, params, tr.name, doodle.source) for tr in tracks]
    matchers = [Matcher(automaton[tr.name] if isinstance(automaton, dict) else automaton, tr.name) for tr in tracks]
    refiners = [Refiner(shapes, tr.p, tr.valid, tr.name) if shapes is not None else None for tr in tracks]

    live = None
    if compiled is not None and len(tracks) > 1 and compiled.library.interactions:
        from grammar.contexter import LiveContexter

        live = LiveContexter(doodle, compiled, threshold)

    def step(k, token, now):
        segments = matchers[k].push(token)
        if refiners[k] is not None:
            refiners[k].tokens.append(token)
            segments = refiners[k].push(segments)
        if live is not None:
            interacted(live.push_token(tracks[k].name, token), now)
            interacted(live.push_segments(tracks[k].name, segments), now)
        return segments

    def finish(k, now):
        segments = []
        for token in segmenters[k].close():
            segments += step(k, token, now)
        closing = matchers[k].close()
        if refiners[k] is not None:
            closing = refiners[k].push(closing) + refiners[k].close()
        if live is not None:
            interacted(live.push_segments(tracks[k].name, closing), now)
        return segments + closing

    def interacted(new, now):
        for f, segs in new:
            for role, (name, s) in enumerate(zip(f.tracks, segs)):
                t = doodle.track(name).t
                r = Recognised(name, s.action, float(t[min(s.start, len(t) - 1)]),
                               float(t[min(max(s.end - 1, s.start), len(t) - 1)]), float(now), s.exact, s.distance,
                               f.interaction, role)
                found.append(r)
                if on_action:
                    on_action(r)

    found: list[Recognised] = []
    times = tracks[0].t
    costs = np.empty(len(times))
    start_wall = clock()

    def report(k, segments, now):
        t = tracks[k].t
        for s in segments:
            if s.action == "unknown":
                continue
            r = Recognised(tracks[k].name, s.action, float(t[min(s.start, len(t) - 1)]),
                           float(t[min(max(s.end - 1, s.start), len(t) - 1)]), float(now), s.exact, s.distance)
            found.append(r)
            if on_action:
                on_action(r)

    for i, now in enumerate(times):
        if speed:
            wait = start_wall + now / speed - clock()
            if wait > 0:
                sleep(wait)
        tick = time.perf_counter()
        for k, tr in enumerate(tracks):
            for token in segmenters[k].push(now, tr.p[i], tr.q[i], bool(tr.valid[i])):
                report(k, step(k, token, now), now)
        costs[i] = time.perf_counter() - tick
    end = float(times[-1])
    for k in range(len(tracks)):
        report(k, finish(k, end), end)
    if live is not None:
        interacted(live.close(), end)
    return found, costs
