"""Run a percent-format script (``# %%`` cells) cell by cell and record what each cell shows.

    python fohw_cells.py SCRIPT OUTDIR

Writes OUTDIR/cells.json and the figures as OUTDIR/cell<i>_<j>.png. A cell shows what a notebook
would: what it prints (stdout, then stderr), every pyplot figure still open at its end, and the
value of its last line if that is an expression (a matplotlib Figure, or a ``(Figure, axes)``
pair as fohw's plotting methods return, as an image; else the object's ``_repr_html_`` when it
has one; else its ``repr``). ``# %% [markdown]`` cells are
comments whose text (``# `` removed) is Markdown. The script runs in one namespace, in its own
process (the docs build starts it), with the Agg backend; an exception stops the run with exit
status 1 and the traceback on stderr.
"""

import ast
import contextlib
import io
import json
import os
import sys
import traceback
from pathlib import Path


def split_cells(text):
    """``[(kind, source), ...]`` of a percent-format script; what precedes the first ``# %%`` is code."""
    cells, kind, lines = [], "code", []
    for line in text.splitlines():
        if line.startswith("# %%"):
            cells.append((kind, lines))
            kind, lines = ("markdown" if "[markdown]" in line else "code"), []
        else:
            lines.append(line)
    cells.append((kind, lines))
    out = []
    for kind, lines in cells:
        if kind == "markdown":
            lines = [line[2:] if line.startswith("# ") else line.lstrip("#") for line in lines]
        source = "\n".join(lines).strip("\n")
        if source.strip():
            out.append((kind, source))
    return out


def _figure_class():
    from matplotlib.figure import Figure

    return Figure


def _save(fig, outdir, name):
    fig.savefig(outdir / name, dpi=100)
    return {"type": "image", "path": name}


def run(script, outdir):
    """Execute ``script`` cell by cell; return the list of cells with their outputs."""
    os.environ.setdefault("MPLBACKEND", "Agg")
    outdir.mkdir(parents=True, exist_ok=True)
    namespace = {"__name__": "__main__", "__file__": str(script)}
    cells = []
    for index, (kind, source) in enumerate(split_cells(script.read_text())):
        cell = {"kind": kind, "source": source, "outputs": []}
        cells.append(cell)
        if kind == "markdown":
            continue
        tree = ast.parse(source, filename=f"{script.name} cell {index}")
        head = tree.body[0] if tree.body else None
        if index == 0 and isinstance(head, ast.Expr) and isinstance(head.value, ast.Constant) \
                and isinstance(head.value.value, str):
            # the module docstring runs but is not shown: the page says what it says
            cell["source"] = "\n".join(source.splitlines()[tree.body[0].end_lineno:]).strip("\n")
        last = tree.body.pop() if tree.body and isinstance(tree.body[-1], ast.Expr) else None
        stdout, stderr = io.StringIO(), io.StringIO()
        try:
            with contextlib.redirect_stdout(stdout), contextlib.redirect_stderr(stderr):
                exec(compile(tree, str(script), "exec"), namespace)
                value = None
                if last is not None:
                    value = eval(compile(ast.Expression(last.value), str(script), "eval"), namespace)
        except BaseException:
            sys.stderr.write(f"cell {index} printed:\n{stdout.getvalue()}{stderr.getvalue()}\n")
            raise
        for text in (stdout.getvalue(), stderr.getvalue()):
            if text:
                cell["outputs"].append({"type": "stream", "text": text})
        shown = set()
        if "matplotlib.pyplot" in sys.modules:
            import matplotlib.pyplot as plt

            for number in plt.get_fignums():
                fig = plt.figure(number)
                shown.add(id(fig))
                cell["outputs"].append(_save(fig, outdir, f"cell{index}_{len(cell['outputs'])}.png"))
                plt.close(fig)
        if value is None:
            continue
        if (isinstance(value, tuple) and len(value) == 2 and "matplotlib" in sys.modules
                and isinstance(value[0], _figure_class())):
            value = value[0]
        if "matplotlib" in sys.modules and isinstance(value, _figure_class()):
            if id(value) not in shown:
                cell["outputs"].append(_save(value, outdir, f"cell{index}_{len(cell['outputs'])}.png"))
        elif getattr(value, "_repr_html_", None) is not None and value._repr_html_() is not None:
            cell["outputs"].append({"type": "html", "html": value._repr_html_(), "text": repr(value)})
        else:
            cell["outputs"].append({"type": "text", "text": repr(value)})
    return cells


def main(argv=None):
    """Run ``SCRIPT`` and write ``OUTDIR/cells.json``; exit status 1 on an exception."""
    script, outdir = (Path(a) for a in (argv or sys.argv[1:]))
    try:
        cells = run(script.resolve(), outdir)
    except Exception:   # the traceback is the build's error message
        traceback.print_exc()
        return 1
    (outdir / "cells.json").write_text(json.dumps(cells, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
