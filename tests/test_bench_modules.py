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
