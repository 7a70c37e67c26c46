"""Write the version-2 result and model files of tests/data with fohw's code *before* format 3.

Run once with the old fohw (commit 29a506a) on the path, from the repository root::

    python tests/data/make_v2_results.py

Each ``result_v2_<name>.json`` is what ``IdentificationResult.to_json`` wrote; the companion
``result_v2_<name>.view.json`` is how that fohw read the file back (every attribute, the model,
``repr`` and ``summary()``), which tests/test_result_files.py compares with today's reader;
likewise ``model_v2_<name>.json`` (``save_model``) and its ``repr`` as read back.
"""

import json
import warnings
from pathlib import Path

import numpy as np

import fohw

HERE = Path(__file__).resolve().parent
ATTRIBUTES = ("method", "schedule", "alpha", "theta", "J", "status", "nit", "nfev", "message",
              "alpha_at_bound", "theta_history", "alpha_sample_history", "alpha_history",
              "J_history", "n_samples", "options", "covariance", "noise_variance",
              "alpha_profile", "orders", "offset", "past", "operating_point", "input_range",
              "linear", "nonlinear", "estimate_names", "dt", "converged", "parameter_names",
              "na", "nb")


def plain(value):
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, (tuple, list)):
        return [plain(v) for v in value]
    if isinstance(value, dict):
        return {k: plain(v) for k, v in value.items()}
    if isinstance(value, np.generic):
        return value.item()
    return value


def view(res):
    out = {name: plain(getattr(res, name)) for name in ATTRIBUTES}
    out["status"] = int(res.status)
    out["layout"] = [res.layout.na, res.layout.nb, list(res.layout.names)]
    out["f_basis"], out["g_basis"] = list(res.f_basis.names), list(res.g_basis.names)
    out["structure"] = res.structure.to_dict()
    out["model"] = None if res.model is None else repr(res.model)
    out["repr"], out["summary"] = repr(res), res.summary()
    return out


def main():
    data = fohw.datasets.paper_example(300, random_state=0)
    u, y = data.u, data.y
    fits = {
        "varpro": dict(method="varpro", na=2, nb=2, f_basis=2, g_basis=3),
        "hybrid": dict(method="hybrid", n=100, na=2, nb=2, f_basis=2, g_basis=3, innovation_length=3),
        "output_error_mixed": dict(method="output_error", na=1, nb=1, f_basis=2, g_basis=1,
                                   orders="mixed", offset=True, past="estimate", max_nfev=20),
        "fixed_order": dict(method="varpro", na=1, nb=2, f_basis=1, g_basis=1, orders=0.5),
    }
    for name, kw in fits.items():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            n = kw.pop("n", len(u))
            res = fohw.identify(u[:n], y[:n], **kw)
        path = HERE / f"result_v2_{name}.json"
        res.to_json(path)
        back = fohw.load_result(path)
        (HERE / f"result_v2_{name}.view.json").write_text(json.dumps(view(back), indent=1) + "\n")
    models = {"paper": fohw.datasets.paper_model(),
              "mixed": fohw.HammersteinWiener([0.5, 0.2], [1.0, 0.3], [1, 0.2], [1], alpha=0.4,
                                              orders="mixed", dt=0.5, offset=0.25,
                                              past=(0.1, -0.2), operating_point=(1.0, 2.0))}
    for name, model in models.items():
        path = HERE / f"model_v2_{name}.json"
        fohw.save_model(model, path)
        (HERE / f"model_v2_{name}.view.json").write_text(
            json.dumps({"repr": repr(fohw.load_model(path))}, indent=1) + "\n")


if __name__ == "__main__":
    main()
