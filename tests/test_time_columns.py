"""Issue 42: a user's files as they come. A time column is time (seconds or ISO 8601 stamps),
checked as ``Record(t=...)`` checks instants; units per column; several inputs; the command
line reads through the same reader and never guesses a column."""

import io
import json

import numpy as np
import pytest

import fohw
from fohw.cli import main
from fohw.io.text import read_table

RNG = np.random.default_rng(42)
U = RNG.uniform(-1, 1, 200)
Y = fohw.datasets.paper_model().simulate(U)


def _csv(path, header, t, *columns, comments=()):
    rows = "".join(",".join(str(v) for v in row) + "\n" for row in zip(t, *columns))
    path.write_text("".join(f"# {c}\n" for c in comments) + header + "\n" + rows)
    return str(path)


def test_a_time_column_in_seconds_gives_the_sampling_time(tmp_path):
    path = _csv(tmp_path / "tank.csv", "time_s,pump_voltage,tank_level", 4.0 * np.arange(200),
                U, Y, comments=["units: pump_voltage=V, tank_level=V"])
    rec = fohw.read_record(path)
    # the time from the column's name, the channels the two other columns, units from '# units:'
    assert (rec.dt, rec.t0, rec.time_unit) == (4.0, 0.0, "s")
    assert (rec.input_name, rec.output_name, rec.output_unit) == ("pump_voltage", "tank_level",
                                                                  "V")
    np.testing.assert_array_equal(rec.u, U)
    # the command line reads the same record: its summary says dt = 4 s, not 1
    assert main(["identify", path, "--na", "1", "--nb", "1", "--f-basis", "1", "--g-basis", "1",
                 "--json", "-q"]) == 0


def test_the_command_line_summary_says_the_files_sampling_time(tmp_path, capsys):
    path = _csv(tmp_path / "tank.csv", "Time [s],pump,level", 4.0 * np.arange(200), U, Y)
    assert main(["identify", path, "--na", "1", "--nb", "1", "--f-basis", "1", "--g-basis", "1",
                 "-q"]) == 0
    assert "input pump; output level, dt = 4 s" in capsys.readouterr().out


def test_iso_stamps_are_instants_in_seconds_from_the_first(tmp_path, capsys):
    """Issue 43, N46: ISO stamps were 'a second header line'."""
    stamps = [f"2024-01-01T00:{k // 60:02d}:{k % 60:02d}" for k in range(200)]
    path = _csv(tmp_path / "iso.csv", "time,u,y", stamps, U, Y)
    rec = fohw.read_record(path)
    assert (rec.dt, rec.time_unit) == (1.0, "s")
    assert read_table(path).meta["time_origin"] == "2024-01-01T00:00:00"
    assert main(["identify", path, "--na", "1", "--nb", "1", "--f-basis", "1", "--g-basis", "1",
                 "-q"]) == 0
    assert "dt = 1 s" in capsys.readouterr().out
    # irregular stamps stay instants (0, 0.5, 2 s: not uniform)
    text = "time,u,y\n2024-01-01T00:00:00,1,2\n2024-01-01T00:00:00.5,2,3\n2024-01-01T00:00:02,3,4\n"
    np.testing.assert_array_equal(fohw.read_record(io.StringIO(text)).t, [0.0, 0.5, 2.0])
    mixed = "time,u,y\n2024-01-01T00:00:00,1,2\n2024-01-01T00:00:01+01:00,2,3\n"
    with pytest.raises(fohw.DataFileError, match="line 3: .* has a time zone, but the first"):
        fohw.read_record(io.StringIO(mixed))


