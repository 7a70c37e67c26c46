"""Oustaloup and refined Oustaloup approximations (FOMCON oustapp) against the reference formulas,
the reported band error, and the python-control export (issue 25, item 5)."""

import numpy as np
import pytest

import fohw
from fohw.exceptions import ParameterError


def reference_oustaloup(r, wb, wh, N, s):
    """FOMCON oustafod written out: K prod_{k=-N}^{N} (s + w'_k) / (s + w_k)."""
    k = np.arange(-N, N + 1)
    wz = wb * (wh / wb) ** ((k + N + 0.5 * (1 - r)) / (2 * N + 1))
    wp = wb * (wh / wb) ** ((k + N + 0.5 * (1 + r)) / (2 * N + 1))
    out = wh ** r * np.ones_like(s)
    for a, b in zip(wz, wp):
        out = out * (s + a) / (s + b)
    return out


def reference_refined(r, wb, wh, N, s, b=10.0, d=9.0):
    """FOMCON new_fod: (d/b)^r (d s^2 + b wh s) / (d (1 - r) s^2 + b wh s + d r) times oustafod."""
    return (d / b) ** r * (d * s ** 2 + b * wh * s) / (d * (1 - r) * s ** 2 + b * wh * s + d * r) \
        * reference_oustaloup(r, wb, wh, N, s)


@pytest.mark.parametrize("method, reference", [("oustaloup", reference_oustaloup),
                                               ("refined", reference_refined)])
@pytest.mark.parametrize("r", [0.5, -0.3, 0.8])
def test_operator_filter_equals_the_reference_formulas(method, reference, r):
    band, N = (1e-2, 1e2), 4
    G = fohw.FractionalTF([1.0], [r], [1.0], [0.0])                  # s^r
    approx = G.oustaloup(band, N, method)
    w = np.logspace(-3, 3, 200)
    np.testing.assert_allclose(approx.frequency_response(w), reference(r, *band, N, 1j * w), rtol=1e-9)
    # the reported band error is the reference filter's error against (j w)^r
    wb = approx.band_frequencies()
    ref_err = np.max(np.abs(reference(r, *band, N, 1j * wb) / (1j * wb) ** r - 1))
    assert approx.max_relative_error() == pytest.approx(ref_err, rel=1e-8)


def test_transfer_function_approximation_splits_integer_and_fractional_parts():
    """1 / (s^1.5 + 0.5): s^1.5 = s * s^0.5 with the filter for s^0.5 (FOMCON's fix())."""
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 0.5], [1.5, 0.0])
    approx = G.oustaloup((1e-3, 1e3), 5)
    w = np.logspace(-3, 3, 100)
    ref = 1 / (1j * w * reference_oustaloup(0.5, 1e-3, 1e3, 5, 1j * w) + 0.5)
    np.testing.assert_allclose(approx.frequency_response(w), ref, rtol=1e-9)
    # errors shrink inside the band; the refined filter trades mid-band for edge accuracy
    e_in = approx.max_relative_error(band=(1e-1, 1e1))
    assert e_in < 0.01 < approx.max_relative_error()
    refined = G.oustaloup((1e-3, 1e3), 5, "refined")
    assert refined.max_relative_error() < approx.max_relative_error()


def test_export_to_python_control_within_the_reported_error():
    control = pytest.importorskip("control")
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
    for method in ("oustaloup", "refined"):
        approx = G.oustaloup((1e-2, 1e2), 4, method)
        sys = approx.to_control()
        assert isinstance(sys, control.TransferFunction)
        w = approx.band_frequencies()
        g_control = np.asarray(sys(1j * w)).ravel()
        err = np.max(np.abs(g_control / G.frequency_response(w) - 1))
        assert err <= approx.max_relative_error() * (1 + 1e-9)
        np.testing.assert_allclose(g_control, approx.frequency_response(w), rtol=1e-10)


def test_bad_approximation_input():
    G = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0])
    with pytest.raises(ParameterError, match="`band`"):
        G.oustaloup((10.0, 1.0))
    with pytest.raises(ParameterError, match="`order`"):
        G.oustaloup((1.0, 10.0), order=0)
    with pytest.raises(ParameterError, match="`method`"):
        G.oustaloup((1.0, 10.0), method="matsuda")
    Gd = fohw.FractionalTF([1.0], [0.0], [1.0, 1.0], [0.5, 0.0], delay=1.0)
    with pytest.raises(ParameterError, match="delay"):
        Gd.oustaloup((1.0, 10.0)).to_control()
