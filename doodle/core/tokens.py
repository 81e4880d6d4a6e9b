"""Motion tokens: the Segmenter's alphabet (thesis §4.2.2, Appendix 2).

A token is ``T_STILL`` or a direction bin of the local linear (``T_…``) or angular (``R_…``)
velocity. Each axis of the figurine frame (+x LEFT, +y UP, +z FRONT) contributes its sign when
the velocity's direction is within π/3 of it (``|dot(v̂, axis)| ≥ 0.5``): 26 bins per kind.
Names list the contributing axes in x, y, z order with ``N_`` before a negative one:
``T_Z`` forward, ``T_N_Z`` backward, ``T_N_X_Y`` right-and-up, ``R_Y`` a turn to the left.

Internally a bin is a small integer *code*: 0 is still, ``1 + k`` a translation and
``28 + k`` a rotation, where ``k = 9(sx+1) + 3(sy+1) + (sz+1)`` for axis signs in {-1, 0, 1}.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

STILL = 0
T_BASE = 1
R_BASE = 28
N_CODES = 55


def _axis_name(signs: tuple[int, int, int]) -> str:
    parts = []
    for s, axis in zip(signs, "XYZ"):
        if s > 0:
            parts.append(axis)
        elif s < 0:
            parts.append("N_" + axis)
    return "_".join(parts)


def _build_names() -> list[str]:
    names = [""] * N_CODES
    names[STILL] = "T_STILL"
    for k in range(27):
        signs = (k // 9 - 1, (k // 3) % 3 - 1, k % 3 - 1)
        if signs == (0, 0, 0):
            continue
        names[T_BASE + k] = "T_" + _axis_name(signs)
        names[R_BASE + k] = "R_" + _axis_name(signs)
    return names


NAMES: list[str] = _build_names()
CODES: dict[str, int] = {name: code for code, name in enumerate(NAMES) if name}
ALPHABET: tuple[str, ...] = tuple(name for name in NAMES if name)  # 53 tokens


def signs_of(name: str) -> tuple[str, tuple[int, int, int]]:
    """Kind ('T', 'R' or 'S' for still) and axis signs of a token name; ValueError if unknown."""
    code = CODES.get(name)
    if code is None:
        raise ValueError(f"unknown token {name!r}")
    if code == STILL:
        return "S", (0, 0, 0)
    k = code - (T_BASE if code < R_BASE else R_BASE)
    return ("T" if code < R_BASE else "R"), (k // 9 - 1, (k // 3) % 3 - 1, k % 3 - 1)


@dataclass(frozen=True)
class Token:
    """One motion token covering samples ``start`` (inclusive) to ``end`` (exclusive)."""

    name: str
    start: int
    end: int


def direction_index(cx: float, cy: float, cz: float) -> int:
    """Bin index ``k`` of a non-zero vector (scalar form of :func:`direction_indices`)."""
    n2 = cx * cx + cy * cy + cz * cz
    sx = (1 if cx > 0 else -1) if 4.0 * cx * cx >= n2 else 0
    sy = (1 if cy > 0 else -1) if 4.0 * cy * cy >= n2 else 0
    sz = (1 if cz > 0 else -1) if 4.0 * cz * cz >= n2 else 0
    return 9 * (sx + 1) + 3 * (sy + 1) + (sz + 1)


def direction_indices(c: np.ndarray) -> np.ndarray:
    """Bin index ``k`` per row of ``c`` (m, 3): same arithmetic as :func:`direction_index`.

    ``|dot(ĉ, axis)| ≥ 0.5`` is evaluated as ``4 c_k² ≥ |c|²`` (exact, no division).
    """
    cx, cy, cz = c[:, 0], c[:, 1], c[:, 2]
    n2 = cx * cx + cy * cy + cz * cz
    k = np.full(len(c), 13, dtype=np.int64)
    for comp, weight in ((cx, 9), (cy, 3), (cz, 1)):
        on = 4.0 * comp * comp >= n2
        k += np.where(on, np.where(comp > 0, weight, -weight), 0)
    return k
