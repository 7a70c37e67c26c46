"""Coverage of varpro's 95 % confidence intervals, by Monte Carlo on the paper's example.

    python examples/interval_coverage.py --outdir results [--fast] [--seeds 200] [--n-samples 2000]
        [--method varpro|structured]

For every seed: simulate, fit with the method (default "varpro"), and check whether each 95 % interval
(theta, alpha and the recovered p2, q2, q3) contains the true value. Writes coverage.md with
the fraction per parameter and its binomial standard error.
"""

import argparse
import sys
import time
from pathlib import Path

import numpy as np

import fohw

STRUCT = dict(na=2, nb=2, f_basis=2, g_basis=3)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--outdir", type=Path, default=Path("results"))
    ap.add_argument("--fast", action="store_true", help="20 seeds, N = 1000")
    ap.add_argument("--seeds", type=int, default=200)
    ap.add_argument("--n-samples", type=int, default=2000)
    ap.add_argument("--method", choices=("varpro", "structured"), default="varpro")
    args = ap.parse_args(argv)
    n_seeds, n = (20, 1000) if args.fast else (args.seeds, args.n_samples)
    t0 = time.perf_counter()
    model = fohw.datasets.paper_model()
    truth = dict(zip(model.parameter_names, model.theta), alpha=model.alpha)
    truth.update(zip(model.layout.model_parameter_names, model.layout.recover_vector(model.theta)))
    hits = {k: 0 for k in truth}
    for seed in range(n_seeds):
        d = fohw.datasets.paper_example(n, random_state=50_000 + seed)
        ci = fohw.identify(d.u, d.y, method=args.method, **STRUCT).confidence_intervals(0.95)
        for k, v in truth.items():
            hits[k] += ci[k][0] <= v <= ci[k][1]
    se = np.sqrt(0.95 * 0.05 / n_seeds)
    lines = [f"# Coverage of the 95 % intervals ({args.method}, paper's example, N = {n}, {n_seeds} seeds)",
             "", f"Binomial standard error of a coverage near 0.95 over {n_seeds} seeds: {se:.3f}.",
             "", "| parameter | coverage | (coverage - 0.95) / se |", "|---|---:|---:|"]
    for k, h in hits.items():
        c = h / n_seeds
        lines.append(f"| {k} | {c:.3f} | {(c - 0.95) / se:+.1f} |")
    pooled = sum(hits.values()) / (n_seeds * len(hits))
    lines += ["", f"Pooled over all parameters: {pooled:.3f}. Time {time.perf_counter() - t0:.0f} s."]
    text = "\n".join(lines) + "\n"
    args.outdir.mkdir(parents=True, exist_ok=True)
    (args.outdir / "coverage.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
