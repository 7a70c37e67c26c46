"""Numbers and figures of docs/transfer_functions.md: convergence table, two identifications, Bode.

    python benchmarks/transfer_function_figures.py [--outdir docs/figures]
"""

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(ROOT / "tests"))
from tf_reference import SYSTEMS  # noqa: E402

import fohw  # noqa: E402


def convergence_table():
    hs = [0.1 / 2 ** i for i in range(7)]
    print("| system | step error at t = 1, h = 0.1 | h = 0.1/64 | order at t = 1 | sup-norm step order "
          "| impulse order at t = 1 |")
    print("|---|---:|---:|---:|---:|---:|")
    for name, (args, step, impulse) in SYSTEMS.items():
        G = fohw.FractionalTF(*args)
        e1, emax, ei = [], [], []
        for h in hs:
            t = np.arange(int(round(3.0 / h)) + 1) * h
            k1 = int(round(1.0 / h))
            ys, yi = G.step(t, dt=h), G.impulse(t, dt=h)
            e1.append(abs(ys[k1] - step(1.0)))
            emax.append(np.max(np.abs(ys[1:] - step(t[1:]))))
            ei.append(abs(yi[k1] - impulse(1.0)))
        order = [np.log2(e[-2] / e[-1]) for e in (e1, emax, ei)]
        print(f"| {name} | {e1[0]:.3g} | {e1[-1]:.3g} | {order[0]:.3f} | {order[1]:.3f} | {order[2]:.3f} |")


def _start(num_orders, den_orders, h, bounds=None):
    """The start model: coefficients 1, the given orders, default free parameters, ``bounds``."""
    G = fohw.FractionalTF(np.ones(len(num_orders)), num_orders, np.ones(len(den_orders)), den_orders,
                          dt=h)
    p = G.parameters
    for name, bound in (bounds or {}).items():
        p = p.replace(name, bounds=bound)
    return G.with_parameters(p)


def identify(outdir):
    rng = np.random.default_rng(2025)
    h, n = 0.05, 2000
    u = rng.standard_normal(n)
    cases = {
        "1/(2 s^0.6 + 1)": (fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.6, 0.0]),
                            dict(num_orders=[0.0], den_orders=[0.5, 0.0])),
        "1.5/(0.8 s^1.4 + 1.2 s^0.45 + 1)": (fohw.FractionalTF([1.5], [0.0], [0.8, 1.2, 1.0],
                                                               [1.4, 0.45, 0.0]),
                                             dict(num_orders=[0.0], den_orders=[1.0, 0.6, 0.0],
                                                  bounds={"a0": (0, np.inf), "a1": (0, np.inf)})),
    }
    for i, (name, (G, spec)) in enumerate(cases.items()):
        y0 = G.simulate(u, dt=h)
        sigma = 0.05 * np.std(y0)
        y = y0 + sigma * rng.standard_normal(n)
        fit = fohw.fit(_start(h=h, **spec), u, y)
        print(f"\n### {name}, noise std {sigma:.3g}, N = {n}, dt = {h}\n")
        se = fit.standard_errors()
        print("```\n" + f"{name}: {fit.model}\n  "
              + ", ".join(f"{k} {fit.parameters[k].value:.5g} ± {v:.2g}" for k, v in se.items())
              + "\n```\n")
        print("```\n" + fit.summary() + "\n```")
        fig = fit.model.bode(np.logspace(-3, 3, 400), others={"truth " + str(G): G},
                             title=f"estimate beside the truth: {name}")
        fig.savefig(outdir / f"tf_bode_fit_{i + 1}.png", dpi=90)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--outdir", default=str(ROOT / "docs" / "figures"))
    outdir = Path(parser.parse_args().outdir)
    outdir.mkdir(parents=True, exist_ok=True)
    convergence_table()
    identify(outdir)
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
    approx = G.oustaloup((1e-2, 1e2), 4)
    refined = G.oustaloup((1e-2, 1e2), 4, "refined")
    w = np.logspace(-4, 4, 400)
    from fohw.analysis.frequency import bode_plot
    curves = {"1/(s^0.5+1)": G.frequency_response(w), "Oustaloup N=4": approx.frequency_response(w),
              "refined N=4": refined.frequency_response(w)}
    fig = bode_plot(w, curves, band=(1e-2, 1e2),
                    title="Oustaloup approximations in [0.01, 100] rad/s")
    fig.savefig(outdir / "tf_oustaloup.png", dpi=90)
    for a in (approx, refined):
        e = a.errors()
        e_in = a.errors(band=(1e-1, 1e1))
        print(f"{a.method}: band max rel {e['max_relative']:.3g}, {e['max_magnitude_db']:.3g} dB, "
              f"{e['max_phase_deg']:.3g} deg; one decade inside: {e_in['max_relative']:.3g}")


if __name__ == "__main__":
    main()
