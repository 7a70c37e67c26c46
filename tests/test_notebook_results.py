"""Every kind's result in a real Jupyter kernel (nbclient): the same HTML fields for each.

Issue 42's acceptance: "an executed notebook shows every kind's result with the same HTML
fields". A tiny notebook, built here, fits a FractionalTF, a FractionalHW, an EquivalentCircuit,
a HammersteinWiener and a CircuitTables (``fohw.fit``, a :class:`fohw.FitResult` each) and the
lagged kind's identification form (``fohw.identify``, a ThetaHW) on Records
whose names and units are set in the cell, and shows each result as a cell's last value. Each
result cell must display one ``text/html`` output with the status, the data line with the
record's units, the 95 % interval columns and no NaN. Skipped, saying so, when the kernel
packages (the ``test`` extra's nbclient, nbformat and ipykernel) are missing.
"""

import importlib.util
import os
import re
from pathlib import Path

import pytest

MISSING = [p for p in ("nbclient", "nbformat", "ipykernel") if importlib.util.find_spec(p) is None]
if MISSING:
    pytest.skip(f"a Jupyter kernel is needed to execute the notebook: {', '.join(MISSING)} not "
                "installed (pip install -e '.[test]')", allow_module_level=True)

import nbformat  # noqa: E402
from nbclient import NotebookClient  # noqa: E402

SETUP = """\
import numpy as np
import fohw

rng = np.random.default_rng(0)
u = np.repeat(rng.uniform(-1.0, 1.0, 15), 10)
tf = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.0, 0.6], dt=0.1)
start = fohw.FractionalTF([0.5], [0.0], [1.0, 1.0], [0.0, 0.5], dt=0.1)
"""

#: kind -> (cell, the units its data line must show)
CELLS = {
    "FractionalTF": ("""\
y = tf.simulate(u) + 0.01 * rng.standard_normal(u.size)
rec = fohw.Record(u, y, dt=0.1, input_name="pump", output_name="level", input_unit="V",
                  output_unit="m")
fohw.fit(start, rec)""", "input pump [V]; output level [m]"),
    "FractionalHW": ("""\
y = fohw.FractionalHW(tf, p=(1.0, 0.3)).simulate(u) + 0.01 * rng.standard_normal(u.size)
rec = fohw.Record(u, y, dt=0.1, input_name="valve", output_name="flow", input_unit="mA",
                  output_unit="l/s")
fohw.fit(fohw.FractionalHW(start, p=(1.0, 0.0)), rec)""", "input valve [mA]; output flow [l/s]"),
    "EquivalentCircuit": ("""\
ocv = fohw.OCVTable([0.0, 0.5, 1.0], [3.3, 3.7, 4.2])
i = np.repeat(rng.uniform(-1.0, 3.0, 12), 20)
soc = 0.9 - np.cumsum(i) / 18000.0
cell = fohw.EquivalentCircuit([fohw.ZARC(0.012, 40.0, 0.6)], r0=0.015, ocv=ocv,
                              current_sign="discharge_positive")
v = cell.simulate(np.column_stack([i, soc])) + 2e-4 * rng.standard_normal(i.size)
rec = fohw.Record(np.column_stack([i, soc]), v, dt=1.0, input_name=["current", "soc"],
                  output_name="voltage", input_unit=["A", "1"], output_unit="V")
fohw.fit(fohw.EquivalentCircuit(("zarc",), ocv=ocv, tau_bounds=(1.0, 500.0),
                                current_sign="discharge_positive"), rec)""",
                          "input current [A], soc [1]; output voltage [V]"),
    "HammersteinWiener": ("""\
hw = fohw.HammersteinWiener([0.3], [1.0, 0.5], [1.0, 0.3], [1.0], 0.4)
x = rng.uniform(-1.5, 1.5, 300)
rec = fohw.Record(x, hw.simulate(x) + 0.01 * rng.standard_normal(300), dt=1.0,
                  input_name="heater", output_name="temp", input_unit="W", output_unit="K")
fohw.fit(fohw.HammersteinWiener([0.1], [0.5, 0.1], [1.0, 0.0], [1.0], 0.6), rec)""",
                          "input heater [W]; output temp [K]"),
    "CircuitTables": ("""\
i2 = np.repeat(rng.uniform(-3.0, 3.0, 40), 20)
soc2 = np.clip(0.7 - np.cumsum(np.r_[0.0, i2[:-1]]) / (3600 * 1.2), 0.0, 1.0)
temp = np.repeat([10.0, 30.0], 400)
grid = dict(soc_points=[0.3, 0.7], temperature_points=[10.0, 30.0], ocv=ocv)
tables = fohw.CircuitTables(("zarc",), **grid)             # its default values make the data
v2 = tables.simulate(np.column_stack([i2, soc2, temp])) + 2e-4 * rng.standard_normal(i2.size)
rec = fohw.Record(np.column_stack([i2, soc2, temp]), v2, dt=1.0,
                  input_name=["current", "soc", "temperature"], output_name="voltage",
                  input_unit=["A", "1", "degC"], output_unit="V")
fohw.fit(tables, rec, order_grid=2, n_starts=1)""",
                      "input current [A], soc [1], temperature [degC]; output voltage [V]"),
    "lagged (identify)": ("""\
d = fohw.datasets.paper_example(400, random_state=0)
rec = fohw.Record(d.u, d.y, dt=1.0, input_name="torque", output_name="speed", input_unit="N m",
                  output_unit="rad/s")
fohw.identify(rec, na=2, nb=2, f_basis=2, g_basis=3)""", "input torque [N m]; output speed [rad/s]"),
}


