"""The p-k flutter method (Nastran PK / PKNL) with continuation and Rayleigh-quotient correction.

For each flight point (V, rho, M) and each root, the p-k equation (MSC Nastran Aeroelastic Analysis
User's Guide, PK method, eq. 3-xx; Hassig, J. Aircraft 8(11), 1971)

    [ M_hh p^2 + (B_hh - rho cbar V Q^I_hh(k) / (4 k)) p + (K_hh - rho V^2 Q^R_hh(k) / 2) ] u = 0,

is solved with the root's own reduced frequency k = omega b / V (b = cbar / 2), p = omega (gamma + i)
and g = 2 gamma. Instead of a full eigen-decomposition per root per iteration, every root is followed
from the previous flight point and corrected by two-sided Rayleigh-quotient iteration on the
quadratic pencil with a Newton update of k (Ruhe, SIAM J. Numer. Anal. 10(4), 1973, nonlinear
Rayleigh functional / inverse iteration), batched over the roots (flutter.pk_solver). A step whose
roots collide or whose eigenvectors lose correlation with the previous point (MAC below ``mac_min``)
is bisected, so roots are tracked by continuity and eigenvector correlation, never by sorting. Several
sweeps (Mach numbers, densities) can be continued in lockstep with one batched correction per point
(:func:`pk_solve_many`).

Zero-frequency roots (rigid-body, divergence) are kept; their damping is Nastran's
g = p cbar / (V ln 2) (as printed in the F06 for KFREQ = 0 roots).
"""
from __future__ import annotations

import warnings
import numpy as np
import xarray as xr
from threadpoolctl import threadpool_limits

from flutter.crossings import (G_TOL, crossing_at, drift_roots, find_brackets, illinois,
                               interpolate_zero, resolved_damping)
from flutter.parallel import map_cases
from flutter.pk_solver import PKSolver, RootState
from flutter.results import vg_dataset, attach_crossings
from flutter.system import ModalSystem
from structures.common.errors import InputError

def check_sweep(velocity: np.ndarray, density: np.ndarray, mach: np.ndarray, sweep: str):
    """Validate a sweep of flight points; the swept variable must increase strictly."""
    for name, v in (("velocity", velocity), ("density", density)):
        if not np.all(np.isfinite(v)) or np.any(v <= 0):
            raise InputError(f"p-k: every {name} must be finite and > 0 (got {v.tolist()}). "
                             "Fix: check the FLFACT list.")
    if np.any(mach < 0) or not np.all(np.isfinite(mach)):
        raise InputError("p-k: Mach numbers must be finite and >= 0. Fix: check the FLFACT list.")
    swept = {"velocity": velocity, "density": density}[sweep]
    bad = np.flatnonzero(np.diff(swept) <= 0)
    if bad.size:
        i = int(bad[0])
        raise InputError(f"p-k: the {sweep} list is not strictly increasing at points {i + 1} and "
                         f"{i + 2} ({swept[i]} then {swept[i + 1]}). Fix: sort the FLFACT {sweep} "
                         "values in increasing order and remove duplicates (for a density sweep "
                         "use sweep='density').")


def sweep_flights(cases, sweep: str) -> list[tuple[np.ndarray, np.ndarray, np.ndarray]]:
    """The flight points of every case, broadcast and checked (:func:`check_sweep`).

    Parameters
    ----------
    cases : list of (velocity, density, mach)
        Each an array_like of shape (npts_c,) or a scalar (broadcast).
    sweep : {"velocity", "density"}
        The swept variable, which must increase strictly.

    Returns
    -------
    list of (V, rho, M), each ndarray of shape (npts_c,) (new arrays)
    """
    flights = []
    for velocity, density, mach in cases:
        V, rho, M = np.broadcast_arrays(np.atleast_1d(np.asarray(velocity, dtype=float)),
                                        np.atleast_1d(np.asarray(density, dtype=float)),
                                        np.atleast_1d(np.asarray(mach, dtype=float)))
        check_sweep(V, rho, M, sweep)
        flights.append((V.copy(), rho.copy(), M.copy()))
    return flights


