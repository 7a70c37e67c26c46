"""fohw.read_record and the table parser under it (and under the command line)."""

import os

import numpy as np
import pytest

import fohw
from fohw.cli import main
from fohw.io.text import read_table

TANKS = os.path.join(os.path.dirname(fohw.__file__), "data", "cascaded_tanks.csv")


def write(tmp_path, text, name="d.csv", mode="w"):
    path = tmp_path / name
    if mode == "wb":
        path.write_bytes(text)
    else:
        path.write_text(text)
    return path


def test_the_benchmark_csv_loads_with_one_call():
    # The raw file: quoted header, a trailing comma on every line, Ts given on the first row.
    rec = fohw.read_record(TANKS, u="uEst", y="yEst")
    ref = fohw.datasets.cascaded_tanks().estimation
    np.testing.assert_array_equal(rec.u, ref.u)
    np.testing.assert_array_equal(rec.y, ref.y)
    assert rec.dt == 4.0 and rec.n_samples == 1024
    assert (rec.input_name, rec.output_name) == ("uEst", "yEst")
    # the first data line, read by hand
    with open(TANKS) as fh:
        first = fh.read().splitlines()[1].split(",")
    assert (rec.u[0], rec.y[0]) == (float(first[0]), float(first[2]))


def test_the_benchmark_csv_through_the_cli(capsys):
    args = ["identify", TANKS, "--columns", "uEst,yEst", "--na", "1", "--nb", "1",
            "--f-basis", "1", "--g-basis", "1"]
    assert main(args) == 0
    out = capsys.readouterr()
    assert "samples N = 1024" in out.out
    # the tank levels sit far from 0: without an operating point the user is told
    mean = f"{np.mean(fohw.read_record(TANKS, u='uEst', y='yEst').u):.4g}"   # as printed
    assert f"fohw: warning: fohw.identify: `u` has mean {mean}, " in out.err
    assert main(args + ["--operating-point", "mean"]) == 0
    assert "warning" not in capsys.readouterr().err


def test_header_with_u_and_y_is_used_by_default(tmp_path):
    path = write(tmp_path, "t,u,y\n0,1.0,5.0\n1,2.0,6.0\n2,3.0,7.0\n")
    rec = fohw.read_record(path)
    np.testing.assert_array_equal(rec.u, [1.0, 2.0, 3.0])
    np.testing.assert_array_equal(rec.y, [5.0, 6.0, 7.0])
    assert rec.dt is None


def test_more_than_two_columns_without_names_is_refused(tmp_path):
    path = write(tmp_path, "0 1.0 5.0\n1 2.0 6.0\n")
    with pytest.raises(fohw.ParameterError, match="3 signal columns .* u=... and y=..."):
        fohw.read_record(path)
    rec = fohw.read_record(path, u=1, y=2)
    np.testing.assert_array_equal(rec.y, [5.0, 6.0])


def test_byte_order_mark_is_not_a_header(tmp_path):
    path = write(tmp_path, "\ufeff1.0 2.0\n3.0 4.0\n".encode(), mode="wb")
    rec = fohw.read_record(path)
    assert rec.n_samples == 2 and rec.u[0] == 1.0


@pytest.mark.parametrize("first", ["0x10 1", "0.5 0.3.1"])
def test_a_malformed_first_row_is_an_error_not_a_header(tmp_path, first):
    path = write(tmp_path, f"{first}\n1.0 2.0\n", name="d.dat")
    with pytest.raises(fohw.DataFileError, match="line 1: .* is not a number"):
        read_table(path)


def test_comments_blank_lines_and_whitespace(tmp_path):
    path = write(tmp_path, "% DaISy-like header\n# more\n\n 1.0\t2.0 \n\n3.0   4.0\n", "d.dat")
    t = read_table(path)
    np.testing.assert_array_equal(t.data, [[1.0, 2.0], [3.0, 4.0]])
    assert t.names is None and t.scalars == {}


