"""Reliability (issue 14): no file is ever lost, no raw traceback, no silent NaN, and the
newcomer's identify -> save -> simulate loop closes.

The one-line errors of each bad input are in the catalogue, tests/test_bad_input.py (rows
marked #N); here are the behaviours a catalogue row cannot show: files that survive failures
and kills, warnings instead of silent wrong answers, and the command line's loop.
"""

import io
import json
import os
import re
import signal
import subprocess
import sys
import time
import types
from contextlib import redirect_stderr, redirect_stdout

import numpy as np
import pytest
import scipy.signal
from hypothesis import given, settings
from hypothesis import strategies as st

import fohw
from fohw.cli import _fit_text
from fohw.cli import main as cli
from fohw.io import files
from fohw.io import text as text_io

S = dict(na=2, nb=2, f_basis=2, g_basis=3)


def run_cli(args):
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        try:
            status = cli([str(a) for a in args])
        except SystemExit as stop:
            status = stop.code
    return status, out.getvalue(), err.getvalue()


def not_stages(err):
    """The lines of stderr that are not stage messages (``fohw: identifying ...``, ``fohw: done
    in 0.3 s``): errors, warnings, the Ctrl-C line."""
    stage = re.compile(r"fohw: (identifying with \S+ on \d+ samples \.\.\.|fitting \d+ "
                       r"candidates? \(.*\) on \d+ samples \.\.\.|simulating \d+ samples "
                       r"\.\.\.|done in .+)$")
    return [line for line in err.splitlines() if not stage.match(line)]


@pytest.fixture(scope="module")
def paper(tmp_path_factory):
    d = fohw.datasets.paper_example(400, random_state=0)
    folder = tmp_path_factory.mktemp("paper")
    path = folder / "good.dat"
    np.savetxt(path, np.c_[d.u, d.y])
    return d, path


@pytest.fixture
def old_file(tmp_path, paper):
    """A good saved result: the file every failure below must leave byte for byte."""
    d, _ = paper
    path = tmp_path / "old.json"
    fohw.save_result(fohw.identify(d.u, d.y, **S), path)
    return path, path.read_bytes()


# --- case 1: no file is ever lost ----------------------------------------------------------

def test_a_non_finite_result_is_refused_and_the_old_file_kept(old_file, paper):
    path, before = old_file
    import dataclasses

    bad = dataclasses.replace(fohw.identify(paper[0].u, paper[0].y, **S), J=float("inf"))
    with pytest.raises(fohw.ParameterError, match="field 'J' is inf"):
        fohw.save_result(bad, path)
    assert path.read_bytes() == before
    assert os.listdir(path.parent) == ["old.json"]          # no temporary file left


def test_a_save_that_fails_at_the_end_keeps_the_old_file(old_file, paper, monkeypatch):
    """The write fails at its last step (the rename): the old file is untouched."""
    path, before = old_file

    def fail(src, dst):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(files.os, "replace", fail)
    with pytest.raises(OSError, match="No space left"):
        fohw.save_result(fohw.identify(paper[0].u, paper[0].y, **S), path)
    assert path.read_bytes() == before
    assert os.listdir(path.parent) == ["old.json"]


def test_the_cli_save_that_fails_at_the_end_keeps_the_old_file(old_file, paper, monkeypatch):
    """A good run whose save fails at its last step (the rename): one line, status 2, the old
    file byte for byte and no temporary file left."""
    path, before = old_file

    def fail(src, dst):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(files.os, "replace", fail)
    status, _, err = run_cli(["identify", paper[1], "--na", 2, "--nb", 2, "--f-basis", 2,
                              "--g-basis", 3, "--save", path])
    assert status == 2 and len(not_stages(err)) == 1 and "No space left on device" in err, err
    assert path.read_bytes() == before
    assert os.listdir(path.parent) == ["old.json"]


def test_the_cli_run_that_fails_keeps_the_old_file(old_file, tmp_path):
    """Data of size 1e160 overflow the output basis: one line, status 2, old file intact."""
    path, before = old_file
    big = tmp_path / "big.dat"
    rng = np.random.default_rng(0)
    np.savetxt(big, 1e160 * rng.uniform(-1, 1, (200, 2)))
    status, _, err = run_cli(["identify", big, "--na", 2, "--nb", 2, "--f-basis", 2,
                              "--g-basis", 3, "--method", "hybrid", "--save", path])
    assert status == 2 and not_stages(err) == [err.splitlines()[-1]], err
    assert err.splitlines()[-1].startswith("fohw: error:"), err
    assert path.read_bytes() == before


def test_a_save_killed_midway_keeps_the_old_file(tmp_path):
    """SIGKILL while a large file is being written: the old file is byte-identical.

    The child writes ~200 MB through the same atomic writer; it is killed once writing has
    begun. The test checks that it really was killed mid-write (status -9 and its temporary
    file still there), so it cannot pass by the write finishing first.
    """
    target = tmp_path / "old.json"
    target.write_text('{"format": "fohw-result", "old": true}\n')
    before = target.read_bytes()
    child = subprocess.Popen(
        [sys.executable, "-c",
         "import sys; from fohw.io.files import write_text; text = '0123456789' * 20_000_000;"
         " print('writing', flush=True); write_text(text, sys.argv[1])", str(target)],
        stdout=subprocess.PIPE, text=True)
    assert child.stdout.readline().strip() == "writing"
    deadline = time.monotonic() + 30
    while not [n for n in os.listdir(tmp_path) if n.endswith(".tmp")]:
        assert time.monotonic() < deadline and child.poll() is None, "the write never started"
        time.sleep(0.001)
    child.send_signal(signal.SIGKILL)
    child.wait()
    child.stdout.close()
    assert child.returncode == -signal.SIGKILL
    assert [n for n in os.listdir(tmp_path) if n.endswith(".tmp")], "finished before the kill"
    assert target.read_bytes() == before


