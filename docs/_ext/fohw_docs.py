"""Sphinx extension of the fohw docs: the API pages from ``fohw.__all__``, the examples gallery and
the executed tutorial, all made at build time.

* ``{fohw-api-all}`` in a page is replaced by one autosummary table per part of the package
  (grouped by the module that defines each name), and every name of ``fohw.__all__`` gets its own
  page under ``api/`` (autosummary's stub generation with the templates in ``_templates``). Adding
  or removing a name from ``fohw.__all__`` needs no edit of the docs.
* The gallery: every ``examples/*.py`` runs as ``python examples/NAME.py --outdir DIR --fast``
  (``fohw_gallery_jobs`` at a time), and ``gallery/NAME.rst`` shows its description, the figures
  and Markdown tables it wrote, what it printed and its source. The examples named in
  ``fohw_gallery_not_executed`` are not run; their pages show the committed figures named there,
  and say so.
* ``{fohw-executed} SCRIPT`` in a Markdown page is replaced by the cells of the percent-format
  script run by ``fohw_cells.py``: prose, code, printed output, figures and HTML reprs.

An example or a cell that fails is a build warning (an error under ``-W``) with its stderr.
"""

import concurrent.futures
import json
import os
import re
import shutil
import subprocess
import sys
import time
from pathlib import Path

from markdown_it import MarkdownIt
from sphinx.ext import autosummary
from sphinx.util import logging
from sphinx.util.docutils import SphinxDirective

logger = logging.getLogger(__name__)

HERE = Path(__file__).resolve().parent
API_MARKER = "```{fohw-api-all}\n```"
EXECUTED = re.compile(r"^```\{fohw-executed\} (\S+)\n```$", re.MULTILINE)
GROUPS = [("fohw.model", "Models and simulation"),
          ("fohw.estimators", "Estimation"),
          ("fohw.analysis", "Uncertainty, tests, selection and validation"),
          ("fohw.results", "Results and records"), ("fohw.record", "Results and records"),
          ("fohw.presentation", "Results and records"),
          ("fohw.io", "Files"),
          ("fohw.exceptions", "Errors and warnings")]
MODULES_GROUP = "Modules"
OTHER_GROUP = "Other names"
_MD = MarkdownIt("commonmark", {"html": False}).enable("table")


# --- API -----------------------------------------------------------------------------------------

def api_groups():
    """``{title: [fohw.name, ...]}`` of ``fohw.__all__`` in its order, grouped by defining module."""
    import inspect

    import fohw

    groups = {title: [] for _, title in GROUPS}
    groups[MODULES_GROUP], groups[OTHER_GROUP] = [], []
    for name in fohw.__all__:
        obj = getattr(fohw, name)
        if inspect.ismodule(obj):
            groups[MODULES_GROUP].append(f"fohw.{name}")
            continue
        module = getattr(obj, "__module__", "") or ""
        title = next((t for prefix, t in GROUPS if module == prefix or module.startswith(prefix + ".")),
                     OTHER_GROUP)
        groups[title].append(f"fohw.{name}")
    return {title: names for title, names in groups.items() if names}


def api_markdown(toctree=None):
    """The Markdown that replaces the marker: a section and an autosummary table per group."""
    lines = []
    for title, names in api_groups().items():
        lines += [f"## {title}", "", "```{eval-rst}", ".. autosummary::"]
        lines += [f"   :toctree: {toctree}"] if toctree else []
        lines += ["   :nosignatures:", ""] + [f"   {n}" for n in names] + ["```", ""]
    return "\n".join(lines)


def generate_api_stubs(app):
    """One page per name of ``fohw.__all__`` in ``<srcdir>/api`` (before autosummary's own pass)."""
    from sphinx.ext.autosummary.generate import generate_autosummary_docs

    outdir = Path(app.srcdir) / "api"
    scan = Path(app.doctreedir) / "fohw_api_all.rst"
    scan.parent.mkdir(parents=True, exist_ok=True)
    names = [n for group in api_groups().values() for n in group]
    scan.write_text(".. autosummary::\n   :toctree: " + str(outdir) + "\n\n"
                    + "".join(f"   {n}\n" for n in names))
    generate_autosummary_docs([str(scan)], app=app, base_path=app.srcdir, suffix=".rst",
                              imported_members=True, overwrite=True)


class _Unreplaced(SphinxDirective):
    """A marker the ``source-read`` handler did not replace (a typo in the page): an error."""

    has_content = True
    optional_arguments = 1

    def run(self):
        raise self.error(f"{self.name}: the marker must be a fenced block on its own lines")


# --- running scripts -----------------------------------------------------------------------------

def _env():
    env = dict(os.environ, MPLBACKEND="Agg")
    src = str(Path(sys.modules["fohw"].__file__).resolve().parents[1])
    env["PYTHONPATH"] = os.pathsep.join([src] + [p for p in env.get("PYTHONPATH", "").split(os.pathsep)
                                                 if p])
    return env


def _run(command, cwd, timeout):
    start = time.perf_counter()
    proc = subprocess.run(command, cwd=cwd, env=_env(), capture_output=True, text=True,
                          timeout=timeout)
    return proc, time.perf_counter() - start