def test_irregular_instants_are_kept_and_checked_against_dt(tmp_path):
    t = np.cumsum(np.r_[0.0, RNG.uniform(0.5, 1.5, 199)])
    path = _csv(tmp_path / "irr.csv", "t,u,y", t, U, Y)
    rec = fohw.read_record(path)
    assert not rec.uniform and rec.dt is None
    np.testing.assert_array_equal(rec.t, t)
    with pytest.raises(fohw.DataFileError, match=r"line 3: the time column 't' steps .* from "
                       r"line 2, but `dt` = 1.0 says 1"):
        fohw.read_record(path, dt=1.0)
    # t=False reads every column as a signal; the time column is never a signal otherwise
    with pytest.raises(fohw.ParameterError, match="'t' is the time column"):
        fohw.read_record(path, u="t", y="y")
    assert fohw.read_record(path, u="t", y="y", t=False).u[1] == t[1]


def test_a_time_unit_in_ms_is_compared_with_dt_in_seconds(tmp_path):
    path = _csv(tmp_path / "ms.csv", "t_ms,u,y", 250 * np.arange(200), U, Y,
                comments=["dt: 0.25 s"])
    rec = fohw.read_record(path)
    assert (rec.dt, rec.time_unit) == (250.0, "ms")
    bad = _csv(tmp_path / "bad.csv", "t_ms,u,y", 250 * np.arange(200), U, Y,
               comments=["dt: 0.5 s"])
    with pytest.raises(fohw.DataFileError, match=r"steps 250 ms from line 3, but `# dt: 0.5 s` "
                       r"\(line 1\) says 500 ms"):
        fohw.read_record(bad)


def test_several_inputs_by_name_with_their_units(tmp_path):
    soc = np.linspace(0.8, 0.7, 200)
    path = _csv(tmp_path / "cell.csv", "t,i,soc,v", np.arange(200.0), U, soc, Y,
                comments=["units: i=A, soc=1, v=V"])
    rec = fohw.read_record(path, u=["i", "soc"], y="v")
    assert rec.n_inputs == 2 and rec.input_names == ("i", "soc")
    assert rec.input_units == ("A", "1") and rec.output_unit == "V" and rec.dt == 1.0
    np.testing.assert_array_equal(rec.u, np.column_stack([U, soc]))
    with pytest.raises(fohw.ParameterError, match="a fohw.Record holds one output"):
        fohw.read_record(path, u="i", y=["soc", "v"])
    with pytest.raises(fohw.ParameterError, match="3 signal columns .* besides the time column"):
        fohw.read_record(path)          # three signals: which is the input is not guessed


def test_simulate_never_takes_the_time_column_and_writes_a_table(tmp_path):
    """Issue 42: `fohw simulate` simulated column 0 (the time column) by default."""
    m = fohw.datasets.paper_model()
    fohw.save_model(m, tmp_path / "m.json")
    path = _csv(tmp_path / "in.csv", "time_s,a,b", np.arange(200.0), U, U[::-1],
                comments=["units: a=V, b=V"])
    assert main(["simulate", "--model", str(tmp_path / "m.json"), "--input", path]) == 2
    out = tmp_path / "y.csv"
    assert main(["simulate", "--model", str(tmp_path / "m.json"), "--input", path, "--column",
                 "a", "--output", str(out), "-q"]) == 0
    text = out.read_text()
    assert "# dt: 1.0 s\n# units: time_s=s\ntime_s,y\n" in text
    back = read_table(out)
    np.testing.assert_array_equal(back.data[:, 0], np.arange(200.0))
    np.testing.assert_array_equal(back.data[:, 1], fohw.simulate(m, U))
    # a file with a column named u: that one, by name (not column 0)
    named = _csv(tmp_path / "named.csv", "t,y,u", np.arange(200.0), U[::-1], U)
    assert main(["simulate", "--model", str(tmp_path / "m.json"), "--input", named, "--output",
                 str(out), "-q"]) == 0
    np.testing.assert_array_equal(read_table(out).data[:, 1], fohw.simulate(m, U))


