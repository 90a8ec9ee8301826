"""The p-method on a rational approximation of the GAFs ("P-RFA"): exact roots of the fitted model.

With a rational fit Q(p_bar) = A0 + A1 p_bar + A2 p_bar^2 + D (p_bar I - R)^-1 E p_bar of the GAFs
(p_bar = s b / V, b = REFC / 2; fitted by aero.rfa and passed in as the ``fit`` callable: flutter/
calls no aerodynamics), the flutter equation [M s^2 + B s + K - q Q(s b / V)] u = 0
(q = rho V^2 / 2) is the linear time-invariant system of Karpel, J. Aircraft 19(3), 1982, eq. 4-6:

    Mbar = M - q (b/V)^2 A2,  Bbar = B - q (b/V) A1,  Kbar = K - q A0,
    u'' = Mbar^-1 (-Kbar u - Bbar u' + q D x),   x' = E u' + (V/b) R x,

whose eigenvalues at a flight point (V, rho, M) are all roots of the fitted model at once, exact
off the imaginary axis (no harmonic assumption: the damping of strongly damped and real roots, such
as the short period and the plunge of a free-free aircraft, is exact up to the fit error). Of the
2 n + m eigenvalues, the structural roots are kept, one per mode (Im p >= 0; real roots too), and
the aerodynamic lag roots left out: every root is followed by continuity and eigenvector
correlation (flutter.tracking.assign on the modal part u) from its in-vacuo mode, first along the
dynamic pressure at the first flight point (q from 1e-14 of its value, where lag roots carry no
structural motion) and then along the sweep, bisecting a step whose roots jump or lose correlation.
Root r starts from in-vacuo mode r (rigid modes first; as in p-k, the rigid roots at the first
flight point go to the rigid modes they participate in most). A pair that splits into two real
roots keeps the real root that continues it best.

Conventions (flutter package): p = omega (gamma + i), g = 2 Re p / Im p; a real root (Im p = 0) has
Nastran's g = p cbar / (V ln 2); k = omega b / V. Points where a root's k exceeds the fitted k range
(the rational function is then extrapolated; default range :func:`fit_range`) are flagged not
converged. Rigid-body drift roots below the table's resolution give no crossings
(flutter.crossings.drift_roots). Structural damping enters
as viscous modal damping g_j omega_j at each in-vacuo mode (ModalSystem.viscous_structural) for
either kind: hysteretic i g K is not a rational function of s, and its viscous equivalent is exact
at the in-vacuo frequencies. Mach numbers between tabulated ones interpolate Q linearly in Mach
(flutter.gafinterp) before the fit; one fit per Mach number of the cases.
"""
from __future__ import annotations

from typing import Callable

import numpy as np
import xarray as xr
from scipy.optimize import linear_sum_assignment

from flutter.crossings import (G_TOL, crossing_at, drift_roots, find_brackets, illinois,
                               interpolate_zero, resolved_damping, root_damping)
from flutter.gafinterp import _q_at_mach
from flutter.parallel import map_cases
from flutter.pk import sweep_flights
from flutter.results import attach_crossings, vg_dataset
from flutter.system import ModalSystem
from flutter.tracking import assign, mac_matrix
from structures.common.errors import InputError, SolverError

START_Q = 1e-14     # the first flight point is reached along q from START_Q q ...
START_STEPS = 50    # ... in this many geometric steps
STRUCTURAL = 1e-5   # at START_Q q, roots with a smaller structural share are aerodynamic lags
FIT_MODES = 4       # default fit range: up to FIT_MODES x the first elastic frequency (fit_range)
FIT_POINTS = 10     # ... and at least this many tabulated k (aero.rfa's default fit has 13 matrices)


