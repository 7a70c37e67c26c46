"""Convergence of the fine-grid scheme on non-uniform instants (docs/irregular_time.md).

    python benchmarks/irregular_convergence.py [--seeds 10]

Each GL-based kind is simulated with fohw.model.irregular.simulate_at on irregular instants
(60 steps uniform in [0.05, 0.15] s) for a random held input, at refine = 2 ... 256, and compared
with the closed form (tests/irregular_reference.py): the error is the largest |error| over the
instants; the order is log2 of the ratio of successive
errors. The spread of the order between refine 16 and 128 over several instant sets and inputs
is printed last (the test's tolerance comes from it).
"""

import argparse
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "src"))
sys.path.insert(0, str(ROOT / "tests"))
from irregular_reference import (  # noqa: E402
    foh_response,
    half_ramp,
    half_step,
    instants,
    ml_step,
    zoh_response,
)

import fohw  # noqa: E402
from fohw.model.irregular import simulate_at  # noqa: E402

TAU = 0.5
REFINES = [2, 4, 8, 16, 32, 64, 128, 256]


def cases(seed):
    """(name, model, u, t, intersample, exact output at t)."""
    t = instants(60, seed)
    rng = np.random.default_rng(100 + seed)
    u = rng.standard_normal(t.size)
    S = lambda x: half_step(x, TAU)          # noqa: E731
    Q = lambda x: half_ramp(x, TAU)          # noqa: E731
    tf = fohw.FractionalTF([1.0], [0.0], [TAU ** 0.5, 1.0], [0.5, 0.0], dt=0.1)
    out = [("FractionalTF 1/((0.5 s)^0.5 + 1), zoh", tf, u, t, "zoh", zoh_response(t, u, S)),
           ("FractionalTF 1/((0.5 s)^0.5 + 1), foh", tf, u, t, "foh", foh_response(t, u, S, Q))]
    tf7 = fohw.FractionalTF([1.0], [0.0], [TAU ** 0.7, 1.0], [0.7, 0.0], dt=0.1)
    out.append(("FractionalTF 1/((0.5 s)^0.7 + 1), zoh", tf7, u, t, "zoh",
                zoh_response(t, u, ml_step(0.7, TAU))))
    hw = fohw.FractionalHW(tf, p=[1.0, 0.3], f_basis=2, output_map=2, output_params=[-0.2])
    w = u + 0.3 * u ** 2
    x = zoh_response(t, w, S)
    out.append(("FractionalHW u+0.3u² → G → x−0.2x², zoh", hw, u, t, "zoh", x - 0.2 * x ** 2))
    i = 2.0 * u
    soc = np.full(t.size, 0.5)
    cell = fohw.EquivalentCircuit([fohw.ZARC(0.01, TAU, 0.5), fohw.RC(0.005, 0.3)], r0=0.015,
                                  a=3.7, dt=0.1, tau_bounds=(0.01, 100.0))
    static = 3.7 + 0.015 * i
    from irregular_reference import rc_ramp, rc_step
    for hold, resp in (("zoh", lambda s, q: zoh_response(t, i, s)),
                       ("foh", lambda s, q: foh_response(t, i, s, q))):
        exact = static + 0.01 * resp(S, Q) + resp(rc_step(0.005, 0.3), rc_ramp(0.005, 0.3))
        out.append((f"EquivalentCircuit ZARC + RC + R0, {hold}", cell,
                    np.column_stack([i, soc]), t, hold, exact))
    return out


def table():
    print("| kind, hold | " + " | ".join(f"refine {r}" for r in REFINES) + " | order 16→128 |")
    print("|---|" + "---:|" * (len(REFINES) + 1))
    for name, model, u, t, hold, exact in cases(0):
        errs = [np.max(np.abs(simulate_at(model, u, t, intersample=hold, refine=r)
                              - exact)) for r in REFINES]
        order = np.log2(errs[REFINES.index(16)] / errs[REFINES.index(128)]) / 3
        print(f"| {name} | " + " | ".join(f"{e:.2g}" for e in errs) + f" | {order:.3f} |")
    print()
    print("orders between refine r and 2r (first case):")
    name, model, u, t, hold, exact = cases(0)[0]
    errs = [np.max(np.abs(simulate_at(model, u, t, intersample=hold, refine=r) - exact))
            for r in REFINES]
    print("  ", [f"{np.log2(a / b):.2f}" for a, b in zip(errs, errs[1:])])


def spread(seeds):
    orders = {}
    for seed in range(seeds):
        for name, model, u, t, hold, exact in cases(seed):
            e16, e128 = (np.max(np.abs(simulate_at(model, u, t, intersample=hold, refine=r)
                                       - exact)) for r in (16, 128))
            orders.setdefault(name, []).append(np.log2(e16 / e128) / 3)
    print(f"order 16→128 over {seeds} seeds (instants and inputs): min / mean / max")
    for name, o in orders.items():
        print(f"  {name}: {min(o):.3f} / {np.mean(o):.3f} / {max(o):.3f}")


if __name__ == "__main__":
    parser = argparse.ArgumentParser()
    parser.add_argument("--seeds", type=int, default=10)
    args = parser.parse_args()
    table()
    spread(args.seeds)
