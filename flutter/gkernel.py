"""Chen's g-method equation: its matrices, the reduced-frequency sweep and the local root solve.

P. C. Chen, "Damping Perturbation Method for Flutter Solution: The g-Method", AIAA J. 38(9), 2000,
1519-1524. With the nondimensional Laplace variable p_bar = p b / V = g + i k (b = refc / 2,
k = omega b / V; g here is Chen's real part of p_bar, the reported damping is 2 Re p / Im p), the
GAFs off the imaginary axis are expanded to first order about p_bar = i k (Chen's damping
perturbation; the paper was not at hand, so no equation numbers are given here):

    Q(p_bar) ~ Q(ik) + g Q'(ik),   Q'(ik) = dQ / d(ik) = -i dQ/dk,

exact at g = 0 and first-order accurate in g. p-k's Q^R(k) + p_bar Q^I(k) / k agrees with it except
for the k-derivative of Q^R off the axis (the term -i g dQ^R/dk), which is why p-k damping is only
exact at g = 0 and the g-method's is right to first order in g. The expansion is about ik, and the
aerodynamics have a branch point at p_bar = 0, so it holds while |g| is well below k: for a root
near critical damping (bah_plane's short period, g ~ -1.15 k) the g-method's |p| is 10-15 % above
the exact root's (tests/flutter/test_rigid_roots_bah.py, test_gmethod.py's xfail). With Q^R and D = Q^I / k interpolated in k (flutter.gafinterp),

    Q'(ik)       = D + k dD/dk - i dQ^R/dk,
    Q - ik Q'    = Q^R - k dQ^R/dk - i k^2 dD/dk,

and the g-method flutter equation (Chen 2000, written in p_bar and scaled by (b/V)^2, q = rho V^2/2)

    [ M p_bar^2 + ((b/V) B - (rho b^2 / 2) Q') p_bar
      + (b/V)^2 K (1 + i g_s) - (rho b^2 / 2)(Q - ik Q') ] u = 0

is, for each k, a quadratic eigenproblem in p_bar with complex matrices (no conjugate pairs). A
root is a k where an eigenvalue has Im p_bar = k (Chen's root condition Im g = 0).

Chen's reduced-frequency sweep (RFS, :meth:`GProblem.roots`): at one flight point the 2 n
eigenvalues are computed on a grid of k (one stacked ``np.linalg.eig``), followed as branches
across k by eigenvector correlation and continuity (flutter.tracking.assign), and every sign change
of Im p_bar_j(k) - k is refined by Illinois root-finding on k (flutter.crossings.illinois) to
|Im g| ~ 1e-10. At k = 0 the equation is real (Q^R is even in k, so dQ^R/dk = 0 there; hysteretic
damping, which has no zero-frequency equivalent, is dropped as in flutter.pk): its real eigenvalues
are the real (zero-frequency) roots, reported with Im p = 0 and Nastran's g = p cbar / (V ln 2).
Above the GAF table Q is held constant (zero slopes), so the equation no longer depends on k and a
branch still above Im p_bar = k at the table's end has its root at k = Im p_bar: those roots are
flagged not converged (outside the table).

The sweep finds every root but costs ~60 eigen-decompositions of 2n x 2n per flight point; roots
known near a first guess (the previous flight point's, along a sweep) are solved locally instead by
:meth:`GProblem.correct` (inverse iteration and a secant on k, a few n x n LUs per root).
"""
from __future__ import annotations

import numpy as np

from flutter.crossings import illinois, root_damping
from flutter.gafinterp import GafInterpolator
from flutter.linalg import inverse_iteration, unit_rows
from flutter.system import ModalSystem
from flutter.tracking import assign
from structures.common.errors import InputError

CORRECT_ITER = 30   # local iterations per root (normally 3-6)
CORRECT_TOL = 1e-10  # relative convergence of p_bar and of Chen's Im g = 0 in the local solve