# --- gallery -------------------------------------------------------------------------------------

def _docstring(path):
    import ast

    return ast.get_docstring(ast.parse(path.read_text())) or path.stem


def _markdown(text):
    """Markdown as HTML with its headings moved down three levels (the page has its own)."""
    html = _MD.render(text)
    for level in (3, 2, 1):
        html = html.replace(f"<h{level}>", f"<h{level + 3}>").replace(f"</h{level}>", f"</h{level + 3}>")
    return html


def _raw_html(html, css_class):
    body = "\n".join("   " + line for line in f'<div class="{css_class}">\n{html}</div>'.splitlines())
    return [".. raw:: html", "", body, ""]


def _literal(text, language="text"):
    return [f".. code-block:: {language}", ""] + ["   " + line for line in text.splitlines()] + [""]


def _title(text):
    text = text.replace("*", r"\*").replace("`", r"\`")
    return [text, "=" * len(text), ""]


def example_page(script, outdir, run, page_dir, docs_dir):
    """The reST of one example's page; ``run`` is ``(proc, seconds)`` or None (not executed)."""
    doc = _docstring(script)
    first, _, rest = doc.partition("\n\n")
    first = " ".join(first.split())
    lines = [f".. _gallery-{script.stem}:", ""] + _title(first.rstrip("."))
    lines += _raw_html(_markdown(rest.strip("\n")), "fohw-docstring") if rest.strip() else []
    figures = sorted(outdir.glob("*.png"))
    if run is not None:
        proc, seconds = run
        lines += [".. admonition:: Executed while these pages were built", "   :class: note", "",
                  f"   ``python examples/{script.name} --outdir OUT --fast`` ran in {seconds:.1f} s. "
                  "``--fast`` makes a smaller run (fewer samples, seeds or candidates), so the numbers "
                  "and figures below are a quick run's, not the full run's that the study pages discuss.", ""]
    else:
        lines += [".. admonition:: Not executed while these pages were built", "   :class: warning", "",
                  "   This example is one of the two slowest even with ``--fast`` "
                  "(``fohw_gallery_not_executed`` in ``docs/conf.py``), so the build does not run it; "
                  "the figures below are the committed ones in ``docs/figures/`` that the study pages "
                  "show (made by the full run). Run it yourself with "
                  f"``python examples/{script.name} --outdir OUT --fast``.", ""]
    for fig in figures:
        rel = os.path.relpath(fig, page_dir).replace(os.sep, "/")
        lines += [f".. figure:: {rel}", f"   :alt: {fig.name}", "", f"   ``{fig.name}``", ""]
    for table in sorted(outdir.glob("*.md")):
        lines += [".. rubric:: " + table.name, ""] + _raw_html(_markdown(table.read_text()), "fohw-table")
    others = sorted(p for p in outdir.iterdir() if p.suffix not in (".png", ".md")) if outdir.is_dir() else []
    if others:
        lines += ["Other files it wrote: " + ", ".join(
            f":download:`{p.name} <{os.path.relpath(p, page_dir).replace(os.sep, '/')}>`" for p in others)
            + ".", ""]
    if run is not None and run[0].stdout.strip():
        lines += [".. rubric:: What it printed", ""] + _literal(run[0].stdout.rstrip())
    source = page_dir / f"{script.stem}.py"
    lines += [".. rubric:: Source", "", f":download:`Download {script.name} <{source.name}>`", "",
              f".. literalinclude:: {source.name}", "   :language: python", ""]
    return "\n".join(lines), (figures[0] if figures else None), first.rstrip(".")


