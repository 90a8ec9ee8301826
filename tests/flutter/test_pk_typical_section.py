"""p-k on the Hodges & Pierce typical section with Theodorsen aerodynamics (analytic references).

Hodges & Pierce, Introduction to Structural Dynamics and Aeroelasticity, 2nd ed. (2011), sec. 5.5.3
and Fig. 5.22-5.23: a = -1/5, e = -1/10, mu = 20, r^2 = 6/25, sigma = 2/5 flutters at
U/(b omega_theta) ~ 2.17-2.18 with omega/omega_theta ~ 0.65; its divergence speed is analytic,
U_D/(b omega_theta) = sqrt(mu r^2 / (1 + 2a)) = 2.828 (H&P eq. 5.44 for the typical section).
"""
from __future__ import annotations

import warnings

import numpy as np
import pytest
import xarray as xr

from aero.strip import section_gaf
from flutter.kmethod import k_solve
from flutter.pk import pk_solve
from flutter.system import ModalSystem, StructuralDamping
from structures.common.errors import InputError
import flutter_plain_pk as plain

A, E, MU, R2, SIGMA = -0.2, -0.1, 20.0, 0.24, 0.4
B = 1.0
RHO = 1.0


def section(structural=StructuralDamping()):
    """Plunge/pitch section with b = 1, omega_theta = 1, rho = 1."""
    m = MU * np.pi * RHO * B * B
    xt = E - A
    M = np.array([[m, m * B * xt], [m * B * xt, m * R2 * B * B]])
    K = np.diag([m * SIGMA ** 2, m * R2 * B * B])
    return ModalSystem(M, K, structural=structural)


def gaf(mach, k):
    return section_gaf(k, A, B)


@pytest.fixture(scope="module")
def sweep():
    V = np.linspace(0.05, 3.2, 64)
    return pk_solve(section(), gaf, V, density=RHO, mach=0.0, refc=2 * B)


def test_flutter_speed_and_frequency(sweep):
    fl = sweep.crossing_kind.values == "flutter"
    assert fl.sum() == 1
    U = float(sweep.crossing_velocity[fl][0])
    w = 2 * np.pi * float(sweep.crossing_frequency[fl][0])
    assert 2.17 * 0.98 <= U <= 2.18 * 1.02
    assert abs(w / 0.65 - 1) < 0.03


def test_divergence_speed_analytic(sweep):
    dv = sweep.crossing_kind.values == "divergence"
    assert dv.sum() == 1
    U_D = np.sqrt(MU * R2 / (1 + 2 * A))
    assert abs(float(sweep.crossing_velocity[dv][0]) / U_D - 1) < 1e-3
    assert float(sweep.crossing_frequency[dv][0]) == 0.0


@pytest.mark.parametrize("kind", ["hysteretic", "viscous"])
def test_zero_speed_limit_in_vacuo(kind):
    """V -> 0 with vanishing air (rho -> 0): in-vacuo frequencies and g -> -g_s (stable by g_s).

    Exactly: viscous b = g_s omega0 gives p = omega0 (-g_s/2 + i sqrt(1 - g_s^2/4)); the hysteretic
    form (g_s/omega) K at the root's omega gives omega^2 = omega0^2 (1 + sqrt(1 - g_s^2)) / 2 and
    Re p = -g_s omega0^2 / (2 omega)."""
    gs = 0.03
    sys_ = section(StructuralDamping(g=gs, kind=kind))
    ds = pk_solve(sys_, gaf, [1e-4, 2e-4], density=1e-9, mach=0.0, refc=2 * B)
    omega, _ = sys_.in_vacuo()
    c = np.sqrt(1 - gs ** 2 / 4) if kind == "viscous" else np.sqrt((1 + np.sqrt(1 - gs ** 2)) / 2)
    g_exact = -gs / c if kind == "viscous" else -gs / c ** 2
    np.testing.assert_allclose(ds.frequency.isel(velocity=0).values * 2 * np.pi, omega * c, rtol=1e-6)
    np.testing.assert_allclose(ds.damping.isel(velocity=0).values, g_exact, rtol=1e-6)
    undamped = pk_solve(section(), gaf, [1e-4], density=1e-9, mach=0.0, refc=2 * B)
    assert np.abs(undamped.damping.values).max() < 1e-8


def test_zero_speed_limit_still_air():
    """V -> 0 in still air: the circulatory terms vanish and Theodorsen's apparent mass
    pi rho b^2 [[1, -b a], [-b a, b^2 (1/8 + a^2)]] remains (H&P eq. 5.303-5.304)."""
    sys_ = section()
    Ma = np.pi * RHO * B ** 2 * np.array([[1.0, -B * A], [-B * A, B ** 2 * (0.125 + A ** 2)]])
    lam = np.linalg.eigvals(np.linalg.solve(sys_.mass + Ma, sys_.stiffness))
    ds = pk_solve(sys_, gaf, [1e-5, 2e-5], density=RHO, mach=0.0, refc=2 * B)
    np.testing.assert_allclose(ds.frequency.isel(velocity=0).values * 2 * np.pi,
                               np.sort(np.sqrt(lam.real)), rtol=1e-4)
    assert np.abs(ds.damping.isel(velocity=0).values).max() < 1e-3


