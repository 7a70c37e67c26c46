"""The forgetting-factor reading of the paper (issue 16): `--forgetting` and the forgetting map.

The forgetting factor is not in the paper, so the first thing pinned down is that its default
(lambda = 1) is the paper exactly: bit for bit the same numbers as not giving it at all.
"""


import numpy as np
import pytest

import fohw
from fohw.cli import main
from fohw.paper import forgetting, table2

STRUCT = dict(na=2, nb=2, f_basis=2, g_basis=3)


def _table2_csv(tmp_path, name, *extra):
    out = tmp_path / name
    assert table2.main(("table_2",), "test", ["--outdir", str(out), "--fast", *extra]) == 0
    return (out / "table_2.csv").read_text(), (out / "table_2.md").read_text()


@pytest.fixture(scope="module")
def default_table(tmp_path_factory):
    """Table 2 (fast) as printed: no --forgetting given."""
    return _table2_csv(tmp_path_factory.mktemp("table2"), "default")


def test_forgetting_one_is_the_paper_bit_for_bit(tmp_path, default_table):
    default_csv, default_md = default_table
    one_csv, one_md = _table2_csv(tmp_path, "one", "--forgetting", "1")
    assert one_csv == default_csv and one_md == default_md
    # and the runs themselves, not only their 17-digit text
    a = table2.run_paper_example(400, innovation_lengths=(3,), baselines=False)
    b = table2.run_paper_example(400, innovation_lengths=(3,), baselines=False, forgetting=1.0)
    assert np.array_equal(a.hybrid[3].theta_history, b.hybrid[3].theta_history)
    assert np.array_equal(a.hybrid[3].alpha_sample_history, b.hybrid[3].alpha_sample_history)


def test_forgetting_below_one_changes_the_run_and_says_so(tmp_path, default_table):
    default_csv, default_md = default_table
    csv, md = _table2_csv(tmp_path, "lam", "--forgetting", "0.95")
    assert csv != default_csv
    assert "Forgetting factor" not in default_md and "no forgetting factor" not in default_md
    assert "Forgetting factor lambda = 0.95" in md and "no forgetting factor" in md
    # The option reaches the estimator: the same numbers as identify with forgetting=0.95.
    data = fohw.datasets.paper_example(2000, random_state=0)
    res = fohw.identify(data.u, data.y, method="hybrid", innovation_length=5, forgetting=0.95,
                        **STRUCT)
    row = next(line for line in csv.splitlines() if line.startswith("5,2000,a1,"))
    assert float(row.split(",")[4]) == res.theta[0]


@pytest.mark.parametrize("bad", ["0", "1.5", "-0.2"])
def test_example_rejects_a_forgetting_factor_outside_0_1(bad, tmp_path, capsys):
    with pytest.raises(SystemExit) as exc:
        table2.main(("table_2",), "test", ["--outdir", str(tmp_path), "--forgetting", bad])
    assert exc.value.code == 2
    assert "--forgetting must be in (0, 1]" in capsys.readouterr().err


def test_cli_forwards_forgetting_and_wires_the_map(monkeypatch, tmp_path):
    calls = []
    monkeypatch.setattr(table2, "main", lambda which, desc, argv: calls.append(
        ("table", which, argv)) or 0)
    monkeypatch.setattr(forgetting, "main", lambda argv, desc: calls.append(
        ("map", argv)) or 0)
    out = str(tmp_path)
    assert main(["reproduce", "table2", "--outdir", out, "--forgetting", "0.95"]) == 0
    assert main(["reproduce", "table2", "--outdir", out]) == 0
    assert main(["reproduce", "forgetting", "--outdir", out, "--fast"]) == 0
    assert calls[0] == ("table", table2.OUTPUTS,
                        ["--outdir", out, "--seed", "0", "--forgetting", "0.95"])
    assert "--forgetting" not in calls[1][2]           # the default is not even passed on
    assert calls[2] == ("map", ["--outdir", out, "--fast"])


@pytest.mark.parametrize("argv, message", [
    (["reproduce", "table2", "--forgetting", "1.5"], "--forgetting must be in (0, 1]"),
    (["reproduce", "accuracy", "--forgetting", "0.9"], "applies to table2 and figures"),
    (["reproduce", "forgetting", "--forgetting", "0.9"], "applies to table2 and figures"),
])
def test_cli_forgetting_misuse_is_a_one_line_error(argv, message, capsys):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and message in err


def test_map_rows_are_the_runs_they_name():
    # Recursive: the estimate after sample k of one pass. Iterative: a run on the first k
    # samples. Both recomputed here through fohw.identify directly.
    rows, curves = forgetting.forgetting_map([3], 400, forgetting=(1.0, 0.9), innovation_lengths=(1, 2),
                                      schedules=("recursive", "iterative"),
                                      checkpoints=(200, 400), max_iter=3, curve_step=100)
    assert len(rows) == 2 * 2 * 2 * 2
    data = fohw.datasets.paper_example(400, random_state=3)
    theta = data.model.theta
    by = {(r["schedule"], r["forgetting"], r["P"], r["k"]): r for r in rows}
    rec = fohw.identify(data.u, data.y, method="hybrid", innovation_length=2, forgetting=0.9,
                        **STRUCT)
    with pytest.warns(fohw.ConvergenceWarning, match="max_iter = 3"):
        it = fohw.identify(data.u[:200], data.y[:200], method="hybrid", innovation_length=2,
                           forgetting=0.9, schedule="iterative", max_iter=3, **STRUCT)
    r = by[("recursive", 0.9, 2, 200)]
    # The row's delta is one entry of relative_error(history=True), a norm over the whole
    # history at once; numpy may sum a batched norm in another order than this 1-D one (numpy
    # 2.4 does: one ulp apart), so the same run agrees to a few ulps, not bit for bit.
    one = np.linalg.norm(rec.theta_history[199] - theta) / np.linalg.norm(theta)
    assert r["delta"] == pytest.approx(one, rel=4 * np.finfo(float).eps, abs=0)
    assert r["alpha"] == rec.alpha_sample_history[199]
    r = by[("iterative", 0.9, 2, 200)]
    assert r["delta"] == np.linalg.norm(it.theta - theta) / np.linalg.norm(theta)
    assert r["alpha"] == it.alpha and r["n_iter"] == it.nit
    # the kept path of the recursive run, every 100 samples
    d, a = curves[("recursive", 0.9, 3)][2]
    assert d[1] == by[("recursive", 0.9, 2, 200)]["delta"] and a.shape == (4,)


def test_p_comparison_counts_paired_seeds():
    # Hand-made: P = 5 is better on seeds 0 and 2 (by 0.1 and 0.3), worse on seed 1 (by 0.2).
    rows = [dict(schedule="recursive", forgetting=0.9, k=10, seed=s, P=P, delta=d)
            for s, d1, d5 in [(0, 0.5, 0.4), (1, 0.5, 0.7), (2, 0.6, 0.3)]
            for P, d in ((1, d1), (5, d5))]
    out = forgetting.forgetting_p_comparison(rows)
    entry = out[("recursive", 0.9, 10)]
    assert (entry["wins"], entry["n"]) == (2, 3)
    assert entry["median_difference"] == pytest.approx(0.1)
