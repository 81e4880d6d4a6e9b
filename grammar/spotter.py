"""Learned gestures named as they end, when they follow each other without a pause: live
provisional labels only (:class:`grammar.recognizer.Live`); what is final is the Refiner's.

Back to back, the Matcher keeps a learned action's continuations open and the Refiner decides
a learned gesture once the pause after its motion is known, or :data:`~grammar.refiner.SPOT_MAX`
tokens later without one — seconds after the gesture ended. A :class:`Spotter` reads the
tokens past what the Matcher has settled, one at a time, and scores, at every token boundary,
the windows ending there. A window starts at the spotter's anchor — where the last gesture it
named ended, a pause ended, or :data:`~grammar.refiner.TRIM` tokens before what the Matcher
settled ends (what the Refiner may give up at a segment's end, the next gesture may begin
with) — or anywhere after it; it holds at least :data:`~grammar.refiner.SPOT_TOKENS`
tokens and no pause, and is the learned action it is nearest by the Refiner's own rule
(``edits + WEIGHT × shape distance``, within the action's examples' durations:
:meth:`Refiner.nearest`) — here only when its shape distance is within :data:`~grammar.refiner.SURE` of the
action's rejection distance, not the whole of it: a gesture's first part fits a shorter
gesture loosely, a whole gesture its own closely. (SURE was chosen by leave-one-user-out on
the real users' held-out takes streamed back to back: per user, the value among 0.3–1.0 whose
spots, on the other four users, best balance naming the final action against leaving out
spots that name it — 0.4 in every fold.) The best window ending at a boundary is spotted once
every window ending at each of the :data:`LAG` boundaries after it scores worse: the gesture
fits best there and what follows is another motion. (LAG too was chosen by
leave-one-user-out on those streams: per user, among 1–3, the value whose names on the other
four users come within 0.3 s of a gesture's end, the median and 90 % of them, naming the
final action most often — 1 in every fold; 3 would name it 2 % more often, 90 % within
0.6–0.7 s.) The anchor then moves to its end; and while a window from the spotted one's
start to a later boundary scores better for its action, the gesture was going on: the spot
reaches there and so does the anchor (a spot ended early by a passing dip in the score). Of
windows starting at the anchor or within TRIM tokens of it alone, a gesture ended early left
its tail before the next one's start, and no window could begin there until every action's
longest example had passed: by leave-one-user-out on those streams (per user, on the other
four: the variants whose names come within 0.3 s, the median and 90 %, naming the final
action most often, differences within a standard error counted as ties, broken by the
quicker), windows starting anywhere and spots that go on were chosen in 4 of 5 folds (one
chose starting anywhere alone). This
is continuous segmentation by a score read as the stream goes on, in the spirit of Machete
(Taranta, Pittman, Maghoumi, Maslych, Moolenaar & LaViola 2021, "Machete: easy, efficient,
and precise continuous custom gesture segmentation", ACM TOCHI 28(1)). A pause ends every
window: gestures a pause apart are named by the Refiner's own provisional reading, soon after
the pause begins.

A gesture's first part can fit a shorter gesture whole (a left-right-left combo's first two
punches a hook). A window about to be spotted that fits a longer action's beginning — open-end
DTW against the first :data:`BEGINNING` of its examples, within SURE — more closely than it
fits its own action whole is held back while the motion goes on as that beginning (or the
whole of it); once it does not, or at a pause, the window held back (of two, the one that
scores better) is spotted after all. (On
the streams above, leave-one-user-out: the held-out users' labels name the final action as
often or more often, 90 % of names staying within 0.3 s on the other four users.)
"""

from __future__ import annotations

import numpy as np

from grammar.refiner import SPOT_MAX, SPOT_TOKENS, SURE, TEMPO, TRIM, Refiner

LAG = 1  # token boundaries after a window that must score worse before it is spotted
BEGINNING = (1 / 3, 0.8)  # how much of a longer action's examples a window is compared against as their beginning
HELD = -1  # where a scores dict keeps a window held back: (its end, the window, the longer action it may begin, its score)


