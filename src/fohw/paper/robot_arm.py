"""The paper's real system: the DaISy flexible robot arm (Section 6.2, Figs. 7-9, Table 3), and more.

    fohw reproduce robot-arm --outdir results [--fast] [--data PATH]

The record is read by fohw.datasets.robot_arm (the copy shipped with fohw, or --data).

1. Structure for the equation-error models: the (na, nb, f degree, g degree) with the smallest
   BIC = N ln J + d ln N of the separable least-squares fit over the whole record.
2. The paper's hybrid method with P = 1, 3, 5 (iterative schedule, Steps 1-9): Fig. 7 (J against
   iteration), Fig. 8 (measured and P = 5 one-step output), Fig. 9 (its error).
3. Table 3: one-step error ranges after a start-up window of N_INIT samples, beside the printed
   ranges of [28], [14] and the paper; also fohw's varpro model.
4. Simulation: a linear integer-order output-error baseline and the simulation-focused
   fractional HW model (method="output_error"), each with its structure chosen by the free-run
   fit on samples 384-511 after fitting on 0-383; the chosen structures are refitted on the first
   half (0-511) and scored on the held-back second half (512-1023), which mirrors the first half.
5. The general model's classes of orders (every order 0, commensurate, mixed, per lag), each
   with its order n chosen by fohw.select_structure the same way, refitted and scored alike.
Writes robot_arm.md, figure_7.png, figure_8.png, figure_9.png and robot_arm_simulation.png.
"""

import argparse
import itertools
import sys
import time
from pathlib import Path

import numpy as np

import fohw
from fohw._parallel import progress_bar
from fohw._plotting import subplots
from fohw.analysis.batch import identify_quietly
from fohw.analysis.metrics import bic, cross_correlation_test, error_range, fit_percent, whiteness_test
from fohw.analysis.selection import expand_candidates
from fohw.estimators.baselines import fit_linear_output_error
from fohw.io.files import save_figure
from fohw.paper.common import paper_table2

N_INIT = 20          # start-up samples excluded from every error measure


def cube(x):
    return x**3


def identity(x):
    return x


# The record is antiperiodic: u(k + 512) ~ -u(k) and y(k + 512) ~ -y(k) (data README). A
# system mapping -u to -y is odd, so the nonlinear candidates of section 4 are odd.
ODD = fohw.Basis((identity, cube), names=("x", "x^3"))
LINEAR = fohw.polynomial_basis(1)


def progress(message):
    """Stage messages on stderr when a terminal is attached (the study takes minutes)."""
    progress_bar(None, "robot-arm").write(message)


def bic_scan(u, y, orders, degrees):
    """Varpro fits over (na, nb) x (f degree, g degree), smallest BIC first."""
    rows = []
    n = len(y)
    for na, nb in orders:
        for df, dg in degrees:
            r = identify_quietly(u, y, na=na, nb=nb, f_basis=df, g_basis=dg, method="varpro",
                                 alpha_bounds=(0.0, 2.0))
            d = r.linear.size + r.nonlinear.size
            rows.append(dict(na=na, nb=nb, f=df, g=dg, bic=bic(r.J, n, d), J=r.J, alpha=r.alpha,
                             result=r))
    return sorted(rows, key=lambda r: r["bic"])


def linear_start(layout, lin):
    """Theta of a fractional model that equals the linear OE model B/F when alpha -> 0."""
    theta = np.zeros(layout.n_params)
    theta[:layout.na] = -lin.f
    k = layout.n_output_params
    theta[k:k + layout.nb] = lin.b
    return theta


