"""The protocol every model kind follows (:class:`fohw.Model`) and the registry of kinds.

A kind is a class that provides its :attr:`~Model.parameters` (a :class:`fohw.Parameters`), a
copy with new values (:meth:`~Model.with_parameters`) and a simulator
(:meth:`~Model.simulate`). Everything else fohw does with a model is written once on top of
these three: :func:`fohw.fit`, :func:`fohw.crb`, :func:`fohw.lr_test`,
:func:`fohw.profile_interval`, :func:`fohw.select_structure`, :func:`fohw.compare`,
:func:`fohw.simulate`, the JSON files and the batch runs. A kind may also give an exact
:meth:`~Model.jacobian` (else finite differences are used, and results say so) and better
starts for the fit (:meth:`~Model.starts`, :meth:`~Model.linear_start`).

Subclasses are registered by name when they are defined, so :func:`fohw.load_model` can
rebuild them; :func:`register_model` registers one explicitly (e.g. defined with
``register=False``).
"""

from __future__ import annotations

import abc
import copy
import inspect

import numpy as np

from .._validation import check_array
from ..exceptions import DimensionError, ModelHookError, ParameterError
from .parameters import Parameters, bounds_overridden

__all__ = ["Model", "register_model", "model_class", "registered_kinds"]

_REGISTRY: dict[str, type] = {}


def register_model(cls, name=None):
    """Register a :class:`Model` subclass under ``name`` (default its ``kind``) for files.

    Usable as a decorator. Registering another class under a name that is taken raises,
    unless it is the same class (re-registering is harmless) or a class of the same module
    and qualified name (a module reloaded in a notebook).

    Examples
    --------
    >>> import fohw
    >>> class Gain(fohw.Model, register=False):
    ...     def __init__(self, k=1.0):
    ...         self.k = k
    ...     @property
    ...     def parameters(self):
    ...         return fohw.Parameters([fohw.Parameter("k", self.k)])
    ...     def with_parameters(self, values):
    ...         return Gain(self.parameters.with_values(values)["k"].value)
    ...     def simulate(self, u, *, initial=None):
    ...         return self.k * self.check_input(u)
    >>> fohw.register_model(Gain) is Gain
    True
    """
    if not (isinstance(cls, type) and issubclass(cls, Model)):
        raise ParameterError(f"register_model takes a subclass of fohw.Model; got {cls!r}.")
    if inspect.isabstract(cls):
        missing = sorted(cls.__abstractmethods__)
        raise ParameterError(f"{cls.__name__} does not implement {missing}; a model kind provides "
                             "`parameters`, `with_parameters` and `simulate`.")
    name = cls.kind_name() if name is None else name
    if not isinstance(name, str) or not name:
        raise ParameterError(f"a model kind's name must be a non-empty string; got {name!r}.")
    old = _REGISTRY.get(name)
    if old is not None and old is not cls and (old.__module__, old.__qualname__) != \
            (cls.__module__, cls.__qualname__):
        raise ParameterError(f"the model kind name {name!r} is taken by {old.__module__}."
                             f"{old.__qualname__}; give {cls.__qualname__} another `kind`.")
    _REGISTRY[name] = cls
    return cls


def model_class(name):
    """The registered :class:`Model` subclass called ``name`` (raises naming the known kinds)."""
    try:
        return _REGISTRY[name]
    except (KeyError, TypeError):
        raise ParameterError(f"no model kind {name!r} is registered; known kinds: "
                             f"{sorted(_REGISTRY)}. Import the module that defines it, or call "
                             "fohw.register_model(cls), before loading.") from None


def registered_kinds():
    """The names of the registered model kinds."""
    return tuple(sorted(_REGISTRY))


_SETTINGS = "_fohw_parameter_settings"


