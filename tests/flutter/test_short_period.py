"""The rigid aircraft's plunge-pitch characteristic equation against the textbook short-period
approximation, dimensional analysis and the flutter conventions (analytic references only; the
bah_plane check against Nastran is in tests/aero/test_stability.py)."""
from __future__ import annotations

import numpy as np
import pytest

from aero.stability import StabilityDerivatives
from flutter.short_period import ROOT_LABELS, short_period, short_period_approximation
from structures.common.errors import InputError

#: A transport-like aircraft: S 100 m^2, c 5 m, m 50 t, I_yy 2e6 kg m^2 (relative density
#: 2 m / (rho S c) = 500 at rho 0.4).
MASS, IYY, RHO = 5.0e4, 2.0e6, 0.4


def derivs(**change) -> StabilityDerivatives:
    values = dict(cl_alpha=5.0, cm_alpha=-1.0, cl_q=6.0, cm_q=-20.0, cl_alphadot=1.0,
                  cm_alphadot=-6.0, reference_area=100.0, reference_chord=5.0,
                  reference_point=np.zeros(3), mach=0.5)
    return StabilityDerivatives(**{**values, **change})


def natural(ds) -> tuple[np.ndarray, np.ndarray]:
    """omega_n = |p| and zeta = -Re p / |p| of the short period (root 1)."""
    p = ds["eigenvalue"].sel(root=1).values
    return np.abs(p), -p.real / np.abs(p)


def test_approximation_is_exact_without_lift_rate_terms():
    """With C_L_q = C_L_alphadot = 0 the alpha-q equations are the ones the textbook approximation
    solves (Nelson ch. 4: (s - Z_a/V)(s - M_q) - (M_a + M_adot s) = 0): same omega_n and zeta to
    rounding, at several speeds."""
    d = derivs(cl_q=0.0, cl_alphadot=0.0)
    v = np.array([80.0, 150.0, 240.0])
    omega, zeta = short_period_approximation(d, MASS, IYY, RHO, v)
    got = natural(short_period(d, MASS, IYY, RHO, v))
    np.testing.assert_allclose(got[0], omega, rtol=1e-10)
    np.testing.assert_allclose(got[1], zeta, rtol=1e-10)


def test_approximation_accurate_for_a_heavy_aircraft():
    """With the lift-rate terms (C_L_q = 6, C_L_alphadot = 1) and relative density 500 the
    approximation is within 1 % in omega_n and zeta (the neglected terms are
    rho S c C_L_q / (4 m) = 0.6 % of m V)."""
    v = np.array([80.0, 150.0, 240.0])
    omega, zeta = short_period_approximation(derivs(), MASS, IYY, RHO, v)
    got = natural(short_period(derivs(), MASS, IYY, RHO, v))
    np.testing.assert_allclose(got[0], omega, rtol=0.01)
    np.testing.assert_allclose(got[1], zeta, rtol=0.01)


def test_alphadot_on_pitch_rate_only_adds_z_alpha_m_alphadot_to_the_stiffness():
    """Applying the alpha-dot derivatives to q only (the quasi-steady modal truncation) keeps the
    damping sum -(M_q + M_adot + Z_a/V) and adds Z_a M_adot / V to omega_n^2 (derivation in
    flutter.short_period); C_L_q = C_L_alphadot = 0 so that the exact roots are those of the
    quadratic."""
    d = derivs(cl_q=0.0, cl_alphadot=0.0)
    v = 150.0
    qs = 0.5 * RHO * v * v * 100.0
    c_hat = 5.0 / (2.0 * v)
    z_a = -qs * 5.0 / MASS
    m_adot = qs * 5.0 * (-6.0) * c_hat / IYY
    omega, zeta = short_period_approximation(d, MASS, IYY, RHO, [v])
    w2 = omega[0] ** 2 + z_a * m_adot / v
    got = natural(short_period(d, MASS, IYY, RHO, [v], alphadot="pitch_rate"))
    assert got[0][0] == pytest.approx(np.sqrt(w2), rel=1e-10)
    assert got[0][0] * got[1][0] == pytest.approx(omega[0] * zeta[0], rel=1e-10)


