"""Live recognition during replay: how long after a gesture ends its name is on screen, and
what each frame costs.

* Latency: for every final action, how long after the gesture's last sample the stream had
  decided it (final), and how long until its name was first shown, provisional or final
  (:class:`grammar.recognizer.Live`: provisional as soon as the tokens so far decide it, if
  what the Segmenter still holds back stands) — median and p90 (target provisional ≤ 0.3 s),
  over the actions that end a movement (a pause, Idle, is not one: it is named once it is a
  pause whatever follows).
  Beside it, how often a provisional name was the one decided: of the provisional labels
  whose samples a final action covers, the share naming that action.
* On the demo (seven times over, two tracks) with the built-in library, and on the real
  Vive recordings when ``../shared/data`` is there: per user, a library learned from ex_0..2
  of every gesture (``doodle learn``'s function, c0), and the held-out ex_3, ex_4 of every
  gesture streamed one after another with an idle stretch between them (the live case) —
  read with that library alone and with the built-in actions beside it, and back to back
  (no pause between gestures, where a gesture ends where the next begins) with the
  built-in actions, and those once more at real speed on the clock a performer watches
  (:class:`RealTime`: the time recognition takes counted, as ``doodle replay --speed 1``
  shows it); and two
  performers of built-in actions, one per track (``bench.performers``' two-performer
  scenes), beside two users' gestures learned with both hands — where a built-in segment
  waits for what the other hand's Matcher reads, and the other hand's for the two-handed
  actions' track.
  Where a gesture ends: :func:`doodle.app.replay.latencies`.
* Recording at pace: ``doodle record``'s loop (:func:`doodle.app.recorder.record`) fed by a
  source that, like SteamVR, gives only the pose of the moment — a real user's held-out
  gestures back to back, read with their learned library and the built-in actions (where
  deciding an action takes longest) — for :data:`PACE_SECONDS` on the real clock: how often
  a poll came more than a period late, the longest wait between polls and the samples the
  file lacks; beside the floor, the same recording with recognition off.
* Cost per 90 Hz frame on the demo (Segmenter, Matcher, provisional labels), CPU time of
  the thread: p50 and p99 (target p99 ≤ 1 ms), beside the same without provisional labels
  and the Segmenter alone in the same run; and the wall-clock time replay measures.
"""

import tempfile
import time
from pathlib import Path

import numpy as np

from bench.timing import cpu_per_frame
from doodle.app.replay import latencies, replay
from doodle.core.model import Doodle, Track
from doodle.input.loader import load
from doodle.input.sources import SyntheticSource
from grammar.recognizer import load_actions

DEMO = Path(__file__).resolve().parents[1] / "examples" / "demo.doodle"


def _long_two_tracks(doodle, repeats=7) -> Doodle:
    tr = doodle.tracks[0]
    n = len(tr.t)
    step = tr.t[-1] + 1.0 / doodle.rate
    t = np.concatenate([tr.t + k * step for k in range(repeats)])
    p = np.concatenate([tr.p + [0.0, 0.0, 0.0] for _ in range(repeats)])
    q = np.concatenate([tr.q] * repeats)
    valid = np.ones(n * repeats, dtype=bool)
    return Doodle((Track("c0", t, p, q, valid), Track("c1", t.copy(), p + 1.0, q.copy(), valid.copy())), doodle.rate)


def report(label: str, lines: list) -> None:
    final = np.concatenate([d.final for d in lines])
    named = np.concatenate([d.named for d in lines])
    agree = [a for d in lines for a in d.agree]
    covered = [a for a in agree if a is not None]
    pauses = sum(d.pauses for d in lines)
    print(f"  {label}: {len(final)} actions ending a movement"
          + (f" (and {pauses} pauses, Idle, not counted)" if pauses else ""))
    print(f"    name shown after the gesture ends (provisional or final): median {np.median(named):.2f} s, "
          f"p90 {np.percentile(named, 90):.2f} s   (target ≤ 0.3 s)")
    print(f"    decided (final):                                          median {np.median(final):.2f} s, "
          f"p90 {np.percentile(final, 90):.2f} s")
    print(f"    provisional labels: {len(agree)}; of the {len(covered)} a final action covers, "
          f"{np.mean(covered) if covered else 0:.0%} name it ({len(agree) - len(covered)} over what ends unknown)")


