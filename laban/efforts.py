"""Laban Effort names (thesis §2.1.2, Fig. 2.1 and 2.3): three Factors, two Elements each, and
the eight Drives that combine one Element of every Factor.

Signs follow the stylisation modifiers (``retarget.stylize``): +1 is Direct, Sudden, Strong;
−1 is Indirect, Sustained, Light. A *State* (§4.4.2) is the Time and Weight pair without
Space — what the system recognises on actual doodles (§4.4.3).
"""

from __future__ import annotations

FACTORS = ("space", "time", "weight")
ELEMENTS = {
    "space": ("Indirect", "Direct"),
    "time": ("Sustained", "Sudden"),
    "weight": ("Light", "Strong"),
}
# Drive → (space, time, weight) signs
DRIVES = {
    "Punch": (1, 1, 1),
    "Dab": (1, 1, -1),
    "Press": (1, -1, 1),
    "Glide": (1, -1, -1),
    "Slash": (-1, 1, 1),
    "Flick": (-1, 1, -1),
    "Wring": (-1, -1, 1),
    "Float": (-1, -1, -1),
}
STATES = ("Sudden Strong", "Sudden Light", "Sustained Strong", "Sustained Light")


def element(factor: str, sign: int) -> str:
    """``element("time", 1) == "Sudden"``."""
    return ELEMENTS[factor][1 if sign > 0 else 0]


def drive_of(space: int, time: int, weight: int) -> str:
    """The Drive with these signs."""
    for name, signs in DRIVES.items():
        if signs == (1 if space > 0 else -1, 1 if time > 0 else -1, 1 if weight > 0 else -1):
            return name
    raise AssertionError("unreachable")


def state_of(time: int, weight: int) -> str:
    """``state_of(1, -1) == "Sudden Light"``."""
    return f"{element('time', time)} {element('weight', weight)}"
