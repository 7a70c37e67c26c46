"""A lithium-ion cell's drive cycle: fractional against integer equivalent circuits, checked by impedance.

    python examples/battery.py --outdir results [--fast]

The LG M50LT record of Hallemans et al. (arXiv:2412.10896; PyBOP, BSD-3-Clause) ships with fohw
(fohw.datasets.battery_cell()): a drive cycle from SOC 0.80 to 0.20, the OCV from the electrode
potentials, and impedance spectra measured separately on the same cell.

1. Decimation: block means of 10 samples (h = 1.5 s; --fast: 40, h = 6 s). The series
   resistance R0 takes up everything faster than a few seconds; the impedance between 0.1 and
   1 Hz is nearly real and flat (R0-like), so 1.5 s keeps the band the elements live in
   (1e-3 to 0.33 Hz) with 10 times fewer samples than 0.15 s.
2. Split: estimation = first half (SOC 0.80 -> 0.50), validation = second half (0.50 -> 0.20).
   The validation is a free run of the whole record from t = 0 (only the current, the known
   initial SOC, elements at rest), scored on the second half.
3. Every bound and structure is chosen on the estimation half only: each circuit is fitted on
   70 % of it with every candidate upper bound of the time constants, scored by free run on the
   other 30 % (--holdout end: its last 30 %, default; middle: its middle 30 %, the fit's criterion
   skipping it while the simulation runs through); the bound with the smallest held-back error
   is kept (errors within 1e-6 relative are a tie, which goes to the smallest bound: bounds no
   fit reaches differ only by where each search stopped), the circuit refitted on the whole
   estimation half and validated once.
4. The fractional element's order: profile interval and LR test against its integer limit
   (alpha = 1, the RC element), with the nominal n and with Bartlett's effective n of the
   correlated residuals.
5. Impedance: the identified circuits' Z(j omega) (with the OCV's capacitor) beside the measured
   spectra at SOC 0.4, 0.5 and 0.6, in the band 1e-3 to 0.33 Hz.

Writes battery.md, battery_structures.csv, battery_bounds.csv, battery_impedance.csv, battery_fit.png,
battery_nyquist.png and battery_profile.png to --outdir.
"""

import argparse
import csv
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import fohw  # noqa: E402
from fohw.analysis.circuit_checks import (  # noqa: E402
    circuit_lr_test,
    circuit_order_interval,
    effective_samples,
    impedance_error,
)

STRUCTURES = [((), False), (("rc",), False), (("rc", "rc"), False), (("rc", "rc", "rc"), False),
              (("zarc",), False), (("rc", "zarc"), False), (("zarc", "zarc"), False),
              ((), True), (("rc",), True), (("rc", "rc"), True), (("rc", "rc", "rc"), True),
              (("zarc",), True), (("rc", "zarc"), True), (("zarc", "zarc"), True),
              (("warburg",), False), (("zarc", "warburg"), False)]
FAST_STRUCTURES = [((), False), (("rc",), False), (("rc", "rc"), False), (("zarc",), False),
                   (("zarc",), True)]
TAU_MAX = (250.0, 500.0, 1000.0, 2000.0, 5000.0, 20000.0)
FAST_TAU_MAX = (500.0, 2000.0)
BAND = (1e-3, 0.33)
TIE = 1e-6          # held-back errors within this relative distance are a tie (see choose_and_fit)
IMPEDANCE_SOC = (0.4, 0.5, 0.6)


def label(elements, cubic):
    text = " + ".join(e.upper() for e in elements) if elements else "R0 only"
    return text + (" + c3 i^3" if cubic else "")


def is_fractional(elements):
    return any(e in ("zarc", "warburg") for e in elements)


def inputs(cell, part=slice(None)):
    """The circuit's input ``u = [current, state of charge]`` of a part of the record."""
    return np.column_stack([cell.i[part], cell.soc[part]])


def fit_circuit(cell, part, elements, cubic, tau_max, fit_kw, sample_weight=None, held=None):
    """``fohw.fit`` of a circuit (time constants in [h, tau_max]) on ``cell[part]``, and its time.

    ``held``: parameters fixed at given values. The circuit's own scan (``EquivalentCircuit.starts``)
    covers the orders, so the generic order grid of ``fohw.fit`` is off (``order_grid=1``).
    """
    model = fohw.EquivalentCircuit(elements, c3=0.0 if cubic else None, ocv=cell.ocv, dt=cell.dt,
                                   tau_bounds=(cell.dt, tau_max), **fit_kw["model"])
    params = model.parameters
    for name, value in (held or {}).items():
        params = params.replace(name, value=value, fixed=True)
    t0 = time.perf_counter()
    fit = fohw.fit(model.with_parameters(params), inputs(cell, part), cell.v[part],
                   sample_weight=sample_weight, order_grid=1, **fit_kw["fit"])
    return fit, time.perf_counter() - t0


