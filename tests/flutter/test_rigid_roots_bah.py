"""Rigid-body roots of Nastran's bah_plane (free in plunge and pitch) by every flutter method.

Nastran's own QHH (OUTPUT4) and generalized mass and stiffness of FLUTTER 502 (PK, Mach 0.2, sea
level, 30-450 m/s) feed p-k (the default), the g-method and the p-method on a rational fit; the
F06's FLUTTER SUMMARY is the regression reference, the flight mechanics of the same aircraft
(stability derivatives of our own lattice, aero.stability; the plunge-pitch characteristic equation,
flutter.short_period) the independent one.

What the comparison shows (issue 13). The short period here is a root near critical damping
(zeta ~ 0.75, g ~ -2.3, |Re p_bar| ~ 1.15 k). The damping of p-k (Nastran's and ours) is exact only
at g = 0: it evaluates Q at p_bar = ik, so the k^2 part of Q^R (apparent mass, the alpha-dot lift
of plunge) acts as -k^2 instead of p_bar^2 = (Re p_bar)^2 - k^2 + 2 i k Re p_bar. Nastran's PK
point 2 therefore is not the exact short period, and no exact-damping method can match it within
the issue's 5 % / 10 %: the right references are

* for p-k: Nastran's PK (same approximation; our p-k within 1.2 %),
* for the exact damping: the p-method on a rational fit of the same QHH (fit error below 2 %,
  exact off the axis up to the fit) and, independently, flight mechanics with the alpha-dot
  derivatives on the angle of attack (Etkin & Reid's classical form) and the wing's elastic modes
  in quasi-static equilibrium: their natural frequency |p| agrees within 3 % and their decay rate
  Re p within 1.3 %, at every F06 speed 30-200 m/s; the damped frequency of a root with
  zeta ~ 0.75 amplifies differences (Im p = |p| sqrt(1 - zeta^2)): within 10 %,
* and the evidence that the gap to Nastran is the method, not the fit: p-k run on the fit's own
  Q(ik) gives Nastran's numbers (below).

The g-method (first order in Re p_bar about ik; here |Re p_bar| ~ k) falls between: its |p| is
10-15 % above the p-method's (tests/flutter/test_gmethod.py records it against the F06).
"""
from __future__ import annotations

import warnings

import numpy as np
import pytest

from aero.model import read_aero_model
from aero.rfa import fit_rfa
from aero.stability import flexible_derivatives, longitudinal_inertia
from flutter.crossings import G_TOL
from flutter.gmethod import g_solve
from flutter.pk import pk_solve
from flutter.pmethod import p_solve
from flutter.rigid_roots import root_labels
from flutter.short_period import short_period
from flutter.system import ModalSystem
from flutter_nastran import DATA, bah_qhh_dataset, f06_flutter_summaries, f06_modes_used, first_crossing
from structures.bdf import read_model
from structures.massprops import mass_properties
from structures.modal import compute_modes

F06 = DATA / "bah_plane" / "bah_plane.f06"
DECK = DATA / "bah_plane" / "bah_plane.bdf"
RHO, MACH = 1.225, 0.2           # FLUTTER 502: FLFACT 4 (density ratio 1 x RHOREF) and 5 (Mach)
V_MAX_COMPARED = 200.0           # the range: 30-200 m/s


def _summary(point: int) -> dict:
    """Nastran's PK point ``point`` at Mach 0.2 (``rows``: k, 1/k, V, g, f, Re, Im)."""
    return next(s for s in f06_flutter_summaries(F06)
                if np.isclose(s["mach"], MACH) and s["point"] == point)


@pytest.fixture(scope="module")
def solved():
    """Every method on Nastran's QHH at the F06's velocities, and Nastran's points 2 and 4."""
    gaf = bah_qhh_dataset()
    gm, gk, _ = f06_modes_used(F06)
    system = ModalSystem(np.diag(gm), np.diag(gk))
    rows = _summary(2)["rows"]
    V = rows[:, 2]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # roots 9-10 start above k = 10
        out = {"pk": pk_solve(system, gaf, V, density=RHO, mach=MACH),
               "g": g_solve(system, gaf, V, density=RHO, mach=MACH),
               "p": p_solve(system, gaf, V, density=RHO, mach=MACH, fit=fit_rfa)}
    omega = np.sqrt(np.maximum(gk / gm, 0.0))
    return dict(gaf=gaf, system=system, V=V, nastran=rows, omega=omega, **out)