def test_every_kinds_result_shows_the_same_html_fields(tmp_path, monkeypatch):
    monkeypatch.setenv("JUPYTER_PLATFORM_DIRS", "1")      # jupyter_core's path migration warning
    src = Path(__file__).resolve().parents[1] / "src"
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(filter(None, [str(src),
                                                                     os.environ.get("PYTHONPATH")])))
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(SETUP)] + [nbformat.v4.new_code_cell(code)
                                                     for code, _ in CELLS.values()]
    NotebookClient(nb, timeout=300, kernel_name="python3",
                   resources={"metadata": {"path": str(tmp_path)}}).execute()
    assert not [o for c in nb.cells for o in c.outputs if o.output_type == "error"]
    for cell, (kind, (_, units)) in zip(nb.cells[1:], CELLS.items()):
        html = [o["data"]["text/html"] for o in cell.outputs if "text/html" in o.get("data", {})]
        assert len(html) == 1, kind
        text = re.sub(r"\s+", " ", re.sub(r"<[^>]+>", " ", html[0]))
        assert "status = CONVERGED" in text, (kind, text[:400])
        assert f"data: 1 record(s); {units}" in text, (kind, text[:400])
        assert "estimate std err 95% CI low 95% CI high" in text, (kind, text[:600])
        assert not re.search(r"\bnan\b", text, re.IGNORECASE), (kind, text)


PROGRESS = """\
import numpy as np
import fohw

rng = np.random.default_rng(1)
tf = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.0, 0.6], dt=0.1)
records = [(x, tf.simulate(x)) for x in rng.standard_normal((3, 100))]
fits = fohw.identify_many(records, model=tf, progress=True, order_grid=1, n_starts=1)
[type(f).__name__ for f in fits]"""


@pytest.mark.skipif(importlib.util.find_spec("ipywidgets") is None,
                    reason="the widget needs ipywidgets (the `progress` and `test` extras)")
def test_progress_is_a_widget_in_a_kernel(tmp_path, monkeypatch):
    # README: with the progress extra, work that reports progress shows a widget in a notebook
    # (tqdm.auto), not a text bar on stderr.
    monkeypatch.setenv("JUPYTER_PLATFORM_DIRS", "1")
    src = Path(__file__).resolve().parents[1] / "src"
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(filter(None, [str(src),
                                                                     os.environ.get("PYTHONPATH")])))
    nb = nbformat.v4.new_notebook()
    nb.cells = [nbformat.v4.new_code_cell(PROGRESS)]
    NotebookClient(nb, timeout=300, kernel_name="python3",
                   resources={"metadata": {"path": str(tmp_path)}}).execute()
    outputs = nb.cells[0].outputs
    assert not [o for o in outputs if o.output_type == "error"]
    widgets = [o for o in outputs if "application/vnd.jupyter.widget-view+json" in o.get("data", {})]
    assert widgets, [o.get("data", o.get("text", "")) for o in outputs]
    assert not [o for o in outputs if o.get("name") == "stderr" and "|" in o.get("text", "")]
    assert "['FitResult', 'FitResult', 'FitResult']" in str(outputs[-1]["data"]["text/plain"])
