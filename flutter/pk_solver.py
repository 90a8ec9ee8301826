"""The p-k continuation kernel: roots followed from flight point to flight point (used by flutter.pk).

Every root of the p-k equation (MSC Nastran Aeroelastic Analysis User's Guide, PK method; Hassig,
J. Aircraft 8(11), 1971)

    [ M_hh p^2 + (B_hh - rho cbar V Q^I_hh(k) / (4 k)) p + (K_hh - rho V^2 Q^R_hh(k) / 2) ] u = 0,

with its own k = omega b / V (b = cbar / 2) is predicted from the previous flight point (eigenvalue
and phase-aligned eigenvectors extrapolated along the path) and corrected, batched over the roots,
by two-sided Rayleigh-quotient iteration on the quadratic pencil (Ruhe, SIAM J. Numer. Anal. 10(4),
1973: nonlinear Rayleigh functional, one LU per root per iteration for the inverse iteration) with a
Newton step on the matching condition k = b Im(p) / V (dp/dk from the Rayleigh functional). A step
whose roots collide or whose eigenvectors lose correlation with the previous point (MAC below
``mac_min``) is bisected; roots that still jump at the smallest step are restarted by a plain per-root
p-k (full eigen-decomposition).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg as sla

from flutter.crossings import root_damping
from flutter.gafinterp import GafInterpolator
from flutter.linalg import inverse_iteration, path_length, pencil_system, rayleigh, unit_rows
from flutter.rigid_start import rigid_branches
from flutter.system import ModalSystem
from structures.common.errors import InputError

NEWTON_ITER = 12  # Newton k-matching normally converges in 2-4 iterations; slower roots are retried


@dataclass
class RootState:
    """Eigen-state of all roots at one flight point (internal, mutable working state)."""

    p: np.ndarray          # (R,) complex, Im >= 0
    u: np.ndarray          # (R, n) right eigenvectors (unit 2-norm)
    w: np.ndarray          # (R, n) left eigenvectors (unit 2-norm)
    converged: np.ndarray  # (R,) bool
    outside: np.ndarray    # (R,) bool, k outside the tabulated range
    slope: np.ndarray | None = None  # (R,) dp per unit path length of the last step (predictor)
    du: np.ndarray | None = None     # (R, n) du per unit path length (phase-aligned vectors)
    dw: np.ndarray | None = None     # (R, n) dw per unit path length


class PKSolver:
    """Fast p-k solver for one modal system and one GAF set.

    Parameters
    ----------
    system : ModalSystem
        Modal mass, stiffness, damping and structural damping.
    gaf : xarray.Dataset or callable
        GAFs ``Q(mach, k, mode_i, mode_j)`` (attrs ``refc``) or ``gaf(mach, k) -> (nk, n, n)``.
    refc : float, optional
        Reference chord (b = refc / 2); defaults to ``gaf.attrs["refc"]``.
    interpolation : {"linear", "cubic"}
        Interpolation of Q in k.
    tol : float
        Relative convergence tolerance on p: a root is converged when an iteration moves p, and
        the k mismatch would move it, by less than tol |p| (1e-6 keeps crossings within 1e-8 of
        those at 1e-9 and saves a fifth of the factorisations; Nastran's FLUTTER EPS, 1e-3 by
        default, applies to k).
    max_iter : int
        Iterations per root and flight point before the point is flagged not converged.
    mac_min : float
        Minimum eigenvector correlation between consecutive points before the step is bisected.
    max_depth : int
        Maximum number of step bisections.
    rigid_hz : float
        In-vacuo modes below this frequency [Hz] are rigid-body modes; their roots start from the
        quasi-steady eigenvalues at the first flight point (:meth:`start`).
    """

    def __init__(self, system: ModalSystem, gaf, *, refc: float | None = None,
                 interpolation: str = "linear", tol: float = 1e-6, max_iter: int = 60,
                 mac_min: float = 0.7, max_depth: int = 8, rigid_hz: float = 0.05):
        self.system = system
        self.gaf = gaf
        if refc is None:
            attrs = getattr(gaf, "attrs", {})
            if "refc" not in attrs:
                raise InputError("p-k: the GAFs carry no 'refc' attribute. Fix: pass refc= (the AERO "
                                 "card's REFC) or use the Dataset written by aero.gaf.")
            refc = float(attrs["refc"])
        if not refc > 0:
            raise InputError(f"p-k: refc={refc} must be > 0. Fix: use the AERO card's REFC.")
        self.b = 0.5 * float(refc)
        self.interpolation = interpolation
        self.tol, self.max_iter, self.mac_min, self.max_depth = tol, max_iter, mac_min, max_depth
        if not rigid_hz >= 0:
            raise InputError(f"p-k: rigid_hz = {rigid_hz} must be >= 0. Fix: e.g. rigid_hz = 0.05.")
        self.rigid_hz = float(rigid_hz)
        self._interp: dict[float, GafInterpolator] = {}
        omega, self.phi = system.in_vacuo()
        self.omega0 = omega
        self.scale = 1e-3 * max(float(omega.max()), 1e-12)
        self._hyst = system.hysteretic
        B = self.B = system.viscous_damping()
        self._MKB = np.concatenate([system.mass.T, system.stiffness.T, B.T], axis=1).astype(complex)
        self._KBM = np.stack([system.stiffness.ravel(), B.ravel(), system.mass.ravel()])
        n = system.n
        if GafInterpolator(gaf, self._any_mach(gaf), interpolation).n != n:
            raise InputError(f"p-k: the GAFs have a different number of modes than the system ({n}). "
                             "Fix: compute Q_hh with the same modes as M_hh and K_hh.")

    @staticmethod
    def _any_mach(gaf) -> float:
        if hasattr(gaf, "coords") and "mach" in gaf.coords:
            return float(np.atleast_1d(gaf["mach"].values)[0])
        return 0.0

    def interpolator(self, mach: float) -> GafInterpolator:
        """The (cached) GAF interpolator at Mach ``mach``."""
        key = round(float(mach), 9)
        if key not in self._interp:
            self._interp[key] = GafInterpolator(self.gaf, mach, self.interpolation)
        return self._interp[key]

    # ----------------------------------------------------------------------------- matrices
    def pencil(self, k: np.ndarray, V, rho, mach):
        """Damping and stiffness of the p-k pencil at each root's k.

        Parameters
        ----------
        k : ndarray, shape (R,)
            Reduced frequencies (k = omega b / V).
        V, rho, mach : float or ndarray, shape (R,)
            Flight point (one for all roots, or one per root).

        Returns
        -------
        C, Kt : ndarray, shape (R, n, n)
            C = B_hh + B_s - rho b V Q^I/(2k) and Kt = K_hh - q Q^R (Nastran PK equation; b = cbar/2).
        outside : ndarray of bool, shape (R,)
        """
        R = np.size(k)
        V, rho, mach = (np.broadcast_to(np.asarray(a, dtype=float), (R,)) for a in (V, rho, mach))
        G, kc, _, outside = self._linearised(np.asarray(k, dtype=float).reshape(R), mach)
        kb = kc[:, None, None]
        cd = (0.5 * rho * self.b * V)[:, None, None]
        q = (0.5 * rho * V * V)[:, None, None]
        C = self.B[None] - cd * (G[:, 2] + kb * G[:, 3])  # rho cbar V Q^I / (4k), Nastran PK
        if self._hyst:  # i g K -> (g/omega) K p
            C = C + self._hysteretic(k, V)[:, None, None] * self.system.stiffness[None]
        Kt = self.system.stiffness[None] - q * (G[:, 0] + kb * G[:, 1])
        return C, Kt, outside

    def _hysteretic(self, k: np.ndarray, V: np.ndarray) -> np.ndarray:
        """g(omega) / omega per root: hysteretic damping i g K written as (g / omega) K p."""
        omega = k * V / self.b
        g = self.system.structural.at(omega / (2 * np.pi))
        return np.where(omega > 1e-12, g / np.maximum(omega, 1e-300), 0.0)

    def _linearised(self, k: np.ndarray, mach: np.ndarray):
        """:meth:`GafInterpolator.linearised` for roots at their own Mach numbers."""
        machs = np.unique(mach)
        if machs.size == 1:
            return self.interpolator(machs[0]).linearised(k)
        n = self.system.n
        G, kc = np.empty((k.size, 4, n, n)), np.empty(k.size)
        sloped, outside = np.empty(k.size, dtype=bool), np.empty(k.size, dtype=bool)
        for m in machs:
            sel = mach == m
            G[sel], kc[sel], sloped[sel], outside[sel] = self.interpolator(m).linearised(k[sel])
        return G, kc, sloped, outside

    # ----------------------------------------------------------------------------- kernels
    def correct(self, state: RootState, V: float, rho: float, mach: float,
                p_start: np.ndarray | None = None, newton: bool = True,
                retry: bool = True) -> RootState:
        """Converge every root at (V, rho, M) from ``state`` by two-sided Rayleigh-quotient iteration.

        Each iteration, batched over the unconverged roots and with one gather of the GAF
        interpolant at each root's current k: the two-sided Rayleigh functional w^H T(p, k) u = 0 (a
        quadratic in p; Ruhe 1973) gives p at the root's current k, and its derivative
        dp/dk = -w^H (p dC/dk + dKt/dk) u / w^H (2 M p + C) u gives a Newton step on the matching
        condition f(k) = b Im p(k) / V - k = 0 (:func:`flutter.linalg.rayleigh`). A root is
        converged when p agrees with the linearised prediction of the previous iteration and the k
        mismatch moves p by less than ``tol``; that test needs no factorisation. Otherwise one LU of
        T(p) per root gives the next right and left vectors (inverse iteration,
        :func:`flutter.linalg.pencil_system`). ``p_start`` (predicted eigenvalues) replaces
        ``state.p`` as the first guess. Roots the Newton update fails to converge within
        ``NEWTON_ITER`` iterations are retried (if ``retry``) with plain substitution of k (slower,
        linearly convergent, up to ``max_iter`` iterations).
        """
        p = (state.p if p_start is None else p_start).copy()
        u, w = state.u.copy(), state.w.copy()
        R = p.size
        V, rho, mach = (np.broadcast_to(np.asarray(a, dtype=float), (R,)) for a in (V, rho, mach))
        b_V = self.b / V
        cd_all = 0.5 * rho * self.b * V           # rho cbar V / 4, Nastran PK damping term
        q_all = 0.5 * rho * V * V
        # one interpolator for all roots when they share a Mach number (the usual case)
        interp = self.interpolator(mach[0]) if np.all(mach == mach[0]) else None
        done = np.zeros(R, dtype=bool)
        solved = np.zeros(R, dtype=bool)          # at least one inverse iteration at this point
        outside = np.zeros(R, dtype=bool)
        kk = b_V * np.abs(p.imag)                 # k at which each root's pencil is evaluated
        act = np.arange(R)
        with np.errstate(divide="ignore", invalid="ignore"):
            for _ in range(min(self.max_iter, NEWTON_ITER) if newton else self.max_iter):
                k, bv = kk[act], b_V[act]
                G, kc, sloped, out = interp.linearised(k) if interp is not None else \
                    self._linearised(k, mach[act])
                outside[act] = out
                cd, q, pa, ua, wa = cd_all[act], q_all[act], p[act], u[act], w[act]
                hc = self._hysteretic(k, V[act]) if self._hyst else None
                pn, dpdk = rayleigh(G, kc, sloped, cd, q, hc, self._MKB, ua, wa, pa)
                flip = pn.imag < 0                  # report the root with Im p >= 0 (conjugate pair)
                pc = np.where(flip, pn.conj(), pn)
                dpc = np.where(flip, dpdk.conj(), dpdk)
                f = bv * pc.imag - k                # matching condition, Nastran PK
                ptol = self.tol * np.maximum(np.abs(pn), self.scale)
                conv = solved[act] & (np.abs(pc - pa) <= ptol) & (np.abs(dpc * f) <= ptol)
                done[act[conv]] = True
                p[act[conv]] = pc[conv]
                keep = ~conv
                if not keep.any():
                    break
                if not keep.all():
                    act, G, kc, cd, q, ua, wa = act[keep], G[keep], kc[keep], cd[keep], q[keep], \
                        ua[keep], wa[keep]
                    pn, pc, dpc, f, k, bv, flip = pn[keep], pc[keep], dpc[keep], f[keep], k[keep], \
                        bv[keep], flip[keep]
                    hc = hc[keep] if hc is not None else None
                # inverse iteration at (pn, k): eigenvectors of the pencil at the current k
                un, wn = inverse_iteration(*pencil_system(G, kc, cd, q, hc, pn, self.system.mass,
                                                          self._KBM, ua, wa))
                # a defective root at p = 0 (surge of a free aircraft: no aerodynamic force, T(0) u
                # = 0 and T'(0) u = 0) gives no right-hand side: its vectors are already exact
                lost = ~(np.isfinite(un).all(axis=1) & np.isfinite(wn).all(axis=1))
                lost &= np.abs(pn) <= 1e-9 * self.scale
                un[lost], wn[lost] = ua[lost], wa[lost]
                un[flip], wn[flip] = un[flip].conj(), wn[flip].conj()
                u[act], w[act] = un, wn
                solved[act] = True
                # k update: Newton on f(k) = b Im p(k) / V - k, plain substitution where unsafe
                k_sub = bv * pc.imag
                fp = bv * dpc.imag - 1.0
                k_new = k - f / fp
                use = newton & np.isfinite(k_new) & (fp < 0) & (k_new >= 0) & \
                    (np.abs(k_new - k_sub) <= 0.5 * np.maximum(k_sub, bv * self.scale))
                k_next = np.where(use, k_new, k_sub)
                kk[act] = k_next
                p[act] = pc + dpc * (k_next - k)    # linearised prediction at the new k
        new = RootState(p, u, w, done, outside)
        if newton and retry and not done.all():
            start = state if p_start is None else RootState(p_start, state.u, state.w,
                                                            state.converged, state.outside)
            new = self.retry(new, start, V, rho, mach)
        return new

    def retry(self, new: RootState, start: RootState, V, rho, mach) -> RootState:
        """Re-solve the not-converged roots of ``new`` from their first guess in ``start`` with plain
        substitution of k (:meth:`correct` with ``newton=False``)."""
        bad = np.flatnonzero(~new.converged)
        R = new.p.size
        V, rho, mach = (np.broadcast_to(np.asarray(a, dtype=float), (R,))[bad] for a in (V, rho, mach))
        again = self.correct(RootState(start.p[bad], start.u[bad], start.w[bad],
                                       new.converged[bad], new.outside[bad]),
                             V, rho, mach, newton=False)
        out = RootState(new.p.copy(), new.u.copy(), new.w.copy(), new.converged.copy(),
                        new.outside.copy())
        out.p[bad], out.u[bad], out.w[bad] = again.p, again.u, again.w
        out.converged[bad], out.outside[bad] = again.converged, again.outside
        return out

    def start(self, V: float, rho: float, mach: float) -> RootState:
        """Roots at the first flight point.

        Elastic roots are followed up from their in-vacuo modes at a tiny speed. Rigid-body roots
        (in-vacuo frequency below ``rigid_hz``) cannot be: at V -> 0 all of them sit at p = 0, so a
        continuation from there picks an eigenvalue branch at random, and the p-k's k-matching
        has several solutions on the near-zero branch (the plunge / flight-path pair), because a
        small change of Q^R with k moves a root that has no structural stiffness a lot. Two rigid
        roots then settled on that one branch at two matching k, and the short period was never
        followed (Nastran's bah_plane: two slightly unstable ~0 Hz roots instead of a short period
        with g ~ -2.3). They start instead from the eigenvalues of the quasi-steady system at the
        first flight point (:meth:`_rigid_start`): one root per eigenvalue branch.
        """
        n = self.system.n
        rigid = np.flatnonzero(self.omega0 < 2 * np.pi * self.rigid_hz)
        elastic = np.setdiff1d(np.arange(n), rigid)
        phi = self.phi / np.linalg.norm(self.phi, axis=0)
        p = 1j * self.omega0.astype(complex)
        state = RootState(p, phi.T.astype(complex), phi.T.astype(complex),
                          np.ones(n, dtype=bool), np.zeros(n, dtype=bool))
        if rigid.size:
            state = _subset(state, elastic)
        if elastic.size:
            state = self.correct(state, 1e-3 * V, rho, mach)
            state = self.advance(state, (1e-3 * V, rho, mach), (V, rho, mach))
        if not rigid.size:
            return state
        first = self.correct(self._rigid_start(rigid, V, rho, mach), V, rho, mach)
        order = np.argsort(np.concatenate([rigid, elastic]))
        both = _stack_states([first, state])
        return RootState(*(getattr(both, f)[order] for f in ("p", "u", "w", "converged", "outside")))

    def _rigid_start(self, rigid: np.ndarray, V: float, rho: float, mach: float) -> RootState:
        """First guesses of the rigid-body roots: eigenvalues of the quasi-steady p-k system.

        The first-order matrix of [M p^2 + C(0) p + K_t(0)] (Q^R and Q^I/k at k -> 0) has 2 n
        eigenvalues; :func:`flutter.rigid_start.rigid_branches` picks the branch of each rigid mode
        (oscillatory pairs first, one root each, then real ones by |p|), returned with its right and
        left vectors.
        """
        n, nr = self.system.n, rigid.size
        C, Kt, _ = self.pencil(np.zeros(1), V, rho, mach)
        Minv = np.linalg.inv(self.system.mass)
        A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ Kt[0], -Minv @ C[0]]])
        lam, Y, X = sla.eig(A, left=True, right=True)
        U = X[:n].T                                   # right vectors of the quadratic, (2n, n)
        W = (Minv.T @ Y[n:]).T                        # left: w^H = y_2^H M^-1
        pick = rigid_branches(lam, U, self.system.mass @ self.phi, rigid, self.scale)
        p = np.where(lam[pick].imag < 0, lam[pick].conj(), lam[pick])
        flip = lam[pick].imag < 0
        u, w = unit_rows(U[pick]), unit_rows(W[pick])
        u[flip], w[flip] = u[flip].conj(), w[flip].conj()
        return RootState(p.astype(complex), u, w, np.ones(nr, dtype=bool), np.zeros(nr, dtype=bool))

    def advance(self, state: RootState, frm: tuple, to: tuple, depth: int = 0) -> RootState:
        """Continue all roots from flight point ``frm`` to ``to`` (V, rho, M), bisecting bad steps.

        Predictor: linear extrapolation of each eigenvalue and of its phase-aligned right and left
        eigenvectors along the path (slopes of the last step, :meth:`predict`).
        A step is bisected (up to ``max_depth`` times) when a root lands closer to another root's
        prediction than to its own, loses eigenvector correlation while its eigenvalue jumps, or two
        roots land on the same eigenpair.
        """
        guess = self.predict(state, frm, to)
        # the slow retry of a root Newton failed is spent only on a step that would be kept: a
        # strict step fails on it anyway, and a step whose roots jump is bisected anyway
        last = depth >= self.max_depth
        new = self.correct(guess, *to, retry=last)
        if not last and depth >= 3 and not new.converged.all() and \
                self._step_ok(state, new, guess.p, strict=False):
            new = self.retry(new, guess, *to)
        return self.accept(state, new, guess.p, frm, to, depth)

    @staticmethod
    def predict(state: RootState, frm: tuple, to: tuple) -> RootState:
        """First guess at ``to``: eigenvalues and (phase-aligned) eigenvectors extrapolated linearly
        along the path from the last step."""
        h = path_length(frm, to)
        pred = state.p + (state.slope * h if state.slope is not None else 0)
        pred = np.where(pred.imag < 0, pred.real + 0j, pred)
        u, w = state.u, state.w
        if state.du is not None:
            u = u + state.du * h
            w = w + state.dw * h
            u = u / np.linalg.norm(u, axis=1, keepdims=True)
            w = w / np.linalg.norm(w, axis=1, keepdims=True)
        return RootState(pred, u, w, state.converged, state.outside)

    def accept(self, state: RootState, new: RootState, pred: np.ndarray, frm: tuple, to: tuple,
               depth: int) -> RootState:
        """Keep a corrected step if it passes the tracking checks, else bisect it (``advance``) or,
        at the smallest step, reseed the roots that still jump; sets the predictor slope."""
        h = path_length(frm, to)
        strict = depth < 3
        if not self._step_ok(state, new, pred, strict=strict):
            if depth < self.max_depth:
                mid = tuple(0.5 * (a + b) for a, b in zip(frm, to))
                half = self.advance(state, frm, mid, depth + 1)
                return self.advance(half, mid, to, depth + 1)
            new, reseeded = self._reseed(new, pred, *to)
        else:
            reseeded = np.zeros(0, dtype=int)
        if h > 0:
            # a reseeded root jumped (e.g. a pair turning real): its jump is no slope to predict with
            new.slope = (new.p - state.p) / h
            new.slope[reseeded] = 0.0
            new.u, new.w = _aligned(new.u, state.u), _aligned(new.w, state.w)
            new.du, new.dw = (new.u - state.u) / h, (new.w - state.w) / h
            new.du[reseeded] = 0.0
            new.dw[reseeded] = 0.0
        else:
            new.slope = None
        return new

    def _reseed(self, new: RootState, pred: np.ndarray, V: float, rho: float,
                mach: float) -> tuple[RootState, np.ndarray]:
        """Restart roots that still jump or collide at the smallest step (e.g. a pair turning real):
        full eigen-decomposition of the first-order p-k matrix at the root's k, nearest eigenvalue
        not taken by another root, then the usual correction. Returns the state and the indices of
        the restarted roots."""
        sep = np.abs(pred[:, None] - pred[None, :])
        np.fill_diagonal(sep, np.inf)
        jump = np.abs(new.p - pred) / np.maximum(sep.min(axis=1), self.scale)
        dp = np.abs(new.p[:, None] - new.p[None, :])
        np.fill_diagonal(dp, np.inf)
        rel = dp / np.maximum(np.abs(new.p), self.scale)[:, None]
        dup = rel.min(axis=1) <= 1e-6
        later = np.any(np.tril(rel <= 1e-9, k=-1), axis=1)  # second of an identical pair
        bad = np.flatnonzero((jump > 0.5) | (dup & (jump > 0.05)) | later)
        if bad.size == 0:
            return new, bad
        n = self.system.n
        Minv = np.linalg.inv(self.system.mass)
        taken = list(new.p[np.setdiff1d(np.arange(new.p.size), bad)])
        for r in bad:
            p_r, ok = pred[r], False
            tk = np.asarray(taken, dtype=complex)
            for _ in range(self.max_iter):  # plain per-root p-k: all eigenvalues per iteration
                k = np.array([self.b * abs(p_r.imag) / V])
                C, Kt, out = self.pencil(k, V, rho, mach)
                A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ Kt[0], -Minv @ C[0]]])
                lam = np.linalg.eigvals(A)
                lam = np.where(lam.imag < 0, lam.conj(), lam)
                clash = np.abs(lam[:, None] - tk[None, :]) <= 1e-6 * np.maximum(np.abs(tk), self.scale)
                free = [j for j in np.argsort(np.abs(lam - p_r)) if not clash[j].any()]
                j = free[0] if free else int(np.argmin(np.abs(lam - p_r)))
                step = abs(lam[j] - p_r)
                p_r = lam[j]
                if step <= self.tol * max(abs(p_r), self.scale):
                    ok = bool(free)
                    break
            taken.append(p_r)
            # the eigenvector of the last matrix, at its eigenvalue p_r (or its conjugate)
            lam, X = np.linalg.eig(A)
            j = int(np.argmin(np.abs(np.where(lam.imag < 0, lam.conj(), lam) - p_r)))
            u = X[:n, j] if lam[j].imag >= 0 else X[:n, j].conj()
            u = u / np.linalg.norm(u)
            new.p[r], new.u[r], new.w[r] = p_r, u, u.conj()
            new.converged[r], new.outside[r] = ok, bool(out[0])
        return new, bad

    def _step_ok(self, old: RootState, new: RootState, pred: np.ndarray, strict: bool) -> bool:
        """Accept a step by eigenvalue continuity, eigenvector correlation (MAC) and distinctness."""
        sep = np.abs(pred[:, None] - pred[None, :])
        np.fill_diagonal(sep, np.inf)
        near = np.maximum(sep.min(axis=1), self.scale)
        jump = np.abs(new.p - pred) / near
        if np.any(jump > 0.5):
            return False
        mac = np.abs(np.einsum("ri,ri->r", old.u.conj(), new.u)) ** 2
        if np.any((mac < self.mac_min) & (jump > 0.05)):
            return False
        if strict and not np.all(new.converged | ~old.converged):
            return False
        dp = np.abs(new.p[:, None] - new.p[None, :])
        close = dp <= 1e-6 * np.maximum(np.abs(new.p)[:, None], self.scale)
        np.fill_diagonal(close, False)
        if close.any():
            same = close & (np.abs(new.u.conj() @ new.u.T) ** 2 > 0.99)
            moved = jump > 0.05
            exact = dp <= 1e-9 * np.maximum(np.abs(new.p)[:, None], self.scale)  # never a real EP
            if np.any(same & (moved[:, None] | moved[None, :] | exact)):
                return False
        return True

    # ----------------------------------------------------------------------------- outputs
    def damping(self, p: np.ndarray, V: np.ndarray) -> np.ndarray:
        """Damping g = 2 Re(p)/Im(p) (p = omega(gamma + i)); g = p cbar/(V ln 2) for real roots."""
        p = np.asarray(p)
        return root_damping(p, V, self.b, np.abs(p.imag) <= 1e-9 * np.maximum(np.abs(p), self.scale))


def _subset(state: RootState, idx: np.ndarray) -> RootState:
    """The roots ``idx`` of a state (new arrays)."""
    return RootState(state.p[idx], state.u[idx], state.w[idx], state.converged[idx],
                     state.outside[idx])


def _stack_states(states: list[RootState]) -> RootState:
    """Roots of several states side by side (new arrays; slopes dropped)."""
    return RootState(*(np.concatenate([getattr(s, f) for s in states])
                       for f in ("p", "u", "w", "converged", "outside")))


def _aligned(u: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """Vectors u (R, n) rotated in phase so that ref_r^H u_r is real and >= 0."""
    c = np.einsum("ri,ri->r", ref.conj(), u)
    return u * np.exp(-1j * np.angle(c))[:, None]