def at_bound(fit):
    """Free parameters that ended on (within 1e-6 relative of) a bound."""
    out = []
    for name in fit.free_names:
        x, (lo, hi) = fit.parameters[name].value, fit.parameters[name].bounds
        if (np.isfinite(lo) and x <= lo * (1 + 1e-6) + 1e-12) or (np.isfinite(hi) and x >= hi * (1 - 1e-6)):
            out.append(name)
    return tuple(out)


def se_held_at_bounds(fit, u, name):
    """Standard error of ``name`` with the parameters that ended on a bound held there.

    ``fit.standard_errors()`` counts every free parameter, also one on a bound; holding those
    (as the profile interval does, whose refits keep them there) gives the narrower figure the
    circuit's former fitter reported.
    """
    names = list(fit.parameters)
    keep = [n for n in fit.free_names if n not in at_bound(fit)]
    _, jac = fit.model.jacobian(u)
    j = jac[:, [names.index(n) for n in keep]]
    scale = np.sqrt(np.sum(j ** 2, axis=0))
    cov = np.linalg.pinv((j / scale).T @ (j / scale)) / np.outer(scale, scale)
    return float(np.sqrt(fit.sse / (fit.n_samples - fit.n_free) * cov[keep.index(name), keep.index(name)]))


def free_run_error(fit, cell, part):
    """Free run of the record from t = 0, errors on the samples of ``part`` (a slice)."""
    v = fit.simulate(inputs(cell, slice(0, part.stop)))
    return v[part] - cell.v[part]


def rms(e):
    return float(np.sqrt(np.mean(e ** 2)))


def choose_and_fit(cell, est, elements, cubic, tau_max, fit_kw, holdout):
    """The bound chosen on the estimation half's held-back 30 %, then the refit on the whole half.

    ``holdout="end"``: fit on the first 70 %, score the last 30 % (extrapolates in SOC).
    ``holdout="middle"``: fit on the first 35 % and the last 35 % (weight 0 between them, the
    free run going through), score the middle 30 % (interpolates in SOC).
    """
    length = est.stop - est.start
    if holdout == "end":
        held = slice(est.start + int(0.7 * length), est.stop)
    else:
        held = slice(est.start + int(0.35 * length), est.start + int(0.65 * length))
    weight = np.ones(length)
    weight[held.start - est.start:held.stop - est.start] = 0.0
    scores = {}
    candidates = tau_max if set(elements) - {"warburg"} else tau_max[:1]
    for t in candidates:
        fit, _ = fit_circuit(cell, est, elements, cubic, t, fit_kw, sample_weight=weight)
        scores[t] = rms(free_run_error(fit, cell, held))
    # Bounds that no fit reaches give the same minimum: their held-back errors then differ only
    # by where each search stopped (measured: 1.5e-7 relative), so a tie within TIE goes to the
    # smallest bound, not to the last digits.
    low = min(scores.values())
    best = min(t for t in scores if scores[t] <= low * (1 + TIE))
    fit, seconds = fit_circuit(cell, est, elements, cubic, best, fit_kw)
    return fit, best, scores, seconds


def goal_alpha(alpha, interval):
    """The goal for the order: inside (0.3, 0.7), its interval off the bounds 0.05 and 1."""
    return "met" if 0.3 < alpha < 0.7 and interval.low > 0.05 and interval.high < 1 else "not met"


