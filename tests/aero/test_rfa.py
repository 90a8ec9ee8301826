"""Rational function approximation (aero.rfa): exact recovery, and the strict fit error on Nastran's
bah_plane QHH and on Theodorsen's typical section."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

from aero.rfa import _basis, fit_rfa, fit_roger
from aero.strip import section_gaf
from structures.common.errors import InputError

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "flutter"))  # shared Nastran readers
from flutter_nastran import bah_qhh_dataset  # noqa: E402

K_THEO = np.concatenate([[0.001, 0.01, 0.02, 0.05], np.linspace(0.1, 2.0, 20)])


def test_exact_rational_form_is_recovered():
    """Q built from A0..A2, one real lag (0.3) and one pair (0.5, 1.2): the optimiser finds the lag
    roots and the coefficients to 1e-8 (the fit's residual is then zero)."""
    rng = np.random.default_rng(3)
    k = np.linspace(0.01, 3.0, 25)
    beta, pairs = np.array([0.3]), np.array([[0.5, 1.2]])
    A = rng.normal(size=(6, 3, 3))
    Q = np.einsum("kt,tij->kij", _basis(1j * k, beta, pairs), A)
    fit = fit_rfa(k, Q, refc=2.0, nlag=1, npair=1)
    np.testing.assert_allclose(fit.beta, beta, rtol=1e-8)
    np.testing.assert_allclose(fit.pairs, pairs, rtol=1e-8)
    np.testing.assert_allclose(fit.A, A, atol=1e-7)
    assert fit.fit_error < 1e-9 and fit.overall_error < 1e-9


@pytest.mark.parametrize("mach", [0.0, 0.2])
def test_bah_qhh_fit_under_two_percent(mach):
    """Nastran's bah_plane QHH, k <= 5 (15 tabulated k up to 10; k <= 5 is where roots 1-8 are over
    most of 30-450 m/s): strict per-entry error max_k |dQ_ij| / max_k |Q_ij| < 2 % for every entry
    with aerodynamics (modes 5 and 10 have none: |Q| ~ 1e-14 of the largest), overall < 2 %, and
    Q matched exactly at the smallest k (0.001): Q(0) and the k -> 0 slope."""
    gaf = bah_qhh_dataset()
    fit = fit_roger(gaf, mach, k_max=5.0)
    assert fit.k_max == 5.0 and fit.k.size == 12
    assert fit.fit_error < 0.02, fit.fit_error
    assert fit.overall_error < 0.02
    assert np.all(fit.entry_error[[4, 9], :] == 0) and np.all(fit.entry_error[:, [4, 9]] == 0)
    Q0 = gaf.Q.sel(mach=mach).isel(k=0).values
    np.testing.assert_allclose(fit.evaluate(gaf.k.values[:1])[0], Q0, rtol=0,
                               atol=1e-12 * abs(Q0).max())


def test_bah_four_real_lags_are_not_enough():
    """Roger with 4 optimised real lags only misses the strict 2 % on the same data (why the fit has
    complex lag pairs)."""
    fit = fit_roger(bah_qhh_dataset(), 0.2, k_max=5.0, nlag=4, npair=0)
    assert fit.fit_error > 0.05


def test_theodorsen_fit_under_two_percent():
    """Theodorsen typical section (analytic Q(k), aero.strip.section_gaf), k 0.001-2."""
    Q = section_gaf(K_THEO, -0.2, 1.0)
    fit = fit_rfa(K_THEO, Q, refc=2.0)
    assert fit.fit_error < 0.02 and fit.overall_error < 0.02
    np.testing.assert_allclose(fit.evaluate(K_THEO), Q, atol=0.02 * np.abs(Q).max())


def test_bad_input_raises():
    gaf = bah_qhh_dataset()
    with pytest.raises(InputError, match="not tabulated"):
        fit_roger(gaf, 0.5)
    with pytest.raises(InputError, match="> 0"):
        fit_rfa(np.array([0.0, 0.1, 0.2]), np.ones((3, 1, 1)), refc=1.0)
    with pytest.raises(InputError, match="cannot fit"):
        fit_rfa(K_THEO[:4], section_gaf(K_THEO[:4], -0.2, 1.0), refc=2.0)
