"""The p-method on a rational fit of the GAFs (flutter.pmethod, method "P-RFA"): an exact rational
case, Theodorsen's typical section against p-k, and Nastran's bah_plane (QHH, generalized mass and
stiffness, F06 FLUTTER SUMMARY)."""
from __future__ import annotations

import warnings

import control
import numpy as np
import pytest
import xarray as xr

from aero.rfa import _basis, fit_rfa, fit_roger
from aero.strip import section_gaf
from flutter.pk import pk_solve
from flutter.pmethod import aeroelastic_statespace, p_solve, p_solve_many
from flutter.system import ModalSystem, StructuralDamping
from flutter.tracking import assign
from flutter_nastran import (DATA, bah_qhh_dataset, f06_flutter_summaries, f06_modes_used,
                             first_crossing)
from structures.common.errors import InputError
from test_pk_typical_section import A, B, section

F06 = DATA / "bah_plane" / "bah_plane.f06"
K_THEO = np.concatenate([[0.001, 0.01, 0.02, 0.05], np.linspace(0.1, 2.0, 20)])
K_MAX = 5.0   # bah fit range (see tests/aero/test_rfa.py)


def _gaf(k, Q, mach=0.0, refc=2.0):
    n = Q.shape[-1]
    return xr.Dataset({"Q": (("mach", "k", "mode_i", "mode_j"), Q[None])},
                      coords={"mach": [mach], "k": k, "mode_i": np.arange(1, n + 1),
                              "mode_j": np.arange(1, n + 1)}, attrs={"refc": refc})


def test_exact_rational_gafs_give_the_known_roots():
    """Q(ik) = A0 + A1 ik + A2 (ik)^2 + A3 ik / (ik + beta) exactly (one lag, beta = 0.4): the
    fitted p-method's roots are roots of the cubic matrix polynomial (p_bar + beta) [M p^2 + B p +
    K - q (A0 + A1 p_bar + A2 p_bar^2)] - q A3 p_bar (p_bar = p b / V), solved here by its own
    block companion matrix, to 1e-8 relative, at every speed."""
    rng = np.random.default_rng(7)
    n, beta, b = 3, 0.4, 1.0
    M = np.diag([1.0, 1.5, 2.0])
    K = np.diag([4.0, 25.0, 90.0])
    Bv = 0.01 * K
    Acoef = 0.3 * rng.normal(size=(4, n, n))
    k = np.linspace(0.02, 3.0, 30)
    Q = np.einsum("kt,tij->kij", _basis(1j * k, np.array([beta]), np.zeros((0, 2))), Acoef)
    V = np.linspace(0.5, 3.0, 6)
    ds = p_solve(ModalSystem(M, K, damping=Bv), _gaf(k, Q, refc=2 * b), V, density=1.0, mach=0.0,
                 fit=fit_rfa, fit_options={"nlag": 1, "npair": 0})
    assert ds.attrs["method"] == "P-RFA" and ds.attrs["rfa_fit_error"] < 1e-10
    np.testing.assert_allclose(ds.attrs["lags"], [beta], rtol=1e-8)
    for i, v in enumerate(V):
        q, c = 0.5 * v * v, b / v
        Mp, Bp, Kp = M - q * c * c * Acoef[2], Bv - q * c * Acoef[1], K - q * Acoef[0]
        C3, C2, C0 = c * Mp, beta * Mp + c * Bp, beta * Kp
        C1 = beta * Bp + c * Kp - q * c * Acoef[3]
        inv = np.linalg.inv(C3)
        Z, I = np.zeros((n, n)), np.eye(n)
        comp = np.block([[Z, I, Z], [Z, Z, I], [-inv @ C0, -inv @ C1, -inv @ C2]])
        ref = np.linalg.eigvals(comp)
        for p in ds.eigenvalue.values[i]:
            assert np.min(np.abs(ref - p)) <= 1e-8 * abs(p), (v, p)
        assert len(set(np.round(ds.eigenvalue.values[i], 6))) == n


