"""Every benchmark module imports (``make bench`` is not run by CI, so a syntax error in one
would otherwise land unnoticed); none is run here."""

import importlib
import pkgutil
from pathlib import Path

import pytest

BENCH = Path(__file__).resolve().parents[1] / "bench"


@pytest.mark.parametrize("name", sorted(m.name for m in pkgutil.iter_modules([str(BENCH)])))
def test_benchmark_module_imports(name):
    module = importlib.import_module(f"bench.{name}")
    assert name in ("__main__", "timing") or callable(getattr(module, "main", None))


def test_a_childs_peak_memory_is_its_own_not_its_parents():
    """``bench.long_doodles`` reads a child's peak resident memory from the child itself:
    Linux's ``ru_maxrss`` of a child keeps its parent's resident size at the fork, and inside
    ``python -m bench`` (grown to 2 GB) it read 2 GB for a 60 s doodle."""
    import os
    import sys

    import numpy as np

    from bench.long_doodles import run_child

    ballast = np.ones(40_000_000)  # 320 MB resident in this process while the child forks
    _, peak = run_child([sys.executable, "-m", "timeit", "-n", "1", "pass"], dict(os.environ))
    assert ballast[-1] == 1.0 and peak < 100.0
