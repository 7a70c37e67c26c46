"""Figures: one kind of Figure everywhere, ``ax=``, layouts that do not clip, and image comparisons.

The image comparisons draw three key figures from deterministic inputs (an analytic transfer
function, the true paper model on a seeded record, the seeded Fig. 3 run) under matplotlib's
default style with hinting off (as matplotlib's own image tests), and compare them with the PNGs in
``tests/baseline/`` by :func:`matplotlib.testing.compare.compare_images`. The baselines were made by
``python tests/test_figures.py`` and looked at before they were committed; after a deliberate change
of a figure, run it again, look at the new PNGs, and commit them with the change.
"""

import io
import sys
from pathlib import Path

import matplotlib
import numpy as np
import pytest

matplotlib.use("Agg")

import matplotlib.pyplot as plt  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.testing.compare import compare_images  # noqa: E402

import fohw  # noqa: E402
from fohw.paper.table2 import plot_figure_3, plot_figure_4, run_paper_example  # noqa: E402

BASELINE = Path(__file__).parent / "baseline"
STYLE = {"text.hinting": "none", "font.family": "DejaVu Sans", "figure.dpi": 100,
         "savefig.dpi": 60}
# RMS difference (0-255 grey levels) allowed between a drawing and its baseline. Measured when the
# baselines were made: the same figure drawn again gives 0; dropping one curve gives 6.2 (Bode),
# 8.0 (validation), 7.6 (Fig. 3); moving a legend 8.4 to 14.4. A third of the smallest of these
# lets anti-aliasing and FreeType versions differ and still catches a lost curve or a moved legend.
TOL = 2.0


@pytest.fixture(scope="module")
def runs():
    return run_paper_example(2000, baselines=False)


def make_bode():
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
    return G.bode(np.logspace(-2, 3, 200),
                  others={"1/(s+1)": fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [1.0, 0.0])})


def make_validation():
    data = fohw.datasets.paper_example(200, random_state=0)
    return fohw.compare(fohw.datasets.paper_model(), data.u, data.y).plot()


def make_figure_3(runs):
    return plot_figure_3(runs)


def _draw(name, runs):
    with matplotlib.style.context("default"), matplotlib.rc_context(STYLE):
        fig = {"bode": make_bode, "validation": make_validation,
               "figure_3": lambda: make_figure_3(runs)}[name]()
        buf = io.BytesIO()
        fig.savefig(buf, format="png")
    return buf.getvalue()


@pytest.mark.parametrize("name", ["bode", "validation", "figure_3"])
def test_figure_matches_its_baseline(name, runs, tmp_path):
    expected = BASELINE / f"{name}.png"
    actual = tmp_path / f"{name}.png"
    actual.write_bytes(_draw(name, runs))
    err = compare_images(str(expected), str(actual), tol=TOL, in_decorator=True)
    assert err is None, f"{name}: RMS {err['rms']:.2f} > {TOL} (diff image: {err['diff']})"


# ---------------------------------------------------------------- one kind of Figure
def test_every_plot_returns_a_figure_a_notebook_displays(runs):
    before = plt.get_fignums()
    data = fohw.datasets.paper_example(200, random_state=0)
    res = fohw.identify(data.u, data.y, na=2, nb=2, f_basis=2, g_basis=3)
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
    figs = [res.plot(), res.bode(), fohw.compare(res, data.u, data.y).plot(), G.bode(), G.nyquist(),
            plot_figure_3(runs), plot_figure_4(runs)]
    for fig in figs:
        assert isinstance(fig, matplotlib.figure.Figure)
        png = fig._repr_png_()                      # what Jupyter calls, with or without pyplot
        assert png[:8] == b"\x89PNG\r\n\x1a\n"
        assert isinstance(fig.get_layout_engine(), matplotlib.layout_engine.ConstrainedLayoutEngine)
    assert plt.get_fignums() == before              # none registered with pyplot: no window


def _outside(fig):
    """How far (inches) the drawn texts, legends and axes reach beyond the figure's edges; 0 if not."""
    renderer = FigureCanvasAgg(fig).get_renderer()
    fig.draw(renderer)
    bb = fig.get_tightbbox(renderer)            # inches; only what is drawn
    w, h = fig.get_size_inches()
    return round(max(0.0, -bb.x0, -bb.y0, bb.x1 - w, bb.y1 - h), 3)


