import subprocess
import sys

import fohw
from fohw.cli import main


def test_reproduce_table2_fast(tmp_path, capsys):
    assert main(["reproduce", "table2", "--outdir", str(tmp_path), "--fast"]) == 0
    out = capsys.readouterr().out
    assert "| alpha | 0.6 |" in out
    for name in ("table_2.md", "table_2.csv", "figure_3.png", "figure_6.png"):
        assert (tmp_path / name).stat().st_size > 0


def test_usage_error_is_one_line_exit_2():
    proc = subprocess.run([sys.executable, "-m", "fohw", "reproduce", "table3"],
                          capture_output=True, text=True)
    assert proc.returncode == 2
    assert proc.stderr.count("\n") == 1 and "invalid choice" in proc.stderr


def test_version():
    proc = subprocess.run([sys.executable, "-m", "fohw", "--version"], capture_output=True, text=True)
    assert proc.returncode == 0 and fohw.__version__ in proc.stdout