def sweep_states(solver: PKSolver, velocity, density, mach) -> list[RootState]:
    """Roots at every flight point of a sweep, continued point to point.

    Parameters
    ----------
    solver : PKSolver
    velocity, density, mach : ndarray, shape (npts,)

    Returns
    -------
    list of RootState, one per point.
    """
    return sweep_states_many(solver, [(velocity, density, mach)])[0]


def _stack(states: list[RootState]) -> RootState:
    return RootState(*(np.concatenate([getattr(s, f) for s in states])
                       for f in ("p", "u", "w", "converged", "outside")))


def _part(state: RootState, sl: slice) -> RootState:
    return RootState(state.p[sl], state.u[sl], state.w[sl], state.converged[sl], state.outside[sl])


def sweep_states_many(solver: PKSolver, cases: list[tuple]) -> list[list[RootState]]:
    """Several sweeps continued in lockstep, their roots corrected together.

    At every sweep index the roots of all cases (e.g. the Mach numbers of a PK analysis) are
    corrected in one batched call (each root at its own case's flight point); a case whose step
    fails the tracking checks is then bisected on its own (:meth:`PKSolver.accept`), so each case
    follows the same steps as :func:`sweep_states` on it alone; the numbers agree with that to
    rounding only (the BLAS products and reductions of a batch round differently with its size:
    measured 2e-14 relative on eigenvalues, 2e-13 on eigenvectors).

    Parameters
    ----------
    solver : PKSolver
    cases : list of (velocity, density, mach), each ndarray of shape (npts_c,)

    Returns
    -------
    list (one per case) of lists of RootState (one per point).
    """
    pts = [list(zip(*case)) for case in cases]
    out = [[solver.start(*pc[0])] for pc in pts]
    R = solver.system.n
    for i in range(1, max(len(pc) for pc in pts)):
        live = [c for c, pc in enumerate(pts) if i < len(pc)]
        guesses = [solver.predict(out[c][-1], pts[c][i - 1], pts[c][i]) for c in live]
        flight = np.repeat(np.array([pts[c][i] for c in live]), R, axis=0)  # (R * ncases, 3)
        new = solver.correct(_stack(guesses), flight[:, 0], flight[:, 1], flight[:, 2],
                             retry=solver.max_depth == 0)
        for j, c in enumerate(live):
            part = _part(new, slice(j * R, (j + 1) * R))
            out[c].append(solver.accept(out[c][-1], part, guesses[j].p, pts[c][i - 1], pts[c][i], 0))
    return out


def warn_out_of_range(states: list[RootState], solver: PKSolver, velocity, mach) -> None:
    """One warning per root whose k leaves the tabulated GAF range (those points are not converged)."""
    for r in range(solver.system.n):
        hits = [i for i, s in enumerate(states) if s.outside[r]]
        if hits:
            i = hits[0]
            k = solver.b * abs(states[i].p[r].imag) / velocity[i]
            interp = solver.interpolator(mach[i])
            warnings.warn(
                f"p-k: root {r + 1} needs k={k:.4g} at V={velocity[i]:.6g} (Mach {mach[i]:g}), outside "
                f"the tabulated k range [{interp.k_min:g}, {interp.k_max:g}] at {len(hits)} point(s); "
                "those points are marked not converged. Fix: extend the MKAERO1 k list.",
                RuntimeWarning, stacklevel=3)


