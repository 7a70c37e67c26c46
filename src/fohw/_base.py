"""Private base class giving estimators the scikit-learn parameter contract without depending on it."""

from __future__ import annotations

import dataclasses
import inspect

from .exceptions import NotFittedError

#: Marks a setting without a default (a required keyword).
REQUIRED = inspect.Parameter.empty


class BaseEstimator:
    """Settings as keyword-only ``__init__`` parameters, ``get_params`` / ``set_params`` over them.

    A subclass declares its settings once: ``_model`` lists ``(name, default)`` of the model's
    own (``REQUIRED`` for no default) and ``_options`` names the options dataclass whose fields
    and defaults are the rest. ``__init__`` is made from the two and stores the settings only.
    """

    _model: tuple = ()
    _options: type | None = None

    def __init_subclass__(cls, **kwargs):
        super().__init_subclass__(**kwargs)
        settings = cls._settings()
        params = [inspect.Parameter("self", inspect.Parameter.POSITIONAL_OR_KEYWORD)]
        params += [inspect.Parameter(name, inspect.Parameter.KEYWORD_ONLY, default=default)
                   for name, default in settings.items()]

        def __init__(self, **given):
            unknown = [name for name in given if name not in settings]
            if unknown:
                raise TypeError(f"{cls.__name__}() got an unexpected keyword argument "
                                f"{unknown[0]!r}; its parameters are {', '.join(settings)}.")
            missing = [name for name, default in settings.items()
                       if default is REQUIRED and name not in given]
            if missing:
                raise TypeError(f"{cls.__name__}() missing required keyword argument(s): "
                                f"{', '.join(missing)}.")
            for name, default in settings.items():
                setattr(self, name, given.get(name, default))

        __init__.__signature__ = inspect.Signature(params)
        __init__.__qualname__ = f"{cls.__name__}.__init__"
        __init__.__doc__ = f"Store the settings of {cls.__name__} (keyword-only)."
        cls.__init__ = __init__

    @classmethod
    def _settings(cls):
        """``{name: default}`` of every setting, the model's first."""
        settings = dict(cls._model)
        if cls._options is not None:
            settings.update((f.name, f.default) for f in dataclasses.fields(cls._options))
        return settings

    @classmethod
    def _param_names(cls):
        return list(cls._settings())

    def get_params(self, deep=True):
        """Return the estimator's settings as a dict."""
        return {name: getattr(self, name) for name in self._param_names()}

    def set_params(self, **params):
        """Set settings by name; unknown names raise ``ValueError``. Returns ``self``."""
        valid = self._param_names()
        for key, value in params.items():
            if key not in valid:
                raise ValueError(f"invalid parameter {key!r} for {type(self).__name__}; valid "
                                 f"parameters are {valid}.")
            setattr(self, key, value)
        return self

    def _given_options(self):
        """The settings that are options, as the options dataclass (not yet checked)."""
        return self._options(**{f.name: getattr(self, f.name)
                                for f in dataclasses.fields(self._options)})

    def __repr__(self):
        args = ", ".join(f"{k}={v!r}" for k, v in self.get_params().items())
        return f"{type(self).__name__}({args})"


def check_is_fitted(estimator, attribute):
    """Raise :class:`NotFittedError` unless ``estimator`` has ``attribute``."""
    if not hasattr(estimator, attribute):
        raise NotFittedError(f"this {type(estimator).__name__} is not fitted yet; call `fit` "
                             "first.")
