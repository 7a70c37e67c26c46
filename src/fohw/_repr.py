"""Private: the short text repr and the notebook HTML table every fohw object shares.

Results, validations, selections, tests and models each show a few lines in a terminal and a small
table in a notebook (``_repr_html_``); this module builds both from plain rows, so every object
looks the same and no object formats HTML by hand.
"""

from __future__ import annotations

import html
import math
import numbers

__all__ = ["cell", "html_table"]


def cell(value, digits=4):
    """One value as table text: numbers to ``digits`` significant figures, NaN and None blank."""
    if value is None:
        return ""
    if isinstance(value, bool):
        return "yes" if value else "no"
    if isinstance(value, numbers.Integral):
        return str(int(value))
    if isinstance(value, numbers.Real):
        return "" if math.isnan(value) else f"{float(value):.{digits}g}"
    return str(value)


def html_table(title, header, rows, *, lines=(), notes=(), digits=4):
    """An HTML block: a bold ``title``, ``lines`` of text, a table, then ``notes`` (small).

    ``header`` names the columns; each row is a sequence of values (:func:`cell` formats them to
    ``digits`` significant figures); numeric cells are right-aligned.
    """
    esc = html.escape
    out = [f"<div class='fohw-repr'><b>{esc(title)}</b>"]
    out += [f"<br>{esc(line)}" for line in lines if line]
    if rows:
        out.append("<table><thead><tr>" + "".join(f"<th>{esc(h)}</th>" for h in header)
                   + "</tr></thead><tbody>")
        for row in rows:
            tds = "".join(
                f"<td style='text-align:right'>{esc(cell(v, digits))}</td>" if _numeric(v)
                else f"<td style='text-align:left'>{esc(cell(v))}</td>" for v in row)
            out.append(f"<tr>{tds}</tr>")
        out.append("</tbody></table>")
    out += [f"<small>{esc(n)}</small><br>" for n in notes if n]
    out.append("</div>")
    return "".join(out)


def _numeric(value):
    """Right-align numbers, and text that is a formatted number."""
    if isinstance(value, bool):
        return False
    if isinstance(value, numbers.Number):
        return True
    try:
        float(value)
    except (TypeError, ValueError):
        return False
    return True
