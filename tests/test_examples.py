"""Every example runs in fast mode and writes its files."""

import subprocess
import sys

import pytest

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

EXAMPLES = {
    "simulate_paper_example.py": ["simulation.png", "simulation.md"],
}


@pytest.mark.parametrize("script", sorted(EXAMPLES))
def test_example_runs_fast(script, tmp_path):
    proc = subprocess.run([sys.executable, str(ROOT / "examples" / script), "--outdir", str(tmp_path),
                           "--fast"], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    for name in EXAMPLES[script]:
        assert (tmp_path / name).stat().st_size > 0, name