class GProblem:
    """The g-method's matrices and its reduced-frequency sweep for one system and GAF set.

    Parameters
    ----------
    system : ModalSystem
    gaf : xarray.Dataset or callable
        ``Q(mach, k, mode_i, mode_j)`` with attrs ``refc``, or ``gaf(mach, k) -> (nk, n, n)``.
    refc : float, optional
        Reference chord (b = refc / 2); default ``gaf.attrs["refc"]``.
    interpolation : {"linear", "cubic"}
        Interpolation of Q^R and Q^I/k in k (module docstring: cubic gives continuous dQ/dk).
    nk : int
        Points of the k grid of the sweep (half geometric, half uniform, plus the table's k).
    rigid_hz : float
        In-vacuo modes below this frequency [Hz] are rigid-body modes: their drift roots below the
        GAF table's resolution give no crossings (flutter.crossings.drift_roots), as in p-k.
    """

    def __init__(self, system: ModalSystem, gaf, *, refc: float | None = None,
                 interpolation: str = "cubic", nk: int = 60, rigid_hz: float = 0.05):
        if refc is None:
            if "refc" not in getattr(gaf, "attrs", {}):
                raise InputError("g-method: the GAFs carry no 'refc' attribute. Fix: pass refc= "
                                 "(the AERO card's REFC) or use the Dataset written by aero.gaf.")
            refc = float(gaf.attrs["refc"])
        if not refc > 0:
            raise InputError(f"g-method: refc={refc} must be > 0. Fix: use the AERO card's REFC.")
        if not (isinstance(nk, (int, np.integer)) and nk >= 8):
            raise InputError(f"g-method: nk = {nk!r}. Fix: give a whole number >= 8 (default 60).")
        if not rigid_hz >= 0:
            raise InputError(f"g-method: rigid_hz = {rigid_hz} must be >= 0. Fix: e.g. 0.05.")
        self.system, self.gaf, self.interpolation, self.nk = system, gaf, interpolation, int(nk)
        self.rigid_hz = float(rigid_hz)
        self.b = 0.5 * float(refc)
        self._interp: dict[float, GafInterpolator] = {}
        self.omega0, self.phi = system.in_vacuo()
        self._hyst = system.hysteretic
        self.B = system.viscous_damping()
        self._Minv = np.linalg.inv(system.mass)
        mach0 = float(np.atleast_1d(gaf["mach"].values)[0]) if hasattr(gaf, "coords") else 0.0
        if self.interpolator(mach0).n != system.n:
            raise InputError(f"g-method: the GAFs have a different number of modes than the system "
                             f"({system.n}). Fix: compute Q_hh with the same modes as M_hh, K_hh.")

    def interpolator(self, mach: float) -> GafInterpolator:
        """The (cached) GAF interpolator at Mach ``mach``."""
        key = round(float(mach), 9)
        if key not in self._interp:
            self._interp[key] = GafInterpolator(self.gaf, mach, self.interpolation)
        return self._interp[key]

    # ----------------------------------------------------------------------------- kernels
    def coefficients(self, k: np.ndarray, V: float, rho: float, mach: float):
        """Coefficients of the g-method equation M p_bar^2 + A1 p_bar + A0 at reduced frequencies k.

        Parameters
        ----------
        k : ndarray, shape (nk,)
            Reduced frequencies k = omega b / V (>= 0).
        V, rho, mach : float
            Flight point.

        Returns
        -------
        A0, A1 : ndarray, shape (nk, n, n) complex
            (b/V)^2 K (1 + i g_s) - (rho b^2 / 2)(Q - ik Q') and (b/V) B - (rho b^2 / 2) Q'.
        outside : ndarray of bool, shape (nk,)
            k above the tabulated GAF range.
        """
        n = self.system.n
        QR, D, dQR, dD, outside = self.interpolator(mach).with_slopes(k)
        kb = k[:, None, None]
        dQR = np.where(kb > 0, dQR, 0.0)     # Q^R is even in k: dQ^R/dk = 0 at k = 0
        dQ = D + kb * dD - 1j * dQR          # Q'(ik) = -i dQ/dk (Chen 2000)
        Q0 = QR - kb * dQR - 1j * kb * kb * dD   # Q(ik) - ik Q'(ik)
        h = 0.5 * rho * self.b ** 2          # q (b/V)^2
        s = self.b / V
        Kc = np.broadcast_to(s * s * self.system.stiffness, (k.size, n, n)).astype(complex)
        if self._hyst:                       # K (1 + i g_s(f)), f = k V / (2 pi b); none at k = 0
            gs = np.where(k > 0, self.system.structural.at(k / s / (2 * np.pi)), 0.0)
            Kc = Kc * (1 + 1j * gs)[:, None, None]
        # g-method equation (Chen 2000) scaled by (b/V)^2
        return Kc - h * Q0, s * self.B[None] - h * dQ, outside

    def eig(self, k: np.ndarray, V: float, rho: float, mach: float, vectors: bool = True):
        """Eigenvalues p_bar and right vectors of the g-method equation at reduced frequencies k.

        Parameters
        ----------
        k : ndarray, shape (nk,)
            Reduced frequencies k = omega b / V (>= 0).
        V, rho, mach : float
            Flight point.
        vectors : bool
            Compute the eigenvectors (else ``U`` is None; eigenvalues only are about twice as fast).

        Returns
        -------
        lam : ndarray, shape (nk, 2n) complex
            p_bar = p b / V (exactly real at k = 0 where the matrices are real).
        U : ndarray, shape (nk, 2n, n) complex, or None
            Right vectors u (unit 2-norm) of each eigenvalue.
        outside : ndarray of bool, shape (nk,)
            k above the tabulated GAF range.
        """
        n = self.system.n
        k = np.asarray(k, dtype=float)
        A0, A1, outside = self.coefficients(k, V, rho, mach)
        A = np.zeros((k.size, 2 * n, 2 * n), dtype=complex)
        A[:, :n, n:] = np.eye(n)
        A[:, n:, :n] = -self._Minv @ A0
        A[:, n:, n:] = -self._Minv @ A1
        if not vectors:
            lam = np.linalg.eigvals(A).astype(complex)
            if np.any(k == 0):
                lam[k == 0] = np.linalg.eigvals(A[k == 0].real)
            return lam, None, outside
        lam = np.empty((k.size, 2 * n), dtype=complex)
        X = np.empty((k.size, 2 * n, 2 * n), dtype=complex)
        zero = k == 0
        if zero.any():                       # real matrices at k = 0: real roots exactly real
            lr, Xr = np.linalg.eig(A[zero].real)
            lam[zero], X[zero] = lr, Xr
        if (~zero).any():
            lam[~zero], X[~zero] = np.linalg.eig(A[~zero])
        U = np.swapaxes(X[:, :n, :], 1, 2)
        return lam, U / np.linalg.norm(U, axis=2, keepdims=True), outside

    def grid(self, V: float, rho: float, mach: float) -> np.ndarray:
        """The k grid of the sweep at one flight point, shape (nk',): 0, a geometric and a uniform
        grid up to the end of the GAF table (or, for a callable, up to where every branch has
        fallen below Im p_bar = k), and the tabulated k values."""
        interp = self.interpolator(mach)
        if np.isfinite(interp.k_max):
            top, extra = interp.k_max, interp.k_grid
        else:
            top, extra = max(2.0 * float(self.omega0.max()) * self.b / V, 1.0), np.zeros(0)
            for _ in range(12):
                lam, _, _ = self.eig(np.array([top]), V, rho, mach, vectors=False)
                if np.all(lam.imag <= top):
                    break
                top *= 2.0
        half = self.nk // 2
        return np.unique(np.concatenate([[0.0], np.geomspace(top * 1e-4, top, half),
                                         np.linspace(0.0, top, self.nk - half), extra]))

    def roots(self, V: float, rho: float, mach: float):
        """All g-method roots at one flight point by the reduced-frequency sweep.

        Returns
        -------
        p : ndarray, shape (m,) complex
            Roots p = p_bar V / b (rad/s), Im p >= 0; real roots exactly real.
        u : ndarray, shape (m, n)
            Right eigenvectors (unit 2-norm).
        converged : ndarray of bool, shape (m,)
            The refinement reached Im g = 0 (False at a jump of a linear interpolant).
        outside : ndarray of bool, shape (m,)
            The root's k lies above the GAF table.
        """
        kg = self.grid(V, rho, mach)
        lam, U, out = self.eig(kg, V, rho, mach)
        for i in range(1, kg.size):          # branches across k (Chen's RFS), never by sorting
            perm = assign(lam[i - 1], U[i - 1], lam[i], U[i])
            lam[i], U[i] = lam[i][perm], U[i][perm]
        f = lam.imag - kg[:, None]           # Im g of each branch
        real = np.flatnonzero(lam[0].imag == 0)
        ps = [lam[0, real]]
        us = [U[0, real]]
        ok = [np.ones(real.size, dtype=bool)]
        outs = [np.zeros(real.size, dtype=bool)]
        for i, j in zip(*np.nonzero(f[:-1] * f[1:] < 0)):
            p, u, good = self._refine(kg[i], kg[i + 1], lam[i, j], lam[i + 1, j], f[i, j],
                                      f[i + 1, j], V, rho, mach)
            ps.append([p])
            us.append(u[None])
            ok.append([good])
            outs.append([False])
        if np.isfinite(self.interpolator(mach).k_max):
            for j in np.flatnonzero(f[-1] > 0):   # beyond the table: Q constant in k
                p, u = self._beyond(lam[-1, j], U[-1, j], V, rho, mach)
                ps.append([p])
                us.append(u[None])
                ok.append([False])
                outs.append([True])
        pbar = np.concatenate([np.asarray(x, dtype=complex) for x in ps])
        return (pbar * V / self.b, unit_rows(np.concatenate(us)), np.concatenate(ok),
                np.concatenate(outs))

    def _pick(self, k: float, target: complex, V, rho, mach, vectors: bool = True):
        """The eigenvalue at k nearest ``target`` and its vector (None without ``vectors``)."""
        lam, U, _ = self.eig(np.array([k]), V, rho, mach, vectors)
        j = int(np.argmin(np.abs(lam[0] - target)))
        return lam[0, j], (U[0, j] if vectors else None)

    def _refine(self, ka, kb, la, lb, fa, fb, V, rho, mach):
        """Zero of Im p_bar(k) - k on one branch between two grid points (Illinois on k)."""
        cache = {}

        def fun(t):
            k = ka + t * (kb - ka)
            lam, _ = self._pick(k, la + t * (lb - la), V, rho, mach, vectors=False)
            cache[t] = (k, lam)
            return float(lam.imag - k)

        if fa > 0:                               # illinois wants fun(0) < 0 < fun(1)
            t, good = illinois(lambda s: -fun(1 - s), -fb, -fa, xtol=1e-9)
            t = 1 - t
        else:
            t, good = illinois(fun, fa, fb, xtol=1e-9)
        k, lam = cache[t] if t in cache else cache[min(cache, key=lambda s: abs(s - t))]
        lam, u = self._pick(k, lam, V, rho, mach)
        good = good and abs(lam.imag - k) <= max(1e-8 * abs(lam), 1e-10)
        return complex(lam.real, k), u, good

    def _beyond(self, lam, u, V, rho, mach):
        """A root above the GAF table: k = Im p_bar by substitution (Q held: one or two steps)."""
        for _ in range(20):
            k = float(lam.imag)
            lam, u = self._pick(k, lam, V, rho, mach)
            if abs(lam.imag - k) <= 1e-10 * max(abs(lam), 1e-12):
                break
        return complex(lam.real, float(lam.imag)), u

    def correct(self, pbar: np.ndarray, u: np.ndarray, w: np.ndarray, V: float, rho: float,
                mach: float):
        """Roots near first guesses at one flight point, without a sweep, batched over the roots.

        Each iteration, at each root's current k: one step of two-sided nonlinear inverse
        iteration on T(p_bar) = M p_bar^2 + A1(k) p_bar + A0(k) (Ruhe, SIAM J. Numer. Anal.
        10(4), 1973: one LU per root, shift at the current p_bar), the two-sided Rayleigh
        functional w^H T(p_bar) u = 0 (a quadratic in p_bar, the solution nearest the shift), and
        a secant step on k for Chen's root condition Im p_bar(k) = k. A real guess
        (Im p_bar = 0) stays at k = 0, where the matrices are real; a root whose k goes to zero or
        below (a pair turning real) continues there as the real root nearest its eigenvalue. A
        root fails (``converged`` False) if a real root's Rayleigh value turns complex (two real
        roots merging into a pair) or it does not converge to |Im g| and a p_bar update
        <= ``CORRECT_TOL`` |p_bar| within ``CORRECT_ITER`` iterations.

        Parameters
        ----------
        pbar : ndarray, shape (R,) complex
            First guesses p_bar = p b / V (Im >= 0).
        u, w : ndarray, shape (R, n) complex
            Right and left eigenvector guesses.
        V, rho, mach : float
            Flight point.

        Returns
        -------
        pbar : ndarray, shape (R,) complex
            Roots p_bar (Im p_bar = k; real roots exactly real).
        u, w : ndarray, shape (R, n)
            Right and left vectors (unit 2-norm).
        converged : ndarray of bool, shape (R,)
        outside : ndarray of bool, shape (R,)
            The root's k lies above the GAF table.
        """
        M = self.system.mass
        p, u, w = np.array(pbar, dtype=complex), unit_rows(u), unit_rows(w)
        R = p.size
        real = p.imag == 0
        k = np.where(real, 0.0, p.imag)
        k_old, f_old = np.full(R, np.nan), np.full(R, np.nan)
        done, outside = np.zeros(R, dtype=bool), np.zeros(R, dtype=bool)
        sc = 1e-3 * float(self.omega0.max()) * self.b / V
        act = np.arange(R)
        with np.errstate(divide="ignore", invalid="ignore"):
            for it in range(CORRECT_ITER):
                A0, A1, outside[act] = self.coefficients(k[act], V, rho, mach)
                pa = p[act][:, None, None]
                Tp = 2 * pa * M + A1                       # dT / dp_bar
                x = np.einsum("rij,rj->ri", Tp, u[act])
                y = np.einsum("rji,rj->ri", Tp.conj(), w[act])
                null = np.linalg.norm(x, axis=1) <= 1e-13 * np.abs(Tp).max(axis=(1, 2))
                x[null], y[null] = u[act][null], w[act][null]   # T' u = 0 (a free drift mode)
                un, wn = inverse_iteration(pa * pa * M + pa * A1 + A0, x, y)
                a = np.einsum("ri,ij,rj->r", wn.conj(), M, un)   # w^H T(p_bar) u = a p^2 + b p + c
                bq = np.einsum("ri,rij,rj->r", wn.conj(), A1, un)
                c = np.einsum("ri,rij,rj->r", wn.conj(), A0, un)
                disc = np.sqrt(bq * bq - 4 * a * c)
                r1, r2 = (-bq + disc) / (2 * a), (-bq - disc) / (2 * a)
                pn = np.where(np.abs(r1 - p[act]) <= np.abs(r2 - p[act]), r1, r2)
                ra = real[act]
                size = np.maximum(np.abs(pn), sc)
                bad = ~np.isfinite(pn) | (ra & (np.abs(pn.imag) > 1e-8 * size))
                pn = np.where(ra, pn.real + 0j, pn)
                f = np.where(ra, 0.0, pn.imag - k[act])  # Chen's root condition, Im g = 0
                conv = (it > 0) & (np.abs(pn - p[act]) <= CORRECT_TOL * size) & \
                    (np.abs(f) <= CORRECT_TOL * size) & ~bad
                ka = k[act]
                slope = (f - f_old[act]) / (ka - k_old[act])   # d(Im p_bar - k)/dk
                k_new = ka + f                             # substitution k = Im p_bar
                sec = ka - f / slope                       # secant on Im p_bar(k) - k
                use = np.isfinite(sec) & (np.abs(sec - k_new) <= 0.5 * np.maximum(k_new, sc))
                k_new = np.where(ra, 0.0, np.where(use, sec, k_new))
                real[act] = ra | (k_new <= 1e-8 * size)   # k -> 0: a pair turned real
                k_new = np.where(real[act], 0.0, k_new)
                k_old[act], f_old[act] = ka, f
                p[act], u[act], w[act] = np.where(conv, pn.real + 1j * np.where(ra, 0.0, ka), pn), \
                    un, wn
                p[act] = np.where(real[act], p[act].real + 0j, p[act])
                done[act[conv]] = True
                k[act] = np.where(conv, ka, k_new)
                keep = ~conv & ~bad
                act = act[keep]
                if act.size == 0:
                    break
        return p, u, w, done, outside

    # ----------------------------------------------------------------------------- outputs
    def damping(self, p: np.ndarray, V) -> np.ndarray:
        """g = 2 Re p / Im p; Nastran's g = p cbar / (V ln 2) for real roots (Im p = 0)."""
        p = np.asarray(p)
        return root_damping(p, V, self.b, p.imag == 0)
