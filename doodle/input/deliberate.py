"""Tokens that mean deliberate motion: holds and blips are absorbed (SPEC Segmenter).

The bins of the Segmenter see every wiggle: the slow start of a glide whose direction is
still the hand's bob, the moment a reversing hand passes through zero speed, the wobble
of a prop at the end of a stroke. Such excursions last longer than the debounce α at slow
tempi and high rates, so they become tokens — ``T_Y`` before a forward glide, ``T_X_Y``
between two strokes, a ``T_STILL`` at the top of a kick — that no action expects. Two rules,
both relative to the performance itself:

* **A hold is not a pause.** A ``T_STILL`` between two movements shorter than
  ``pause_s`` (0.12 s) is the hand changing direction, not the performer pausing; it is
  absorbed. A hand slowing into a reversal or a corner spends a while under ε before it
  stops, and longer the slower and smaller the movement, so a slow performer's corners
  look like short pauses. So a still up to 2 × ``pause_s`` long is a hold unless it holds
  at least ``REST_S`` (0.1 s) of rest beyond the slowing ends of the movements around it:
  each end's time under ε is estimated from how long that movement took to slow from 2ε
  to ε (× 1.7: between a linear fall, × 1, and a minimum-jerk one, speed ∝ t², × 2.41).
  The pauses people leave between actions hold more rest than that (0.15 s and up).
* **A token must cover ground.** A token's *extent* is ``√(d² + (θ·φ)²)`` — the chord d it
  moves and the angle φ it turns, in the Segmenter's metres-per-radian exchange rate θ.
  Any moving token under ``ε·min_extent_s`` (1 cm by default) is absorbed: no deliberate
  movement is that small. A translation token is also absorbed when its extent is under
  ``significance`` (⅕) of the largest translation within ``window`` (2) places on either
  side — holds skipped, pauses ending the search (translations only: θ is an exchange rate
  of speeds, and a half turn is not "bigger" than a 20 cm glide). A translation alone
  between two pauses (the landing after a bobbed walk, the hand settling the prop) is a
  leftover when it is under half that share (1/10) of the movements before the pause
  before it. Rotation tokens face the floor only: a controller gesture's turns of the
  wrist are short and carry what tells two gestures apart (on the real Vive recordings the
  relative rule on rotations cost nearest-string consistency). The floor and the shares
  scale with the doodle (``params.scaled``), so "scaled doodle, scaled thresholds, same
  tokens" still holds. A still, a flicker under the floor and a still are one still, so a
  noisy pause is judged by its whole length.

Absorbed tokens give their samples to their neighbours: to one token if both neighbours
carry the same name (a walk bobbed up for a moment stays one walk), else split at the
middle sample. :class:`Absorber` is a streaming stage (push raw tokens with their extents,
get final tokens); the batch Segmenter runs the same stage to the end, so both agree.
"""

from __future__ import annotations

import copy
import math

from doodle.core.tokens import Token

STILL = "T_STILL"
REST_S = 0.1  # s: a still with less rest than this beyond the movements' slowing ends is a hold ...
# time a movement spends under ε as it comes to rest, per unit of time it takes from 2ε to ε:
# 1 if its speed falls linearly, 1/(√2 − 1) = 2.41 if as t² (minimum jerk); the midpoint, as
# the smoothing kernel rounds the speed near rest
SLOWING = (1.0 + 1.0 / (math.sqrt(2.0) - 1.0)) / 2.0
ACROSS = 0.5  # a lone token is a leftover under half the share against the movements before the pause
HOLD_CAP = 2.0  # ... up to twice pause_s; a still as long as that is always a pause
KEEP = 64  # raw tokens kept behind the first undecided one (neighbours, the movement before a still)


def extent(a: tuple, b: tuple, theta: float) -> float:
    """Extent of the motion between two smoothed rows ``(t, px, py, pz, qx, qy, qz, qw)``."""
    dx, dy, dz = b[1] - a[1], b[2] - a[2], b[3] - a[3]
    ax, ay, az, aw = a[4], a[5], a[6], a[7]
    bx, by, bz, bw = b[4], b[5], b[6], b[7]
    # relative rotation conj(a) ⊗ b: its vector part and scalar part
    rx = aw * bx - ax * bw - ay * bz + az * by
    ry = aw * by + ax * bz - ay * bw - az * bx
    rz = aw * bz - ax * by + ay * bx - az * bw
    rw = aw * bw + ax * bx + ay * by + az * bz
    angle = 2.0 * math.atan2(math.sqrt(rx * rx + ry * ry + rz * rz), abs(rw))
    return math.sqrt(dx * dx + dy * dy + dz * dz + (theta * angle) ** 2)


