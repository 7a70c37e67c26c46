"""fohw.CircuitTables: a circuit whose parameters are tables over state of charge and temperature.

The model before any estimator (STYLE 12): the simulator against a literal per-sample loop with
its own interpolation, the constant-table case against fohw.EquivalentCircuit, the Jacobian
against central differences; then the smoothing penalty and the fit that uses it; then the
PyBaMM pulse records it is meant for.
"""

import math
import warnings

import numpy as np
import pytest

import fohw
from fohw.model.circuit_tables import R_MIN, table_weights, varying_solve

SOC_POINTS = [0.3, 0.5, 0.8]
T_POINTS = [0.0, 25.0, 45.0]
OCV = fohw.OCVTable([0.0, 1.0], [3.3, 4.2])


def _model(**kw):
    rng = np.random.default_rng(5)
    values = {"a": rng.uniform(-0.01, 0.01, (3, 3)), "R0": rng.uniform(0.01, 0.04, (3, 3)),
              "R1": rng.uniform(0.002, 0.01, (3, 3)), "tau1": rng.uniform(1.0, 5.0, (3, 3)),
              "R2": rng.uniform(0.005, 0.02, (3, 3)), "tau2": rng.uniform(20.0, 80.0, (3, 3)),
              "alpha2": 0.6}
    return fohw.CircuitTables(["rc", "zarc"], soc_points=SOC_POINTS, temperature_points=T_POINTS,
                              values=values, ocv=OCV, dt=0.5, tau_bounds=(0.5, 500.0), **kw)


