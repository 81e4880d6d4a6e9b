"""Interaction constraints (thesis §6.3, SPEC "Several characters"): pure functions on the
characters' states at one time.

* Distance (§6.3.1): ``D(i, j, α)`` holds when ``‖P_i − P_j‖ ≤ α``; α is a number of metres
  or one of Hall's proxemic zones, computed from the characters' bounding-sphere radii:
  Intimate ``r_i + r_j``, Personal ``2(r_i + r_j)``, Social ``4(…)``, Public ``8(…)``. The
  distance is the thesis's full 3-D one. In doodle space a character is its figurine, so the
  default radius is :data:`RADIUS` = 0.1 m (half the 20 cm prop of ``doodle.app.pipeline``).
* Field of view (§6.3.2): ``V(i, j, γ)`` holds when ``dot(unit(P_j − P_i), F_i) ≥ γ`` (i sees
  j), ``MV(i, j, β)`` when ``dot(F_i, F_j) ≤ β`` (they face each other for β < 0). ``F`` is
  the figurine's front (its local +z) projected on the ground plane and normalised; the
  direction ``P_j − P_i`` is projected on the ground too, so a height difference between the
  figurines does not narrow the view. A figurine pointing straight up or down has no front
  (zero vector): V then fails for any γ > 0.
* Behaviour states (§6.3.3): a character's state is a set of boolean variables; an action
  may require some true and some false (pre-conditions) and set or clear some when it ends
  (post-conditions). :class:`Behaviour` is that, as plain sets, read from the manifest's
  ``requires``/``forbids``/``sets``/``clears`` fields (the library's ``states`` are true at
  the start); :func:`grammar.contexter.apply_behaviour` applies them to recognised segments.

Constraints are written in the thesis's notation, e.g. ``"D(0, 1, Personal)"``,
``"V(1, 0, 0.5)"``, ``"MV(0, 1, -0.5)"``; indices are roles (the position of the action in
the interaction's action list). :func:`parse_constraint` reads one, with errors naming the
interaction and the constraint.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

import numpy as np

from doodle.core import quat
from doodle.core.errors import DoodleError

RADIUS = 0.1  # metres: bounding-sphere radius of a character in doodle (prop) space
ZONES = {"intimate": 1.0, "personal": 2.0, "social": 4.0, "public": 8.0}  # × (r_i + r_j)
KINDS = ("D", "V", "MV")
_SYNTAX = re.compile(r"^\s*([A-Za-z]+)\s*\(\s*([^,()]*?)\s*,\s*([^,()]*?)\s*,\s*([^,()]*?)\s*\)\s*$")


@dataclass(frozen=True, eq=False)
class State:
    """A character at one time: position (metres), ground-plane unit front, radius."""

    position: np.ndarray  # (3,)
    front: np.ndarray  # (3,) y = 0, unit or zero
    radius: float = RADIUS


def ground_front(q) -> np.ndarray:
    """The figurine's front (local +z) of quaternion(s) xyzw, on the ground plane, unit
    (zero where it points straight up or down). Works on (4,) or (n, 4)."""
    f = quat.front(np.asarray(q, dtype=float))  # scipy Rotation's, to the bit
    f[..., 1] = 0.0
    n = np.linalg.norm(f, axis=-1, keepdims=True)
    return np.where(n > 1e-6, f / np.maximum(n, 1e-12), 0.0)


def zone_distance(zone: str, r_i: float, r_j: float) -> float:
    """The proxemic threshold of a zone name (case-insensitive) for radii r_i, r_j (§6.3.1)."""
    return ZONES[zone.lower()] * (r_i + r_j)


def distance(p_i, p_j) -> float:
    return float(np.linalg.norm(np.asarray(p_j, float) - np.asarray(p_i, float), axis=-1))


def within(p_i, p_j, threshold: float) -> bool:
    """``D(i, j, α)``: ``‖P_i − P_j‖ ≤ α``."""
    return bool(within_all(_rows(p_i), _rows(p_j), threshold)[0])


def sees(p_i, f_i, p_j, gamma: float) -> bool:
    """``V(i, j, γ)``: ``dot(unit(P_j − P_i), F_i) ≥ γ``, on the ground plane."""
    return bool(sees_all(_rows(p_i), _rows(f_i), _rows(p_j), gamma)[0])


def mutual_view(f_i, f_j, beta: float) -> bool:
    """``MV(i, j, β)``: ``dot(F_i, F_j) ≤ β``."""
    return bool(mutual_view_all(_rows(f_i), _rows(f_j), beta)[0])


def within_all(p_i: np.ndarray, p_j: np.ndarray, threshold: float) -> np.ndarray:
    """:func:`within` at every time of (n, 3) positions."""
    d = p_j - p_i
    return np.sqrt((d * d).sum(axis=-1)) <= threshold  # np.linalg.norm's arithmetic, without its checks


def sees_all(p_i: np.ndarray, f_i: np.ndarray, p_j: np.ndarray, gamma: float) -> np.ndarray:
    """:func:`sees` at every time of (n, 3) positions and fronts (at one place: nothing to
    look towards, so not seen)."""
    d = p_j - p_i
    d[:, 1] = 0.0
    n = np.sqrt((d * d).sum(axis=-1))
    return (n >= 1e-9) & ((d * f_i).sum(axis=-1) / np.maximum(n, 1e-9) >= gamma)


def mutual_view_all(f_i: np.ndarray, f_j: np.ndarray, beta: float) -> np.ndarray:
    """:func:`mutual_view` at every time of (n, 3) fronts."""
    return (f_i * f_j).sum(axis=-1) <= beta


def _rows(x) -> np.ndarray:
    return np.asarray(x, dtype=float).reshape(1, 3)


@dataclass(frozen=True)
class Constraint:
    """One constraint between roles i and j; ``value`` is a zone name or a number."""

    kind: str  # "D", "V" or "MV"
    i: int
    j: int
    value: str | float

    def holds(self, state_i: State, state_j: State) -> bool:
        return bool(self.holds_all(_rows(state_i.position), _rows(state_i.front), state_i.radius,
                                   _rows(state_j.position), _rows(state_j.front), state_j.radius)[0])

    def holds_all(self, p_i, f_i, r_i: float, p_j, f_j, r_j: float) -> np.ndarray:
        """Whether it holds at every time of roles i and j's (n, 3) positions and fronts."""
        if self.kind == "D":
            alpha = zone_distance(self.value, r_i, r_j) if isinstance(self.value, str) else self.value
            return within_all(p_i, p_j, alpha)
        if self.kind == "V":
            return sees_all(p_i, f_i, p_j, self.value)
        return mutual_view_all(f_i, f_j, self.value)

    def __str__(self) -> str:
        v = self.value.capitalize() if isinstance(self.value, str) else f"{self.value:g}"
        return f"{self.kind}({self.i}, {self.j}, {v})"