def _short_period(ds, omega) -> np.ndarray:
    """Eigenvalues (npts,) of the root the labels name the short period."""
    labels = root_labels(ds, omega)
    assert labels.count("short period") == 1, labels
    return ds["eigenvalue"].isel(root=labels.index("short period")).values


def _nastran_p(rows) -> np.ndarray:
    return rows[:, 5] + 1j * rows[:, 6]


def test_default_method_short_period_is_nastrans_pk_point_2(solved):
    """p-k, the default, against Nastran's PK point 2 at every F06 speed 30-200 m/s: the issue's
    5 % in frequency and 10 % in g hold (measured 0.5-1.1 % and 1.0-1.2 %); both are p-k."""
    ds, rows = solved["pk"], solved["nastran"]
    sel = rows[:, 2] <= V_MAX_COMPARED
    p = _short_period(ds, solved["omega"])[sel]
    f, g = np.abs(p.imag) / (2 * np.pi), 2 * p.real / p.imag
    assert sel.sum() == 12
    np.testing.assert_allclose(f, rows[sel, 4], rtol=0.05)
    np.testing.assert_allclose(g, rows[sel, 3], rtol=0.10)


def test_exact_damping_short_period_flight_mechanics_and_p_method(solved):
    """Two independent exact-damping routes to the short period agree; Nastran's PK does not.

    The p-method on the rational fit of Nastran's QHH (strict fit error < 2 %) and the flight
    mechanics of the elastic aircraft (our lattice's derivatives, alpha-dot on alpha, the six wing
    modes in quasi-static equilibrium at each dynamic pressure) at every F06 speed 30-200 m/s:
    natural frequency |p| within 5 % (measured 1.6-2.8 %), Re p within 5 % (0.1-1.3 %), g within
    10 % (7.3-8.7 %), damped frequency within 10 % (6.6-9.8 %). Nastran's |p| is 12-17 % above
    the p-method's at every one of these speeds."""
    ds, rows = solved["p"], solved["nastran"]
    assert ds.attrs["rfa_fit_error"] < 0.02
    sel = rows[:, 2] <= V_MAX_COMPARED
    V = rows[sel, 2]
    exact = _short_period(ds, solved["omega"])[sel]
    model = read_model(DECK)
    aero = read_aero_model(DECK)
    props = mass_properties(model)
    mass, iyy = longitudinal_inertia(props, aero)
    derivs = flexible_derivatives(aero, compute_modes(model, 8), MACH, props.cg, 0.5 * RHO * V ** 2)
    fm = short_period(list(derivs), mass, iyy, RHO, V, alphadot="alpha").sel(root=1)
    p_fm = fm["eigenvalue"].values
    np.testing.assert_allclose(np.abs(p_fm), np.abs(exact), rtol=0.05)
    np.testing.assert_allclose(p_fm.real, exact.real, rtol=0.05)
    np.testing.assert_allclose(fm["damping"].values, 2 * exact.real / exact.imag, rtol=0.10)
    np.testing.assert_allclose(fm["frequency"].values, exact.imag / (2 * np.pi), rtol=0.10)
    gap = np.abs(_nastran_p(rows[sel])) / np.abs(exact) - 1
    assert np.all(gap > 0.10), gap


def test_the_gap_to_nastran_is_the_method_not_the_fit(solved):
    """p-k run on the rational fit's own Q(ik) (tabulated at the QHH's k) gives Nastran's PK
    point 2 within 2 % in frequency and g (the fit is faithful on the imaginary axis), while the
    exact roots of that same fit are 20-30 % lower in frequency: the gap is p-k's harmonic
    evaluation of a root near critical damping."""
    gaf, rows = solved["gaf"], solved["nastran"]
    sel = rows[:, 2] <= V_MAX_COMPARED
    k = gaf["k"].values
    fit = fit_rfa(k, gaf["Q"].sel(mach=MACH).transpose("k", "mode_i", "mode_j").values,
                  refc=gaf.attrs["refc"], mach=MACH, k_max=solved["p"].attrs["rfa_k_max"])
    on_axis = gaf.sel(mach=[MACH]).copy()
    on_axis["Q"] = (("mach", "k", "mode_i", "mode_j"), fit.evaluate(k)[None])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        ds = pk_solve(solved["system"], on_axis, rows[sel, 2], density=RHO, mach=MACH)
    p = _short_period(ds, solved["omega"])
    np.testing.assert_allclose(np.abs(p.imag) / (2 * np.pi), rows[sel, 4], rtol=0.02)
    np.testing.assert_allclose(2 * p.real / p.imag, rows[sel, 3], rtol=0.02)
    exact = _short_period(solved["p"], solved["omega"])[sel]
    assert np.all(exact.imag / p.imag < 0.85)


