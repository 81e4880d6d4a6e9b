"""The one Recognizer: a doodle's samples to the actions its tracks perform, for every path.

Stages, in order (SPEC grammar): the Segmenter's tokens (:mod:`doodle.input.segmenter`) →
the Matcher's segments (:mod:`grammar.matcher`) → learned actions re-decided by their shapes
(:class:`grammar.refiner.Refiner`) → interactions between tracks (the Contexter,
:mod:`grammar.contexter`) → behaviour states (refused actions, §6.3.3).

* :func:`recognize` is the batch form (``doodle recognize`` and ``doodle compile``): each
  track tokenised whole (vectorised), matched and refined, then :func:`decide`.
* :class:`Live` is the streaming form (``doodle replay`` and ``doodle record``): samples
  pushed one at a time go through the streaming Segmenter, Matcher and Refiner — each equal
  to its batch form — and are reported as soon as each is final, with interactions
  (:class:`grammar.contexter.LiveContexter`) and behaviour states applied as they come.
  When the stream closes, :meth:`Live.close` decides the whole performance with the same
  :func:`decide` as the batch, on the same tokens and segments, so what replay and record
  end with is what ``recognize`` says of the file.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from doodle.core.errors import DoodleError
from doodle.core.tokens import Token
from doodle.input.segmenter import Segmenter, SegmenterParams, tokenize_doodle
from grammar.constraints import RADIUS
from grammar.contexter import InteractionSegment, LiveContexter, Refused, apply_behaviour, behaviours, with_interactions
from grammar.library import Compiled, compile_library
from grammar.matcher import Matcher, Segment, match
from grammar.refiner import Refiner, refine, unread
from grammar.spotter import Spotter
from library.manifest import load_combined

PAUSE = "Idle"  # the built-in action of a hand at rest


def load_actions(library_dir=None, use_builtin: bool = True) -> Compiled:
    """The built-in library, extended or overridden by the one in ``library_dir``, compiled."""
    return compile_library(load_combined(library_dir, use_builtin)[0])


def track_automata(compiled: Compiled, tracks: list[str], threshold: float = 2.0,
                   direction_costs: bool = False) -> dict:
    """The Matcher's tables per track: one shared unless some action is bound to a track."""
    if not compiled.bound:
        automaton = compiled.automaton(threshold, direction_costs)
        return {name: automaton for name in tracks}
    return {name: compiled.automaton(threshold, direction_costs, name, present=tracks) for name in tracks}


def recognize(doodle, compiled: Compiled, params: SegmenterParams = SegmenterParams(),
              threshold: float = 2.0, direction_costs: bool = False,
              interactions: bool = True) -> dict[str, tuple[list[Token], list[Segment]]]:
    """Per track: its tokens and the action segments recognised in them — with the
    library's interactions between tracks (unless ``interactions`` is False) and behaviour
    states applied (:func:`decide`)."""
    tokens = tokenize_doodle(doodle, params)
    automata = track_automata(compiled, list(tokens), threshold, direction_costs)
    matched = {name: match(toks, automata[name], name) if automata[name] is not None else unmatched(toks)
               for name, toks in tokens.items()}  # a track with no automaton only partners two-handed actions
    result = {}
    for name, toks in tokens.items():
        segments = matched[name]
        if compiled.shapes is not None and automata[name] is not None:  # learned actions re-decided by their shapes
            track = doodle.track(name)
            others = {o: (doodle.track(o).p, doodle.track(o).q, doodle.track(o).valid) for o in tokens if o != name}
            partners = {o: (unread(tokens[o], matched[o]), math.inf) for o in tokens if o != name}
            segments = refine(segments, toks, track.p, track.valid, compiled.shapes, name, track.q, others, track.t,
                              partners)
        result[name] = (toks, segments)
    return decide(doodle, compiled, result, threshold, interactions)


def unmatched(tokens: list[Token]) -> list[Segment]:
    """The segments of a track no action is recognised on: one unknown run."""
    if not tokens:
        return []
    return [Segment("unknown", 0, len(tokens), tokens[0].start, tokens[-1].end, False, None)]


def two_handed(compiled: Compiled) -> dict:
    """Two-handed learned actions: name → the other tracks performing them."""
    shapes = compiled.shapes
    if shapes is None:
        return {}
    return {n: others for n, others in zip(shapes.names, shapes.partners) if others}


def with_pairs(compiled: Compiled, result: dict) -> dict:
    """A two-handed action, recognised on its first track, read as one gesture on every
    track performing it: an :class:`InteractionSegment` named after it (``interaction`` is
    the action's name, ``role`` the track's place in its ``tracks``) over the same samples
    on each — replacing, on the other tracks, the unknown runs it covers and the actions
    it covers for at least half of their tokens."""
    pairs = two_handed(compiled)
    if not pairs:
        return result
    out = {name: list(segs) for name, (_, segs) in result.items()}
    found = []
    for name, (_, segs) in result.items():
        for x, s in enumerate(segs):
            if s.action in pairs and not isinstance(s, (InteractionSegment, Refused)):
                out[name][x] = _role(s, s.first, s.stop, 0)
                found.append(s)
    for s in found:
        for role, other in enumerate(pairs[s.action], 1):
            if other in result:
                out[other] = overlay(out[other], result[other][0], s, role)
    return {name: (toks, out[name]) for name, (toks, _) in result.items()}