def test_sampling_time_by_name_and_given_once(tmp_path):
    path = write(tmp_path, "u,y,period\n1,2,0.1\n3,4,\n")
    assert fohw.read_record(path).dt is None            # not a recognised name: not guessed
    assert fohw.read_record(path, dt="period").dt == 0.1
    assert fohw.read_record(path, dt=0.5).dt == 0.5
    with pytest.raises(fohw.ParameterError, match="`dt` = 'Ts' is not a column"):
        fohw.read_record(path, dt="Ts")


@pytest.mark.parametrize("text, message", [
    ("u,y\n1,2\n3,\n4,5\n", "line 3: column 'y' has no value"),
    ("u,y\n1,2\n3,nan\n", "line 3 holds a non-finite value"),
    ("u,y\n1,2\n3,abc\n", "line 3: 'abc' is not a number"),
    ("# only a comment\n", "no data lines"),
    ("u,y,z\n1,2,\n3,4,\n", "column 'z' has a name but no values"),
])
def test_bad_tables_name_the_line(tmp_path, text, message):
    with pytest.raises(fohw.DataFileError, match=message):
        read_table(write(tmp_path, text))


def test_bad_column_choices(tmp_path):
    path = write(tmp_path, "a,b\n1,2\n3,4\n")
    with pytest.raises(fohw.ParameterError, match="same column"):
        fohw.read_record(path, u="a", y=0)
    with pytest.raises(fohw.ParameterError, match="'c' is not a column .* \\(a, b\\)"):
        fohw.read_record(path, u="a", y="c")
    with pytest.raises(fohw.ParameterError, match="has 2 signal column"):
        fohw.read_record(path, u=0, y=2)
    with pytest.raises(fohw.ParameterError, match="both"):
        fohw.read_record(path, u=0)


def test_a_directory_is_not_a_data_file(tmp_path):
    with pytest.raises(fohw.DataFileError, match="is a directory"):
        read_table(tmp_path)
    with pytest.raises(FileNotFoundError, match="data file not found"):
        read_table(tmp_path / "missing.csv")


def test_cli_refuses_the_same_column_twice(tmp_path, capsys):
    path = write(tmp_path, "1 2\n3 4\n5 6\n", "d.dat")
    assert main(["identify", str(path), "--columns", "0,0", "--na", "1", "--nb", "1",
                 "--f-basis", "1", "--g-basis", "1"]) == 2
    assert "same column twice" in capsys.readouterr().err


def test_cli_default_columns_never_guess(tmp_path, capsys):
    data = fohw.datasets.paper_example(300, random_state=0)
    named = tmp_path / "named.csv"
    named.write_text("t,u,y\n" + "\n".join(f"{k},{a:.17g},{b:.17g}" for k, (a, b)
                                            in enumerate(zip(data.u, data.y))) + "\n")
    args = ["--na", "2", "--nb", "2", "--f-basis", "2", "--g-basis", "3", "--json"]
    assert main(["identify", str(named), *args]) == 0          # picks u and y by name
    by_name = capsys.readouterr().out
    assert main(["identify", str(named), "--columns", "u,y", *args]) == 0
    assert capsys.readouterr().out == by_name
    unnamed = tmp_path / "three.dat"
    np.savetxt(unnamed, np.c_[np.arange(300), data.u, data.y])
    assert main(["identify", str(unnamed), *args]) == 2
    err = capsys.readouterr().err
    assert "has 3 columns: say which to use with --columns" in err and err.count("\n") == 1


def test_the_cli_takes_the_sampling_time_the_file_gives(tmp_path, capsys):
    """The tanks file gives Ts = 4 once: identify uses it unless --dt says otherwise."""
    args = ["identify", TANKS, "--columns", "uEst,yEst", "--na", "1", "--nb", "1",
            "--operating-point", "mean"]
    assert main(args + ["--save", str(tmp_path / "a.json")]) == 0
    assert fohw.load_result(tmp_path / "a.json").structure.dt == fohw.read_record(
        TANKS, u="uEst", y="yEst").dt == 4.0
    assert main(args + ["--dt", "1", "--save", str(tmp_path / "b.json")]) == 0
    assert fohw.load_result(tmp_path / "b.json").structure.dt == 1.0
    capsys.readouterr()
