"""The p-k flutter method (Nastran PK / PKNL) with continuation and Rayleigh-quotient correction.

For each flight point (V, rho, M) and each root, the p-k equation (MSC Nastran Aeroelastic Analysis
User's Guide, PK method, eq. 3-xx; Hassig, J. Aircraft 8(11), 1971)

    [ M_hh p^2 + (B_hh - rho cbar V Q^I_hh(k) / (4 k)) p + (K_hh - rho V^2 Q^R_hh(k) / 2) ] u = 0,

is solved with the root's own reduced frequency k = omega b / V (b = cbar / 2), p = omega (gamma + i)
and g = 2 gamma. Instead of a full eigen-decomposition per root per iteration, every root is followed
from the previous flight point and corrected by two-sided Rayleigh-quotient iteration on the
quadratic pencil with k updated at every step (Ruhe, SIAM J. Numer. Anal. 10(4), 1973, nonlinear
Rayleigh functional / inverse iteration), batched over the roots. A step whose roots collide or whose
eigenvectors lose correlation with the previous point (MAC below ``mac_min``) is bisected, so roots
are tracked by continuity and eigenvector correlation, never by sorting.

Zero-frequency roots (rigid-body, divergence) are kept; their damping is Nastran's
g = p cbar / (V ln 2) (as printed in the F06 for KFREQ = 0 roots).
"""
from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
import xarray as xr

from flutter.crossings import G_TOL, Crossing, find_brackets, illinois, interpolate_zero
from flutter.gafinterp import GafInterpolator
from flutter.linalg import inverse_iteration, path_length, real_matvec
from flutter.results import vg_dataset, attach_crossings
from flutter.system import ModalSystem
from structures.errors import InputError