def _owners(compiled: Compiled | None, names: list[str]) -> dict:
    """Each of ``names`` that two-handed learned actions also read → the tracks of ``names``
    those actions are decided on."""
    shapes = compiled.shapes if compiled is not None else None
    out = {}
    if shapes is None or not shapes.partners:
        return out
    bound = shapes.tracks or (None,) * len(shapes.names)
    for b, others in zip(bound, shapes.partners):
        for o in others:
            if o in names:
                out.setdefault(o, set()).update(n for n in names if n != o and (b is None or n == b))
    return {o: own for o, own in out.items() if own}


def _role(s: Segment, first: int, stop: int, role: int) -> InteractionSegment:
    return InteractionSegment(s.action, first, stop, s.start, s.end, s.exact, s.distance, interaction=s.action,
                              role=role)


def overlay(segments: list[Segment], tokens: list[Token], s: Segment, role: int) -> list[Segment]:
    """A track's ``segments`` with the two-handed segment ``s`` (samples of another track,
    the same moments) laid over its ``tokens`` as role ``role``."""
    starts = np.array([k.start for k in tokens], dtype=np.int64)
    ends = np.array([k.end for k in tokens], dtype=np.int64)
    first = int(np.searchsorted(ends, s.start, side="right"))
    stop = int(np.searchsorted(starts, s.end, side="left"))
    if stop <= first:
        return segments
    kept = []
    for o in segments:
        if o.action == "unknown" and not isinstance(o, Refused):
            for a, b in ((o.first, min(o.stop, first)), (max(o.first, stop), o.stop)):
                if a < b:
                    kept.append(Segment("unknown", a, b, tokens[a].start, tokens[b - 1].end, False, None))
        elif 2 * (min(o.stop, stop) - max(o.first, first)) < (o.stop - o.first):
            kept.append(o)
    return sorted(kept + [_role(s, first, stop, role)], key=lambda o: (o.first, o.stop))


def decide(doodle, compiled: Compiled, result: dict, threshold: float = 2.0, interactions: bool = True) -> dict:
    """Per-track ``(tokens, segments)`` of the Matcher and Refiner, with the library's
    interactions recognised across tracks (§6.2.1) where the doodle has several, and then
    behaviour states (§6.3.3): actions whose pre-conditions fail become :class:`Refused`."""
    result = with_pairs(compiled, result)
    if interactions and len(result) > 1 and compiled.library.interactions:
        resolved = with_interactions(doodle, compiled, result, threshold)
        result = {name: (toks, resolved[name]) for name, (toks, _) in result.items()}
    rules = behaviours(compiled)
    if rules:
        walked = apply_behaviour(doodle, {name: segs for name, (_, segs) in result.items()}, rules,
                                 frozenset(compiled.library.states), frozenset(compiled.library.names))
        result = {name: (toks, walked[name]) for name, (toks, _) in result.items()}
    return result


def recognize_interactions(doodle, compiled: Compiled, params: SegmenterParams | None = None,
                           threshold: float = 2.0, radius: float | dict = RADIUS,
                           mode: str = "any") -> dict[str, list[Segment]]:
    """Per track, the segments of :func:`recognize` (without its interactions) with the
    library's interactions recognised across tracks by a Contexter of the given ``radius``
    and ``mode`` (:class:`~grammar.contexter.InteractionSegment` where they are)."""
    recognised = recognize(doodle, compiled, params or SegmenterParams(), threshold, interactions=False)
    return with_interactions(doodle, compiled, recognised, threshold, radius, mode)


# --- streaming ---------------------------------------------------------------------------

@dataclass(frozen=True)
class Heard:
    """One thing the stream has decided: a segment of ``track`` (an action, a
    :class:`Refused` one, or an :class:`InteractionSegment` role once the interaction is
    decided). Sample indices are the track's, from the stream's first sample. With
    ``final`` False it is provisional: the action as the tokens so far stand
    (:meth:`Live.push`), not decided yet."""

    track: str
    segment: Segment
    final: bool = True


