"""The paper's example and the DaISy loader."""

import hashlib

import numpy as np
import pytest

import fohw


def test_paper_example_uniform_input_statistics():
    d = fohw.datasets.paper_example(20_000, random_state=0)
    assert np.all(np.abs(d.u) <= np.sqrt(3))
    # Sample mean and variance of U(-sqrt3, sqrt3): sd of the mean 1/sqrt(N) = 0.007.
    assert abs(d.u.mean()) < 5 / np.sqrt(20_000)
    assert abs(d.u.var() - 1.0) < 5 * np.sqrt(0.8 / 20_000)
    assert abs(d.noise.var() - 0.01) < 5 * 0.01 * np.sqrt(2 / 20_000)
    assert d.n_samples == 20_000 and "uniform" in repr(d)


def test_paper_example_is_seeded():
    a = fohw.datasets.paper_example(500, random_state=7)
    b = fohw.datasets.paper_example(500, random_state=np.random.default_rng(7))
    np.testing.assert_array_equal(a.y, b.y)


def test_paper_example_bad_input():
    with pytest.raises(fohw.ParameterError, match="`input_kind`"):
        fohw.datasets.paper_example(100, input_kind="binary")
    with pytest.raises(fohw.ParameterError, match="`n_samples` must be at least 3"):
        fohw.datasets.paper_example(1)
    with pytest.raises(fohw.ParameterError, match="`noise_variance`"):
        fohw.datasets.paper_example(100, noise_variance=-0.1)


def test_load_daisy_robot_arm(robot_arm_path):
    assert hashlib.sha256(robot_arm_path.read_bytes()).hexdigest() == (
        "4ee167a8a28ce0da868d1b42f6a2fe0c456ea0e56b60c70915bf6d4a2a933635")
    data = fohw.datasets.load_daisy(robot_arm_path)
    assert data.shape == (1024, 2)
    # First row as printed in the data README.
    np.testing.assert_array_equal(data[0], [2.2183165e-01, -1.7703630e-01])
    np.testing.assert_allclose(data.std(axis=0), [0.16443, 0.27510], atol=5e-6)


@pytest.mark.parametrize(
    "text, match",
    [
        ("1.0 2.0\n3.0 x\n", r"line 2: 'x' is not a number"),
        ("1.0 2.0\n3.0\n", r"line 2 has 1 column\(s\); expected 2"),
        ("% header only\n\n", "no data lines"),
        ("1.0 nan\n", "line 1 holds a non-finite value"),
        (b"1.0 2.0\n\xff\xfe\n", "line 2 is not ASCII"),
    ],
)
def test_load_daisy_rejects_malformed_files(tmp_path, text, match):
    path = tmp_path / "bad.dat"
    path.write_bytes(text if isinstance(text, bytes) else text.encode())
    with pytest.raises(fohw.DataFileError, match=match):
        fohw.datasets.load_daisy(path)


def test_load_daisy_missing_file_and_column_count(tmp_path):
    with pytest.raises(FileNotFoundError, match="nothere.dat"):
        fohw.datasets.load_daisy(tmp_path / "nothere.dat")
    path = tmp_path / "three.dat"
    path.write_text("1 2 3\n4 5 6\n")
    with pytest.raises(fohw.DataFileError, match="line 1 has 3 column"):
        fohw.datasets.load_daisy(path, n_columns=2)


def test_cascaded_tanks_is_the_benchmark_file():
    t = fohw.datasets.cascaded_tanks()
    with open(t.estimation.path, "rb") as fh:
        assert hashlib.sha256(fh.read()).hexdigest() == (
            "ef2388ed822f3aef4aa80d6b0f2b466dd80b361786b3eafc7a2957c31ea323a7")
    est, val = t.estimation, t.validation
    assert (est.n_samples, val.n_samples, est.dt, val.dt) == (1024, 1024, 4.0, 4.0)
    # First data row of dataBenchmark.csv: uEst, uVal, yEst, yVal = 3.2567, 0.97619, 5.205, 4.9728.
    assert (est.u[0], val.u[0], est.y[0], val.y[0]) == (3.2567, 0.97619, 5.205, 4.9728)
    # The data README: the sensor saturates at 10 V, 47 estimation and 37 validation samples.
    assert (np.sum(est.y == 10.0), np.sum(val.y == 10.0), est.y.max()) == (47, 37, 10.0)
    assert "Schoukens" in t.source and "free run" in t.rules
    assert (est.input_unit, est.output_unit, est.time_unit) == ("V", "V", "s")


