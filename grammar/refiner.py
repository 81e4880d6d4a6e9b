"""The Matcher's segments re-decided by the learned actions' shapes (:mod:`grammar.shapes`).

The shape distance of a performance to an action ranks the actions whose expressions the
Matcher found: ``edits +`` :data:`WEIGHT` ``× shape distance``; an action is rejected past
its rejection distance. Of the windows around a segment, the one explaining the motion
between the pauses best wins — the whole motion whenever it fits an action —, and a window
leaving part of it out pays for that part at the action's rejection distance (:class:`Refiner`); a
motion that two learned gestures fit better than one is read as both, back to back; one
the Matcher read as pieces of built-in actions is the learned action that fits it whole —
or, where gestures follow each other without a pause, that fits those pieces together.
Streaming (:class:`Refiner`, pushed segments as the Matcher gives them) equals batch
(:func:`refine`).
"""

from __future__ import annotations

import bisect
import copy
from dataclasses import replace

import numpy as np

from grammar.shapes import Group, ShapeSet, sample, times

WEIGHT = 62.0  # edits one unit of shape distance counts as (two per step whose features are 1 apart; `make bench` shows it held out)
REACH = 3  # tokens a refined segment may extend past the Matcher's at either end
TRIM = 3  # tokens it may give up at either end
UNKNOWN_REACH = 8  # tokens it may take from a neighbouring unknown run
SPOT_TOKENS, SPOT_MAX = 4, 40  # unknown runs of this many tokens are searched for a learned action…
SPOT = 1.0  # …found when its shape distance is under this part of the action's rejection distance
SEEN = 20000  # windows whose shape distances a Refiner keeps (beyond: the oldest half forgotten)
SURE = 0.4  # a window fits an action closely within this part of its rejection distance (chosen for the Spotter: grammar.spotter)
TEMPO = 1.5  # a window is not an action when it lasts over this × its longest example or under its shortest / this


def refine(segments: list, tokens: list, p: np.ndarray, valid: np.ndarray, shapes: ShapeSet,
           track: str | None = None, q: np.ndarray | None = None, others: dict | None = None,
           t: np.ndarray | None = None, partners: dict | None = None) -> list:
    """Batch form of :class:`Refiner`: every segment of a track re-decided."""
    refiner = Refiner(shapes, p, valid, track, q, others, t, partners)
    refiner.tokens.extend(tokens)
    return refiner.push(segments) + refiner.close()


def unread(tokens: list, segments: list) -> list[tuple[int, int]]:
    """The samples ``(start, end)`` of a track's movement its Matcher read as no action: the
    tokens other than pauses in its unknown segments."""
    from grammar.matcher import UNKNOWN

    return [(k.start, k.end) for s in segments if s.action == UNKNOWN for k in tokens[s.first:s.stop]
            if k.name != "T_STILL"]


