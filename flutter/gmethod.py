"""Chen's g-method (damping perturbation) flutter solution along sweeps of flight points.

P. C. Chen, "Damping Perturbation Method for Flutter Solution: The g-Method", AIAA J. 38(9), 2000,
1519-1524. The equation, Chen's reduced-frequency sweep and the local root solve are in
flutter.gkernel; the roots along a sweep (one per mode, rigid-body roots started from the
quasi-steady branches, continuation with step checks and the sweep as fallback) in flutter.gtrack.
This module finds and refines the crossings and builds the result Datasets (flutter.results).

Divergence: a real root through p = 0 is a zero of det(K - q Q^R(0)), whatever the damping terms,
so besides the sign changes of the tracked roots' g, the dynamic pressures q_D of
(K - q_D Q^R(0)) u = 0 passed between two points are divergence crossings, given to the root whose
eigenvector correlates best with u. This matters because the real root that diverges need not be
the continuation of any modal root: on the Theodorsen typical section the g-method's pitch root
stays oscillatory and heavily damped past the divergence speed, as the exact root with the
generalized Theodorsen function does (U = 2.5 b w_theta: exact p = -0.445 + 0.517i, g-method
-0.505 + 0.488i), while p-k's turns real; the real root crossing zero at U_D is an extra root.

Interpolation: with ``interpolation="linear"`` dQ/dk is piecewise constant in k, so Q' and the
eigenvalues jump at the tabulated k values (with ``"cubic"`` only at the smallest tabulated k, where
the spline meets the even continuation below the table); a sign change of Im g at such a jump is no
root. It is refined to the jump and flagged not converged, and used only when a root has no other
candidate (bah_plane, cubic: such a jump at k_min = 0.001 gave a spurious g = +1.02 root at 378 m/s
before they were set aside). The g-method defaults to ``"cubic"`` (continuous slopes inside the
table); ``"linear"`` gives the same elastic flutter point on bah_plane within 0.15 %.
"""
from __future__ import annotations

import warnings

import numpy as np
import scipy.linalg as sla
import xarray as xr
from threadpoolctl import threadpool_limits

from flutter.crossings import (G_TOL, Crossing, crossing_at, drift_roots, find_brackets,
                               illinois, interpolate_zero, resolved_damping)
from flutter.gkernel import GProblem
from flutter.gtrack import match, sweep_roots
from flutter.parallel import map_cases
from flutter.pk import sweep_flights
from flutter.results import attach_crossings, vg_dataset
from flutter.system import ModalSystem
from structures.common.errors import InputError

__all__ = ["GProblem", "g_solve", "g_solve_many"]

OPTIONS = ("nk", "rigid_hz")


def _warn_outside(prob: GProblem, p, outside, V, mach) -> None:
    """One warning per root whose k leaves the tabulated GAF range (those points not converged)."""
    for r in range(prob.system.n):
        hits = np.flatnonzero(outside[:, r])
        if hits.size:
            i = int(hits[0])
            interp = prob.interpolator(mach[i])
            warnings.warn(
                f"g-method: root {r + 1} needs k={prob.b * abs(p[i, r].imag) / V[i]:.4g} at "
                f"V={V[i]:.6g} (Mach {mach[i]:g}), outside the tabulated k range "
                f"[{interp.k_min:g}, {interp.k_max:g}] at {hits.size} point(s); those points are "
                "marked not converged. Fix: extend the MKAERO1 k list.", RuntimeWarning, stacklevel=3)