def _overlay_settings(fget):
    def parameters(self):
        settings = getattr(self, _SETTINGS, None)
        if settings is None:
            return fget(self)
        with bounds_overridden():       # the settings' bounds hold, not the kind's defaults
            own = fget(self)
        # the values are the kind's own; the bounds the settings' (which may have just changed)
        return settings.with_values({n: p.value for n, p in own.items() if p.tie is None
                                     and settings[n].tie is None}, check_bounds=False)
    parameters.__wrapped__ = fget
    return parameters


def _keep_settings(method):
    def with_parameters(self, values):
        if isinstance(values, Parameters):
            # The new settings, in the kind's own order (the Jacobian's columns follow it), are
            # in force while the kind builds the copy, so values inside widened bounds pass.
            fget = getattr(type(self).parameters.fget, "__wrapped__", None)
            with bounds_overridden():
                own = fget(self) if fget is not None else self.parameters
            settings = own.merged(values)
            self.check_settings(settings)
            probe = copy.copy(self)
            _attach(probe, settings)
            new = method(probe, values)
        else:
            settings = getattr(self, _SETTINGS, None)
            new = method(self, values)
        if not isinstance(new, Model):      # said here, not as a failure to attach settings
            raise ModelHookError(f"{type(self).__name__}.with_parameters returned "
                                 f"{type(new).__name__} {repr(new)[:40]}; it must return a new "
                                 f"model of the kind (a {type(self).__name__}).", "with_parameters")
        if settings is not None and new is not self:
            _attach(new, settings)
        return new
    with_parameters.__wrapped__ = method
    with_parameters.__doc__ = method.__doc__
    return with_parameters


def _attach(model, settings):
    try:
        object.__setattr__(model, _SETTINGS, settings)
    except AttributeError:
        raise ParameterError(f"{type(model).__name__} keeps no attributes (__slots__); fixed "
                             "flags, bounds and ties given through fohw.Parameters cannot be "
                             "kept. Declare them in the kind's `parameters`.") from None


