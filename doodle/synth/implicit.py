"""Implicit actions (thesis §6.4): a minimal spatial motion doodle generated from an action's
expression, recognised as that action, optionally rotated and scaled to reach a target.

1. **A string recognised as intended.** The thesis picks one of the expression's strings;
   the library's expressions overlap (Appendix 2), so the string must also win against
   every other action: the shortest accepted string first, then sampled ones, each checked
   with the Matcher of the whole library — the first that reads back as exactly the action
   is used (:func:`intended_tokens`).
2. **Minimal SMD.** One brisk stroke per token from the figurine's current local frame
   (:func:`doodle.synth.strokes.perform`: minimum-jerk translations of 0.1 m or rotations of
   1.2 rad, well above the Segmenter's ε), framed by pauses, from a start pose.
3. **Reaching a target** (eq. 6.8). Positions and orientations are rotated together about
   the start point so the start→end chord points at the goal, then positions are scaled
   about the start so the end lands on it. Tokens live in the figurine's moving frame, so a
   rigid rotation leaves them unchanged. Scaling keeps the tokens while strokes stay well
   above the Segmenter's ε (absolute thresholds): measured on every built-in action,
   0.7× to 3× all read back as intended; at 0.5× three of them do not.

4. **End orientation and smoothing** (eq. 6.9). Rotating the whole curve introduces no
   discontinuity inside it (its first orientation turns with it); an end orientation
   ``goal_q`` is then met by deforming the orientation curve as rigidly as possible with
   both ends pinned (:func:`end_orientation`), spreading the turn instead of jumping.
"""

from __future__ import annotations

import numpy as np

from doodle.core import quat
from doodle.core.errors import DoodleError
from doodle.core.model import Track
from doodle.synth.strokes import perform
from grammar.automata import sample, shortest
from grammar.library import Compiled
from grammar.matcher import match

CANDIDATES = 200  # sampled strings tried after the shortest
LAPLACIAN = 100.0  # weight on keeping the orientation curve's bends when its end is turned (eq. 6.9)


def intended_tokens(compiled: Compiled, action: str, seed: int = 0, threshold: float = 2.0) -> list[str]:
    """A token string of ``action``'s language that the library's Matcher reads back as
    exactly one segment of ``action``."""
    from doodle.core.tokens import Token

    if action not in compiled.library.names:
        raise DoodleError(f"no action {action!r} with an expression in the library")
    dfa = compiled.dfa(action)
    auto = compiled.automaton(threshold)
    rng = np.random.default_rng(seed)
    candidates = [shortest(dfa)] + [sample(dfa, rng) for _ in range(CANDIDATES)]
    for names in candidates:
        tokens = [Token(n, k, k + 1) for k, n in enumerate(_framed(names))]
        moving = [s for s in match(tokens, auto) if s.action not in ("unknown", "Idle") or action == "Idle"]
        if [s.action for s in moving] == [action] and moving[0].exact:
            return list(names)
    raise DoodleError(f"{action}: no string of its expression is recognised as {action} against the library")


def _framed(names: list[str]) -> list[str]:
    """The string between pauses, without doubling a pause it already starts or ends with."""
    names = list(names)
    return (["T_STILL"] if names[:1] != ["T_STILL"] else []) + names + (["T_STILL"] if names[-1:] != ["T_STILL"] else [])


def minimal_smd(tokens: list[str], start_p=(0.0, 0.0, 0.0), start_q=(0.0, 0.0, 0.0, 1.0), rate: float = 90.0,
                stroke_s: float = 0.3, seed: int = 0, name: str = "c0") -> Track:
    """A track performing ``tokens`` between two pauses, from the pose (start_p, start_q)."""
    track = perform(_framed(tokens), rate=rate, seed=seed, name=name, stroke_s=stroke_s)
    q0 = quat.normalise(np.asarray(start_q, dtype=float)[None])
    p = quat.rotate(np.broadcast_to(q0, track.q.shape), track.p - track.p[0]) + np.asarray(start_p, dtype=float)
    q = quat.make_continuous(quat.multiply(np.broadcast_to(q0, track.q.shape), track.q))
    return Track(name, track.t, p, q, track.valid)


