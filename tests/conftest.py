from pathlib import Path

import pytest

SHARED = Path(__file__).resolve().parents[1].parent / "shared"
VIVE = SHARED / "data" / "vive-gestures"


@pytest.fixture(scope="session")
def vive_files():
    files = sorted(VIVE.glob("*/*/*.csv"))
    if not files:
        pytest.skip(f"real Vive recordings not found under {VIVE}")
    return files
