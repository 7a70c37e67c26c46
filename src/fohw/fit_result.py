"""The result of fitting any model kind (returned by :func:`fohw.fit`): one vocabulary.

:class:`FitResult` holds the fitted :class:`fohw.Model`, its :class:`fohw.Parameters`, the
covariance of the free ones, the status, the simulation error ``sse`` and the noise variance;
it simulates, summarises itself and writes itself to JSON. The lagged kind's
:class:`fohw.IdentificationResult` (:mod:`fohw.results`) is a subclass: it adds what the
paper's methods have (theta, the histories, the iterations) and derives ``model``,
``parameters`` and ``sse`` from them.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from types import MappingProxyType

import numpy as np

from ._status import Status
from .exceptions import ParameterError
from .model.base import Model
from .model.parameters import Parameters
from .model.simulate import record_list, simulate
from .record import describe_data
from .result_checks import check_fit_result_dict

__all__ = ["FitResult"]


def _readonly(a):
    if a is None:
        return None
    a = np.array(a, dtype=np.float64, copy=True)
    a.setflags(write=False)
    return a


@dataclass(frozen=True, repr=False, eq=False, kw_only=True)
class FitResult:
    """A fitted model of any kind with its uncertainty and diagnostics.

    Attributes
    ----------
    model : Model
        The fitted model (its ``parameters`` are :attr:`parameters`).
    parameters : Parameters
        Every parameter at its estimate, with the bounds, fixed flags and ties of the fit.
    covariance : ndarray or None
        Covariance of the free parameters (``free_names`` order), ``s^2 (J^T J)^{-1}`` at the
        estimate; ``None`` when the Jacobian is rank deficient (:attr:`status`
        ``RANK_DEFICIENT``; the message names the parameters).
    status : Status
        ``CONVERGED``, ``MAX_ITER``, ``FAILED`` (stuck at its start), ``IMPLAUSIBLE`` (the
        fitted model's free run on its own input is not finite or leaves the envelope
        :func:`fohw.compare` uses) or ``RANK_DEFICIENT``.
    sse : float
        Sum of squared simulation errors ``sum (y - yhat)^2`` over the record.
    n_samples : int
        Samples in the criterion.
    noise_variance : float
        ``sse / (n_samples - n_free)``.
    message : str
        What happened, in words.
    nfev : int
        Simulations the search used.
    jacobian : str
        ``"exact"`` (the kind's :meth:`~fohw.Model.jacobian`) or ``"finite differences"``.
    starts : tuple of (dict, float)
        The scanned starts (free order values) and their SSE, best first.
    residuals : ndarray
        ``y - yhat`` at the estimate.
    data_digest : str
        A fingerprint of the record ``(u, y)`` the fit used (tests of two fits check it).
    options : dict
        The fit's settings.
    data : dict
        What the data were, when the fit was given :class:`fohw.Record` s: channel names and
        units (``input_names``, ``input_units``, ``output_name``, ``output_unit``,
        ``time_unit``), ``dt``, and one entry per record (``name``, ``n_samples``, ``t0``,
        ``uniform``, ``dt``). Empty for arrays.
    per_record : dict
        ``{name: {"values": [...], "standard_errors": [...] or None}}`` of the parameters
        estimated once per record (``fohw.fit(..., per_record=...)``), in record order.
    n_per_record : int
        Values estimated besides :attr:`free_names` (each per-record parameter's copies for the
        records after the first); counted in :attr:`noise_variance`'s degrees of freedom.
    """

    model: Model
    parameters: Parameters
    covariance: np.ndarray | None
    status: Status
    sse: float
    n_samples: int
    message: str = ""
    nfev: int = 0
    jacobian: str = "exact"
    starts: tuple = ()
    residuals: np.ndarray | None = None
    data_digest: str = ""
    options: dict = field(default_factory=dict)
    data: dict = field(default_factory=dict)
    per_record: dict = field(default_factory=dict)
    n_per_record: int = 0

    def __post_init__(self):
        object.__setattr__(self, "covariance", _readonly(self.covariance))
        object.__setattr__(self, "residuals", _readonly(self.residuals))
        for name in ("options", "data", "per_record"):
            object.__setattr__(self, name, MappingProxyType(dict(getattr(self, name))))

    # --- derived facts --------------------------------------------------------------------
    @property
    def free_names(self) -> tuple[str, ...]:
        """The estimated parameters, in the covariance's order."""
        return self.parameters.free_names

    @property
    def n_free(self) -> int:
        """Number of estimated parameters."""
        return len(self.free_names)

    @property
    def noise_variance(self) -> float:
        """``sse / (n_samples - n_free - n_per_record)``: every estimated value counted."""
        dof = self.n_samples - self.n_free - self.n_per_record
        return self.sse / dof if dof > 0 else math.nan

    @property
    def rmse(self) -> float:
        """Root mean squared simulation error ``sqrt(sse / n_samples)`` (the data's units)."""
        return math.sqrt(self.sse / self.n_samples)

    @property
    def converged(self) -> bool:
        """True when :attr:`status` is ``CONVERGED``."""
        return self.status == Status.CONVERGED

    @property
    def dt(self) -> float:
        """The model's sampling time."""
        return self.model.dt

    def standard_errors(self) -> dict:
        """``{name: standard error}`` of the free parameters and of the tied ones.

        A tied parameter ``factor * source`` has ``|factor|`` times its source's standard error
        (a tie to a fixed parameter, 0). Raises when there is no covariance.
        """
        if self.covariance is None:
            raise ParameterError(f"this fit has no covariance (status {self.status.name}: "
                                 f"{self.message}); no standard errors.")
        se = dict(zip(self.free_names, np.sqrt(np.diag(self.covariance)).tolist()))
        for name, par in self.parameters.items():
            if par.tie is not None:
                se[name] = abs(par.tie[1]) * se.get(par.tie[0], 0.0)
        return se

    def confidence_intervals(self, level=0.95) -> dict:
        """``{name: (low, high)}`` Wald intervals ``estimate ± z se`` of the free parameters."""
        from scipy.stats import norm

        if not 0.0 < level < 1.0:
            raise ParameterError(f"`level` must be in (0, 1); got {level!r}.")
        z = float(norm.ppf(0.5 + level / 2.0))
        return {n: (self.parameters[n].value - z * s, self.parameters[n].value + z * s)
                for n, s in self.standard_errors().items()}

    def simulate(self, u, *, initial=None):
        """The fitted model's free run for ``u`` (:meth:`fohw.Model.simulate`).

        ``u`` may be a :class:`fohw.Record` (its input, at its sampling time, checked against
        the model's) or a list of Records (a list of outputs): as :func:`fohw.simulate`.
        """
        if record_list(u) is not None:
            return simulate(self.model, u, initial=initial)
        return self.model.simulate(u, initial=initial)

    # --- reading -----------------------------------------------------------------------------
    def _rows(self):
        se = self.standard_errors() if self.covariance is not None else {}
        rows = []
        for name, par in self.parameters.items():
            how = ("fixed" if par.fixed else f"= {par.tie[1]:g} * {par.tie[0]}" if par.tie
                   else "")
            rows.append((name, par.value, se.get(name), how))
        return rows

    def summary(self) -> str:
        """A text table of the estimates (with standard errors) and the fit's diagnostics."""
        more = f" (+ {self.n_per_record} per-record values)" if self.n_per_record else ""
        lines = [f"fohw fit: {type(self.model).__name__}, N = {self.n_samples}, "
                 f"{self.n_free} free parameters{more}, Jacobian {self.jacobian}",
                 f"  status = {self.status.name}, sse = {self.sse:.6g}, rmse = {self.rmse:.6g}, "
                 f"noise variance = {self.noise_variance:.6g}, simulations = {self.nfev}",
                 f"  {self.message}"]
        if self.data:
            lines.append(f"  {describe_data(self.data)}")
        lines.append("")
        width = max(12, max((len(n) for n in self.parameters), default=0) + 2)
        lines.append(f"  {'parameter':<{width}}{'estimate':>14}{'std err':>14}")
        for name, value, se, how in self._rows():
            se_text = f"{se:>14.4g}" if se is not None else f"{how:>14}"
            lines.append(f"  {name:<{width}}{value:>14.6g}{se_text}")
        for name, entry in self.per_record.items():
            ses = entry["standard_errors"] or [None] * len(entry["values"])
            for r, (v, se) in enumerate(zip(entry["values"], ses)):
                se_text = f"{se:>14.4g}" if se is not None else f"{'':>14}"
                lines.append(f"  {f'{name}[{r}]':<{width}}{v:>14.6g}{se_text}  (record {r})")
        return "\n".join(lines)

    def __repr__(self):
        est = ", ".join(f"{n}={self.parameters[n].value:.4g}" for n in self.free_names[:6])
        more = ", …" if self.n_free > 6 else ""
        return (f"<FitResult {type(self.model).__name__} {self.status.name} sse={self.sse:.4g} "
                f"N={self.n_samples}: {est}{more}>")

    def _record_lines(self):
        """The records the fit used: name, samples and step (from :attr:`data`)."""
        records = self.data.get("records") or []
        if not records:
            return []
        unit = f" {self.data.get('time_unit')}".rstrip() if self.data.get("time_unit") else ""
        parts = []
        for k, r in enumerate(records):
            step = "non-uniform" if r.get("dt") is None else f"dt = {r['dt']:g}{unit}"
            parts.append(f"{r.get('name') or f'record {k}'} (N = {r['n_samples']}, {step})")
        return ["records: " + "; ".join(parts)]

    def _repr_html_(self):
        """The notebook view: what :meth:`summary` shows, with 95 % intervals and the records.

        The same view as :class:`fohw.IdentificationResult`'s (:func:`fohw._repr.estimates_html`):
        the head (kind, N, status, message, the data's names and units), the estimates with
        standard errors and Wald intervals (:meth:`confidence_intervals`), then the records.
        """
        from scipy.stats import norm

        from ._repr import estimates_html

        head = [line.strip() for line in self.summary().split("\n\n")[0].splitlines()]
        ci = self.confidence_intervals() if self.covariance is not None else {}
        rows = [(n, v, se, *ci.get(n, (None, None)), how) for n, v, se, how in self._rows()]
        z = float(norm.ppf(0.975))
        for name, entry in self.per_record.items():
            ses = entry["standard_errors"] or [None] * len(entry["values"])
            for r, (v, se) in enumerate(zip(entry["values"], ses)):
                low, high = (None, None) if se is None else (v - z * se, v + z * se)
                rows.append((f"{name}[{r}]", v, se, low, high, f"(record {r})"))
        return estimates_html(head[0], rows, lines=head[1:] + self._record_lines(), se_digits=4)

    # --- figures -------------------------------------------------------------------------------
    def bode(self, omega=None, *, others=None, label=None, title=None, ax=None, hz=False,
             time_unit=None, **where):
        """Bode diagram of the fitted model (:meth:`fohw.Model.bode`), in the record's time unit.

        The parameters are those of :func:`fohw.frequency_plots.bode`; the frequency axis is in
        the unit of the records the fit was given (``rad/s`` for seconds), the curve is
        ``"estimate"`` beside ``others``. A kind without a frequency response is refused,
        naming it.

        Returns
        -------
        matplotlib.figure.Figure
        """
        from .frequency_plots import bode

        return bode(self, omega, others=others, label=label, title=title, ax=ax, hz=hz,
                    time_unit=time_unit, **where)

    def nyquist(self, omega=None, *, others=None, label=None, title=None, ax=None, **where):
        """Nyquist diagram of the fitted model (:func:`fohw.frequency_plots.nyquist`).

        Returns
        -------
        matplotlib.figure.Figure
        """
        from .frequency_plots import nyquist

        return nyquist(self, omega, others=others, label=label, title=title, ax=ax, **where)

    # --- files -------------------------------------------------------------------------------
    def to_dict(self) -> dict:
        """JSON-ready values (:func:`fohw.save_result` writes them)."""
        return {"model": Model.to_dict(self.model), "covariance": None if self.covariance is None
                else self.covariance.tolist(), "status": self.status.name, "sse": self.sse,
                "n_samples": self.n_samples, "message": self.message, "nfev": self.nfev,
                "jacobian": self.jacobian,
                "starts": [[dict(s), float(v) if math.isfinite(v) else None]
                           for s, v in self.starts],
                "residuals": None if self.residuals is None else self.residuals.tolist(),
                "data_digest": self.data_digest, "options": _jsonable(dict(self.options)),
                "data": _jsonable(dict(self.data)), "per_record": _jsonable(dict(self.per_record)),
                "n_per_record": self.n_per_record}

    @classmethod
    def from_dict(cls, d) -> FitResult:
        """Inverse of :meth:`to_dict`, every field checked first.

        The checks are :func:`fohw.result_checks.check_fit_result_dict`'s, the same that
        :func:`fohw.load_result` makes: a field missing, unknown, of the wrong type, out of
        range or contradicting another is a :class:`~fohw.ParameterError` naming it.
        """
        model = check_fit_result_dict(d)
        cov = d.get("covariance")
        res = d.get("residuals")
        try:
            status = Status[d["status"]]
        except KeyError:
            raise ParameterError(f"unknown status {d['status']!r}; one of "
                                 f"{[s.name for s in Status]}.") from None
        return cls(model=model, parameters=model.parameters,
                   covariance=None if cov is None else np.array(cov, dtype=float),
                   status=status, sse=float(d["sse"]), n_samples=int(d["n_samples"]),
                   message=str(d.get("message", "")), nfev=int(d.get("nfev", 0)),
                   jacobian=str(d.get("jacobian", "exact")),
                   starts=tuple((dict(s), math.inf if v is None else float(v))
                                for s, v in d.get("starts", [])),
                   residuals=None if res is None else np.array(res, dtype=float),
                   data_digest=str(d.get("data_digest", "")), options=dict(d.get("options") or {}),
                   data=dict(d.get("data") or {}), per_record=dict(d.get("per_record") or {}),
                   n_per_record=int(d.get("n_per_record", 0)))

    def __reduce__(self):
        return (_rebuild, (self.to_dict(),))

    # --- the order test ----------------------------------------------------------------------
    def order_test(self, data_or_u=None, y=None, **kwargs):
        """The likelihood-ratio test of the free orders against orders 0: see :func:`fohw.order_test`.

        The test refits the model with its free orders held at 0 (:func:`fohw.fit`) on the
        data it was fitted to. A result keeps no data, and the fitting code sits above this
        module (CONTRIBUTING.md's layers: results, then estimators, then analysis; an import
        of either here would climb them), so this method runs no test: it raises, naming the
        call that does, ``fohw.order_test(fit, data_or_u, y, validation=(u_val, y_val))``.

        Raises
        ------
        ParameterError
            Always: the message gives the call with the data.

        Examples
        --------
        >>> import numpy as np, fohw
        >>> G = fohw.FractionalTF([1.0], [0.5], [2.0, 1.0], [1.0, 0.0], dt=0.05)   # s^0.5 / (2 s + 1)
        >>> G = G.with_parameters(G.parameters.replace("alpha0", fixed=True))     # beta0 free
        >>> u = np.random.default_rng(0).standard_normal(200)
        >>> y = G.simulate(u) + 0.01 * np.random.default_rng(1).standard_normal(200)
        >>> fit = fohw.fit(G, u, y)
        >>> t = fohw.order_test(fit, u, y)          # beta0 = 0 refitted, then fohw.lr_test
        >>> t.hypothesis, t.distribution, t.pvalue < 1e-6
        ('beta0 = 0', 'chi2_1', True)
        >>> try:
        ...     fit.order_test(u, y)
        ... except fohw.ParameterError as exc:
        ...     print(str(exc).split(": ")[-1])
        fohw.order_test(fit, record) or fohw.order_test(fit, u, y),
        with validation=(u_val, y_val) for the verdict.
        """
        from .lr_statistic import order_test

        return order_test(self)             # a FitResult: refused, naming fohw.order_test


def _rebuild(d):
    return FitResult.from_dict(d)


def _jsonable(value):
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, (list, tuple)):
        return [_jsonable(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _jsonable(v) for k, v in value.items()}
    return repr(value)