def test_roots_scale_with_speed_and_layout():
    """Every term scales so that p is proportional to V at fixed density and derivatives: g and
    f / V are the same at every speed; roots 3 and 4 (flight-path angle and altitude) are zero;
    roots 1 and 2 are the same oscillatory short period; units and conventions in attrs."""
    v = np.array([50.0, 100.0, 200.0])
    ds = short_period(derivs(), MASS, IYY, RHO, v)
    assert ds["eigenvalue"].dims == ("velocity", "root")
    assert list(ds["root_label"].values) == list(ROOT_LABELS)
    p = ds["eigenvalue"].values
    np.testing.assert_allclose(p[:, 0] / v, p[0, 0] / v[0], rtol=1e-12)
    np.testing.assert_array_equal(p[:, 1], p[:, 0])
    assert np.all(p[:, 2:] == 0) and np.all(ds["damping"].values[:, 2:] == 0)
    assert np.all(p[:, 0].imag > 0) and np.all(p[:, 0].real < 0)
    np.testing.assert_allclose(ds["damping"].values[:, 0], 2 * p[:, 0].real / p[:, 0].imag)
    np.testing.assert_allclose(ds["frequency"].values[:, 0], p[:, 0].imag / (2 * np.pi))
    np.testing.assert_allclose(ds["k"].values[:, 0], p[:, 0].imag * 2.5 / v)
    assert ds["frequency"].attrs["units"] == "Hz" and ds.attrs["alphadot"] == "alpha"


def test_statically_unstable_aircraft_has_real_roots_with_nastran_g():
    """C_m_alpha > 0 beyond the pitch damping's reach: the short period splits into two real
    roots, one positive (divergence in pitch); g = p c / (V ln 2) as Nastran prints for real
    roots, frequency 0; the product of the roots is -M_a + Z_a M_q / V (C_L rate terms zero)."""
    d = derivs(cm_alpha=+2.0, cl_q=0.0, cl_alphadot=0.0, cm_alphadot=0.0)
    v = 100.0
    ds = short_period(d, MASS, IYY, RHO, [v])
    p = ds["eigenvalue"].values[0, :2]
    assert np.all(p.imag == 0) and p[0].real > 0 > p[1].real
    np.testing.assert_allclose(ds["damping"].values[0, :2], p.real * 5.0 / (v * np.log(2.0)))
    assert np.all(ds["frequency"].values[0] == 0)
    qs = 0.5 * RHO * v * v * 100.0
    m_a, z_a = qs * 5.0 * 2.0 / IYY, -qs * 5.0 / MASS
    m_q = qs * 5.0 * (-20.0) * (5.0 / (2 * v)) / IYY
    assert (p[0] * p[1]).real == pytest.approx(-m_a + z_a * m_q / v, rel=1e-10)
    omega, _ = short_period_approximation(d, MASS, IYY, RHO, [v])
    assert np.isnan(omega[0])


def test_one_set_of_derivatives_per_speed():
    """A list of derivatives, one per speed, gives at each speed the root of that set alone."""
    v = np.array([80.0, 150.0])
    sets = [derivs(), derivs(cm_alpha=-1.5, cl_alpha=5.5)]
    both = short_period(sets, MASS, IYY, RHO, v)
    for i in range(2):
        alone = short_period(sets[i], MASS, IYY, RHO, v[i:i + 1])
        np.testing.assert_allclose(both["eigenvalue"].values[i], alone["eigenvalue"].values[0],
                                   rtol=1e-13)
    with pytest.raises(InputError, match=r"1 sets of derivatives for 2 velocities"):
        short_period(sets[:1], MASS, IYY, RHO, v)
    with pytest.raises(InputError, match=r"different reference areas"):
        short_period([derivs(), derivs(reference_area=50.0)], MASS, IYY, RHO, v)


def test_bad_input_is_rejected():
    with pytest.raises(InputError, match=r"alphadot='beta' unknown"):
        short_period(derivs(), MASS, IYY, RHO, [100.0], alphadot="beta")
    with pytest.raises(InputError, match=r"velocities \[-1\.0\]"):
        short_period(derivs(), MASS, IYY, RHO, [-1.0])
    with pytest.raises(InputError, match=r"mass=0"):
        short_period(derivs(), 0, IYY, RHO, [100.0])
    with pytest.raises(InputError, match=r"lacks \['cl_alpha'"):
        short_period(object(), MASS, IYY, RHO, [100.0])
    with pytest.raises(InputError, match=r"reference area"):
        derivs(reference_area=0.0)