class _Tape:
    """The samples pushed so far, per track, in growing arrays (a doodle's ``track(name)``
    and ``tracks`` for the Refiner and the Contexter, which read what is known so far)."""

    def __init__(self, names: list[str]):
        self.names = list(names)
        self.n = 0
        self._t = np.zeros(64)
        self._p = {n: np.zeros((64, 3)) for n in names}
        self._q = {n: np.tile([0.0, 0.0, 0.0, 1.0], (64, 1)) for n in names}
        self._valid = {n: np.zeros(64, dtype=bool) for n in names}

    def append(self, t: float, poses) -> None:
        if self.n == len(self._t):
            grow = len(self._t)
            self._t = np.concatenate([self._t, np.zeros(grow)])
            for n in self.names:
                self._p[n] = np.concatenate([self._p[n], np.zeros((grow, 3))])
                self._q[n] = np.concatenate([self._q[n], np.tile([0.0, 0.0, 0.0, 1.0], (grow, 1))])
                self._valid[n] = np.concatenate([self._valid[n], np.zeros(grow, dtype=bool)])
        self._t[self.n] = t
        for n, (p, q, ok) in zip(self.names, poses):
            self._p[n][self.n], self._q[n][self.n], self._valid[n][self.n] = p, q, bool(ok)
        self.n += 1

    def track(self, name: str) -> "_TrackView":
        k = self.n
        return _TrackView(name, self._t[:k], self._p[name][:k], self._q[name][:k], self._valid[name][:k])

    @property
    def tracks(self) -> tuple:
        return tuple(self.track(n) for n in self.names)


@dataclass(frozen=True)
class _TrackView:
    """One track of the live recogniser's tape (_Tape): its samples so far, as the Segmenter reads a Track."""

    name: str
    t: np.ndarray
    p: np.ndarray
    q: np.ndarray
    valid: np.ndarray


