"""Private: the short text repr and the notebook HTML table every fohw object shares.

Results, validations, selections, tests and models each show a few lines in a terminal and a small
table in a notebook (``_repr_html_``); this module builds both from plain rows, so every object
looks the same and no object formats HTML by hand.
"""

from __future__ import annotations

import html
import math
import numbers

__all__ = ["cell", "html_table", "estimates_html"]


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


def estimates_html(title, rows, *, lines=(), notes=(), se_digits=3, level=0.95):
    """The notebook view of every fit result: a head, the estimates with intervals, notes.

    One style for the results of every kind (:class:`fohw.FitResult`,
    :class:`fohw.IdentificationResult`): ``title`` and ``lines`` (the run, the data: names,
    units, records) above a table ``parameter | estimate | std err | CI low | CI high`` (the
    ``level`` Wald interval; the columns of the standard error and the interval only when some
    row has one), then ``notes``. Each row is ``(name, estimate, std err or None, low or None,
    high or None, remark)``; estimates and bounds are written to 6 significant figures,
    standard errors to ``se_digits``, as the text summaries write them.

    Examples
    --------
    >>> from fohw._repr import estimates_html
    >>> page = estimates_html("fit", [("k", 2.0, 0.1, 1.804, 2.196, "")], lines=["N = 10"])
    >>> "<th>95% CI low</th>" in page and "<td style='text-align:right'>1.804</td>" in page
    True
    """
    def text(v, digits):
        return "" if v is None else f"{float(v):.{digits}g}"

    pct = f"{100 * level:g}%"
    with_se = any(r[2] is not None for r in rows)
    remarks = any(r[5] for r in rows)
    header = ["parameter", "estimate"] + (["std err", f"{pct} CI low", f"{pct} CI high"]
                                          if with_se else []) + ([""] if remarks else [])
    table = []
    for name, value, se, low, high, remark in rows:
        row = [name, text(value, 6)]
        if with_se:
            row += [text(se, se_digits), text(low, 6), text(high, 6)]
        table.append(row + ([remark] if remarks else []))
    return html_table(title, header, table, lines=lines, notes=notes)


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
