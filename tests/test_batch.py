"""fohw.stream_fits / identify_many: any kind, any executor, failures isolated, results streamed.

The kinds come from the protocol's conformance test (``test_model_protocol.KINDS``): adding a
kind there adds it here. Each backend must give the same fits as the serial run, bit for bit
(the same deterministic computation on the same numbers); a record that fails is one named
outcome among the others; and records are read only as room frees up, so a run over a
generator yields its first outcome before the generator is exhausted.
"""

import concurrent.futures
import importlib
import json
import os
import threading
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor

import numpy as np
import pytest

import fohw
from fohw._parallel import progress_bar

# The protocol tests' kinds, from the module pytest loads (``--import-mode=importlib`` names it
# ``tests.test_model_protocol``; a second copy would register its kind twice).
_protocol = importlib.import_module("tests.test_model_protocol")
KINDS, _case = _protocol.KINDS, _protocol._case

FAST = dict(order_grid=1, n_starts=1)


def _same(a, b):
    return json.dumps(a.to_dict(), sort_keys=True) == json.dumps(b.to_dict(), sort_keys=True)


@pytest.fixture(scope="module")
def pools():
    with ThreadPoolExecutor(2) as threads, ProcessPoolExecutor(2) as processes:
        yield {"threads": threads, "processes": processes}


@pytest.fixture(scope="module")
def dask_client(dask_cluster_options):
    import distributed

    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  **dask_cluster_options) as cluster, \
            distributed.Client(cluster) as client:
        yield client


@pytest.mark.parametrize("factory", KINDS, ids=lambda f: f.__name__)
def test_every_backend_gives_the_serial_fits_for_every_kind(factory, pools, request):
    cases = [_case(factory, seed) for seed in (1, 2)]
    start = cases[0].start
    dt = start.dt if "dt" in start.config() else None
    pieces = [fohw.Record(c.u, c.y, dt=dt, name=f"seed {k}") for k, c in enumerate(cases)]
    # a pair, a Record (its sampling goes along), two Records as one data set (fitted jointly)
    records = [(cases[0].u, cases[0].y), pieces[1], pieces]
    alone = [fohw.fit(start, cases[0].u, cases[0].y, **FAST), fohw.fit(start, pieces[1], **FAST),
             fohw.fit(start, pieces, **FAST)]
    serial = list(fohw.stream_fits(records, start, **FAST))
    assert [item.index for item in serial] == [0, 1, 2]
    assert [item.name for item in serial] == ["records[0]", "seed 1", "records[2]"]
    assert all(item.ok and _same(item.result, fit) for item, fit in zip(serial, alone))
    backends = dict(pools)
    try:
        backends["dask"] = request.getfixturevalue("dask_client")    # the Client itself
    except pytest.skip.Exception:
        pass
    for name, executor in backends.items():
        items = list(fohw.stream_fits(records, start, executor=executor, **FAST))
        assert [item.index for item in items] == [0, 1, 2], name
        assert all(item.ok and _same(item.result, fit) for item, fit in zip(items, alone)), name
        listed = fohw.identify_many(records, model=start, executor=executor, **FAST)
        assert all(_same(r, fit) for r, fit in zip(listed, alone)), name


def _write(path, u, y):
    np.savetxt(path, np.column_stack([u, y]), delimiter=",", header="u,y", comments="",
               fmt="%.17g")
    return path


@pytest.mark.parametrize("backend", ["serial", "processes"])
def test_a_failing_record_is_named_and_the_others_go_on(tmp_path, pools, backend):
    c = _case(KINDS[2], 1)                                   # fractional_tf
    good = _write(tmp_path / "good.csv", c.u, c.y)
    records = [(c.u, c.y), str(tmp_path / "missing.csv"), good, (c.u, np.full_like(c.y, np.nan)),
               str(good), 3]
    executor = None if backend == "serial" else pools["processes"]
    items = list(fohw.stream_fits(records, c.start, executor=executor, **FAST))
    assert [item.index for item in items] == list(range(6))
    assert [item.ok for item in items] == [True, False, True, False, True, False]
    reference = fohw.fit(c.start, c.u, c.y, **FAST)
    assert _same(items[0].result, reference)
    from_file = fohw.fit(c.start, fohw.read_record(good), **FAST)    # its name and path go along
    for i in (2, 4):                                 # a path is read by the worker: same fit
        assert _same(items[i].result, from_file)
        assert items[i].result.parameters == reference.parameters
    assert items[2].name == str(good)
    missing = items[1]
    assert isinstance(missing.error, FileNotFoundError) and missing.result is None
    assert missing.message.startswith(f"records[1] ({tmp_path / 'missing.csv'}): "
                                      "FileNotFoundError")
    assert isinstance(items[3].error, fohw.FohwError) and "records[3]: " in items[3].message
    assert isinstance(items[5].error, fohw.ParameterError)
    assert "`records[5]` must be a Record, a pair (u, y) or a file path; got int" in \
        items[5].message
    # several records per task: the same outcomes, one item per record
    chunked = list(fohw.stream_fits(records, c.start, executor=executor, chunksize=4, **FAST))
    assert [(it.index, it.name, it.message) for it in chunked] == \
        [(it.index, it.name, it.message) for it in items]
    assert all(_same(a.result, b.result) for a, b in zip(chunked, items) if a.ok)
    # identify_many: the same outcomes as a list, a bad record refused before anything runs
    out = fohw.identify_many(records[:5], model=c.start, executor=executor, **FAST)
    assert [isinstance(r, Exception) for r in out] == [False, True, False, True, False]
    with pytest.raises(fohw.ParameterError, match=r"`records\[5\]`"):
        fohw.identify_many(records, model=c.start, **FAST)


