"""Compile a library's actions to automata, check overlaps, and build the Matcher's tables."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from doodle.core.errors import DoodleError
from doodle.core.tokens import CODES
from grammar.automata import DFA, check_language, compile_expression, intersection_witness, sample, shortest
from grammar.constraints import parse_constraints
from grammar.matcher import Automaton
from grammar.shapes import ShapeSet, load_shape, shape_set
from library.manifest import ActionDef, Library


@dataclass(frozen=True, eq=False)
class Compiled:
    """A library's recognisable actions with their minimal DFAs (and the Matcher's tables, built once)."""

    library: Library
    dfas: tuple[DFA, ...]
    roles: "Compiled | None" = None  # interaction-only actions, matched by the Contexter
    shapes: ShapeSet | None = None  # the learned actions' example shapes (grammar.shapes)
    _tables: dict = field(default_factory=dict, repr=False)  # the Matcher's tables, built once per kind
    store: object = field(default=None, repr=False, compare=False)  # where built tables are kept between
    # runs, or None: ``get(compiled, key, build)`` returns the automaton of ``key`` (made by
    # ``build()`` if it has none; see automaton_from) — the app's disk cache, doodle.app.libcache

    def automaton(self, threshold: float = 2.0, direction_costs: bool = False, track: str | None = None,
                  present=None) -> Automaton | None:
        """The Matcher's tables; with ``track``, without the actions bound to other tracks
        (and, given the tracks ``present``, without two-handed actions missing one); None
        when a track has no action of its own (it only partners two-handed actions)."""
        key = (threshold, direction_costs, track, None if present is None else tuple(sorted(present)))
        if key not in self._tables:
            build = lambda: self._automaton(threshold, direction_costs, track, present)  # noqa: E731
            self._tables[key] = build() if self.store is None else self.store.get(self, key, build)
        return self._tables[key]

    def automaton_from(self, key: tuple, tables: dict) -> Automaton | None:
        """The automaton of ``key`` (as :meth:`automaton` makes it: threshold, direction
        costs, track, present tracks) with its step tables taken from ``tables``
        (:meth:`grammar.matcher.Automaton.tables`): what a cache reads back."""
        threshold, direction_costs, track, present = key
        return self._automaton(threshold, direction_costs, track, present, tables)

    def _automaton(self, threshold, direction_costs, track, present, tables=None) -> Automaton | None:
        keep = [k for k, a in enumerate(self.library.actions) if (track is None or a.track in (None, track))
                and (present is None or all(t in present for t in a.tracks))]
        if not keep:
            if track is not None and any(track in a.tracks for a in self.library.actions):
                return None
            raise DoodleError(f"{self.library.source}: no action may be recognised on track {track!r}")
        actions = [self.library.actions[k] for k in keep]
        return Automaton([a.name for a in actions], [self.dfas[k] for k in keep], threshold, direction_costs,
                         [a.cyclic for a in actions],
                         limits=[a.tolerance if a.tolerance is not None else threshold for a in actions],
                         tables=tables)

    @property
    def bound(self) -> bool:
        """Whether some action is bound to a track."""
        return any(a.track is not None for a in self.library.actions)

    def dfa(self, name: str) -> DFA:
        return self.dfas[self.library.names.index(name)]

    def action(self, name: str) -> ActionDef:
        return self.library.action(name)


def compile_action(action: ActionDef, known: dict | None = None) -> DFA:
    """The minimal DFA of one action; DoodleError naming the manifest, action and column.
    ``known``: DFAs already compiled, by expression text (read back from a cache)."""
    if known and action.expression in known:
        return known[action.expression]
    from grammar.expr import parse  # here: a compile whose DFAs are cached parses no expression

    try:
        dfa = compile_expression(parse(action.expression, action.name))
        check_language(dfa, action.name)
    except DoodleError as e:
        raise DoodleError(f"{action.source}: {e}" if action.source else str(e)) from None
    return dfa


def compile_library(library: Library, known: dict | None = None) -> Compiled:
    """Automata of the library's recognisable actions (those with an expression); an
    interaction naming an unknown action is an error. ``known``: DFAs already compiled, by
    expression text (:func:`compile_action`)."""
    names = set(library.names)
    for inter in library.interactions:
        for a in inter.actions:
            if a not in names:
                raise DoodleError(f"{library.source}: interaction {inter.name!r}: no action {a!r} in the library")
        try:
            parse_constraints(inter.constraints, inter.name, len(inter.actions))
        except DoodleError as e:
            raise DoodleError(f"{library.source}: {e}") from None
    _check_invertible(library)
    recognisable = Library(library.name, tuple(a for a in library.actions if a.expression.strip()
                                               and not a.interaction_only), library.source,
                           library.roles, library.interactions, library.states)
    if not recognisable.actions:
        raise DoodleError(f"{library.source}: no action has an expression to recognise")
    named = {}
    for a in recognisable.actions:
        if a.shape:
            paths, quats, seconds, elapsed = load_shape(a.shape, a.name)
            if paths.shape[1] != max(1, len(a.tracks)):
                raise DoodleError(f"{a.source}: action {a.name!r}: its shape file {a.shape} holds "
                                  f"{paths.shape[1]} track(s), its 'tracks' name {max(1, len(a.tracks))}")
            named[a.name] = (paths, quats, seconds, elapsed)
    return Compiled(recognisable, tuple(compile_action(a, known) for a in recognisable.actions), compile_roles(library, known),
                    shape_set(named, {a.name: a.expression for a in recognisable.actions},
                              {a.name: a.track for a in recognisable.actions},
                              partners={a.name: a.tracks[1:] for a in recognisable.actions if a.tracks}))


def _check_invertible(library: Library) -> None:
    """Behaviour states (§6.3.3) must be invertible — "each action or interaction changing
    one state variable must be invertible": a state some action sets, another clears, and
    the other way round, so no character is stuck in it."""
    sets = {v: a.name for a in library.actions for v in a.sets}
    clears = {v: a.name for a in library.actions for v in a.clears}
    for v, name in sets.items():
        if v not in clears:
            raise DoodleError(f"{library.source}: action {name!r} sets state {v!r} but no action clears it "
                              "(a character could never leave it; add an action with clears = [...])")
    for v, name in clears.items():
        if v not in sets:
            raise DoodleError(f"{library.source}: action {name!r} clears state {v!r} but no action sets it "
                              "(add an action with sets = [...])")


def compile_roles(library: Library, known: dict | None = None) -> Compiled | None:
    """The automata of the actions that are only roles of interactions (``interaction_only``:
    the Contexter matches them; independent recognition never does), or None."""
    roles = tuple(a for a in library.actions if a.interaction_only and a.expression.strip())
    if not roles:
        return None
    lib = Library(library.name, roles, library.source, library.roles, library.interactions, library.states)
    return Compiled(lib, tuple(compile_action(a, known) for a in roles))


@dataclass(frozen=True)
class Overlap:
    """Two actions whose languages intersect, with a shortest token string both accept."""

    first: str
    second: str
    witness: tuple[str, ...]  # a shortest compacted token string both accept


def overlaps(compiled: Compiled, only: str | None = None) -> list[Overlap]:
    """Every pair of actions whose languages intersect (or every action overlapping
    ``only``), each with a shortest token string both accept (§4.2.4)."""
    names, dfas = compiled.library.names, compiled.dfas
    found = []
    for i in range(len(names)):
        for j in range(i + 1, len(names)):
            if only is not None and only not in (names[i], names[j]):
                continue
            witness = intersection_witness(dfas[i], dfas[j])
            if witness is not None:
                found.append(Overlap(names[i], names[j], tuple(witness)))
    return found


@dataclass(frozen=True)
class Swallow:
    """``winner`` is read instead of ``action`` on a ``share`` of the latter's typical strings."""

    winner: str
    action: str
    share: float
    witness: tuple[str, ...]  # the shortest such string


