import json
import subprocess
import sys

import numpy as np
import pytest

import fohw
from fohw.cli import main


def test_reproduce_table2_fast(tmp_path, capsys):
    assert main(["reproduce", "table2", "--outdir", str(tmp_path), "--fast"]) == 0
    out = capsys.readouterr().out
    assert "| alpha | 0.6 |" in out
    for name in ("table_2.md", "table_2.csv", "figure_3.png", "figure_6.png"):
        assert (tmp_path / name).stat().st_size > 0


def test_reproduce_accuracy_fast(tmp_path):
    assert main(["reproduce", "accuracy", "--outdir", str(tmp_path), "--fast"]) == 0
    assert "Cramér-Rao" in (tmp_path / "accuracy.md").read_text()


def test_usage_error_is_one_line_exit_2():
    proc = subprocess.run([sys.executable, "-m", "fohw", "reproduce", "table3"],
                          capture_output=True, text=True)
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1 and "invalid choice" in proc.stderr


def test_version():
    proc = subprocess.run([sys.executable, "-m", "fohw", "--version"], capture_output=True, text=True)
    assert proc.returncode == 0 and fohw.__version__ in proc.stdout


@pytest.fixture
def record(tmp_path):
    d = fohw.datasets.paper_example(800, random_state=0)
    ws = tmp_path / "data.txt"
    np.savetxt(ws, np.column_stack([d.u, d.y]))
    csv = tmp_path / "data.csv"
    with open(csv, "w") as fh:
        fh.write("time,y,u\n")
        for k, (u, y) in enumerate(zip(d.u, d.y)):
            fh.write(f"{k},{float(y)!r},{float(u)!r}\n")
    return d, ws, csv


def test_identify_json_round_trip(record, capsys):
    d, ws, csv = record
    assert main(["identify", str(csv), "--columns", "u,y", "--na", "2", "--nb", "2",
                 "--f-basis", "2", "--g-basis", "3", "--json"]) == 0
    out = json.loads(capsys.readouterr().out)
    res = fohw.identify(d.u, d.y, na=2, nb=2, f_basis=2, g_basis=3, method="varpro")
    assert out["alpha"] == res.alpha
    assert list(out["theta"].values()) == res.theta.tolist()
    assert out["standard_errors"]["alpha"] == res.standard_errors()["alpha"]
    # The whitespace file with default columns gives the same numbers (savetxt keeps 18 digits).
    assert main(["identify", str(ws), "--na", "2", "--nb", "2", "--f-basis", "2", "--g-basis",
                 "3", "--json"]) == 0
    out2 = json.loads(capsys.readouterr().out)
    np.testing.assert_allclose(list(out2["theta"].values()), res.theta, rtol=1e-12)


def test_identify_summary_plot_and_save(record, tmp_path, capsys):
    d, ws, _ = record
    png, saved = tmp_path / "fit.png", tmp_path / "res.json"
    assert main(["identify", str(ws), "--na", "2", "--nb", "2", "--f-basis", "2", "--g-basis", "3",
                 "--plot", str(png), "--save", str(saved)]) == 0
    assert "std err" in capsys.readouterr().out
    assert png.stat().st_size > 0
    loaded = fohw.load_result(saved)
    assert loaded.method == "varpro" and loaded.theta.shape == (10,)


def test_simulate_command(tmp_path, capsys):
    m = fohw.datasets.paper_model()
    fohw.save_model(m, tmp_path / "m.json")
    u = np.random.default_rng(0).uniform(-1, 1, 300)
    np.savetxt(tmp_path / "u.txt", u)
    assert main(["simulate", "--model", str(tmp_path / "m.json"), "--input",
                 str(tmp_path / "u.txt"), "--output", str(tmp_path / "y.txt")]) == 0
    y = np.loadtxt(tmp_path / "y.txt")
    np.testing.assert_array_equal(y, fohw.simulate(m, np.loadtxt(tmp_path / "u.txt")))


def test_model_and_result_json_are_exact(tmp_path):
    d = fohw.datasets.paper_example(600, random_state=3)
    m = fohw.HammersteinWiener([0.1 / 3, 0.2], [-0.4, np.pi / 10], [1, 0.5], [1, 0.7, 1 / 7], 0.6)
    fohw.save_model(m, tmp_path / "m.json")
    m2 = fohw.load_model(tmp_path / "m.json")
    assert m2 == m
    np.testing.assert_array_equal(fohw.simulate(m2, d.u), fohw.simulate(m, d.u))
    for method in ("varpro", "hybrid"):
        res = fohw.identify(d.u, d.y, na=2, nb=2, f_basis=2, g_basis=3, method=method)
        fohw.save_result(res, tmp_path / "r.json")
        back = fohw.load_result(tmp_path / "r.json")
        for key in ("theta", "theta_history", "alpha_history", "J_history", "covariance"):
            a, b = getattr(res, key), getattr(back, key)
            assert (a is None and b is None) or np.array_equal(a, b), key
        assert (back.alpha, back.J, back.message) == (res.alpha, res.J, res.message)
        np.testing.assert_array_equal(back.simulate(d.u), res.simulate(d.u))


def test_custom_basis_needs_the_basis_on_load(tmp_path):
    m = fohw.HammersteinWiener([0.3], [1.0], [1.0, 0.2], [1.0], 0.5,
                               f_basis={"u": lambda x: x, "tanh": np.tanh}, g_basis=1)
    fohw.save_model(m, tmp_path / "m.json")
    with pytest.raises(fohw.ParameterError, match="custom `f_basis`"):
        fohw.load_model(tmp_path / "m.json")
    with pytest.raises(fohw.ParameterError, match="has functions"):
        fohw.load_model(tmp_path / "m.json", f_basis=[np.sin, np.tanh])
    assert fohw.load_model(tmp_path / "m.json", f_basis=m.f_basis) == m
