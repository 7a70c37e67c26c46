"""Judging identified models: bounds, validation metrics and Monte Carlo studies.

:mod:`~fohw.analysis.crb` (Cramér–Rao bounds), :mod:`~fohw.analysis.metrics` (fit index, error
range, residual tests) and :mod:`~fohw.analysis.montecarlo` (many seeds × methods × settings).
"""