class Model(abc.ABC):
    """A model kind: parameters, a copy with new values, a simulator.

    Subclass it and provide :attr:`parameters`, :meth:`with_parameters` and :meth:`simulate`;
    every fohw verb then works for the new kind. The class is registered under its ``kind``
    (default: the class name; the qualified name ``module.Class`` when another class already
    holds that name) when it is defined; pass ``register=False`` in the class statement to skip
    that and call :func:`fohw.register_model` later.

    Optional hooks: :attr:`dt` (the sampling time; 1 by default), :attr:`n_inputs`,
    :meth:`jacobian` (exact ``d yhat / d parameters``; finite differences otherwise),
    :meth:`starts` and :meth:`linear_start` (where :func:`fohw.fit` starts), :meth:`config`
    (the settings that are not parameters, for files), :meth:`check_settings` (bounds or ties
    the kind cannot hold), :meth:`penalty` (a regularisation added to the fit's criterion),
    :meth:`check_fitted` (a kind's own sanity check of a fitted model), :meth:`simulate_at`
    (non-uniform instants) and :meth:`frequency_response` (the response at ``s = j omega``;
    with it :meth:`bode` and :meth:`nyquist` draw the kind, together with
    :meth:`default_frequencies`, :meth:`response_label` and :attr:`response_kind`). Every kind
    reads in a terminal (:meth:`summary`) and a notebook (``_repr_html_``) as a table of its
    parameters; :meth:`description` adds the kind's own lines.

    What fohw checks of a kind, once, in :func:`fohw.fit` (and the verbs built on it) and
    :func:`fohw.simulate`: the input it hands the hooks is read-only (the caller's arrays are
    never changed; copy before writing); ``simulate`` returns shape ``(N,)``; ``jacobian``
    returns ``None`` or ``(yhat, J)`` with ``J`` of shape ``(N, n_parameters)``, finite where
    ``yhat`` is; ``starts`` a list of models of the kind, ``linear_start`` one or ``None``;
    ``with_parameters`` a model. A hook refuses values with a :class:`fohw.ParameterError`
    (or returns a diverging output); anything else it raises, or returns against these rules,
    is a :class:`fohw.exceptions.ModelHookError` naming the hook.

    Examples
    --------
    A first-order lag ``y[k] = a y[k-1] + b u[k-1]``, a kind of its own in a dozen lines:

    >>> import numpy as np
    >>> import fohw
    >>> class Lag(fohw.Model):
    ...     def __init__(self, a=0.5, b=1.0):
    ...         self.a, self.b = a, b
    ...     @property
    ...     def parameters(self):
    ...         return fohw.Parameters([fohw.Parameter("a", self.a, bounds=(-0.99, 0.99)),
    ...                                 fohw.Parameter("b", self.b)])
    ...     def with_parameters(self, values):
    ...         v = self.parameters.with_values(values).valuesdict()
    ...         return Lag(v["a"], v["b"])
    ...     def simulate(self, u, *, initial=None):
    ...         u = self.check_input(u)
    ...         y = np.zeros_like(u)
    ...         for k in range(1, u.size):
    ...             y[k] = self.a * y[k - 1] + self.b * u[k - 1]
    ...         return y
    >>> u = np.random.default_rng(0).standard_normal(200)
    >>> y = Lag(0.8, 2.0).simulate(u)
    >>> fit = fohw.fit(Lag(), u, y)
    >>> print(fit.status.name, np.round([fit.parameters["a"].value, fit.parameters["b"].value], 6))
    CONVERGED [0.8 2. ]
    """

    #: The name the kind is registered and written to files under (default: the class name).
    kind: str | None = None

    def __init_subclass__(cls, register=True, **kwargs):
        super().__init_subclass__(**kwargs)
        # A kind writes `parameters` and `with_parameters` for values only; the settings of a
        # fohw.Parameters given to `with_parameters` (fixed flags, bounds, ties) ride along here,
        # so every kind keeps them without writing a line for it.
        if isinstance(cls.__dict__.get("parameters"), property):
            cls.parameters = property(_overlay_settings(cls.__dict__["parameters"].fget),
                                      doc=cls.__dict__["parameters"].__doc__)
        if "with_parameters" in cls.__dict__:
            cls.with_parameters = _keep_settings(cls.__dict__["with_parameters"])
        if register and not inspect.isabstract(cls):
            taken = _REGISTRY.get(cls.kind_name())
            if taken is not None and taken is not cls and "kind" not in cls.__dict__ and \
                    (taken.__module__, taken.__qualname__) != (cls.__module__, cls.__qualname__):
                # Another class of that name (e.g. a `Lag` in two notebooks or test files): this
                # one is registered under its qualified name, which its files then carry.
                cls.kind = f"{cls.__module__}.{cls.__qualname__}"
            register_model(cls)

    @classmethod
    def kind_name(cls) -> str:
        """The registry name: :attr:`kind` if the class sets it, else the class name."""
        return cls.__dict__.get("kind") or cls.__name__

    # --- the three a kind must provide ---------------------------------------------------
    @property
    @abc.abstractmethod
    def parameters(self) -> Parameters:
        """Every number of the model, with bounds, fixed flags and ties."""

    @abc.abstractmethod
    def with_parameters(self, values) -> Model:
        """A new model with new parameter values.

        ``values`` is a mapping ``name -> float``, or a :class:`fohw.Parameters` (whose bounds,
        fixed flags and ties the new model keeps, so :func:`fohw.fit` holds its fixed ones).
        """

    @abc.abstractmethod
    def simulate(self, u, *, initial=None) -> np.ndarray:
        """The model's output for the input ``u`` (free run from ``initial``; default rest)."""

    # --- optional hooks --------------------------------------------------------------------
    @property
    def dt(self) -> float:
        """Sampling time (default 1)."""
        return 1.0

    @property
    def n_inputs(self) -> int:
        """Number of input columns ``u`` has (default 1: a 1-D signal)."""
        return 1

    def jacobian(self, u):
        """``(yhat, J)``: the output and ``d yhat / d value`` of every parameter, or ``None``.

        ``J`` has one column per parameter in :attr:`parameters` order (fixed and tied ones
        included). ``None`` (the default) makes :func:`fohw.fit` use central finite differences
        and say so in its result.
        """
        return None

    def starts(self, u, y):
        """Candidate start models for :func:`fohw.fit` (default: the model itself).

        A kind whose scan can weight the samples declares a keyword ``sample_weight``
        (``starts(u, y, *, sample_weight=None)``); :func:`fohw.fit` passes its
        ``sample_weight`` only to a hook that declares it (so does :meth:`linear_start`).
        """
        return [self]

    def linear_start(self, u, y):
        """A start whose linear parameters are solved for ``y`` (or ``None``: no such step).

        May declare ``sample_weight`` like :meth:`starts`.
        """
        return None

    def penalty(self):
        """``(r, J)``: residuals the kind adds to a fit's squared error (a regularisation), or ``None``.

        ``r`` (shape ``(m,)``) at the model's values and ``J = d r / d value`` (shape ``(m,
        n_parameters)``, :attr:`parameters` order); :func:`fohw.fit` minimises
        ``sum (y - yhat)^2 + r @ r``. ``None`` (the default): no penalty.
        """
        return None

    def check_settings(self, parameters):
        """Refuse settings the kind cannot hold, naming the parameter (default: accept them).

        Called when :meth:`with_parameters` gets a :class:`fohw.Parameters`: a bound beyond the
        kind's domain, or a tie the kind has no meaning for, is refused there.
        """
        return None

    def check_fitted(self, u, y):
        """A sentence saying why this fitted model is not trustworthy, or ``None`` (default)."""
        return None

    def simulate_at(self, u, t, *, intersample="zoh", refine=None, step=None) -> np.ndarray:
        """The output at non-uniform instants ``t`` (:func:`fohw.model.irregular.simulate_at`).

        The default is the fine-grid scheme (:func:`fohw.model.irregular.grid_simulate`): the
        kind rebuilt at a fine step through :meth:`config`'s ``dt``, which a kind without one
        cannot take (refused). A kind that is exact on any steps, or discrete in samples,
        overrides it.
        """
        from .irregular import grid_simulate

        return grid_simulate(self, u, t, intersample=intersample, refine=refine, step=step)

    #: What :meth:`frequency_response` returns, for the figures: ``"transfer"`` (a transfer
    #: function from input to output; the Nyquist plot marks the critical point -1) or
    #: ``"impedance"`` (voltage over current; the Nyquist plot is the impedance plane, ``-Im Z``
    #: upwards, without the critical point, as electrochemistry draws it).
    response_kind: str = "transfer"

    def frequency_response(self, omega):
        """The response at ``s = j omega`` (complex, shape of ``omega``), or ``None`` (default).

        ``omega`` is the angular frequency in radians per unit of :attr:`dt`'s time. ``None``
        says "this kind has none": :meth:`bode` and :meth:`nyquist` then refuse, naming the
        kind. A kind whose response depends on an operating point takes it as keywords with
        documented defaults (or refuses without them, naming them); :meth:`bode` and
        :meth:`nyquist` pass their extra keywords on.
        """
        return None

    def default_frequencies(self, n=400):
        """The grid :meth:`bode` and :meth:`nyquist` draw on without ``omega``.

        The default: ``n`` logarithmically spaced frequencies over the three decades below the
        Nyquist frequency ``pi / dt`` (where sampled data see the response); a kind overrides
        it with its own corner frequencies.

        Examples
        --------
        >>> import numpy as np
        >>> import fohw
        >>> w = fohw.datasets.paper_model().default_frequencies(4)      # dt = 1
        >>> np.round(w / np.pi, 12)
        array([0.001, 0.01 , 0.1  , 1.   ])
        """
        from .._validation import check_int

        n = check_int(n, "n", minimum=2, maximum=1_000_000)
        dt = self.dt
        if dt is None:
            raise ParameterError(f"this {type(self).__name__} has no sampling time `dt`, so it has "
                                 "no default frequency grid; give `omega`.")
        nyquist = np.pi / float(dt)
        return np.logspace(np.log10(nyquist) - 3.0, np.log10(nyquist), n)

    def response_label(self) -> str:
        """What the curve of :meth:`frequency_response` is called in a figure (default: the kind)."""
        return self.kind_name()

    def bode(self, omega=None, *, others=None, label=None, title=None, ax=None, hz=False,
             time_unit=None, **where):
        """Bode diagram of :meth:`frequency_response` (:func:`fohw.frequency_plots.bode`).

        Parameters
        ----------
        omega : array_like, optional
            Angular frequencies (default :meth:`default_frequencies`).
        others : dict of str to model or fit, optional
            Further models (or fit results) drawn on the same axes, e.g. the truth beside an
            estimate.
        label : str, optional
            The curve's name (default :meth:`response_label`).
        title : str, optional
            Figure title.
        ax : matplotlib Axes or sequence of two Axes, optional
            One Axes: the magnitude only; two: magnitude and phase (default: a new figure).
        hz : bool, optional
            Against ``f = omega / (2 pi)``.
        time_unit : str, optional
            The unit of :attr:`dt`, for the axis label (``"s"``: rad/s; default unknown).
        **where
            Passed to :meth:`frequency_response` (an operating point, e.g. ``soc=`` and
            ``temperature=`` of :class:`fohw.CircuitTables`).

        Returns
        -------
        matplotlib.figure.Figure
            Magnitude and phase axes; a new figure opens no window and shows in a notebook.

        Raises
        ------
        ParameterError
            The kind has no frequency response (:meth:`frequency_response` returns ``None``).

        Examples
        --------
        >>> import fohw
        >>> fig = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0]).bode()
        >>> fig.axes[0].get_ylabel()
        'magnitude [dB]'
        """
        from ..frequency_plots import bode

        return bode(self, omega, others=others, label=label, title=title, ax=ax, hz=hz,
                    time_unit=time_unit, **where)

    def nyquist(self, omega=None, *, others=None, label=None, title=None, ax=None, **where):
        """Nyquist diagram of :meth:`frequency_response` (:func:`fohw.frequency_plots.nyquist`).

        The parameters are those of :meth:`bode` (without ``hz`` and ``time_unit``); an
        ``"impedance"`` kind (:attr:`response_kind`) is drawn in the impedance plane.

        Returns
        -------
        matplotlib.figure.Figure

        Examples
        --------
        >>> import fohw
        >>> fig = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [1.5, 0.0]).nyquist()
        >>> fig.axes[0].get_xlabel()
        'real part'
        """
        from ..frequency_plots import nyquist

        return nyquist(self, omega, others=others, label=label, title=title, ax=ax, **where)

    # --- how a model reads ---------------------------------------------------------------------
    def description(self) -> list:
        """Lines that say what the model is besides its parameters' values.

        The default: the kind's own text (its ``str``) when it writes one, and the sampling
        time. :meth:`summary` and the notebook table show them above the parameters.
        """
        lines = []
        if type(self).__str__ is not object.__str__:
            lines.append(str(self))
        dt = self.dt
        if dt is not None:
            lines.append(f"dt = {float(dt):g}")
        return lines

    def _parameter_rows(self):
        rows = []
        for name, par in self.parameters.items():
            how = (f"= {par.tie[1]:g} * {par.tie[0]}" if par.tie is not None
                   else "fixed" if par.fixed else "free")
            rows.append((name, par.value, f"[{par.bounds[0]:g}, {par.bounds[1]:g}]", how))
        return rows

    def summary(self) -> str:
        """A text table of the parameters: name, value, bounds, free or fixed (or tied).

        Examples
        --------
        >>> import fohw
        >>> print(fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.5, 0.0], dt=0.1).summary())
        FractionalTF
          1 / (2 s^0.5 + 1)
          dt = 0.1
        <BLANKLINE>
          parameter          value  bounds            free/fixed
          b0                     1  [-inf, inf]       free
          beta0                  0  [-2, 2]           fixed
          a0                     2  [-inf, inf]       free
          a1                     1  [-inf, inf]       fixed
          alpha0               0.5  [0, 2]            free
          alpha1                 0  [0, 2]            fixed
        """
        rows = self._parameter_rows()
        width = max(12, max((len(r[0]) for r in rows), default=0) + 2)
        lines = [self.kind_name(), *(f"  {line}" for line in self.description()), ""]
        lines.append(f"  {'parameter':<{width}}{'value':>12}  {'bounds':<18}free/fixed")
        lines += [f"  {n:<{width}}{v:>12.6g}  {b:<18}{how}" for n, v, b, how in rows]
        return "\n".join(line.rstrip() for line in lines)

    def _repr_html_(self):
        """The notebook view: the parameters' table (name, value, bounds, free or fixed)."""
        from .._repr import html_table

        return html_table(self.kind_name(), ["parameter", "value", "bounds", ""],
                          self._parameter_rows(), lines=self.description(), digits=6)

    def config(self) -> dict:
        """The settings that are not parameters, as keyword arguments of the constructor.

        The default (``{}``) suits a kind whose constructor needs no arguments besides its
        parameters' values; :meth:`from_dict` calls ``cls(**config)`` and then
        :meth:`with_parameters`.
        """
        return {}

    def check_input(self, u) -> np.ndarray:
        """``u`` as a float array with :attr:`n_inputs` columns (1-D for one input), or raise."""
        if self.n_inputs == 1:
            if np.ndim(u) == 2 and np.shape(u)[1] == 1:
                u = np.asarray(u)[:, 0]
            return check_array(u, "u")
        arr = check_array(u, "u", ndim=2)
        if arr.shape[1] != self.n_inputs:
            raise DimensionError(f"`u` must have {self.n_inputs} columns for this "
                                 f"{type(self).__name__}; got shape {arr.shape}.")
        return arr

    # --- files -------------------------------------------------------------------------------
    def to_dict(self) -> dict:
        """``{"kind", "config", "parameters"}``: what :func:`fohw.save_model` writes."""
        return {"kind": self.kind_name(), "config": self.config(),
                "parameters": self.parameters.to_dict()}

    @classmethod
    def from_dict(cls, d) -> Model:
        """Rebuild a model written by :meth:`to_dict` (of this class or a registered kind)."""
        if not isinstance(d, dict) or not {"kind", "parameters"} <= set(d):
            raise ParameterError("a model file entry needs 'kind' and 'parameters'; got "
                                 f"{sorted(d) if isinstance(d, dict) else type(d).__name__}.")
        kind = model_class(d["kind"])
        if cls is not Model and not issubclass(kind, cls):
            raise ParameterError(f"the entry is a {d['kind']!r} model, not a {cls.__name__}.")
        config = d.get("config") or {}
        if not isinstance(config, dict):
            raise ParameterError(f"a model's 'config' must be a mapping; got {config!r}.")
        try:
            base = kind.from_config(config)
        except TypeError as exc:
            raise ParameterError(f"cannot rebuild a {d['kind']!r} model from its config "
                                 f"{config!r}: {exc}") from None
        params = base.parameters.merged(Parameters.from_dict(d["parameters"]))
        return base.with_parameters(params)

    @classmethod
    def from_config(cls, config) -> Model:
        """A model of this kind from :meth:`config`'s settings (parameters at their defaults)."""
        return cls(**config)

    def __eq__(self, other):
        if type(other) is not type(self):
            return NotImplemented
        return self.config() == other.config() and self.parameters == other.parameters

    __hash__ = None
