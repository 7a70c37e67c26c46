"""How models are estimated: :func:`fohw.fit` for every kind, and the lagged kind's methods.

:mod:`~fohw.estimators.fit` fits any :class:`fohw.Model` by simulation error (starts, bounded
least squares, status, covariance); :mod:`~fohw.estimators.frequency_fit` fits any kind with a
frequency response to a measured one (:func:`fohw.fit_frequency_response`), and
:mod:`~fohw.estimators.impedance_fit` is that fit for a circuit's impedance spectrum (with the
circuit's conventions), alone or with a time record. :func:`fohw.identify`
(:mod:`~fohw.estimators.identify`) is the lagged kind's front door: the paper's own method
(:mod:`~fohw.estimators.hybrid`, built on the kernels of :mod:`~fohw.estimators.migd` and
:mod:`~fohw.estimators.milm`) and the estimators beyond it (:mod:`~fohw.estimators.varpro`,
:mod:`~fohw.estimators.structured`, :mod:`~fohw.estimators.output_error`,
:mod:`~fohw.estimators.rls`), one module per method.
"""
