"""fohw.read_record and the table parser under it (and under the command line)."""

import os

import numpy as np
import pytest

import fohw
from fohw.cli import main
from fohw.io import text as text_io
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
    assert rec.dt == 1.0 and rec.t0 == 0.0          # the column t is the time (issue 42)
    assert fohw.read_record(path, t=False).dt is None      # read without it: no sampling time


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


# --- issue 28 (28a) -------------------------------------------------------------------------

def test_a_file_that_changes_while_it_is_read_is_refused(tmp_path, monkeypatch):
    """Case 2: a file truncated (or grown) while it is read used to give fewer rows, silently."""
    path = write(tmp_path, "u,y\n" + "".join(f"{k},{k + 1}\n" for k in range(100)))
    real = text_io._read_lines

    def truncate_midway(src, decimal, *time):
        table = real(src, decimal, *time)
        with open(path, "r+") as fh:              # someone cuts the file while fohw reads it
            fh.truncate(200)
        return table

    monkeypatch.setattr(text_io, "_read_fast", lambda src, decimal: None)
    monkeypatch.setattr(text_io, "_read_lines", truncate_midway)
    with pytest.raises(fohw.DataFileError, match=r"d\.csv changed while it was read \(size "):
        fohw.read_record(path)


@pytest.mark.parametrize("tail", ["9,0.12", "9,"])
def test_a_last_line_without_its_end_is_refused(tmp_path, tail):
    """Case 2: a file cut mid-number (no line end on the last line) is not read as complete."""
    path = write(tmp_path, "u,y\n1,2\n3,4\n" + tail)
    with pytest.raises(fohw.DataFileError, match=r"d\.csv: the last line has no line end"):
        fohw.read_record(path)


def test_bytes_paths_and_file_objects_are_read(tmp_path):
    """Case 6: bytes paths gave a raw TypeError; file objects named no argument."""
    import io

    text = "u,y\n1,2\n3,4\n5,6\n"
    path = write(tmp_path, text)
    expected = fohw.read_record(path)
    for source in (os.fsencode(path), io.StringIO(text), io.BytesIO(text.encode())):
        rec = fohw.read_record(source)
        np.testing.assert_array_equal(rec.u, expected.u)
        np.testing.assert_array_equal(rec.y, expected.y)
    with open(path) as fh:
        assert fohw.read_record(fh).name == "d.csv"
    with open(path, "rb") as fh:
        np.testing.assert_array_equal(fohw.read_record(fh, dt=2.0).y, expected.y)
    rec = fohw.read_record(io.StringIO("t,u,y,Ts\n0,1,2,0.5\n0.5,3,4,\n"))
    assert rec.dt == 0.5 and rec.input_name == "u"
    with pytest.raises(fohw.DataFileError, match=r"<StringIO>: line 3: the time column 't' steps "
                       r"1 from line 2, but the column 'Ts' says 0.5"):
        fohw.read_record(io.StringIO("t,u,y,Ts\n0,1,2,0.5\n1,3,4,\n"))
    with pytest.raises(fohw.ParameterError, match="`path` must be a file path .* got int"):
        fohw.read_record(3)


def test_dt_must_name_a_value_given_once(tmp_path):
    """Case 12: dt="u" used to take the first input sample as the sampling time."""
    path = write(tmp_path, "u,y,Ts\n1,2,0.5\n3,4,\n")
    with pytest.raises(fohw.ParameterError, match="`dt` = 'u' names a signal column .* \\(Ts\\)"):
        fohw.read_record(path, dt="u")
    assert fohw.read_record(path, dt="Ts").dt == 0.5


def test_a_header_naming_a_column_twice_is_refused(tmp_path):
    """Case 12: `u,u,y` silently took the first u."""
    with pytest.raises(fohw.DataFileError, match="header on line 1 names 'u' twice \\(columns 0 "
                       "and 1\\)"):
        fohw.read_record(write(tmp_path, "u,u,y\n1,2,3\n4,5,6\n"))


@pytest.mark.parametrize("text, message", [
    # case 19: each is blamed on its own line, with its own diagnosis
    ("u,y\n" + "1,2\n" * 4 + "0.5,1,234.5\n" + "1,2\n" * 5,
     "line 6 has 3 field\\(s\\) but the header on line 1 has 2: an extra field .*\\(1,234.5"),
    ("u,y\n" + "1,2\n" * 9 + "1,2,3\n" + "1,2\n" * 3, "line 11 has 3 field\\(s\\) but the header"),
    ("1,2\n" * 9 + "1,2,3\n", "line 10 has 3 field\\(s\\) but line 1 \\(the first data line\\) has 2"),
    ("u,y\n" + "1,2\n" * 6 + "7\n" + "1,2\n" * 3, "line 8 has 1 field\\(s\\) but the header on "
     "line 1 has 2: a missing field"),
    ("u y\n" + "1 2\n" * 6 + "1 x\n", "line 8: 'x' is not a number \\(column 'y'\\)"),
])
def test_a_ragged_or_bad_row_is_blamed_on_its_own_line(tmp_path, text, message):
    with pytest.raises(fohw.DataFileError, match=message):
        read_table(write(tmp_path, text))


def test_the_line_reader_streams_the_file(tmp_path):
    """Case 19: the fallback reader holds numbers, not the file's lines (the old one kept every
    line as bytes, then as lists of str): reading 200 000 rows with one comment in the data
    allocates little more than the numbers."""
    import tracemalloc

    n = 200_000
    path = tmp_path / "big.csv"
    with open(path, "w") as fh:
        fh.write("u,y\n")
        fh.writelines(f"{k * 0.001!r},{k * 0.002!r}\n" for k in range(n // 2))
        fh.write("# a comment inside the data\n")
        fh.writelines(f"{k * 0.001!r},{k * 0.002!r}\n" for k in range(n // 2))
    tracemalloc.start()
    table = read_table(path)
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    assert table.data.shape == (n, 2)
    numbers = table.data.nbytes
    assert peak < 4 * numbers + 2**20, (peak, numbers)      # the old reader: ~ 40 x the numbers


@pytest.mark.parametrize("text", ['"u","y"\n"0.47","-0.02"\n"0.5","0.1"\n',
                                  "'u';'y'\n'0.47';'-0.02'\n'0.5';'0.1'\n",
                                  '"u","y"\n0.47,-0.02\n"0.5",0.1\n'])
def test_quoted_fields_are_read(tmp_path, text):
    """Case 20: every field quoted used to be "line 2 looks like a second header line"."""
    rec = fohw.read_record(write(tmp_path, text))
    np.testing.assert_array_equal(rec.u, [0.47, 0.5])
    np.testing.assert_array_equal(rec.y, [-0.02, 0.1])


def test_decimal_comma_on_a_headerless_comma_file_names_no_header(tmp_path):
    """Case 20: a header-less comma CSV read with decimal=',' called its first line a header."""
    path = write(tmp_path, "0.5,1.25\n0.25,0.5\n")
    with pytest.raises(fohw.DataFileError) as info:
        fohw.read_record(path, decimal=",")
    assert "line 1: '0.5,1.25' holds numbers separated by commas" in str(info.value)
    assert "header" not in str(info.value).split("d.csv")[1]


def test_a_header_separated_otherwise_than_the_data_is_refused(tmp_path):
    """Case 20: `u,y` above `;` data was "line 2 looks like a second header line"."""
    with pytest.raises(fohw.DataFileError, match="line 2 is separated by ';' but the header on "
                       "line 1 by ','"):
        fohw.read_record(write(tmp_path, "u,y\n1;2\n3;4\n"))
