"""The model kinds and what they are built from: nothing in here estimates anything.

The protocol every kind follows (:mod:`~fohw.model.base`, :class:`fohw.Model`), its
parameters (:mod:`~fohw.model.parameters`) and its one simulation front door
(:mod:`~fohw.model.simulate`, :func:`fohw.simulate`); then the kinds:

- the paper's lagged Hammerstein–Wiener model, in its own folder (:mod:`fohw.model.lagged`):
  one map per branch (:class:`fohw.HammersteinWiener`) or a map per lag, theta itself
  (:class:`fohw.ThetaHW`, what ``fohw.identify`` fits), with its class, parameter layout,
  simulator, sensitivity, information matrix, initial states and frequency view;
- a fractional transfer function (:mod:`~fohw.model.transfer`, :class:`fohw.FractionalTF`, with
  :mod:`~fohw.model.transfer_stability`, :mod:`~fohw.model.oustaloup`,
  :mod:`~fohw.model.frequency_response`);
- f → G(s) → h around one (:mod:`~fohw.model.wiener`, :class:`fohw.FractionalHW`);
- a battery cell's equivalent circuit (:mod:`~fohw.model.circuit`,
  :class:`fohw.EquivalentCircuit`) and its tables over SOC and temperature
  (:mod:`~fohw.model.circuit_tables`, :class:`fohw.CircuitTables`).

Shared by several kinds: the orders of fractional terms (:mod:`~fohw.model.orders`), the basis
functions of static maps (:mod:`~fohw.model.basis`) and series output maps
(:mod:`~fohw.model.output_map`); the GL weights and differences (:mod:`~fohw.model.gl`,
:mod:`~fohw.model.gl_expansion`), the convolution kernels (:mod:`~fohw.model.kernels`), the
compiled leaves (:mod:`~fohw.model._compiled`) and non-uniform instants
(:mod:`~fohw.model.irregular`).
"""