def test_ctrl_c_is_one_line_and_status_130(paper, monkeypatch):
    def interrupted(*args, **kwargs):
        raise KeyboardInterrupt

    monkeypatch.setattr(fohw, "identify", interrupted)
    status, _, err = run_cli(["identify", paper[1], "--na", 2, "--nb", 2])
    assert status == 130
    assert err.endswith("fohw: interrupted; no file was left half-written.\n"), err
    assert not_stages(err) == ["fohw: interrupted; no file was left half-written."], err


def test_an_unreadable_file_is_one_line(paper, monkeypatch):
    """Case 15 (PermissionError); root reads mode-000 files, so the refusal is simulated."""
    def refuse(*args, **kwargs):
        raise PermissionError(13, "Permission denied")

    monkeypatch.setattr(text_io, "open", refuse, raising=False)
    with pytest.raises(fohw.DataFileError, match="cannot be read \\(Permission denied\\)"):
        fohw.read_record(paper[1])
    status, _, err = run_cli(["identify", paper[1], "--na", 2, "--nb", 2])
    assert status == 2 and err.count("\n") == 1 and "Permission denied" in err


def test_output_paths_are_checked_before_the_run(paper, tmp_path, monkeypatch):
    """A bad --plot fails before identify is called (it used to fail after the whole run)."""
    def must_not_run(*args, **kwargs):
        raise AssertionError("identify ran before the output paths were checked")

    monkeypatch.setattr(fohw, "identify", must_not_run)
    for flag, value in (("--plot", tmp_path / "fit.xyz"), ("--plot", tmp_path / "no" / "f.png"),
                        ("--save", tmp_path), ("--save", tmp_path / "no" / "r.json")):
        status, _, err = run_cli(["identify", paper[1], "--na", 2, "--nb", 2, flag, value])
        assert status == 2 and err.startswith(f"fohw: error: {flag} "), err


# --- no silent NaN or silent wrong answer ---------------------------------------------------

def test_a_zero_output_is_reported_rank_deficient_not_a_traceback(paper):
    """Case 8: y = 0 (and u = y = 0) was `LinAlgError: singular matrix`."""
    d = paper[0]
    for u, y in ((d.u, 0 * d.y), (0 * d.u, 0 * d.y)):
        for method in ("varpro", "output_error"):
            with pytest.warns(fohw.RankDeficiencyWarning, match="rank deficient"):
                res = fohw.identify(u, y, method=method, **S)
            assert res.status == fohw.Status.RANK_DEFICIENT and not res.converged
            assert np.all(np.isfinite(res.theta))


def test_data_far_from_zero_without_an_offset_are_warned_about(paper):
    """Case 10: offset data used to converge silently to alpha ~ 0."""
    d = paper[0]
    mean = f"{np.mean(d.y + 3.0):.4g}"                # as the warning prints it
    with pytest.warns(fohw.DataWarning, match=f"`y` has mean {mean}, .* operating_point='mean'"):
        # and the fit that must explain the level with its dynamics is unstable in free run
        # on its own input (y^3 feedback): IMPLAUSIBLE, not CONVERGED (issue 36)
        with pytest.warns(fohw.ConvergenceWarning, match="free run on its own estimation"):
            fohw.identify(d.u, d.y + 3.0, **S)
    with pytest.warns(fohw.DataWarning, match="`u` has mean 1, and it is constant"):
        with pytest.warns(fohw.RankDeficiencyWarning):
            fohw.identify(np.ones_like(d.u), d.y, **S)
    res = fohw.identify(d.u + 5.0, d.y + 3.0, operating_point="mean", **S)   # no warning
    centred = fohw.identify(d.u + 5.0 - np.mean(d.u + 5.0), d.y + 3.0 - np.mean(d.y + 3.0), **S)
    assert res.converged
    np.testing.assert_array_equal(res.theta, centred.theta)   # the same fit, levels aside
    assert res.alpha == centred.alpha


def test_a_huge_basis_is_reported_for_the_paper_method(paper):
    """Case 13: f_basis = 50 with hybrid gave J = 1.6e10 and no conditioning warning."""
    d = paper[0]
    with pytest.warns(fohw.RankDeficiencyWarning, match="rank deficient: rank"):
        # its free run on its own input diverges too: IMPLAUSIBLE wins (issue 36)
        with pytest.warns(fohw.ConvergenceWarning, match="free run on its own estimation"):
            res = fohw.identify(d.u, d.y, method="hybrid", na=2, nb=2, f_basis=50, g_basis=3)
    assert res.status == fohw.Status.IMPLAUSIBLE and "Rank deficient: rank" in res.message


def test_tiny_data_give_finite_fit_indices():
    """Data x 1e-200: the fit index used to fail ('y is constant') from underflowed squares."""
    rng = np.random.default_rng(0)
    y = rng.normal(size=100)
    yhat = y + 0.1 * rng.normal(size=100)
    for scale in (1e-200, 1.0, 1e200):
        assert fohw.analysis.metrics.fit_percent(scale * y, scale * yhat) == pytest.approx(
            fohw.analysis.metrics.fit_percent(y, yhat), rel=1e-12)
        assert fohw.analysis.metrics.rmse(scale * y, scale * yhat) / scale == pytest.approx(
            np.sqrt(np.mean((y - yhat) ** 2)), rel=1e-12)


def test_data_whose_squares_underflow_are_warned_about(paper):
    """Data x 1e-170: J, the noise variance and the covariance are squares of 1e-170; they came
    out 0 and NaN without a word (and alpha moved 3e-7 from its value in normal units)."""
    d = paper[0]
    lin = dict(na=2, nb=2, f_basis=1, g_basis=1)
    with pytest.warns(fohw.DataWarning, match=r"`y` has RMS .*e-17\d, whose square is below"):
        res = fohw.identify(1e-170 * d.u, 1e-170 * d.y, **lin)
    assert res.J == 0.0                       # what the warning is about
    fohw.identify(1e-150 * d.u, 1e-150 * d.y, **lin)      # 1e-300 is a normal double: silent


