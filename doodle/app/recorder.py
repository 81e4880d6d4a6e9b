"""The recording loop: poll a pose source at its rate, append every frame to a doodle file,
and recognise actions live.

:func:`record` is the same loop for SteamVR, a replayed file or a synthetic performance
(:mod:`doodle.input.sources`). Each frame is written at once with :class:`~doodle.input.fileformat.DoodleWriter`
(fsync about once a second: a crash or ``kill -9`` loses at most about a second) and every
track goes through a streaming Segmenter and Matcher, reported through
``on_event(kind, payload)``; ``payload`` is a dict:

* ``"started"`` — ``t`` (0.0), ``path``, ``tracks`` (names): the first frame is being written;
* ``"token"`` — ``track``, ``token``, ``start``, ``end`` (s), ``final``: a token completed
  (``final=True``) or a new token in progress (``final=False``, for live feedback);
* ``"action"`` — ``track``, ``action``, ``start``, ``end`` (s), ``exact``, ``distance``, ``at``
  (the recording time when it was recognised);
* ``"lost"`` — ``track``, ``t``, ``error``: tracking went away (``error`` None); or, when it
  comes back after a gap too long to bridge (``SegmenterParams.max_gap``), the Segmenter's
  message in ``error``: what was recognised before the gap is final and recognition starts
  afresh from this sample (the file keeps every sample with its ok flag);
* ``"found"`` — ``track``, ``t``, ``gap`` (s without tracking), ``restarted``;
* ``"stopped"`` — ``t``, ``reason`` (``"end"``, ``"seconds"``, ``"trigger"``,
  ``"interrupted"``), ``samples``.

Times in events and results are seconds from the first recorded frame, as in the file.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from doodle.core import quat
from doodle.input.devices import IDENTITY, profile
from doodle.core.errors import DoodleError
from doodle.input.fileformat import DoodleWriter
from doodle.input.segmenter import Segmenter, SegmenterParams


@dataclass(frozen=True)
class RecordResult:
    path: Path
    samples: int
    duration: float  # seconds from the first to the last sample
    actions: dict  # track name -> list of (action, start_s, end_s), unknown segments left out
    reason: str  # why it stopped: "end", "seconds", "trigger" or "interrupted"


class _Live:
    """One track's live recognition: Segmenter → Matcher, restarted after a long loss."""

    def __init__(self, name, rate, params, automaton, mount, times, emit):
        self.name, self.rate, self.params, self.automaton = name, rate, params, automaton
        self.mount = None if np.allclose(mount, IDENTITY) else np.asarray(mount, dtype=float)
        self.times, self.emit = times, emit
        self.actions: list[tuple[str, float, float]] = []
        self.tracked, self.lost_at, self.restarted = True, 0.0, False
        self._start(0)

    def _start(self, offset: int) -> None:
        from grammar.matcher import Matcher

        self.segmenter = Segmenter(self.rate, self.params, self.name, "<recording>")
        self.matcher = Matcher(self.automaton, self.name)
        self.offset, self.shown = offset, None

    def _span(self, start: int, end: int) -> tuple[float, float]:
        last = len(self.times) - 1
        a = min(self.offset + start, last)
        return self.times[a], self.times[min(max(self.offset + end - 1, a), last)]

    def push(self, i: int, p, q, ok: bool) -> None:
        t = self.times[i]
        if self.mount is not None and ok:
            q = quat.normalise(quat.multiply(np.asarray(q, dtype=float), self.mount))
        if self.tracked and not ok:
            self.lost_at, self.restarted = t, False
            self.emit("lost", {"track": self.name, "t": t, "error": None})
        try:
            tokens = self.segmenter.push(t, p, q, ok)
        except DoodleError as exc:  # tracking is back after a gap too long to bridge
            self._finish(flush=False)
            self.emit("lost", {"track": self.name, "t": t, "error": str(exc)})
            self._start(i)
            self.restarted = True
            tokens = self.segmenter.push(t, p, q, ok)
        if ok and not self.tracked:
            self.emit("found", {"track": self.name, "t": t, "gap": t - self.lost_at, "restarted": self.restarted})
        self.tracked = ok
        self._read(tokens)
        pending = self.segmenter.pending
        if pending is not None and pending.name != self.shown:
            self.shown = pending.name
            start, end = self._span(pending.start, pending.end)
            self.emit("token", {"track": self.name, "token": pending.name, "start": start, "end": end, "final": False})

    def close(self) -> None:
        """Flush at the end of the recording (a track lost for longer than ``max_gap`` at the
        end keeps what was recognised before the loss)."""
        self._finish(flush=self.tracked or self.times[-1] - self.lost_at <= self.params.max_gap)

    def _finish(self, flush: bool) -> None:
        tokens = []
        if flush:
            try:
                tokens = self.segmenter.close()
            except DoodleError:  # fewer than two samples since a restart, or never tracked
                flush = False
        if not flush:
            tokens = self.segmenter.cut()
        self._read(tokens, close=True)

    def _read(self, tokens, close: bool = False) -> None:
        segments = []
        for token in tokens:
            start, end = self._span(token.start, token.end)
            self.emit("token", {"track": self.name, "token": token.name, "start": start, "end": end, "final": True})
            segments += self.matcher.push(token)
        if close:
            segments += self.matcher.close()
        for s in segments:
            if s.action == "unknown":
                continue
            start, end = self._span(s.start, s.end)
            self.actions.append((s.action, start, end))
            self.emit("action", {"track": self.name, "action": s.action, "start": start, "end": end,
                                 "exact": s.exact, "distance": s.distance, "at": self.times[-1]})


