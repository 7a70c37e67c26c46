"""The model kinds and what they are built from: nothing in here estimates anything.

The protocol every kind follows (:mod:`~fohw.model.base`, :class:`fohw.Model`) and its
parameters (:mod:`~fohw.model.parameters`); one module per kind:

- the paper's lagged Hammerstein–Wiener model (Sections 2.1–2.3, Eqs. 7, 14, 16) with one map
  per branch (:mod:`~fohw.model.system`, :class:`fohw.HammersteinWiener`) or a map per lag,
  theta itself (:mod:`~fohw.model.theta_hw`, :class:`fohw.ThetaHW`, what ``fohw.identify``
  fits), and their machinery: orders (:mod:`~fohw.model.orders`), bases
  (:mod:`~fohw.model.basis`), the class without values (:mod:`~fohw.model.structure`), the
  parameter layout (:mod:`~fohw.model.params`), the simulator (:mod:`~fohw.model.simulation`),
  its sensitivity (:mod:`~fohw.model.sensitivity`), the information matrix
  (:mod:`~fohw.model.regressors`), initial states (:mod:`~fohw.model.initial`), series output
  maps (:mod:`~fohw.model.output_map`) and the linear block's frequency view
  (:mod:`~fohw.model.hw_frequency`);
- a fractional transfer function (:mod:`~fohw.model.transfer`, :class:`fohw.FractionalTF`, with
  :mod:`~fohw.model.transfer_stability`, :mod:`~fohw.model.oustaloup`,
  :mod:`~fohw.model.frequency_response`);
- f → G(s) → h around one (:mod:`~fohw.model.wiener`, :class:`fohw.FractionalHW`);
- a battery cell's equivalent circuit (:mod:`~fohw.model.circuit`,
  :class:`fohw.EquivalentCircuit`) and its tables over SOC and temperature
  (:mod:`~fohw.model.circuit_tables`, :class:`fohw.CircuitTables`).

Shared by all: the GL weights and differences (:mod:`~fohw.model.gl`,
:mod:`~fohw.model.gl_expansion`), the convolution kernels (:mod:`~fohw.model.kernels`), the
compiled leaves (:mod:`~fohw.model._compiled`) and non-uniform instants
(:mod:`~fohw.model.irregular`).
"""