def state_matrix(M: np.ndarray, B: np.ndarray, K: np.ndarray, rfa, velocity: float,
                 density: float) -> np.ndarray:
    """First-order matrix of the aeroelastic model at one flight point; states [u, u', x].

    Parameters
    ----------
    M, B, K : ndarray, shape (n, n)
        Modal mass, viscous damping, stiffness.
    rfa : object with ``descriptor()`` and ``refc``
        A rational fit (aero.rfa.RationalFit): A0, A1, A2 (n, n), D (n, m), R (m, m), E (m, n).
    velocity, density : float

    Returns
    -------
    ndarray, shape (2 n + m, 2 n + m)
    """
    A0, A1, A2, D, R, E = rfa.descriptor()
    n, m = M.shape[0], R.shape[0]
    b = rfa.refc / 2.0
    q = 0.5 * density * velocity ** 2
    Mbar = M - q * (b / velocity) ** 2 * A2      # Karpel 1982 eq. 4
    Bbar = B - q * (b / velocity) * A1
    Kbar = K - q * A0
    Mi = np.linalg.inv(Mbar)
    N = 2 * n + m
    Amat = np.zeros((N, N))
    Amat[:n, n:2 * n] = np.eye(n)
    Amat[n:2 * n, :n] = -Mi @ Kbar
    Amat[n:2 * n, n:2 * n] = -Mi @ Bbar
    Amat[n:2 * n, 2 * n:] = q * Mi @ D
    Amat[2 * n:, n:2 * n] = E                    # x' = E u' + (V/b) R x, Karpel eq. 5
    Amat[2 * n:, 2 * n:] = (velocity / b) * R
    return Amat


def aeroelastic_statespace(M: np.ndarray, B: np.ndarray, K: np.ndarray, rfa, velocity: float,
                           density: float):
    """The LTI aeroelastic model of :func:`state_matrix` as a python-control system (outputs u,
    one zero input: the poles are the flutter roots; for control design, hence imported here)."""
    import control

    A = state_matrix(M, B, K, rfa, velocity, density)
    N, n = A.shape[0], M.shape[0]
    C = np.zeros((n, N))
    C[:, :n] = np.eye(n)
    return control.ss(A, np.zeros((N, 1)), C, np.zeros((n, 1)))


def _candidates(A: np.ndarray, n: int, scale: float):
    """Eigenvalues with Im p >= 0 (real ones with Im set to 0), their unit modal parts u, shape
    (c, n), and their structural share |[u, u']| / |[u, u', x]| (unit eigenvectors)."""
    lam, X = np.linalg.eig(A)
    real = np.abs(lam.imag) <= 1e-9 * np.maximum(np.abs(lam), scale)
    keep = real | (lam.imag > 0)
    lam = np.where(real, lam.real + 0j, lam)[keep]
    share = np.linalg.norm(X[:2 * n, keep], axis=0)
    U = X[:n, keep].T
    U = U / np.maximum(np.linalg.norm(U, axis=1, keepdims=True), 1e-300)
    return lam, U, share


