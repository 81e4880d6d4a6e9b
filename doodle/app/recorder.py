"""The recording loop: poll a pose source at its rate, append every frame to a doodle file,
and recognise actions live.

:func:`record` is the same loop for SteamVR, a replayed file or a synthetic performance
(:mod:`doodle.input.sources`). Each frame is written at once with :class:`~doodle.input.fileformat.DoodleWriter`
(fsync about once a second: a crash or ``kill -9`` loses at most about a second) and every
track goes through the streaming Recognizer (:class:`grammar.recognizer.Live`) on a thread of its
own, fed the frames in order, so that the source is polled on every tick however long a frame's
recognition takes. What it finds is reported through ``on_event(kind, payload)`` — called from
that thread, except ``"started"`` and ``"stopped"``, and in order —; ``payload`` is a dict:

* ``"started"`` — ``t`` (0.0), ``path``, ``tracks`` (names): the first frame is being written;
* ``"token"`` — ``track``, ``token``, ``start``, ``end`` (s), ``final``: a token completed
  (``final=True``) or a new token in progress (``final=False``, for live feedback);
* ``"action"`` — ``track``, ``action``, ``start``, ``end`` (s), ``exact``, ``distance``, ``at``
  (the time of the frame whose recognition found it: recognition may run behind the
  recording); an interaction's roles come once more, with ``interaction`` and ``role``, once
  the interaction is decided;
* ``"provisional"`` — the same fields, before that: an action as soon as the tokens so far
  say it (:class:`grammar.recognizer.Live`; ``start`` and ``end`` as they stand — a pause's
  end is where it has got to), which the ``"action"`` that decides it may name differently;
* ``"refused"`` — ``track``, ``action``, ``reason``, ``start``, ``end``, ``at``: an action
  whose behaviour pre-conditions did not hold (§6.3.3);
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

import gc
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from doodle.core import quat
from doodle.input.devices import IDENTITY, profile
from doodle.core.errors import DoodleError
from doodle.input.fileformat import DoodleWriter
from doodle.input.segmenter import SegmenterParams


@dataclass(frozen=True)
class RecordResult:
    path: Path
    samples: int
    duration: float  # seconds from the first to the last sample
    actions: dict  # track name -> list of (action, start_s, end_s), unknown segments left out
    reason: str  # why it stopped: "end", "seconds", "trigger" or "interrupted"
    recognised: dict = None  # per track (tokens, segments): the recording decided as doodle recognize does


class _Live:
    """Every track's live recognition (the one Recognizer, :class:`grammar.recognizer.Live`)
    and what a performer is shown: tokens, actions, refusals, tracking lost and found."""

    def __init__(self, compiled, names, rate, params, mounts, emit):
        from grammar.recognizer import Live

        self.live = Live(compiled, names, rate, params, source="<recording>", restart=True)
        self.names, self.params = list(names), params
        self.mounts = [None if np.allclose(m, IDENTITY) else np.asarray(m, dtype=float) for m in mounts]
        self.times: list[float] = []  # of the frames pushed so far
        self.emit = emit
        self.actions: dict[str, list[tuple[str, float, float]]] = {n: [] for n in names}
        self.tracked = {n: True for n in names}
        self.lost_at = {n: 0.0 for n in names}
        self.shown: dict[str, str | None] = {n: None for n in names}

    def _span(self, start: int, end: int) -> tuple[float, float]:
        last = len(self.times) - 1
        a = min(start, last)
        return self.times[a], self.times[min(max(end - 1, a), last)]

    def push(self, t: float, poses, labels: bool = True) -> None:
        """One frame recognised (``labels``: :meth:`grammar.recognizer.Live.push`)."""
        self.times.append(t)
        mounted = []
        for name, mount, (p, q, ok) in zip(self.names, self.mounts, poses):
            ok = bool(ok)
            if mount is not None and ok:
                q = quat.normalise(quat.multiply(np.asarray(q, dtype=float), mount))
            if self.tracked[name] and not ok:
                self.lost_at[name] = t
                self.emit("lost", {"track": name, "t": t, "error": None})
            mounted.append((p, q, ok))
        step = self.live.push(t, mounted, labels)
        for name, why in step.restarted.items():  # back after a gap too long to bridge
            self.emit("lost", {"track": name, "t": t, "error": why})
        for name, (_, _, ok) in zip(self.names, mounted):
            if ok and not self.tracked[name]:
                self.emit("found", {"track": name, "t": t, "gap": t - self.lost_at[name],
                                    "restarted": name in step.restarted})
            self.tracked[name] = ok
        self._show(step)
        for name in self.names:
            pending = self.live.pending(name)
            if pending is not None and pending.name != self.shown[name]:
                self.shown[name] = pending.name
                start, end = self._span(pending.start, pending.end)
                self.emit("token", {"track": name, "token": pending.name, "start": start, "end": end, "final": False})

    def close(self) -> dict:
        """Flush at the end of the recording (a track lost for longer than ``max_gap`` at the
        end keeps what was recognised before the loss); returns the whole recording decided
        as ``doodle recognize`` decides it."""
        end = self.times[-1]
        flush = {n: self.tracked[n] or end - self.lost_at[n] <= self.params.max_gap for n in self.names}
        self._show(self.live.close(flush))
        return self.live.result

    def _show(self, step) -> None:
        from grammar.contexter import InteractionSegment, Refused

        for name, tokens in step.tokens.items():
            for token in tokens:
                start, end = self._span(token.start, token.end)
                self.emit("token", {"track": name, "token": token.name, "start": start, "end": end, "final": True})
        for h in list(step.provisional) + step.heard:
            s = h.segment
            start, end = self._span(s.start, s.end)
            if not h.final:  # what the tokens so far say, not decided yet
                self.emit("provisional", {"track": h.track, "action": s.action, "start": start, "end": end,
                                          "exact": s.exact, "distance": s.distance, "at": self.times[-1]})
                continue
            if isinstance(s, Refused):
                self.emit("refused", {"track": h.track, "action": s.refused, "reason": s.reason,
                                      "start": start, "end": end, "at": self.times[-1]})
                continue
            if s.action == "unknown":
                continue
            payload = {"track": h.track, "action": s.action, "start": start, "end": end,
                       "exact": s.exact, "distance": s.distance, "at": self.times[-1]}
            if isinstance(s, InteractionSegment):
                payload.update(interaction=s.interaction, role=s.role)
            else:
                self.actions[h.track].append((s.action, start, end))
            self.emit("action", payload)


class _Behind:
    """:class:`_Live` on a thread of its own, fed the recorded frames in order through a
    queue, so that the recording loop polls the source at its rate whatever recognition
    costs. A live source (SteamVR) gives only the pose of the moment: a frame not polled on
    its tick is a hole in the file, and deciding an action can take a few tenths of a second
    (a learned action's shape compared with the motion's, at a gesture's end). Recognition
    may fall behind for as long — while frames wait, provisional actions are worked out
    only at the newest, so that it catches up soon; the events it emits come from its
    thread, in frame order.
    An exception in it stops the recording at the next frame (:meth:`push` raises it)."""

    def __init__(self, live: _Live):
        import queue
        import threading

        self.live, self.frames, self.error = live, queue.SimpleQueue(), None
        self.thread = threading.Thread(target=self._run, name="doodle-live-recognition", daemon=True)
        self.thread.start()

    def _run(self) -> None:
        while (frame := self.frames.get()) is not None:
            if self.error is None:
                try:  # behind, with frames waiting: their labels are worked out once, at the newest
                    self.live.push(*frame, labels=self.frames.empty())
                except BaseException as e:  # re-raised in the recording loop
                    self.error = e

    @property
    def actions(self) -> dict:
        return self.live.actions

    def push(self, t: float, poses) -> None:
        if self.error is not None:
            raise self.error
        self.frames.put((t, poses))

    def finish(self) -> None:
        """Wait until every frame pushed is recognised and the thread has ended."""
        if self.thread.is_alive():
            self.frames.put(None)
            self.thread.join()

    def close(self) -> dict:
        """:meth:`_Live.close` once every frame is recognised (raises what recognition raised)."""
        self.finish()
        if self.error is not None:
            raise self.error
        return self.live.close()


def record(source, path, *, clock=time.monotonic, sleep=time.sleep, wait_for_trigger: bool = False,
           max_seconds: float | None = None, on_event=None, library_dir=None, use_builtin: bool = True,
           params: SegmenterParams = SegmenterParams(), compiled=None, overwrite: bool = False,
           mounts: dict | None = None, recognise: bool = True) -> RecordResult:
    """Record ``source`` (see :mod:`doodle.input.sources`) into the doodle file ``path``.

    Reads one frame per tick of ``1/source.rate`` seconds on ``clock``, sleeping until each
    tick (a tick missed by more than a period is skipped, not caught up in a burst). With
    ``wait_for_trigger`` the recording starts at the first trigger press and stops at the
    next; otherwise it runs until the source ends, ``max_seconds`` of recording, or Ctrl-C
    (KeyboardInterrupt ends it cleanly). Actions come from the built-in library, extended by
    ``library_dir`` (``compiled``, a compiled library, given instead skips compiling it),
    recognised by the one Recognizer as ``doodle recognize`` does: learned shapes,
    interactions between tracks and behaviour states included; with ``recognise`` False no
    library is read and the tokens alone are shown (nothing to recognise yet). Orientations
    are mounted by the device's profile, or by ``mounts`` (track → device-to-figurine
    quaternion, from calibration) where given, as the file will be read. The caller closes the
    source. The file is created at the first recorded frame; an existing file is refused
    unless ``overwrite``. Raises DoodleError when fewer than two samples were recorded
    (nothing is left on disk then).
    """
    path = Path(path)
    if path.exists() and not overwrite:
        raise DoodleError(f"{path}: already exists (pass --overwrite to replace it)")
    if max_seconds is not None and not (max_seconds > 0 and np.isfinite(max_seconds)):
        raise DoodleError(f"recording length must be a positive number of seconds, not {max_seconds!r}")
    if compiled is None and recognise:
        from grammar.recognizer import load_actions

        compiled = load_actions(library_dir, use_builtin)
    emit = on_event or (lambda kind, payload: None)
    rate = float(source.rate)
    period = 1.0 / rate
    mount = profile(source.device).mount
    names = [name for name, _, _ in source.tracks]
    writer, times, t0, reason = None, [], None, "end"
    # ready before the first frame (compiling its automata takes a tenth of a second or so)
    live = _Behind(_Live(compiled if recognise else None, names, rate, params,
                         [(mounts or {}).get(n, mount) for n in names], emit))
    # What is loaded by now (modules, the library) is never scanned again while recording: a full
    # collection of it stalls every thread for tens of milliseconds, and the source is not polled meanwhile.
    gc.freeze()
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
                    emit("started", {"t": 0.0, "path": str(path), "tracks": names})
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
                live.push(t, frame.poses)
        except KeyboardInterrupt:
            reason = "interrupted"
        result = live.close() if len(times) >= 2 else {}
    finally:
        live.finish()  # nothing left running, whatever ended the recording
        gc.unfreeze()
        if writer is not None:
            writer.close()
    emit("stopped", {"t": times[-1] if times else 0.0, "reason": reason, "samples": len(times)})
    if len(times) < 2:
        if writer is not None:
            path.unlink(missing_ok=True)
        if t0 is None and wait_for_trigger:
            raise DoodleError(f"{path}: the trigger was never pressed; nothing recorded")
        raise DoodleError(f"{path}: recording stopped after {len(times)} sample(s); nothing recorded")
    return RecordResult(path, len(times), times[-1], live.actions, reason, result)
