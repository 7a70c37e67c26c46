"""Private base class giving estimators the scikit-learn parameter contract without depending on it."""

from __future__ import annotations

import inspect

from .exceptions import NotFittedError


class BaseEstimator:
    """``get_params`` / ``set_params`` from the ``__init__`` signature; settings only in ``__init__``.

    A subclass lists parameters renamed or removed since fohw 0.1 in ``_renamed = {old: what to
    do instead}``; passing an old name raises a ``ParameterError`` that says it.
    """

    _renamed: dict = {}

    def __new__(cls, *args, **kwargs):
        for old in kwargs:
            if old in cls._renamed:
                from .exceptions import ParameterError

                raise ParameterError(f"{cls.__name__} has no parameter `{old}`: "
                                     f"{cls._renamed[old]}")
        return super().__new__(cls)

    @classmethod
    def _param_names(cls):
        sig = inspect.signature(cls.__init__)
        return [p.name for p in sig.parameters.values()
                if p.name != "self" and p.kind != p.VAR_KEYWORD]

    def get_params(self, deep=True):
        """Return the estimator's settings as a dict."""
        return {name: getattr(self, name) for name in self._param_names()}

    def set_params(self, **params):
        """Set settings by name; unknown names raise ``ValueError``. Returns ``self``."""
        valid = self._param_names()
        for key, value in params.items():
            if key in self._renamed:
                from .exceptions import ParameterError

                raise ParameterError(f"{type(self).__name__} has no parameter `{key}`: "
                                     f"{self._renamed[key]}")
            if key not in valid:
                raise ValueError(f"invalid parameter {key!r} for {type(self).__name__}; valid "
                                 f"parameters are {valid}.")
            setattr(self, key, value)
        return self

    def __repr__(self):
        args = ", ".join(f"{k}={v!r}" for k, v in self.get_params().items())
        return f"{type(self).__name__}({args})"


def check_is_fitted(estimator, attribute):
    """Raise :class:`NotFittedError` unless ``estimator`` has ``attribute``."""
    if not hasattr(estimator, attribute):
        raise NotFittedError(f"this {type(estimator).__name__} is not fitted yet; call `fit` "
                             "first.")
