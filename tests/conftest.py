import copy
import importlib.util
import signal
import sys
from pathlib import Path

import pytest

# The SIGINT handler this process inherited (a shell starts a background job, `nohup` and many
# CI runners with SIGINT ignored), read before fohw is imported: importing fohw as a library
# must leave it as it was (tests/test_cli.py). None if something imported fohw before us.
SIGINT_BEFORE_FOHW = None if "fohw" in sys.modules else signal.getsignal(signal.SIGINT)

import fohw  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
# The literal reference implementations in tests/reference.py (``import reference``).
sys.path.insert(0, str(Path(__file__).resolve().parent))

import dask_service  # noqa: E402


@pytest.fixture
def robot_arm_path():
    """The DaISy robot-arm file shipped inside the package (no skip: it is always there)."""
    return Path(fohw.datasets.robot_arm().path)


@pytest.fixture(scope="session")
def sigint_before_fohw():
    """The SIGINT handler the test process had before it imported fohw."""
    if SIGINT_BEFORE_FOHW is None:
        pytest.fail("fohw was imported before tests/conftest.py: the SIGINT handler the process "
                    "inherited is not known")
    return SIGINT_BEFORE_FOHW


@pytest.fixture(scope="session")
def dask_cluster_options(tmp_path_factory):
    """Keywords for every ``distributed.LocalCluster`` a test starts (see tests/dask_service.py).

    Loopback only, every port picked by the system, scratch files in the session's temporary
    folder. Checked once, by starting a one-worker cluster: if it cannot start, the run stops
    here with one line naming the cause, instead of each dask test failing on its own. Skips
    where distributed (an optional dependency, in the ``test`` extra) is not installed.
    """
    if importlib.util.find_spec("distributed") is None:
        pytest.skip("dask's distributed is not installed")
    options = copy.deepcopy(dask_service.OPTIONS)
    scratch = str(tmp_path_factory.mktemp("dask"))
    options["local_directory"] = options["scheduler_kwargs"]["local_directory"] = scratch
    reason = dask_service.cannot_start(options)
    if reason is not None:
        pytest.exit(f"a dask LocalCluster on 127.0.0.1 cannot start, and the dask tests need one: "
                    f"{reason}", returncode=pytest.ExitCode.TESTS_FAILED)
    return options