def ocv_slope(cell, soc, step=0.01):
    """dOCV/dsoc by a central difference over +-1 % SOC (the OCV is a tabulated interpolant)."""
    return (cell.ocv(soc + step) - cell.ocv(soc - step)) / (2 * step)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--outdir", type=Path, default=Path("results"))
    parser.add_argument("--fast", action="store_true", help="a coarse run for the test suite")
    parser.add_argument("--holdout", choices=("end", "middle"), default="end",
                        help="held-back 30 %% of the estimation half: its end or its middle")
    args = parser.parse_args(argv)
    args.outdir.mkdir(parents=True, exist_ok=True)
    t_start = time.perf_counter()

    factor = 40 if args.fast else 10
    cell = fohw.datasets.battery_cell().decimate(factor)
    n = cell.n_samples
    est, val = slice(0, n // 2), slice(n // 2, n)
    structures = FAST_STRUCTURES if args.fast else STRUCTURES
    tau_max = FAST_TAU_MAX if args.fast else TAU_MAX
    fit_kw = ({"model": dict(n_tau=5, n_alpha=3), "fit": dict(n_starts=1)} if args.fast else
              {"model": {}, "fit": {}})

    rows, fits = [], {}
    for elements, cubic in structures:
        fit, bound, scores, seconds = choose_and_fit(cell, est, elements, cubic, tau_max, fit_kw,
                                                     args.holdout)
        e_val = free_run_error(fit, cell, val)
        fits[(elements, cubic)] = fit
        alpha = [f"{fit.parameters[nm].value:.3f}" for nm in fit.parameters if nm.startswith("alpha")]
        rows.append(dict(structure=label(elements, cubic), n_params=fit.n_free,
                         tau_max=bound if set(elements) - {"warburg"} else "",
                         fractional=is_fractional(elements),
                         held_back_mV=1e3 * scores[bound], est_mV=1e3 * fit.rmse,
                         val_mV=1e3 * rms(e_val), val_max_mV=1e3 * float(np.max(np.abs(e_val))),
                         alpha=" ".join(alpha), at_bound=" ".join(at_bound(fit)),
                         fit_s=seconds,
                         **{f"held_back_mV_tau{t:g}": 1e3 * scores[t] if t in scores else ""
                            for t in tau_max}))
        print(f"{rows[-1]['structure']:>24}: d = {fit.n_free}, tau_max = {bound:g}, est "
              f"{rows[-1]['est_mV']:.2f} val {rows[-1]['val_mV']:.2f} mV, alpha {alpha}", flush=True)

    # Every circuit at the same bound (no selection): which circuit is better at a given bound?
    same = [k for k in structures if not k[1] and "warburg" not in k[0] and len(k[0]) <= 3
            and k[0] != () and k[0] not in (("rc", "zarc"), ("zarc", "zarc"))]
    bound_rows = []
    for elements, cubic in same:
        for t in tau_max:
            fit, _ = fit_circuit(cell, est, elements, cubic, t, fit_kw)
            alpha = fit.parameters["alpha1"].value if "alpha1" in fit.parameters else float("nan")
            bound_rows.append(dict(structure=label(elements, cubic), tau_max=t,
                                   est_mV=1e3 * fit.rmse,
                                   val_mV=1e3 * rms(free_run_error(fit, cell, val)), alpha=alpha))
    with open(args.outdir / "battery_bounds.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(bound_rows[0]))
        w.writeheader()
        for r in bound_rows:
            w.writerow({k: (f"{v:.4f}" if isinstance(v, float) else v) for k, v in r.items()})

    with open(args.outdir / "battery_structures.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        for r in rows:
            w.writerow({k: (f"{v:.4f}" if isinstance(v, float) else v) for k, v in r.items()})

    # The fractional circuit and its integer competitors.
    key_frac = (("zarc",), False)
    frac = fits[key_frac]
    frac_row = rows[structures.index(key_frac)]
    competitors = [r for r in rows if not r["fractional"] and r["n_params"] >= frac.n_free]
    best_int = min(competitors, key=lambda r: r["val_mV"])
    best_int_held = min(competitors, key=lambda r: r["held_back_mV"])
    gain = 1 - frac_row["val_mV"] / best_int["val_mV"]

    # The order: LR test and profile interval, nominal n and effective n.
    u_e, v_e = inputs(cell, est), cell.v[est]
    restricted, _ = fit_circuit(cell, est, ("zarc",), False, frac_row["tau_max"], fit_kw,
                                held={"alpha1": 1.0})
    n_eff = effective_samples(frac.residuals)
    lr_nominal = circuit_lr_test(restricted, frac)
    lr_eff = circuit_lr_test(restricted, frac, n=n_eff)
    n_grid = 3 if args.fast else 9
    prof = circuit_order_interval(frac, u_e, v_e, "alpha1", n_grid=n_grid)
    prof_eff = circuit_order_interval(frac, u_e, v_e, "alpha1", n=n_eff, n_grid=n_grid)

    # Impedance against the measured spectra.
    integer_key = next(k for k in fits if label(*k) == best_int["structure"])
    compared = {"1 ZARC (fractional)": frac, f"{best_int['structure']} (integer)": fits[integer_key]}
    for key, name in (((("rc", "rc"), False), "2 RC (integer)"),
                      ((("rc", "rc", "rc"), False), "3 RC (integer)"),
                      ((("warburg",), False), "1 Warburg (fractional)")):
        if key in fits and key != integer_key:
            compared[name] = fits[key]
    plotted = list(compared)[:2] + [k for k in compared if "Warburg" in k]
    imp_rows = []
    fig, axes = plt.subplots(1, len(IMPEDANCE_SOC), figsize=(15, 4.6))
    for ax, soc in zip(axes, IMPEDANCE_SOC):
        col = int(np.argmin(np.abs(cell.impedance_soc - soc)))
        z = cell.impedance[:, col]
        f = cell.impedance_f
        inband = (f >= BAND[0]) & (f <= BAND[1])
        ax.plot(1e3 * z.real[inband], -1e3 * z.imag[inband], "ko", ms=4, label="measured")
        ax.plot(1e3 * z.real, -1e3 * z.imag, "k:", lw=0.8, label="measured, 4e-4 to 1000 Hz")
        slope = ocv_slope(cell, soc)
        styles = iter(("C0-", "C3--", "C2-."))
        for name, fit in compared.items():
            _, zm, rel = impedance_error(fit.model, f, z, BAND, capacity=cell.capacity,
                                         ocv_slope=slope)
            imp_rows.append(dict(soc=soc, model=name, rms_rel_error=rms(rel),
                                 max_rel_error=float(rel.max()), n_freq=int(rel.size)))
            if name in plotted:
                ax.plot(1e3 * zm.real, -1e3 * zm.imag, next(styles),
                        label=f"{name}: {100 * rms(rel):.1f} %")
        ax.set_title(f"SOC {soc:g}: {BAND[0]:g} to {BAND[1]:g} Hz")
        ax.set_xlabel("Re Z (mOhm)")
        ax.set_ylabel("-Im Z (mOhm)")
        ax.set_aspect("equal", adjustable="datalim")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(args.outdir / "battery_nyquist.png", dpi=110)
    plt.close(fig)
    with open(args.outdir / "battery_impedance.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(imp_rows[0]))
        w.writeheader()
        for r in imp_rows:
            w.writerow({k: (f"{v:.5f}" if isinstance(v, float) else v) for k, v in r.items()})

    # Figures: the record and the errors; the profile.
    t_h = cell.t / 3600
    fig, axes = plt.subplots(3, 1, figsize=(11, 8), sharex=True)
    axes[0].plot(t_h, cell.i, lw=0.4)
    axes[0].set_ylabel("current (A)")
    axes[1].plot(t_h, cell.v, "k", lw=0.5, label="measured")
    axes[1].plot(t_h, cell.ocv(cell.soc), "C1", lw=0.8, label="OCV(SOC)")
    axes[1].set_ylabel("voltage (V)")
    axes[1].legend(fontsize=8)
    for name, color in zip(plotted, ("C0", "C3", "C2")):
        fit = compared[name]
        e = fit.simulate(inputs(cell)) - cell.v
        axes[2].plot(t_h, 1e3 * e, color=color, lw=0.5, label=name)
    axes[2].axvline(t_h[val.start], color="k", lw=0.8)
    axes[2].set_ylabel("free-run error (mV)")
    axes[2].set_xlabel("time (h); estimation left of the line, validation right")
    axes[2].legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(args.outdir / "battery_fit.png", dpi=110)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(6, 4))
    ax.semilogy(prof.grid, np.maximum(prof.statistic, 1e-3), "o-", label=f"n = {frac.n_samples}")
    ax.semilogy(prof_eff.grid, np.maximum(prof_eff.statistic, 1e-3), "s-",
                label=f"effective n = {n_eff:.0f}")
    ax.axhline(3.84, color="k", lw=0.8, ls="--")
    ax.set_xlabel("alpha1 (ZARC order)")
    ax.set_ylabel("n log(RSS(alpha) / RSS_min)")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(args.outdir / "battery_profile.png", dpi=110)
    plt.close(fig)

    # The report.
    md = [f"# LG M50LT drive cycle: fractional against integer equivalent circuits"
          f"{' (fast mode)' if args.fast else ''}", "",
          f"Block means of {factor} samples: h = {cell.dt:g} s, {n} samples; estimation "
          f"{est.stop} samples (SOC {cell.soc[0]:.2f} -> {cell.soc[est.stop - 1]:.2f}), validation "
          f"{n - est.stop} (-> {cell.soc[-1]:.2f}). Upper bound of the time constants chosen per "
          f"circuit from {', '.join(f'{t:g}' for t in tau_max)} s on the estimation half's "
          f"{'last' if args.holdout == 'end' else 'middle'} 30 %. "
          "Validation: free run of the record from t = 0, RMSE and max error on the second half.",
          "", "| circuit | parameters | tau max (s) | held back (mV) | estimation (mV) | "
          "validation RMSE (mV) | validation max (mV) | alpha | at bound | fit (s) |",
          "|---|---:|---:|---:|---:|---:|---:|---|---|---:|"]
    for r in rows:
        md.append(f"| {r['structure']} | {r['n_params']} | {r['tau_max']} | {r['held_back_mV']:.2f} | "
                  f"{r['est_mV']:.2f} | {r['val_mV']:.2f} | {r['val_max_mV']:.1f} | {r['alpha']} | "
                  f"{r['at_bound']} | {r['fit_s']:.1f} |")
    md += ["", f"Held-back RMSE (mV, {args.holdout} 30 % of the estimation half, free run) by the "
           "upper bound of "
           "the time constants; the smallest is chosen:", "",
           "| circuit | " + " | ".join(f"{t:g} s" for t in tau_max) + " |",
           "|---|" + "---:|" * len(tau_max)]
    for r in rows:
        cells = [r[f"held_back_mV_tau{t:g}"] for t in tau_max]
        md.append(f"| {r['structure']} | " + " | ".join(
            (f"**{c:.2f}**" if t == r["tau_max"] else f"{c:.2f}") if c != "" else ""
            for c, t in zip(cells, tau_max)) + " |")
    md += ["", "Every circuit at the same upper bound of its time constants (no selection), estimation / "
           "validation RMSE (mV), and the ZARC's alpha:", "",
           "| circuit | " + " | ".join(f"{t:g} s" for t in tau_max) + " |",
           "|---|" + "---:|" * len(tau_max)]
    for name in dict.fromkeys(r["structure"] for r in bound_rows):
        cells = []
        for r in (r for r in bound_rows if r["structure"] == name):
            text = f"{r['est_mV']:.2f} / {r['val_mV']:.2f}"
            cells.append(text + (f" (α {r['alpha']:.2f})" if np.isfinite(r["alpha"]) else ""))
        md.append(f"| {name} | " + " | ".join(cells) + " |")
    verdict_rmse = "met" if gain >= 0.05 else "not met"
    a1 = frac.parameters["alpha1"].value
    md += ["", "## The goal", "",
           f"- 1 ZARC ({frac.n_free} parameters) validates at {frac_row['val_mV']:.2f} mV; the best "
           f"integer circuit with at least as many parameters (by validation, the strongest competitor) "
           f"is {best_int['structure']} ({best_int['n_params']}) at {best_int['val_mV']:.2f} mV: "
           f"{100 * gain:.1f} % better (goal >= 5 %: **{verdict_rmse}**). The integer circuit the "
           f"held-back part would pick is {best_int_held['structure']} at "
           f"{best_int_held['val_mV']:.2f} mV.",
           f"- alpha1 = {a1:.3f} (standard error {frac.standard_errors()['alpha1']:.3g}, "
           f"white-residual; {se_held_at_bounds(frac, u_e, 'alpha1'):.3g} with "
           f"{' '.join(at_bound(frac)) or 'nothing'} held at its bound), profile 95 % interval "
           f"[{prof.low:.3f}, {prof.high:.3f}] with "
           f"n = {frac.n_samples}; "
           f"[{prof_eff.low:.3f}, {prof_eff.high:.3f}] with Bartlett's effective n = {n_eff:.0f} "
           f"of the correlated residuals (goal: alpha in (0.3, 0.7) and the interval off 0 and 1: "
           f"**{goal_alpha(a1, prof)}** with n, **{goal_alpha(a1, prof_eff)}** with the effective n).",
           f"- LR test of the ZARC against its integer limit (alpha = 1, an RC element, same tau bound): "
           f"{lr_nominal.statistic:.4g}, p = {lr_nominal.pvalue:.3g} with n = {frac.n_samples}; "
           f"{lr_eff.statistic:.3g}, p = {lr_eff.pvalue:.3g} with the effective n "
           f"({lr_nominal.distribution}).",
           "", "## Impedance against the measured spectra (never used in the fit)", "",
           "| SOC | circuit | RMS relative error | max relative error | frequencies |",
           "|---:|---|---:|---:|---:|"]
    for r in imp_rows:
        md.append(f"| {r['soc']:g} | {r['model']} | {100 * r['rms_rel_error']:.1f} % | "
                  f"{100 * r['max_rel_error']:.1f} % | {r['n_freq']} |")
    md += ["", f"Run time {time.perf_counter() - t_start:.0f} s.", ""]
    (args.outdir / "battery.md").write_text("\n".join(md))
    print("\n".join(md))


if __name__ == "__main__":
    main()
