"""``fohw.fit(model, data, method=...)``: identify's table of methods behind the one front door.

The lagged kind's identification form (:class:`fohw.ThetaHW`) is fitted by every method of
:func:`fohw.identify`'s table through ``fohw.fit``; the model states the class, the operating
point and the orders' bounds (one statement of each), and the result is the one ``identify``
gives for that class and those bounds, to the bit. Every other kind is refused by name, and
nothing the method cannot honour is ignored.
"""

import warnings

import numpy as np
import pytest

import fohw
from fohw.estimators.identify import METHODS
from fohw.model.base import model_class, registered_kinds

DATA = fohw.datasets.paper_example(300, random_state=3)
CLASS = dict(na=2, nb=2, f_basis=2, g_basis=2)
# The methods whose runs on this record take well under a second each.
FAST = ("varpro", "output_error", "structured", "hybrid", "rls")


@pytest.fixture(scope="module")
def reference():
    """``identify``'s varpro fit with order bounds (0.2, 0.9): its model carries them."""
    return fohw.identify(DATA.u, DATA.y, method="varpro", alpha_bounds=(0.2, 0.9), **CLASS)


def test_the_table_is_what_identify_dispatches():
    assert set(FAST) <= set(METHODS)


@pytest.mark.parametrize("method", FAST)
def test_fit_with_a_method_is_identify_with_the_models_class_and_bounds(reference, method):
    model = reference.model
    assert model.parameters["alpha"].bounds == (0.2, 0.9)
    direct = fohw.identify(DATA.u, DATA.y, method=method, alpha_bounds=(0.2, 0.9), **CLASS)
    through = fohw.fit(model, DATA.u, DATA.y, method=method)
    assert isinstance(through, fohw.IdentificationResult) and isinstance(through, fohw.FitResult)
    assert through.method == method
    np.testing.assert_array_equal(through.theta, direct.theta)
    assert dict(through.orders) == dict(direct.orders)
    assert through.sse == direct.sse and through.status == direct.status
    assert through.model.parameters["alpha"].bounds == (0.2, 0.9)
    assert 0.2 <= through.alpha <= 0.9


def test_the_models_bounds_are_the_ones_the_method_keeps(reference):
    # Bounds that exclude the unconstrained estimate: the method must stop on them.
    free = reference.alpha
    lo, hi = (free + 0.1, free + 0.3)
    params = reference.model.parameters.replace("alpha", value=lo, bounds=(lo, hi))
    fitted = fohw.fit(reference.model.with_parameters(params), DATA.u, DATA.y, method="varpro")
    assert fitted.alpha == pytest.approx(lo, abs=1e-6)
    assert fitted.model.parameters["alpha"].bounds == (lo, hi)
    assert fitted.options["alpha_bounds"] == (lo, hi)       # as identify(alpha_bounds=(lo, hi))


def test_a_record_gives_its_sampling_and_names(reference):
    rec = fohw.Record(u=DATA.u, y=DATA.y, dt=1.0, input_name="pump", output_name="level")
    fitted = fohw.fit(reference.model, rec, method="varpro", options={"n_grid": 21})
    assert fitted.options["n_grid"] == 21
    assert fitted.data["output_name"] == "level"
    other = fohw.Record(u=DATA.u, y=DATA.y, dt=0.5)
    with pytest.raises(fohw.ParameterError, match="dt"):
        fohw.fit(reference.model, other, method="varpro")


OCV = fohw.OCVTable([0.0, 1.0], [3.3, 4.2])
#: One model of every other shipped kind (the test below checks the list is complete).
OTHER_KINDS = {
    "FractionalTF": lambda: fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0], dt=0.05),
    "FractionalHW": lambda: fohw.FractionalHW(
        fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0]), p=[1.0, 0.0], f_basis=2,
        dt=0.05),
    "HammersteinWiener": lambda: fohw.HammersteinWiener([0.1], [0.5, 0.1], [1.0, 0.0], [1.0],
                                                        0.6),
    "EquivalentCircuit": lambda: fohw.EquivalentCircuit(["zarc"], ocv=OCV),
    "CircuitTables": lambda: fohw.CircuitTables(["zarc"], soc_points=[0.3, 0.7],
                                                temperature_points=[5.0, 35.0], ocv=OCV),
}


def test_the_list_of_other_kinds_is_every_shipped_kind_but_theta_hw():
    shipped = {k for k in registered_kinds() if model_class(k).__module__.startswith("fohw.")}
    assert "FractionalTF" in shipped and shipped - {"ThetaHW"} == set(OTHER_KINDS)


@pytest.mark.parametrize("kind", sorted(OTHER_KINDS))
def test_every_other_kind_is_sent_to_the_engine(kind):
    model = OTHER_KINDS[kind]()
    assert type(model).__name__ == kind
    with pytest.raises(fohw.ParameterError, match=rf"a {kind} is fitted by the engine"):
        fohw.fit(model, DATA.u, DATA.y, method="varpro")


@pytest.mark.parametrize("change, match", [
    (lambda p: p.replace("a1", fixed=True), "'a1' is fixed"),
    (lambda p: p.replace("b1", bounds=(-5.0, 5.0)), "'b1' is bounded"),
    (lambda p: p.replace("alpha", fixed=True), "order 'alpha' is fixed"),
])
def test_what_a_method_cannot_honour_is_refused_by_name(reference, change, match):
    model = reference.model.with_parameters(change(reference.model.parameters))
    with pytest.raises(fohw.ParameterError, match=match):
        fohw.fit(model, DATA.u, DATA.y, method="varpro")
    with warnings.catch_warnings():                      # a short run: only that it is taken
        warnings.simplefilter("ignore", fohw.ConvergenceWarning)
        fohw.fit(model, DATA.u, DATA.y, max_nfev=5, order_grid=1, n_starts=1)


@pytest.mark.parametrize("kwargs, match", [
    (dict(method="varpro", n_starts=5), r"\['n_starts'\] are the engine's settings"),
    (dict(method="varpro", max_nfev=10, order_grid=2), r"\['max_nfev', 'order_grid'\]"),
    (dict(method="no_such_method"), "`method` must be None"),
    (dict(options={"n_grid": 5}), "`options` are a method's"),
    (dict(method="varpro", options={"no_such_option": 1}), "no_such_option"),
])
def test_settings_for_the_other_path_are_refused(reference, kwargs, match):
    with pytest.raises(fohw.ParameterError, match=match):
        fohw.fit(reference.model, DATA.u, DATA.y, **kwargs)
