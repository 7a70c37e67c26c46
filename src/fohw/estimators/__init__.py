"""How theta and the fractional order are estimated: one module per method.

The paper's own method (:mod:`~fohw.estimators.hybrid`, built on the kernels of
:mod:`~fohw.estimators.migd` and :mod:`~fohw.estimators.milm`) and the estimators beyond it.
"""
