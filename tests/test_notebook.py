"""The getting-started steps as a notebook, executed by a real Jupyter kernel (nbclient).

A notebook user must see every figure and every result without a ``%matplotlib`` line: each cell
tagged ``figure`` must produce exactly one ``image/png`` output (a figure shown twice, or shown as
``<Figure size ...>`` text, fails), each cell tagged ``result`` a ``text/html`` table, and no cell
an error. The notebook is ``tests/data/getting_started.ipynb`` (outputs not stored).
"""

import os
from pathlib import Path

import nbformat
from nbclient import NotebookClient

NOTEBOOK = Path(__file__).parent / "data" / "getting_started.ipynb"


def _tags(cell):
    return set(cell.get("metadata", {}).get("tags", []))


def test_getting_started_notebook_shows_figures_and_tables(tmp_path, monkeypatch):
    monkeypatch.setenv("JUPYTER_PLATFORM_DIRS", "1")      # jupyter_core's path migration warning
    monkeypatch.delenv("MPLBACKEND", raising=False)       # the kernel's own default, as a user has
    src = Path(__file__).resolve().parents[1] / "src"
    monkeypatch.setenv("PYTHONPATH", os.pathsep.join(filter(None, [str(src),
                                                                     os.environ.get("PYTHONPATH")])))
    nb = nbformat.read(NOTEBOOK, as_version=4)
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert not any("%matplotlib" in c.source for c in code)
    assert all(not c.get("outputs") for c in code)                 # stored without outputs
    figures = [c for c in code if "figure" in _tags(c)]
    results = [c for c in code if "result" in _tags(c)]
    assert len(figures) >= 3 and len(results) >= 3
    NotebookClient(nb, timeout=120, kernel_name="python3",
                   resources={"metadata": {"path": str(tmp_path)}}).execute()
    for cell in code:
        assert not [o for o in cell.outputs if o.output_type == "error"], cell.source
        stderr = "".join(o.get("text", "") for o in cell.outputs if o.get("name") == "stderr")
        assert "Warning" not in stderr, (cell.source, stderr)   # progress lines only
    for cell in figures:
        pngs = [o for o in cell.outputs if "image/png" in o.get("data", {})]
        assert len(pngs) == 1, (cell.source, [o.get("data", {}).keys() for o in cell.outputs])
        assert pngs[0]["data"]["image/png"]                          # base64 PNG, not empty
    for cell in results:
        html = [o for o in cell.outputs if "text/html" in o.get("data", {})]
        assert len(html) == 1 and "<table>" in html[0]["data"]["text/html"], cell.source
