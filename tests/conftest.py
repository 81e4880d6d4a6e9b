import os
import shutil
import tempfile
from pathlib import Path

import pytest
from hypothesis import settings

# The disk cache of analysed library clips and automata (doodle.core.cache) goes to a folder
# of this test session, never the home folder: set before any test (or CLI subprocess, which
# inherits it) runs, removed at the end.
CACHE = tempfile.mkdtemp(prefix="doodle-test-cache-")
os.environ["DOODLE_CACHE"] = CACHE
os.environ.pop("DOODLE_NO_CACHE", None)


def pytest_unconfigure(config):
    shutil.rmtree(CACHE, ignore_errors=True)

SHARED = Path(__file__).resolve().parents[1].parent / "shared"
VIVE = SHARED / "data" / "vive-gestures"


@pytest.fixture(scope="session")
def vive_files():
    files = sorted(VIVE.glob("*/*/*.csv"))
    if not files:
        pytest.skip(f"real Vive recordings not found under {VIVE}")
    return files

# Deterministic property tests: the same examples on every run and in CI (set
# HYPOTHESIS_PROFILE=explore to search afresh).
settings.register_profile("deterministic", derandomize=True, database=None)
settings.register_profile("explore", derandomize=False)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "deterministic"))