def fit_fractional_oe(u, y, n, f_basis, g_basis, lin):
    """Output-error fit from the default chain of starts and from the linear OE model at alpha ~ 0.

    The better simulation SSE is kept.
    """
    struct = dict(na=n, nb=n, f_basis=f_basis, g_basis=g_basis, method="output_error",
                  alpha_bounds=(0.0, 2.0), n_init=N_INIT)
    layout = fohw.model.lagged.params.ThetaLayout(na=n, nb=n, n_g=len(fohw.model.basis.as_basis(g_basis)),
                                           n_f=len(fohw.model.basis.as_basis(f_basis)))
    fits = [identify_quietly(u, y, **struct),
            identify_quietly(u, y, start=(linear_start(layout, lin), 1e-3), **struct)]
    return min(fits, key=lambda r: r.details["simulation_sse"])


def sim_fit(simulate, u, y, score):
    """Free-run fit % of ``simulate(u)`` on the samples ``score`` (NaN if it diverged)."""
    try:
        return fit_percent(y[score], simulate(u)[score])
    except fohw.SimulationDivergedError:
        return float("nan")


def show(value):
    """A fit % for a table: one decimal, or "diverged"."""
    return "diverged" if np.isnan(value) else f"{value:.1f}"


#: Legends beside the axes: the records fill them, a legend inside would cover the data.
BESIDE = dict(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)


def save(fig, outdir, name):
    save_figure(fig, outdir / name, dpi=120)


def structure_section(u, y, fast):
    """Section 1: the equation-error structure by BIC. Returns (lines, scan, struct)."""
    if fast:
        orders, degrees = [(2, 2), (4, 4)], [(1, 1)]
    else:
        orders = list(itertools.product(range(1, 7), range(1, 7)))
        degrees = list(itertools.product((1, 2, 3), (1, 2, 3)))
    progress(f"structure scan over {len(orders) * len(degrees)} candidates")
    scan = bic_scan(u, y, orders, degrees)
    best = scan[0]
    struct = dict(na=best["na"], nb=best["nb"], f_basis=best["f"], g_basis=best["g"])
    out = ["## 1. Structure (equation error, BIC over the whole record)", "",
           f"{len(scan)} candidates: na, nb in {sorted({o[0] for o in orders})}, polynomial "
           f"degrees of f and g in {sorted({d[0] for d in degrees})}. Best five:", "",
           "| na | nb | f degree | g degree | BIC | J (Eq. 41) | alpha |",
           "|---:|---:|---:|---:|---:|---:|---:|"]
    out += [f"| {r['na']} | {r['nb']} | {r['f']} | {r['g']} | {r['bic']:.1f} | {r['J']:.3e} | "
            f"{r['alpha']:.3f} |" for r in scan[:5]]
    return out, scan, struct


def plot_figures_7_to_9(outdir, y, hybrid, pred5, pred_vp):
    """Fig. 7 (J per iteration), Fig. 8 (one-step output), Fig. 9 (its error)."""
    fig, ax = subplots(figsize=(7, 4))
    for P, r in hybrid.items():
        ax.plot(np.arange(1, r.nit + 1), r.J_history, marker=".", label=f"P = {P}")
    ax.set_xlabel("iteration m")
    ax.set_ylabel("J (Eq. 41)")
    ax.set_yscale("log")
    ax.set_title("Fig. 7: objective J against iteration, robot arm")
    ax.legend()
    save(fig, outdir, "figure_7.png")

    k = np.arange(len(y))
    fig, ax = subplots(figsize=(9, 4))
    ax.plot(k, y, "k", lw=1, label="measured y")
    ax.plot(k, pred5, "C1--", lw=0.9, label="hybrid P = 5, one-step")
    ax.plot(k, pred_vp, "C0:", lw=0.9, label="varpro, one-step")
    ax.set_xlabel("sample k")
    ax.set_ylabel("arm acceleration")
    ax.set_title("Fig. 8: measured and estimated output (one-step-ahead)")
    ax.legend(**BESIDE)
    save(fig, outdir, "figure_8.png")
    fig, ax = subplots(figsize=(9, 3.5))
    ax.plot(k, y - pred5, "C1", lw=0.8, label="hybrid P = 5")
    ax.plot(k, y - pred_vp, "C0", lw=0.8, label="varpro")
    ax.axvspan(0, N_INIT, color="0.9", label=f"start-up (first {N_INIT} samples)")
    for level in (-0.1, 0.1):
        ax.axhline(level, color="k", ls=":", lw=0.8)
    ax.set_xlabel("sample k")
    ax.set_ylabel("one-step error")
    ax.set_title("Fig. 9: estimation error (dotted: the paper's range [-0.1, 0.1])")
    ax.legend(**BESIDE)
    save(fig, outdir, "figure_9.png")