def test_narrow_alpha_bounds_work_with_the_paper_method(paper):
    """Case 29: `--alpha-bounds 0.7,0.9 --method hybrid` asked for an --alpha0 that did not
    exist; the default start is now inside any bounds."""
    status, out, err = run_cli(["identify", paper[1], "--na", 2, "--nb", 2, "--f-basis", 2,
                                "--g-basis", 3, "--method", "hybrid", "--alpha-bounds", "0.7,0.9",
                                "--json"])
    assert status == 0, err
    assert 0.7 <= json.loads(out)["alpha"] <= 0.9


# --- the table reader ----------------------------------------------------------------------

def test_decimal_commas_on_request(tmp_path):
    path = tmp_path / "dc.csv"
    path.write_text("u;y\n0,5;1,25\n-0,25;0,5\n1;2\n")
    rec = fohw.read_record(path, decimal=",")
    np.testing.assert_array_equal(rec.u, [0.5, -0.25, 1.0])
    np.testing.assert_array_equal(rec.y, [1.25, 0.5, 2.0])
    status, out, err = run_cli(["identify", path, "--na", 1, "--nb", 1, "--decimal-comma",
                                "--method", "rls"])
    assert status == 0, err


def test_what_the_reader_skipped_is_reported(tmp_path):
    path = tmp_path / "r.csv"
    path.write_text("# logged 2026-11-23\nu,y,\n1,2,\n\n3,4,\n5,6,\n")
    table = text_io.read_table(path)
    assert table.skipped == ["header on line 2 (u, y)", "2 comment or blank line(s)",
                             "a trailing separator"]
    np.testing.assert_array_equal(table.data, [[1, 2], [3, 4], [5, 6]])


numbers = st.floats(allow_nan=False, allow_infinity=False, width=64)


@settings(max_examples=60, deadline=None)
@given(rows=st.lists(st.lists(numbers, min_size=2, max_size=2), min_size=1, max_size=20),
       sep=st.sampled_from([" ", "\t", ",", ";", " ,  "]),
       header=st.booleans(), fmt=st.sampled_from(["{!r}", "{:.6g}", "{:.17e}"]))
def test_the_fast_reader_equals_the_line_reader(tmp_path_factory, rows, sep, header, fmt):
    """Clean files go through numpy.loadtxt, the rest line by line: the same numbers."""
    path = tmp_path_factory.mktemp("t") / "t.csv"
    lines = (["u" + sep + "y"] if header else []) + \
        [sep.join(fmt.format(v) for v in row) for row in rows]
    path.write_text("\n".join(lines) + "\n")
    fast = text_io.read_table(path)
    slow = text_io._read_lines(str(path), ".")
    np.testing.assert_array_equal(fast.data, slow.data)
    assert fast.names == slow.names
    expected = np.array([[float(fmt.format(v)) for v in row] for row in rows])
    np.testing.assert_array_equal(fast.data, expected)


# --- the newcomer's loop ---------------------------------------------------------------------

def test_identify_save_then_simulate_the_result_file(paper, tmp_path):
    d, data = paper
    saved = tmp_path / "fit.json"
    status, out, err = run_cli(["identify", data, "--na", 2, "--nb", 2, "--f-basis", 2,
                                "--g-basis", 3, "--save", saved])
    assert status == 0, err
    assert "free-run simulation fit" in out and "stayed bounded" in out
    status, out, err = run_cli(["simulate", "--model", saved, "--input", data])
    assert status == 2 and "has 2 columns: say which to use with --column" in err   # no guess
    status, out, err = run_cli(["simulate", "--model", saved, "--input", data, "--column", 0])
    assert status == 0, err
    simulated = _simulated(out)
    np.testing.assert_array_equal(simulated, fohw.load_result(saved).simulate(d.u))
    status, out, err = run_cli(["simulate", "--model", saved, "--input", data, "--column", 0,
                                "--noise-std", 0.1, "--seed", 3])
    noisy = _simulated(out)
    v = 0.1 * np.random.default_rng(3).standard_normal(d.u.shape[0])
    np.testing.assert_array_equal(noisy, fohw.load_result(saved).simulate(d.u, noise=v))


def _simulated(text):
    """The output column of ``fohw simulate`` (CSV: comments, a header, the time if any, y)."""
    import io

    from fohw.io.text import read_table

    return read_table(io.StringIO(text)).data[:, -1]


def test_the_json_output_has_the_free_run(paper):
    status, out, _ = run_cli(["identify", paper[1], "--na", 2, "--nb", 2, "--f-basis", 2,
                              "--g-basis", 3, "--json"])
    record = json.loads(out)["estimation_record"]
    check = fohw.compare(fohw.identify(paper[0].u, paper[0].y, **S), paper[0].u, paper[0].y)
    assert record["free_run"]["bounded"] is True
    assert record["free_run"]["fit_percent"] == check.fit_simulation
    assert record["one_step"]["rmse"] == check.rmse_prediction


def test_a_diverging_free_run_is_said_loudly():
    check = types.SimpleNamespace(simulated=None, diverged="diverged at sample k = 112",
                                  fit_prediction=99.0, rmse_prediction=0.01)
    text = _fit_text(check)
    assert "FREE RUN DIVERGED (diverged at sample k = 112)" in text
    assert "do not use this model to simulate" in text


def test_the_python_default_is_the_recommended_method(paper):
    assert fohw.identify(paper[0].u, paper[0].y, **S).method == "varpro"


def test_select_prints_warnings_as_single_lines():
    """The refit of the winner used to print Python's two-line warnings on tank data."""
    from importlib import resources

    status, _, err = run_cli(["select", resources.files("fohw") / "data" / "cascaded_tanks.csv",
                              "--columns", "uEst,yEst", "--na", 1, "--f-basis", 1, "--g-basis", 1])
    assert status == 0
    lines = not_stages(err)
    assert lines and all(line.startswith("fohw: warning: ") for line in lines), err
    assert len(lines) == len(set(lines))


# --- found by review ---------------------------------------------------------------------------

