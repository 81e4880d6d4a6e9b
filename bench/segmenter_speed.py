"""Segmenter speed: batch tokenisation of one hour at 90 Hz, and streaming push per sample.

Baselines (the floor) measured in the same run over the same arrays:
* batch — one plain numpy pass: per-sample displacement norms ``‖p_i − p_{i−1}‖``;
* streaming — a Python loop that only hands each sample to a function doing one small
  numpy operation (a 3-vector difference), i.e. the cost of touching each sample.
"""

import time

import numpy as np

from doodle.input.segmenter import Segmenter, tokenize
from doodle.synth.strokes import stroke, synth_track

HOUR = 3600.0
RATE = 90.0
TOKENS = ["T_Z", "T_STILL", "T_X", "T_N_Z", "R_Y", "T_Y", "T_N_Y", "T_N_X_Y", "R_N_Z", "T_Y_Z"]


def hour_track():
    strokes = [stroke(TOKENS[i % len(TOKENS)], 0.5) for i in range(int(HOUR / 0.5))]
    return synth_track(strokes, rate=RATE, seed=0)[0]


def best_of(fn, repeat=3):
    times = []
    for _ in range(repeat):
        start = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - start)
    return min(times), result


def main() -> None:
    track = hour_track()
    n = len(track)
    print(f"Segmenter speed ({n:,} samples = {track.t[-1] / 3600:.2f} h at {RATE:g} Hz, one track)")

    floor, _ = best_of(lambda: np.linalg.norm(np.diff(track.p, axis=0), axis=1))
    batch, tokens = best_of(lambda: tokenize(track, RATE))
    print(f"  batch tokenize:        {batch:8.3f} s   ({len(tokens):,} tokens; target ≤ 1 s)")
    print(f"  floor, one numpy pass: {floor:8.3f} s   ({batch / floor:.0f}× the floor)")

    m = 60_000
    t, p, q = track.t[:m].tolist(), track.p[:m], track.q[:m]
    seg = Segmenter(RATE)
    costs = np.empty(m)
    clock = time.perf_counter
    for i in range(m):
        start = clock()
        seg.push(t[i], p[i], q[i])
        costs[i] = clock() - start
    seg.close()
    prev = np.zeros(3)
    floor_costs = np.empty(m)
    for i in range(m):
        start = clock()
        prev = p[i] - prev
        floor_costs[i] = clock() - start
    us = costs * 1e6
    fl = floor_costs * 1e6
    print(f"  streaming push:        mean {us.mean():6.1f} µs   p50 {np.percentile(us, 50):6.1f} µs   "
          f"p99 {np.percentile(us, 99):6.1f} µs   (targets: mean ≤ 20, p99 ≤ 100; over {m:,} pushes)")
    print(f"  floor, one numpy op:   mean {fl.mean():6.1f} µs   p50 {np.percentile(fl, 50):6.1f} µs   "
          f"p99 {np.percentile(fl, 99):6.1f} µs")


if __name__ == "__main__":
    main()