LN2 = np.log(2.0)
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
        Relative convergence tolerance on p.
    max_iter : int
        Iterations per root and flight point before the point is flagged not converged.
    mac_min : float
        Minimum eigenvector correlation between consecutive points before the step is bisected.
    max_depth : int
        Maximum number of step bisections.
    """

    def __init__(self, system: ModalSystem, gaf, *, refc: float | None = None,
                 interpolation: str = "linear", tol: float = 1e-9, max_iter: int = 60,
                 mac_min: float = 0.7, max_depth: int = 8):
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
        self._interp: dict[float, GafInterpolator] = {}
        omega, self.phi = system.in_vacuo()
        self.omega0 = omega
        self.scale = 1e-3 * max(float(omega.max()), 1e-12)
        sd = system.structural
        self._hyst = (not sd.is_zero) and sd.kind == "hysteretic"
        B = system.damping.copy()
        if (not sd.is_zero) and sd.kind == "viscous":
            B = B + system.viscous_structural()
        self.B = B
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
    def pencil(self, k: np.ndarray, V: float, rho: float, mach: float, slopes: bool = False):
        """Damping and stiffness of the p-k pencil at each root's k (and their k-derivatives).

        Parameters
        ----------
        k : ndarray, shape (R,)
            Reduced frequencies (k = omega b / V).
        V, rho, mach : float or ndarray, shape (R,)
            Flight point (one for all roots, or one per root).
        slopes : bool
            Also return dC/dk and dKt/dk (aerodynamic part; the k-dependence of the hysteretic
            structural damping is left out of them).

        Returns
        -------
        C, Kt : ndarray, shape (R, n, n)
            C = B_hh + B_s - rho b V Q^I/(2k) and Kt = K_hh - q Q^R (Nastran PK equation; b = cbar/2).
        outside : ndarray of bool, shape (R,)
        dC, dKt : ndarray, shape (R, n, n)
            Only with ``slopes=True``.
        """
        QR, D, dQR, dD, outside = self._gafs(k, mach, slopes)
        V, rho = np.asarray(V, dtype=float), np.asarray(rho, dtype=float)
        cd = (0.5 * rho * self.b * V).reshape(-1, 1, 1)
        q = (0.5 * rho * V * V).reshape(-1, 1, 1)
        C = self.B[None] - cd * D  # rho cbar V Q^I / (4k), Nastran PK
        if self._hyst:  # i g K -> (g/omega) K p
            C = C + self._hysteretic(k, V)[:, None, None] * self.system.stiffness[None]
        Kt = self.system.stiffness[None] - q * QR
        if not slopes:
            return C, Kt, outside
        return C, Kt, outside, (-cd) * dD, (-q) * dQR

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

    def _gafs(self, k: np.ndarray, mach, slopes: bool):
        """Interpolated Q^R, Q^I/k (and slopes) at each root's k and Mach number."""
        machs = np.unique(np.asarray(mach, dtype=float))
        if machs.size == 1:
            return self.interpolator(machs[0]).with_slopes(k, slopes)
        mach = np.broadcast_to(np.asarray(mach, dtype=float), k.shape)
        n = self.system.n
        out = [np.empty((k.size, n, n)) for _ in range(4 if slopes else 2)]
        outside = np.zeros(k.shape, dtype=bool)
        for m in machs:
            sel = mach == m
            vals = self.interpolator(m).with_slopes(k[sel], slopes)
            for arr, v in zip(out, vals[:4] if slopes else vals[:2]):
                arr[sel] = v
            outside[sel] = vals[4]
        return (*out, outside) if slopes else (*out, None, None, outside)

    # ----------------------------------------------------------------------------- kernels
    def correct(self, state: RootState, V: float, rho: float, mach: float,
                p_start: np.ndarray | None = None, newton: bool = True,
                retry: bool = True) -> RootState:
        """Converge every root at (V, rho, M) from ``state`` by two-sided Rayleigh-quotient iteration.

        Each iteration, batched over the unconverged roots: the two-sided Rayleigh functional
        w^H T(p, k) u = 0 (a quadratic in p; Ruhe 1973) gives p at the root's current k, and its
        derivative dp/dk = -w^H (p dC/dk + dKt/dk) u / w^H (2 M p + C) u gives a Newton step on the
        matching condition f(k) = b Im p(k) / V - k = 0. A root is converged when p agrees with the
        linearised prediction of the previous iteration and the k mismatch moves p by less than
        ``tol``; that test needs no factorisation. Otherwise one LU of T(p) per root gives the next
        right and left vectors (inverse iteration). ``p_start`` (predicted eigenvalues) replaces
        ``state.p`` as the first guess. Roots the Newton update fails to converge within
        ``NEWTON_ITER`` iterations are retried (if ``retry``) with plain substitution of k (slower,
        linearly convergent, up to ``max_iter`` iterations).
        """
        M = self.system.mass
        p = (state.p if p_start is None else p_start).copy()
        u, w = state.u.copy(), state.w.copy()
        R = p.size
        V, rho, mach = (np.broadcast_to(np.asarray(a, dtype=float), (R,)) for a in (V, rho, mach))
        b_V = self.b / V
        done = np.zeros(R, dtype=bool)
        solved = np.zeros(R, dtype=bool)          # at least one inverse iteration at this point
        outside = np.zeros(R, dtype=bool)
        kk = b_V * np.abs(p.imag)                 # k at which each root's pencil is evaluated
        kscale = b_V * self.scale
        act = np.arange(R)
        M, K, B, n = self.system.mass, self.system.stiffness, self.B, self.system.n
        for it in range(min(self.max_iter, NEWTON_ITER) if newton else self.max_iter):
            k, bv, ks = kk[act], b_V[act], kscale[act]
            G, kc, sloped, out = self._linearised(k, mach[act])
            outside[act] = out
            cd = 0.5 * rho[act] * self.b * V[act]  # rho cbar V / 4, Nastran PK damping term
            q = 0.5 * rho[act] * V[act] ** 2
            ua, wa, pa = u[act], w[act], p[act]
            wc = wa.conj()
            # Q^R u, Q^I/k u and their k-derivatives from one batched product
            Gu = real_matvec(G.reshape(-1, 4 * n, n), ua).reshape(-1, 4, n)
            kb, sl = kc[:, None], sloped[:, None]
            Mu, Ku0 = ua @ M.T, ua @ K.T
            Ku = Ku0 - q[:, None] * (Gu[:, 0] + kb * Gu[:, 1])      # (K_hh - q Q^R) u
            Cu = ua @ B.T - cd[:, None] * (Gu[:, 2] + kb * Gu[:, 3])  # (B - rho b V Q^I/(2k)) u
            hc = self._hysteretic(k, V[act]) if self._hyst else None
            if hc is not None:
                Cu = Cu + hc[:, None] * Ku0
            a2 = np.einsum("ri,ri->r", wc, Mu)
            a1 = np.einsum("ri,ri->r", wc, Cu)
            a0 = np.einsum("ri,ri->r", wc, Ku)
            disc = np.sqrt(a1 * a1 - 4 * a2 * a0 + 0j)
            r1, r2 = (-a1 + disc) / (2 * a2), (-a1 - disc) / (2 * a2)
            pn = np.where(np.abs(r1 - pa) <= np.abs(r2 - pa), r1, r2)  # Rayleigh functional root
            flip = pn.imag < 0
            dTu = np.where(sl, -(pn * cd)[:, None] * Gu[:, 3] - q[:, None] * Gu[:, 1], 0.0)
            with np.errstate(divide="ignore", invalid="ignore"):
                dpdk = -np.einsum("ri,ri->r", wc, dTu) / (2 * a2 * pn + a1)  # implicit function thm
            dpdk = np.where(np.isfinite(dpdk), dpdk, 0.0)
            pc = np.where(flip, pn.conj(), pn)
            dpc = np.where(flip, dpdk.conj(), dpdk)
            f = bv * pc.imag - k                    # matching condition, Nastran PK
            ptol = self.tol * np.maximum(np.abs(pn), self.scale)
            conv = solved[act] & (np.abs(pc - pa) <= ptol) & (np.abs(dpc * f) <= ptol)
            done[act[conv]] = True
            p[act[conv]] = pc[conv]
            keep = ~conv
            if not keep.any():
                break
            if not keep.all():
                act = act[keep]
                pn, pc, dpc, f, k, flip = pn[keep], pc[keep], dpc[keep], f[keep], k[keep], flip[keep]
                bv, ks, G, kc, cd, q = bv[keep], ks[keep], G[keep], kc[keep], cd[keep], q[keep]
                ua, wa, Mu, Cu = ua[keep], wa[keep], Mu[keep], Cu[keep]
                hc = hc[keep] if hc is not None else None
            # inverse iteration with T(p) = K_t + p C + p^2 M at the current k (eigenvectors of the
            # pencil at k); right-hand sides T'(p) u and T'(p)^H w with T' = 2 M p + C (C, M real)
            kb3 = kc[:, None, None]
            Cm = B - cd[:, None, None] * (G[:, 2] + kb3 * G[:, 3])
            if hc is not None:
                Cm = Cm + hc[:, None, None] * K
            pb = pn[:, None, None]
            T = (K - q[:, None, None] * (G[:, 0] + kb3 * G[:, 1])) + pb * (Cm + pb * M)
            x = 2 * pn[:, None] * Mu + Cu
            y = 2 * pn.conj()[:, None] * (wa @ M) + real_matvec(Cm.transpose(0, 2, 1), wa)
            un, wn = inverse_iteration(T, x, y)
            un[flip] = un[flip].conj()
            wn[flip] = wn[flip].conj()
            u[act], w[act] = un, wn
            solved[act] = True
            # k update: Newton on f(k) = b Im p(k) / V - k, plain substitution where Newton is unsafe
            k_sub = bv * pc.imag
            fp = bv * dpc.imag - 1.0
            with np.errstate(divide="ignore", invalid="ignore"):
                k_new = k - f / fp
            use = newton & np.isfinite(k_new) & (fp < 0) & (k_new >= 0) & \
                (np.abs(k_new - k_sub) <= 0.5 * np.maximum(k_sub, ks))
            k_next = np.where(use, k_new, k_sub)
            kk[act] = k_next
            p[act] = pc + dpc * (k_next - k)          # linearised prediction at the new k
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
        """Roots at the first flight point, followed up from in-vacuo modes at a tiny speed."""
        n = self.system.n
        phi = self.phi / np.linalg.norm(self.phi, axis=0)
        p = 1j * self.omega0.astype(complex)
        state = RootState(p, phi.T.astype(complex), phi.T.astype(complex),
                          np.ones(n, dtype=bool), np.zeros(n, dtype=bool))
        state = self.correct(state, 1e-3 * V, rho, mach)
        return self.advance(state, (1e-3 * V, rho, mach), (V, rho, mach))

    def advance(self, state: RootState, frm: tuple, to: tuple, depth: int = 0) -> RootState:
        """Continue all roots from flight point ``frm`` to ``to`` (V, rho, M), bisecting bad steps.

        Predictor: linear extrapolation of each eigenvalue along the path (slope of the last step).
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
            for _ in range(self.max_iter):  # plain per-root p-k: full eig per iteration
                k = np.array([self.b * abs(p_r.imag) / V])
                C, Kt, out = self.pencil(k, V, rho, mach)
                A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ Kt[0], -Minv @ C[0]]])
                lam, X = np.linalg.eig(A)
                neg = lam.imag < 0
                lam, X = np.where(neg, lam.conj(), lam), np.where(neg[None, :], X.conj(), X)
                clash = np.abs(lam[:, None] - tk[None, :]) <= 1e-6 * np.maximum(np.abs(tk), self.scale)
                free = [j for j in np.argsort(np.abs(lam - p_r)) if not clash[j].any()]
                j = free[0] if free else int(np.argmin(np.abs(lam - p_r)))
                step = abs(lam[j] - p_r)
                p_r = lam[j]
                if step <= self.tol * max(abs(p_r), self.scale):
                    ok = bool(free)
                    break
            taken.append(p_r)
            u = X[:n, j] / np.linalg.norm(X[:n, j])
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
        real = np.abs(p.imag) <= 1e-9 * np.maximum(np.abs(p), self.scale)
        with np.errstate(divide="ignore", invalid="ignore"):
            g = np.where(real, p.real * 2 * self.b / (np.asarray(V) * LN2),
                         2.0 * p.real / np.where(real, 1.0, p.imag))
        return g


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


def _aligned(u: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """Vectors u (R, n) rotated in phase so that ref_r^H u_r is real and >= 0."""
    c = np.einsum("ri,ri->r", ref.conj(), u)
    return u * np.exp(-1j * np.angle(c))[:, None]


def _stack(states: list[RootState]) -> RootState:
    return RootState(*(np.concatenate([getattr(s, f) for s in states])
                       for f in ("p", "u", "w", "converged", "outside")))


def _part(state: RootState, sl: slice) -> RootState:
    return RootState(state.p[sl], state.u[sl], state.w[sl], state.converged[sl], state.outside[sl])


def sweep_states_many(solver: PKSolver, cases: list[tuple]) -> list[list[RootState]]:
    """Several sweeps continued in lockstep, their roots corrected together.

    At every sweep index the roots of all cases (e.g. the Mach numbers of a PK analysis) are
    corrected in one batched call (each root at its own case's flight point); a case whose step
    fails the tracking checks is then bisected on its own (:meth:`PKSolver.accept`), so each case's
    result is that of :func:`sweep_states` on it alone.

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
                  g_tol: float = G_TOL, **options) -> list[xr.Dataset]:
    """Several p-k sweeps (e.g. one per Mach number or density) solved together.

    The roots of all cases are corrected in one batched call per sweep index
    (:func:`sweep_states_many`); each result equals ``pk_solve`` on that case alone.

    Parameters
    ----------
    system, gaf, sweep, refc, interpolation, refine, g_tol, **options
        As :func:`pk_solve`.
    cases : list of (velocity, density, mach)
        Each an array_like of shape (npts_c,) or a scalar (broadcast), as in :func:`pk_solve`.

    Returns
    -------
    list of xarray.Dataset, one per case, as :func:`pk_solve`.
    """
    if sweep not in ("velocity", "density"):
        raise InputError(f"p-k: unknown sweep {sweep!r}. Fix: use 'velocity' or 'density'.")
    flights = []
    for velocity, density, mach in cases:
        V, rho, M = np.broadcast_arrays(np.atleast_1d(np.asarray(velocity, dtype=float)),
                                        np.atleast_1d(np.asarray(density, dtype=float)),
                                        np.atleast_1d(np.asarray(mach, dtype=float)))
        check_sweep(V, rho, M, sweep)
        flights.append((V.copy(), rho.copy(), M.copy()))
    solver = PKSolver(system, gaf, refc=refc, interpolation=interpolation, **options)
    for m in np.unique(np.concatenate([M for _, _, M in flights])):
        solver.interpolator(m)
    all_states = sweep_states_many(solver, flights)
    return [_case_dataset(solver, states, *flight, sweep=sweep, interpolation=interpolation,
                          refine=refine, g_tol=g_tol) for states, flight in zip(all_states, flights)]


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
    for r, i in find_brackets(g, g_tol):
        if refine:
            t, s, ok = _refine(solver, states, pts, r, i, g[i, r], g[i + 1, r])
            pr, ur = s.p[r], s.u[r]
        else:
            t = interpolate_zero(g[i, r], g[i + 1, r])
            pr = p[i, r] + t * (p[i + 1, r] - p[i, r])
            ur = u[i, r] if t < 0.5 else u[i + 1, r]
            ok = True
        vectors.append(ur)
        Vc, rc, Mc = (a + t * (b - a) for a, b in zip(pts[i], pts[i + 1]))
        real = abs(pr.imag) <= 1e-9 * max(abs(pr), solver.scale)
        crossings.append(Crossing(root=r + 1, index=i, t=float(t), velocity=float(Vc),
                                  density=float(rc), mach=float(Mc),
                                  frequency=0.0 if real else float(abs(pr.imag) / (2 * np.pi)),
                                  kind="divergence" if real else "flutter",
                                  converged=bool(ok and conv[i, r] and conv[i + 1, r]),
                                  refined=refine))
    ds = vg_dataset(p, u, g, conv, V, rho, M, b=solver.b, modes=system.modes, sweep=sweep,
                    method="PKNL" if sweep == "density" else "PK",
                    attrs={"interpolation": interpolation, "g_tol": g_tol,
                           "structural_damping": system.structural.kind
                           if not system.structural.is_zero else "none"})
    return attach_crossings(ds, crossings, np.array(vectors).reshape(len(crossings), system.n))