def main() -> None:
    doodle = _long_two_tracks(load(DEMO))
    compiled = load_actions()
    replayed = replay(doodle, compiled)
    costs = replayed.costs
    with_labels, without = cpu_per_frame(doodle, compiled, True), cpu_per_frame(doodle, compiled, False)
    seg_only = _segmenter_only(doodle)
    print(f"Replay: {doodle.t[-1]:.0f} s, 2 tracks at {doodle.rate:g} Hz, {len(replayed.found)} actions recognised")
    print(f"  per frame, CPU time:  the Recognizer  p50 {np.percentile(with_labels, 50) * 1e3:.3f} ms, "
          f"p99 {np.percentile(with_labels, 99) * 1e3:.3f} ms, max {with_labels.max() * 1e3:.2f} ms   (target p99 ≤ 1 ms)")
    print(f"    without provisional labels      p50 {np.percentile(without, 50) * 1e3:.3f} ms, "
          f"p99 {np.percentile(without, 99) * 1e3:.3f} ms")
    print(f"    baseline, the Segmenter alone   p50 {np.percentile(seg_only, 50) * 1e3:.3f} ms, "
          f"p99 {np.percentile(seg_only, 99) * 1e3:.3f} ms")
    print(f"    wall-clock, as replay measures it: p50 {np.percentile(costs, 50) * 1e3:.3f} ms, "
          f"p99 {np.percentile(costs, 99) * 1e3:.3f} ms (a shared machine adds other jobs' time)")
    report("the demo, built-in library", [latencies(doodle, replayed)])
    _real()


def _real() -> None:
    from bench.learning_protocol import ROOT, load as load_vive, make_library, stream

    if not sorted(ROOT.glob("*/*/*.csv")):
        print(f"  real recordings: no data under {ROOT}")
        return
    data = load_vive()
    users = sorted(data)
    rng, lines, joined, order = np.random.default_rng(0), {False: [], True: []}, [], np.random.default_rng(1)
    watched = []
    with tempfile.TemporaryDirectory() as tmp:
        for user in users:
            classes = sorted(data[user])
            folder = make_library(Path(tmp) / user, {g: data[user][g][:3] for g in classes}, ("c0",))
            pieces = [(g, d.select(["c0"])) for g in classes for d in data[user][g][3:5]]
            doodle, _ = stream(pieces, rng, idle=True)
            for builtin, into in lines.items():
                into.append(latencies(doodle, replay(doodle, load_actions(folder, builtin))))
            doodle, _ = stream(pieces, order, idle=False)
            joined.append(latencies(doodle, replay(doodle, load_actions(folder, True))))
            watched.append(at_real_time(doodle, load_actions(folder, True)))
    report(f"real recordings, {len(users)} users' held-out gestures streamed, each user's learned library (c0)",
           lines[False])
    report("the same, with the built-in actions beside the learned ones (`--library DIR`, the default)", lines[True])
    report("the same gestures back to back, no pause between (a gesture ends where the next begins), with the "
           "built-in actions: a learned segment waits for the pause that ends its motion, or 40 tokens", joined)
    report("the same at real speed, on the clock a performer watches (the time recognition takes counted: "
           "`doodle replay --speed 1`, RealTime)", watched)
    _two_performers(data)
    _recording_pace(data)


def _two_performers(data, users=("Sub_U001", "Sub_U007")) -> None:
    """Two characters each playing built-in actions (one per track, generated performers:
    ``bench.performers``' two-performer scenes, every other one) read live beside a user's
    gestures learned with both hands: a built-in segment waits for what the other hand's
    Matcher reads, and the other hand's segments for the two-handed actions' track."""
    from bench.learning_protocol import make_library
    from bench.performers import two_performer_scenes
    from doodle.synth.performers import perform_two

    lines = []
    with tempfile.TemporaryDirectory() as tmp:
        for user in users:
            classes = sorted(data[user])
            compiled = load_actions(make_library(Path(tmp) / user, {g: data[user][g][:3] for g in classes},
                                                 ("c0", "c1")), True)
            for first, second, style, seed in two_performer_scenes()[::2]:
                doodle = perform_two(first, second, style, seed)
                lines.append(latencies(doodle, replay(doodle, compiled)))
    report(f"two performers of built-in actions, beside {' and '.join(u.replace('Sub_', '') for u in users)}'s "
           "gestures learned with both hands (c0+c1)", lines)