def test_fast_matches_plain_per_root(sweep):
    """Continuation p-k vs a plain per-root p-k with a full eigen-decomposition per iteration."""
    sys_ = section()
    kg = np.linspace(1e-3, 25.0, 25000)
    q_of_k = plain.make_q(kg, section_gaf(kg, A, B))
    fl = int(np.flatnonzero(sweep.crossing_kind.values == "flutter")[0])
    r = int(sweep.crossing_root[fl]) - 1
    V = sweep.velocity.values
    P = plain.sweep(sys_.mass, sys_.stiffness, sys_.damping, q_of_k, B, V, RHO,
                    [complex(sweep.eigenvalue.values[0, r])])[:, 0]
    np.testing.assert_allclose(P, sweep.eigenvalue.values[:, r], rtol=2e-3)
    g = plain.damping(P)
    i = int(np.flatnonzero((g[:-1] < 0) & (g[1:] > 0))[0])
    Vc, fc = plain.crossing(sys_.mass, sys_.stiffness, sys_.damping, q_of_k, B, V[i], V[i + 1], RHO, P[i])
    assert abs(float(sweep.crossing_velocity[fl]) / Vc - 1) < 1e-3
    assert abs(float(sweep.crossing_frequency[fl]) / fc - 1) < 1e-3


def test_k_method_cross_check(sweep):
    """The k-method's g = 0 point is the p-k flutter point (same harmonic solution)."""
    ks = np.linspace(0.05, 1.5, 3000)
    kd = k_solve(section(), gaf, ks, density=RHO, mach=0.0, refc=2 * B)
    fl = int(np.flatnonzero(sweep.crossing_kind.values == "flutter")[0])
    assert kd.sizes["crossing"] >= 1
    j = int(np.argmin(np.abs(kd.crossing_velocity.values - float(sweep.crossing_velocity[fl]))))
    assert abs(float(kd.crossing_velocity[j]) / float(sweep.crossing_velocity[fl]) - 1) < 2e-3
    assert abs(float(kd.crossing_frequency[j]) / float(sweep.crossing_frequency[fl]) - 1) < 2e-3


def test_velocity_not_increasing():
    with pytest.raises(InputError, match="not strictly increasing at points 2 and 3"):
        pk_solve(section(), gaf, [0.5, 1.0, 0.9], density=RHO, mach=0.0, refc=2 * B)


def test_nan_in_qhh():
    k = np.array([0.01, 0.1, 1.0, 3.0])
    Q = section_gaf(k, A, B)
    Q[2, 1, 0] = np.nan
    ds = xr.Dataset({"Q": (("mach", "k", "mode_i", "mode_j"), Q[None])},
                    coords={"mach": [0.0], "k": k, "mode_i": [1, 2], "mode_j": [1, 2]},
                    attrs={"refc": 2.0, "rhoref": 1.0})
    with pytest.raises(InputError, match=r"NaN/inf \(first at mach=0.0, k=1.0, mode_i=2, mode_j=1\)"):
        pk_solve(section(), ds, [1.0, 2.0], density=RHO, mach=0.0)


def test_k_range_not_covering_roots():
    """GAFs tabulated only up to k = 0.2: the low-speed roots need more; warning and flag."""
    k = np.linspace(0.01, 0.2, 8)
    ds = xr.Dataset({"Q": (("mach", "k", "mode_i", "mode_j"), section_gaf(k, A, B)[None])},
                    coords={"mach": [0.0], "k": k, "mode_i": [1, 2], "mode_j": [1, 2]},
                    attrs={"refc": 2.0, "rhoref": 1.0})
    with pytest.warns(RuntimeWarning, match=r"root 2 needs k=[0-9.]+ at V=1 .*outside the tabulated"):
        out = pk_solve(section(), ds, [1.0, 2.0, 3.0], density=RHO, mach=0.0)
    assert not bool(out.converged.sel(root=2, velocity=1.0))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        ok = pk_solve(section(), ds, [8.0, 9.0], density=RHO, mach=0.0)
    assert bool(ok.converged.all())


def test_mach_outside_table():
    k = np.linspace(0.01, 3, 8)
    ds = xr.Dataset({"Q": (("mach", "k", "mode_i", "mode_j"), section_gaf(k, A, B)[None])},
                    coords={"mach": [0.3], "k": k, "mode_i": [1, 2], "mode_j": [1, 2]},
                    attrs={"refc": 2.0, "rhoref": 1.0})
    with pytest.raises(InputError, match="Mach 0.5 is outside the tabulated Mach numbers"):
        pk_solve(section(), ds, [1.0], density=RHO, mach=0.5)