def _refine(solver: PKSolver, states: list[RootState], pts: list[tuple], r: int, i: int,
            g0: float, g1: float) -> tuple[float, RootState, bool]:
    """Locate the zero of root r's damping between points i and i+1 by Illinois root-finding.

    Each evaluation corrects root r alone, started from the linear interpolation of its bracketing
    eigen-states (the bracket is one accepted continuation step, so the root is unambiguous). When
    the root turns from oscillatory to real inside the bracket (divergence), the real branch is
    followed back from the real end instead, so the zero found is the real root's p = 0.
    """
    s0, s1 = states[i], states[i + 1]
    real = [abs(s.p[r].imag) <= 1e-9 * max(abs(s.p[r]), solver.scale) for s in (s0, s1)]
    if real[1] and not real[0]:
        s0 = s1
    u1 = s1.u[r] * np.exp(-1j * np.angle(np.vdot(s0.u[r], s1.u[r])))
    w1 = s1.w[r] * np.exp(-1j * np.angle(np.vdot(s0.w[r], s1.w[r])))
    cache = {}

    def point(t):
        return tuple(a + t * (b - a) for a, b in zip(pts[i], pts[i + 1]))

    def fun(t):
        guess = RootState(np.array([s0.p[r] + t * (s1.p[r] - s0.p[r])]),
                          ((1 - t) * s0.u[r] + t * u1)[None], ((1 - t) * s0.w[r] + t * w1)[None],
                          np.ones(1, dtype=bool), np.zeros(1, dtype=bool))
        st = solver.correct(guess, *point(t))
        cache[t] = st
        return float(solver.damping(st.p, point(t)[0])[0])

    t, ok = illinois(fun, g0, g1)
    st = cache[t] if t in cache else solver.correct(cache[max(cache)], *point(t))
    s0 = states[i]
    full = RootState(s0.p.copy(), s0.u.copy(), s0.w.copy(), s0.converged.copy(), s0.outside.copy())
    full.p[r], full.u[r], full.w[r] = st.p[0], st.u[0], st.w[0]
    full.converged[r], full.outside[r] = st.converged[0], st.outside[0]
    return t, full, ok and bool(st.converged[0]) and not bool(st.outside[0])


def pk_solve(system: ModalSystem, gaf, velocity, *, density, mach, sweep: str = "velocity",
             refc: float | None = None, interpolation: str = "linear", refine: bool = True,
             g_tol: float = G_TOL, **options) -> xr.Dataset:
    """p-k flutter solution along a sweep of flight points (Nastran PK, or PKNL with a density sweep).

    Parameters
    ----------
    system : ModalSystem
        M_hh, K_hh, B_hh and structural damping.
    gaf : xarray.Dataset or callable
        ``Q(mach, k, mode_i, mode_j)`` with attrs ``refc`` (DESIGN.md section 6), or
        ``gaf(mach, k) -> Q`` of shape (nk, n, n).
    velocity : array_like, shape (npts,) or scalar
        True airspeeds (model units). Strictly increasing for a velocity sweep.
    density, mach : array_like, shape (npts,) or scalar
        Density and Mach number per point (broadcast). Density strictly increasing for
        ``sweep="density"`` (PKNL).
    sweep : {"velocity", "density"}
        Swept variable: it becomes the first dimension of the result.
    refc : float, optional
        Reference chord; default ``gaf.attrs["refc"]``.
    interpolation : {"linear", "cubic"}
        Interpolation of Q in k.
    refine : bool
        Locate crossings by root-finding on the solver (else linear interpolation of g).
    g_tol : float
        Neutral-damping band for crossings.
    **options
        ``tol``, ``max_iter``, ``mac_min``, ``max_depth`` of :class:`PKSolver`.

    Returns
    -------
    xarray.Dataset
        dims (sweep, root, mode): ``damping``, ``frequency`` [Hz], ``k``, ``eigenvalue``,
        ``eigenvector``, ``converged`` (False where not converged or k outside the GAF table);
        crossings on dim ``crossing`` (``crossing_velocity``, ``crossing_frequency``, ...).
    """
    return pk_solve_many(system, gaf, [(velocity, density, mach)], sweep=sweep, refc=refc,
                         interpolation=interpolation, refine=refine, g_tol=g_tol, **options)[0]


