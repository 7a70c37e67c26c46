"""The input side of a real plant on simulated data: direct feedthrough (nk) and several inputs.

The numbers of docs/real_data.md ("The exchanger-style lesson" and "Several inputs"). A plant
with a direct feedthrough term ``b0`` and a fractional order, measured with output noise, is
fitted by ``method="output_error"`` with the paper's input lags (``nk = 1``) and with
``nk = 0``; the structure is also chosen by :func:`fohw.select_structure` on the estimation
record alone; every model is judged by its free run on a separate validation record. Writes
``input_lessons.md`` to ``--outdir``.

    python examples/input_lessons.py --outdir results [--fast]
"""

import argparse
from pathlib import Path

import numpy as np

import fohw


def feedthrough(fast):
    """The exchanger-style lesson: rows of (what, estimation fit, validation fit, RMSE, alpha)."""
    n_est, n_val = (1000, 500) if fast else (2000, 1000)
    model = fohw.HammersteinWiener([0.4, 0.2], [0.3, 0.8], [1.0, 0.3], [1.0], 0.55, nk=0)
    rng = np.random.default_rng(2024)
    u_est, u_val = rng.uniform(-1, 1, n_est), rng.uniform(-1, 1, n_val)
    y_est = fohw.simulate(model, u_est) + 0.05 * rng.standard_normal(n_est)
    y_val = fohw.simulate(model, u_val) + 0.05 * rng.standard_normal(n_val)
    rows = []
    for nk, nb in ((1, 2), (1, 3), (0, 2)):
        r = fohw.identify(u_est, y_est, na=2, nb=nb, nk=nk, f_basis=2, g_basis=1,
                          method="output_error")
        est, val = fohw.compare(r, u_est, y_est), fohw.compare(r, u_val, y_val)
        rows.append((f"nk = {nk}, nb = {nb} ({', '.join(r.parameter_names[2:2 + nb])})",
                     est.fit_simulation, val.fit_simulation, val.rmse_simulation, r.alpha))
    sel = fohw.select_structure(u_est, y_est, {"nk": [0, 1, 2], "nb": [2, 3]}, na=2,
                                f_basis=2, g_basis=1, method="output_error")
    best = sel.best
    val = fohw.compare(best, u_val, y_val)
    rows.append((f"select_structure on the estimation record: nk = {best.nk}, nb = {best.nb}",
                 fohw.compare(best, u_est, y_est).fit_simulation, val.fit_simulation,
                 val.rmse_simulation, best.alpha))
    truth = fohw.compare(model, u_val, y_val)
    rows.append(("the true model (noise floor)", float("nan"), truth.fit_simulation,
                 truth.rmse_simulation, 0.55))
    return rows


def several_inputs(fast):
    """The MISO example: rows of (what, estimation fit, validation fit, RMSE, orders)."""
    n_est, n_val = (1000, 500) if fast else (2000, 1000)
    orders = fohw.Orders([(1, "alpha"), (2, "alpha")],
                         [(0, "alpha", 0), (1, "alpha", 0), (1, "beta", 1), (2, "beta", 1),
                          (3, "beta", 1)], inputs=("heat", "flow"))
    plant = fohw.Structure.make(na=2, nb=[2, 3], nk=[0, 1], f_basis=[2, 1], g_basis=1,
                                orders=orders, inputs=("heat", "flow"))
    true = np.r_[0.5, 0.2, 0.6, 0.3, 0.18, 0.09, -0.5, 0.3, 0.2, 0.45, 0.8]
    rng = np.random.default_rng(7)
    u_est, u_val = rng.uniform(-1, 1, (n_est, 2)), rng.uniform(-1, 1, (n_val, 2))
    y_est = fohw.simulate(plant, u_est, params=true) + 0.05 * rng.standard_normal(n_est)
    y_val = fohw.simulate(plant, u_val, params=true) + 0.05 * rng.standard_normal(n_val)
    kw = dict(na=2, g_basis=1, method="output_error")
    fits = [
        ("heat only (one input, nk = 0, nb = 2)", u_est[:, 0], u_val[:, 0],
         dict(nb=2, nk=0, f_basis=2)),
        ("heat and flow, one shared order", u_est, u_val,
         dict(nb=[2, 3], nk=[0, 1], f_basis=[2, 1], inputs=("heat", "flow"))),
        ("heat and flow, an order per input (the plant's class)", u_est, u_val,
         dict(nb=[2, 3], nk=[0, 1], f_basis=[2, 1], orders=orders,
              alpha_bounds={"alpha": (0.0, 1.0), "beta": (0.0, 1.5)})),
    ]
    rows = []
    for what, ue, uv, extra in fits:
        r = fohw.identify(ue, y_est, **kw, **extra)
        rows.append((what, fohw.compare(r, ue, y_est).fit_simulation,
                     fohw.compare(r, uv, y_val).fit_simulation,
                     fohw.compare(r, uv, y_val).rmse_simulation,
                     ", ".join(f"{k} = {v:.3f}" for k, v in r.orders.items())))
    ysim = fohw.simulate(plant, u_val, params=true)
    rmse = float(np.sqrt(np.mean((y_val - ysim) ** 2)))
    fit = 100 * (1 - np.linalg.norm(y_val - ysim) / np.linalg.norm(y_val - y_val.mean()))
    rows.append(("the true model (noise floor)", float("nan"), fit, rmse,
                 "alpha = 0.450, beta = 0.800"))
    return rows


def table(rows):
    out = ["| model | estimation fit % | validation fit % | validation RMSE | estimated orders |",
           "|---|---:|---:|---:|---:|"]
    for what, fe, fv, rmse, alpha in rows:
        fe_text = "" if np.isnan(fe) else f"{fe:.1f}"
        alpha = alpha if isinstance(alpha, str) else f"{alpha:.3f}"
        out.append(f"| {what} | {fe_text} | {fv:.1f} | {rmse:.4f} | {alpha} |")
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--outdir", type=Path, default=Path("results"))
    ap.add_argument("--fast", action="store_true", help="shorter records")
    args = ap.parse_args(argv)
    args.outdir.mkdir(parents=True, exist_ok=True)
    lines = ["# The input side of a real plant (simulated)", "",
             "## Direct feedthrough", "",
             "Plant: a = (0.4, 0.2), b0 = 0.3, b1 = 0.8 (nk = 0), p = (1, 0.3), q = (1), "
             "alpha = 0.55; output noise of standard deviation 0.05; free-run fits.", ""]
    lines += table(feedthrough(args.fast))
    lines += ["", "## Two inputs", "",
              "Plant: y = 0.5 D^a y(k-1) + 0.2 D^a y(k-2) + D^a fh(heat)(k) terms (b0 = 0.6, "
              "b1 = 0.3, fh(u) = u + 0.3 u^2; nk = 0, order a = 0.45) + D^b flow(k-i) terms "
              "(i = 1, 2, 3: -0.5, 0.3, 0.2; order b = 0.8); output noise 0.05.", ""]
    lines += table(several_inputs(args.fast))
    text = "\n".join(lines) + "\n"
    (args.outdir / "input_lessons.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