def reach(track: Track, goal, goal_q=None) -> Track:
    """``track`` rotated (positions and orientations together) and scaled about its first
    point so its last point is ``goal`` (eq. 6.8) — and, with ``goal_q``, ending in that
    orientation (:func:`end_orientation`). A track that ends where it started (an in-place
    action) cannot be aimed: only its end orientation is set."""
    aimed = _aim(track, goal) if goal is not None else track
    return end_orientation(aimed, goal_q) if goal_q is not None else aimed


def end_orientation(track: Track, goal_q) -> Track:
    """``track`` ending in orientation ``goal_q`` (§6.4: "we assign q_n to q_goal") without
    the jump that assigning it would make: the orientation curve, as rotation vectors from
    the first orientation, is deformed as rigidly as possible with its first point kept and
    its last pinned to ``goal_q`` (eq. 6.9, the discontinuity terms as pins;
    :func:`doodle.core.arap.deform`, with its second differences kept too: a figurine holding
    still has no ``(α, β)`` to keep, and the turn would stay a jump at the end). The turn is
    made over the closing pause where the doodle has one (a minimal SMD does), so the
    action's own tokens — translations read in the figurine's frame — are unchanged;
    without one it is spread over the whole curve. Positions are unchanged."""
    from doodle.core.arap import deform

    q = quat.make_continuous(quat.normalise(track.q))
    q1 = np.broadcast_to(q[0], q.shape)
    goal_q = quat.normalise(np.asarray(goal_q, dtype=float)[None])[0]
    r = quat.log(quat.multiply(quat.conjugate(q1), q))
    rel_goal = quat.multiply(quat.conjugate(q[:1]), goal_q[None])
    rel_goal = rel_goal * np.sign(rel_goal[0, 3] or 1.0)
    r_goal = quat.log(rel_goal)[0]
    # the turn is made in the closing pause where there is one: a figurine turning while it
    # travels would change how its translations read in its own frame (tokens)
    from doodle.input.segmenter import tokenize

    rate = (len(track.t) - 1) / max(float(track.t[-1] - track.t[0]), 1e-9)
    tokens = tokenize(track, rate)
    k0 = tokens[-1].start if len(tokens) > 1 and tokens[-1].name == "T_STILL" and \
        tokens[-1].start + 3 < len(r) - 1 else 0
    part = r[k0:]
    ramp = np.linspace(0.0, 1.0, len(part))[:, None]
    smoothed = r.copy()
    smoothed[k0:] = deform(part, {0: part[0], len(part) - 1: r_goal}, start=part + ramp * (r_goal - part[-1]),
                           laplacian=LAPLACIAN)
    new_q = quat.make_continuous(quat.multiply(q1, quat.exp(smoothed)))
    return Track(track.name, track.t, track.p, new_q, track.valid, track.role, track.serial)


def _aim(track: Track, goal) -> Track:
    c1, cn, goal = track.p[0], track.p[-1], np.asarray(goal, dtype=float)
    chord, want = cn - c1, goal - c1
    if np.linalg.norm(chord) < 1e-6 or np.linalg.norm(want) < 1e-9:
        return track
    a, b = chord / np.linalg.norm(chord), want / np.linalg.norm(want)
    axis = np.cross(a, b)
    angle = float(np.arctan2(np.linalg.norm(axis), np.dot(a, b)))
    if np.linalg.norm(axis) < 1e-12:  # parallel (angle 0) or opposite (π): any perpendicular axis
        axis = np.cross(a, [1.0, 0.0, 0.0] if abs(a[0]) < 0.9 else [0.0, 1.0, 0.0])
    rot = quat.exp((axis / np.linalg.norm(axis) * angle)[None])[0]
    R = np.broadcast_to(rot, track.q.shape)
    scale = np.linalg.norm(want) / np.linalg.norm(chord)
    p = c1 + scale * quat.rotate(R, track.p - c1)
    q = quat.make_continuous(quat.multiply(R, track.q))
    return Track(track.name, track.t, p, q, track.valid, track.role, track.serial)


def implicit_action(compiled: Compiled, action: str, start_p=(0.0, 0.0, 0.0), start_q=(0.0, 0.0, 0.0, 1.0),
                    goal=None, goal_q=None, rate: float = 90.0, seed: int = 0, name: str = "c0") -> Track:
    """§6.4 end to end: a minimal SMD of ``action`` from a start pose, reaching ``goal``
    and ending in orientation ``goal_q`` where given."""
    track = minimal_smd(intended_tokens(compiled, action, seed), start_p, start_q, rate, seed=seed, name=name)
    return reach(track, goal, goal_q)
