"""The documentation: the tutorial runs as a newcomer would, and the site builds with warnings
as errors."""

import importlib.util
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_tutorial_runs(tmp_path):
    proc = subprocess.run([sys.executable, str(ROOT / "docs" / "tutorial.py")], cwd=tmp_path,
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    assert "saved and reloaded exactly" in proc.stdout
    assert proc.stderr == ""


@pytest.mark.skipif(importlib.util.find_spec("sphinx") is None
                    or importlib.util.find_spec("myst_parser") is None,
                    reason="the docs extra is not installed")
def test_docs_build_without_warnings(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "sphinx", "-W", "-q", "-b", "html",
                           str(ROOT / "docs"), str(tmp_path / "html")],
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr[-3000:]
    assert (tmp_path / "html" / "api.html").is_file()


def test_every_docs_page_is_in_the_toctree():
    index = (ROOT / "docs" / "index.md").read_text()
    pages = {p.stem for p in (ROOT / "docs").glob("*.md")} - {"index"}
    assert all(f"\n{page}\n" in index for page in pages), pages