def hybrid_section(u, y, best, struct, max_iter, outdir):
    """Sections 2-3: the paper's hybrid, P = 1, 3, 5, Figs. 7-9 and Table 3. Returns lines."""
    progress("the paper's hybrid, P = 1, 3, 5")
    hybrid = {P: identify_quietly(u, y, method="hybrid", innovation_length=P,
                                  schedule="iterative", max_iter=max_iter, **struct)
              for P in (1, 3, 5)}
    varpro = best["result"]
    pred_vp = varpro.predict(u, y)
    plot_figures_7_to_9(outdir, y, hybrid, hybrid[5].predict(u, y), pred_vp)
    n = len(y)
    printed = paper_table2()["table3_error_range_robot_arm"]
    out = ["", f"## 2-3. The paper's hybrid method and Table 3 (structure na = {best['na']}, "
           f"nb = {best['nb']}, f degree {best['f']}, g degree {best['g']})", "",
           f"One-step error ranges over samples {N_INIT}..{n - 1} (the first {N_INIT} samples are "
           "the start-up transient of the zero-initial-condition model and are excluded). "
           f"Hybrid: iterative schedule (Steps 1-9), alpha0 = 0.5, max_iter = {max_iter}.", "",
           "| method | error range | J (Eq. 41) | alpha | iterations | status |",
           "|---|---|---:|---:|---:|---|"]
    for name, rng in printed.items():
        out.append(f"| {name} (printed) | [{rng[0]}, {rng[1]}] | | | | |")
    for P, r in hybrid.items():
        lo, hi = error_range(y, r.predict(u, y), n_init=N_INIT)
        out.append(f"| fohw: paper's hybrid, P = {P} | [{lo:.3f}, {hi:.3f}] | {r.J:.3e} | "
                   f"{r.alpha:.3f} | {r.nit} | {r.status.name} |")
    lo, hi = error_range(y, pred_vp, n_init=N_INIT)
    out.append(f"| fohw: varpro | [{lo:.3f}, {hi:.3f}] | {varpro.J:.3e} | {varpro.alpha:.3f} | "
               f"{varpro.nit} | {varpro.status.name} |")
    white = whiteness_test(y - pred_vp, n_init=N_INIT)
    xcorr = cross_correlation_test(y - pred_vp, u, n_init=N_INIT)
    out += ["", f"varpro residual tests (99 %, 25 lags): whiteness p = {white.p_value:.3g} "
            f"({white.n_outside} lags outside ±{white.bound:.3f}); input cross-correlation "
            f"p = {xcorr.p_value:.3g} ({xcorr.n_outside} of {len(xcorr.lags)} lags outside)."]
    return out


