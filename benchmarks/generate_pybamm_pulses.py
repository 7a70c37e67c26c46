"""Pulse tests of an LG M50 cell simulated with PyBaMM: the source of ``fohw/data/pybamm_pulses.npz``.

    python benchmarks/generate_pybamm_pulses.py [--out src/fohw/data/pybamm_pulses.npz]

Needs PyBaMM (``pip install pybamm``; the file shipped with fohw was written with PyBaMM
26.10.1.1, Python 3.11, by this script with its defaults). fohw does not need PyBaMM: the tests
and examples read the ``.npz`` file through :func:`fohw.datasets.pybamm_pulses`.

What is simulated: the Doyle–Fuller–Newman model (``pybamm.lithium_ion.DFN``, default options
plus ``{"thermal": "lumped"}``: one cell temperature, heated by the losses and cooled to the
ambient) with the ``Chen2020`` parameter set (an LG M50 21700 cell, nominal 5 Ah). In
``Chen2020`` the only parameters that depend on temperature are the two electrodes'
exchange-current densities (Arrhenius, 35 and 17.8 kJ/mol); the diffusivities and the
electrolyte's conductivity do not, and the open-circuit voltage has no entropic term. So the
series resistance falls with temperature, the diffusion polarisation hardly moves: a property of
the parameter set, not of LG M50 cells (whose measured diffusion slows in the cold).

Each record starts at rest at an ambient (= initial) temperature of 0, 10, 25, 35 or 45 degC and
an initial state of charge (PyBaMM's ``initial_soc``) of 0.3, 0.5 or 0.8, and follows one
protocol: rest 10 s, discharge at 1C (5 A) for 10 s, rest 40 s, charge at 1C for 10 s, rest 40 s
(110 s). The solution is read at ``t = k dt``, ``dt = 0.1 s`` (1101 samples), at step
boundaries from the step that ends there, so sample ``k`` carries the current that flowed over
``(t[k-1], t[k]]``: ``current[k]`` is that current, in fohw's sign (positive = charge, PyBaMM's
``Current [A]`` negated). The state of charge is the coulomb count from the initial one with the
nominal capacity, ``soc[k] = soc0 + dt sum_{j<k} current[j] / (3600 * 5)`` (the convention of
:class:`fohw.EquivalentCircuit`), and ``temperature`` is PyBaMM's ``X-averaged cell temperature``
in degC. ``ocv_soc``/``ocv_volts`` tabulate the cell's open-circuit voltage (positive minus
negative electrode potential at PyBaMM's stoichiometries for each state of charge).

Stored: the voltage on a 1 uV grid (int32), the temperature on a 1 uK grid (int32), the current
as float64; 64 kB compressed.
"""

import argparse
import platform
from pathlib import Path

import numpy as np

TEMPERATURES_C = (0.0, 10.0, 25.0, 35.0, 45.0)
SOCS = (0.3, 0.5, 0.8)
DT = 0.1
CAPACITY_AH = 5.0
STEPS = ("Rest for 10 seconds", "Discharge at 1C for 10 seconds", "Rest for 40 seconds",
         "Charge at 1C for 10 seconds", "Rest for 40 seconds")
DURATION = 110.0


def simulate(pybamm, temperature_c, soc0):
    """``(t, current, voltage, temperature)`` of one record at ``t = k DT`` (fohw's current sign)."""
    params = pybamm.ParameterValues("Chen2020")
    kelvin = 273.15 + temperature_c
    params.update({"Ambient temperature [K]": kelvin, "Initial temperature [K]": kelvin})
    model = pybamm.lithium_ion.DFN(options={"thermal": "lumped"})
    experiment = pybamm.Experiment([STEPS], period=f"{DT} seconds")
    sol = pybamm.Simulation(model, parameter_values=params, experiment=experiment).solve(
        initial_soc=soc0)
    t = sol["Time [s]"].entries
    grid = np.round(np.arange(0.0, DURATION + DT / 2, DT), 10)
    # np.searchsorted(side="left") takes the first of duplicated boundary times: the end of the
    # step that ends there.
    idx = np.searchsorted(t, grid - 1e-9, side="left")
    if not np.allclose(t[idx], grid, atol=1e-6):
        raise RuntimeError(f"PyBaMM's output times miss the grid by up to {np.abs(t[idx] - grid).max()} s")
    current = -sol["Current [A]"].entries[idx]
    voltage = sol["Voltage [V]"].entries[idx]
    temp = sol["X-averaged cell temperature [K]"].entries[idx] - 273.15
    # The current of sample k is the one that flowed over (t[k-1], t[k]]: at a boundary the
    # ending step's; PyBaMM's value there is already that step's. Round the set-point noise.
    current = np.round(current, 9) + 0.0       # no -0.0
    return grid, current, voltage, temp


def ocv_table(pybamm):
    """The open-circuit voltage at states of charge 0.05, 0.06, ..., 0.95 (Chen2020)."""
    params = pybamm.ParameterValues("Chen2020")
    un, up = params["Negative electrode OCP [V]"], params["Positive electrode OCP [V]"]
    socs = np.round(np.arange(0.05, 0.9501, 0.01), 10)
    volts = []
    for s in socs:
        x, y = pybamm.lithium_ion.get_initial_stoichiometries(float(s), params)
        volts.append(float(params.evaluate(up(pybamm.Scalar(y)) - un(pybamm.Scalar(x)))))
    return socs, np.array(volts)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=str(Path(__file__).resolve().parents[1] / "src" / "fohw"
                                             / "data" / "pybamm_pulses.npz"))
    args = parser.parse_args(argv)
    import pybamm

    records = [(tc, s) for tc in TEMPERATURES_C for s in SOCS]
    currents, volts_uv, temps_uk = [], [], []
    for tc, s in records:
        t, i, v, temp = simulate(pybamm, tc, s)
        currents.append(i)
        volts_uv.append(np.round(v * 1e6).astype(np.int32))
        temps_uk.append(np.round(temp * 1e6).astype(np.int32))
        print(f"T = {tc:4.1f} degC, soc0 = {s:.1f}: {t.size} samples, v {v.min():.4f}..{v.max():.4f} V, "
              f"T {temp.min():.3f}..{temp.max():.3f} degC")
    socs, ocv = ocv_table(pybamm)
    np.savez_compressed(
        args.out,
        temperature_c=np.array([r[0] for r in records]), soc0=np.array([r[1] for r in records]),
        dt=np.array(DT), capacity_ah=np.array(CAPACITY_AH),
        current=np.array(currents), voltage_uv=np.array(volts_uv),
        cell_temperature_uk=np.array(temps_uk), ocv_soc=socs, ocv_volts=ocv,
        protocol=np.array(" / ".join(STEPS)),
        generator=np.array(f"benchmarks/generate_pybamm_pulses.py with PyBaMM {pybamm.__version__} "
                           f"(DFN, lumped thermal, Chen2020), Python {platform.python_version()}"))
    print(f"wrote {args.out} ({Path(args.out).stat().st_size} bytes)")


if __name__ == "__main__":
    main()
