"""The Contexter: interactions between characters recognised across tracks (thesis §6.2.1).

An interaction ``{A_n, C_m}`` (a ``[[interactions]]`` entry of a library) is ``n`` actions,
one per character (role 0, 1, …), and ``m`` constraints between roles
(:mod:`grammar.constraints`, §6.3). It works on the per-track Matchers'
segments (batch; :func:`grammar.recognizer.recognize_interactions` runs the whole pipeline):

* **Candidates.** For every interaction and every assignment of its roles to distinct tracks
  (``k!·C(n, k)`` configurations, :func:`itertools.permutations`), every tuple of segments —
  on each assigned track, one segment of that role's action — whose time spans overlap (one
  common open interval ``[max start, min end]``).
* **Constraints** are evaluated on that overlap, sample by sample (the first assigned
  track's sample times; the others' nearest samples; samples where a track lost tracking
  are skipped). With ``mode="any"`` (default) the interaction holds when at some sample of
  the overlap *every* constraint holds at once — a kiss needs the two figurines within the
  Intimate distance at one moment, not throughout the back-and-forth gesture; with
  ``mode="all"`` they must hold at every valid sample. Each character's state there is its
  position, its ground-plane front (:func:`grammar.constraints.ground_front`) and its radius
  (``radius``: one number for all, or per track; default 0.1 m, a figurine in prop scale).
* **Priority.** Candidates are taken earliest overlap first, then the longest (most tokens,
  "keep the longest sequence", §6.2.1), then library order and assignment order; a segment
  belongs to at most one interaction. A taken segment is replaced by an
  :class:`InteractionSegment` — the same span and action (the role's, e.g. "Slap" on the
  slapper, "Slapped" on the other) with the interaction's name and the role — so
  interactions win over the independent actions they cover; other segments stay as they are.

Roles that are ``interaction_only`` actions are matched on each track's tokens by a Matcher
of their own (:func:`with_interactions`) and, when the interaction holds, replace the
independent segments they cover.

Streaming: :class:`LiveContexter` pools each track's final segments as they come and reports
an interaction once every track has decided past its end (what ``doodle replay`` shows). It
asks its Contexter again at every new segment; whether a candidate's constraints hold over
its overlap is worked out once (the overlap's samples are in the past) and all its samples
at once, with the characters' fronts worked out once per sample, so each new segment only
costs its new candidates.

Behaviour states (§6.3.3): :func:`apply_behaviour` walks each character's segments in time
order from the library's initial state; a segment whose action's pre-conditions do not hold
becomes :class:`Refused` (unknown, with the action and the reason), and an interaction one
of whose roles is refused is dropped on every track.
"""

from __future__ import annotations

from dataclasses import dataclass
from itertools import permutations, product

import numpy as np

from grammar.constraints import RADIUS, Behaviour, Constraint, ground_front, parse_constraints
from grammar.matcher import Segment

MODES = ("any", "all")


@dataclass(frozen=True)
class InteractionSegment(Segment):
    """A segment recognised as one role of an interaction."""

    interaction: str = ""
    role: int = 0


@dataclass(frozen=True)
class Rule:
    """An interaction ready to match: its actions by role and its parsed constraints."""

    name: str
    actions: tuple[str, ...]
    constraints: tuple[Constraint, ...]


@dataclass(frozen=True)
class Found:
    """One recognised interaction: per role, the track and the segment's index there."""

    interaction: str
    tracks: tuple[str, ...]
    indices: tuple[int, ...]
    t0: float  # the overlap, seconds
    t1: float


