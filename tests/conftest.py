import os
from pathlib import Path

import pytest
from hypothesis import settings

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