@pytest.mark.parametrize("method", ["pk", "g", "p"])
def test_elastic_flutter_and_no_earlier_instability(solved, method):
    """Every method: the elastic flutter point (root 4) within 0.5 % of Nastran's F06 crossing, no
    crossing before it, and no solved root unstable below it (g <= G_TOL), except the rigid-body drift
    root below the table's resolution (|p| b / V < k_min = 0.001, flutter.crossings: altitude and
    flight path, exactly zero without gravity; Nastran's own point 1 there is a real root of up
    to +0.024 rad/s)."""
    ds = solved[method]
    ref = first_crossing(_summary(4))
    flutter = [i for i in range(ds.sizes["crossing"]) if ds.crossing_kind.values[i] == "flutter"]
    first = int(np.argmin(ds.crossing_velocity.values))
    assert first in flutter and int(ds.crossing_root[first]) == 4
    V_f = float(ds.crossing_velocity[first])
    assert V_f == pytest.approx(ref["velocity"], rel=0.005)
    below = ds["velocity"].values < V_f
    p = ds["eigenvalue"].values[below]
    g = ds["damping"].values[below]
    solved_ = ds["converged"].values[below]    # k outside the table / fitted range: not solved
    drift = np.abs(p) * 2.0 / ds["velocity"].values[below, None] < 1e-3   # b = REFC / 2 = 2 m
    assert np.all((g <= G_TOL) | drift | ~solved_), np.argwhere((g > G_TOL) & ~drift & solved_)
    # roots 1-6 everywhere (p-method: roots 7-10 need k above its fitted range 5 at low speed)
    assert solved_[:, :6].all()
    assert drift.any(axis=0).sum() <= 1                      # one drift root: the plunge


def test_real_rigid_roots_against_the_f06(solved):
    """The rigid roots the F06 compare used to skip. Nastran's point 2 turns real between 334.1 and
    348.6 m/s; our short period (p-k) turns real in the same interval. Nastran's point 1 is the
    near-zero plunge / flight-path root, a real root of up to +0.024 rad/s below the flutter speed;
    ours (the drift root of the same exact double zero) stays smaller at every F06 speed below
    the flutter speed (0.0003 against 0.0009 rad/s at 30 m/s: the even continuation of the GAFs
    below the table removes most of the split)."""
    ds, rows = solved["pk"], solved["nastran"]
    V = rows[:, 2]
    labels = root_labels(ds, solved["omega"])
    sp = ds["eigenvalue"].isel(root=labels.index("short period")).values
    real_ours, real_nastran = np.abs(sp.imag) <= 1e-9 * np.abs(sp), rows[:, 6] == 0
    assert V[np.argmax(real_nastran)] == V[np.argmax(real_ours)] == pytest.approx(348.62, abs=0.01)
    assert not real_ours[:np.argmax(real_ours)].any()
    plunge = ds["eigenvalue"].isel(root=labels.index("plunge")).values
    point1 = _summary(1)["rows"]
    below = V < float(ds.crossing_velocity.min())
    assert np.all(np.abs(plunge[below]) <= np.abs(point1[below, 5] + 1j * point1[below, 6]))


def test_labels_do_not_depend_on_the_first_speed(solved):
    """A sweep that starts at 1 m/s has a short period of 0.0046 Hz there (|p| ~ V): it is still
    named the short period, not the plunge (near zero means far below the largest rigid root too)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        slow = pk_solve(solved["system"], solved["gaf"], np.linspace(1.0, 100.0, 10), density=RHO,
                        mach=MACH)
    labels = root_labels(slow, solved["omega"])
    p = slow["eigenvalue"].isel(velocity=0).values
    assert abs(p[labels.index("short period")]) / (2 * np.pi) < 0.005     # below NEAR_ZERO x 0.05 Hz
    assert labels[:2] == root_labels(solved["pk"], solved["omega"])[:2]
