"""The current record and the OCV shared by the circuit tests (test_circuit_fit, test_circuit_conventions)."""

import numpy as np


def record(n=3000, seed=0, hold=20):
    """Current (positive = charge) held over blocks, and its coulomb count from SOC 0.8 (5 Ah)."""
    rng = np.random.default_rng(seed)
    i = np.repeat(rng.uniform(-3, 1.2, n // hold + 1), hold)[:n]
    soc = 0.8 + np.concatenate([[0.0], np.cumsum(i[:-1])]) / (3600 * 5.0)
    return np.column_stack([i, soc])


def ocv(soc):
    return 3.3 + 0.9 * soc - 0.3 * (soc - 0.5) ** 2
