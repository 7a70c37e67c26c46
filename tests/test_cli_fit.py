"""Issue 42, item 3: ``fohw fit --model START.json --data FILE`` fits any kind from the shell,
with the estimates of :func:`fohw.fit` on the same record."""

import json

import numpy as np
import pytest

import fohw
from fohw.cli import main

RNG = np.random.default_rng(7)


def _write(path, header, columns, comments=()):
    rows = "".join(",".join(repr(float(v)) for v in row) + "\n" for row in zip(*columns))
    path.write_text("".join(f"# {c}\n" for c in comments) + header + "\n" + rows)
    return str(path)


def _tf_case(tmp_path):
    g = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.8, 0.0], dt=0.1)
    u = RNG.standard_normal(300)
    y = g.simulate(u) + 0.01 * RNG.standard_normal(300)
    data = _write(tmp_path / "tf.csv", "time_s,u,y", [0.1 * np.arange(300), u, y])
    start = fohw.FractionalTF([0.5], [0.0], [1.0, 1.0], [0.6, 0.0], dt=0.1)
    return start, data, ["--columns", "u,y"]


def _circuit_case(tmp_path):
    truth = fohw.EquivalentCircuit([fohw.ZARC(0.012, 50.0, 0.6)], r0=0.015, dt=1.0,
                                   ocv=fohw.OCVTable([0.0, 1.0], [3.3, 4.2]))
    i = np.repeat(RNG.uniform(-3.0, 1.0, 20), 20)
    soc = 0.8 + np.cumsum(i) / (3600 * 5)
    v = truth.simulate(np.column_stack([i, soc])) + 1e-4 * RNG.standard_normal(i.size)
    data = _write(tmp_path / "cell.csv", "Time [s],current,soc,voltage",
                  [np.arange(i.size, dtype=float), i, soc, v],
                  comments=["units: current=A, soc=1, voltage=V"])
    start = fohw.EquivalentCircuit(("zarc",), dt=1.0, ocv=fohw.OCVTable([0.0, 1.0], [3.3, 4.2]),
                                   tau_bounds=(1.0, 500.0))
    return start, data, ["--columns", "current,soc,voltage"]


@pytest.mark.parametrize("case", [_tf_case, _circuit_case], ids=["FractionalTF", "circuit"])
def test_fit_from_the_shell_gives_the_estimates_of_fohw_fit(case, tmp_path, capsys):
    start, data, columns = case(tmp_path)
    fohw.save_model(start, tmp_path / "start.json")
    options = dict(order_grid=3, n_starts=2, max_nfev=60)
    saved, plot = tmp_path / "fit.json", tmp_path / "fit.png"
    assert main(["fit", "--model", str(tmp_path / "start.json"), "--data", data, *columns,
                 "--order-grid", "3", "--n-starts", "2", "--max-nfev", "60", "--json",
                 "--save", str(saved), "--plot", str(plot), "-q"]) == 0
    out = json.loads(capsys.readouterr().out)
    names = columns[1].split(",")
    record = fohw.read_record(data, u=names[:-1] if len(names) > 2 else names[0], y=names[-1])
    expected = fohw.fit(start, record, **options)
    assert out["kind"] == type(start).__name__ and out["status"] == expected.status.name
    for name in expected.parameters:
        np.testing.assert_allclose(out["estimates"][name], expected.parameters[name].value,
                                   rtol=1e-9, atol=1e-12, err_msg=name)
    assert set(out["standard_errors"]) == set(expected.free_names)
    back = fohw.load_result(saved)
    assert back.sse == pytest.approx(expected.sse, rel=1e-9)
    assert plot.stat().st_size > 0
    # the record's sampling and units reached the result
    assert out["data"]["dt"] == record.dt and out["data"]["time_unit"] == "s"


def test_fit_takes_the_columns_in_order_only_when_there_are_as_many(tmp_path, capsys):
    start, data, _ = _circuit_case(tmp_path)
    fohw.save_model(start, tmp_path / "start.json")
    args = ["fit", "--model", str(tmp_path / "start.json"), "--order-grid", "1", "--n-starts",
            "1", "--max-nfev", "5", "--json", "-q"]
    # time, current, soc, voltage: three columns for two inputs and the output, in order
    assert main([*args, "--data", data]) == 0
    assert json.loads(capsys.readouterr().out)["data"]["input_names"] == ["current", "soc"]
    # a fourth signal column: fohw does not guess which three
    from pathlib import Path

    lines = Path(data).read_text().splitlines()
    extra = [line if line.startswith("#") else f"{line},{'temp' if k == 1 else 25.0}"
             for k, line in enumerate(lines)]
    (tmp_path / "more.csv").write_text("\n".join(extra) + "\n")
    assert main([*args, "--data", str(tmp_path / "more.csv")]) == 2
    err = capsys.readouterr().err
    assert "has 4 columns (current, soc, voltage, temp) besides the time column 'Time [s]': " \
           "say which to use with --columns" in err
