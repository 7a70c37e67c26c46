import sys
from pathlib import Path

import pytest

import fohw

ROOT = Path(__file__).resolve().parents[1]
# The literal reference implementations in tests/reference.py (``import reference``).
sys.path.insert(0, str(Path(__file__).resolve().parent))


@pytest.fixture
def robot_arm_path():
    """The DaISy robot-arm file shipped inside the package (no skip: it is always there)."""
    return Path(fohw.datasets.robot_arm().path)