@pytest.mark.parametrize("field, value, message", [
    ("offset", "1", "field 'offset' must be a finite number; got '1'"),
    ("orders", {"alpha": "x"}, "field 'orders' must be an object of finite numbers"),
    ("past", [0.0, None], "field 'past' must be a pair of finite numbers"),
    ("operating_point", "ab", "field 'operating_point' must be a pair of finite numbers"),
    ("input_range", "ab", "field 'input_range' must be a pair of finite numbers or null"),
])
def test_every_field_of_a_result_file_is_checked(old_file, field, value, message):
    path, _ = old_file
    d = json.loads(path.read_text())
    d[field] = value
    path.write_text(json.dumps(d))
    with pytest.raises(fohw.DataFileError, match=message):
        fohw.load_result(path)


def test_data_in_extreme_units_are_not_called_rank_deficient(paper):
    """Equilibration squared the columns: at 1e+-100 the regressors looked rank deficient."""
    d = paper[0]
    S2 = dict(na=2, nb=2, f_basis=2, g_basis=2)
    ref = fohw.identify(d.u, d.y, **S2)
    for scale in (1e-100, 1e100):
        res = fohw.identify(scale * d.u, scale * d.y, **S2)
        assert res.status == ref.status == fohw.Status.CONVERGED
        # as tight as the units invariance of tests/test_robustness.py (measured here 3e-11)
        assert res.alpha == pytest.approx(ref.alpha, abs=1e-9)


def test_saving_onto_the_data_file_is_refused(paper, tmp_path):
    data = tmp_path / "d.dat"
    data.write_bytes(paper[1].read_bytes())
    before = data.read_bytes()
    status, _, err = run_cli(["identify", data, "--na", 2, "--nb", 2, "--save", data])
    assert status == 2 and "is the file this run reads" in err
    assert data.read_bytes() == before


def test_a_symlink_is_written_through(old_file, paper, tmp_path):
    path, before = old_file
    link = tmp_path / "link.json"
    link.symlink_to(path)
    res = fohw.identify(paper[0].u, paper[0].y, method="structured", **S)
    fohw.save_result(res, link)
    assert link.is_symlink() and path.read_bytes() != before
    assert fohw.load_result(link).method == "structured"


def test_a_read_only_file_is_refused(old_file, paper, monkeypatch):
    """Root writes anything, so 'read-only' is what os.access says for the file itself (the
    folder stays writable, as it must for the refusal to be the file's)."""
    path, before = old_file
    real_access = os.access

    def access(p, mode):
        if os.path.realpath(p) == os.path.realpath(path) and mode == os.W_OK:
            return False
        return real_access(p, mode)

    monkeypatch.setattr(files.os, "access", access)
    with pytest.raises(fohw.DataFileError, match="is read-only; fohw does not replace it"):
        fohw.save_result(fohw.identify(paper[0].u, paper[0].y, **S), path)
    assert path.read_bytes() == before


def test_numbers_python_alone_would_accept_are_refused(tmp_path):
    for text in ("1_000 2\n3 4\n", "\u0661 2\n3 4\n"):
        path = tmp_path / "n.dat"
        path.write_text(text, encoding="utf-8")
        with pytest.raises(fohw.DataFileError, match="line 1: .* is not a number"):
            text_io.read_table(path)


def test_the_selection_csv_is_saved_atomically(tmp_path, monkeypatch):
    """Selection.to_csv goes through the same writer: a failed rename keeps the old file."""
    path = tmp_path / "rows.csv"
    path.write_text("old\n")
    rng = np.random.default_rng(0)
    u = rng.uniform(-1, 1, 300)
    y = np.convolve(u, [0.0, 0.5, 0.25])[:300] + 0.01 * rng.standard_normal(300)
    sel = fohw.select_structure(u, y, [dict(na=1)], nb=1, f_basis=1, g_basis=1)

    def fail(src, dst):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(files.os, "replace", fail)
    with pytest.raises(OSError, match="No space left"):
        sel.to_csv(path)
    assert path.read_text() == "old\n" and os.listdir(tmp_path) == ["rows.csv"]


def test_an_unknown_divergence_cause_is_not_renamed():
    """An unknown `cause` used to become 'growth' silently."""
    with pytest.raises(ValueError, match="`cause` must be one of"):
        fohw.SimulationDivergedError(3, 1.0, 1.0, "overflow")
    assert fohw.SimulationDivergedError(3, 1.0, 1.0, "output_basis").cause == "output_basis"


# --- issue 28 (28a) -------------------------------------------------------------------------

def test_a_figure_on_a_full_disk_keeps_the_old_figure(paper, tmp_path, monkeypatch):
    """Case 1: --plot over an existing figure on a full disk leaves the old figure byte for byte
    (figures used to be written directly, truncating it) and no temporary file."""
    from matplotlib.figure import Figure

    target = tmp_path / "fig.png"
    target.write_bytes(b"\x89PNG old figure")
    before = target.read_bytes()

    def full_disk(self, fname, *args, **kwargs):
        if hasattr(fname, "write"):
            fname.write(b"\x89PNG partial")                 # part of it is written, then
        else:
            with open(fname, "wb") as fh:
                fh.write(b"\x89PNG partial")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(Figure, "savefig", full_disk)
    status, _, err = run_cli(["identify", paper[1], "--na", 2, "--nb", 2, "--plot", target])
    assert status == 2 and "No space left on device" in err and str(target) in err, err
    assert ".tmp" not in err
    assert target.read_bytes() == before
    assert sorted(os.listdir(tmp_path)) == ["fig.png"]


def test_every_figure_fohw_writes_goes_through_the_atomic_writer():
    """Case 1, the cause: no module of fohw calls savefig on a path itself (a figure's PNG for a
    notebook, written to an in-memory buffer, is no file)."""
    from pathlib import Path

    src = Path(fohw.__file__).parent
    direct = [f"{p.relative_to(src)}:{i}" for p in src.rglob("*.py")
              for i, line in enumerate(p.read_text().splitlines(), 1)
              if ".savefig(" in line and p.name != "files.py" and not line.lstrip().startswith("#")
              and "``" not in line and ":meth:" not in line and ".savefig(buf," not in line]
    assert direct == []


