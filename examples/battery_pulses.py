"""Pulse tests at several temperatures and SOCs: fractional against RC circuits on held-back records.

    python examples/battery_pulses.py --outdir results [--fast]

The records: fohw.datasets.pybamm_pulses(), an LG M50 cell simulated by PyBaMM (DFN, Chen2020,
lumped thermal; benchmarks/generate_pybamm_pulses.py), 10 s pulses at 1C (discharge, then
charge) at 0, 10, 25, 35 and 45 degC and SOC 0.3, 0.5 and 0.8, noise-free. Every circuit is a
fohw.CircuitTables: its offset, R0, resistances and time constants are tables over the SOC
(0.3, 0.5, 0.8) and the temperature (0, 25, 45 degC), one order per ZARC shared by every
breakpoint, smoothing 1e-4 V^2. The protocol:

1. Fit: the nine records at 0, 25 and 45 degC, as one data set (fohw.fit(model, [records])).
2. Choose: the upper bound of the time constants (TAU_MAX) and the interpolation in temperature
   (linear, as PyBaMM's tables, or Arrhenius: logarithms linear in 1/T), by the free-run error on
   the 10 degC records (held back from the fit); the error of every choice is printed, and when
   the errors of two bounds agree within TIE the bound is reported as inactive (a tie carries no
   information) and the smallest of them kept. The test-set error of the interpolation not
   chosen is printed too, marked as not used.
3. Judge: the free-run error on the 35 degC records, held back from both the fit and the choice;
   fractional and RC circuits at (almost) equal parameter count: a ZARC's order is one shared
   parameter, an RC element's time constant a table of nine.
4. The order: each of the nine records fitted alone (one breakpoint) gives its own alpha with a
   95 % interval; the table shows which of them cover the joint estimate, and the order of each
   record in the joint fit with the tables shared (fohw.fit(..., per_record=["alpha1"])).

--fast: samples at 1 s (every=10), two structures, two bounds, linear interpolation only, a
coarser start scan, the single-record fits at 25 degC only. Writes battery_pulses.md,
battery_pulses.csv, battery_pulses_alpha.csv and battery_pulses.png to --outdir.
"""

import argparse
import csv
import math
import time
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import fohw  # noqa: E402

FIT_T, CHOOSE_T, TEST_T = (0.0, 25.0, 45.0), 10.0, 35.0
SOCS = (0.3, 0.5, 0.8)
STRUCTURES = [("rc",), ("zarc",), ("rc", "rc"), ("rc", "zarc"), ("rc", "rc", "rc")]
FAST_STRUCTURES = [("rc",), ("zarc",)]
TAU_MAX = (20.0, 50.0, 200.0, 1000.0)
FAST_TAU_MAX = (50.0, 200.0)
SMOOTHING = 1e-4
TIE = 1e-6
INTERPOLATIONS = ("linear", "arrhenius")


def rms(e):
    return float(np.sqrt(np.mean(np.square(e))))


def free_run_mV(fit, records):
    """RMS free-run error [mV] of a fitted circuit over records (each from rest)."""
    return 1e3 * rms(np.concatenate([fit.model.simulate(r.u) - r.v for r in records]))


def fit_tables(elements, tau_max, interpolation, ocv, dt, data, opts):
    model = fohw.CircuitTables(list(elements), soc_points=SOCS, temperature_points=FIT_T, ocv=ocv,
                               dt=dt, tau_bounds=(dt, tau_max), smoothing=SMOOTHING,
                               temperature_interpolation=interpolation, **opts["model"])
    t0 = time.perf_counter()
    fit = fohw.fit(model, data, **opts["fit"])
    return fit, time.perf_counter() - t0