def test_record_split_keeps_meaning_and_refuses_bad_points():
    est = fohw.datasets.cascaded_tanks().estimation
    a, b = est.split(0.75)
    assert (a.n_samples, b.n_samples) == (768, 256)
    np.testing.assert_array_equal(np.r_[a.y, b.y], est.y)
    assert b.dt == 4.0 and b.output_name == "lower tank level"
    # the second part keeps the instants it had in the whole record (768 samples of 4 s)
    np.testing.assert_array_equal(b.time[:2], [3072.0, 3076.0])
    np.testing.assert_array_equal(np.r_[a.time, b.time], est.time)
    c, d = est.split(100)
    assert c.n_samples == 100 and d.u[0] == est.u[100]
    for bad in (0, 1024, 1.0, 0.0, True, "half"):
        with pytest.raises(fohw.ParameterError, match="`at`"):
            est.split(bad)
    with pytest.raises(fohw.ParameterError, match="contiguous slice"):
        est[::2]
    with pytest.raises(fohw.DimensionError, match="same length"):
        fohw.Record(u=np.ones(3), y=np.ones(4))
    with pytest.raises(fohw.ParameterError, match="`dt`"):
        fohw.Record(u=np.ones(3), y=np.ones(3), dt=0.0)
    assert not est.u.flags.writeable


def test_battery_cell_is_the_shipped_file_decoded_losslessly():
    cell = fohw.datasets.battery_cell()
    with open(cell.path, "rb") as fh:
        assert hashlib.sha256(fh.read()).hexdigest() == (
            "4517f5f43194878fcbc04487efdb59761f46bc728aff1d091ab00352a770ac62")
    assert (cell.n_samples, cell.dt) == (164953, 0.15)
    # First samples, ranges and Z[0, 0] as printed in the source (data README).
    assert list(cell.i[:3]) == [-0.151435, -0.119143, -0.0998028]
    assert list(cell.v[:3]) == [4.03556, 4.03901, 4.03934]
    assert (cell.i.min(), cell.i.max(), cell.v.min(), cell.v.max()) == (-3.9999, 1.31733, 3.42158, 4.0458)
    assert cell.impedance[0, 0] == 0.0140485 - 4.770621e-05j
    assert cell.impedance.shape == cell.impedance_fit.shape == (65, 7)
    np.testing.assert_array_equal(cell.impedance_soc, [0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8])
    assert cell.impedance_f[0] == 1000.702 and cell.impedance_f[-1] == 3.974e-4
    assert cell.t[-1] == pytest.approx(24742.8, abs=1e-9)
    assert "arXiv:2412.10896" in cell.source and "BSD-3-Clause" in cell.source
    assert "arXiv:2412.10896" in fohw.datasets.battery_cell.__doc__


def test_battery_cell_state_of_charge_and_ocv():
    cell = fohw.datasets.battery_cell()
    # Coulomb counting: the charge passed, in Ah, over the nominal capacity (a left Riemann sum).
    assert cell.soc[0] == 0.8
    charge = np.sum(cell.i[:-1]) * 0.15 / 3600
    assert cell.soc[-1] == pytest.approx(0.8 + charge / 4.885, rel=1e-12)
    assert 0.20 < cell.soc[-1] < 0.205                 # "80 % -> 20 %" (source README)
    assert np.all(np.diff(cell.soc) * 4.885 * 3600 / 0.15 == pytest.approx(cell.i[:-1], abs=1e-9))
    # OCV from the electrodes at the SOC 0 and 1 stoichiometries, by hand.
    st = cell.stoichiometry
    assert (st["y1"], st["y0"], st["x0"], st["x1"]) == pytest.approx(  # printed to 4 decimals
        (0.1897, 0.9829, 0.0015, 0.8864), abs=5e-5)
    manual = np.interp(st["y0"], cell.x_pos, cell.U_pos) - np.interp(st["x0"], cell.x_neg, cell.U_neg)
    assert cell.ocv(0.0) == manual
    ocv = cell.ocv(np.linspace(0.2, 0.8, 61))
    assert np.all(np.diff(ocv) > 0)                   # the OCV rises with the state of charge
    # The voltage after a 60 s rest (|i| < 0.02 A) is within 13 mV below-or-near the OCV.
    rests = {4561: 4.01823, 32747: 3.91007, 88724 + 397: 3.69909, 140241: 3.57188}
    for k, v_rest in rests.items():
        assert cell.v[k] == v_rest and abs(cell.i[k]) < 0.02
        assert -0.002 < cell.ocv(cell.soc[k]) - v_rest < 0.013
    with pytest.raises(fohw.ParameterError, match="`soc` must be in"):
        cell.ocv(1.2)


def test_battery_cell_decimate_keeps_the_charge():
    cell = fohw.datasets.battery_cell()
    dec = cell.decimate(10)
    assert (dec.n_samples, dec.dt) == (16495, 1.5)
    np.testing.assert_allclose(dec.i.sum() * 1.5, cell.i[:164950].sum() * 0.15, rtol=1e-12)
    assert dec.v[0] == pytest.approx(cell.v[:10].mean(), rel=1e-15)
    assert "dt=1.5 s" in repr(dec)
    with pytest.raises(fohw.ParameterError, match="`factor`"):
        cell.decimate(0)
