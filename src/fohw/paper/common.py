"""What the paper's studies share: its printed numbers, its example's structure, the CSV format.

The paper's printed numbers come from the package data file ``fohw/data/paper_table2.json``
(with its source and the paper's misprints kept).
"""

from __future__ import annotations

import json
from importlib import resources

__all__ = ["paper_table2", "STRUCTURE", "csv_text"]

#: The structure of the academic example (Section 6.1): na = nb = 2, f of degree 2, g of degree 3.
STRUCTURE = dict(na=2, nb=2, f_basis=2, g_basis=3)


def paper_table2() -> dict:
    """The paper's Table 2 as printed (and Table 3's error ranges), with its source.

    Examples
    --------
    >>> from fohw.paper.common import paper_table2
    >>> t = paper_table2()
    >>> t["true"]["alpha"], len(t["rows"])
    (0.6, 9)
    """
    text = resources.files("fohw").joinpath("data/paper_table2.json").read_text()
    return json.loads(text)


def csv_text(rows, columns):
    """``columns`` of each row as CSV text: floats by ``repr`` (every digit), the rest by ``str``."""
    lines = [",".join(columns)]
    for r in rows:
        lines.append(",".join(repr(r[c]) if isinstance(r[c], float) else str(r[c]) for c in columns))
    return "\n".join(lines) + "\n"
