"""Models the tests share: every kind of term the general model has (Eqs. 7, 14).

``MODELS[name]()`` builds one: several free orders, order-0 and fractional terms on one signal,
named orders shared between terms with a non-polynomial input basis, dt != 1 with an offset and
an operating point, past levels, and the paper's model.
"""

import numpy as np

import fohw

MODELS = {
    "per_lag": lambda: fohw.HammersteinWiener(
        [0.3, -0.1], [1.0, 0.4], [1.0, 0.2], [1.0, -0.05],
        {"alpha_a1": 0.3, "alpha_a2": 0.7, "alpha_b1": 0.5, "alpha_b2": 1.2}, orders="per_lag"),
    "mixed": lambda: fohw.HammersteinWiener(
        [0.5, 0.2, -0.1, 0.05], [1.0, 0.4, 0.3, -0.2], [1.0], [1.0], 0.45, orders="mixed"),
    "custom": lambda: fohw.HammersteinWiener(
        [0.4, 0.1], [0.8, 0.3, -0.2], [1.0, -0.3], [1.0], {"nu": 0.6, "mu": 1.1},
        f_basis={"u": lambda x: x, "tanh": np.tanh},
        orders=fohw.Orders([(1, "nu"), (2, 0.0)], [(1, 0.0), (1, "mu"), (3, "nu")])),
    "offset_dt_point": lambda: fohw.HammersteinWiener(
        [0.5, 0.2], [1.0, 0.3], [1.0], [1.0], 0.35, orders="mixed", dt=4.0, offset=0.7,
        operating_point=(2.0, 5.0)),
    "past": lambda: fohw.HammersteinWiener(
        [0.3, 0.2, 0.1, -0.1], [1.0, 0.5], [1.0, 0.2], [1.0, 0.1], {"alpha": 0.55},
        orders=fohw.Orders([(1, 0.0), (1, "alpha"), (2, 0.0), (2, "alpha")],
                           [(1, 0.0), (1, "alpha")]),
        past=(0.6, -0.4), dt=0.5),
    "paper": fohw.datasets.paper_model,
}
