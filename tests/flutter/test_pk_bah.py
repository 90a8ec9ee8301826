"""Regression of the p-k solver against MSC Nastran on the BAH wing (tests/data/bah_plane).

Nastran's own QHH (OUTPUT4, bah_plane_qhh.op4) and generalized mass/stiffness (F06 eigenvalue table)
feed our p-k; the result is compared with the F06 FLUTTER SUMMARY of the PK subcase at Mach 0.2.
"""
from __future__ import annotations

import warnings

import numpy as np
import pytest

from flutter.pk import pk_solve
from flutter.system import ModalSystem, StructuralDamping
from flutter_nastran import bah_flutter_502, first_crossing
import flutter_plain_pk as plain


@pytest.fixture(scope="module")
def bah():
    case = bah_flutter_502()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # roots 9-10 start above k = 10 (checked below)
        ds = pk_solve(ModalSystem(np.diag(case["gm"]), np.diag(case["gk"])), case["gaf"], case["V"],
                      density=case["rho"], mach=case["mach"])
    return dict(case, tab=case["sdamp"], ds=ds)


def test_qhh_layout(bah):
    """The stacked OP4 layout (per MKAERO1 card, per Mach, per k): Im(Q) vanishes like k at the
    smallest k, the aerodynamic damping of the first flexible mode grows with k over the first
    card's k values, and the M 0 / M 0.2 blocks differ by a compressibility-sized amount at k <= 1."""
    Q = bah["gaf"].Q
    k = Q.k.values
    small = float(np.abs(Q.isel(k=0).imag).max() / np.abs(Q.isel(k=1).imag).max())
    assert small < 2 * k[0] / k[1]
    assert np.all(np.diff(np.abs(Q.imag.sel(mode_i=3, mode_j=3, k=slice(0, 1.5)).values), axis=1) > 0)
    low = Q.sel(k=slice(0, 1.0))
    rel = float(np.abs(low.sel(mach=0.2) - low.sel(mach=0.0)).max() / np.abs(low.sel(mach=0.0)).max())
    assert 0 < rel < 0.1


def test_flutter_crossing_matches_f06(bah):
    ref = [(s["point"], first_crossing(s)) for s in bah["summaries"]]
    ref = [(p, c) for p, c in ref if c is not None and c["frequency"] > 0]
    assert len(ref) == 1, ref  # the rigid roots' real-root sign changes have frequency 0
    root_ref, c = ref[0]
    V_ref, f_ref = c["velocity"], c["frequency"]
    ds = bah["ds"]
    flutter = [i for i in range(ds.sizes["crossing"]) if ds.crossing_kind.values[i] == "flutter"]
    assert len(flutter) == 1
    i = flutter[0]
    V, f = float(ds.crossing_velocity[i]), float(ds.crossing_frequency[i])
    assert abs(V / V_ref - 1) < 0.005, (V, V_ref)
    assert abs(f / f_ref - 1) < 0.005, (f, f_ref)
    assert int(ds.crossing_root[i]) == root_ref
    assert bool(ds.crossing_converged[i])


def test_neutral_and_rigid_roots_never_cross(bah):
    """|g| ~ 1e-15 roots (no aerodynamics) and the rigid roots give no crossing below 450 m/s."""
    ds = bah["ds"]
    neutral = [r for r in ds.root.values if np.abs(ds.damping.sel(root=r)).max() < 1e-6]
    assert len(neutral) >= 1
    crossed = set(ds.crossing_root.values.tolist())
    assert not crossed & set(neutral)
    assert crossed == {4}


def test_flexible_roots_follow_f06_curves(bah):
    """Each flexible root's V-g / V-f curve follows Nastran's (frequency 0.5%, g within 0.005).

    The residual (up to ~0.004 in g, 0.4% in frequency) comes from interpolating the 15 tabulated k
    values between them: we interpolate Q^R and Q^I/k linearly, which Nastran does not specify.
    """
    ds = bah["ds"]
    for s in bah["summaries"]:
        rows = s["rows"]
        if np.any(rows[:, 0] == 0) or rows[0, 4] < 2.0 or rows[0, 4] > 30.0:
            continue  # rigid / real roots, and roots outside the k table at low speed
        r = s["point"]
        f = ds.frequency.sel(root=r).values
        g = ds.damping.sel(root=r).values
        np.testing.assert_allclose(f, rows[:, 4], rtol=5e-3)
        np.testing.assert_allclose(g, rows[:, 3], atol=5e-3)


def test_k_above_table_warns_and_flags(bah):
    """Roots 9-10 need k > 10 at low speed: a warning naming root and k; points not converged."""
    gm, gk = bah["gm"], bah["gk"]
    with pytest.warns(RuntimeWarning, match=r"root 10 needs k=2[0-9.]+ at V=30"):
        ds = pk_solve(ModalSystem(np.diag(gm), np.diag(gk)), bah["gaf"], bah["V"][:4],
                      density=bah["rho"], mach=bah["mach"])
    assert not bool(ds.converged.sel(root=10).isel(velocity=0))
    assert bool(ds.converged.sel(root=4).all())


def test_tabdmp1_structural_damping(bah):
    """The deck's TABDMP1 (g vs Hz), applied as Nastran modal damping, shows as g = -g(f) on a root
    without aerodynamics and delays flutter. The F06 itself was run without it (no SDAMP in case
    control: root 5 has g = 0 there), which is why the regression above uses no damping."""
    tab = bah["tab"]
    sd = StructuralDamping(frequency=tuple(tab.x), table_g=tuple(tab.y), kind="viscous")
    gm, gk = bah["gm"], bah["gk"]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        ds = pk_solve(ModalSystem(np.diag(gm), np.diag(gk), structural=sd), bah["gaf"], bah["V"],
                      density=bah["rho"], mach=bah["mach"])
    f5 = np.sqrt(gk[4]) / (2 * np.pi)
    np.testing.assert_allclose(ds.damping.sel(root=5).values, -sd.at(f5), rtol=1e-4)
    assert np.all(ds.damping.sel(root=5).values != 0)
    V_damped = float(ds.crossing_velocity[ds.crossing_kind == "flutter"][0])
    V_plain = float(bah["ds"].crossing_velocity[0])
    assert V_damped > V_plain * 1.005


def test_fast_pk_matches_plain_per_root_pk(bah):
    """Continuation + Rayleigh-quotient p-k vs a plain per-root p-k (full eig per iteration): 0.1%."""
    gaf = bah["gaf"].sel(mach=bah["mach"])
    q_of_k = plain.make_q(gaf.k.values, gaf.Q.values)
    M, K = np.diag(bah["gm"]), np.diag(bah["gk"])
    V = bah["V"]
    b = 0.5 * bah["gaf"].attrs["refc"]
    ds = bah["ds"]
    r = 4
    p0 = complex(ds.eigenvalue.sel(root=r).values[0])
    P = plain.sweep(M, K, np.zeros_like(M), q_of_k, b, V, bah["rho"], [p0])[:, 0]
    g = plain.damping(P)
    i = int(np.flatnonzero((g[:-1] < 0) & (g[1:] > 0))[0])
    Vc, fc = plain.crossing(M, K, np.zeros_like(M), q_of_k, b, V[i], V[i + 1], bah["rho"], P[i])
    assert abs(float(ds.crossing_velocity[0]) / Vc - 1) < 1e-3
    assert abs(float(ds.crossing_frequency[0]) / fc - 1) < 1e-3
    np.testing.assert_allclose(ds.eigenvalue.sel(root=r).values, P, rtol=1e-6)