class _Chain:
    """One track's Segmenter → Matcher → Refiner, from sample ``offset`` of the stream."""

    def __init__(self, live: "Live", name: str, offset: int):
        self.name, self.offset, self.live = name, offset, live
        live.read[name] = (live.read[name][0], offset)  # its Matcher has read nothing of what follows yet
        self.segmenter = Segmenter(live.rate, live.params, name, live.source)
        self.tokens_only = live.compiled is None  # nothing to recognise: tokens only
        auto = None if self.tokens_only else live.automata[name]
        self.matcher = Matcher(auto, name) if auto is not None else None  # None: it only partners two-handed actions
        shapes = None if self.tokens_only else live.compiled.shapes
        others = {o: (None, None, None) for o in live.names if o != name}  # filled as samples come
        self.refiner = (Refiner(shapes, np.zeros((0, 3)), np.zeros(0, dtype=bool), name, np.zeros((0, 4)), others)
                        if shapes is not None and auto is not None else None)
        self.tokens: list[Token] = []
        self.segments: list[Segment] = []
        self.finished = False  # its tokens and segments moved to the Live's (closed, or restarted)
        self._held = None  # what the provisional segments were last worked out from
        self._refined_from, self._refined_to = None, []  # the Matcher's provisional segments, refined
        self.spotter = Spotter() if self.refiner is not None else None  # learned gestures back to back
        self._read_to = None  # the provisional reading's fork of the Refiner, as last worked out
        self._begun = None  # (the Spotter's anchor, what pair_begun answered) for the reading in _read_to

    def feed(self, tokens: list[Token], tape: _Tape, close: bool = False) -> list[Segment]:
        if self.tokens_only:
            self.tokens += tokens
            return []
        segments = []
        if self.matcher is None:  # every token unknown as it comes
            self.tokens += tokens
            self._matched(unmatched(tokens), len(self.tokens) - len(tokens))
            if close:
                segments = self.end_refining(tape, self.end_matching())
            self.segments += segments
            return segments
        for token in tokens:
            self.tokens.append(token)
            segments += self._refined(self._matched(self.matcher.push(token)), tape, token)
        if close:
            segments += self.end_refining(tape, self.end_matching())
        self.segments += segments
        return segments

    def end_matching(self) -> list[Segment]:
        """The Matcher closed: its last segments (for :meth:`end_refining`)."""
        if self.tokens_only:
            return []
        if self.matcher is None:  # its unknown tokens told as they came
            self.live.read[self.name] = (self.live.read[self.name][0], math.inf)
            return unmatched(self.tokens)
        return self._matched(self.matcher.close(), final=True)

    def end_refining(self, tape: _Tape, segments: list[Segment]) -> list[Segment]:
        """The Refiner given the Matcher's last ``segments`` and closed: the segments it decides."""
        return self._refined(segments, tape, None, close=True)

    def nudge(self, tape: _Tape) -> list[Segment]:
        """The segments the Refiner decides now that other tracks' Matchers have read further."""
        if self.refiner is None or not self.refiner.waiting_for_partners:
            return []
        segments = self._refined([], tape, None)
        self.segments += segments
        return segments

    def _matched(self, segments: list[Segment], shift: int = 0, final: bool = False) -> list[Segment]:
        """The Matcher's new segments (token indices from ``shift``), told to the other tracks'
        Refiners (sample indices of the stream: :attr:`Live.read`)."""
        spans, known = self.live.read[self.name]
        if segments:
            off = self.offset
            spans += [(a + off, b + off) for a, b in unread(self.tokens[shift:], segments)]
            known = segments[-1].end + off
        self.live.read[self.name] = (spans, math.inf if final else known)
        return segments

    def _refined(self, segments: list[Segment], tape: _Tape, token, close: bool = False) -> list[Segment]:
        if self.refiner is None:
            return segments
        self._bind(self.refiner, tape)
        if token is not None:
            self.refiner.tokens.append(token)
        out = self.refiner.push(segments)
        return out + self.refiner.close() if close else out

    def _bind(self, refiner: Refiner, tape: _Tape) -> None:
        """Give the Refiner the samples known so far (this track's and the others')."""
        view = tape.track(self.name)
        k = self.offset
        refiner.p, refiner.valid, refiner.q, refiner.t = view.p[k:], view.valid[k:], view.q[k:], view.t[k:]
        for other in refiner.others:
            o = tape.track(other)
            refiner.others[other] = (o.p[k:], o.q[k:], o.valid[k:])
            refiner.partners[other] = self.live.read[other]
        refiner.shift = k

    def due(self) -> bool:
        """Whether what the Segmenter holds back has changed since :meth:`provisional` last read it."""
        return self.matcher is not None and (len(self.tokens), self.segmenter.held_key()) != self._held

    def provisional(self, tape: _Tape) -> list[Segment] | None:
        """The segments not final yet, as the tokens stand: the Matcher's segments that no
        continuation it still keeps can change, given the tokens the Segmenter holds back
        as they stand (:meth:`Segmenter.held`) — the rules the final decision uses, on a
        copy — then re-decided by the learned shapes as if the stream ended there; and after
        them the learned gestures the Spotter names in the tokens the Matcher has not
        settled (:meth:`_spotted`), where a segment decided as if the stream ended reaches
        into one (as far as :data:`~grammar.refiner.REACH` tokens past the Matcher's) ending
        where it begins. None when what the Segmenter holds back is as it was at the last
        call."""
        if not self.due():
            return None
        held = self.segmenter.held()
        self._held = (len(self.tokens), self.segmenter.held_key())  # as reading it left it
        matcher = self.matcher.fork()
        segments = [s for token in held for s in matcher.push(token)]
        if matcher.unknown is not None:  # as it stands (a learned action may be found in it)
            segments.append(matcher.unknown)
        if self.refiner is None:
            return self._no_hold(segments, len(self.tokens) + len(held))
        settled = (self.matcher.done, tuple((s.action, s.first, s.stop) for s in segments))
        refiner = self.refiner.fork()
        self._bind(refiner, tape)
        refiner.tokens.extend(held)
        spotted = self._spotted(refiner, segments)  # (reads the fork's samples and tokens, changes nothing)
        self._read_to, self._begun = refiner, None
        if settled != self._refined_from:  # the shapes are compared again once the Matcher's segments change
            self._refined_from, self._refined_to = settled, refiner.push(segments) + refiner.close()
        refined = self._refined_to
        if spotted:  # one reading per motion: what is decided as if the stream ended gives way to what is spotted
            f = spotted[0].first
            refined = [r if r.stop <= f else replace(r, stop=f, end=refiner.tokens[f - 1].end) for r in refined if r.first < f]
        return self._no_hold(refined, len(refiner.tokens)) + spotted

    def _no_hold(self, segments: list[Segment], n: int) -> list[Segment]:
        """``segments`` (of ``n`` tokens) less a pause over the still in progress while it may
        yet be a hold (:attr:`Segmenter.held_hold`): the gesture before it is named as soon
        as it could be a pause, the pause itself once it is one whatever follows."""
        if not self.segmenter.held_hold:
            return segments
        return [s for s in segments if not (s.action == PAUSE and s.stop == n)]

    def pair_begun(self) -> bool:
        """Whether this track's motion past what its provisional reading has named so far
        (the Spotter's anchor on) may be a two-handed action under way: it fits the beginning
        of one's examples, or the whole of it (:meth:`Spotter.begins_pair`)."""
        refiner = self._read_to
        if refiner is None:
            return False
        if self._begun is None or self._begun[0] != self.spotter.anchor:  # (once per reading and anchor)
            self._begun = (self.spotter.anchor, self.spotter.begins_pair(refiner))
        return self._begun[1]

    def _spotted(self, refiner: Refiner, segments: list[Segment]) -> list[Segment]:
        """The learned gestures the :class:`~grammar.spotter.Spotter` names past the Matcher's
        provisional ``segments`` (back to back, before the Refiner decides them)."""
        floor = max([self.matcher.done] + [s.stop for s in segments])
        tokens = refiner.tokens
        return [Segment(refiner.shapes.names[k], f, e, tokens[f].start, tokens[e - 1].end, edits == 0.0, edits)
                for f, e, k, edits in self.spotter.spots(refiner, len(self.tokens), floor)]