def select_simulation_structures(u, y, fast):
    """Every linear and fractional output-error candidate fitted on 0-383, scored on 384-511."""
    est_sel, sel = slice(0, 384), slice(384, 512)
    lin_orders = [2, 4] if fast else list(range(1, 9))
    frac_cands = ([(4, LINEAR, LINEAR)] if fast else
                  [(m, fb, gb) for m in (3, 4, 5, 6)
                   for fb, gb in ((LINEAR, LINEAR), (LINEAR, ODD), (ODD, LINEAR))])
    rows = []
    progress(f"structure selection: {len(lin_orders)} linear and {len(frac_cands)} fractional "
             "output-error candidates")
    for m in lin_orders:
        lin = fit_linear_output_error(u[est_sel], y[est_sel], nb=m, nf=m, n_init=N_INIT)
        rows.append(dict(kind="linear OE", desc=f"nb = nf = {m}", m=m, d=lin.n_params,
                         fit=sim_fit(lin.simulate, u[:512], y[:512], sel)))
    for m, fb, gb in frac_cands:
        lin = fit_linear_output_error(u[est_sel], y[est_sel], nb=m, nf=m, n_init=N_INIT)
        r = fit_fractional_oe(u[est_sel], y[est_sel], m, fb, gb, lin)
        rows.append(dict(kind="fractional HW OE", desc=f"na = nb = {m}, f = {fb.names}, "
                         f"g = {gb.names}", m=m, fb=fb, gb=gb, d=r.theta.size + 1,
                         fit=sim_fit(r.simulate, u[:512], y[:512], sel)))
    return rows


def simulation_section(u, y, struct, max_iter, fast):
    """Section 4: free-run simulation of the chosen structures. Returns (lines, lin_final, frac_final)."""
    n = len(y)
    first, second = slice(0, 512), slice(512, n)
    sel_rows = select_simulation_structures(u, y, fast)
    progress("refitting the chosen structures and the equal-order comparison")
    chosen = {}
    for kind in ("linear OE", "fractional HW OE"):
        cands = [r for r in sel_rows if r["kind"] == kind and np.isfinite(r["fit"])]
        chosen[kind] = max(cands, key=lambda r: r["fit"])
    lin_c = chosen["linear OE"]
    lin_final = fit_linear_output_error(u[first], y[first], nb=lin_c["m"], nf=lin_c["m"],
                                        n_init=N_INIT)
    fr_c = chosen["fractional HW OE"]
    lin_same = fit_linear_output_error(u[first], y[first], nb=fr_c["m"], nf=fr_c["m"],
                                       n_init=N_INIT)
    frac_final = fit_fractional_oe(u[first], y[first], fr_c["m"], fr_c["fb"], fr_c["gb"], lin_same)
    eq_first = identify_quietly(u[first], y[first], method="varpro", alpha_bounds=(0.0, 2.0),
                                **struct)
    hyb_first = identify_quietly(u[first], y[first], method="hybrid", innovation_length=5,
                                 schedule="iterative", max_iter=max_iter, **struct)
    models = [("linear OE (integer order), " + lin_c["desc"], lin_final.n_params,
               lin_final.simulate),
              ("linear OE, same order as the fractional model (nb = nf = "
               f"{fr_c['m']})", lin_same.n_params, lin_same.simulate),
              ("fractional HW, simulation-focused (output_error), " + fr_c["desc"],
               frac_final.theta.size + 1, frac_final.simulate),
              ("fractional HW, equation error (varpro), BIC structure", eq_first.theta.size + 1,
               eq_first.simulate),
              ("fractional HW, paper's hybrid P = 5, BIC structure", hyb_first.theta.size + 1,
               hyb_first.simulate)]
    out = ["", "## 4. Free-run simulation", "",
           "Structure selection: every candidate fitted on samples 0-383 and scored by its "
           "free-run fit % on samples 384-511, the end of the first sweep period, which the "
           "fit did not see. Candidates:", "", "| model class | structure | parameters | "
           "selection fit % (384-511) |", "|---|---|---:|---:|"]
    out += [f"| {r['kind']} | {r['desc']} | {r['d']} | {r['fit']:.1f} |" for r in sel_rows]
    out += ["", "The chosen structures refitted on the first half (0-511); fit % = "
            "100 (1 - ||y - ysim|| / ||y - mean y||), free run from k = 0, the first "
            f"{N_INIT} samples excluded from the first-half score. The second half is held back, "
            "but it is almost the mirror image of the first (correlation -0.998 for y), so it "
            "mostly checks that the model is odd-symmetric and stable, not that it generalises.",
            "", "| model | parameters | fit % first half (estimation) | fit % second half "
            "(held back) |", "|---|---:|---:|---:|"]
    fits = []
    for name, d, simf in models:
        f1 = sim_fit(simf, u, y, slice(N_INIT, 512))
        f2 = sim_fit(simf, u, y, second)
        fits.append((f1, f2))
        out.append(f"| {name} | {d} | {show(f1)} | {show(f2)} |")
    for i, label in ((0, "the selected linear OE baseline"), (1, "the linear OE of the same order")):
        out.append(f"\nSimulation-focused fractional HW minus {label}: "
                   f"{fits[2][0] - fits[i][0]:+.1f} points on the first half, "
                   f"{fits[2][1] - fits[i][1]:+.1f} on the held-back half.")
    out.append(f"\nThe simulation-focused model's alpha = {frac_final.alpha:.4f}; "
               f"{frac_final.message}")
    return out, lin_final, frac_final