def _static_divergence(prob: GProblem, pts, U, crossings) -> list[tuple[Crossing, np.ndarray]]:
    """Divergence crossings: dynamic pressures q_D of (K - q_D Q^R(0)) u = 0 passed between two
    points (static divergence: the real root at k = 0 is zero where det(K - q Q^R(0)) = 0), each given to
    the root whose eigenvector correlates best with u and skipped where a tracked root's own
    divergence crossing is already in that interval. A free aircraft's K and Q^R(0) share null
    vectors (rigid modes that neither K nor the steady air loads, e.g. plunge or surge), so the
    pencil is singular and some of its eigenvalues are rounding: a q_D counts only where the
    number of unstable real roots at k = 0 grows across the interval (X-56-class example: a
    spurious q_D at 1538 in/s, no real root through zero)."""
    out = []
    seen = {c.index for c in crossings if c.kind == "divergence"}

    def unstable(pt):
        lam = prob.eig(np.zeros(1), *pt, vectors=False)[0][0]
        return int(np.sum((lam.imag == 0) & (lam.real > 1e-12 * np.abs(lam).max())))

    for i in range(len(pts) - 1):
        (V0, r0, M0), (V1, r1, M1) = pts[i], pts[i + 1]
        q0, q1 = 0.5 * r0 * V0 * V0, 0.5 * r1 * V1 * V1
        if i in seen or not q1 > q0:
            continue

        def modes(mach):
            QR0 = prob.interpolator(mach).with_slopes(np.zeros(1), slopes=False)[0][0]
            lam, X = sla.eig(prob.system.stiffness, QR0)
            ok = np.isfinite(lam) & (np.abs(lam.imag) <= 1e-9 * np.abs(lam))
            return lam.real[ok], X[:, ok].T

        for qd, ud in zip(*modes(M0)):
            if not q0 < qd <= q1 or unstable(pts[i + 1]) <= unstable(pts[i]):
                continue
            t = (qd - q0) / (q1 - q0)
            for _ in range(20 if M1 != M0 else 0):   # Mach along the line: q_D(M(t)) = q(t)
                lam, X = modes(M0 + t * (M1 - M0))
                j = int(np.argmin(np.abs(lam - qd)))
                qd, ud = lam[j], X[j]
                t_new = float(np.clip((qd - q0) / (q1 - q0), 0.0, 1.0))
                if abs(t_new - t) < 1e-10:
                    break
                t = t_new
            ud = ud / np.linalg.norm(ud)
            r = int(np.argmax(np.abs(U[i].conj() @ ud)))
            out.append((crossing_at(r, i, t, pts[i], pts[i + 1], 0j, real=True, converged=True,
                                    refined=True), ud))
    return out


def _refine_crossing(prob: GProblem, pts, P, U, W, r, i, g0, g1):
    """Zero of root r's damping between points i and i+1 by Illinois root-finding on the flight
    point. Each evaluation solves root r alone from its linear interpolation between the two points
    (:meth:`GProblem.correct`); where that fails (e.g. the root turns real inside the bracket) a
    full reduced-frequency sweep is matched to the interpolated roots instead."""
    cache = {}

    def point(t):
        return tuple(a + t * (b - a) for a, b in zip(pts[i], pts[i + 1]))

    def fun(t):
        pt = point(t)
        s = prob.b / pt[0]
        guess = P[i] + t * (P[i + 1] - P[i])
        if P[i, r].imag == 0 or P[i + 1, r].imag == 0:
            guess[r] = guess[r].real if P[i, r].imag == P[i + 1, r].imag else P[i + (t >= 0.5), r]
        pb, u, _, ok, out = prob.correct(guess[r:r + 1] * s, U[i, r:r + 1], W[i, r:r + 1], *pt)
        if ok[0]:
            cache[t] = (pb[0] / s, u[0], not out[0])
        else:
            p, u, ok, out = prob.roots(*pt)
            pr, ur, okr, outr, miss = match(guess, U[i], p, u, ok, out)
            cache[t] = (pr[r], ur[r], bool(okr[r] and not outr[r] and not miss[r]))
        return float(prob.damping(cache[t][0], pt[0]))

    t, ok = illinois(fun, g0, g1)
    t = t if t in cache else min(cache, key=lambda s: abs(s - t))
    pr, ur, good = cache[t]
    # a root that changes branch inside the bracket gives a jump of g, not a zero
    small = abs(float(prob.damping(pr, point(t)[0]))) <= 1e-3 * max(abs(g0), abs(g1))
    return t, pr, ur, ok and good and small


def g_solve(system: ModalSystem, gaf, velocity, *, density, mach, sweep: str = "velocity",
            refc: float | None = None, interpolation: str = "cubic", refine: bool = True,
            g_tol: float = G_TOL, **options) -> xr.Dataset:
    """g-method flutter solution along a sweep of flight points (velocity, or density as PKNL).

    Parameters
    ----------
    system : ModalSystem
        M_hh, K_hh, B_hh and structural damping (hysteretic i g_s K, or modal viscous).
    gaf : xarray.Dataset or callable
        ``Q(mach, k, mode_i, mode_j)`` with attrs ``refc``, or ``gaf(mach, k) -> (nk, n, n)``.
    velocity, density, mach : array_like, shape (npts,) or scalar
        Flight points (broadcast); the swept one strictly increasing.
    sweep : {"velocity", "density"}
    refc : float, optional
        Reference chord; default ``gaf.attrs["refc"]``.
    interpolation : {"cubic", "linear"}
        Interpolation of Q in k; cubic by default (continuous dQ/dk, module docstring).
    refine : bool
        Locate crossings by root-finding on the flight point (else linear interpolation of g).
    g_tol : float
        Neutral-damping band for crossings.
    **options
        ``nk``: points of the k grid of the reduced-frequency sweep (default 60; used at the first
        point and where a continuation step fails); ``rigid_hz``: rigid-body mode threshold [Hz]
        (default 0.05).

    Returns
    -------
    xarray.Dataset
        As :func:`flutter.pk.pk_solve`, attrs ``method = "G"``: dims (sweep, root, mode),
        ``damping``, ``frequency`` [Hz], ``k``, ``eigenvalue``, ``eigenvector``, ``converged``;
        crossings on dim ``crossing``.
    """
    return g_solve_many(system, gaf, [(velocity, density, mach)], sweep=sweep, refc=refc,
                        interpolation=interpolation, refine=refine, g_tol=g_tol, **options)[0]