def test_selection_title_is_never_clipped():
    rows = [{"candidate": f"na={i} nb={i}", "status": "ok", "fit": 70.0 + i} for i in range(1, 4)]
    long = ("the last 25 % of 4096 samples held back, the free run continuing from the estimation "
            "record's last state, scored by the fit on the output in volts")
    sel = fohw.Selection(rows=rows, best=None, best_index=2, results=[None] * 3, validation=long)
    fig = sel.plot()
    assert _outside(fig) == 0
    assert long.split()[-1] in fig.axes[0].get_title()


def test_figure_4_legend_covers_no_data(runs):
    fig = plot_figure_4(runs)
    ax = fig.axes[0]
    renderer = FigureCanvasAgg(fig).get_renderer()
    fig.draw(renderer)
    box = ax.get_legend().get_window_extent(renderer)
    for line in ax.get_lines():
        xy = ax.transData.transform(np.column_stack(line.get_data()).astype(float))
        inside = ((xy[:, 0] > box.x0) & (xy[:, 0] < box.x1) & (xy[:, 1] > box.y0)
                  & (xy[:, 1] < box.y1))
        assert not inside.any(), line.get_label()
    assert _outside(fig) == 0


def test_figure_3_draws_each_innovation_length_apart(runs):
    """The three fohw curves are within a few per cent: each must still be seen (zoom panel)."""
    fig = plot_figure_3(runs)
    zoom = fig.axes[1]
    lines = [ln for ln in zoom.get_lines() if ln.get_label().startswith("fohw")]
    assert len(lines) == 3
    assert len({(ln.get_linestyle(), ln.get_marker()) for ln in lines}) == 3
    # the zoom panel spends its height on the curves (after the first 5 %), not on empty space
    n = runs.data.n_samples
    tails = np.concatenate([ln.get_ydata()[n // 20:] for ln in lines])
    lo, hi = zoom.get_ylim()
    assert np.ptp(tails) / (hi - lo) > 0.8


def test_validation_time_axis_in_the_models_units():
    data = fohw.datasets.paper_example(200, random_state=0)
    res = fohw.identify(data.u, data.y, na=2, nb=2, f_basis=2, g_basis=3, dt=0.5)
    v = fohw.compare(res, data.u, data.y)
    assert v.dt == 0.5
    ax = v.plot().axes[-1]
    assert ax.get_xlabel() == "time" and ax.get_lines()[0].get_xdata()[-1] == 199 * 0.5
    plain = fohw.compare(fohw.datasets.paper_model(), data.u, data.y)      # dt = 1: sample index
    assert plain.dt is None and plain.plot().axes[-1].get_xlabel() == "sample k"


# ---------------------------------------------------------------- ax=
def test_ax_takes_one_axes_or_all_panels():
    data = fohw.datasets.paper_example(200, random_state=0)
    v = fohw.compare(fohw.datasets.paper_model(), data.u, data.y)
    fig = matplotlib.figure.Figure()
    ax = fig.subplots()
    assert v.plot(ax=ax) is fig and len(ax.get_lines()) == 3    # outputs only, no error panel
    fig2 = matplotlib.figure.Figure()
    axes = fig2.subplots(2, 1)
    assert v.plot(ax=axes) is fig2 and len(axes[1].get_lines()) == 2
    with pytest.raises(ValueError, match=r"`ax` must be one Axes .* sequence of 2 Axes .*got 3 Axes"):
        v.plot(ax=list(fig2.subplots(3, 1)))
    with pytest.raises(TypeError, match="`ax` must be None, one matplotlib Axes.*got str"):
        v.plot(ax="top")
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
    fig3 = matplotlib.figure.Figure()
    one = fig3.subplots()
    assert G.bode(ax=one) is fig3 and one.get_ylabel() == "magnitude [dB]"


if __name__ == "__main__":          # write the baselines (look at them before committing)
    BASELINE.mkdir(exist_ok=True)
    r = run_paper_example(2000, baselines=False)
    for n in ("bode", "validation", "figure_3"):
        (BASELINE / f"{n}.png").write_bytes(_draw(n, r))
        print("wrote", BASELINE / f"{n}.png")
    sys.exit(0)
