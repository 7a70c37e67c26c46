"""The documentation: the tutorial runs as a newcomer would, and the site builds offline with
warnings as errors, with a page per public object, the gallery's figures and math from its own
files."""

import ast
import importlib.util
import inspect
import os
import re
import shutil
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

import fohw

ROOT = Path(__file__).resolve().parents[1]
DOCS_PACKAGES = ("sphinx", "myst_parser", "numpydoc", "pydata_sphinx_theme", "sphinx-mathjax-offline")

# Any name lookup (but localhost's) and any TCP/UDP connection made by the build (Sphinx, an
# extension, an example it runs) raises.
NO_NETWORK = textwrap.dedent('''
    import socket

    def _refuse(self, address, *args):
        if self.family in (socket.AF_INET, socket.AF_INET6):
            raise OSError(f"the docs build tried the network: {address!r}")
        return _connect(self, address, *args)

    def _no_lookup(host, *args, **kwargs):
        if host not in (None, "localhost", b"localhost", "127.0.0.1", "::1"):
            raise OSError(f"the docs build tried the network: lookup of {host!r}")
        return _getaddrinfo(host, *args, **kwargs)

    _connect, _getaddrinfo = socket.socket.connect, socket.getaddrinfo
    socket.socket.connect = _refuse
    socket.socket.connect_ex = _refuse
    socket.getaddrinfo = _no_lookup
''')


def test_tutorial_runs(tmp_path):
    proc = subprocess.run([sys.executable, str(ROOT / "docs" / "tutorial.py")], cwd=tmp_path,
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert "saved and reloaded exactly" in proc.stdout
    assert proc.stderr == ""


@pytest.mark.parametrize("code", ["socket.create_connection(('127.0.0.1', 9), timeout=1)",
                                  "socket.getaddrinfo('example.org', 443)"])
def test_network_guard_refuses(code, tmp_path):
    # The guard is what makes "offline" testable: check that it refuses a connection and a lookup.
    (tmp_path / "sitecustomize.py").write_text(NO_NETWORK)
    proc = subprocess.run([sys.executable, "-c", "import socket; " + code], capture_output=True,
                          text=True, timeout=60, env={"PYTHONPATH": str(tmp_path), "PATH": ""})
    assert proc.returncode != 0
    assert "the docs build tried the network" in proc.stderr


@pytest.fixture(scope="module")
def site(tmp_path_factory):
    """The site built from a copy of docs/ and examples/ (the checkout stays clean), offline."""
    missing = [p for p in DOCS_PACKAGES if importlib.util.find_spec(p) is None]
    if missing:
        pytest.skip(f"the docs extra is not installed (missing {missing})")
    base = tmp_path_factory.mktemp("docs")
    shutil.copytree(ROOT / "docs", base / "docs",
                    ignore=shutil.ignore_patterns("_build", "api", "gallery", "_executed"))
    shutil.copytree(ROOT / "examples", base / "examples")
    guard = base / "guard"
    guard.mkdir()
    (guard / "sitecustomize.py").write_text(NO_NETWORK)
    src = str(Path(fohw.__file__).resolve().parents[1])
    env = {**os.environ, "PYTHONPATH": f"{guard}:{src}"}
    proc = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
                           str(base / "docs"), str(base / "html")],
                          capture_output=True, text=True, timeout=900, env=env)
    assert proc.returncode == 0, proc.stderr[-5000:]
    return base


@pytest.mark.slow
def test_docs_build_without_warnings(site):
    assert (site / "html" / "api.html").is_file()
    assert (site / "html" / "objects.inv").is_file()


@pytest.mark.slow
def test_one_page_per_public_object(site):
    api = site / "html" / "api"
    for name in fohw.__all__:
        page = api / f"fohw.{name}.html"
        assert page.is_file(), name
        html = page.read_text()
        target = f"module-fohw.{name}" if inspect.ismodule(getattr(fohw, name)) else f"fohw.{name}"
        assert f'id="{target}"' in html, name
    index = (site / "html" / "api.html").read_text()
    assert all(f'href="api/fohw.{name}.html' in index for name in fohw.__all__)


@pytest.mark.slow
def test_one_page_per_submodule_name_in_api_md(site):
    """The names docs/api.md lists from submodules (option and estimator classes, output maps, ...,
    which the top level does not re-export) have their pages too."""
    listed = re.findall(r"^   (fohw\.[\w.]+)$", (ROOT / "docs" / "api.md").read_text(), re.MULTILINE)
    assert "fohw.model.output_map.Saturation" in listed and "fohw.analysis.batch.end_with_parent" in listed
    index = (site / "html" / "api.html").read_text()
    for name in listed:
        html = (site / "html" / "api" / f"{name}.html").read_text()
        assert f'id="{name}"' in html, name
        assert f'href="api/{name}.html' in index, name


