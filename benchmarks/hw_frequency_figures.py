"""Figures of docs/transfer_functions.md, sections on HW models: the frequency view of a fitted model.

    python benchmarks/hw_frequency_figures.py [--outdir docs/figures]
"""

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))

import fohw  # noqa: E402


def paper_example(outdir):
    """The paper's example (N = 1000, its noise): the varpro estimate's linear block beside the truth."""
    data = fohw.datasets.paper_example(1000, random_state=0)
    res = fohw.identify(data.u, data.y, na=2, nb=2, f_basis=2, g_basis=3)
    print(res.summary().split("\n\n")[-1])
    fig = res.bode(others={"true model": fohw.datasets.paper_model()},
                   title="paper example: linear block, varpro estimate (N = 1000)")
    fig.savefig(outdir / "hw_linear_block_bode.png", dpi=90)


def fractional_hw(outdir):
    """u -> u + 0.3 u^2 -> 1/(2 s^0.6 + 1) -> x - 0.2 x^2: fitted from noisy samples."""
    G = fohw.FractionalTF([1.0], [0.0], [2.0, 1.0], [0.6, 0.0])
    true = fohw.FractionalHW(G, p=[1.0, 0.3], f_basis=2, output_map=2, output_params=[-0.2],
                             dt=0.05)
    rng = np.random.default_rng(7)
    u = rng.uniform(-2, 2, 2000)
    y = true.simulate(u) + 0.01 * rng.standard_normal(u.size)
    start = fohw.FractionalHW(fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0]), p=[1.0, 0.0],
                              f_basis=2, output_map=2, dt=0.05)
    fit = fohw.fit(start, u, y)
    print(fit.summary())
    fig = fit.model.G.bode(others={"true G": G}, title="f → G(s) → h: G of the fit beside the truth")
    fig.savefig(outdir / "fotf_hw_bode.png", dpi=90)


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--outdir", default=str(ROOT / "docs" / "figures"))
    outdir = Path(parser.parse_args().outdir)
    paper_example(outdir)
    fractional_hw(outdir)