@pytest.mark.parametrize("backend", ["serial", "threads", "processes"])
def test_records_are_read_only_as_room_frees_up(pools, backend):
    c = _case(KINDS[2], 1)
    pulled = []

    def records():
        for k in range(12):
            pulled.append(k)
            yield (c.u, c.y + 0.01 * k)

    executor = None if backend == "serial" else pools[backend]
    stream = fohw.stream_fits(records(), c.start, executor=executor, max_pending=3, **FAST)
    seen = []
    for item in stream:
        # never more than max_pending records read and not yet handed out
        assert len(pulled) - len(seen) <= 3, (len(pulled), len(seen))
        seen.append(item.index)
        if len(seen) == 1:
            assert len(pulled) < 12                   # the first outcome came early
    assert seen == list(range(12))
    unordered = fohw.stream_fits(records(), c.start, executor=executor, ordered=False, **FAST)
    assert sorted(item.index for item in unordered) == list(range(12))


def test_closing_the_stream_early_reads_no_more_records(pools):
    c = _case(KINDS[2], 1)
    pulled = []

    def records():
        for k in range(100):
            pulled.append(k)
            yield (c.u, c.y)

    stream = fohw.stream_fits(records(), c.start, executor=pools["threads"], max_pending=2,
                              **FAST)
    first = next(stream)
    stream.close()
    assert first.index == 0 and len(pulled) <= 3


def test_results_written_to_a_folder_by_the_workers(tmp_path, pools):
    c = _case(KINDS[2], 1)
    records = [(c.u, c.y), (c.u, np.full_like(c.y, np.nan))]
    items = list(fohw.stream_fits(records, c.start, executor=pools["processes"],
                                  out_dir=tmp_path, **FAST))
    assert items[0].result is None and items[0].path == str(tmp_path / "000000.json")
    assert _same(fohw.load_result(items[0].path), fohw.fit(c.start, c.u, c.y, **FAST))
    assert not items[1].ok and items[1].path == str(tmp_path / "000001.failed.txt")
    assert (tmp_path / "000001.failed.txt").read_text().startswith(type(items[1].error).__name__)
    with pytest.raises(fohw.ParameterError, match="`out_dir` must be an existing folder"):
        next(fohw.stream_fits(records, c.start, out_dir=tmp_path / "nope"))


def test_the_lagged_identify_and_read_keywords(tmp_path, pools):
    d = fohw.datasets.paper_example(300, random_state=0)
    path = tmp_path / "r.csv"
    np.savetxt(path, np.column_stack([d.y, d.u]), delimiter=",", header="out,in",
               comments="", fmt="%.17g")
    s = dict(na=2, nb=2, f_basis=2, g_basis=3)
    (item,) = fohw.stream_fits([os.fspath(path)], executor=pools["processes"],
                               read={"u": "in", "y": "out"}, **s)
    np.testing.assert_array_equal(item.result.theta, fohw.identify(d.u, d.y, **s).theta)
    # a Record goes to identify as itself: its sampling time is the fit's; a `dt` that
    # contradicts it, or non-uniform instants, are that record's failure
    rec = fohw.Record(d.u, d.y, dt=4.0)
    (first,) = fohw.stream_fits([rec], **s)
    assert first.result.dt == 4.0 and _same(first.result, fohw.identify(rec, **s))
    (second,) = fohw.stream_fits([rec], dt=2.0, **s)
    assert "the record is sampled every 4.0 but `dt` = 2.0" in second.message
    t = np.cumsum(np.random.default_rng(1).uniform(0.5, 1.5, d.u.size))
    (third,) = fohw.stream_fits([fohw.Record(d.u, d.y, t=t)], **s)
    assert "the record has non-uniform time stamps; the lagged kind" in third.message


def test_a_count_without_a_total(capsys, monkeypatch):
    import sys

    monkeypatch.setitem(sys.modules, "tqdm", None)
    monkeypatch.setitem(sys.modules, "tqdm.auto", None)
    bar = progress_bar(None, "fits", True, counting=True)
    bar.update(1)
    bar.close()
    assert capsys.readouterr().err == "fits: 1 done (0 s)\n"


MAIN_PID = os.getpid()


def square_or_die(x):
    """x**2, except x = 3 in a worker process, which it kills (os._exit)."""
    if x == 3 and os.getpid() != MAIN_PID:
        os._exit(3)
    return x * x


