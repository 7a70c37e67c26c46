"""fohw tutorial: simulate a fractional-order Hammerstein-Wiener system, identify it three ways,
check the estimates, and save the result. Run: python docs/tutorial.py

The ``# %%`` lines split it into notebook cells (the percent format that Jupyter's jupytext, VS
Code and Spyder open as a notebook); the docs build runs it cell by cell and shows each cell's
output (docs/tutorial.md).
"""

import tempfile
from pathlib import Path

import numpy as np

import fohw

# %% [markdown]
# ## 1. A system
#
# The paper's academic example (Section 6.1): the output is a weighted sum of past
# Grünwald–Letnikov differences of the output's and the input's static nonlinearities (Eq. 16),
#
# $$
# y(k) = \sum_{i=1}^{n_a} a_i\, \Delta^{\alpha} \bar g\bigl(y(k-i)\bigr)
#      + \sum_{i=1}^{n_b} b_i\, \Delta^{\alpha} \bar f\bigl(u(k-i)\bigr) + v(k),
# $$
#
# $$
# \bar f = \sum_{j=1}^{n_p} p_j f_j, \qquad \bar g = \sum_{j=1}^{n_q} q_j g_j,
# $$
#
# with $f = (u, u^2)$, $g = (y, y^2, y^3)$, $p_1 = q_1 = 1$ and the GL difference
# $\Delta^{\alpha} x(k) = \sum_{j=0}^{k} \beta_j\, x(k-j)$, $\beta_j = (-1)^j \binom{\alpha}{j}$
# (Eq. 5). Its parameter vector is $\theta = [\mathbf q \otimes \mathbf a,\ \mathbf p \otimes \mathbf b]$
# (Eq. 20).

# %%
model = fohw.HammersteinWiener(a=[0.1, 0.2], b=[-0.4, -0.2], p=[1, 0.5], q=[1, 0.7, 0.35],
                               alpha=0.6)                       # f = [u, u^2], g = [y, y^2, y^3]
print(model)
print(dict(zip(model.parameter_names, model.theta.round(3).tolist())))

# %% [markdown]
# ## 2. Data
#
# A uniform input with unit variance and white noise of variance 0.01. The model is linear in
# $\theta$ for a given $\alpha$: $y = \Phi(\alpha)\,\theta + v$ exactly (Eq. 19), which the
# information matrix checks to rounding error.

# %%
rng = np.random.default_rng(0)
u = rng.uniform(-np.sqrt(3), np.sqrt(3), 5000)
v = 0.1 * rng.standard_normal(5000)
y = fohw.simulate(model, u, noise=v)

Phi = fohw.model.lagged.regressors.information_matrix(u, y, 0.6, na=2, nb=2, f_basis=2, g_basis=3)
print("max |y - Phi theta - v| =", np.abs(y - Phi @ model.theta - v).max())

# %% [markdown]
# ## 3. The paper's hybrid method
#
# Table 1 of the paper: one recursive pass, so `hybrid.status` is NOT_TESTED (one pass does not
# test convergence). As the reproduction page shows, it stays far from the truth.

# %%
hybrid = fohw.identify(u, y, na=2, nb=2, f_basis=2, g_basis=3, method="hybrid",
                       innovation_length=5)
print("hybrid: alpha = %.3f, delta = %.3f" % (hybrid.alpha, hybrid.relative_error(model.theta)))

# %% [markdown]
# ## 4. Separable least squares
#
# `method="varpro"` reaches the Cramér–Rao bound and reports its uncertainty. The relative error
# is $\delta = \lVert\hat\theta - \theta\rVert / \lVert\theta\rVert$.

# %%
best = fohw.identify(u, y, na=2, nb=2, f_basis=2, g_basis=3, method="varpro")
print(best.summary())
bound = fohw.crb(model, u, 0.01, random_state=1)
print("varpro delta = %.4f; CRB RMS delta = %.4f, CRB alpha sd = %.4f"
      % (best.relative_error(model.theta), bound.rms_relative_error, bound.alpha_std))
lo, hi = best.confidence_intervals()["alpha"]
print(f"alpha in [{lo:.4f}, {hi:.4f}] with 95 % confidence")

# %% [markdown]
# In a notebook, a result on the last line of a cell shows as a table:

# %%
best

# %% [markdown]
# The identified linear block's frequency response (its fractional difference operator on the
# unit circle):

# %%
best.bode()

# %% [markdown]
# ## 5. Online
#
# MI-RLS processes chunks as they arrive; the result equals one fit on all data.

# %%
online = fohw.estimators.rls.MultiInnovationRLS(na=2, nb=2, f_basis=2, g_basis=3)
for start in range(0, 5000, 1000):
    online.partial_fit(u[start:start + 1000], y[start:start + 1000])
print("MI-RLS after %d samples: alpha = %.4f" % (online.n_samples_seen_, online.alpha_))

# %% [markdown]
# ## 6. Validate
#
# One-step prediction and free-run simulation on fresh data.

# %%
u_new = rng.uniform(-np.sqrt(3), np.sqrt(3), 2000)
y_new = fohw.simulate(model, u_new, noise=0.1 * rng.standard_normal(2000))
print("one-step fit %%: %.1f" % fohw.analysis.metrics.fit_percent(y_new, best.predict(u_new, y_new)))
print("free-run fit %%: %.1f" % fohw.analysis.metrics.fit_percent(y_new, best.simulate(u_new)))

# %% [markdown]
# ## 7. Save and load
#
# JSON, exact floats, never pickle.

# %%
with tempfile.TemporaryDirectory() as folder:
    path = Path(folder) / "result.json"
    fohw.save_result(best, path)
    again = fohw.load_result(path)
    assert np.array_equal(again.theta, best.theta) and again.alpha == best.alpha
print("saved and reloaded exactly")