def _record(n=600, seed=0):
    rng = np.random.default_rng(seed)
    i = np.repeat(rng.uniform(-5.0, 5.0, n // 20), 20)
    soc = np.linspace(0.2, 0.9, n)          # beyond both ends of the table
    temp = np.linspace(-5.0, 50.0, n)       # and of the temperatures
    return np.column_stack([i, soc, temp])


def _interp1(x, points, values):
    """Linear interpolation, end values held: written out per sample."""
    if x <= points[0]:
        return values[0]
    if x >= points[-1]:
        return values[-1]
    j = max(k for k in range(len(points) - 1) if points[k] <= x)
    t = (x - points[j]) / (points[j + 1] - points[j])
    return (1 - t) * values[j] + t * values[j + 1]


def _bilinear(s, t, table):
    rows = [_interp1(t, T_POINTS, table[k]) for k in range(len(SOC_POINTS))]
    return _interp1(s, SOC_POINTS, rows)


def _literal(model, u):
    """The circuit sample by sample: interpolated values, then the implicit GL recursions."""
    n = u.shape[0]
    v = np.zeros(n)
    z = {1: np.zeros(n), 2: np.zeros(n)}
    alpha = {1: 1.0, 2: model.alphas["alpha2"]}
    beta = {e: fohw.gl_weights(alpha[e], n) for e in (1, 2)}
    for k in range(n):
        i, s, t = u[k]
        p = {name: _bilinear(s, t, model.table(name)) for name in model.tables}
        v[k] = OCV(s) + p["a"] + p["R0"] * i
        for e in (1, 2):
            r = (p[f"tau{e}"] / model.dt) ** alpha[e]
            memory = sum(beta[e][j] * z[e][k - j] for j in range(1, k + 1))
            z[e][k] = (i - r * memory) / (1 + r)
            v[k] += p[f"R{e}"] * z[e][k]
    return v


def test_simulate_against_a_literal_loop():
    model, u = _model(), _record()
    np.testing.assert_allclose(model.simulate(u), _literal(model, u), rtol=0, atol=1e-13)


def test_constant_tables_are_the_equivalent_circuit():
    # A record at one (soc, T) inside the table: every table is one number there.
    model = _model()
    u = _record()
    u[:, 1], u[:, 2] = 0.4, 30.0
    w = table_weights(u[:1, 1], u[:1, 2], np.array(SOC_POINTS), np.array(T_POINTS))[0]
    p = {name: float(w @ model.table(name).ravel()) for name in model.tables}
    ec = fohw.EquivalentCircuit([fohw.RC(p["R1"], p["tau1"]), fohw.ZARC(p["R2"], p["tau2"], 0.6)],
                                r0=p["R0"], a=p["a"], ocv=OCV, dt=0.5)
    np.testing.assert_allclose(model.simulate(u), ec.simulate(u[:, :2]), rtol=0, atol=1e-14)


def test_varying_solve_against_the_recursion():
    rng = np.random.default_rng(1)
    n = 300                                  # several leaves and merges
    r = rng.uniform(0.2, 4.0, n)
    beta = fohw.gl_weights(0.45, n)
    f = rng.standard_normal((n, 2))
    z = np.zeros((n, 2))
    for k in range(n):
        z[k] = (f[k] - r[k] * (beta[1:k + 1] @ z[k - 1::-1] if k else 0.0)) / (1 + r[k])
    np.testing.assert_allclose(varying_solve(r, beta, f), z, rtol=0, atol=1e-13)
    np.testing.assert_allclose(varying_solve(r, beta, f[:, 0]), z[:, 0], rtol=0, atol=1e-13)


def test_jacobian_against_central_differences():
    model, u = _model(), _record(n=300)
    v, jac = model.jacobian(u)
    np.testing.assert_array_equal(v, model.simulate(u))
    values = model.parameters.valuesdict()
    assert jac.shape == (u.shape[0], len(values))
    for j, (name, x) in enumerate(values.items()):
        h = 1e-5 * max(abs(x), 1e-2)
        up = model.with_parameters({name: x + h}).simulate(u)
        down = model.with_parameters({name: x - h}).simulate(u)
        fd = (up - down) / (2 * h)
        # central differences: truncation h^2 |v'''| / 6 and rounding eps |v| / h; the voltage
        # is about 4 V, so eps |v| / h is at most 1e-9 V per unit here against columns of order
        # 1e-3 to 5 V per unit.
        scale = max(np.max(np.abs(jac[:, j])), 1e-3)
        assert np.max(np.abs(fd - jac[:, j])) < 1e-6 * scale + 4e-10 * 4 / h, name


def test_penalty_is_the_documented_sum_and_its_jacobian():
    model = _model(smoothing=1e-4)
    r, jac = model.penalty()
    # 12 neighbouring pairs per 3 x 3 table (6 along soc, 6 along T), 5 smoothed tables.
    assert r.shape == (60,) and jac.shape == (60, len(model.parameters))
    total = 0.0
    for name in ("R0", "R1", "tau1", "R2", "tau2"):
        t = np.log(model.table(name))
        total += np.sum(np.diff(t, axis=0) ** 2) + np.sum(np.diff(t, axis=1) ** 2)
    assert float(r @ r) == pytest.approx(1e-4 * total, rel=1e-12)
    values = model.parameters.valuesdict()
    for j, (name, x) in enumerate(values.items()):
        h = 1e-6 * abs(x) if x else 1e-8
        up = model.with_parameters({name: x + h}).penalty()[0]
        down = model.with_parameters({name: x - h}).penalty()[0]
        np.testing.assert_allclose((up - down) / (2 * h), jac[:, j], rtol=1e-6, atol=1e-9)
    assert _model().penalty() is None           # smoothing 0


def _one_temperature_fit(smoothing):
    """Pulses at 0.3, 0.5 and 0.8 SOC, all at 25 degC: the 0 and 45 degC breakpoints unvisited."""
    true = fohw.CircuitTables(["rc"], soc_points=SOC_POINTS, temperature_points=T_POINTS,
                              values={"R0": 0.02, "R1": 0.01, "tau1": 10.0}, ocv=OCV,
                              tau_bounds=(1.0, 100.0))
    rng = np.random.default_rng(3)
    parts = []
    for s in SOC_POINTS:
        i = np.repeat(rng.uniform(-5.0, 5.0, 20), 15)
        parts.append(np.column_stack([i, np.full(i.size, s), np.full(i.size, 25.0)]))
    u = np.concatenate(parts)
    y = true.simulate(u) + 1e-4 * rng.standard_normal(u.shape[0])
    start = fohw.CircuitTables(["rc"], soc_points=SOC_POINTS, temperature_points=T_POINTS, ocv=OCV,
                               tau_bounds=(1.0, 100.0), smoothing=smoothing)
    # The offsets at the unvisited temperatures are not smoothed: hold them.
    params = start.parameters
    for name in params.names:
        if name.startswith("a_") and not name.endswith("T25"):
            params = params.replace(name, fixed=True)
    return true, fohw.fit(start.with_parameters(params), u, y)


def test_unvisited_breakpoints_are_unidentifiable_without_smoothing():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", fohw.RankDeficiencyWarning)
        _, fit = _one_temperature_fit(0.0)
    assert fit.status == fohw.Status.RANK_DEFICIENT
    assert "R0_s0.3_T0" in fit.message and "R0_s0.3_T25" not in fit.message.split("columns of")[1]


def test_smoothing_makes_them_follow_their_neighbours():
    true, fit = _one_temperature_fit(1e-4)
    assert fit.status == fohw.Status.CONVERGED, fit.message
    assert "Regularisation" in fit.message
    tables = {n: fit.model.table(n) for n in ("R0", "R1", "tau1")}
    for name, t in tables.items():
        # the visited column is the truth within 3 standard errors ...
        se = fit.standard_errors()
        for k, s in enumerate(SOC_POINTS):
            pname = f"{name}_s{s:g}_T25"
            assert abs(t[k, 1] - true.parameters[pname].value) < 3 * se[pname], pname
        # ... and the unvisited ones follow from the penalty alone (nothing in the data pulls
        # them): in logarithms, each unvisited column x minimises |x - x25|^2 + x^T L x (its
        # temperature neighbour, then its own soc neighbours; L the Laplacian of a 3-point
        # path), i.e. (I + L) x = x25.
        lap = np.array([[1.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]])
        expected = np.linalg.solve(np.eye(3) + lap, np.log(t[:, 1]))
        np.testing.assert_allclose(np.log(t[:, 0]), expected, rtol=0, atol=1e-6)
        np.testing.assert_allclose(np.log(t[:, 2]), expected, rtol=0, atol=1e-6)
        assert np.ptp(np.log(t[:, 0])) < np.ptp(np.log(t[:, 1]))       # flatter, not equal
    # The reported SSE is the record's part; the criterion adds the penalty.
    np.testing.assert_allclose(fit.sse, np.sum(fit.residuals ** 2), rtol=1e-12)


@pytest.mark.parametrize("kwargs, match", [
    (dict(elements="zarc"), "sequence of 'rc' or 'zarc'"),
    (dict(elements=["warburg"]), r"`elements\[0\]` must be 'rc' or 'zarc'; got 'warburg'"),
    (dict(soc_points=[0.5, 0.3]), r"`soc_points` must increase strictly; got \[0.5, 0.3\]"),
    (dict(values={"R9": 1.0}), r"no tables or orders named \['R9'\]"),
    (dict(values={"R0": [1.0, 2.0]}), r"values\['R0'\]` must be a scalar or of shape \(3, 3\)"),
    (dict(tau_bounds=(1.0, math.inf)), "finite and increasing"),
    (dict(smoothing=-1.0), "smoothing"),
])
def test_bad_settings_are_refused_naming_them(kwargs, match):
    base = dict(elements=["zarc"], soc_points=SOC_POINTS, temperature_points=T_POINTS)
    base.update(kwargs)
    with pytest.raises(fohw.ParameterError, match=match):
        fohw.CircuitTables(base.pop("elements"), **base)


def test_a_temperature_in_kelvin_is_refused():
    u = _record()
    u[:, 2] += 273.15
    with pytest.raises(fohw.ParameterError, match=r"degC .* got 268.15 at sample 0 \(kelvin\?"):
        _model().simulate(u)


def test_resistances_stay_positive_for_the_logarithm():
    assert all(p.bounds[0] == R_MIN for n, p in _model().parameters.items() if n[0] == "R")


# --- the PyBaMM pulse records -------------------------------------------------------------------

def test_pybamm_pulses_file():
    records, ocv = fohw.datasets.pybamm_pulses()
    assert len(records) == 15
    assert sorted({r.ambient for r in records}) == [0.0, 10.0, 25.0, 35.0, 45.0]
    for r in records:
        assert r.u.shape == (1101, 3) and r.dt == 0.1
        # the protocol: rest 10 s, 5 A discharge (negative in fohw's sign) 10 s, rest 40 s,
        # 5 A charge 10 s, rest 40 s; sample k carries the current over (t[k-1], t[k]].
        expected = np.zeros(1101)
        expected[101:201], expected[601:701] = -5.0, 5.0
        np.testing.assert_array_equal(r.i, expected)
        # the voltage falls under discharge and rises under charge (the sign convention)
        assert r.v[101] < r.v[100] - 0.05 and r.v[601] > r.v[600] + 0.05
        # the coulomb count: 10 s at 5 A of a 5 Ah cell is 1/360 of the capacity
        assert r.soc[0] == r.soc0 and r.soc[201] == pytest.approx(r.soc0 - 1 / 360, abs=1e-15)
        # at rest before the pulse the voltage is the open-circuit voltage (no entropic term in
        # Chen2020, so at every temperature); 0.5 mV allows the coulomb count's nominal capacity
        # against PyBaMM's own state of charge
        assert abs(r.v[0] - ocv(r.soc0)) < 5e-4
        assert r.temperature[0] == pytest.approx(r.ambient, abs=1e-6)
        assert 0.1 < r.temperature.max() - r.ambient < 0.5        # the lumped thermal model
    with pytest.raises(fohw.ParameterError, match=r"`temperatures` must be among"):
        fohw.datasets.pybamm_pulses(temperatures=[20.0])