@pytest.mark.slow
def test_gallery_shows_every_example_with_its_figures(site):
    html_dir = site / "html" / "gallery"
    index = (html_dir / "index.html").read_text()
    for script in sorted((ROOT / "examples").glob("*.py")):
        page = html_dir / f"{script.stem}.html"
        assert page.is_file(), script.name
        assert f'href="{script.stem}.html"' in index, script.name
        html = page.read_text()
        shown = dict(re.findall(r'<img alt="([^"]+)" src="([^"]+)"', html))
        for alt, src in shown.items():
            assert (page.parent / src).resolve().is_file(), (script.name, alt, src)
        written = {p.name for p in (site / "docs" / "gallery" / script.stem).glob("*.png")}
        assert written <= set(shown), (script.name, written - set(shown))
        doc = ast.get_docstring(ast.parse(script.read_text()))
        named = set(re.findall(r"\w+\.png", doc))
        if "Executed while these pages were built" in html:
            assert named <= written, (script.name, named - written)
        else:
            assert "Not executed while these pages were built" in html and shown, script.name


@pytest.mark.slow
def test_tutorial_page_is_executed(site):
    html = (site / "html" / "tutorial.html").read_text()
    assert "saved and reloaded exactly" in html
    assert "max |y - Phi theta - v| =" in html
    images = re.findall(r'<img alt="figure" class="fohw-output-image" src="([^"]+)"', html)
    assert images and all((site / "html" / src).is_file() for src in images)
    assert 'class="fohw-output-html"' in html   # a result's HTML repr


@pytest.mark.slow
def test_math_is_rendered_offline(site):
    html_dir = site / "html"
    pages = list(html_dir.rglob("*.html"))
    remote = re.compile(r'<(?:script|link|img)\b[^>]*\b(?:src|href)="(?:https?:)?//', re.IGNORECASE)
    assert not [p.name for p in pages if remote.search(p.read_text())]
    mathjax = re.compile(r'<script[^>]*src="([^"]*mathjax[^"]*)"')
    with_math = [p for p in pages if 'class="math' in p.read_text()]
    assert len(with_math) >= 3
    for page in with_math:
        sources = mathjax.findall(page.read_text())
        assert sources, page.name
        assert all((page.parent / s).resolve().is_file() for s in sources), (page.name, sources)


def test_every_docs_page_is_in_the_toctree():
    index = (ROOT / "docs" / "index.md").read_text()
    pages = {p.stem for p in (ROOT / "docs").glob("*.md")} - {"index"}
    assert all(f"\n{page}\n" in index for page in pages), pages


def test_front_page_quick_start_prints_what_the_page_shows(tmp_path):
    """The quick start of docs/index.md, run as a newcomer would, prints the output block below it
    (the page's numbers are this run's, not typed by hand)."""
    text = (ROOT / "docs" / "index.md").read_text()
    section = text.split("## Quick start", 1)[1].split("\n## ", 1)[0]
    code, shown = re.search(r"```python\n(.*?)```\s*prints\s*```\n(.*?)```", section, re.DOTALL).groups()
    assert len([line for line in code.splitlines() if line.strip()]) <= 12   # a quick start, not a page
    script = tmp_path / "quick_start.py"
    script.write_text(code)
    proc = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True,
                          timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == shown
    assert proc.stderr == ""


def test_front_page_shows_a_figure_and_a_kind_table_not_the_build():
    """The front page is for users: a figure that ships with the docs, the table of which kind serves
    which problem, and no build command (that is in CONTRIBUTING.md)."""
    text = (ROOT / "docs" / "index.md").read_text()
    before_toc = text.split("```{toctree}", 1)[0]
    assert "sphinx-build" not in before_toc
    assert "sphinx-build -W -b html docs docs/_build/html" in (ROOT / "CONTRIBUTING.md").read_text()
    figures = re.findall(r"!\[[^\]]*\]\(([^)]+\.png)\)", before_toc)
    assert figures and all((ROOT / "docs" / f).is_file() for f in figures)
    table = before_toc.split("## Which kind for which problem", 1)[1]
    for kind in ("HammersteinWiener", "FractionalHW", "FractionalTF", "EquivalentCircuit", "CircuitTables"):
        assert f"fohw.{kind}" in table or f"`{kind}`" in table, kind
        assert kind in fohw.__all__, kind


@pytest.mark.parametrize("page", ["battery.md", "irregular_time.md"])
def test_a_pages_try_it_block_prints_what_the_page_shows(page, tmp_path):
    """The battery and irregular-time pages carry runnable code: their "Try it" block, run as a
    user would (warnings as errors), prints the output block below it."""
    text = (ROOT / "docs" / page).read_text()
    section = text.split("## Try it", 1)[1].split("\n## ", 1)[0]
    code, shown = re.search(r"```python\n(.*?)```\s*prints\s*```\n(.*?)```", section, re.DOTALL).groups()
    script = tmp_path / "try_it.py"
    script.write_text(code)
    proc = subprocess.run([sys.executable, "-W", "error", str(script)], cwd=tmp_path,
                          capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    assert proc.stdout == shown