class Refiner:
    """The Matcher's segments of one track, re-decided by the learned actions' shapes.

    Segments are taken in order. One whose action has shapes is re-decided once the next
    segment and the :data:`REACH` tokens after it are known: every window of whole tokens
    from up to :data:`REACH` tokens before to :data:`TRIM` after its first token, and
    likewise around its last — or, when the next segment has shapes too (directly or after
    a few unknown tokens, :meth:`_second_half`), around the next one's last (the Matcher,
    with a learned action's large tolerance, may cut one long gesture in two) — no window
    starting or ending on a pause or reaching back into what
    is already decided, is scored for every shaped action as ``edits + WEIGHT × shape distance``.
    Each window is the action it scores best for, when its shape distance is within that
    action's :attr:`ShapeSet.reject` (else it is none). The segment's *motion* — its tokens
    from the pause before it to the pause after it (or the end of the track), when that is
    at most :data:`SPOT_MAX` tokens — bounds the windows (none crosses those pauses) and is
    a window itself; a window pays for the motion's path length it leaves out as if that
    were at the action's rejection distance (:meth:`_best`). The best window wins — unless
    two learned actions fit the motion's two parts better than one fits it (:meth:`_two`):
    then both are read, back to back (with no pause within :data:`SPOT_MAX` tokens, the
    segment's own tokens are tried so, and the best window too where it reaches over the
    next segment). With none, the segment's own tokens are searched as an unknown run's
    are (two gestures or one); failing that, it is unknown. A window may also take back up
    to :data:`UNKNOWN_REACH` tokens of the unknown run before it, or reach as far into the
    unknown run after it. Tokens a window takes from the next segment are taken from it;
    tokens it gives up are unknown. An unknown run of :data:`SPOT_TOKENS` tokens or more
    is searched the same way — one longer than :data:`SPOT_MAX` a part at a time, each
    ending at a pause — and every learned action that fits within :data:`SPOT` of its
    rejection distance is reported, the best first, then the rest of the run on either side
    searched again (:meth:`_spots`). Other segments pass through
    (less any tokens taken) — but a built-in action's segment in a motion the Matcher read
    in pieces is the learned action that fits the whole motion, if one does (or two that
    fit its two parts better, back to back), or else the one that fits the segment with
    the pieces beside it, cutting no other built-in segment (:meth:`_over_builtin`,
    :meth:`_among_pieces`); it waits for the pause ending its motion
    and for the Matcher's segments as far as such a window may reach. A shaped
    segment is decided once the pause ending its motion is known (or :data:`SPOT_MAX`
    tokens have passed without one). An unknown run whose
    motion goes on, without a pause, into a shaped segment is not searched: it waits, and
    that segment's windows may take its tokens back (a gesture the Matcher found only the
    end of is read whole, not as two). Whatever unknown run lies before a shaped segment once
    that segment's window is chosen — however it was made up: what windows gave up, short
    unknown segments — is searched so too, whole (:meth:`_spot_pending`). The batch form
    (:func:`refine`) is this run to the end, so streaming equals batch.

    ``tokens`` is the track's token list (append as the Segmenter gives them); ``p``, ``q``
    and ``valid`` the track's samples, at least as far as the tokens go; ``track`` its name
    (actions bound to other tracks are not considered); ``others`` the other tracks'
    samples, ``{name: (p, q, valid)}`` over the same sample times, read by two-handed
    actions recognised on this track (a window's shape is both hands' over its samples);
    ``partners`` what the other tracks' Matchers made of them, ``{name: (spans, known)}``:
    the samples of their movement read as no action (:func:`unread`, in order) and the sample
    up to which that is final — counted from :attr:`shift` samples before this track's first.
    A built-in segment read whole as its motion, which a two-handed learned action fits at
    more edits, waits until they are final as far as that motion goes.
    """

    def __init__(self, shapes: ShapeSet, p: np.ndarray, valid: np.ndarray, track: str | None = None,
                 q: np.ndarray | None = None, others: dict | None = None, t: np.ndarray | None = None,
                 partners: dict | None = None):
        self.shapes, self.p, self.valid, self.q, self.t = shapes, p, valid, q, t
        self.track, self.others = track, dict(others or {})
        self.partners = dict(partners or {})
        self.shift = 0  # samples of the stream before this track's first (the partners' indices count from it)
        self.waiting_for_partners = False  # whether the next segment waits for the other tracks' Matchers
        self._over: dict = {}  # _two_handed_over's answers
        self._seen: dict = {}  # shape distances by the samples a window spans (shared with forks)
        self._allowed = shapes.allowed(track, set(self.others) | {track})
        pairs = shapes.partners or ((),) * len(shapes.names)
        self._paired = {o for k, others in enumerate(pairs) if self._allowed[k] for o in others}  # tracks read too
        self.tokens: list = []
        self._waiting: list = []
        self._done = 0  # tokens before this are decided
        self._unknown = None

    @property
    def allowed(self) -> np.ndarray:
        """(actions,): which learned actions may be recognised on this track."""
        return self._allowed

    def fork(self) -> "Refiner":
        """An independent copy (what it is pushed leaves this one as it is)."""
        other = copy.copy(self)
        other.tokens, other._waiting, other.others = list(self.tokens), list(self._waiting), dict(self.others)
        other.partners, other._over = dict(self.partners), dict(self._over)  # (a fork reads tokens not final)
        return other

    def push(self, segments: list) -> list:
        """Segments from the Matcher (in order) → segments decided so far."""
        self._waiting += segments
        self.waiting_for_partners = False
        out = []
        while self._waiting and self._ready():
            after = self._waiting[1] if len(self._waiting) > 1 else None
            out += self._decide(self._waiting.pop(0), after, len(self.tokens))
        return out

    def _ready(self) -> bool:
        from grammar.matcher import UNKNOWN

        first = self._waiting[0]
        if first.action == UNKNOWN and first.stop - max(first.first, self._done) >= SPOT_TOKENS:
            # spotted in only if its motion does not go on into the next segment: wait for that
            return len(self._waiting) >= 2 and len(self.tokens) > first.stop
        if first.action not in self.shapes.names:  # a built-in: its motion's end decides whether a learned one fits it
            if not self._moving(first):
                return True
            motion = self._motion(first, len(self.tokens), False)
            if motion == "pending":
                return False
            if motion is not None and not self._partners_reach(self.tokens[motion[1] - 1].end) \
                    and self._two_handed_over(first, motion):
                self.waiting_for_partners = True  # what the other hands' Matchers read there decides
                return False
            return self._pieces(first, self._waiting[1:], len(self.tokens), False) is not None
        half = self._second_half(self._waiting[1:])  # the next segments decide how far a window may reach
        if half == "pending" or len(self.tokens) < (first if half is None else half).stop + REACH:
            return False
        return self._motion(first, len(self.tokens), False) != "pending"  # where its motion ends is known

    def close(self) -> list:
        out = []
        while self._waiting:
            after = self._waiting[1] if len(self._waiting) > 1 else None
            out += self._decide(self._waiting.pop(0), after, len(self.tokens), closed=True)
        if self._unknown is not None:
            out.append(self._unknown)
            self._unknown = None
        return out

    def _decide(self, seg, after, known: int, closed: bool = False) -> list:
        from grammar.matcher import UNKNOWN

        first = max(seg.first, self._done)
        if first >= seg.stop:
            return []
        continues = (after is not None and after.action in self.shapes.names and seg.stop < len(self.tokens)
                     and self.tokens[seg.stop].name != "T_STILL")  # into a shaped segment, no pause between
        if seg.action == UNKNOWN and seg.stop - first >= SPOT_TOKENS:
            if continues:  # left pending: the next segment may take it back, the rest is searched then
                return self._emit(UNKNOWN, first, seg.stop, False, None)
            found = self._spots(first, seg.stop, known)
        elif seg.action in self.shapes.names:
            ends = [(seg.stop - TRIM, seg.stop + REACH)]
            half = self._second_half(self._waiting)
            if half not in (None, "pending"):  # one gesture the Matcher cut in two
                ends.append((half.stop - TRIM, half.stop + REACH))
            if after is not None and after.action == UNKNOWN:
                ends.append((seg.stop, min(after.stop, seg.stop + UNKNOWN_REACH)))
            lowest = max(self._open_start(first), seg.first - UNKNOWN_REACH)  # into a pending unknown run, if any
            starts = list(range(lowest, min(seg.stop, seg.first + TRIM + 1)))
            motion = self._motion(seg, known, closed)
            motion = None if motion == "pending" else motion
            if motion is not None:  # the whole motion between pauses is a window too, and no window leaves it
                starts = sorted({f for f in starts if f >= motion[0]} | {motion[0]})
                ends = [(lo, min(hi, motion[1])) for lo, hi in ends if lo <= motion[1]] + [(motion[1], motion[1])]
            # the motion (or, with no pause near, the segment itself) is two gestures back to back
            two = self._two(motion if motion is not None else (first, seg.stop), known)
            if two is not None:
                return self._both(two, first, seg.stop, known)
            best = self._best(starts, ends, known, motion=motion)
            if best is not None and best[1] > seg.stop + REACH:  # over the next segment too: or two gestures?
                two = self._two(best[:2], known)
                if two is not None:
                    return self._both(two, first, seg.stop, known)
            found = [best] if best is not None else []
            if best is None and SPOT_TOKENS <= seg.stop - first <= SPOT_MAX:  # none fits around it: searched within
                two = self._two((first, seg.stop), known, whole=False)
                if two is not None:
                    return self._both(two, first, seg.stop, known)
                found = self._spots(first, seg.stop, known)
        else:
            found = self._over_builtin(seg, first, known, closed)
            if not found:
                return self._emit(seg.action, first, seg.stop, seg.exact, seg.distance)
        if not found:
            return self._spot_pending(first, known) + self._emit(UNKNOWN, first, seg.stop, False, None)
        f = found[0][0]
        if f < first:
            self._take_back(f)
        self._emit(UNKNOWN, first, f, False, None)  # what it gives up joins the pending run (emits nothing)
        return self._spot_pending(min(f, first), known) + self._emit_found(found, seg.stop)

    def _second_half(self, rest: list):
        """The learned segment among ``rest`` (the segments after a learned one, in order)
        that may hold the rest of the same gesture — the Matcher, with a learned action's
        large tolerance, may cut one long gesture in two, leaving a few tokens between the
        halves unknown: the next segment, when it has shapes, or the one after an unknown run
        of fewer than :data:`SPOT_TOKENS` tokens and no pause, when that one has. None when
        there is none; "pending" while the Matcher's segments do not reach that far yet."""
        from grammar.matcher import UNKNOWN

        if not rest:
            return "pending"
        nxt = rest[0]
        if nxt.action in self.shapes.names:
            return nxt
        if nxt.action != UNKNOWN or nxt.stop - nxt.first >= SPOT_TOKENS or any(
                self.tokens[i].name == "T_STILL" for i in range(nxt.first, min(nxt.stop, len(self.tokens)))):
            return None
        if len(rest) < 2:
            return "pending"
        return rest[1] if rest[1].action in self.shapes.names else None

    def _moving(self, seg) -> bool:
        """Whether a segment of a built-in action (one without shapes; not unknown) holds
        movement a learned action could be (not a pause, not decided already), on a track
        learned actions are read on."""
        from grammar.matcher import UNKNOWN

        return seg.action != UNKNOWN and bool(self._allowed.any()) and any(
            self.tokens[i].name != "T_STILL" for i in range(max(seg.first, self._done), seg.stop))

    def _over_builtin(self, seg, first: int, known: int, closed: bool):
        """The learned actions read over the motion a segment of an action without shapes lies
        in (``[(first, stop, action, edits)]``; none: it stays): the window of :meth:`_best`
        from within :data:`TRIM` tokens of the motion's start to within as many of its end,
        when it fits — or two learned gestures back to back, when they explain the motion
        better than that one (:meth:`_two`). The Matcher reads a learned gesture's tokens —
        a new performance's, 5 to 10 edits from its examples' — as the few-token expressions
        of built-in actions as readily as its own (a cartwheel as Dodge then Block, a hook as
        Walk Back then Side Walk Right): the tokens cannot tell them apart, and built-in
        actions have no shapes to. A motion between pauses that the Matcher read in pieces — several segments, or
        one with unknown tokens beside it — and that a learned action's shape fits whole,
        within its rejection distance and its examples' durations, is that action, the one
        the user taught. A motion read whole as one built-in action stays that action — a
        learned gesture that hardly moves this hand has a loose rejection distance, and
        would otherwise take built-in actions performed cleanly —, unless a learned action
        whose shape fits the whole motion also reads its tokens with no more edits than the
        built-in one does: then the tokens do not prefer the built-in action, and the shape
        is the user's (an uppercut read as Stop at two edits, which the uppercut's own
        expression reads at two as well), or at one edit more when its shape fits closely
        (:meth:`_close`: a hook read as Crescent Kick at two edits, three for the hook) — or
        the learned action is two-handed, its shape fits both hands, and the other hand's
        Matcher read its movement over that window as no action at all (not even a built-in
        one): the built-in reading leaves that hand unexplained, the two-handed action
        explains both. A motion that no learned action fits whole — no
        pause bounds it (back to back), or it holds more than one gesture — is searched
        around the segment instead (:meth:`_among_pieces`)."""
        if not self._moving(seg):
            return []
        motion = self._motion(seg, known, closed)
        if motion is None:
            return self._among_pieces(seg, first, known)
        if motion == "pending" or motion[1] - motion[0] < SPOT_TOKENS:
            return []
        a, b = motion
        moving = [i for i in range(first, seg.stop) if self.tokens[i].name != "T_STILL"]
        if (moving[0], moving[-1] + 1) == (a, b):  # read whole as this action: it stays, unless …
            whole = self._best([a], [(b, b)], known, motion=motion, across=False) if seg.distance is not None else None
            if whole is None or (whole[3] > seg.distance and not self._close(whole, seg)
                                 and not self._partner_unread(whole)):  # … a learned one reads it as well (or at one
                return []  # edit more, closely), or a two-handed one fits hands the Matchers read as nothing
        else:
            whole = self._best(range(a, min(b, a + TRIM + 1)), [(max(a + 1, b - TRIM), b)], known, motion=motion,
                               across=False)
            if whole is None:
                return self._among_pieces(seg, first, known)
        two = self._two(motion, known)  # or two learned gestures back to back, as a shaped segment's motion may be
        return list(two) if two is not None else [whole]

    def _close(self, window, seg) -> bool:
        """Whether a learned action's ``window`` over a motion read whole as the built-in
        segment ``seg`` reads its tokens with at most one edit more and its shape fits within
        :data:`SURE` of its rejection distance — as closely as the Spotter needs to name a
        gesture with nothing else to go on. The built-in actions' expressions are a few
        tokens long and a new performance is 5 to 10 edits from a learned action's
        examples: one edit is no evidence against the shape the user taught; a loose
        fit (a gesture that hardly moves this hand) is not enough."""
        if window[3] > seg.distance + 1:
            return False
        f, e, k, _ = window
        return bool(self.distances([(f, e)])[0, k] <= SURE * self.shapes.reject[k])

    def _two_handed_over(self, seg, motion) -> bool:
        """Whether what the other hands' Matchers read decides a built-in segment (of
        :meth:`_over_builtin`): it is read whole as its motion, and a two-handed action fits
        that motion whole at more edits."""
        key = (seg.first, seg.stop, max(seg.first, self._done), tuple(motion))
        if key not in self._over:
            self._over[key] = False
            a, b = motion
            moving = [i for i in range(key[2], seg.stop) if self.tokens[i].name != "T_STILL"]
            if moving and (moving[0], moving[-1] + 1) == (a, b) and b - a >= SPOT_TOKENS and seg.distance is not None:
                whole = self._best([a], [(b, b)], len(self.tokens), motion=motion, across=False)
                self._over[key] = bool(whole is not None and whole[3] > seg.distance and self.shapes.partners
                                       and self.shapes.partners[whole[2]])
        return self._over[key]

    def _partners_reach(self, sample: int) -> bool:
        """Whether the other tracks' Matchers are final up to ``sample`` (those two-handed
        actions read here also read; a track whose reading is not given is not waited for)."""
        return all(o not in self.partners or self.partners[o][1] >= sample + self.shift for o in self._paired)

    def _partner_unread(self, window) -> bool:
        """Whether ``(first, stop, action, edits)``'s action is two-handed and one of its
        other tracks moved, over the window's samples, in a way its Matcher read as no action."""
        pairs = self.shapes.partners
        if not pairs or not pairs[window[2]]:
            return False
        a, b = self.tokens[window[0]].start + self.shift, self.tokens[window[1] - 1].end + self.shift
        for o in pairs[window[2]]:
            spans = self.partners.get(o, ((), 0))[0]  # in order
            i = bisect.bisect_right(spans, a, key=lambda span: span[1])  # the first ending after a
            if i < len(spans) and spans[i][0] < b:
                return True
        return False

    def _pieces(self, seg, after: list, known: int, closed: bool):
        """The windows :meth:`_among_pieces` reads around a built-in segment, ``(starts,
        ends)`` as :meth:`_best` takes them, given the segments ``after`` it — or None while
        the Matcher's segments or the tokens do not reach as far as they may (not yet
        ``closed``). A window starts at the segment or up to :data:`UNKNOWN_REACH` tokens
        into the unknown run before it; it ends at the segment's end, within a following
        unknown run or at a following built-in segment's end — cutting none, short of the
        first pause after the segment and of :data:`SPOT_MAX` tokens from its start — or,
        where the next learned segment begins within that, about where that one ends
        (within :data:`TRIM` before to :data:`REACH` after: the Matcher may read a learned
        gesture's start as a built-in piece) or where the rest of it ends, if the Matcher cut
        it in two (:meth:`_second_half`), or within :data:`TRIM` tokens of where it
        begins (its own windows may give those up: the Matcher may read the end of the
        gesture before as the learned one's start)."""
        from grammar.matcher import UNKNOWN

        first = max(seg.first, self._done)
        a = max(self._open_start(first), seg.first - UNKNOWN_REACH)
        b = min(known, a + SPOT_MAX)
        b = next((i for i in range(seg.stop, b) if self.tokens[i].name == "T_STILL"), b)
        ends = [(seg.stop, seg.stop)]
        for i, w in enumerate(after):
            if w.first >= b or (w.action not in self.shapes.names and w.action != UNKNOWN and w.stop > b):
                return range(a, first + 1), ends
            if w.action in self.shapes.names:
                half = self._second_half(after[i + 1:])
                if not closed and (half == "pending" or known < (w if half is None else half).stop + REACH):
                    return None
                ends += [(w.first, min(w.first + TRIM, w.stop)), (w.stop - TRIM, w.stop + REACH)]
                if half not in (None, "pending"):
                    ends.append((half.stop - TRIM, half.stop + REACH))
                return range(a, first + 1), ends
            ends.append((w.first, min(w.stop, b)) if w.action == UNKNOWN else (w.stop, w.stop))
        return (range(a, first + 1), ends) if closed or b <= seg.stop else None

    def _among_pieces(self, seg, first: int, known: int) -> list:
        """Learned actions read over a built-in segment and the pieces beside it (a list of
        one or two ``(first, stop, action, edits)``, or none):
        the best window (:meth:`_best`) of :meth:`_pieces` — one that holds the segment
        whole and cuts no other built-in one — other than the segment alone. Where gestures
        follow each other without a pause no motion bounds one, and the Matcher reads a
        learned gesture's tokens as pieces as readily (built-in segments with unknown tokens
        between, each run too short to search; a hook as Cast Fireball with a few unknown
        tokens after it; an uppercut's start as Walk Back, its rest as the uppercut); a
        window that holds more than the one segment is read as the learned action it fits —
        or as two learned gestures back to back, when two fit its two parts (from as far
        back as a window may start) better than one fits it whole (:meth:`_two`); the
        segment alone stays the built-in action."""
        starts, ends = self._pieces(seg, self._waiting, known, True)
        best = self._best(starts, ends, known, across=False, without=(first, seg.stop))
        if best is None:
            return []
        two = self._two((min(best[0], starts[0]), best[1]), known)  # or two learned gestures back to back
        return list(two) if two is not None else [best]

    def _emit_found(self, found: list, stop: int) -> list:
        """Learned actions found in order ``[(first, stop, action, edits), …]`` emitted, the
        tokens between them and after the last (up to ``stop``) unknown."""
        from grammar.matcher import UNKNOWN

        out, last = [], found[0][0]
        for f, e, k, edits in found:
            out += self._emit(UNKNOWN, last, f, False, None)
            out += self._emit(self.shapes.names[k], f, e, edits == 0.0, edits)
            last = e
        return out + self._emit(UNKNOWN, last, stop, False, None)

    def _spots(self, a: int, b: int, known: int) -> list:
        """Every learned action tokens a..b of an unknown run hold, in order: the one
        :meth:`_spot` finds, then the same search in what it leaves on either side (at least
        :data:`SPOT_TOKENS` tokens) — a run may hold two gestures a pause apart, where a
        performer went on without the pause the Matcher needed (back to back). A run longer
        than :data:`SPOT_MAX` tokens is searched a part at a time, each part ending at its
        last pause within that many tokens (or at that many, without one)."""
        if b - a > SPOT_MAX:  # a long run: a part at a time, each as long as it may be and ending at a pause
            out = []
            while b - a > SPOT_MAX:
                cut = max((i for i in range(a + SPOT_TOKENS, a + SPOT_MAX + 1) if self.tokens[i].name == "T_STILL"),
                          default=a + SPOT_MAX)
                out, a = out + self._spots(a, cut, known), cut
            return out + (self._spots(a, b, known) if b - a >= SPOT_TOKENS else [])
        best = self._spot(a, b, known)
        if best is None:
            return []
        f, e = best[0], best[1]
        before = self._spots(a, f, known) if f - a >= SPOT_TOKENS else []
        return before + [best] + (self._spots(e, b, known) if b - e >= SPOT_TOKENS else [])

    def _spot(self, a: int, b: int, known: int):
        """The learned action that tokens a..b of an unknown run hold, as :meth:`_best` finds it
        within :data:`SPOT` of its rejection distance — a run that is one motion between
        pauses read whole, as a shaped segment's —, or None."""
        moving = [i for i in range(a, b) if self.tokens[i].name != "T_STILL"]
        motion = None
        if moving and all(self.tokens[i].name != "T_STILL" for i in range(moving[0], moving[-1] + 1)):
            motion = (moving[0], moving[-1] + 1)
        return self._best(range(a, b), [(a + 2, b)], known, SPOT, motion=motion, across=False)

    def _spot_pending(self, done: int, known: int) -> list:
        """The pending unknown run before a shaped segment (what that segment did not take
        back, with what it gave up at its start) searched now, when it holds at least
        :data:`SPOT_TOKENS` tokens; its found actions emitted, the rest left pending. ``done``:
        where decided tokens end once the segment is emitted. The run is searched whole,
        however it was made: back to back, a gesture's tokens may end up unknown in pieces —
        what one segment's window gave up, a short unknown segment of the Matcher's, what the
        next window gave up — none of them long enough to be searched alone."""
        pending = self._unknown
        if pending is None or pending.stop - pending.first < SPOT_TOKENS:
            return []
        found = self._spots(pending.first, pending.stop, known)
        if not found:
            return []
        self._take_back(found[0][0])
        out = self._emit_found(found, pending.stop)
        self._done = done
        return out

    def _open_start(self, first: int) -> int:
        """Where the pending unknown run that ends at token ``first`` starts (a window may
        take its tokens back), or ``first`` when none ends there."""
        pending = self._unknown
        return pending.first if pending is not None and pending.stop == first else first

    def _motion(self, seg, known: int, closed: bool):
        """The tokens ``(a, b)`` of the motion a shaped segment lies in: from the last pause
        before it (not reaching back into what is decided, but into a pending unknown run)
        to the first pause at or after its end — or the end of the track once it is closed;
        None when that is more than :data:`SPOT_MAX` tokens (no pause bounds it: back to
        back), "pending" while it is not known yet."""
        names = self.tokens
        first = max(seg.first, self._done)
        a = self._open_start(first)
        for i in range(min(seg.first, known) - 1, a - 1, -1):
            if names[i].name == "T_STILL":
                a = i + 1
                break
        for i in range(seg.stop, min(known, a + SPOT_MAX + 1)):
            if names[i].name == "T_STILL":
                return (a, i) if i - a <= SPOT_MAX else None
        if known > a + SPOT_MAX:
            return None
        return (a, known) if closed and known > seg.first else "pending"

    def _both(self, two, first: int, stop: int, known: int) -> list:
        """Two gestures found back to back (:meth:`_two`) emitted for a segment ``first..stop``."""
        from grammar.matcher import UNKNOWN

        (f, c, k1, e1), (_, e, k2, e2) = two
        if f < first:
            self._take_back(f)
        self._emit(UNKNOWN, first, f, False, None)  # joins the pending run (emits nothing)
        return (self._spot_pending(min(f, first), known)
                + self._emit(self.shapes.names[k1], f, c, e1 == 0.0, e1)
                + self._emit(self.shapes.names[k2], c, e, e2 == 0.0, e2) + self._emit(UNKNOWN, e, stop, False, None))

    def _take_back(self, f: int) -> None:
        """Tokens from ``f`` on taken back from the pending unknown run."""
        pending = self._unknown
        self._unknown = None if f <= pending.first else replace(pending, stop=f, end=self.tokens[f - 1].end)
        self._done = f

    def _two(self, motion, known: int, whole: bool = True):
        """A motion between pauses read as two learned gestures back to back — ``(first, cut,
        action, edits)`` and ``(cut, stop, action, edits)`` — when that explains it better than
        one action: the two windows' scores (``edits + WEIGHT × shape distance``, each the
        action it is nearest and within that action's rejection distance) sum to less than the
        best one window's (each gesture scores what it costs, so one window is read unless it
        fits worse than the two parts together). The windows may leave up to :data:`TRIM`
        tokens out at either end of the motion; each part holds at least :data:`SPOT_TOKENS`
        tokens. Unless ``whole``, two are read even where no one window fits. None otherwise."""
        from doodle.core.tokens import CODES

        a, b = motion
        if b - a < 2 * SPOT_TOKENS:
            return None
        auto = self.shapes.automaton
        heads, cuts = range(a, a + TRIM + 1), range(a + SPOT_TOKENS, b - SPOT_TOKENS + 1)
        windows, edits = [], []
        for f in sorted(set(heads) | set(cuts)):
            d = auto.initial.copy()
            for e in range(f + 1, b + 1):
                d = auto.step(d, CODES[self.tokens[e - 1].name])
                if (e >= b - TRIM or (f in heads and e in cuts)) and e - f >= SPOT_TOKENS \
                        and self.readable(f, e):
                    windows.append((f, e))
                    edits.append(auto.accept_costs(d))
        if not windows:
            return None
        edits = np.array(edits)
        _, alone = self.nearest(windows, edits)
        score = alone.min(axis=1)
        one = min((score[i] for i, (f, e) in enumerate(windows) if f in heads and e >= b - TRIM), default=np.inf)
        firsts = [i for i, (f, e) in enumerate(windows) if f in heads and e in cuts]
        lasts = {}
        for i, (f, e) in enumerate(windows):
            if f in cuts and e >= b - TRIM and (f not in lasts or score[i] < score[lasts[f]]):
                lasts[f] = i
        pairs = [(score[i] + score[lasts[windows[i][1]]], i, lasts[windows[i][1]]) for i in firsts if windows[i][1] in lasts]
        if not pairs:
            return None
        two, i, j = min(pairs)
        if not np.isfinite(two) or (whole and not np.isfinite(one)) or two >= one:
            return None
        k1, k2 = int(np.argmin(alone[i])), int(np.argmin(alone[j]))
        return (*windows[i], k1, float(edits[i, k1])), (*windows[j], k2, float(edits[j, k2]))

    def fits(self, edits: np.ndarray, ds: np.ndarray, windows: list, strict: float = 1.0) -> np.ndarray:
        """(windows, actions): each window is the action it is nearest (``edits + WEIGHT ×
        shape distance``, among those allowed on this track and whose examples last about
        as long as it: :meth:`lasts`), if its shape distance is within ``strict`` × that
        action's rejection distance."""
        own = np.where(self._allowed & np.isfinite(ds) & self.lasts(windows), edits + WEIGHT * ds, np.inf)
        return (np.isfinite(own) & (own == own.min(axis=1, keepdims=True))
                & (ds <= strict * self.shapes.reject[None, :]))

    def readable(self, f: int, e: int) -> bool:
        """Whether tokens f..e hold samples enough for a shape (three tracked ones)."""
        return int(self.valid[self.tokens[f].start:self.tokens[e - 1].end].sum()) >= 3

    def nearest(self, windows: list, edits: np.ndarray, strict: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
        """``(shape distances, scores)``, both (windows, actions): each window's score
        ``edits + WEIGHT × shape distance`` for the action it is (:meth:`fits`, within
        ``strict`` × its rejection distance), inf for the others."""
        ds = self.distances(windows)
        return ds, np.where(self.fits(edits, ds, windows, strict), edits + WEIGHT * ds, np.inf)

    def lasts(self, windows: list) -> np.ndarray:
        """(windows, actions): whether each window lasts no more than :data:`TEMPO` × the
        action's longest example and no less than its shortest / :data:`TEMPO` (True where
        the examples' durations or the samples' times are not known). Shapes are resampled
        by arc length and compare when along the path each step comes (:data:`grammar.shapes.PACE`),
        not how long the whole lasts: without this a gesture and a small one after it with no
        pause between (a combo, then a hook that barely moves this hand) would more often read
        as the first alone, and a part of a gesture as a whole gesture of another action. Performers do
        vary in tempo: the factor is wide (by leave-one-user-out, ``make bench``), and
        learning keeps each example's motion without its still ends
        (:attr:`grammar.learn.Learned.seconds`), as a window holds no pause at its ends."""
        longest = self.shapes.longest
        if self.t is None or longest is None or not windows:
            return np.ones((len(windows), len(self.shapes.names)), dtype=bool)
        t = self.t
        spans = np.array([t[min(self.tokens[e - 1].end, len(t)) - 1] - t[self.tokens[f].start] for f, e in windows])
        return (spans[:, None] <= TEMPO * longest[None, :]) & (spans[:, None] * TEMPO >= self.shapes.shortest[None, :])

    def _arc(self, a: int, b: int) -> np.ndarray:
        """Cumulative path length of the track's valid samples over tokens a..b, at each
        token boundary: (b − a + 1,)."""
        s0, s1 = self.tokens[a].start, self.tokens[b - 1].end
        p, v = np.asarray(self.p[s0:s1], dtype=float), np.asarray(self.valid[s0:s1], dtype=bool)
        step = np.linalg.norm(np.diff(p, axis=0), axis=1) * (v[1:] & v[:-1])
        cum = np.concatenate([[0.0], np.cumsum(step)])
        bounds = [self.tokens[k].start - s0 for k in range(a, b)] + [s1 - 1 - s0]
        return cum[np.clip(bounds, 0, len(cum) - 1)]

    def _best(self, starts, ends: list, known: int, strict: float = 1.0, motion=None, across: bool = True,
              without=None):
        """The best (first, stop, action, edits) over windows starting in ``starts`` and
        ending in one of the ``ends`` intervals, or None when its shape distance is over
        ``strict`` × the action's rejection distance. With ``motion`` (tokens a..b between
        pauses) a window pays for the motion it leaves out: its shape distance counts over
        the part of the motion's path length it covers, the rest at the action's rejection
        distance (what a step nothing explains is worth) — a part of a gesture does not win
        over the whole by matching another gesture's part closely. Unless ``across``, no
        window holds a pause (what is searched in an unknown run is one motion). A whole
        motion that fits an action is that action, whatever its parts fit: a part of a
        gesture (one hook of a combo) may fit another action more closely than the whole
        fits its own, where a new performer's whole gesture differs more from the examples
        than its pieces do."""
        from doodle.core.tokens import CODES

        names = [k.name for k in self.tokens]
        auto = self.shapes.automaton
        last = min(known, max(hi for _, hi in ends))
        windows, edits = [], []
        for f in starts:
            if names[f] == "T_STILL":
                continue
            d = auto.initial.copy()
            for e in range(f + 1, last + 1):
                d = auto.step(d, CODES[names[e - 1]])
                if not across and names[e - 1] == "T_STILL":
                    break
                if not any(lo <= e <= hi for lo, hi in ends) or names[e - 1] == "T_STILL" or (f, e) == without:
                    continue
                if self.readable(f, e):
                    windows.append((f, e))
                    edits.append(auto.accept_costs(d))
        if not windows:
            return None
        ds = self.distances(windows)  # (windows, actions)
        edits = np.array(edits)
        cost = ds
        if motion is not None:
            a, b = motion
            cum = self._arc(a, b)
            if cum[-1] > 0:
                inside = np.array([(cum[min(max(e, a), b) - a] - cum[min(max(f, a), b) - a]) / cum[-1]
                                   for f, e in windows])[:, None]
                cost = inside * ds + (1.0 - inside) * self.shapes.reject[None, :]
        score = np.where(self.fits(edits, ds, windows, strict), edits + WEIGHT * cost, np.inf)
        if motion is not None and tuple(motion) in windows:  # a whole motion that fits is one gesture
            m = windows.index(tuple(motion))
            if np.isfinite(score[m]).any():
                score = np.where(np.arange(len(windows))[:, None] == m, score, np.inf)
        w, k = np.unravel_index(int(np.argmin(score)), score.shape)
        if not np.isfinite(score[w, k]):
            return None
        return windows[w][0], windows[w][1], int(k), float(edits[w, k])

    def distances(self, windows: list) -> np.ndarray:
        """(windows, actions): the shape distances of :meth:`ShapeSet.distances_of`, each
        window's worked out once. A window's distances depend only on its samples, which
        never change once recorded: they are kept by the samples it spans (shared with the
        Refiner's forks, the live provisional readings) — unless a track it reads has not
        reached its end yet."""
        spans = [(self.tokens[f].start, self.tokens[e - 1].end) for f, e in windows]
        new = [i for i, span in enumerate(spans) if span not in self._seen]
        rows = dict(zip(new, self.shapes.distances_of([windows[i] for i in new], self._read))) if new else {}
        out = np.array([rows[i] if i in rows else self._seen[span] for i, span in enumerate(spans)])
        if rows:  # kept — then the oldest forgotten, beyond SEEN (insertion order)
            reach = min((len(self.p) if name is None or name == self.track else
                         len(self.others[name][0]) if self.others.get(name) is not None
                         and self.others[name][0] is not None else 0)
                        for g in self.shapes.groups for name in g.tracks)
            self._seen.update((spans[i], row) for i, row in rows.items() if spans[i][1] <= reach)
            if len(self._seen) > SEEN:
                for span in list(self._seen)[:len(self._seen) - SEEN // 2]:
                    del self._seen[span]
        return out

    def beginnings(self, window: tuple, part: tuple) -> np.ndarray:
        """(actions,): the shape distance of a window to the best fitting beginning, ``part``
        of the way (:func:`grammar.shapes.dtw_costs`), of each action's examples, over that
        action's rejection distance (not kept: only the Spotter asks, of few windows)."""
        return self.shapes.distances_of([window], self._read, part)[0] / self.shapes.reject

    def _read(self, group: Group, window) -> tuple | None:
        """A window's samples of the group's tracks, resampled together (None: a track is missing)."""
        a, b = self.tokens[window[0]].start, self.tokens[window[1] - 1].end
        own = (self.p, self.q, self.valid)
        tracks = [own if name is None or name == self.track else self.others.get(name) for name in group.tracks]
        if any(t is None or t[0] is None or len(t[0]) < b for t in tracks):
            return None
        keep = np.ones(b - a, dtype=bool)
        for _, _, v in tracks:
            keep &= np.asarray(v[a:b], dtype=bool)
        if keep.sum() < 3:
            return None
        poses = [(p[a:b][keep], (q[a:b][keep] if q is not None else np.tile([0.0, 0.0, 0.0, 1.0], (int(keep.sum()), 1))))
                 for p, q, _ in tracks]
        if not group.pace:
            return (*sample(poses), None)
        clock = np.arange(a, b, dtype=float) if self.t is None or len(self.t) < b else np.asarray(self.t[a:b], dtype=float)
        return (*sample(poses), times(poses, clock[keep]))

    def _emit(self, action: str, f: int, e: int, exact: bool, distance) -> list:
        from grammar.matcher import UNKNOWN, Segment

        if e <= f:
            return []
        self._done = e
        t0, t1 = self.tokens[f], self.tokens[e - 1]
        if action == UNKNOWN:  # neighbouring unknowns are one
            prev = self._unknown
            self._unknown = Segment(UNKNOWN, f if prev is None else prev.first, e,
                                    t0.start if prev is None else prev.start, t1.end, False, None)
            return []
        out = [self._unknown] if self._unknown is not None else []
        self._unknown = None
        return out + [Segment(action, f, e, t0.start, t1.end, exact, distance)]
