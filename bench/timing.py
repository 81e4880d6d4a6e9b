"""The timers the benchmarks share."""

import time

import numpy as np


def best_of(fn, runs: int = 3, warm: bool = False) -> float:
    """Seconds of the fastest of ``runs`` calls of ``fn`` (after one untimed call if ``warm``)."""
    if warm:
        fn()
    best = float("inf")
    for _ in range(runs):
        start = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - start)
    return best


def cpu_per_frame(doodle, compiled, provisional: bool = True, automata: dict | None = None) -> np.ndarray:
    """Seconds of CPU time (this thread) per frame of ``doodle`` streamed through the live
    Recognizer as ``doodle replay`` streams it (on a shared machine, wall-clock time adds
    other jobs' time slices to some frames)."""
    from grammar.recognizer import Live

    live = Live(compiled, doodle.names, doodle.rate, automata=automata, provisional=provisional)
    costs = np.empty(len(doodle.t))
    for i, now in enumerate(doodle.t):
        tick = time.thread_time()
        live.push(float(now), [(tr.p[i], tr.q[i], bool(tr.valid[i])) for tr in doodle.tracks])
        costs[i] = time.thread_time() - tick
    live.close()
    return costs