def pk_solve_many(system: ModalSystem, gaf, cases, *, sweep: str = "velocity",
                  refc: float | None = None, interpolation: str = "linear", refine: bool = True,
                  g_tol: float = G_TOL, workers: int = 1, **options) -> list[xr.Dataset]:
    """Several p-k sweeps (e.g. one per Mach number or density) solved together.

    With ``workers = 1`` the roots of all cases are corrected in one batched call per sweep index
    (:func:`sweep_states_many`); with more, the cases are solved on up to ``workers`` processes
    (:func:`flutter.parallel.map_cases`), each one alone, as :func:`pk_solve` would in this process
    (same kernels, BLAS on one thread in both). Both paths take the same tracking steps; their
    numbers are not bit-identical, because a batch of roots from several cases rounds differently
    from a batch of one case's roots. What holds, and is tested (tests/flutter/test_parallel.py,
    also pinned to one core and with 1 or 2 OpenBLAS threads): forked vs batched eigenvalues,
    damping, frequency, k and eigenvectors within 1e-11 of each variable's largest magnitude
    (measured 2e-14 to 2e-13), same converged flags and crossings; forked vs the in-process solve
    of the same case within 1e-12 (measured 0).

    Parameters
    ----------
    system, gaf, sweep, refc, interpolation, refine, g_tol, **options
        As :func:`pk_solve`.
    cases : list of (velocity, density, mach)
        Each an array_like of shape (npts_c,) or a scalar (broadcast), as in :func:`pk_solve`.
    workers : int
        Processes to spread the cases over (1: none; where ``fork`` is unavailable, none).

    Returns
    -------
    list of xarray.Dataset, one per case, as :func:`pk_solve`.
    """
    if sweep not in ("velocity", "density"):
        raise InputError(f"p-k: unknown sweep {sweep!r}. Fix: use 'velocity' or 'density'.")
    if not (isinstance(workers, (int, np.integer)) and workers >= 1):
        raise InputError(f"p-k: workers = {workers!r}. Fix: give a whole number >= 1.")
    if workers > 1 and len(cases) > 1:
        settings = dict(sweep=sweep, refc=refc, interpolation=interpolation, refine=refine,
                        g_tol=g_tol, **options)
        return map_cases(lambda case: pk_solve_many(system, gaf, [case], **settings)[0],
                         list(cases), workers)
    flights = sweep_flights(cases, sweep)
    solver = PKSolver(system, gaf, refc=refc, interpolation=interpolation, **options)
    for m in np.unique(np.concatenate([M for _, _, M in flights])):
        solver.interpolator(m)
    # the kernels' products and factorisations are small (n x n per root): BLAS threads only spin
    # on them, and lose a lot when the cores are shared, so the solve runs on one thread
    with threadpool_limits(limits=1, user_api="blas"):
        all_states = sweep_states_many(solver, flights)
        return [_case_dataset(solver, states, *flight, sweep=sweep, interpolation=interpolation,
                              refine=refine, g_tol=g_tol)
                for states, flight in zip(all_states, flights)]


def _case_dataset(solver: PKSolver, states: list[RootState], V, rho, M, *, sweep: str,
                  interpolation: str, refine: bool, g_tol: float) -> xr.Dataset:
    """Warnings, crossings and the result Dataset of one solved sweep."""
    system = solver.system
    warn_out_of_range(states, solver, V, M)
    p = np.array([s.p for s in states])
    u = np.array([s.u for s in states])
    conv = np.array([s.converged & ~s.outside for s in states])
    g = solver.damping(p, V[:, None])
    pts = list(zip(V, rho, M))
    crossings, vectors = [], []
    k_min = np.array([solver.interpolator(m).k_min for m in M])
    drift = drift_roots(p, V, solver.b, k_min, solver.omega0 < 2 * np.pi * solver.rigid_hz)
    for r, i in find_brackets(resolved_damping(g, drift), g_tol):
        if refine:
            t, s, ok = _refine(solver, states, pts, r, i, g[i, r], g[i + 1, r])
            pr, ur = s.p[r], s.u[r]
        else:
            t = interpolate_zero(g[i, r], g[i + 1, r])
            pr = p[i, r] + t * (p[i + 1, r] - p[i, r])
            ur = u[i, r] if t < 0.5 else u[i + 1, r]
            ok = True
        vectors.append(ur)
        crossings.append(crossing_at(r, i, t, pts[i], pts[i + 1], pr,
                                     real=abs(pr.imag) <= 1e-9 * max(abs(pr), solver.scale),
                                     converged=ok and conv[i, r] and conv[i + 1, r],
                                     refined=refine))
    ds = vg_dataset(p, u, g, conv, V, rho, M, b=solver.b, modes=system.modes, sweep=sweep,
                    method="PKNL" if sweep == "density" else "PK",
                    attrs={"interpolation": interpolation, "g_tol": g_tol,
                           "structural_damping": system.structural.kind
                           if not system.structural.is_zero else "none"})
    return attach_crossings(ds, crossings, np.array(vectors).reshape(len(crossings), system.n))