def swallowed(compiled: Compiled, strings: int = 200, least: float = 0.05, seed: int = 0) -> list[Swallow]:
    """Pairs where one action's language takes another's typical performances.

    An action's typical strings are its shortest string and ``strings`` random walks of its
    automaton stopping at each accepting state with probability ½ (short strings are the
    likely performances). On each, the Matcher's choice between the actions accepting it
    exactly is taken (the narrowest language, then the first listed); a pair is reported
    when another action is chosen on at least ``least`` of them, with the shortest string.
    """
    names, dfas = compiled.library.names, compiled.dfas
    auto = compiled.automaton()
    rng = np.random.default_rng(seed)
    found = []
    for i, name in enumerate(names):
        pool = [tuple(shortest(dfas[i]))] + [tuple(sample(dfas[i], rng, stop=0.5, max_len=24)) for _ in range(strings)]
        taken: dict[int, list[tuple[str, ...]]] = {}
        for words in pool:
            codes = [CODES[w] for w in words]
            winner = auto.most_specific(np.array([j for j in range(len(names)) if dfas[j].accepts(codes)]))
            if winner != i:
                taken.setdefault(winner, []).append(words)
        for j, lost in taken.items():
            if len(lost) >= least * len(pool):
                found.append(Swallow(names[j], name, len(lost) / len(pool), min(lost, key=len)))
    return sorted(found, key=lambda s: -s.share)