class _Model:
    """Tracking of the structural roots of one system and its fits (internal)."""

    def __init__(self, system: ModalSystem, fits: dict, mac_min: float, max_depth: int,
                 rigid_hz: float):
        self.system = system
        self.rigid_hz = rigid_hz
        self.fits = fits
        self.mac_min, self.max_depth = mac_min, max_depth
        B = system.damping
        if not system.structural.is_zero:
            B = B + system.viscous_structural()
        self.B = B
        self.omega0, self.phi = system.in_vacuo()
        self.scale = 1e-3 * max(float(self.omega0.max()), 1e-12)

    def roots(self, point: tuple, p_prev: np.ndarray, u_prev: np.ndarray, structural: float = 0.0):
        """The candidates at ``point`` continuing (p_prev, u_prev), among those whose structural
        share exceeds ``structural``."""
        V, rho, mach = point
        A = state_matrix(self.system.mass, self.B, self.system.stiffness, self.fits[_key(mach)],
                         V, rho)
        lam, U, share = _candidates(A, self.system.n, self.scale)
        lam, U = lam[share > structural], U[share > structural]
        pick = assign(p_prev, u_prev, lam, U)
        return lam[pick], U[pick]

    def jumped(self, p0, u0, p1, u1) -> np.ndarray:
        """Roots (R,) of a step that jump by half their distance to the nearest other root, or
        lose eigenvector correlation (MAC < mac_min) while moving; a step is kept when none do."""
        sep = np.abs(p0[:, None] - p0[None, :])
        np.fill_diagonal(sep, np.inf)
        jump = np.abs(p1 - p0) / np.maximum(sep.min(axis=1), self.scale)
        mac = np.diag(mac_matrix(u0, u1))
        return (jump > 0.5) | ((mac < self.mac_min) & (jump > 0.05))

    def step(self, frm: tuple, to: tuple, p0, u0, depth: int = 0):
        """Roots at ``to`` continued from (p0, u0) at ``frm``, bisecting rejected steps.

        Returns p (R,), u (R, n) and the roots (R,) whose step still jumped at the smallest
        bisection (not tracked with confidence: flagged not converged by the caller)."""
        p1, u1 = self.roots(to, p0, u0)
        bad = self.jumped(p0, u0, p1, u1)
        if depth < self.max_depth and bad.any():
            mid = tuple(0.5 * (a + c) for a, c in zip(frm, to))
            pm, um, bad_a = self.step(frm, mid, p0, u0, depth + 1)
            p1, u1, bad_b = self.step(mid, to, pm, um, depth + 1)
            return p1, u1, bad_a | bad_b
        return p1, u1, bad

    def start(self, point: tuple):
        """Roots at the first flight point, continued from the in-vacuo modes along q.

        At START_Q q a lag root's eigenvector has a structural share of order START_Q (its modal
        part is driven through q only), a structural root's of order 1 (u' = p u and the lag
        states x = (p_bar - R)^-1 E p_bar u are of the order of u): the lag roots are left out
        there (share below STRUCTURAL) before the in-vacuo modes are assigned to the others.
        """
        V, rho, mach = point
        u = (self.phi / np.linalg.norm(self.phi, axis=0)).T.astype(complex)
        p, u = self.roots((V, START_Q * rho, mach), 1j * self.omega0.astype(complex), u, STRUCTURAL)
        if p.size < self.system.n:
            raise SolverError(f"p-method: {p.size} structural roots for {self.system.n} modes at "
                              f"V = {V:g}. Fix: check the modal matrices (duplicated modes).")
        rhos = rho * np.geomspace(START_Q, 1.0, START_STEPS)
        for r0, r1 in zip(rhos[:-1], rhos[1:]):
            p, u, _ = self.step((V, r0, mach), (V, r1, mach), p, u)
        rigid = np.flatnonzero(self.omega0 < 2 * np.pi * self.rigid_hz)
        if rigid.size > 1:  # as p-k: each rigid root to the rigid mode it participates in most
            c = np.abs(u[rigid] @ (self.system.mass @ self.phi[:, rigid])) ** 2
            rows, cols = linear_sum_assignment(-c)
            order = np.arange(p.size)
            order[rigid[cols]] = rigid[rows]
            p, u = p[order], u[order]
        return p, u

    def damping(self, p: np.ndarray, V) -> np.ndarray:
        """g = 2 Re p / Im p; Nastran's g = p cbar / (V ln 2) for real roots."""
        p = np.asarray(p)
        return root_damping(p, V, self.fits[next(iter(self.fits))].refc / 2.0, p.imag == 0)


def _key(mach: float) -> float:
    return round(float(mach), 9)


def p_solve(system: ModalSystem, gaf, velocity, *, density, mach, sweep: str = "velocity",
            refc: float | None = None, interpolation: str = "linear", refine: bool = True,
            g_tol: float = G_TOL, **options) -> xr.Dataset:
    """p-method (rational fit) flutter solution along one sweep: :func:`p_solve_many` of one case.

    Parameters
    ----------
    system, gaf, sweep, refc, interpolation, refine, g_tol, **options
        As :func:`p_solve_many`.
    velocity, density, mach : array_like, shape (npts,) or scalar
        Flight points (broadcast), as flutter.pk.pk_solve.

    Returns
    -------
    xarray.Dataset
    """
    return p_solve_many(system, gaf, [(velocity, density, mach)], sweep=sweep, refc=refc,
                        interpolation=interpolation, refine=refine, g_tol=g_tol, **options)[0]


