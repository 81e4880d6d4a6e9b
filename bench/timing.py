"""The one timer the benchmarks share."""

import time


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
