"""fohw: identification of fractional-order Hammerstein–Wiener systems.

Implements Zhang, Wang & Liu (2022), "Hybrid identification method for fractional-order
nonlinear systems based on the multi-innovation principle": the Grünwald–Letnikov difference,
the discrete fractional-order Hammerstein–Wiener model and its simulator, the information
matrix, and the paper's estimators.
"""

from . import datasets
from .analysis import metrics
from .analysis.batch import identify_many
from .analysis.crb import CRBResult, crb
from .analysis.montecarlo import monte_carlo
from .analysis.selection import Selection, select_structure
from .analysis.validation import Validation, compare
from .estimators.hybrid import (
    HybridIdentifier,
    HybridOptions,
    SingleInnovationGradientOptions,
    SingleInnovationLMOptions,
)
from .estimators.identify import identify
from .estimators.migd import MultiInnovationGradient
from .estimators.output_error import OutputErrorOptions
from .estimators.rls import MultiInnovationRLS, RlsOptions
from .estimators.structured import StructuredOptions
from .estimators.tf_fit import FractionalTFFit, fit_fractional_tf
from .estimators.varpro import VarproOptions
from .exceptions import (
    ConvergenceWarning,
    DataFileError,
    DataWarning,
    DimensionError,
    EstimationDivergedError,
    ExtrapolationWarning,
    FohwError,
    NotFittedError,
    ParameterError,
    RankDeficiencyWarning,
    SimulationDivergedError,
)
from .io.jsonio import load_model, load_result, save_model
from .io.text import read_record
from .model.basis import Basis, as_basis, polynomial_basis
from .model.fotf import FractionalTF
from .model.gl import gl_difference, gl_weights, gl_weights_derivative
from .model.orders import Orders
from .model.params import ThetaLayout
from .model.regressors import RegressorBuilder, information_matrix
from .model.structure import Structure
from .model.system import HammersteinWiener, simulate, simulate_parameters, simulate_theta
from .record import Benchmark, Record
from .results import IdentificationResult, Status

__version__ = "0.1.0.dev0"


def _keep_old_module_paths():
    """``import fohw.migd``, ``from fohw.metrics import rmse``, … as in fohw 0.1.

    The modules moved into subpackages (``fohw.estimators.migd``, ``fohw.analysis.metrics``);
    their old dotted paths stay importable and reachable as attributes.
    """
    import sys

    from .analysis import crb, montecarlo
    from .estimators import baselines, migd, milm, output_error, rls, varpro
    from .io import cli
    from .model import basis, gl, params, regressors, system
    from .paper import reproduction

    moved = dict(gl=gl, basis=basis, params=params, system=system, regressors=regressors,
                 migd=migd, milm=milm, varpro=varpro, output_error=output_error, rls=rls,
                 baselines=baselines, crb=crb, metrics=metrics,
                 montecarlo=montecarlo, reproduction=reproduction, cli=cli)
    for old, module in moved.items():
        sys.modules.setdefault(f"{__name__}.{old}", module)
        globals().setdefault(old, module)


_keep_old_module_paths()

__all__ = [
    "identify_many",
    "Validation",
    "compare",
    "read_record",
    "Selection",
    "select_structure",
    "Basis",
    "CRBResult",
    "ConvergenceWarning",
    "DataWarning",
    "DataFileError",
    "DimensionError",
    "EstimationDivergedError",
    "FohwError",
    "HammersteinWiener",
    "HybridIdentifier",
    "HybridOptions",
    "IdentificationResult",
    "Record",
    "Benchmark",
    "MultiInnovationGradient",
    "MultiInnovationRLS",
    "NotFittedError",
    "Orders",
    "OutputErrorOptions",
    "ParameterError",
    "ExtrapolationWarning",
    "RankDeficiencyWarning",
    "RegressorBuilder",
    "RlsOptions",
    "StructuredOptions",
    "SingleInnovationGradientOptions",
    "SingleInnovationLMOptions",
    "SimulationDivergedError",
    "Status",
    "Structure",
    "ThetaLayout",
    "VarproOptions",
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
    "simulate_parameters",
    "FractionalTF",
    "FractionalTFFit",
    "fit_fractional_tf",
]