def equal_order_section(u, y, fast):
    """Equal orders: the gain of a fractional order (and an odd g) over the linear OE model.

    Each order n: the linear OE model and two fractional ones with the same lags, all fitted
    on the first half. Returns lines.
    """
    first, second = slice(0, 512), slice(512, len(y))
    out = ["", "### Equal orders", "",
           "Each row fitted on the first half; fractional models started from the linear OE "
           "model of the same order (at alpha = 0.001) and from output_error's default chain "
           "of starts (nested integer model, varpro, a scan of the order), the better kept.", "",
           "| order n = na = nb | model | parameters | alpha | fit % first half | fit % "
           "held-back half | gain over linear OE (first / held back) |",
           "|---:|---|---:|---:|---:|---:|---|"]
    for m in ([4] if fast else [3, 4, 5, 6]):
        lin = fit_linear_output_error(u[first], y[first], nb=m, nf=m, n_init=N_INIT)
        base = (sim_fit(lin.simulate, u, y, slice(N_INIT, 512)), sim_fit(lin.simulate, u, y, second))
        out.append(f"| {m} | linear OE | {lin.n_params} | – | {base[0]:.1f} | {base[1]:.1f} | |")
        for label, fb, gb in (("fractional, f = g = identity", LINEAR, LINEAR),
                              ("fractional HW, g = [y, y^3]", LINEAR, ODD)):
            r = fit_fractional_oe(u[first], y[first], m, fb, gb, lin)
            f1 = sim_fit(r.simulate, u, y, slice(N_INIT, 512))
            f2 = sim_fit(r.simulate, u, y, second)
            out.append(f"| {m} | {label} | {r.theta.size + 1} | {r.alpha:.3f} | {show(f1)} | "
                       f"{show(f2)} | {f1 - base[0]:+.1f} / {f2 - base[1]:+.1f} |")
    return out


ORDER_CLASSES = {0: "every order 0", "commensurate": "commensurate (Eq. 16)",
                 "mixed": "mixed (order 0 and alpha at every lag)", "per_lag": "per lag (Eq. 14)"}


