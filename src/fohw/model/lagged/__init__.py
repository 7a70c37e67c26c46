"""The lagged fractional Hammerstein–Wiener kind (the paper's model) and its machinery.

The kind in its two forms: one map per branch, :class:`fohw.HammersteinWiener`
(:mod:`~fohw.model.lagged.system`, Eqs. 10–18) and a map per lag, theta itself,
:class:`fohw.ThetaHW` (:mod:`~fohw.model.lagged.theta_hw`, Eqs. 19–20, what the paper's
methods and ``fohw.identify`` fit); the class without values (:mod:`~fohw.model.lagged.structure`)
and its parameter layout (:mod:`~fohw.model.lagged.params`); the simulator
(:mod:`~fohw.model.lagged.simulation`, Eqs. 14, 16), its sensitivity
(:mod:`~fohw.model.lagged.sensitivity`), the information matrix
(:mod:`~fohw.model.lagged.regressors`), initial states (:mod:`~fohw.model.lagged.initial`) and
the linear block's frequency view (:mod:`~fohw.model.lagged.hw_frequency`). The orders, bases
and series output maps it is built from are shared with other kinds and stay in
:mod:`fohw.model`.
"""