@pytest.mark.parametrize("target", ["/proc/fit.json", "/sys/fit.json", "dangling", "fifo"])
def test_outputs_that_cannot_be_written_are_refused_before_the_run(paper, tmp_path, monkeypatch,
                                                                   target):
    """Cases 13 and 21: /proc, /sys, a dangling link and a FIFO are refused before the fit (they
    used to fail after the whole run naming a hidden temporary file, or replace the FIFO)."""
    def must_not_run(*args, **kwargs):
        raise AssertionError("identify ran before the output paths were checked")

    if target == "dangling":
        target = tmp_path / "link.json"
        target.symlink_to(tmp_path / "nowhere" / "fit.json")
    elif target == "fifo":
        target = tmp_path / "fifo.json"
        os.mkfifo(target)
    monkeypatch.setattr(fohw, "identify", must_not_run)
    for flag in ("--save", "--plot"):
        path = str(target).replace(".json", ".png") if flag == "--plot" and "/proc" in str(
            target) else target
        status, out, err = run_cli(["identify", paper[1], "--na", 2, "--nb", 2, flag, path])
        assert status == 2 and err.startswith(f"fohw: error: {flag} "), err
        assert ".tmp" not in err and err.count("\n") == 1
    if isinstance(target, os.PathLike) and target.name == "fifo.json":
        import stat

        assert stat.S_ISFIFO(os.lstat(target).st_mode)          # still a FIFO


def test_simulate_output_into_proc_is_refused_before_the_run(tmp_path):
    model = tmp_path / "m.json"
    fohw.save_model(fohw.datasets.paper_model(), model)
    inp = tmp_path / "u.dat"
    inp.write_text("0.1\n0.2\n")
    status, out, err = run_cli(["simulate", "--model", model, "--input", inp, "--output",
                                "/proc/y.txt"])
    assert status == 2 and out == "" and "--output '/proc/y.txt': no file can be created" in err


def test_the_atomic_writer_names_the_file_not_its_temporary(tmp_path, monkeypatch):
    def full(fd):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(files.os, "fsync", full)
    with pytest.raises(OSError) as info:
        files.write_text("x", tmp_path / "y.txt")
    assert info.value.filename == str(tmp_path / "y.txt") and ".tmp" not in str(info.value)
    assert os.listdir(tmp_path) == []


# issue 34 (io)
@pytest.mark.parametrize("model", [
    fohw.FractionalTF([1.0, 2.0], [1.7, 0.3], [1.0, -3.0], [0.4, 0.0], delay=0.3),   # unstable
    fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.8, 0.0], delay=0.2),
    fohw.FractionalTF([1.0, 0.5], [0.0, -0.5], [2.0, 1.0], [0.6, 0.0]),
], ids=["unstable improper, delay", "stable, delay", "Warburg numerator"])
@pytest.mark.parametrize("zeros", [1, 5, 17, 64])
def test_a_transfer_function_output_shifts_exactly_with_prepended_zeros(model, zeros):
    """Issue 34 #6: zero initial conditions make G time-invariant: prepending zeros to u shifts y
    by as many samples, bit for bit, and y is exactly 0 until the (delayed) input arrives. The
    FFT solve left ~1e-13 there, and the unstable model amplified it until prepending 1 to 64
    zeros changed the output 1.5 to 1e15 times."""
    u = np.random.default_rng(1).standard_normal(200)
    u[:3] = 0.0
    y = model.simulate(u, dt=0.1, divergence_threshold=np.inf)
    shifted = model.simulate(np.r_[np.zeros(zeros), u], dt=0.1, divergence_threshold=np.inf)
    assert np.array_equal(shifted[zeros:], y)
    first = 3 + round(model.delay / 0.1)
    assert np.all(shifted[:zeros + first] == 0.0) and y[first] != 0.0


def test_a_diverging_transfer_function_is_refused_at_a_stated_bound():
    """Issue 34 #6: an unstable model's output is refused once it grows 1e8 times past the output
    scale of a bounded response (as fohw.simulate does); np.inf lifts the bound; a stable slow
    model and an integrator on a long record are not refused."""
    G = fohw.FractionalTF([1.0, 2.0], [1.7, 0.3], [1.0, -3.0], [0.4, 0.0], delay=0.3)
    u = np.random.default_rng(1).standard_normal(200)
    with pytest.raises(fohw.SimulationDivergedError) as info:
        G.simulate(u, dt=0.1)
    assert info.value.cause == "transfer_function" and "divergence_threshold=np.inf" in str(info.value)
    assert np.max(np.abs(G.simulate(u, dt=0.1, divergence_threshold=np.inf))) > 1e50
    step = np.r_[0.0, np.ones(9999)]
    slow = fohw.FractionalTF([1.0], [0.0], [1e4, 1.0], [1.0, 0.0])         # tau = 1e4, dt = 1e-3
    assert slow.simulate(step, dt=1e-3)[-1] > 0.0
    integrator = fohw.FractionalTF([1.0], [0.0], [1.0], [1.0])
    np.testing.assert_allclose(integrator.simulate(step, dt=0.01)[-1], 9999 * 0.01, rtol=1e-12)
    growing = fohw.FractionalTF([1.0], [0.0], [1.0, -1.0], [1.0, 0.0])        # 1 / (s - 1)
    t = np.arange(0.0, 30.0, 0.01)
    with pytest.raises(fohw.SimulationDivergedError):
        growing.step(t)
    # backward Euler multiplies by 1 / (1 - dt) >= e^dt per step: past the exact e^t - 1
    assert growing.step(t, divergence_threshold=np.inf)[-1] > np.exp(29.99) - 1.0


def test_dataframe_columns_are_matched_by_the_names_the_result_keeps():
    """Issue 34 #27: a fit on columns ['a', 'b'] given a frame with ['b', 'a'] matched them by
    position (fit -7.9 points, no word); now by name, everywhere a result meets an input: the
    same numbers as the array in the fit's order."""
    pd = pytest.importorskip("pandas")
    d = fohw.datasets.paper_example(400, random_state=0)
    u2 = np.column_stack([d.u, np.random.default_rng(5).uniform(-1, 1, 400)])
    r = fohw.identify(pd.DataFrame(u2, columns=["a", "b"]), d.y, **S)
    swapped = pd.DataFrame(u2[:, ::-1], columns=["b", "a"])
    assert r.structure.inputs == ("a", "b")
    assert fohw.compare(r, swapped, d.y).fit == fohw.compare(r, u2, d.y).fit
    np.testing.assert_array_equal(r.simulate(swapped), r.simulate(u2))
    np.testing.assert_array_equal(fohw.simulate(r, swapped), fohw.simulate(r, u2))
    unnamed = fohw.identify(u2, d.y, **S)                       # inputs u1, u2: by position
    np.testing.assert_array_equal(unnamed.simulate(pd.DataFrame(u2, columns=["x", "y"])),
                                  unnamed.simulate(u2))


