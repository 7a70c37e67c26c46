"""``fohw data NAME --out FILE``: a CSV that pandas and fohw.read_record both read cleanly.

The file used to copy the cascaded-tanks source (a trailing comma on every line, ``Ts`` given
once in a fifth column): pandas then read an ``Unnamed: 5`` column and a ``Ts`` column of 1023
NaN. Now the sampling time and the units are ``#`` header comments; every data line has one
value per column, and both readers give the dataset's own numbers bit for bit.
"""

import numpy as np
import pytest

import fohw
from fohw.cli import main


def _expected(name):
    """(columns, dt, time unit, units) of each record, from fohw.datasets."""
    if name == "cascaded_tanks":
        t = fohw.datasets.cascaded_tanks()
        cols = {"uEst": t.estimation.u, "uVal": t.validation.u, "yEst": t.estimation.y,
                "yVal": t.validation.y}
        return cols, 4.0, "s", dict.fromkeys(cols, "V")
    if name == "robot_arm":
        a = fohw.datasets.robot_arm()
        return {"torque": a.u, "acceleration": a.y}, None, "", {}
    if name == "paper_example":
        d = fohw.datasets.paper_example(300, random_state=3)
        return {"u": d.u, "y": d.y}, None, "", {}
    c = fohw.datasets.battery_cell()
    return ({"t": np.round(np.arange(c.i.size) * c.dt, 2), "i": c.i, "v": c.v, "soc": c.soc},
            c.dt, "s", {"t": "s", "i": "A", "v": "V", "soc": "1"})


@pytest.mark.parametrize("name", ["cascaded_tanks", "robot_arm", "paper_example", "battery"])
def test_pandas_and_read_record_read_the_written_file(name, tmp_path):
    pd = pytest.importorskip("pandas")
    out = tmp_path / f"{name}.csv"
    extra = ["--samples", "300", "--seed", "3"] if name == "paper_example" else []
    assert main(["data", name, "--out", str(out)] + extra) == 0
    columns, dt, time_unit, units = _expected(name)
    lines = out.read_text().splitlines()
    data = [line for line in lines if not line.startswith("#")]
    assert data[0] == ",".join(columns)
    assert all(line.count(",") == len(columns) - 1 and not line.endswith(",") for line in data)
    assert len(data) == 1 + len(next(iter(columns.values())))
    frame = pd.read_csv(out, comment="#")
    assert list(frame.columns) == list(columns)
    assert not frame.isna().any().any()
    for key, values in columns.items():
        np.testing.assert_array_equal(frame[key].to_numpy(), values)
    names = list(columns)
    u, y = (names[0], names[2]) if name == "cascaded_tanks" else (
        ("i", "v") if name == "battery" else (names[0], names[1]))
    rec = fohw.read_record(out, u=u, y=y)
    np.testing.assert_array_equal(rec.u, columns[u])
    np.testing.assert_array_equal(rec.y, columns[y])
    assert (rec.dt, rec.time_unit) == (dt, time_unit)
    assert (rec.input_unit, rec.output_unit) == (units.get(u, ""), units.get(y, ""))
    assert (rec.input_name, rec.output_name) == (u, y)


def test_header_comments_that_cannot_be_read_are_errors(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("# what this is: a note, ignored\n# dt: fast\nu,y\n1,2\n3,4\n")
    with pytest.raises(fohw.DataFileError, match=r"line 2: `# dt:` must give a positive"):
        fohw.read_record(bad)
    bad.write_text("# units: u V\nu,y\n1,2\n3,4\n")
    with pytest.raises(fohw.DataFileError, match=r"line 1: `# units:` must list column=unit"):
        fohw.read_record(bad)
    bad.write_text("# dt: 2 s\nu,y,Ts\n1,2,4\n3,4,\n")
    with pytest.raises(fohw.DataFileError, match="'Ts' gives the sampling time 4.0 but the "
                       "header comment `# dt:` 2.0"):
        fohw.read_record(bad)
    good = tmp_path / "good.csv"
    good.write_text("# a note: kept out\n# dt: 0.5 ms\n# units: y=degC\nu,y\n1,2\n3,4\n")
    rec = fohw.read_record(good, input_unit="A")
    assert (rec.dt, rec.time_unit, rec.input_unit, rec.output_unit) == (0.5, "ms", "A", "degC")
    assert fohw.read_record(good, dt=2.0).time_unit == ""        # not the file's dt: no unit
