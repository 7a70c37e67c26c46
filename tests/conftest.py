import os
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
# The literal reference implementations in tests/reference.py (``import reference``).
sys.path.insert(0, str(Path(__file__).resolve().parent))


def shared_data_dir() -> Path | None:
    """The folder holding the DaISy robot-arm file: $FOHW_DATA_DIR, else ../shared/data."""
    env = os.environ.get("FOHW_DATA_DIR")
    candidates = [Path(env)] if env else []
    candidates.append(ROOT.parent / "shared" / "data")
    for c in candidates:
        if (c / "daisy_robot_arm.dat").is_file():
            return c
    return None


# Tests and the examples they run read the robot-arm record from $FOHW_DATA_DIR; fall back to
# the shared folder beside the checkout (where CI has it).
if not os.environ.get("FOHW_DATA_DIR") and shared_data_dir() is not None:
    os.environ["FOHW_DATA_DIR"] = str(shared_data_dir())


@pytest.fixture
def robot_arm_path():
    d = shared_data_dir()
    if d is None:
        pytest.skip("robot-arm data not found (set FOHW_DATA_DIR)")
    return d / "daisy_robot_arm.dat"