def test_compare_names_the_kind_not_a_bound_method(tmp_path, capsys):
    """Issue 43, N45: the note printed '<bound method Model.kind_name of ...>'."""
    g = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.8, 0.0], dt=0.1)
    u = RNG.standard_normal(300)
    y = g.simulate(u)
    fr = fohw.fit(g, fohw.Record(u=u, y=y, dt=0.1), order_grid=2, n_starts=1)
    fohw.save_result(fr, tmp_path / "tf.json")
    path = _csv(tmp_path / "tf.csv", "t,u,y", 0.1 * np.arange(300), u, y)
    assert main(["compare", "--model", str(tmp_path / "tf.json"), "--data", path, "-q"]) == 0
    out = capsys.readouterr().out
    assert "bound method" not in out and "a FractionalTF is an output-error model" in out
    assert main(["compare", "--model", str(tmp_path / "tf.json"), "--data", path, "--json",
                 "-q"]) == 0
    assert json.loads(capsys.readouterr().out)["n_samples"] == 300


def test_messages_point_to_fohws_own_tools(tmp_path):
    """Issue 42, item 6: an irregular record is resampled with fohw's resample (not
    numpy.interp), and the reproduce note names no source path a pip user lacks."""
    t = np.cumsum(np.r_[0.0, RNG.uniform(0.5, 1.5, 199)])
    rec = fohw.read_record(_csv(tmp_path / "irr.csv", "t,u,y", t, U, Y))
    with pytest.raises(fohw.ParameterError, match=r"resample it with "
                       r"fohw\.model\.irregular\.resample\(rec\.t, rec\.u, rec\.y, dt=\.\.\.\)"):
        fohw.identify(rec, na=1, nb=1, f_basis=1, g_basis=1)
    from fohw.model.irregular import resample

    assert resample(rec.t, rec.u, rec.y, dt=1.0)        # the call the message names works
    from fohw.paper.table2 import caption, run_paper_example

    note = caption(run_paper_example(n_samples=300, innovation_lengths=(1,), baselines=False))
    assert "docs/" not in note and ".md" not in note and "method='varpro'" in note


def test_from_dataframe_reads_time_as_read_record_does():
    """The DataFrame path finds and checks a time column as the file reader does, and names
    what is wrong (issue 43, N41, N42, N52, N53 and N25 as they meet it)."""
    pd = pytest.importorskip("pandas")
    u, y = np.arange(6.0), np.arange(6.0) ** 2
    frame = pd.DataFrame({"time_s": 0.5 * np.arange(6), "i": u, "v": y})
    rec = fohw.Record.from_dataframe(frame, "i", "v")
    assert (rec.dt, rec.time_unit) == (0.5, "s")
    stamps = pd.to_datetime([f"2024-01-01 00:00:0{k}" for k in (0, 1, 3, 2, 4, 5)])
    with pytest.raises(fohw.ParameterError, match=r"frame\['stamp'\] must increase strictly: "
                       r"row 3 goes back from row 2 \(3.0 -> 2.0\)"):
        fohw.Record.from_dataframe(pd.DataFrame({"stamp": stamps, "i": u, "v": y}), "i", "v",
                                   time="stamp")
    gap = pd.DatetimeIndex(list(stamps[:2]) + [pd.NaT] + list(stamps[4:]) + [stamps[4]])
    with pytest.raises(fohw.ParameterError, match=r"the index holds no time \(NaT\) at position 2"):
        fohw.Record.from_dataframe(pd.DataFrame({"i": u, "v": y}, index=gap), "i", "v")
    with pytest.raises(fohw.ParameterError, match="`frame` must be a pandas DataFrame; got dict"):
        fohw.Record.from_dataframe({"i": u, "v": y}, "i", "v", dt=0.1)
    with pytest.raises(fohw.ParameterError, match="`units` must map each column to its unit"):
        fohw.Record.from_dataframe(frame, "i", "v", units=["A", "V"])
    with pytest.raises(fohw.ParameterError, match="2 columns named 'v'"):
        fohw.Record.from_dataframe(pd.DataFrame(np.c_[u, y, y], columns=["i", "v", "v"]), "i",
                                   "v", dt=0.1)
    with pytest.raises(fohw.ParameterError, match="`u` and `y` name the same column"):
        fohw.Record.from_dataframe(frame, "v", "v")