def label(elements):
    return " + ".join(e.upper() for e in elements)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--outdir", type=Path, default=Path("results"))
    parser.add_argument("--fast", action="store_true", help="a coarse run for the test suite")
    args = parser.parse_args(argv)
    args.outdir.mkdir(parents=True, exist_ok=True)
    t_start = time.perf_counter()
    every = 10 if args.fast else 5
    structures = FAST_STRUCTURES if args.fast else STRUCTURES
    tau_max = FAST_TAU_MAX if args.fast else TAU_MAX
    opts = ({"model": dict(n_tau=4, n_alpha=3), "fit": dict(n_starts=1)} if args.fast else
            {"model": {}, "fit": {}})

    fit_recs, ocv = fohw.datasets.pybamm_pulses(temperatures=FIT_T, every=every)
    choose_recs, _ = fohw.datasets.pybamm_pulses(temperatures=[CHOOSE_T], every=every)
    test_recs, _ = fohw.datasets.pybamm_pulses(temperatures=[TEST_T], every=every)
    dt = fit_recs[0].dt
    data = [r.record() for r in fit_recs]

    interpolations = ("linear",) if args.fast else INTERPOLATIONS
    rows, fits = [], {}
    for elements in structures:
        scores, by_choice = {}, {}
        for interp in interpolations:
            for t in tau_max:
                fit, seconds = fit_tables(elements, t, interp, ocv, dt, data, opts)
                by_choice[(interp, t)] = (fit, seconds)
                scores[(interp, t)] = free_run_mV(fit, choose_recs)
        low = min(scores.values())
        tied = [c for c in scores if scores[c] <= low * (1 + TIE)]
        interp = min((c[0] for c in tied), key=interpolations.index)
        tied = sorted(t for i, t in tied if i == interp)
        best = tied[0]
        fit, seconds = by_choice[(interp, best)]
        fits[elements] = fit
        other = [i for i in interpolations if i != interp]
        other_test = (free_run_mV(by_choice[(other[0], best)][0], test_recs) if other
                      else float("nan"))
        taus = [fit.model.table(n) for n in fit.model.tables if n.startswith("tau")]
        at_top = sum(int(np.sum(tab >= best * (1 - 1e-6))) for tab in taus)
        alpha = " ".join(f"{fit.parameters[n].value:.3f}" for n in fit.parameters if n.startswith("alpha"))
        rows.append(dict(structure=label(elements), n_params=fit.n_free,
                         fractional="zarc" in elements, tau_max=best, interpolation=interp,
                         bound_inactive=len(tied) > 1,
                         errors_by_choice_mV=" ".join(f"{i[:3]}/{t:g}:{scores[(i, t)]:.4f}"
                                                      for i in interpolations for t in tau_max),
                         other_interpolation_test_mV=other_test,
                         tau_at_bound=at_top, fit_mV=1e3 * fit.rmse, choose_mV=scores[(interp, best)],
                         test_mV=free_run_mV(fit, test_recs), alpha=alpha, fit_s=seconds,
                         status=fit.status.name))

    # The order record by record, against the joint estimate.
    joint = fits[("zarc",)]
    a_joint = joint.parameters["alpha1"].value
    a_lo, a_hi = joint.confidence_intervals(0.95)["alpha1"]
    # The same joint fit with one order per record (fohw.fit's per_record=), the tables shared.
    zarc_model = joint.model.with_parameters(joint.model.parameters)
    per = fohw.fit(zarc_model, data, per_record=["alpha1"], **opts["fit"]).per_record["alpha1"]
    alpha_rows = []
    for k, r in enumerate(fit_recs):
        if args.fast and r.ambient != 25.0:
            continue
        model = fohw.CircuitTables(["zarc"], soc_points=[r.soc0], temperature_points=[r.ambient],
                                   ocv=ocv, dt=dt, tau_bounds=(dt, rows[1]["tau_max"]),
                                   **opts["model"])
        f = fohw.fit(model, r.record(), **opts["fit"])
        lo, hi = f.confidence_intervals(0.95)["alpha1"]
        r0 = f"R0_s{r.soc0:g}_T{r.ambient:g}"
        alpha_rows.append(dict(temperature=r.ambient, soc=r.soc0, alpha=f.parameters["alpha1"].value,
                               low=lo, high=hi, covers_joint=lo <= a_joint <= hi,
                               alpha_joint_per_record=per["values"][k],
                               alpha_joint_per_record_se=per["standard_errors"][k],
                               R0_mOhm=1e3 * f.parameters[r0].value,
                               R0_se_mOhm=1e3 * f.standard_errors()[r0],
                               R0_joint_mOhm=1e3 * float(joint.model.table("R0")[
                                   SOCS.index(r.soc0), FIT_T.index(r.ambient)]),
                               rmse_mV=1e3 * f.rmse))

    with open(args.outdir / "battery_pulses.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    with open(args.outdir / "battery_pulses_alpha.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(alpha_rows[0]))
        w.writeheader()
        w.writerows(alpha_rows)

    # A held-back record: measured, the ZARC and the RC tables.
    rec = next(r for r in test_recs if r.soc0 == 0.5)
    fig, ax = plt.subplots(figsize=(7, 3.5))
    t = np.arange(rec.n_samples) * rec.dt
    ax.plot(t, rec.v, "k", lw=1.5, label="PyBaMM (35 degC, held back)")
    for elements, style in ((("zarc",), "C0--"), (("rc",), "C3:")):
        if elements in fits:
            ax.plot(t, fits[elements].model.simulate(rec.u), style, lw=1.2,
                    label=f"{label(elements)} tables")
    ax.set_xlabel("time [s]")
    ax.set_ylabel("voltage [V]")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(args.outdir / "battery_pulses.png", dpi=120)
    plt.close(fig)

    covered = sum(r["covers_joint"] for r in alpha_rows)
    lines = [
        "# Pulse tests: fractional against RC circuits on held-back records",
        "",
        f"Fit: {len(fit_recs)} records at {', '.join(f'{x:g}' for x in FIT_T)} degC, SOC "
        f"{', '.join(f'{x:g}' for x in SOCS)}, one joint fit per circuit (samples every {dt:g} s). "
        f"Bound chosen on the {CHOOSE_T:g} degC records, judged on the {TEST_T:g} degC records.",
        "",
        "| circuit | parameters | tau max [s] (inactive?) | T interpolation | fit [mV] | "
        "choice set [mV] | test set [mV] | alpha | time constants at the bound | "
        "test set, other interpolation [mV] (not used) |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(f"| {r['structure']} | {r['n_params']} | {r['tau_max']:g}"
                     f"{' (tie: inactive)' if r['bound_inactive'] else ''} | {r['interpolation']} | "
                     f"{r['fit_mV']:.3f} | {r['choose_mV']:.3f} | {r['test_mV']:.3f} | "
                     f"{r['alpha'] or '-'} | {r['tau_at_bound']} | "
                     f"{r['other_interpolation_test_mV']:.3f} |")
    lines += ["", "Choice-set error of every interpolation / bound (mV): "
              + "; ".join(f"{r['structure']}: {r['errors_by_choice_mV']}" for r in rows), "",
              f"Joint order of the ZARC tables: {a_joint:.4f} [{a_lo:.4f}, {a_hi:.4f}] (95 %). "
              f"Single-record intervals that cover it: {covered} of {len(alpha_rows)}.", "",
              "| T [degC] | SOC | alpha (one record) | 95 % interval | covers joint | "
              "alpha (joint tables, one order per record) | "
              "R0 one record [mOhm] | R0 joint [mOhm] |", "|---|---|---|---|---|---|---|---|"]
    for r in alpha_rows:
        lines.append(f"| {r['temperature']:g} | {r['soc']:g} | {r['alpha']:.4f} | "
                     f"[{r['low']:.4f}, {r['high']:.4f}] | {'yes' if r['covers_joint'] else 'no'} | "
                     f"{r['alpha_joint_per_record']:.4f} ± {r['alpha_joint_per_record_se']:.4f} | "
                     f"{r['R0_mOhm']:.3f} ± {r['R0_se_mOhm']:.3f} | {r['R0_joint_mOhm']:.3f} |")
    lines += ["", f"Run time: {time.perf_counter() - t_start:.1f} s ({'fast' if args.fast else 'full'} run)."]
    (args.outdir / "battery_pulses.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0 if all(math.isfinite(r["test_mV"]) for r in rows) else 1


if __name__ == "__main__":
    raise SystemExit(main())