def order_classes_section(u, y, fast):
    """Section 5: the general model's classes of orders (an order per term, order 0 included).

    Each class with its structure chosen by fohw.select_structure. Returns lines.
    """
    first, second = slice(0, 512), slice(512, len(y))
    progress("classes of orders: select_structure")
    grid = ({"orders": [0, "mixed"], "na": [4]} if fast else
            {"orders": list(ORDER_CLASSES), "na": [3, 4, 5, 6]})
    grid = [dict(c, nb=c["na"]) for c in expand_candidates(grid)]
    choice = fohw.select_structure(u[first], y[first], grid, validation=128, refit=False,
                                   method="output_error", f_basis=LINEAR, g_basis=LINEAR,
                                   n_init=N_INIT)
    out = ["", "## 5. Classes of orders (the general model, Eqs. 7 and 14)", "",
           "`fohw.select_structure` over na = nb and the class of orders, f = g = identity, "
           "`method=\"output_error\"` with its default start: each candidate fitted on samples "
           "0-383 and scored by the free-run fit on 384-511. The best of each class refitted "
           "on the first half (0-511) and simulated over the whole record.", "",
           "| class of orders | chosen n = na = nb | estimated orders | selection fit % "
           "(384-511) | fit % first half | fit % held-back half |",
           "|---|---:|---|---:|---:|---:|"]
    for cls, row in choice.best_by("orders").items():
        r = identify_quietly(u[first], y[first], na=row["na"], nb=row["nb"],
                             f_basis=LINEAR, g_basis=LINEAR, orders=cls, method="output_error",
                             n_init=N_INIT)
        f1 = sim_fit(r.simulate, u, y, slice(N_INIT, 512))
        f2 = sim_fit(r.simulate, u, y, second)
        est = ", ".join(f"{k} = {v:.3f}" for k, v in (r.orders or {}).items()) or "-"
        out.append(f"| {ORDER_CLASSES[cls]} | {row['na']} | {est} | {row['fit']:.1f} | "
                   f"{show(f1)} | {show(f2)} |")
    failed = [f"{r['candidate']} ({r['status']})" for r in choice.rows if r["status"] != "ok"]
    out.append(f"\n{len(choice.rows)} candidates in {choice.seconds:.0f} s; failed: "
               + (", ".join(failed) or "none") + ".")
    return out


def plot_simulation(outdir, u, y, lin_final, frac_final):
    """The held-back second half: measured, linear OE and fractional HW free runs, and errors."""
    n = len(y)
    second = slice(512, n)
    fig, axes = subplots(2, 1, figsize=(9, 5.5), sharex=True)
    kk = np.arange(512, n)
    axes[0].plot(kk, y[second], "k", lw=1, label="measured")
    axes[0].plot(kk, lin_final.simulate(u)[second], "C2", lw=0.9, label="linear OE")
    axes[0].plot(kk, frac_final.simulate(u)[second], "C0--", lw=0.9,
                 label="fractional HW, output_error")
    axes[0].set_ylabel("y")
    axes[0].legend(**BESIDE)
    axes[0].set_title("Free-run simulation on the held-back second half")
    axes[1].plot(kk, y[second] - lin_final.simulate(u)[second], "C2", lw=0.8, label="linear OE")
    axes[1].plot(kk, y[second] - frac_final.simulate(u)[second], "C0", lw=0.8,
                 label="fractional HW")
    axes[1].set_xlabel("sample k")
    axes[1].set_ylabel("simulation error")
    axes[1].legend(**BESIDE)
    save(fig, outdir, "robot_arm_simulation.png")


def main(argv=None):
    """Command line of ``fohw reproduce robot-arm`` and ``examples/robot_arm.py``."""
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--outdir", type=Path, default=Path("results"))
    ap.add_argument("--fast", action="store_true", help="small structure grids, fewer iterations")
    ap.add_argument("--data", default=None, help="the DaISy file or its folder "
                    "(default: the copy shipped with fohw)")
    args = ap.parse_args(argv)
    t0 = time.perf_counter()
    data = fohw.datasets.robot_arm(args.data)
    u, y = data.u, data.y
    args.outdir.mkdir(parents=True, exist_ok=True)
    out = [f"# The flexible robot arm (DaISy 96-009), N = {data.n_samples}", ""]
    lines, scan, struct = structure_section(u, y, args.fast)
    out += lines
    max_iter = 5 if args.fast else 50
    out += hybrid_section(u, y, scan[0], struct, max_iter, args.outdir)
    lines, lin_final, frac_final = simulation_section(u, y, struct, max_iter, args.fast)
    out += lines
    out += equal_order_section(u, y, args.fast)
    out += order_classes_section(u, y, args.fast)
    plot_simulation(args.outdir, u, y, lin_final, frac_final)
    out += ["", f"Total time {time.perf_counter() - t0:.0f} s."]
    text = "\n".join(out) + "\n"
    (args.outdir / "robot_arm.md").write_text(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