def test_typical_section_flutter_matches_pk():
    """Theodorsen typical section: at g = 0 p-k is exact, so the P-RFA flutter point (fit error
    below 2 %) agrees with p-k within 1 % in speed and frequency."""
    sys_ = section()
    Q = section_gaf(K_THEO, A, B)
    ds = p_solve(sys_, _gaf(K_THEO, Q, refc=2 * B), np.linspace(0.05, 3.0, 60), density=1.0,
                 mach=0.0, fit=fit_rfa)
    assert ds.attrs["rfa_fit_error"] < 0.02
    pk = pk_solve(sys_, lambda m, k: section_gaf(k, A, B), np.linspace(0.05, 3.0, 60), density=1.0,
                  mach=0.0, refc=2 * B)
    fl = int(np.flatnonzero(pk.crossing_kind.values == "flutter")[0])
    assert list(ds.crossing_kind.values) == ["flutter"]
    assert abs(float(ds.crossing_velocity[0]) / float(pk.crossing_velocity[fl]) - 1) < 0.01
    assert abs(float(ds.crossing_frequency[0]) / float(pk.crossing_frequency[fl]) - 1) < 0.01
    assert bool(ds.crossing_converged[0])


def test_statespace_model_and_missing_fit():
    """The python-control model has 2 n + m states; no fit function is a loud error."""
    sys_ = section()
    fit = fit_rfa(K_THEO, section_gaf(K_THEO, A, B), refc=2 * B)
    ss = aeroelastic_statespace(sys_.mass, sys_.damping, sys_.stiffness, fit, 1.0, 1.0)
    m = fit.descriptor()[4].shape[0]
    assert isinstance(ss, control.StateSpace) and ss.nstates == 2 * 2 + m
    with pytest.raises(InputError, match="fit=aero.rfa.fit_rfa"):
        p_solve(sys_, _gaf(K_THEO, section_gaf(K_THEO, A, B)), [1.0, 2.0], density=1.0, mach=0.0)


@pytest.fixture(scope="module")
def bah():
    gaf = bah_qhh_dataset()
    gm, gk, _ = f06_modes_used(F06)
    system = ModalSystem(np.diag(gm), np.diag(gk))
    summaries = [s for s in f06_flutter_summaries(F06) if np.isclose(s["mach"], 0.2)]
    V = summaries[0]["rows"][:, 2]
    ds = p_solve(system, gaf, V, density=1.225, mach=0.2, fit=fit_rfa,
                 fit_options={"k_max": K_MAX})
    return dict(gaf=gaf, system=system, summaries=summaries, V=V, ds=ds)


def test_bah_elastic_flutter_matches_f06(bah):
    """One flutter crossing, root 4, within 1 % of the F06's (interpolated) crossing."""
    ds = bah["ds"]
    ref = first_crossing(next(s for s in bah["summaries"] if s["point"] == 4))
    flutter = np.flatnonzero(ds.crossing_kind.values == "flutter")
    assert flutter.size == 1
    i = int(flutter[0])
    assert int(ds.crossing_root[i]) == 4 and bool(ds.crossing_converged[i])
    assert abs(float(ds.crossing_velocity[i]) / ref["velocity"] - 1) < 0.01
    assert abs(float(ds.crossing_frequency[i]) / ref["frequency"] - 1) < 0.01
    assert ds.attrs["rfa_fit_error"] < 0.02 and ds.attrs["rfa_k_max"] == K_MAX


def test_bah_short_period_is_an_exact_root_of_the_fit(bah):
    """Root 1 is the short period (oscillatory, heavily damped, g < -2 from 30 to 200 m/s, as
    Nastran's point 2, g -2.29 to -2.6) and an exact root of the fitted model: the smallest singular
    value of M p^2 + K - q Q_fit(p b / V) (Q_fit evaluated off the imaginary axis) is below 1e-9 of
    the largest term."""
    ds, system = bah["ds"], bah["system"]
    fit = fit_roger(bah["gaf"], 0.2, k_max=K_MAX)
    for v in bah["V"][bah["V"] <= 200]:
        p = complex(ds.eigenvalue.sel(velocity=v, root=1))
        assert p.imag > 0 and float(ds.damping.sel(velocity=v, root=1)) < -2.0
        q = 0.5 * 1.225 * v * v
        Qp = np.einsum("t,tij->ij", _basis(np.array([p * 2.0 / v]), fit.beta, fit.pairs)[0], fit.A)
        T = system.mass * p * p + system.stiffness - q * Qp
        scale = max(np.abs(system.mass * p * p).max(), np.abs(q * Qp).max())
        assert np.linalg.svd(T, compute_uv=False)[-1] < 1e-9 * scale


