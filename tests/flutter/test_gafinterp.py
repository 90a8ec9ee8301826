"""GAF interpolation in k: values, k-derivatives and the per-interval linear form used by flutter.pk."""
from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from scipy.interpolate import interp1d

from flutter.gafinterp import GafInterpolator

K_TAB = np.array([0.01, 0.1, 0.3, 1.0, 3.0])


def table():
    rng = np.random.default_rng(3)
    Q = rng.standard_normal((1, K_TAB.size, 3, 3)) + 1j * rng.standard_normal((1, K_TAB.size, 3, 3))
    return xr.Dataset({"Q": (("mach", "k", "mode_i", "mode_j"), Q)},
                      coords={"mach": [0.0], "k": K_TAB, "mode_i": [1, 2, 3], "mode_j": [1, 2, 3]},
                      attrs={"refc": 1.0})


# off the tabulated k values, where the linear interpolant has one-sided slopes
K_EVAL = np.array([0.0, 0.005, 0.05, 0.2, 0.99, 2.5, 4.0])


def test_linear_values_match_scipy_interp1d():
    """Inside the table: scipy's linear interpolation; above it: held at the largest k."""
    ds = table()
    Q = ds.Q.values[0]
    QR, D, out = GafInterpolator(ds, 0.0, "linear")(K_EVAL)
    ref_R = interp1d(K_TAB, Q.real, axis=0, bounds_error=False, fill_value=(Q.real[0], Q.real[-1]))
    D_tab = Q.imag / K_TAB[:, None, None]
    ref_D = interp1d(K_TAB, D_tab, axis=0, bounds_error=False, fill_value=(D_tab[0], D_tab[-1]))
    inside = K_EVAL >= K_TAB[0]
    np.testing.assert_allclose(QR[inside], ref_R(K_EVAL[inside]), rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(D[inside], ref_D(K_EVAL[inside]), rtol=1e-13, atol=1e-13)
    assert out.tolist() == [False] * 6 + [True]


@pytest.mark.parametrize("kind", ["linear", "cubic"])
def test_even_continuation_below_the_table(kind):
    """Below the smallest k, Q^R and Q^I/k follow the even parabola a + c k^2 through the two
    smallest tabulated k (hand formula), so a table of an exactly even function (here
    Q^R = A + C k^2, Q^I / k = B + E k^2) is reproduced at k = 0 and in between, slopes 2 C k."""
    rng = np.random.default_rng(5)
    A, B, C, E = (rng.standard_normal((3, 3)) for _ in range(4))
    k2 = K_TAB[:, None, None] ** 2
    Q = (A + C * k2) + 1j * K_TAB[:, None, None] * (B + E * k2)
    ds = xr.Dataset({"Q": (("mach", "k", "mode_i", "mode_j"), Q[None])},
                    coords={"mach": [0.0], "k": K_TAB, "mode_i": [1, 2, 3], "mode_j": [1, 2, 3]},
                    attrs={"refc": 1.0})
    k = np.array([0.0, 0.004, 0.009])
    QR, D, dQR, dD, _ = GafInterpolator(ds, 0.0, kind).with_slopes(k)
    kk = k[:, None, None]
    np.testing.assert_allclose(QR, A + C * kk ** 2, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(D, B + E * kk ** 2, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(dQR, 2 * C * kk, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(dD, 2 * E * kk, rtol=1e-10, atol=1e-12)
    G, kc, sloped, _ = GafInterpolator(ds, 0.0, kind).linearised(k)
    np.testing.assert_allclose(G[:, 0] + kc[:, None, None] * G[:, 1], A + C * kk ** 2, atol=1e-12)
    assert kc.tolist() == k.tolist() and sloped.all()


@pytest.mark.parametrize("kind, tol", [("linear", 1e-6), ("cubic", 1e-3)])
def test_slopes_match_finite_differences(kind, tol):
    """Forward differences with step 1e-7 (error ~ 1e-7 |Q''|: zero for linear, O(1e-4) for cubic)."""
    interp = GafInterpolator(table(), 0.0, kind)
    QR, D, dQR, dD, _ = interp.with_slopes(K_EVAL)
    h = 1e-7
    QR2, D2, _ = interp(K_EVAL + h)
    np.testing.assert_allclose(dQR, (QR2 - QR) / h, atol=tol * max(1.0, np.abs(dQR).max()))
    np.testing.assert_allclose(dD, (D2 - D) / h, atol=tol * max(1.0, np.abs(dD).max()))
    assert np.all(dQR[[0, -1]] == 0) and np.all(dD[[0, -1]] == 0)  # k = 0 (even) and held above


@pytest.mark.parametrize("kind", ["linear", "cubic"])
def test_linearised_form_reproduces_values_and_slopes(kind):
    interp = GafInterpolator(table(), 0.0, kind)
    QR, D, dQR, dD, out = interp.with_slopes(K_EVAL)
    G, kc, sloped, out2 = interp.linearised(K_EVAL)
    kb = kc[:, None, None]
    np.testing.assert_allclose(G[:, 0] + kb * G[:, 1], QR, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(G[:, 2] + kb * G[:, 3], D, rtol=1e-12, atol=1e-12)
    s = sloped[:, None, None]
    np.testing.assert_allclose(np.where(s, G[:, 1], 0.0), dQR, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(np.where(s, G[:, 3], 0.0), dD, rtol=1e-12, atol=1e-12)
    assert out2.tolist() == out.tolist()


def test_callable_slopes():
    """A callable GAF gets one-sided finite-difference slopes (step 1e-6 k)."""
    def gaf(mach, k):
        k = np.asarray(k, dtype=float)
        return (np.sin(k) + 1j * k * np.cos(k))[:, None, None] * np.ones((1, 2, 2))
    k = np.array([0.1, 0.5, 2.0])
    _, D, dQR, dD, _ = GafInterpolator(gaf, 0.0).with_slopes(k)
    np.testing.assert_allclose(dQR[:, 0, 0], np.cos(k), rtol=1e-5)
    np.testing.assert_allclose(dD[:, 0, 0], -np.sin(k), rtol=1e-5, atol=1e-6)