class Contexter:
    """Interactions of a library over per-track segments (batch form, see the module)."""

    def __init__(self, interactions, radius: float | dict = RADIUS, mode: str = "any"):
        if mode not in MODES:
            raise ValueError(f"mode must be one of {MODES}, not {mode!r}")
        self.rules = [Rule(i.name, tuple(i.actions), parse_constraints(i.constraints, i.name, len(i.actions)))
                      for i in interactions]
        self.radius, self.mode = radius, mode
        self._doodle = None  # the doodle read so far, and of it:
        self._held: dict = {}  # (rule, tracks, overlap) -> whether the constraints hold there
        self._known: dict = {}  # track -> its samples' usability and fronts so far

    def _radius(self, track: str) -> float:
        return float(self.radius.get(track, RADIUS)) if isinstance(self.radius, dict) else float(self.radius)

    def candidates(self, doodle, segments: dict[str, list[Segment]]) -> list[Found]:
        """Every (interaction, assignment, segment tuple) whose segments overlap and whose
        constraints hold, in priority order. Whether the constraints hold over an overlap is
        worked out once per Contexter (the live one asks again as segments come: the
        samples of an overlap, all in the past, do not change)."""
        if doodle is not self._doodle:  # what is remembered is of one doodle
            self._doodle, self._held, self._known = doodle, {}, {}
        tracks = {tr.name: tr for tr in doodle.tracks}
        names = [n for n in segments if n in tracks]
        spans = {n: [(_time(tracks[n], s.start), _time(tracks[n], s.end)) for s in segments[n]] for n in names}
        found = []
        for order, rule in enumerate(self.rules):
            k = len(rule.actions)
            for assigned in permutations(names, k):
                choices = [[x for x, s in enumerate(segments[tr]) if s.action == act]
                           for tr, act in zip(assigned, rule.actions)]
                for picked in product(*choices):
                    t0 = max(spans[tr][x][0] for tr, x in zip(assigned, picked))
                    t1 = min(spans[tr][x][1] for tr, x in zip(assigned, picked))
                    if not t0 < t1:
                        continue
                    key = (order, assigned, t0, t1)  # what the constraints read: the samples of the overlap
                    if key not in self._held:
                        self._held[key] = self._constraints_hold(rule, [tracks[tr] for tr in assigned], t0, t1)
                    if self._held[key]:
                        length = sum(segments[tr][x].stop - segments[tr][x].first for tr, x in zip(assigned, picked))
                        found.append(((t0, -length, order), Found(rule.name, assigned, tuple(picked), t0, t1)))
        found.sort(key=lambda item: item[0])  # stable: assignment order breaks the last ties
        return [f for _, f in found]

    def _constraints_hold(self, rule: Rule, tracks: list, t0: float, t1: float) -> bool:
        if not rule.constraints:
            return True
        ref = tracks[0].t
        a, b = int(np.searchsorted(ref, t0, side="left")), int(np.searchsorted(ref, t1, side="right"))
        times = ref[a:b] if b > a else np.array([(t0 + t1) / 2])
        poses = []
        ok = np.ones(len(times), dtype=bool)
        for tr in tracks:
            shared = b > a and len(tr.t) == len(ref) and _start(tr.t) == _start(ref)  # sampled together
            idx = slice(a, b) if shared else _nearest(tr.t, times)
            usable, fronts = self._poses(tr, b - 1 if shared else int(idx.max()))
            ok &= usable[idx]
            poses.append((tr.p[idx], fronts[idx], self._radius(tr.name)))
        holds = ok.copy()  # every constraint at once, at every valid sample
        for c in rule.constraints:
            (p_i, f_i, r_i), (p_j, f_j, r_j) = poses[c.i], poses[c.j]
            holds &= c.holds_all(p_i, f_i, r_i, p_j, f_j, r_j)
        if self.mode == "any":
            return bool(holds.any())
        return bool(ok.any()) and bool((holds == ok).all())

    def _poses(self, track, last: int) -> tuple[np.ndarray, np.ndarray]:
        """Per sample of the track up to ``last`` at least: whether it can be read (tracked,
        finite) and its ground-plane front (:func:`ground_front`), worked out once per
        sample (a sample's pose does not change)."""
        usable, fronts = self._known.get(track.name, (np.empty(0, dtype=bool), np.empty((0, 3))))
        if len(usable) <= last:
            k = len(usable)
            p, q = track.p[k:], track.q[k:]
            usable = np.concatenate([usable, track.valid[k:] & np.isfinite(p).all(axis=1) & np.isfinite(q).all(axis=1)])
            fronts = np.concatenate([fronts, ground_front(np.where(np.isfinite(q), q, [0.0, 0.0, 0.0, 1.0]))])
            self._known[track.name] = (usable, fronts)
        return usable, fronts

    def resolve(self, doodle, segments: dict[str, list[Segment]]) -> dict[str, list[Segment]]:
        """Per track, its segments with those of recognised interactions relabelled."""
        return relabel(segments, self.select(doodle, segments))

    def select(self, doodle, segments: dict[str, list[Segment]]) -> list[Found]:
        """The recognised interactions: candidates taken greedily, a segment used once."""
        used, taken = set(), []
        for f in self.candidates(doodle, segments):
            keys = set(zip(f.tracks, f.indices))
            if keys & used:
                continue
            used |= keys
            taken.append(f)
        return taken


