"""fohw tutorial: simulate a fractional-order Hammerstein-Wiener system, identify it three ways,
check the estimates, and save the result. Run: python docs/tutorial.py"""

import tempfile
from pathlib import Path

import numpy as np

import fohw

# 1. A system: y[k] = sum_i a_i Δ^α gbar(y)[k-i] + sum_i b_i Δ^α fbar(u)[k-i] + v[k]
model = fohw.HammersteinWiener(a=[0.1, 0.2], b=[-0.4, -0.2], p=[1, 0.5], q=[1, 0.7, 0.35],
                               alpha=0.6)                       # f = [u, u^2], g = [y, y^2, y^3]
print(model)
print(dict(zip(model.parameter_names, model.theta.round(3))))

# 2. Data: a uniform input with unit variance, white noise of variance 0.01.
rng = np.random.default_rng(0)
u = rng.uniform(-np.sqrt(3), np.sqrt(3), 5000)
v = 0.1 * rng.standard_normal(5000)
y = fohw.simulate(model, u, noise=v)

# The model is linear in theta for a given alpha: y = Phi(alpha) theta + v exactly.
Phi = fohw.information_matrix(u, y, 0.6, na=2, nb=2, f_basis=2, g_basis=3)
print("max |y - Phi theta - v| =", np.abs(y - Phi @ model.theta - v).max())

# 3. The paper's hybrid method (Table 1: one recursive pass, so hybrid.status is NOT_TESTED:
#    one pass does not test convergence). As docs/reproduction.md shows, it stays far from the truth.
hybrid = fohw.identify(u, y, na=2, nb=2, f_basis=2, g_basis=3, method="hybrid",
                       innovation_length=5)
print("hybrid: alpha = %.3f, delta = %.3f" % (hybrid.alpha, hybrid.relative_error(model.theta)))

# 4. Separable least squares: reaches the Cramér-Rao bound and reports its uncertainty.
best = fohw.identify(u, y, na=2, nb=2, f_basis=2, g_basis=3, method="varpro")
print(best.summary())
bound = fohw.crb(model, u, 0.01, random_state=1)
print("varpro delta = %.4f; CRB RMS delta = %.4f, CRB alpha sd = %.4f"
      % (best.relative_error(model.theta), bound.rms_relative_error, bound.alpha_std))
lo, hi = best.confidence_intervals()["alpha"]
print(f"alpha in [{lo:.4f}, {hi:.4f}] with 95 % confidence")

# 5. Online: MI-RLS processes chunks as they arrive; the result equals one fit on all data.
online = fohw.MultiInnovationRLS(na=2, nb=2, f_basis=2, g_basis=3)
for start in range(0, 5000, 1000):
    online.partial_fit(u[start:start + 1000], y[start:start + 1000])
print("MI-RLS after %d samples: alpha = %.4f" % (online.n_samples_seen_, online.alpha_))

# 6. Validate: one-step prediction and free-run simulation on fresh data.
u_new = rng.uniform(-np.sqrt(3), np.sqrt(3), 2000)
y_new = fohw.simulate(model, u_new, noise=0.1 * rng.standard_normal(2000))
print("one-step fit %%: %.1f" % fohw.analysis.metrics.fit_percent(y_new, best.predict(u_new, y_new)))
print("free-run fit %%: %.1f" % fohw.analysis.metrics.fit_percent(y_new, best.simulate(u_new)))

# 7. Save and load (JSON, exact floats, never pickle).
with tempfile.TemporaryDirectory() as folder:
    path = Path(folder) / "result.json"
    fohw.save_result(best, path)
    again = fohw.load_result(path)
    assert np.array_equal(again.theta, best.theta) and again.alpha == best.alpha
print("saved and reloaded exactly")
