"""Live recognition cost during replay: processing time per 90 Hz frame for two
tracks (streaming Segmenter + Matcher), p50 and p99 (target p99 ≤ 1 ms), beside the
Segmenter alone in the same run; and how long after a gesture ends it is recognised."""

from pathlib import Path

import numpy as np

from doodle.input.loader import load
from doodle.core.model import Doodle, Track
from grammar.recognizer import load_actions
from doodle.app.replay import replay

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


def main() -> None:
    doodle = _long_two_tracks(load(DEMO))
    replayed = replay(doodle, load_actions())
    found, costs = replayed.found, replayed.costs
    seg_only = _segmenter_only(doodle)
    print(f"Replay: {doodle.t[-1]:.0f} s, 2 tracks at {doodle.rate:g} Hz, {len(found)} actions recognised")
    print(f"  per frame, the Recognizer:      p50 {np.percentile(costs, 50) * 1e3:.3f} ms, "
          f"p99 {np.percentile(costs, 99) * 1e3:.3f} ms, max {costs.max() * 1e3:.2f} ms   (target p99 ≤ 1 ms)")
    print(f"  baseline, Segmenter alone:      p50 {np.percentile(seg_only, 50) * 1e3:.3f} ms, "
          f"p99 {np.percentile(seg_only, 99) * 1e3:.3f} ms")
    lat = np.array([r.latency for r in found])
    print(f"  recognised after the gesture ends: median {np.median(lat):.2f} s, p90 {np.percentile(lat, 90):.2f} s "
          "(the Matcher waits until every live continuation agrees)")


def _segmenter_only(doodle) -> np.ndarray:
    import time

    from doodle.input.segmenter import Segmenter

    segs = [Segmenter(doodle.rate, name=tr.name) for tr in doodle.tracks]
    costs = np.empty(len(doodle.t))
    for i, now in enumerate(doodle.t):
        tick = time.perf_counter()
        for s, tr in zip(segs, doodle.tracks):
            s.push(now, tr.p[i], tr.q[i], True)
        costs[i] = time.perf_counter() - tick
    return costs


if __name__ == "__main__":
    main()