def test_a_two_input_result_from_the_command_line_is_simulated_by_it(tmp_path):
    """Issue 34 #32: `fohw identify two.csv --columns u1,u2,y --save two.json` could not be
    simulated by `fohw simulate` ('`u` must be 2-D' with one --column, '--column needs 1 entry'
    with two), and --plot failed after the run ('the result has no model to simulate')."""
    d = fohw.datasets.paper_example(400, random_state=0)
    u2 = np.column_stack([d.u, np.random.default_rng(5).uniform(-1, 1, 400)])
    data, inp = tmp_path / "two.csv", tmp_path / "inp.csv"
    data.write_text("u1,u2,y\n" + "".join(f"{a!r},{b!r},{c!r}\n" for (a, b), c in
                                          zip(u2.tolist(), d.y.tolist())))
    inp.write_text("u2,u1\n" + "".join(f"{b!r},{a!r}\n" for a, b in u2[:60].tolist()))
    status, _, err = run_cli(["identify", data, "--columns", "u1,u2,y", "--na", 2, "--nb", 2,
                              "--f-basis", 2, "--g-basis", 3, "--save", tmp_path / "two.json",
                              "--plot", tmp_path / "two.png", "-q"])
    assert status == 0 and err == "" and (tmp_path / "two.png").stat().st_size > 0
    expected = fohw.load_result(tmp_path / "two.json").simulate(u2[:60])
    for column in ([], ["--column", "u1,u2"], ["--column", "u2,u1"], ["--column", "1,0"]):
        status, out, err = run_cli(["simulate", "--model", tmp_path / "two.json", "--input", inp,
                                    *column, "-q"])
        assert status == 0 and err == "", (column, err)
        np.testing.assert_array_equal(_simulated(out), expected)


def _proc_stat(pid):
    """``(state, parent pid)`` of a process from /proc, or None once it is gone."""
    try:
        with open(f"/proc/{pid}/stat") as fh:
            fields = fh.read().rsplit(")", 1)[1].split()
    except OSError:
        return None
    return fields[0], int(fields[1])