def p_solve_many(system: ModalSystem, gaf, cases, *, sweep: str = "velocity",
                 refc: float | None = None, interpolation: str = "linear", refine: bool = True,
                 g_tol: float = G_TOL, workers: int = 1, fit: Callable | None = None,
                 fit_options: dict | None = None, mac_min: float = 0.7, max_depth: int = 8,
                 rigid_hz: float = 0.05) -> list[xr.Dataset]:
    """Flutter roots of the rationally approximated GAFs along several sweeps (method "P-RFA").

    Parameters
    ----------
    system : ModalSystem
    gaf : xarray.Dataset
        ``Q(mach, k, mode_i, mode_j)`` with attrs ``refc``.
    cases : list of (velocity, density, mach)
        Each array_like of shape (npts_c,) or scalar (broadcast); the ``sweep`` variable strictly
        increasing.
    sweep : {"velocity", "density"}
    refc : float, optional
        Reference chord; default ``gaf.attrs["refc"]``.
    interpolation : str
        Recorded only: the rational fit is the interpolant in k.
    refine : bool
        Locate crossings by root-finding (Illinois) on the model, else linear interpolation of g.
    g_tol : float
        Neutral-damping band for crossings.
    workers : int
        Processes to spread the cases over (flutter.parallel.map_cases).
    fit : callable
        ``fit(k, Q, refc=..., mach=..., **fit_options)`` returning a rational fit with
        ``descriptor()``, ``refc``, ``k_max``, ``fit_error``, ``overall_error``, ``beta``,
        ``pairs`` (aero.rfa.fit_rfa).
    fit_options : dict, optional
        Passed to ``fit`` (e.g. ``nlag``, ``npair``, ``k_max``); ``k_max`` defaults to
        :func:`fit_range`.
    mac_min, max_depth : float, int
        Tracking: minimum eigenvector correlation of a moving root, and step bisections.
    rigid_hz : float
        In-vacuo modes below this frequency [Hz] are rigid; at the first flight point their roots
        are given to the rigid modes they participate in most (as flutter.pk_solver).

    Returns
    -------
    list of xarray.Dataset
        One per case, the p-k layout (flutter.results.vg_dataset + attach_crossings): dims (sweep,
        root, mode); attrs ``method`` "P-RFA", ``rfa_fit_error`` (strict, largest over the Mach
        numbers), ``rfa_overall_error``, ``lags`` (real roots), ``lag_pairs`` (sigma, w),
        ``rfa_k_max``.
    """
    if sweep not in ("velocity", "density"):
        raise InputError(f"p-method: unknown sweep {sweep!r}. Fix: use 'velocity' or 'density'.")
    if not (isinstance(workers, (int, np.integer)) and workers >= 1):
        raise InputError(f"p-method: workers = {workers!r}. Fix: give a whole number >= 1.")
    if fit is None:
        raise InputError("p-method: no rational-fit function given. Fix: pass fit=aero.rfa.fit_rfa "
                         "(flutter/ does not import aero).")
    if refc is None:
        if "refc" not in getattr(gaf, "attrs", {}):
            raise InputError("p-method: the GAFs carry no 'refc' attribute. Fix: pass refc= (the "
                             "AERO card's REFC) or use the Dataset written by aero.gaf.")
        refc = float(gaf.attrs["refc"])
    flights = sweep_flights(cases, sweep)
    k = np.asarray(gaf["k"].values, dtype=float)
    options = dict(fit_options or {})
    # one fit range for all the cases, however they are spread over workers
    v_min = min(float(V.min()) for V, _, _ in flights)
    options.setdefault("k_max", fit_range(system, k, refc, v_min, rigid_hz))
    if workers > 1 and len(cases) > 1:
        settings = dict(sweep=sweep, refc=refc, interpolation=interpolation, refine=refine,
                        g_tol=g_tol, fit=fit, fit_options=options, mac_min=mac_min,
                        max_depth=max_depth, rigid_hz=rigid_hz)
        return map_cases(lambda case: p_solve_many(system, gaf, [case], **settings)[0],
                         list(cases), workers)
    fits = {}
    for m in np.unique(np.concatenate([M for _, _, M in flights])):
        Q = _q_at_mach(gaf, float(m))
        if Q.shape[-1] != system.n:
            raise InputError(f"p-method: the GAFs have {Q.shape[-1]} modes, the system {system.n}. "
                             "Fix: compute Q_hh with the same modes as M_hh and K_hh.")
        fits[_key(m)] = fit(k, Q, refc=refc, mach=float(m), **options)
    model = _Model(system, fits, mac_min, max_depth, rigid_hz)
    k_min = float(k[k > 0].min())
    return [_case(model, flight, sweep, interpolation, refine, g_tol, k_min) for flight in flights]