class RealTime:
    """A clock for :func:`doodle.app.replay.replay` at speed 1 without its waits: the time
    the replay's own work took plus the sleeps it asked for. On it a replay falls behind
    the performance, and catches up, exactly as at real speed, in a fraction of the time."""

    def __init__(self):
        self.slept, self.start = 0.0, None  # from the first reading (the replay's start) on

    def __call__(self) -> float:
        now = time.perf_counter()
        self.start = now if self.start is None else self.start
        return now - self.start + self.slept

    def sleep(self, seconds: float) -> None:
        self.slept += max(seconds, 0.0)


def at_real_time(doodle, compiled):
    """:func:`doodle.app.replay.latencies` with each name at the time it was shown on the
    :class:`RealTime` clock of a replay at speed 1 (stream time plus how far recognition
    had fallen behind), not at the frame's stream time."""
    from dataclasses import replace

    from doodle.app.replay import Replayed

    clock, shown = RealTime(), {}
    replayed = replay(doodle, compiled, speed=1.0, clock=clock, sleep=clock.sleep,
                      on_action=lambda r: shown.setdefault(id(r), clock()))
    seen = lambda rs: [replace(r, at=shown[id(r)]) for r in rs]  # noqa: E731
    return latencies(doodle, Replayed(seen(replayed.found), replayed.costs, replayed.result, seen(replayed.provisional)))


PACE_SECONDS = 15.0


class OfTheMoment(SyntheticSource):
    """A doodle's sample at the current time on the real clock — as SteamVR gives poses: a
    sample not read on its tick is never read — up to its ``samples``-th; the times it was
    polled at in ``polls``."""

    def __init__(self, doodle, samples: int):
        super().__init__(doodle)
        self.samples, self.start, self.polls = samples, None, []

    def read(self):
        now = time.monotonic()
        self.start = now if self.start is None else self.start
        self.polls.append(now)
        self._i = int((now - self.start) * self.rate)
        return super().read() if self._i < self.samples else None


def _recording_pace(data) -> None:
    from bench.learning_protocol import make_library, stream
    from doodle.app.recorder import record

    user = sorted(data)[min(2, len(data) - 1)]
    classes = sorted(data[user])
    print(f"  recording at pace, {PACE_SECONDS:g} s on the real clock ({user}'s held-out gestures back to back, "
          f"learned library and built-in actions; a pose source of the moment, as SteamVR):")
    with tempfile.TemporaryDirectory() as tmp:
        folder = make_library(Path(tmp) / user, {g: data[user][g][:3] for g in classes}, ("c0",))
        doodle, _ = stream([(g, d.select(["c0"])) for g in classes for d in data[user][g][3:5]],
                           np.random.default_rng(0), idle=False)
        compiled = load_actions(folder, True)
        for label, recognise in (("recognising", True), ("floor, recognition off", False)):
            source = OfTheMoment(doodle, int(PACE_SECONDS * doodle.rate))
            result = record(source, Path(tmp) / f"{recognise}.doodle", compiled=compiled, recognise=recognise)
            waits = np.diff(source.polls[1:])  # from the first frame's poll on
            expected = int(PACE_SECONDS * doodle.rate)
            late = int((waits > 2 / doodle.rate).sum())
            print(f"    {label:<24} polls more than a period late {late:3d}, longest wait {waits.max() * 1e3:5.1f} ms; "
                  f"samples {result.samples} of {expected}")


def _segmenter_only(doodle) -> np.ndarray:
    from doodle.input.segmenter import Segmenter

    segs = [Segmenter(doodle.rate, name=tr.name) for tr in doodle.tracks]
    costs = np.empty(len(doodle.t))
    for i, now in enumerate(doodle.t):
        tick = time.thread_time()
        for s, tr in zip(segs, doodle.tracks):
            s.push(now, tr.p[i], tr.q[i], True)
        costs[i] = time.thread_time() - tick
    return costs


if __name__ == "__main__":
    main()