def test_bah_fit_reproduces_nastran_pk_short_period(bah):
    """p-k on the fitted Q(ik) (instead of Nastran's tabulated QHH) reproduces Nastran's PK short
    period (point 2) at 30-200 m/s within 5 % in frequency and 10 % in g: the fit is right at the
    short period's k ~ 0.04. (The p-method's own short period differs from PK by ~20 % in frequency:
    PK evaluates Q on the imaginary axis at a root whose damping ratio is ~0.75.)"""
    fit = fit_roger(bah["gaf"], 0.2, k_max=K_MAX)
    rows = next(s for s in bah["summaries"] if s["point"] == 2)["rows"]
    sel = rows[:, 2] <= 200
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # roots 9-10 above the fitted k at 30 m/s
        pk = pk_solve(bah["system"], lambda m, k: fit.evaluate(k), rows[sel, 2], density=1.225,
                      mach=0.2, refc=4.0)
    np.testing.assert_allclose(pk.frequency.sel(root=1).values, rows[sel, 4], rtol=0.05)
    np.testing.assert_allclose(pk.damping.sel(root=1).values, rows[sel, 3], rtol=0.10)


def test_bah_no_oscillatory_root_unstable_below_flutter(bah):
    """Below the elastic flutter speed no oscillatory root has g > 1e-3 where its k is inside the
    fitted range; one root per mode; roots 9-10 (k > 5 below ~100-140 m/s) are flagged."""
    ds = bah["ds"]
    Vf = float(ds.crossing_velocity[np.flatnonzero(ds.crossing_kind.values == "flutter")[0]])
    below = ds.sel(velocity=ds.velocity < Vf)
    osc = (below.frequency > 0) & below.converged
    assert float(below.damping.where(osc).max()) < 1e-3
    assert ds.sizes["root"] == 10
    assert not bool(ds.converged.sel(root=10).isel(velocity=0))
    assert bool(ds.converged.sel(root=[1, 2, 3, 4, 5, 6]).all())


def test_density_sweep_matches_velocity_sweep(bah):
    """A density sweep (PKNL-like, matched-point lines) at 203.8 m/s ends at the flight point of the
    velocity sweep: same roots there (same model, same tracking from the in-vacuo modes) to 1e-9."""
    V = float(bah["V"][12])
    rho = np.linspace(0.4, 1.225, 5)
    dd = p_solve_many(bah["system"], bah["gaf"], [(V, rho, 0.2)], sweep="density", fit=fit_rfa,
                      fit_options={"k_max": K_MAX})[0]
    dv = bah["ds"].isel(velocity=12)
    assert dd.attrs["sweep"] == "density" and dd.sizes["density"] == 5
    np.testing.assert_allclose(dd.eigenvalue.isel(density=-1).values, dv.eigenvalue.values,
                               rtol=1e-9, atol=1e-9)


@pytest.mark.parametrize("kind", ["viscous", "hysteretic"])
def test_bah_structural_damping_is_modal_viscous(bah, kind):
    """The deck's TABDMP1 (g vs Hz) enters as modal viscous damping g_j omega_j for either kind (a
    hysteretic i g K has no rational form): root 5, which has no aerodynamics, shows g = -g(f5)."""
    from pyNastran.bdf.bdf import read_bdf

    tab = read_bdf(str(DATA / "bah_plane" / "bah_plane.bdf"), debug=None).tables_sdamping[2001]
    sd = StructuralDamping(frequency=tuple(tab.x), table_g=tuple(tab.y), kind=kind)
    system = bah["system"]
    damped = ModalSystem(system.mass, system.stiffness, structural=sd)
    ds = p_solve(damped, bah["gaf"], bah["V"][:3], density=1.225, mach=0.2, fit=fit_rfa,
                 fit_options={"k_max": K_MAX})
    f5 = np.sqrt(system.stiffness[4, 4]) / (2 * np.pi)
    np.testing.assert_allclose(ds.damping.sel(root=5).values, -sd.at(f5), rtol=1e-4)
    assert kind in ds.attrs["structural_damping"]


def test_assign_follows_vectors_not_order():
    """Two roots whose frequencies cross: correlation keeps each root on its own eigenvector,
    where sorting by frequency (or nearest eigenvalue alone) would swap them."""
    u = np.eye(2, dtype=complex)
    p_old = np.array([1.0j, 1.1j])
    p_new = np.array([1.12j, 1.08j])              # mode 1 now above mode 2
    U_new = np.eye(2, dtype=complex)
    assert assign(p_old, u, p_new, U_new).tolist() == [0, 1]
