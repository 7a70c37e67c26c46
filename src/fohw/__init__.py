"""fohw: identification of fractional-order Hammerstein–Wiener systems.

Implements Zhang, Wang & Liu (2022), "Hybrid identification method for fractional-order
nonlinear systems based on the multi-innovation principle": the Grünwald–Letnikov difference,
the discrete fractional-order Hammerstein–Wiener model and its simulator, the information
matrix, and the paper's estimators.
"""

from . import datasets, metrics
from .basis import Basis, as_basis, polynomial_basis
from .crb import CRBResult, crb
from .driver import HybridIdentifier, identify
from .exceptions import (
    ConvergenceWarning,
    DataFileError,
    DimensionError,
    FohwError,
    NotFittedError,
    ParameterError,
    SimulationDivergedError,
)
from .gl import gl_difference, gl_weights, gl_weights_derivative
from .io import load_model, load_result, save_model
from .migd import MultiInnovationGradient
from .montecarlo import monte_carlo
from .params import ThetaLayout
from .regressors import RegressorBuilder, information_matrix
from .results import IdentificationResult
from .rls import MultiInnovationRLS
from .system import HammersteinWiener, simulate, simulate_theta

__version__ = "0.1.0.dev0"

__all__ = [
    "Basis",
    "CRBResult",
    "ConvergenceWarning",
    "DataFileError",
    "DimensionError",
    "FohwError",
    "HammersteinWiener",
    "HybridIdentifier",
    "IdentificationResult",
    "MultiInnovationGradient",
    "MultiInnovationRLS",
    "NotFittedError",
    "ParameterError",
    "RegressorBuilder",
    "SimulationDivergedError",
    "ThetaLayout",
    "as_basis",
    "crb",
    "datasets",
    "metrics",
    "gl_difference",
    "gl_weights",
    "gl_weights_derivative",
    "identify",
    "information_matrix",
    "load_model",
    "load_result",
    "monte_carlo",
    "save_model",
    "polynomial_basis",
    "simulate",
    "simulate_theta",
]