def relabel(segments: dict[str, list[Segment]], found: list[Found]) -> dict[str, list[Segment]]:
    out = {tr: list(segs) for tr, segs in segments.items()}
    for f in found:
        for role, (tr, x) in enumerate(zip(f.tracks, f.indices)):
            s = out[tr][x]
            out[tr][x] = InteractionSegment(s.action, s.first, s.stop, s.start, s.end, s.exact, s.distance,
                                            interaction=f.interaction, role=role)
    return out


def with_interactions(doodle, compiled, recognised: dict, threshold: float = 2.0, radius: float | dict = RADIUS,
                      mode: str = "any") -> dict[str, list[Segment]]:
    """Per track, the segments of already recognised ``(tokens, segments)`` with the
    library's interactions recognised across tracks (:class:`InteractionSegment` where they are).

    Roles that are ordinary actions are looked for among each track's segments; roles that
    are ``interaction_only`` actions (the thesis's Slap ``(T_N_Z)+ T_Z``, Slapped
    ``T_STILL+``…) are matched on the track's tokens by a Matcher of their own, and where
    such an interaction is recognised its segment replaces the independent segments it
    covers (interactions take priority, §6.2.1) — but not a learned action's (:func:`overrides`)."""
    from grammar.matcher import match

    segments = {tr: segs for tr, (_, segs) in recognised.items()}
    pools = {tr: list(segs) for tr, segs in segments.items()}
    if compiled.roles is not None:
        auto = compiled.roles.automaton(threshold)
        learned = learned_names(compiled)
        for tr, (tokens, segs) in recognised.items():
            mine = [o for o in segs if o.action in learned]
            pools[tr] += [s for s in match(tokens, auto, tr) if s.action != "unknown" and not overrides(s, mine)]
    found = Contexter(compiled.library.interactions, radius, mode).select(doodle, pools)
    return splice(segments, pools, found)


def learned_names(compiled) -> frozenset:
    """The names of the learned actions (those with shapes) of a compiled library."""
    return frozenset(compiled.shapes.names) if compiled.shapes is not None else frozenset()


def overrides(s: Segment, learned: list) -> bool:
    """Whether an interaction role's own segment ``s`` would replace one of the ``learned``
    actions' segments (cover at least half of its tokens, as :func:`splice` replaces). It
    may not: a role matched on the tokens alone (Slap's ``(T_N_Z)+ T_Z`` is the start of many
    a hook) does not outweigh the gesture the user taught, whose shape decided it."""
    return any(2 * (min(o.stop, s.stop) - max(o.first, s.first)) >= (o.stop - o.first) for o in learned)


