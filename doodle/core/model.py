"""The doodle data model: synchronised tracks of timestamped 6-DoF poses.

Everything in memory is in the project's frame (see SPEC "Conventions"): metres, seconds,
right-handed world with +y up, +z the performer's forward and +x their left; orientations
are unit quaternions ``(x, y, z, w)`` giving world-from-figurine rotations, where the
figurine's own axes are +x LEFT, +y UP, +z FRONT. Importers convert into this frame.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from doodle.core.errors import DoodleError


@dataclass(frozen=True, eq=False)
class Track:
    """One tracked object (one character): n samples on the doodle's clock.

    ``valid[i]`` is False where the device reported lost tracking; the pose values of such
    samples are meaningless (often NaN) until :func:`doodle.input.repair.fill_gaps` repairs them.
    """

    name: str
    t: np.ndarray  # (n,) seconds from the first sample, strictly increasing
    p: np.ndarray  # (n, 3) metres, world frame
    q: np.ndarray  # (n, 4) unit quaternions xyzw, world-from-figurine
    valid: np.ndarray  # (n,) bool
    role: str = ""  # e.g. right_hand, left_hand, tracker
    serial: str = ""

    def __post_init__(self) -> None:
        n = len(self.t)
        if self.p.shape != (n, 3) or self.q.shape != (n, 4) or self.valid.shape != (n,):
            raise ValueError(
                f"track {self.name}: shapes t{self.t.shape} p{self.p.shape} "
                f"q{self.q.shape} valid{self.valid.shape} do not agree"
            )

    def __len__(self) -> int:
        return len(self.t)

    @property
    def duration(self) -> float:
        return float(self.t[-1] - self.t[0]) if len(self.t) else 0.0


@dataclass(frozen=True, eq=False)
class Doodle:
    """One or more synchronised tracks recorded by one device set at a nominal rate."""

    tracks: tuple[Track, ...]
    rate: float  # nominal samples per second of the device
    device: str = "unknown"
    source: str = "<memory>"  # where it came from, for messages
    meta: dict = field(default_factory=dict)  # free-form header entries (x-… keys)

    @property
    def names(self) -> list[str]:
        return [tr.name for tr in self.tracks]

    @property
    def t(self) -> np.ndarray:
        return self.tracks[0].t

    def track(self, name: str) -> Track:
        for tr in self.tracks:
            if tr.name == name:
                return tr
        raise DoodleError(f"{self.source}: no track {name!r} (tracks: {', '.join(self.names)})")

    def select(self, names: list[str] | None) -> "Doodle":
        """The doodle restricted to the named tracks, in that order (all when None)."""
        if not names:
            return self
        return Doodle(tuple(self.track(n) for n in names), self.rate, self.device, self.source, self.meta)