def test_a_record_that_kills_its_worker_loses_only_itself():
    from fohw._parallel import TaskError, stream_tasks

    with ProcessPoolExecutor(2) as pool:
        out = list(stream_tasks(square_or_die, ((x,) for x in range(10)), executor=pool,
                                max_pending=4))
    assert [i for i, _ in out] == list(range(10))
    lost = out[3][1]
    assert isinstance(lost, TaskError) and "kills its worker" in lost.message
    assert [v for i, v in out if i != 3] == [x * x for x in range(10) if x != 3]


# Issue 43: a per-record timeout (N4, N55) and a failed file for a worker that died (N21). The
# kinds are issue 43's Lag with a record that hangs (it waits for an event no one sets in time)
# or kills its worker process; at module level so that process workers can unpickle them.
RELEASE = threading.Event()         # set at the end: an abandoned thread returns


class Lag43(fohw.Model):
    """y[k] = a y[k-1] + b u[k-1] (issue 43's fixtures)."""

    def __init__(self, a=0.5, b=1.0):
        self.a, self.b = a, b

    @property
    def parameters(self):
        return fohw.Parameters([fohw.Parameter("a", self.a, bounds=(-0.99, 0.99)),
                                fohw.Parameter("b", self.b)])

    def with_parameters(self, values):
        v = self.parameters.with_values(values).valuesdict()
        return type(self)(v["a"], v["b"])

    def simulate(self, u, *, initial=None):
        u = self.check_input(u)
        if u[0] == 321.0:
            RELEASE.wait(1000)                       # hangs (N4)
        if u[0] == 123.0 and os.getpid() != MAIN_PID:
            os._exit(1)                              # kills its worker (N21)
        y = np.zeros_like(u)
        for k in range(1, u.size):
            y[k] = self.a * y[k - 1] + self.b * u[k - 1]
        return y


def _records43(n, marked, mark):
    out = []
    for k in range(n):
        u = np.random.default_rng(k).standard_normal(60)
        y = Lag43(0.8, 2.0).simulate(u)
        if k == marked:
            u[0] = mark
        out.append((u, y))
    return out


@pytest.mark.parametrize("backend", ["serial", "threads", "processes"])
def test_a_record_past_its_timeout_is_a_failure_and_the_others_go_on(tmp_path, pools, backend):
    records = _records43(4, 1, 321.0)
    executor = None if backend == "serial" else pools[backend]
    try:
        items = list(fohw.stream_fits(records, Lag43(), executor=executor, ordered=False,
                                      timeout=5.0, out_dir=tmp_path, **FAST))
    finally:
        RELEASE.set()                                # the abandoned thread (threads) returns
        RELEASE.clear()
    by_index = {item.index: item for item in items}
    assert sorted(by_index) == [0, 1, 2, 3]
    hung = by_index[1]
    assert not hung.ok and isinstance(hung.error, fohw.exceptions.TaskTimeoutError)
    assert "ran longer than `timeout` = 5 s" in hung.message
    assert (tmp_path / "000001.failed.txt").read_text().startswith("TaskTimeoutError: the fit ran")
    for k in (0, 2, 3):                              # the same fits as without a timeout
        assert by_index[k].ok and _same(fohw.load_result(by_index[k].path),
                                        fohw.fit(Lag43(), *records[k], **FAST))


def test_a_worker_that_dies_leaves_a_failed_file(tmp_path):
    records = _records43(8, 3, 123.0)
    with ProcessPoolExecutor(2) as pool:
        items = list(fohw.stream_fits(records, Lag43(), executor=pool, out_dir=tmp_path, **FAST))
    assert [item.ok for item in items] == [k != 3 for k in range(8)]
    assert items[3].path == str(tmp_path / "000003.failed.txt")
    text = (tmp_path / "000003.failed.txt").read_text()
    assert text.startswith("BrokenProcessPool") and "this task kills its worker" in text
    assert sorted(p.name for p in tmp_path.iterdir() if not p.name.startswith(".")) == \
        sorted([f"{k:06d}.json" for k in range(8) if k != 3] + ["000003.failed.txt"])


class _DeadExecutor(concurrent.futures.Executor):
    """An executor whose workers are gone: a task is accepted and never ends (issue 43 N55)."""

    def submit(self, fn, *args, **kwargs):
        return concurrent.futures.Future()


def test_the_stream_gives_up_on_an_executor_that_runs_nothing(tmp_path, monkeypatch):
    import fohw._parallel

    monkeypatch.setattr(fohw._parallel, "STALL_GRACE", 0.2)
    records = _records43(3, None, 0.0)
    items = list(fohw.stream_fits(records, Lag43(), executor=_DeadExecutor(), timeout=0.1,
                                  out_dir=tmp_path, **FAST))
    assert [item.index for item in items] == [0, 1, 2] and not any(item.ok for item in items)
    assert all(isinstance(item.error, fohw.exceptions.TaskTimeoutError) for item in items)
    assert "no task ended within 0.3 s" in items[0].message
    assert all((tmp_path / f"{k:06d}.failed.txt").exists() for k in range(3))
