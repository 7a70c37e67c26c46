"""What a fractional-order Hammerstein–Wiener system is (paper Sections 2.1–2.3).

GL weights and differences (:mod:`~fohw.model.gl`), basis functions of the static
nonlinearities (:mod:`~fohw.model.basis`), the parameter layout (:mod:`~fohw.model.params`),
the model (:mod:`~fohw.model.system`), its simulator (:mod:`~fohw.model.simulation`) and the
information matrix (:mod:`~fohw.model.regressors`). Nothing in here estimates anything.
"""