def g_solve_many(system: ModalSystem, gaf, cases, *, sweep: str = "velocity",
                 refc: float | None = None, interpolation: str = "cubic", refine: bool = True,
                 g_tol: float = G_TOL, workers: int = 1, **options) -> list[xr.Dataset]:
    """Several g-method sweeps (e.g. one per Mach number or density line).

    Parameters
    ----------
    system, gaf, sweep, refc, interpolation, refine, g_tol, **options
        As :func:`g_solve`.
    cases : list of (velocity, density, mach)
        Each an array_like of shape (npts_c,) or a scalar (broadcast).
    workers : int
        Processes to spread the cases over (:func:`flutter.parallel.map_cases`).

    Returns
    -------
    list of xarray.Dataset, one per case, as :func:`g_solve`.
    """
    if sweep not in ("velocity", "density"):
        raise InputError(f"g-method: unknown sweep {sweep!r}. Fix: use 'velocity' or 'density'.")
    if not (isinstance(workers, (int, np.integer)) and workers >= 1):
        raise InputError(f"g-method: workers = {workers!r}. Fix: give a whole number >= 1.")
    unknown = sorted(set(options) - set(OPTIONS))
    if unknown:
        raise InputError(f"g-method: unknown options {unknown}. Fix: use only {list(OPTIONS)}.")
    if workers > 1 and len(cases) > 1:
        settings = dict(sweep=sweep, refc=refc, interpolation=interpolation, refine=refine,
                        g_tol=g_tol, **options)
        return map_cases(lambda case: g_solve_many(system, gaf, [case], **settings)[0],
                         list(cases), workers)
    prob = GProblem(system, gaf, refc=refc, interpolation=interpolation, **options)
    out = []
    with threadpool_limits(limits=1, user_api="blas"):
        for V, rho, M in sweep_flights(cases, sweep):
            out.append(_case_dataset(prob, V, rho, M, sweep=sweep, interpolation=interpolation,
                                     refine=refine, g_tol=g_tol))
    return out


def _case_dataset(prob: GProblem, V, rho, M, *, sweep, interpolation, refine, g_tol) -> xr.Dataset:
    """Roots, warnings, crossings and the result Dataset of one sweep."""
    pts = list(zip(V, rho, M))
    p, u, w, conv, outside = sweep_roots(prob, pts)
    _warn_outside(prob, p, outside, V, M)
    g = prob.damping(p, V[:, None])
    crossings, vectors = [], []
    k_min = np.array([prob.interpolator(m).k_min for m in M])
    drift = drift_roots(p, V, prob.b, k_min, prob.omega0 < 2 * np.pi * prob.rigid_hz)
    for r, i in find_brackets(resolved_damping(g, drift), g_tol):
        if refine:
            t, pr, ur, ok = _refine_crossing(prob, pts, p, u, w, r, i, g[i, r], g[i + 1, r])
        else:
            t = interpolate_zero(g[i, r], g[i + 1, r])
            pr = p[i, r] + t * (p[i + 1, r] - p[i, r])
            ur, ok = (u[i, r] if t < 0.5 else u[i + 1, r]), True
        vectors.append(ur)
        crossings.append(crossing_at(r, i, t, pts[i], pts[i + 1], pr, real=pr.imag == 0,
                                     converged=ok and conv[i, r] and conv[i + 1, r],
                                     refined=refine))
    for c, ud in _static_divergence(prob, pts, u, crossings):
        crossings.append(c)
        vectors.append(ud)
    order = sorted(range(len(crossings)), key=lambda j: (crossings[j].index, crossings[j].root))
    crossings, vectors = [crossings[j] for j in order], [vectors[j] for j in order]
    system = prob.system
    ds = vg_dataset(p, u, g, conv, V, rho, M, b=prob.b, modes=system.modes, sweep=sweep,
                    method="G", attrs={"interpolation": interpolation, "g_tol": g_tol,
                                       "structural_damping": system.structural.kind
                                       if not system.structural.is_zero else "none"})
    return attach_crossings(ds, crossings, np.array(vectors).reshape(len(crossings), system.n))