def fit_range(system: ModalSystem, k: np.ndarray, refc: float, v_min: float,
              rigid_hz: float = 0.05) -> float:
    """Default upper end of the fitted k range: the smallest tabulated k at or above the reduced
    frequency of FIT_MODES x the first elastic in-vacuo frequency at the lowest speed and at or
    above the FIT_POINTS-th tabulated k, else the largest tabulated k.

    Flutter couples the lowest modes; fitting the sparse high end of a table as well costs the fit
    its accuracy where the roots are (Nastran's bah_plane QHH: strict fit error 14 % over k <= 10,
    0.54 % over k <= 5; elastic flutter 409 m/s instead of 394 with our own GAFs). Roots above the
    fitted range are flagged not converged.

    Parameters
    ----------
    system : ModalSystem
    k : ndarray, shape (nk,)
        Tabulated reduced frequencies.
    refc : float
        Reference chord (b = refc / 2).
    v_min : float
        Lowest flight speed of the cases.
    rigid_hz : float
        In-vacuo modes below this frequency [Hz] are rigid (not elastic).

    Returns
    -------
    float
    """
    omega, _ = system.in_vacuo()
    elastic = omega[omega >= 2 * np.pi * rigid_hz]
    table = np.sort(k[k > 0])
    if elastic.size == 0:
        return float(table[-1])
    need = max(FIT_MODES * float(elastic.min()) * 0.5 * refc / v_min,
               table[min(FIT_POINTS, table.size) - 1])
    above = table[table >= need]
    return float(above[0] if above.size else table[-1])


def _case(model: _Model, flight: tuple, sweep: str, interpolation: str, refine: bool,
          g_tol: float, k_min: float) -> xr.Dataset:
    """Sweep, crossings and result Dataset of one case."""
    V, rho, M = flight
    pts = list(zip(V, rho, M))
    p, u = model.start(pts[0])
    P, U, lost = [p], [u], [np.zeros(p.size, dtype=bool)]
    for a, c in zip(pts[:-1], pts[1:]):
        p, u, bad = model.step(a, c, p, u)
        P.append(p)
        U.append(u)
        lost.append(bad)
    P, U = np.array(P), np.array(U)
    fits = model.fits
    b = fits[_key(M[0])].refc / 2.0
    kmax = np.array([fits[_key(m)].k_max for m in M])
    # not converged: k above the fitted range, or a step that still jumped at the smallest bisection
    conv = (np.abs(P.imag) * b / V[:, None] <= kmax[:, None] * (1 + 1e-9)) & ~np.array(lost)
    g = model.damping(P, V[:, None])
    crossings, vectors = [], []
    drift = drift_roots(P, V, b, np.full(V.size, k_min), model.omega0 < 2 * np.pi * model.rigid_hz)
    for r, i in find_brackets(resolved_damping(g, drift), g_tol):
        if refine:
            t, pr, ur, ok = _refine(model, pts[i], pts[i + 1], P[i], U[i], r, g[i, r], g[i + 1, r])
        else:
            t = interpolate_zero(g[i, r], g[i + 1, r])
            pr, ur, ok = P[i, r] + t * (P[i + 1, r] - P[i, r]), U[i if t < 0.5 else i + 1, r], True
        vectors.append(ur)
        crossings.append(crossing_at(r, i, t, pts[i], pts[i + 1], pr, real=pr.imag == 0,
                                     converged=ok and conv[i, r] and conv[i + 1, r],
                                     refined=refine))
    used = [fits[key] for key in sorted({_key(m) for m in M})]
    sd = model.system.structural
    ds = vg_dataset(P, U, g, conv, V, rho, M, b=b, modes=model.system.modes, sweep=sweep,
                    method="P-RFA",
                    attrs={"interpolation": interpolation, "g_tol": g_tol,
                           "rfa_fit_error": max(f.fit_error for f in used),
                           "rfa_overall_error": max(f.overall_error for f in used),
                           "rfa_k_max": min(f.k_max for f in used),
                           "lags": [float(x) for f in used for x in f.beta],
                           "lag_pairs": [float(x) for f in used for x in np.ravel(f.pairs)],
                           "structural_damping": "none" if sd.is_zero else
                           f"{sd.kind} as modal viscous g_j omega_j"})
    vectors = np.array(vectors).reshape(len(crossings), model.system.n)
    return attach_crossings(ds, crossings, vectors)


def _refine(model: _Model, a: tuple, c: tuple, p0, u0, r: int, g0: float, g1: float):
    """Zero of root r's damping between flight points a and c (Illinois on the path fraction t);
    each evaluation continues all roots from point a to the point at t."""
    cache = {}

    def fun(t):
        pt = tuple(x + t * (y - x) for x, y in zip(a, c))
        p, u, _ = model.step(a, pt, p0, u0)
        cache[t] = (p[r], u[r])
        return float(model.damping(p[r:r + 1], pt[0])[0])

    t, ok = illinois(fun, g0, g1)
    if t not in cache:
        fun(t)
    return t, cache[t][0], cache[t][1], ok