class Spotter:
    """One track's spotting state over its final tokens (the Refiner's ``tokens``): the
    automaton's costs of every window start still open, and the best window per end."""

    def __init__(self):
        self.anchor = 0  # no window starts before this token
        self._n = 0  # final tokens read
        self._states: dict[int, np.ndarray] = {}  # window start -> automaton costs of its tokens so far
        self._scores: dict[int, tuple | None] = {}  # window end -> (score, first, stop, action, edits) or None
        self.spotted: list[tuple] = []  # (first, stop, action, edits) from final tokens, in order
        self._going: list | None = None  # while the last spot may go on: [its score, its start's automaton costs]

    def spots(self, refiner: Refiner, final: int, floor: int) -> list[tuple]:
        """The windows spotted from token ``floor`` − :data:`~grammar.refiner.TRIM` on
        (``floor``: where what the Matcher settled ends), ``(first, stop, action, edits)`` in
        order: ``refiner`` bound to the track's samples, its ``tokens`` the ``final`` tokens
        then those held back as they stand (what may yet change: read on a copy, at most one
        window spotted there)."""
        floor -= TRIM  # (what the Refiner gives up at a segment's end the next gesture may begin with)
        if floor > self.anchor:
            self._move(floor)
        while self._n < final:
            self._read(refiner, self._n, self._states, self._scores, keep=True)
        self.spotted = [s for s in self.spotted if s[0] >= floor]
        states, scores, anchor = dict(self._states), dict(self._scores), self.anchor
        for k in range(final, len(refiner.tokens)):
            spot = self._read(refiner, k, states, scores, keep=False, anchor=anchor)
            if spot is not None:
                return self.spotted + [spot]
        return list(self.spotted)

    def begins_pair(self, refiner: Refiner) -> bool:
        """Whether the tokens of ``refiner`` (bound as for :meth:`spots`) from the anchor on,
        or from anywhere after it (as a window may start), may be a two-handed action under
        way: they fit the beginning of one's examples, or all of them (:meth:`_begins`).
        (From anywhere, not only the anchor or a few tokens after it: on the streams the
        Spotter's constants were chosen on, with both hands learned, the second hand's own
        reading was shown under a two-handed gesture less often for every held-out user, the
        names as soon — leave-one-user-out.)"""
        pairs = refiner.shapes.partners
        e = len(refiner.tokens)
        if not pairs or e - self.anchor < SPOT_TOKENS:
            return False
        two = np.array([bool(others) for others in pairs]) & refiner.allowed
        return any(Spotter._may_begin(refiner, f, e, two).any()
                   for f in range(max(self.anchor, e - SPOT_MAX), e - SPOT_TOKENS + 1)
                   if refiner.readable(f, e) and all(k.name != "T_STILL" for k in refiner.tokens[f:e]))

    def _move(self, anchor: int) -> None:
        self.anchor = anchor
        self._states = {f: d for f, d in self._states.items() if f >= anchor}
        self._scores = {e: s for e, s in self._scores.items()
                        if (e > anchor and (s is None or s[1] >= anchor)) or (e == HELD and s[1][0] >= anchor)}

    def _read(self, refiner: Refiner, k: int, states: dict, scores: dict, keep: bool, anchor: int | None = None):
        """Token ``k`` read into ``states`` and ``scores``; the window it spots, if any (kept,
        and the anchor moved, when ``keep``)."""
        from doodle.core.tokens import CODES

        auto = refiner.shapes.automaton
        token = refiner.tokens[k]
        anchor = self.anchor if anchor is None else anchor
        if keep:
            self._n = k + 1
        if token.name == "T_STILL":  # a pause ends every window (one held back is the gesture: it stops there)
            if keep:
                self._going = None
            held = scores.pop(HELD, None)
            spot = held[1] if held is not None and held[1][0] >= anchor else None
            if keep and spot is not None:
                self.spotted.append(spot)
            states.clear()
            scores[k + 1] = None
            if keep:
                self._move(k + 1)
            return spot
        code = CODES[token.name]
        if keep:  # (going on may move the anchor, which renews the kept dicts)
            self._go_on(refiner, k, code)
            states, scores, anchor = self._states, self._scores, self.anchor
        for f in list(states):
            if k + 1 - f > SPOT_MAX:
                del states[f]
            else:
                states[f] = auto.step(states[f], code)
        states[k] = auto.step(auto.initial.copy(), code)
        scores[k + 1] = self._best(refiner, states, k + 1, anchor)
        held = scores.pop(HELD, None)
        if held is not None and held[1][0] >= anchor:
            if self._begins(refiner, held[1][0], k + 1, held[2]):
                scores[HELD] = held  # (still that action's beginning, or the whole of it)
            else:  # the motion went on as something else: the window held back was the gesture
                return self._spot(held[1], held[0], keep)
        c = k + 1 - LAG
        best = scores.get(c)
        if best is None or best[1] < anchor or any(
                scores.get(c + j) is not None and scores[c + j][0] <= best[0] for j in range(1, LAG + 1)):
            return None
        spot = best[1:]
        longer = self._longer(refiner, spot)
        if longer is not None:
            if HELD not in scores or scores[HELD][3] > best[0]:  # (the better of two windows held back stays)
                scores[HELD] = (c, spot, longer, best[0])
            return None
        scores.pop(HELD, None)
        if not keep:
            return spot
        going = [best[0], states[spot[0]].copy()]  # (before the anchor moves past its start)
        self._spot(spot, c, True)
        self._going = going
        return spot

    def _spot(self, spot: tuple, c: int, keep: bool) -> tuple:
        if keep:
            self.spotted.append(spot)
            self._going = None  # (only a spot made at a turn of the score goes on: :meth:`_read` sets it)
            self._move(c)
        return spot

    def _go_on(self, refiner: Refiner, k: int, code: int) -> None:
        """Token ``k`` (of automaton ``code``, final) read into the last spot while it may go
        on: if the window from its start through ``k`` scores better for its action than the
        spot did, the spot reaches there, and so does the anchor. It stops going on once that
        window holds a pause, or lasts longer than the action may, or more than
        :data:`~grammar.refiner.SPOT_MAX` tokens."""
        going = self._going
        if going is None or not self.spotted:  # (what the Matcher settled may have passed it)
            self._going = None
            return
        f, _, a, _ = self.spotted[-1]
        auto = refiner.shapes.automaton
        going[1] = auto.step(going[1], code)
        e = k + 1
        if e - f > SPOT_MAX or not refiner.readable(f, e) or not Spotter._could_go_on(refiner, f, e)[a]:
            self._going = None
            return
        edits = auto.accept_costs(going[1])[None]
        _, score = refiner.nearest([(f, e)], edits, SURE)
        if score[0, a] < going[0]:
            going[0] = float(score[0, a])
            self.spotted[-1] = (f, e, a, float(edits[0, a]))
            self._move(e)

    @staticmethod
    def _longer(refiner: Refiner, spot: tuple) -> int | None:
        """The action a spot's window may be the beginning of, or None: another action, one
        that could still be going on (:meth:`_begins`), whose examples' beginnings
        (:data:`BEGINNING`, open-end DTW) the window fits within :data:`~grammar.refiner.SURE` of its
        rejection distance and closer, for that distance, than the spot's action whole. A
        gesture's first part can fit a shorter gesture whole (a combo's first two punches a
        hook): it is held back while the motion goes on as the longer one's beginning."""
        f, e, a, _ = spot
        begun = refiner.beginnings((f, e), BEGINNING)
        whole = refiner.distances([(f, e)])[0, a] / refiner.shapes.reject[a]
        longer = np.flatnonzero(refiner.allowed & Spotter._could_go_on(refiner, f, e) & (begun <= SURE) & (begun < whole))
        longer = longer[longer != a]
        return int(longer[np.argmin(begun[longer])]) if len(longer) else None

    @staticmethod
    def _begins(refiner: Refiner, f: int, e: int, b: int) -> bool:
        """Whether window f..e may still be action ``b``'s beginning, or the whole of it
        (:meth:`_may_begin`)."""
        among = np.zeros(len(refiner.shapes.names), dtype=bool)
        among[b] = True
        return bool(Spotter._may_begin(refiner, f, e, among)[b])

    @staticmethod
    def _may_begin(refiner: Refiner, f: int, e: int, among: np.ndarray) -> np.ndarray:
        """(actions,): which of the actions ``among`` window f..e may be the beginning of, or
        the whole of: it lasts less than :data:`~grammar.refiner.TEMPO` × the action's longest
        example, and fits its examples' beginnings (from :data:`BEGINNING`'s first part to all
        of them) within :data:`~grammar.refiner.SURE` of its rejection distance (no DTW when none could last)."""
        could = among & Spotter._could_go_on(refiner, f, e)
        if not could.any():
            return could
        return could & (refiner.beginnings((f, e), (BEGINNING[0], 1.0)) <= SURE)

    @staticmethod
    def _could_go_on(refiner: Refiner, f: int, e: int) -> np.ndarray:
        """(actions,): whether window f..e lasts less than TEMPO × each action's longest
        example (all True when durations are not known)."""
        longest = refiner.shapes.longest
        if refiner.t is None or longest is None:
            return np.ones(len(refiner.shapes.names), dtype=bool)
        return Spotter._seconds(refiner, f, e) < TEMPO * longest

    @staticmethod
    def _seconds(refiner: Refiner, f: int, e: int) -> float:
        t, tokens = refiner.t, refiner.tokens
        return float(t[min(tokens[e - 1].end, len(t)) - 1] - t[tokens[f].start])

    @staticmethod
    def _best(refiner: Refiner, states: dict, e: int, anchor: int):
        """The best window ending at token boundary ``e`` (of the starts in ``states``), or None."""
        windows = [(f, e) for f in sorted(states) if f >= anchor and e - f >= SPOT_TOKENS and refiner.readable(f, e)]
        windows = [w for w, fits in zip(windows, refiner.lasts(windows).any(axis=1)) if fits] if windows else []
        if not windows:  # (none lasts about as long as some action's examples)
            return None
        edits = np.array([refiner.shapes.automaton.accept_costs(states[f]) for f, _ in windows])
        _, score = refiner.nearest(windows, edits, SURE)
        w, k = np.unravel_index(int(np.argmin(score)), score.shape)
        if not np.isfinite(score[w, k]):
            return None
        return float(score[w, k]), windows[w][0], windows[w][1], int(k), float(edits[w, k])