def _children(pid):
    """The process ids whose parent is ``pid`` (from /proc)."""
    return [int(e) for e in os.listdir("/proc")
            if e.isdigit() and (st := _proc_stat(e)) is not None and st[1] == pid]


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_workers_end_when_select_is_killed(tmp_path):
    """Issue 34 #34: SIGKILL of `fohw select --jobs 2` left both workers alive 120 s later.
    The pool's initializer (fohw.analysis.batch.end_with_parent) ends them: gone within 5 s."""
    d = fohw.datasets.paper_example(3000, random_state=0)
    data = tmp_path / "d.dat"
    np.savetxt(data, np.c_[d.u, d.y])
    child = subprocess.Popen([sys.executable, "-m", "fohw", "select", str(data), "--na", "1,2,3",
                              "--f-basis", "1,2,3", "--g-basis", "1,2,3", "--method",
                              "output_error", "--jobs", "2", "-q"],
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 60
    while len(workers := _children(child.pid)) < 2:
        assert time.monotonic() < deadline and child.poll() is None, "no workers started"
        time.sleep(0.05)
    child.send_signal(signal.SIGKILL)
    child.wait()
    deadline = time.monotonic() + 5
    alive = workers
    while alive and time.monotonic() < deadline:
        time.sleep(0.1)
        alive = [w for w in workers if (st := _proc_stat(w)) is not None and st[0] != "Z"]
    for w in alive:                                   # do not leave them running
        os.kill(w, signal.SIGKILL)
    assert not alive, f"workers {alive} outlived their killed parent"


@settings(max_examples=60, deadline=None)
@given(den_order=st.floats(0.1, 2.0), num_order=st.floats(-0.9, 2.5), a0=st.floats(-3.0, 3.0),
       b1=st.floats(-2.0, 2.0), delay=st.integers(0, 5), zeros=st.integers(1, 40),
       n=st.integers(1, 300), seed=st.integers(0, 2**32 - 1))
def test_fuzz_transfer_function_simulation_is_shift_invariant_and_linear(
        den_order, num_order, a0, b1, delay, zeros, n, seed):
    """Issue 34 #6, the fuzz target: for any G in the ordinary domain, prepending zeros shifts
    the output bit for bit (or moves the divergence refusal by as many samples), and a stable
    proper G is linear to rounding (1e-9 of the output's size)."""
    G = fohw.FractionalTF([1.0, b1], [num_order, 0.0], [1.0, a0], [den_order, 0.0], delay=0.1 * delay)
    rng = np.random.default_rng(seed)
    u, v = rng.standard_normal(n), rng.standard_normal(n)
    padded = np.r_[np.zeros(zeros), u]
    try:
        y = G.simulate(u, dt=0.1)
    except fohw.SimulationDivergedError as err:
        with pytest.raises(fohw.SimulationDivergedError) as again:
            G.simulate(padded, dt=0.1)
        assert again.value.sample == err.sample + zeros and again.value.value == err.value
        return
    shifted = G.simulate(padded, dt=0.1)
    assert np.array_equal(shifted[zeros:], y) and not np.any(shifted[:zeros])
    try:
        stable = G.is_stable()
    except fohw.ParameterError as err:            # coefficients beyond the argument principle
        assert "beyond double precision" in str(err)
        return
    if stable and num_order <= den_order:
        both = G.simulate(u + 2.0 * v, dt=0.1)
        scale = max(np.abs(y).max(), np.abs(both).max(), 1e-300)
        np.testing.assert_allclose(both, y + 2.0 * G.simulate(v, dt=0.1), rtol=0, atol=1e-9 * scale)


def test_an_expanded_integer_polynomial_simulates_to_its_conditioning():
    """Found with issue 34 #6: 1/(s + 1)^5 written as one polynomial simulated at dt = 0.01 by the
    FFT divide and conquer ended 10.96 away from its step response (of size 1) after 2000
    samples. Integer orders give polynomial weights; the recursion itself is now run, and
    agrees with five backward-Euler sections in cascade (the same discretisation, well
    conditioned) to the expanded form's own conditioning, eps * sum|c| / |sum c|."""
    h, n = 0.01, 2000
    G = fohw.FractionalTF([1.0], [0.0], np.poly(-np.ones(5)), np.arange(5.0, -1.0, -1.0))
    u = np.r_[0.0, np.ones(n - 1)]
    x = u.copy()
    for _ in range(5):                                      # (1 + (1 - q^-1)/h)^-1, five times
        x = scipy.signal.lfilter([h / (1 + h)], [1.0, -1.0 / (1 + h)], x)
    c = (1.0 / h + 1.0) ** 5 * np.poly(np.full(5, 1.0 / (1.0 + h)))     # the weights of (s+1)^5
    bound = 10 * np.finfo(float).eps * np.sum(np.abs(c)) / abs(np.sum(c))
    np.testing.assert_allclose(G.simulate(u, dt=h), x, rtol=0, atol=bound)


# issue 34 (fits): circuits #15 and the fuzz targets of every kind's simulate and fit
def _cell(sign=1.0):
    """Issue 34's circuit record: 20 s current steps from U(-3, 1.2) A, ``(u, v)``."""
    rng = np.random.default_rng(1)
    i = np.repeat(rng.uniform(-3.0, 1.2, 30), 20)
    soc = 0.8 + np.cumsum(i) / (3600 * 5)
    truth = fohw.EquivalentCircuit([fohw.ZARC(0.012, 50.0, 0.55)], r0=0.015, a=3.3, b=0.9)
    v = truth.simulate(np.column_stack([i, soc])) + 1e-4 * rng.standard_normal(i.size)
    return np.column_stack([sign * i, soc]), v


@pytest.mark.parametrize("elements", [(), ("zarc",)])
def test_the_other_current_sign_is_named_not_called_rank_deficient(elements):
    """Issue 34 #15: a discharge-positive current (the other convention) ended in 'no grid point
    gave non-negative resistances; widen `tau_bounds`', then in a rank-deficiency warning about
    tau1 and alpha1 ("remove a basis function or a lag"). Issue 37: the record is checked against
    the circuit's `current_sign` before any fit, and the refusal names the other convention."""
    u, v = _cell(sign=-1.0)
    model = fohw.EquivalentCircuit(list(elements), tau_bounds=(1.0, 500.0))
    with pytest.raises(fohw.ParameterError, match="current_sign='discharge_positive'") as err:
        fohw.fit(model, u, v)
    assert "tau_bounds" not in str(err.value) and "rank" not in str(err.value)
    good = fohw.fit(model, *_cell())                 # the same record in the fit's convention
    assert good.converged and good.parameters["R0"].value > 0.01
    flipped = fohw.EquivalentCircuit(list(elements), tau_bounds=(1.0, 500.0),
                                     current_sign="discharge_positive")
    same = fohw.fit(flipped, u, v)                   # the other record, its convention declared
    assert same.converged
    assert same.parameters["R0"].value == pytest.approx(good.parameters["R0"].value, rel=1e-6)


FUZZ = settings(max_examples=15, deadline=None, derandomize=True)
_TF_KIND = dict(num=[1.0], num_orders=[0.0], den_orders=[0.8, 0.0])


def _fhw(den_order, a0, p2, output_map):
    G = fohw.FractionalTF([1.0], [0.0], [1.0, a0], [den_order, 0.0])
    return fohw.FractionalHW(G, p=[1.0, p2], output_map=output_map, dt=0.1)


@FUZZ
@given(den_order=st.floats(0.1, 1.9), a0=st.floats(0.1, 3.0), p2=st.floats(-1.0, 1.0),
       cubic=st.booleans(), zeros=st.integers(1, 30), n=st.integers(2, 200),
       seed=st.integers(0, 2**32 - 1))
def test_fuzz_fractional_hw_simulation_is_shift_invariant_and_linear(den_order, a0, p2, cubic,
                                                                       zeros, n, seed):
    """Prepending zeros to u shifts a FractionalHW's output exactly (f(0) = 0, G at rest, h(0) = 0);
    with p = [1, 0] and no output map it is G: linear to rounding."""
    m = _fhw(den_order, a0, p2, 3 if cubic else None)
    if cubic:
        m = m.with_parameters({"h_c2": 0.1, "h_c3": -0.05})
    rng = np.random.default_rng(seed)
    u, w = rng.standard_normal(n), rng.standard_normal(n)
    y = m.simulate(u)
    shifted = m.simulate(np.r_[np.zeros(zeros), u])
    assert np.all(np.isfinite(y)) and np.array_equal(shifted[zeros:], y)
    assert not np.any(shifted[:zeros])
    lin = _fhw(den_order, a0, 0.0, None)
    both = lin.simulate(u + 2.0 * w)
    scale = max(np.abs(both).max(), 1e-300)
    np.testing.assert_allclose(both, lin.simulate(u) + 2.0 * lin.simulate(w), rtol=0,
                               atol=1e-12 * scale)


@FUZZ
@given(kinds=st.lists(st.sampled_from(["rc", "zarc", "warburg"]), max_size=3),
       tau=st.floats(1.0, 100.0), alpha=st.floats(0.2, 0.9), zeros=st.integers(1, 30),
       n=st.integers(2, 300), seed=st.integers(0, 2**32 - 1))
def test_fuzz_circuit_simulation_is_shift_invariant_and_linear_in_the_current(kinds, tau, alpha,
                                                                                zeros, n, seed):
    """Without c3 i^3 and an OCV map, v - (a + b soc) is linear in the current; prepending zero
    current (the state of charge held at its first value) shifts it (elements at rest)."""
    elements = [fohw.RC(0.01, tau) if k == "rc" else fohw.ZARC(0.01, tau, alpha) if k == "zarc"
                else fohw.Warburg(0.002, alpha) for k in kinds]
    cell = fohw.EquivalentCircuit(elements, r0=0.015, a=3.3, b=0.9)
    rng = np.random.default_rng(seed)
    i1, i2 = rng.uniform(-3, 1.2, n), rng.uniform(-3, 1.2, n)
    soc = rng.uniform(0.2, 0.8, n)
    rest = cell.simulate(np.column_stack([0 * i1, soc]))
    np.testing.assert_array_equal(rest, 3.3 + 0.9 * soc)

    def part(i):
        return cell.simulate(np.column_stack([i, soc])) - rest

    both = part(i1 + 2.0 * i2)
    np.testing.assert_allclose(both, part(i1) + 2.0 * part(i2), rtol=0,
                               atol=1e-12 * max(np.abs(both).max(), 1e-300))
    y = cell.simulate(np.column_stack([i1, soc]))
    shifted = cell.simulate(np.column_stack([np.r_[np.zeros(zeros), i1],
                                             np.r_[np.full(zeros, soc[0]), soc]]))
    np.testing.assert_array_equal(shifted[:zeros], np.full(zeros, 3.3 + 0.9 * soc[0]))
    np.testing.assert_allclose(shifted[zeros:], y, rtol=0, atol=1e-12 * np.abs(y).max())


@FUZZ
@given(na=st.integers(1, 2), nb=st.integers(1, 2), alpha=st.floats(0.1, 1.5),
       scale=st.floats(0.0, 0.2), zeros=st.integers(1, 30), n=st.integers(3, 200),
       seed=st.integers(0, 2**32 - 1))
def test_fuzz_lagged_model_simulation_is_shift_invariant_and_linear(na, nb, alpha, scale, zeros, n,
                                                                      seed):
    """The lagged HammersteinWiener at rest: prepending zeros shifts its free run (f(0) = g(0) =
    0); with p = q = [1] (linear bases) it is linear in u to rounding."""
    rng = np.random.default_rng(seed)
    a = scale * rng.uniform(-1, 1, na) / na
    b = rng.uniform(-1, 1, nb)
    m = fohw.HammersteinWiener(a, b, [1.0, rng.uniform(-1, 1)], [1.0, 0.3 * rng.uniform(-1, 1)],
                               alpha)
    u, w = rng.uniform(-1, 1, n), rng.uniform(-1, 1, n)
    try:
        y = m.simulate(u)
    except fohw.SimulationDivergedError as err:
        assert 0 <= err.sample < n
        return
    shifted = m.simulate(np.r_[np.zeros(zeros), u])
    # the GL difference's FFT path (over 160 samples) is exact to rounding only (SPEC section 2)
    tol = 1e-12 * max(np.abs(y).max(), 1.0)
    assert np.all(np.abs(shifted[:zeros]) <= tol)
    np.testing.assert_allclose(shifted[zeros:], y, rtol=0, atol=tol)
    lin = fohw.HammersteinWiener(a, b, [1.0], [1.0], alpha)
    both = lin.simulate(u + 2.0 * w)
    np.testing.assert_allclose(both, lin.simulate(u) + 2.0 * lin.simulate(w), rtol=0,
                               atol=1e-12 * max(np.abs(both).max(), 1.0))


def _fuzz_models():
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0], dt=0.1)
    return {"FractionalTF": G,
            "FractionalHW": fohw.FractionalHW(G, p=[1.0, 0.0], dt=0.1),
            "EquivalentCircuit": fohw.EquivalentCircuit(["zarc"], tau_bounds=(1.0, 50.0), n_tau=4,
                                                        n_alpha=3),
            "HammersteinWiener": fohw.HammersteinWiener([0.1], [0.5], [1.0], [1.0], 0.6)}