def _shifted(s: Segment, samples: int, tokens: int) -> Segment:
    if not samples and not tokens:
        return s
    return replace(s, first=s.first + tokens, stop=s.stop + tokens, start=s.start + samples, end=s.end + samples)


@dataclass(frozen=True)
class Step:
    """What one frame (or the end of the stream) made final, and what it made provisional."""

    tokens: dict  # track -> tokens made final (sample indices from the stream's start)
    heard: list  # Heard, in the order they were decided
    restarted: dict  # track -> why its recognition started afresh at this frame
    provisional: list = ()  # Heard (final False): actions newly provisional at this frame


TOLD = 64  # provisional labels a track remembers so as to report each once (more than stay undecided at a time)


class Live:
    """Streaming recognition of the tracks ``names`` (all sampled together at ``rate``).

    :meth:`push` one frame (a time and one ``(p, q, ok)`` per track) at a time; it returns
    what became final (a :class:`Step`): each track's segments as the Matcher and Refiner
    decide them, with behaviour states applied per track as they come, and an interaction's
    roles once every track has decided past it; a track that two-handed learned actions
    also read has its segments heard once the tracks deciding those actions have decided
    past them, less those a two-handed action heard there covers (as :func:`with_pairs`
    lays it over them in the batch). :meth:`close` ends the stream and returns
    the rest; :attr:`result` is then the whole performance decided as :func:`recognize`
    decides it. With ``restart``, a track whose samples the Segmenter refuses (tracking back
    after a gap too long to bridge) starts afresh at that frame, what came before staying
    final (live recording); without, the error propagates (a file is read as a whole).
    ``compiled`` None streams the tokens alone (a library with nothing to recognise yet):
    no segments, and :attr:`result` has each track's tokens with none.

    Provisional actions (``provisional``, on by default): a step also carries, in
    :attr:`Step.provisional`, the actions the tokens so far already decide if what the
    Segmenter still holds back stands as it is (its tokens not final yet, a pause once it
    could be one) — the final decision's own rules on a copy of each track's Matcher, so
    that a segment is provisional only once no continuation the Matcher still keeps could
    change it: typically as soon as the pause after a gesture could be a pause, long before
    the pause ends and makes it final. Past what the Matcher has settled, learned gestures
    performed back to back are named as they end by a :class:`~grammar.spotter.Spotter`.
    Each is reported once (again if its name changes, not once a later motion on its track
    has been reported); interactions are only reported final.
    """

    def __init__(self, compiled: Compiled | None, names: list[str], rate: float, params: SegmenterParams = SegmenterParams(),
                 threshold: float = 2.0, source: str = "<stream>", automata: dict | None = None,
                 restart: bool = False, provisional: bool = True):
        self.compiled, self.names, self.rate, self.params = compiled, list(names), float(rate), params
        self.threshold, self.source, self.restart, self.provisional = threshold, source, restart, provisional
        if automata is None:
            automata = track_automata(compiled, self.names, threshold) if compiled is not None else {}
        self.automata = automata
        self.tape = _Tape(self.names)
        self.read = {n: ([], 0) for n in self.names}  # per track: movement its Matcher read as no action, final to
        self.chains = {n: _Chain(self, n, 0) for n in self.names}
        self._done = {n: ([], []) for n in self.names}  # tokens and segments of finished chains, shifted
        self._rules = behaviours(compiled) if compiled is not None else {}
        self._pairs = two_handed(compiled) if compiled is not None else {}
        self._laying = []  # two-handed segments still to be heard on their other tracks
        self._owners = _owners(compiled, self.names)  # a track two-handed actions read → the tracks deciding them
        self._decided = {n: -1 for n in self.names}  # sample up to which a track's segments were heard
        self._holding = {n: [] for n in self.names}  # a partner track's final segments, until its owners decide
        self._covered = {n: [] for n in self.names}  # samples of two-handed actions heard, laid over a partner
        self._settled_at = {n: (None, False) for n in self.names}  # what _settled last read, and whether at rest
        self._state = {n: frozenset(compiled.library.states if compiled is not None else ()) for n in self.names}
        self._shown = {n: [] for n in self.names}  # the provisional segments last worked out, per track
        self._told = {n: [] for n in self.names}  # the provisional segments last reported, in order (TOLD)
        self._front = {n: -1 for n in self.names}  # where the latest motion reported provisional begins (sample)
        self._turn = 0  # the track whose provisional actions are worked out first at the next frame
        self._contexter = None
        if compiled is not None and len(self.names) > 1 and compiled.library.interactions:
            self._contexter = LiveContexter(self.tape, compiled, threshold)
        self.result: dict | None = None

    def pending(self, name: str) -> Token | None:
        """The token in progress on a track (live feedback)."""
        chain = self.chains[name]
        token = chain.segmenter.pending
        return None if token is None else Token(token.name, token.start + chain.offset, token.end + chain.offset)

    def push(self, t: float, poses, labels: bool = True) -> Step:
        """One frame: a time and one ``(p, q, ok)`` per track, in the order of ``names``.
        ``labels`` False leaves the provisional actions to a later frame (one reading
        behind the clock, with frames waiting: the first frame that works them out reads
        all the tokens so far); what is decided is the same."""
        self.tape.append(t, poses)
        tokens, heard, restarted = {}, [], {}
        for name, (p, q, ok) in zip(self.names, poses):
            try:
                new = self.chains[name].segmenter.push(t, p, q, ok)
            except DoodleError as exc:
                if not self.restart:
                    raise
                old, h = self._finish(name, flush=False)
                heard += h
                self.chains[name] = _Chain(self, name, self.tape.n - 1)
                restarted[name] = str(exc)
                new = self.chains[name].segmenter.push(t, p, q, ok)
                tokens[name] = old
            tokens[name] = tokens.get(name, []) + self._global(name, new)
            heard += self._heard(name, self.chains[name].feed(new, self.tape), new)
        if self._pairs:  # a Refiner waiting for what another track's Matcher read there
            for name in self.names:
                heard += self._heard(name, self.chains[name].nudge(self.tape), [])
            heard += self._release()
        if self._laying:
            heard += self._lay()
        return Step(tokens, heard, restarted, self._provisional_labels() if self.provisional and labels else [])

    def _provisional_labels(self) -> list[Heard]:
        """One track's provisional actions worked out afresh per frame, the tracks taking
        turns among those whose held-back tokens changed (a frame's cost stays that of one
        track; another waits a frame, 11 ms at 90 Hz)."""
        n = len(self.names)
        for k in range(n):
            name = self.names[(self._turn + k) % n]
            if self.chains[name].due():
                self._turn = (self._turn + k + 1) % n
                return self._provisional(name)
        return []

    def _provisional(self, name: str) -> list[Heard]:
        """A track's actions newly provisional (:meth:`_Chain.provisional`): behaviour
        states applied as they would be (a refused one is no action), a two-handed action as
        its first role — and as its other roles on the other tracks performing it, whose own
        readings it covers there (as :func:`with_pairs` lays it over them in the batch); each
        reported once, and again only if its name changes."""
        chain = self.chains[name]
        segments = chain.provisional(self.tape)
        if segments is None:
            return []
        shift, state = len(self._done[name][0]), self._state[name]
        covered = [(p.start, p.end) for p in self._paired_shown(name)] + self._covered[name]  # (provisional, final)
        reach, further = self._owners_read(name)
        shown, out = [], []
        for s in segments:
            s = _shifted(s, chain.offset, shift)
            if s.end > reach and further is not None:
                reach, further = further(), None
            if s.end > reach:
                break  # (a two-handed action under way on a track deciding it may yet be shown there)
            rule = self._rules.get(s.action)
            if rule is not None:
                if not rule.allowed(state):
                    continue
                state = rule.after(state)
            if s.action == "unknown" or any(a < s.end and s.start < b for a, b in covered):
                continue  # (what a two-handed action shown on another track covers is that action here)
            if s.action in self._pairs:
                s = _role(s, s.first, s.stop, 0)
            shown.append(s)
            if self._tell(name, s):
                out.append(Heard(name, s, final=False))
        self._shown[name] = shown
        # a two-handed action newly shown is shown on its other tracks too (token indices: the deciding track's)
        return out + [Heard(other, replace(h.segment, role=role), final=False)
                      for h in out if h.segment.action in self._pairs
                      for role, other in enumerate(self._pairs[h.segment.action], 1) if other in self._shown]

    def _tell(self, name: str, s: Segment) -> bool:
        """Whether segment ``s`` is to be reported on track ``name``: nothing was reported
        over the same motion yet (most of the shorter of the two), or the last report there
        has another name. Remembered as what is reported there now (in place of what it
        mostly covers). The same motion, not any overlap: two readings of neighbouring motion
        that overlap at their ends (one decided as if the stream ended there, the next
        spotted past it) would otherwise each be reported again at every frame, and a
        gesture repeated back to back would not be reported the second time. Never a motion
        ending before the latest one reported there (other than a pause) begins: the live
        view moves forward, and an earlier motion's name comes when it is decided — where
        gestures follow each other without a pause, the reading of motion seconds old, not
        settled yet, may change back and forth as the motion after it goes on."""
        told = self._told[name]
        if s.end <= self._front[name]:
            return False
        same = [o for o in told if 2 * (min(o.end, s.end) - max(o.start, s.start)) > min(o.end - o.start, s.end - s.start)]
        if same and same[-1].action == s.action:
            return False
        told[:] = [o for o in told if 2 * (min(o.end, s.end) - max(o.start, s.start)) <= o.end - o.start][-TOLD + 1:] + [s]
        if s.action != PAUSE:
            self._front[name] = max(self._front[name], s.start)
        return True

    def _owners_read(self, name: str) -> tuple:
        """The sample past which track ``name``'s own provisional reading waits: where a track
        deciding two-handed actions that read it too (:func:`_owners`), whose motion may be
        one under way (:meth:`_Chain.pair_begun`), has shown what it reads up to (provisional
        or final) — there, a two-handed action may yet be laid over this track's reading.
        Infinite when no such track's motion may be one. Given as ``(the least of those
        samples, a function giving it)``: whether a motion may be a two-handed action under
        way is worked out only for a segment that ends past all of them."""
        owners = self._owners.get(name, ())
        if not owners:
            return math.inf, None
        shown = {o: max([self._decided[o]] + [s.end for s in self._shown[o]]) for o in owners}
        return min(shown.values()), lambda: min((r for o, r in shown.items() if self.chains[o].pair_begun()),
                                                default=math.inf)

    def _paired_shown(self, name: str) -> list[Segment]:
        """The two-handed actions shown provisional on the tracks deciding those that read
        track ``name`` too (:func:`_owners`), now or as last reported there: the track's own
        reading there is that action."""
        return [s for owner in self._owners.get(name, ()) for s in self._shown[owner] + self._told[owner]
                if s.action in self._pairs and name in self._pairs[s.action]]

    def close(self, flush: dict | None = None) -> Step:
        """End every track; ``flush[name]`` False ends a track where its classification
        stands (tracking lost for good at the end), without the samples still being smoothed."""
        tokens, heard = {}, []
        ends = {name: self._end_matching(name, True if flush is None else flush.get(name, True)) for name in self.names}
        for name in self.names:  # every Matcher closed first: a Refiner may read what the others' found
            tokens[name], new = self._end_refining(name, *ends[name])
            heard += new
        heard += self._release(final=True)
        heard += self._lay(final=True)
        if self._contexter is not None:
            heard += self._interactions(self._contexter.close())
        view = {n: tuple(self._done[n]) for n in self.names}
        self.result = decide(self.tape, self.compiled, view, self.threshold) if self.compiled is not None else view
        return Step(tokens, heard, {})

    def _global(self, name: str, tokens: list[Token]) -> list[Token]:
        off = self.chains[name].offset
        return [Token(k.name, k.start + off, k.end + off) for k in tokens] if off else list(tokens)

    def _finish(self, name: str, flush: bool) -> tuple[list[Token], list[Heard]]:
        return self._end_refining(name, *self._end_matching(name, flush))

    def _end_matching(self, name: str, flush: bool) -> tuple[list[Token], list[Segment], list[Segment]]:
        """A track's Segmenter and Matcher closed: its last tokens, the segments decided on the
        way and the Matcher's last segments (not refined yet)."""
        chain = self.chains[name]
        tokens = []
        if flush:
            try:
                tokens = chain.segmenter.close()
            except DoodleError:  # fewer than two samples since a restart, or never tracked
                flush = False
        if not flush:
            tokens = chain.segmenter.cut()
        return tokens, chain.feed(tokens, self.tape), chain.end_matching()

    def _end_refining(self, name: str, tokens: list[Token], decided: list[Segment],
                      last: list[Segment]) -> tuple[list[Token], list[Heard]]:
        """A track's Refiner closed after :meth:`_end_matching`: its last tokens and what was heard."""
        chain = self.chains[name]
        segments = chain.end_refining(self.tape, last)
        chain.segments += segments
        heard = self._heard(name, decided + segments, tokens)
        done_tokens, done_segments = self._done[name]
        shift = len(done_tokens)
        done_tokens += self._global(name, chain.tokens)
        done_segments += [_shifted(s, chain.offset, shift) for s in chain.segments]
        chain.finished = True
        return self._global(name, tokens), heard

    def _heard(self, name: str, segments: list[Segment], tokens: list[Token]) -> list[Heard]:
        chain = self.chains[name]
        shift = len(self._done[name][0])
        segments = [_shifted(s, chain.offset, shift) for s in segments]
        out = []
        if self._contexter is not None:
            for token in self._global(name, tokens):
                out += self._interactions(self._contexter.push_token(name, token))
        if segments:
            self._decided[name] = max(self._decided[name], segments[-1].end)
        if name in self._owners:  # heard once the tracks deciding its two-handed actions have decided past it
            self._holding[name] += segments
            return out
        return out + self._hear(name, segments)

    def _settled(self, name: str) -> float:
        """The sample before which no action still to come on track ``name`` can lie: the
        end of what it has decided — or, when all it has not decided yet is a pause that
        may be a pause by now (:meth:`Segmenter.held`), the samples classified so far: an
        action starts with a movement (so a character at rest holds back no other's)."""
        chain, decided = self.chains[name], self._decided[name]
        if chain.finished or chain.tokens_only:
            return decided
        key = (id(chain), len(chain.tokens), decided, chain.segmenter.held_key())
        if self._settled_at[name][0] != key:  # what held() reads has changed
            self._settled_at[name] = (key, self._at_rest(chain, decided))
        if not self._settled_at[name][1]:
            return decided
        return max(decided, chain.segmenter.pending.end + chain.offset)  # the pause goes on

    @staticmethod
    def _at_rest(chain: _Chain, decided: float) -> bool:
        """Whether all of a track not decided yet is a pause that may be a pause by now."""
        for k in reversed(chain.tokens):
            if k.end + chain.offset <= decided:
                break
            if k.name != "T_STILL":
                return False
        held = chain.segmenter.held()
        pending = chain.segmenter.pending
        return bool(held) and pending is not None and all(k.name == "T_STILL" for k in held) \
            and held[-1].end >= pending.end

    def _known(self, name: str) -> list[Token]:
        """A track's tokens so far (sample indices of the stream)."""
        chain = self.chains[name]
        return self._done[name][0] + ([] if chain.finished else self._global(name, chain.tokens))

    def _release(self, final: bool = False) -> list[Heard]:
        """A partner track's held segments heard, as far as the tracks deciding its
        two-handed actions have decided (all at the end): less the actions a two-handed one
        heard there covers for at least half of their tokens (it is laid over them, as
        :func:`overlay` does in the batch)."""
        out = []
        for name, owners in self._owners.items():
            held = self._holding[name]
            if not held:
                continue
            upto = math.inf if final else min(self._settled(o) for o in owners)
            n = 0
            while n < len(held) and held[n].end <= upto:
                n += 1
            if not n:
                continue
            ready, self._holding[name] = held[:n], held[n:]
            covered = self._covered[name] = [(a, b) for a, b in self._covered[name] if b > ready[0].start]
            kept = [s for s in ready if s.action == "unknown" or not any(
                2 * self._within(name, s, a, b) >= s.stop - s.first for a, b in covered if a < s.end and s.start < b)]
            out += self._hear(name, kept)
        return out

    def _within(self, name: str, s: Segment, a: int, b: int) -> int:
        """How many of segment ``s``'s tokens (of track ``name``) lie over samples a..b."""
        done, chain = self._done[name][0], self.chains[name]
        count = 0
        for i in range(s.first, s.stop):
            k = done[i] if i < len(done) else chain.tokens[i - len(done)]
            start, end = (k.start, k.end) if i < len(done) else (k.start + chain.offset, k.end + chain.offset)
            count += end > a and start < b
        return count

    def _hear(self, name: str, segments: list[Segment]) -> list[Heard]:
        """A track's final segments heard: interactions, behaviour states, two-handed actions."""
        out = []
        if self._contexter is not None:
            out += self._interactions(self._contexter.push_segments(name, segments))
        for s in segments:
            rule = self._rules.get(s.action)
            if rule is not None:
                if rule.allowed(self._state[name]):
                    self._state[name] = rule.after(self._state[name])
                else:
                    s = Refused("unknown", s.first, s.stop, s.start, s.end, False, None,
                                refused=s.action, reason=rule.why(self._state[name]))
            if s.action in self._pairs and not isinstance(s, (Refused, InteractionSegment)):
                out.append(Heard(name, _role(s, s.first, s.stop, 0)))  # one gesture, heard on every track
                for other in self._pairs[s.action]:
                    self._covered.get(other, []).append((s.start, s.end))
                self._laying += [(s, role, other) for role, other in enumerate(self._pairs[s.action], 1)
                                 if other in self.chains]  # once the other track's tokens reach its end
                continue
            out.append(Heard(name, s))
        return out

    def _lay(self, final: bool = False) -> list[Heard]:
        """Two-handed segments heard on their other tracks once those tracks' tokens reach
        their end (at the end of the stream, as far as they go)."""
        out, waiting = [], []
        for s, role, other in self._laying:
            chain, done = self.chains[other], self._done[other][0]
            last = (chain.tokens[-1].end + chain.offset if chain.tokens and not chain.finished
                    else done[-1].end if done else None)  # where the other track's tokens reach
            if not final and (last is None or last < s.end):
                waiting.append((s, role, other))
                continue
            out += [Heard(other, o) for o in overlay([], self._known(other), s, role) if isinstance(o, InteractionSegment)]
        self._laying = waiting
        return out

    def _interactions(self, found) -> list[Heard]:
        out = []
        for f, segs in found:
            for role, (name, s) in enumerate(zip(f.tracks, segs)):
                out.append(Heard(name, InteractionSegment(s.action, s.first, s.stop, s.start, s.end, s.exact,
                                                          s.distance, interaction=f.interaction, role=role)))
        return out