def build_gallery(app):
    """Run the examples and write ``<srcdir>/gallery``: an index and one page per example."""
    cfg = app.config
    docs_dir = Path(app.srcdir)
    examples_dir = (docs_dir / cfg.fohw_gallery_examples).resolve()
    gallery = docs_dir / "gallery"
    shutil.rmtree(gallery, ignore_errors=True)
    gallery.mkdir(parents=True)
    scripts = sorted(examples_dir.glob("*.py"))
    unknown = set(cfg.fohw_gallery_not_executed) - {s.name for s in scripts}
    if unknown:
        logger.warning("fohw_gallery_not_executed names no example: %s", sorted(unknown))
    jobs = {}
    start = time.perf_counter()
    with concurrent.futures.ThreadPoolExecutor(max_workers=cfg.fohw_gallery_jobs) as pool:
        for script in scripts:
            if script.name in cfg.fohw_gallery_not_executed:
                continue
            out = gallery / script.stem
            jobs[script.name] = pool.submit(
                _run, [sys.executable, str(script), "--outdir", str(out), "--fast"], gallery,
                cfg.fohw_gallery_timeout)
        tutorial = None
        if cfg.fohw_executed:
            tutorial = pool.submit(run_cells_all, app)
        results = {name: job.result() for name, job in jobs.items()}
        if tutorial is not None:
            tutorial.result()
    logger.info("fohw gallery: %d examples and %s executed page(s) in %.1f s, %d at a time",
                len(jobs), len(cfg.fohw_executed), time.perf_counter() - start, cfg.fohw_gallery_jobs)
    cards = []
    for script in scripts:
        out = gallery / script.stem
        run = results.get(script.name)
        if run is not None and run[0].returncode != 0:
            logger.warning("example %s failed (exit status %s):\n%s", script.name, run[0].returncode,
                           run[0].stderr[-3000:])
        if run is None:
            out.mkdir(exist_ok=True)
            for rel in cfg.fohw_gallery_not_executed[script.name]:
                shutil.copy(docs_dir / rel, out / Path(rel).name)
        shutil.copy(script, gallery / script.name)
        text, thumb, title = example_page(script, out, run, gallery, docs_dir)
        (gallery / f"{script.stem}.rst").write_text(text)
        cards.append((script.stem, title, thumb))
    index = _title("Gallery of the examples") + [
        cfg.fohw_gallery_intro.strip(), "",
        ".. toctree::", "   :hidden:", ""] + [f"   {stem}" for stem, _, _ in cards] + [
        "", ".. container:: fohw-gallery", ""]
    for stem, _, thumb in cards:
        index += ["   .. container:: fohw-card", ""]
        if thumb is not None:
            rel = os.path.relpath(thumb, gallery).replace(os.sep, "/")
            index += [f"      .. image:: {rel}", f"         :target: {stem}.html",
                      f"         :alt: {stem}", ""]
        else:
            index += ["      .. rst-class:: fohw-no-figure", "", "      (tables only)", ""]
        index += [f"      :doc:`{stem}`", ""]
    (gallery / "index.rst").write_text("\n".join(index) + "\n")


# --- executed pages ------------------------------------------------------------------------------

def run_cells_all(app):
    """Run every script of ``fohw_executed`` with ``fohw_cells.py`` into ``<srcdir>/_executed``."""
    docs_dir = Path(app.srcdir)
    for script in app.config.fohw_executed:
        out = docs_dir / "_executed" / Path(script).stem
        shutil.rmtree(out, ignore_errors=True)
        proc, seconds = _run([sys.executable, str(HERE / "fohw_cells.py"), str(docs_dir / script),
                              str(out)], docs_dir, app.config.fohw_gallery_timeout)
        if proc.returncode != 0:
            logger.warning("%s failed (exit status %s):\n%s", script, proc.returncode, proc.stderr[-3000:])
        else:
            (out / "seconds.txt").write_text(f"{seconds:.1f}")


def executed_markdown(docs_dir, script):
    """The Markdown of a script's executed cells (``fohw_cells.py``'s ``cells.json``)."""
    out = docs_dir / "_executed" / Path(script).stem
    cells = json.loads((out / "cells.json").read_text())
    seconds = (out / "seconds.txt").read_text()
    lines = [f"```{{note}}\nThe cells below ran while these pages were built ({seconds} s for "
             f"the whole script); the output under each cell is what it printed or showed.\n```", ""]
    for cell in cells:
        if cell["kind"] == "markdown":
            lines += [cell["source"], ""]
            continue
        lines += ["````python", cell["source"], "````", ""]
        for output in cell["outputs"]:
            if output["type"] == "image":
                rel = f"_executed/{Path(script).stem}/{output['path']}"
                lines += ["```{image} " + rel, ":alt: figure", ":class: fohw-output-image", "```", ""]
            elif output["type"] == "html":
                lines += ["```{raw} html", f'<div class="fohw-output-html">{output["html"]}</div>',
                          "```", ""]
            else:
                lines += ["````{code-block} text", ":class: fohw-output", output["text"].rstrip("\n"),
                          "````", ""]
    return "\n".join(lines)


# --- hooks ---------------------------------------------------------------------------------------

def on_builder_inited(app):
    generate_api_stubs(app)
    build_gallery(app)


def on_source_read(app, docname, source):
    text = source[0]
    if API_MARKER in text:
        text = text.replace(API_MARKER, api_markdown(toctree="api"))
    text = EXECUTED.sub(lambda m: executed_markdown(Path(app.srcdir), m.group(1)), text)
    source[0] = text


def setup(app):
    # autosummary's one-line summaries end at the first ". ": fohw's docstrings cite "(Eq. 16)"
    # and "(paper Eqs. 7, 14)", which are not sentence ends.
    autosummary.WELL_KNOWN_ABBREVIATIONS = tuple(autosummary.WELL_KNOWN_ABBREVIATIONS) + ("Eq.", "Eqs.")
    app.add_config_value("fohw_gallery_examples", "../examples", "env")
    app.add_config_value("fohw_gallery_not_executed", {}, "env")
    app.add_config_value("fohw_gallery_jobs", 2, "env")
    app.add_config_value("fohw_gallery_timeout", 600, "env")
    app.add_config_value("fohw_gallery_intro", "", "env")
    app.add_config_value("fohw_executed", [], "env")
    app.add_directive("fohw-api-all", _Unreplaced)
    app.add_directive("fohw-executed", _Unreplaced)
    app.connect("builder-inited", on_builder_inited, priority=400)
    app.connect("source-read", on_source_read)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
