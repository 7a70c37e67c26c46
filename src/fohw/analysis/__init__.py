"""What is done with fitted models, for every kind: judge, test, select, run in batches.

Validation on a record (:mod:`~fohw.analysis.validation`, :mod:`~fohw.analysis.metrics`),
Cramér–Rao bounds (:mod:`~fohw.analysis.crb`), likelihood-ratio tests and the order verdict
(:mod:`~fohw.analysis.lrtest`, :mod:`~fohw.analysis.order_verdict`), profile intervals
(:mod:`~fohw.analysis.profile_interval`), structure selection (:mod:`~fohw.analysis.selection`),
Monte Carlo studies (:mod:`~fohw.analysis.montecarlo`) and many records at once
(:mod:`~fohw.analysis.batch`).
"""