class Absorber:
    """Streaming stage: raw tokens (with extents and ramps) in, deliberate tokens out. A
    token is decided once what its rules look at is known (its neighbours, the window on
    either side); it is emitted once the next kept token is decided."""

    def __init__(self, rate: float, pause_s: float, significance: float, floor: float, window: int):
        self.pause = pause_s * rate  # samples
        self.longest_hold = HOLD_CAP * pause_s * rate
        self.rest = REST_S * rate  # samples of rest beyond the slowing ends that make a pause
        self.significance, self.floor, self.window = significance, floor, window
        self._raw: list[tuple[Token, float, tuple[int, int]]] = []  # raw tokens (token, extent, ramps)
        self._next = 0  # index into _raw of the first undecided token
        self._decided: list[tuple[Token, bool]] = []  # decided, not yet emitted: (token, absorbed)
        self._closed = False

    # --- classification of raw tokens --------------------------------------------------
    def _is_hold(self, i: int) -> bool | None:
        """Whether raw token i (an index into _raw) is a short still between movements;
        None while its next neighbour is not known."""
        tok = self._raw[i][0]
        if self.pause <= 0 or tok.name != STILL or tok.end - tok.start >= self.longest_hold or tok.start == 0:
            return False  # a doodle's opening rest is never a hold
        if i + 1 >= len(self._raw):
            return False if self._closed else None
        if self._raw[i + 1][1] < self.floor and i + 2 >= len(self._raw) and not self._closed:
            return None  # a flicker follows: a still after it would join this one
        return self._short(tok, self._raw[i - 1][2][1], self._raw[i + 1][2][0])

    def _short(self, still: Token, before: int, after: int) -> bool:
        """Whether a still between movements is a hold by its length: under ``pause_s``, or
        with less than ``REST_S`` of rest beyond the slowing ends of the movements around it
        (``before``, ``after``: the samples each takes from its last, and to its first,
        sample over 2ε)."""
        if still.end - still.start < self.pause:
            return True
        return still.end - still.start - SLOWING * (before + after) < self.rest

    def pause_from(self, still: Token) -> tuple[float, float]:
        """The samples from which a still in progress (not pushed yet) would be a pause were a
        movement to begin there: the earliest it can be known to be one — the next
        movement's slowing start, unknown yet, only makes a hold likelier — and from which it
        is one however the next movement starts (:data:`HOLD_CAP` × ``pause_s``)."""
        before = len(self._raw) - 1  # the movement before it
        if self._joins(still):
            still, before = Token(STILL, self._raw[-2][0].start, still.end), before - 2
        if self.pause <= 0 or still.start == 0 or before < 0:
            return still.start, still.start
        may = still.start + min(self.longest_hold, max(self.pause, self.rest + SLOWING * self._raw[before][2][1]))
        return may, still.start + self.longest_hold

    def copy(self) -> "Absorber":
        """An independent copy (what it is pushed leaves this one as it is)."""
        other = copy.copy(self)
        other._raw, other._decided = list(self._raw), list(self._decided)
        return other

    def _is_pause(self, i: int) -> bool | None:
        """Whether raw token i is a still that separates movements (None: not known yet)."""
        if self._raw[i][0].name != STILL:
            return False
        hold = self._is_hold(i)
        return None if hold is None else not hold

    def _reference(self, i: int, step: int, across: bool = False) -> float | None:
        """Largest extent among the movements of raw token i's kind (translations or
        rotations) within the window on one side of it, up to the nearest pause — or, with
        ``across``, among the window's movements beyond that pause; None when that side is
        not known yet."""
        kind = self._raw[i][0].name[0]
        best, seen, j, crossed = 0.0, 0, i + step, False
        while seen < self.window:
            if j < 0:
                return best
            if j >= len(self._raw):
                return best if self._closed else None
            tok, ext, _ = self._raw[j]
            if tok.name == STILL:
                pause = self._is_pause(j)
                if pause is None:
                    return None
                if pause and (crossed or not across):
                    return best
                crossed = crossed or pause
                j += step  # a hold (or, across, the pause): look past it
                continue
            if tok.name[0] == kind and crossed == across:
                best = max(best, ext)
            seen, j = seen + 1, j + step
        return best

    def _absorbed(self, i: int) -> bool | None:
        tok, ext, _ = self._raw[i]
        if tok.name == STILL:
            return self._is_hold(i)
        if ext < self.floor:
            return True
        if tok.name[0] == "R":  # rotations carry a controller gesture's detail: only the floor
            return False
        before, after = self._reference(i, -1), self._reference(i, +1)
        if before is None or after is None:
            return None
        if ext < self.significance * max(before, after):
            return True
        # a leftover after an action, alone before the next pause: against what came before it
        lone = i > 0 and before == 0.0 and after == 0.0 and self._raw[i - 1][0].name == STILL
        return lone and ext < ACROSS * self.significance * self._reference(i, -1, across=True)

    # --- streaming ----------------------------------------------------------------------
    def push(self, token: Token, ext: float, ramps: tuple[int, int] = (0, 0)) -> list[Token]:
        """Add a raw token with its extent (m) and ramps: the samples from its start to its
        first sample faster than 2ε, and from its last such sample to its end."""
        if self._joins(token):  # a still, a flicker below any deliberate movement, a still: one still
            self._raw[-2:] = [(Token(STILL, self._raw[-2][0].start, token.end), 0.0, (0, 0))]
        else:
            self._raw.append((token, ext, ramps))
        return self._advance()

    def _joins(self, token: Token) -> bool:
        """Whether a still joins the undecided still before the flicker it follows (so a
        noisy pause is judged by its whole length)."""
        raw = self._raw
        return (token.name == STILL and len(raw) - self._next >= 2 and raw[-2][0].name == STILL
                and raw[-1][0].name != STILL and raw[-1][1] < self.floor)

    def close(self) -> list[Token]:
        self._closed = True
        out = self._advance()
        return out + self._flush(final=True)

    def _advance(self) -> list[Token]:
        out: list[Token] = []
        while self._next < len(self._raw):
            verdict = self._absorbed(self._next)
            if verdict is None:
                break
            self._decided.append((self._raw[self._next][0], verdict))
            self._next += 1
            out += self._flush(final=False)
        drop = self._next - KEEP  # keep what later decisions look back at
        if drop > 0:
            del self._raw[:drop]
            self._next -= drop
        return out

    def _flush(self, final: bool) -> list[Token]:
        """Emit the kept tokens whose samples can no longer change."""
        out: list[Token] = []
        while True:
            kept = [k for k, (_, absorbed) in enumerate(self._decided) if not absorbed]
            start = self._decided[0][0].start if self._decided else 0  # the first kept token takes what precedes it
            if len(kept) >= 2:
                first, nxt = self._decided[kept[0]][0], self._decided[kept[1]][0]
                if first.name == nxt.name:  # one token across the absorbed run
                    self._decided[kept[0]: kept[1] + 1] = [(Token(first.name, first.start, nxt.end), False)]
                    continue
                gap = self._decided[kept[0] + 1: kept[1]]
                mid = first.end if not gap else (gap[0][0].start + gap[-1][0].end) // 2
                out.append(Token(first.name, start, mid))
                self._decided[: kept[1] + 1] = [(Token(nxt.name, mid, nxt.end), False)]
                continue
            if final and self._decided:
                name = self._decided[kept[0]][0].name if kept else STILL  # nothing deliberate: still
                out.append(Token(name, start, self._decided[-1][0].end))
                self._decided = []
            return out


def absorb(tokens: list[Token], extents: list[float], ramps: list[tuple[int, int]], absorber: Absorber) -> list[Token]:
    """Batch form: the stage run over a whole token list."""
    out: list[Token] = []
    for tok, ext, ramp in zip(tokens, extents, ramps):
        out += absorber.push(tok, ext, ramp)
    return out + absorber.close()