def splice(segments: dict[str, list[Segment]], pools: dict[str, list[Segment]], found: list[Found]):
    """``segments`` with the found interactions' segments (indices into ``pools``) in
    place: an independent segment relabelled, or a role segment of its own replacing the
    independent segments it covers for at least half of their tokens."""
    out = {tr: list(segs) for tr, segs in segments.items()}
    for f in found:
        for role, (tr, x) in enumerate(zip(f.tracks, f.indices)):
            s = pools[tr][x]
            new = InteractionSegment(s.action, s.first, s.stop, s.start, s.end, s.exact, s.distance,
                                     interaction=f.interaction, role=role)
            if x < len(segments[tr]):
                out[tr] = [new if o is s else o for o in out[tr]]
                continue
            kept = [o for o in out[tr]
                    if 2 * (min(o.stop, s.stop) - max(o.first, s.first)) < (o.stop - o.first)]
            out[tr] = sorted(kept + [new], key=lambda o: (o.first, o.stop))
    return out


def _time(track, index: int) -> float:
    return float(track.t[min(max(index, 0), len(track.t) - 1)])


def _start(t: np.ndarray) -> int:
    """Where an array's data starts (two views of one array of times start together)."""
    return t.__array_interface__["data"][0]


def _nearest(t: np.ndarray, times: np.ndarray) -> np.ndarray:
    if len(t) < 2:
        return np.zeros(len(times), dtype=np.int64)
    i = np.clip(np.searchsorted(t, times), 1, len(t) - 1)
    return np.where(np.abs(t[i - 1] - times) <= np.abs(t[i] - times), i - 1, i)


class LiveContexter:
    """The Contexter on streams (replay): tracks are read in parallel; each track's final
    segments (and, for ``interaction_only`` roles, the segments of a role Matcher fed the
    same tokens) are pooled as they come, and an interaction is reported once every track
    has decided past its end — so no segment still to come could take its place and what
    is reported equals the batch :func:`with_interactions` on the same segments.
    """

    def __init__(self, doodle, compiled, threshold: float = 2.0, radius: float | dict = RADIUS, mode: str = "any"):
        from grammar.matcher import Matcher

        self.doodle = doodle
        self.contexter = Contexter(compiled.library.interactions, radius, mode)
        names = [tr.name for tr in doodle.tracks]
        self.pools = {n: [] for n in names}
        self.frontier = {n: -np.inf for n in names}
        auto = compiled.roles.automaton(threshold) if compiled.roles is not None else None
        self.role_matchers = {n: Matcher(auto, n) for n in names} if auto is not None else {}
        self.role_frontier = {n: -np.inf for n in names} if auto is not None else {}
        self._learned_names = learned_names(compiled)
        self._learned = {n: [] for n in names}  # learned actions' segments: no role segment may replace them
        self._reported = set()
        self._roles = {a for rule in self.contexter.rules for a in rule.actions}  # what may join one
        self._selected: list = []  # the Contexter's selection, (Found, segments), as of the last new segment
        self._stale = False  # a segment has joined the pools since

    def push_token(self, track: str, token) -> list:
        """One token of a track (for the role Matchers); returns newly recognised interactions."""
        if not self.role_matchers:
            return []
        return self._add(track, self.role_matchers[track].push(token), self.role_frontier)

    def push_segments(self, track: str, segments: list) -> list:
        """A track's newly final segments; returns newly recognised interactions."""
        return self._add(track, segments, self.frontier)

    def close(self) -> list:
        """End of every stream: the interactions not reported yet."""
        for n, m in self.role_matchers.items():
            self._add(n, m.close(), self.role_frontier, check=False)
        return self._check(final=True)

    def _add(self, track: str, segments: list, frontier: dict, check: bool = True) -> list:
        if not segments:
            return []
        tr = self.doodle.track(track)
        for s in segments:
            frontier[track] = max(frontier[track], _time(tr, s.end - 1))
            if s.action in self._roles:  # only a role's action may join an interaction
                self.pools[track].append(s)
                self._stale = True
            elif s.action in self._learned_names and frontier is self.frontier:
                self._learned[track].append(s)
                self._stale = True
        return self._check() if check and self.contexter.rules else []

    def _check(self, final: bool = False) -> list:
        """Newly recognised interactions: ``(Found, [segment per role])``. The selection is
        made again only when a segment has joined the pools: a segment forgotten since (all
        tracks decided past it) took part in no candidate still to report, and candidates
        that shared none of its segments are taken or not as before."""
        decided = min(min(self.frontier.values()), min(self.role_frontier.values(), default=np.inf))
        if self._stale:
            pools = {n: [s for s in pool if not overrides(s, self._learned[n])]  # (the track's own segments tile
                     for n, pool in self.pools.items()}                           # it: only role segments can)
            self._selected = [(f, [pools[tr][x] for tr, x in zip(f.tracks, f.indices)])
                              for f in self.contexter.select(self.doodle, pools)]
            self._stale = False
        out = []
        for f, segs in self._selected:
            key = (f.interaction, tuple((tr, s.first, s.action) for tr, s in zip(f.tracks, segs)))
            if key not in self._reported and (final or decided >= f.t1):
                self._reported.add(key)
                out.append((f, segs))
        if not final:  # a segment every track has decided past can join nothing new: forget it
            for name, pool in self.pools.items():
                track = self.doodle.track(name)
                self.pools[name] = [s for s in pool if _time(track, s.end - 1) >= decided]
                self._learned[name] = [s for s in self._learned[name] if _time(track, s.end - 1) >= decided]
        return out


