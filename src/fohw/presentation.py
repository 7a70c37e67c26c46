"""How an identification result reads: its text summary, repr, HTML table and plot.

:class:`ResultPresentation` is the presentation half of :class:`fohw.IdentificationResult`
(which inherits it); it only reads the result's public attributes, so the data half
(:mod:`fohw.results`) stays free of formatting and plotting.
"""

from __future__ import annotations

import numpy as np

from .record import describe_data

__all__ = ["ResultPresentation"]


class ResultPresentation:
    """``summary()``, ``repr``, the notebook table and ``plot()`` of an identification result."""

    __slots__ = ()

    def _display_names(self):
        """The free orders and past levels first (alpha, as the paper lists it), then theta."""
        return list(self.structure.nonlinear_names) + list(self.structure.linear_names)

    def _repr_html_(self):
        """The notebook view: what :meth:`summary` shows, its estimates as a table."""
        import html

        from ._repr import estimates_html

        paragraphs = self.summary().split("\n\n")       # head, estimates, then the rest
        names = self._display_names()
        est = (self._estimates() if self.shared_model is not None
               else dict(zip(self.estimate_names, np.r_[self.linear, self.nonlinear])))
        if self.covariance is not None:
            se, ci = self.standard_errors(), self.confidence_intervals()
            rows = [(n, est[n], se[n], ci[n][0], ci[n][1], "") for n in names]
        else:
            rows = [(n, est[n], None, None, None, "") for n in names]
        head = [line.strip() for line in paragraphs[0].splitlines()]
        table = estimates_html(head[0], rows, lines=head[1:])     # as summary() writes them
        return table + "".join(f"<pre>{html.escape(p)}</pre>" for p in paragraphs[2:])

    def summary(self, linear_block=True) -> str:
        """A text table of the estimates and the run's diagnostics.

        Parameters
        ----------
        linear_block : bool, optional
            End with the linear block's static gain and stability verdict (default True;
            :meth:`fohw.IdentificationResult.linear_block`).
        """
        lines = [f"fohw identification: method={self.method!r}"
                 + (f", schedule={self.schedule!r}" if self.schedule else ""),
                 f"  samples N = {self.n_samples}, na = {self.structure.na}, "
                 f"nb = {self.structure.nb}, "
                 + (f"nk = {self.structure.nk}, " if self.structure.nk != 1 else "")
                 + f"f_basis = {self.f_basis!r}, "
                 f"g_basis = {self.g_basis!r}"]
        if not self.structure.is_paper_model:
            lines.append(f"  model: {self.structure.describe()}")
        if self.data:
            lines.append(f"  {describe_data(self.data)}")
        u0, y0 = self.operating_point
        if isinstance(u0, tuple):                    # several inputs
            if any(u0) or y0:
                lines.append("  operating point (u0, y0) = ((" + ", ".join(f"{x:.6g}" for x in u0)
                             + f"), {y0:.6g}), removed before fitting")
        elif self.operating_point != (0.0, 0.0):
            lines.append(f"  operating point (u0, y0) = ({self.operating_point[0]:.6g}, "
                         f"{self.operating_point[1]:.6g}), removed before fitting")
        lines += [f"  status = {self.status.name} ({int(self.status)}), iterations = {self.nit}, "
                  f"evaluations = {self.nfev}, J (Eq. 41) = {self.J:.6g}",
                  f"  {self.message}",
                  ""]
        names = self._display_names()
        est = dict(zip(self.estimate_names, np.r_[self.linear, self.nonlinear]))
        if self.shared_model is not None:
            est = self._estimates()
        if self.covariance is not None:
            lines += self._estimate_table(names, est)
        else:
            width = max(12, max(len(n) for n in names) + 2)
            lines.append(f"  {'parameter':<{width}}{'estimate':>14}")
            lines += [f"  {n:<{width}}{est[n]:>14.6g}" for n in names]
            if self.shared_model is not None:
                lines += ["", "  recovered by Eqs. (39)-(40):"]
                for name in "abpq":
                    vals = ", ".join(f"{v:.6g}" for v in getattr(self.shared_model, name))
                    lines.append(f"  {name} = [{vals}]")
        if self.alpha_at_bound:
            lines.append("  alpha was held at (or ended at) a bound of alpha_bounds.")
        test = self.order_test() if "integer_sse" in self.details else None
        if test is not None:
            lines += ["", f"  {test}"]
        if linear_block:
            lines += ["", *self._linear_block_lines()]
        return "\n".join(lines)

    def _linear_block_lines(self):
        """Static gain and stability of the linear block (linearised at the operating point)."""
        from .exceptions import ParameterError

        try:
            block = self.linear_block()
        except ParameterError as err:
            return [f"  linear block: undefined ({err})"]
        gain = block.static_gain
        why = "" if gain != 0.0 else " (no order-0 term: every fractional term vanishes at z = 1)"
        return ["  linear block H(z) = f' B(z) / (1 - g' A(z)), linearised at the operating point "
                f"(f' = {block.f_slope:.6g}, g' = {block.g_slope:.6g}):",
                f"  static gain H(1) = {gain:.6g}{why}",
                f"  stability: {block.stability()}"]

    def bode(self, omega=None, *, others=None, title=None, ax=None, hz=False):
        """Bode diagram of the linear block (:meth:`fohw.IdentificationResult.linear_block`).

        Parameters
        ----------
        omega : array_like, optional
            Angular frequencies, ``0 < omega dt <= pi`` (default: three decades up to the
            Nyquist frequency ``pi / dt``).
        others : dict of str to model, optional
            Further models of any kind with a frequency response (a ``HammersteinWiener``, a
            result or a ``LinearBlock``, ...) drawn on the same axes, e.g. the true model beside
            the estimate (:func:`fohw.frequency_plots.bode`, which draws this figure).
        title : str, optional
            Figure title.
        ax : matplotlib Axes or sequence of two Axes, optional
            One Axes: the magnitude only; two: magnitude and phase (default: a new figure).
        hz : bool, optional
            Against ``f = omega / (2 pi)`` (Hz for a record in seconds).

        Returns
        -------
        matplotlib.figure.Figure
            Magnitude and phase axes (:func:`fohw.frequency_plots.bode_plot`), the frequency
            in the record's time unit (rad/s for a :class:`fohw.Record` in seconds;
            ``rad / sample`` at ``dt = 1`` without a record; ``rad / time unit`` for another
            ``dt`` whose unit is unknown); a new figure
            is not registered with pyplot (no window; ``fig.savefig`` writes it) and shows as
            the last expression of a notebook cell.
        """
        from .frequency_plots import bode

        self.linear_block()                 # raises, saying why, when the model is undefined
        return bode(self, omega, others=others, title=title, ax=ax, hz=hz,
                    time_unit=self._time_unit())

    def nyquist(self, omega=None, *, others=None, title=None, ax=None):
        """Nyquist diagram of the linear block (:func:`fohw.frequency_plots.nyquist`).

        The parameters are those of :meth:`bode` (without ``hz``).

        Returns
        -------
        matplotlib.figure.Figure
        """
        from .frequency_plots import nyquist

        self.linear_block()
        return nyquist(self, omega, others=others, title=title, ax=ax)

    def _time_unit(self):
        """The record's time unit; ``"sample"`` at ``dt = 1`` without a record; else unknown."""
        return (self.data or {}).get("time_unit") or (
            "sample" if self.structure.dt == 1.0 and not (self.data or {}).get("dt") else None)

    def _estimate_table(self, names, est):
        """Rows of estimates with standard errors and 95 % intervals (a fit with a covariance)."""
        se = self.standard_errors()
        ci = self.confidence_intervals()
        width = max(12, max(len(n) for n in names) + 2)
        lines = [f"  {'parameter':<{width}}{'estimate':>14}{'std err':>12}"
                 f"{'95% CI low':>14}{'95% CI high':>14}"]

        def row(n):
            return (f"  {n:<{width}}{est[n]:>14.6g}{se[n]:>12.3g}{ci[n][0]:>14.6g}"
                    f"{ci[n][1]:>14.6g}")
        lines += [row(n) for n in names]
        if self.shared_model is not None and (self.layout.n_f > 1 or self.layout.n_g > 1):
            lines += ["", "  p and q estimated directly (structured least squares):"
                      if self.method == "structured" else
                      "  p and q recovered by Eqs. (39)-(40), delta-method errors:"]
            lines += [row(n) for n in self.layout.model_parameter_names if n[0] in "pq"]
        lines += ["", f"  noise variance estimate s^2 = {self.noise_variance:.6g}"]
        return lines

    def __repr__(self):
        orders = ", ".join(f"{k}={v:.6g}" for k, v in self.orders.items())
        return (f"IdentificationResult(method={self.method!r}, schedule={self.schedule!r}, "
                f"{orders + ', ' if orders else ''}J={self.J:.6g}, status={self.status.name}, "
                f"nit={self.nit}, n_params={self.theta.shape[0]})")

    def plot(self, theta_true=None, *, ax=None):
        """Histories of theta (or delta, given ``theta_true``), alpha and J.

        A batch method (no per-sample history) shows its estimates, the profile of J over
        alpha where it has one, and J over the evaluations.

        Parameters
        ----------
        theta_true : array_like, optional
            The true theta: the first panel then shows the relative error delta(k).
        ax : matplotlib Axes or sequence of three Axes, optional
            One Axes receives the first panel only; three receive all (default: a new figure).

        Returns
        -------
        matplotlib.figure.Figure
            A new figure is not registered with pyplot (no window; ``fig.savefig`` writes it)
            and shows as the last expression of a notebook cell.
        """
        from ._plotting import axes_for

        fig, axes = axes_for(ax, 3, figsize=(8, 7))
        axes = axes + [None] * (3 - len(axes))
        if self.theta_history is None:       # batch methods: no per-sample history
            self._plot_batch(axes)
        else:
            self._plot_recursive(axes, theta_true)
        return fig

    def _plot_batch(self, axes):
        names = self._display_names()             # the free orders first, then theta
        est = dict(zip(self.estimate_names, np.r_[self.linear, self.nonlinear]))
        yerr = None
        if self.covariance is not None:           # 95 % intervals, as summary() gives them
            ci = self.confidence_intervals()
            yerr = np.array([[est[n] - ci[n][0] for n in names], [ci[n][1] - est[n] for n in names]])
        axes[0].bar(range(len(names)), [est[n] for n in names], yerr=yerr, capsize=2)
        axes[0].set_xticks(range(len(names)), names, rotation=60, fontsize=7)
        axes[0].set_ylabel("estimate" if yerr is None else "estimate, 95 % interval")
        if axes[1] is None:
            return
        if self.alpha_profile is not None:
            axes[1].plot(*self.alpha_profile, marker=".")
            axes[1].set_xlabel("alpha")
            axes[1].set_ylabel("J(alpha), profile")
        axes[2].plot(np.arange(1, len(self.J_history) + 1), self.J_history, marker="o")
        axes[2].set_xlabel("evaluation")
        axes[2].set_ylabel("J")

    def _plot_recursive(self, axes, theta_true):
        k = np.arange(1, self.n_samples + 1)
        if theta_true is None:
            axes[0].plot(k, self.theta_history, lw=0.8)
            axes[0].set_ylabel("theta(k)")
        else:
            axes[0].semilogy(k, self.relative_error(theta_true, history=True))
            axes[0].set_ylabel("delta(k)")
        axes[0].set_xlabel("sample k (last pass)")
        if axes[1] is None:
            return
        axes[1].plot(k, self.alpha_sample_history)
        axes[1].set_ylabel("alpha(k)")
        axes[1].set_xlabel("sample k (last pass)")
        axes[2].plot(np.arange(1, len(self.J_history) + 1), self.J_history, marker="o")
        axes[2].set_ylabel("J (Eq. 41)")
        axes[2].set_xlabel("iteration m")
