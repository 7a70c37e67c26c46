"""fohw: identification of fractional-order Hammerstein–Wiener systems.

Implements Zhang, Wang & Liu (2022), "Hybrid identification method for fractional-order
nonlinear systems based on the multi-innovation principle": the Grünwald–Letnikov difference,
the discrete fractional-order Hammerstein–Wiener model and its simulator, the information
matrix, and the paper's estimators.
"""

# _startup first ("_" sorts first): for the `fohw` command only, Ctrl-C while importing is one
# line and status 130.
from . import _startup, datasets  # noqa: F401
from .analysis.batch import identify_many, stream_fits
from .analysis.crb import crb
from .analysis.lrtest import LRTest, lr_test, order_test
from .analysis.montecarlo import monte_carlo
from .analysis.profile_interval import ProfileInterval, profile_interval
from .analysis.selection import Selection, select_structure
from .analysis.validation import Validation, compare
from .estimators.fit import fit
from .estimators.frequency_fit import fit_frequency_response
from .estimators.identify import identify
from .exceptions import (
    ConvergenceWarning,
    DataFileError,
    DataWarning,
    DimensionError,
    EstimationDivergedError,
    ExtrapolationWarning,
    FohwError,
    NotFittedError,
    NothingSelectedWarning,
    ParameterError,
    RankDeficiencyWarning,
    SimulationDivergedError,
)
from .fit_result import FitResult
from .frequency_plots import bode, nyquist
from .io.jsonio import load_model, load_result, save_model, save_result
from .io.text import read_record
from .model.base import Model, register_model
from .model.basis import Basis, polynomial_basis
from .model.circuit import RC, ZARC, EquivalentCircuit, OCVTable, Warburg
from .model.circuit_tables import CircuitTables
from .model.gl import gl_difference, gl_weights
from .model.lagged.initial import InitialState, initial_state
from .model.lagged.structure import Structure
from .model.lagged.system import HammersteinWiener
from .model.lagged.theta_hw import ThetaHW
from .model.orders import Orders
from .model.parameters import Parameter, Parameters
from .model.simulate import simulate
from .model.transfer import FractionalTF
from .model.wiener import FractionalHW
from .record import Record
from .results import IdentificationResult, Status


def _installed_version():
    """The version of the installed distribution (pyproject.toml is the one place it is written).

    From a source tree that was never installed (``PYTHONPATH=src``) there is no distribution
    metadata; the version is then ``"0+unknown"`` (a valid PEP 440 version that sorts below every
    release) rather than a number that could be stale.
    """
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("fohw")
    except PackageNotFoundError:
        return "0+unknown"


def __getattr__(name):
    # The version is read from the distribution's metadata when first asked for, not at
    # `import fohw` (importlib.metadata and the lookup cost about 40 ms: benchmarks/bench_import.py).
    if name == "__version__":
        globals()["__version__"] = version = _installed_version()
        return version
    raise AttributeError(f"module 'fohw' has no attribute {name!r}")

__all__ = [
    "Model",
    "Parameter",
    "Parameters",
    "register_model",
    "fit",
    "fit_frequency_response",
    "FitResult",
    "bode",
    "nyquist",
    "identify_many",
    "stream_fits",
    "Validation",
    "compare",
    "read_record",
    "Selection",
    "select_structure",
    "Basis",
    "ConvergenceWarning",
    "NothingSelectedWarning",
    "DataWarning",
    "DataFileError",
    "DimensionError",
    "EstimationDivergedError",
    "FohwError",
    "HammersteinWiener",
    "ThetaHW",
    "IdentificationResult",
    "Record",
    "NotFittedError",
    "Orders",
    "ParameterError",
    "ExtrapolationWarning",
    "RankDeficiencyWarning",
    "SimulationDivergedError",
    "Status",
    "Structure",
    "crb",
    "datasets",
    "gl_difference",
    "gl_weights",
    "identify",
    "load_model",
    "load_result",
    "monte_carlo",
    "save_model",
    "save_result",
    "polynomial_basis",
    "simulate",
    "InitialState",
    "initial_state",
    "FractionalTF",
    "LRTest",
    "lr_test",
    "order_test",
    "ProfileInterval",
    "profile_interval",
    "FractionalHW",
    # battery cells: the fractional equivalent circuit
    "EquivalentCircuit",
    "OCVTable",
    "RC",
    "ZARC",
    "Warburg",
    "CircuitTables",
]