@dataclass(frozen=True)
class Refused(Segment):
    """A segment whose action's pre-conditions (§6.3.3) did not hold: unknown, with the
    action it was recognised as and why it was refused."""

    refused: str = ""
    reason: str = ""


def behaviours(compiled) -> dict:
    """Action name → :class:`Behaviour` for the actions (and interaction roles) that have one."""
    actions = list(compiled.library.actions) + (list(compiled.roles.library.actions) if compiled.roles else [])
    return {a.name: b for a in actions if (b := Behaviour.of(a)) is not None}


def apply_behaviour(doodle, segments: dict[str, list[Segment]], rules: dict, initial=frozenset(),
                    independent=frozenset()) -> dict[str, list[Segment]]:
    """Each character's segments with behaviour states applied (§6.3.3): from ``initial``,
    in time order, an action allowed by its pre-conditions updates the state by its
    post-conditions, one that is not becomes :class:`Refused`. An interaction a role of
    which is refused is dropped on every track: its other roles become plain segments of
    their action (unknown when the role is not an ``independent`` action) and are checked
    again as such."""
    if not rules:
        return segments
    out, dropped = _walk(segments, rules, initial), []
    for tr, segs in out.items():
        for s, before in zip(segs, segments[tr]):
            if isinstance(s, Refused) and isinstance(before, InteractionSegment):
                track = doodle.track(tr)
                dropped.append((before.interaction, _time(track, before.start), _time(track, before.end)))
    if not dropped:
        return out
    stripped = {}
    for tr, segs in segments.items():
        track = doodle.track(tr)
        stripped[tr] = [(refused if isinstance(refused, Refused) else _plain(s, independent))
                        if isinstance(s, InteractionSegment) and any(
                            s.interaction == name and _time(track, s.start) < t1 and _time(track, s.end) > t0
                            for name, t0, t1 in dropped) else s for s, refused in zip(segs, out[tr])]
    return _walk(stripped, rules, initial)


def _walk(segments, rules, initial):
    out = {}
    for tr, segs in segments.items():
        state, kept = frozenset(initial), []
        for s in segs:
            rule = rules.get(s.action)
            if rule is None:
                kept.append(s)
            elif rule.allowed(state):
                kept.append(s)
                state = rule.after(state)
            else:
                kept.append(Refused("unknown", s.first, s.stop, s.start, s.end, False, None,
                                    refused=s.action, reason=rule.why(state)))
        out[tr] = kept
    return out


def _plain(s: Segment, independent) -> Segment:
    return Segment(s.action if s.action in independent else "unknown", s.first, s.stop, s.start, s.end,
                   s.exact, s.distance if s.action in independent else None)