@FUZZ
@given(kind=st.sampled_from(["FractionalTF", "FractionalHW", "EquivalentCircuit",
                             "HammersteinWiener"]),
       n=st.integers(8, 60), noise=st.floats(0.0, 1.0), seed=st.integers(0, 2**32 - 1))
def test_fuzz_fit_never_marks_garbage_converged(kind, n, noise, seed):
    """fohw.fit of every kind on small random records (a true model's output plus noise, or pure
    noise): it raises a named error, warns, or returns a result whose model simulates finitely and
    reproduces the result's own residuals and SSE to rounding; CONVERGED then has a covariance."""
    model = _fuzz_models()[kind]
    rng = np.random.default_rng(seed)
    if kind == "EquivalentCircuit":
        i = np.repeat(rng.uniform(-3, 1.2, n // 4 + 1), 4)[:n]
        u = np.column_stack([i, np.clip(0.5 + np.cumsum(i) / 3600, 0, 1)])
        truth = fohw.EquivalentCircuit([fohw.ZARC(0.01, 10.0, 0.6)], r0=0.015, a=3.3)
        y = truth.simulate(u) + 0.01 * noise * rng.standard_normal(n)
    else:
        u = rng.standard_normal(n)
        y = model.simulate(u) + noise * rng.standard_normal(n)
    import warnings

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", fohw.ConvergenceWarning)
        warnings.simplefilter("ignore", fohw.RankDeficiencyWarning)
        try:
            fit = fohw.fit(model, u, y, n_starts=1, max_nfev=50)
        except (fohw.ParameterError, fohw.DimensionError) as err:
            assert str(err)
            return
    yhat = fit.simulate(u)
    assert np.all(np.isfinite(yhat)) and np.isfinite(fit.sse)
    np.testing.assert_allclose(y - yhat, fit.residuals, rtol=0, atol=1e-9 * np.abs(y).max())
    np.testing.assert_allclose(np.sum((y - yhat) ** 2), fit.sse, rtol=1e-8, atol=1e-300)
    if fit.status == fohw.Status.CONVERGED:
        assert fit.covariance is not None and np.all(np.isfinite(fit.covariance))