def all_hold(constraints, states) -> bool:
    """Every constraint holds for ``states`` indexed by role (the conjunction, §6.2.1)."""
    return all(c.holds(states[c.i], states[c.j]) for c in constraints)


def parse_constraint(text: str, interaction: str = "", roles: int | None = None) -> Constraint:
    """A constraint in the thesis's notation; DoodleError naming the interaction and text."""
    where = f"interaction {interaction!r}: constraint {text!r}" if interaction else f"constraint {text!r}"
    if not isinstance(text, str):
        raise DoodleError(f"{where}: expected a string such as \"D(0, 1, Personal)\"")
    m = _SYNTAX.match(text)
    if not m:
        raise DoodleError(f"{where}: expected KIND(i, j, value), e.g. D(0, 1, Personal), V(0, 1, 0.5), MV(0, 1, -0.5)")
    kind, a, b, raw = m.groups()
    if kind not in KINDS:
        raise DoodleError(f"{where}: unknown kind {kind!r} (known: {', '.join(KINDS)})")
    if not (a.isdigit() and b.isdigit()):
        raise DoodleError(f"{where}: character indices must be whole numbers (roles 0, 1, …)")
    i, j = int(a), int(b)
    if i == j:
        raise DoodleError(f"{where}: relates a character to itself")
    if roles is not None and max(i, j) >= roles:
        raise DoodleError(f"{where}: role {max(i, j)} out of range (the interaction has {roles} actions)")
    value: str | float
    if kind == "D" and raw.lower() in ZONES:
        value = raw.lower()
    else:
        try:
            value = float(raw)
        except ValueError:
            extra = f" or a zone ({', '.join(z.capitalize() for z in ZONES)})" if kind == "D" else ""
            raise DoodleError(f"{where}: value {raw!r} is not a number{extra}") from None
        if not np.isfinite(value):
            raise DoodleError(f"{where}: value must be finite")
        if kind == "D" and value < 0:
            raise DoodleError(f"{where}: a distance must not be negative")
        if kind in ("V", "MV") and not -1.0 <= value <= 1.0:
            raise DoodleError(f"{where}: a cosine must be in [-1, 1]")
    return Constraint(kind, i, j, value)


def parse_constraints(texts, interaction: str = "", roles: int | None = None) -> tuple[Constraint, ...]:
    return tuple(parse_constraint(t, interaction, roles) for t in texts)


@dataclass(frozen=True)
class Behaviour:
    """Pre/post-conditions on a character's boolean state variables (§6.3.3)."""

    requires: frozenset = field(default_factory=frozenset)  # must be true before
    forbids: frozenset = field(default_factory=frozenset)  # must be false before
    sets: frozenset = field(default_factory=frozenset)  # true after
    clears: frozenset = field(default_factory=frozenset)  # false after

    def allowed(self, state: frozenset) -> bool:
        return self.requires <= state and not (self.forbids & state)

    def after(self, state: frozenset) -> frozenset:
        return (frozenset(state) - self.clears) | self.sets

    def why(self, state: frozenset) -> str:
        """Why it is not allowed in ``state`` ("" when it is)."""
        missing, present = sorted(self.requires - state), sorted(self.forbids & state)
        return "; ".join([f"needs {', '.join(missing)}"] * bool(missing) + [f"not while {', '.join(present)}"] * bool(present))

    @staticmethod
    def of(action) -> "Behaviour | None":
        """An action definition's behaviour (``library.manifest.ActionDef``), None without one."""
        parts = [frozenset(getattr(action, k)) for k in ("requires", "forbids", "sets", "clears")]
        return Behaviour(*parts) if any(parts) else None