def record(source, path, *, clock=time.monotonic, sleep=time.sleep, wait_for_trigger: bool = False,
           max_seconds: float | None = None, on_event=None, library_dir=None, use_builtin: bool = True,
           params: SegmenterParams = SegmenterParams(), automaton=None, overwrite: bool = False) -> RecordResult:
    """Record ``source`` (see :mod:`doodle.input.sources`) into the doodle file ``path``.

    Reads one frame per tick of ``1/source.rate`` seconds on ``clock``, sleeping until each
    tick (a tick missed by more than a period is skipped, not caught up in a burst). With
    ``wait_for_trigger`` the recording starts at the first trigger press and stops at the
    next; otherwise it runs until the source ends, ``max_seconds`` of recording, or Ctrl-C
    (KeyboardInterrupt ends it cleanly). Actions come from the built-in library, extended by
    ``library_dir`` (``automaton`` given instead skips compiling it). The caller closes the
    source. The file is created at the first recorded frame; an existing file is refused
    unless ``overwrite``. Raises DoodleError when fewer than two samples were recorded
    (nothing is left on disk then).
    """
    path = Path(path)
    if path.exists() and not overwrite:
        raise DoodleError(f"{path}: already exists (pass --overwrite to replace it)")
    if max_seconds is not None and not (max_seconds > 0 and np.isfinite(max_seconds)):
        raise DoodleError(f"recording length must be a positive number of seconds, not {max_seconds!r}")
    if automaton is None:  # per track (actions may be bound to one); shapes are applied on replay and compile
        from doodle.app.pipeline import load_actions, track_automata

        automaton = track_automata(load_actions(library_dir, use_builtin), [name for name, _, _ in source.tracks])
    emit = on_event or (lambda kind, payload: None)
    rate = float(source.rate)
    period = 1.0 / rate
    mount = profile(source.device).mount
    writer, lives, times, t0, reason = None, [], [], None, "end"
    try:
        try:
            tick = clock()
            while True:
                wait = tick - clock()
                if wait > 0:
                    sleep(wait)
                frame = source.read()
                tick += period
                if clock() - tick > period:
                    tick = clock()
                if frame is None:
                    break
                if t0 is None:
                    if wait_for_trigger and not frame.trigger:
                        continue
                    t0 = frame.t
                    writer = DoodleWriter(path, source.tracks, rate, source.device, overwrite=overwrite)
                    lives = [_Live(name, rate, params, automaton[name] if isinstance(automaton, dict) else automaton,
                                   mount, times, emit) for name, _, _ in source.tracks]
                    emit("started", {"t": 0.0, "path": str(path), "tracks": [name for name, _, _ in source.tracks]})
                elif wait_for_trigger and frame.trigger:
                    reason = "trigger"
                    break
                t = float(frame.t) - t0
                if max_seconds is not None and t > max_seconds + 1e-9:
                    reason = "seconds"
                    break
                if times and round(t, 6) <= round(times[-1], 6):
                    continue  # nothing new since the last poll
                writer.append(t, frame.poses)
                times.append(t)
                for live, (p, q, ok) in zip(lives, frame.poses):
                    live.push(len(times) - 1, p, q, bool(ok))
        except KeyboardInterrupt:
            reason = "interrupted"
        if len(times) >= 2:
            for live in lives:
                live.close()
    finally:
        if writer is not None:
            writer.close()
    emit("stopped", {"t": times[-1] if times else 0.0, "reason": reason, "samples": len(times)})
    if len(times) < 2:
        if writer is not None:
            path.unlink(missing_ok=True)
        if t0 is None and wait_for_trigger:
            raise DoodleError(f"{path}: the trigger was never pressed; nothing recorded")
        raise DoodleError(f"{path}: recording stopped after {len(times)} sample(s); nothing recorded")
    return RecordResult(path, len(times), times[-1], {live.name: live.actions for live in lives}, reason)
