"""Chen's g-method (damping perturbation) flutter solution with the reduced-frequency sweep.

P. C. Chen, "Damping Perturbation Method for Flutter Solution: The g-Method", AIAA J. 38(9), 2000,
1519-1524. With the nondimensional Laplace variable p_bar = p b / V = g + i k (b = refc / 2,
k = omega b / V; g here is Chen's real part of p_bar, the reported damping is 2 Re p / Im p), the
GAFs off the imaginary axis are expanded to first order about p_bar = i k (Chen's damping
perturbation; the paper was not at hand, so no equation numbers are given here):

    Q(p_bar) ~ Q(ik) + g Q'(ik),   Q'(ik) = dQ / d(ik) = -i dQ/dk,

exact at g = 0 and first-order accurate in g. p-k's Q^R(k) + p_bar Q^I(k) / k agrees with it except
for the k-derivative of Q^R off the axis (the term -i g dQ^R/dk), which is why p-k damping is only
exact at g = 0 and the g-method's is right to first order for the heavily damped rigid-body and
body-freedom roots. With Q^R and D = Q^I / k interpolated in k (flutter.gafinterp),

    Q'(ik)       = D + k dD/dk - i dQ^R/dk,
    Q - ik Q'    = Q^R - k dQ^R/dk - i k^2 dD/dk,

and the g-method flutter equation (Chen 2000, written in p_bar and scaled by (b/V)^2, q = rho V^2/2)

    [ M p_bar^2 + ((b/V) B - (rho b^2 / 2) Q') p_bar
      + (b/V)^2 K (1 + i g_s) - (rho b^2 / 2)(Q - ik Q') ] u = 0

is, for each k, a quadratic eigenproblem in p_bar with complex matrices (no conjugate pairs). A
root is a k where an eigenvalue has Im p_bar = k (Chen's root condition Im g = 0).

Chen's reduced-frequency sweep (RFS): at each flight point the
2 n eigenvalues are computed on a grid of k (one stacked ``np.linalg.eig``), followed as branches
across k by eigenvector correlation and continuity (flutter.tracking.assign), and every sign change
of Im p_bar_j(k) - k is refined by Illinois root-finding on k (flutter.crossings.illinois) to
|Im g| ~ 1e-10. At k = 0 the equation is real (Q^R is even in k, so dQ^R/dk = 0 there; hysteretic
damping, which has no zero-frequency equivalent, is dropped as in flutter.pk): its real eigenvalues
are the real (zero-frequency) roots, reported with Im p = 0 and Nastran's g = p cbar / (V ln 2).
Above the GAF table Q is held constant (zero slopes), so the equation no longer depends on k and a
branch still above Im p_bar = k at the table's end has its root at k = Im p_bar: those roots are
flagged not converged, with one warning per root.

Roots per flight point: the candidates (real roots at k = 0 and the k > 0 roots) outnumber the
modes (a complex pair gives one root, its two real limits two), so exactly system.n are kept: at
the first point by optimal assignment to the in-vacuo modes (modal participation and distance from
i omega_r; root r follows mode r, rigid modes first), then point to point by assignment to the
previous roots (eigenvector correlation and distance from the extrapolated eigenvalue). A complex
pair that splits into two real roots continues as the nearer real root, the other real root stays
a candidate and is picked up when a root needs it; the near-zero plunge / flight-path cluster of a
free-free aircraft is either one complex root with tiny k or real roots, whichever continues the
root. Missing candidates (never seen in the tests) repeat the previous point, flagged.

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

from flutter.crossings import (G_TOL, Crossing, drift_roots, find_brackets, illinois,
                               interpolate_zero, resolved_damping)
from flutter.gafinterp import GafInterpolator
from flutter.linalg import path_length, unit_rows
from flutter.parallel import map_cases
from flutter.pk import check_sweep
from flutter.results import attach_crossings, vg_dataset
from flutter.system import ModalSystem
from flutter.tracking import assign
from structures.common.errors import InputError

LN2 = np.log(2.0)
OPTIONS = ("nk", "rigid_hz")
_BIG = 1e30  # eigenvalue of a placeholder candidate: never preferred by the assignment


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
        sd = system.structural
        self._hyst = (not sd.is_zero) and sd.kind == "hysteretic"
        B = system.damping.copy()
        if (not sd.is_zero) and sd.kind == "viscous":
            B = B + system.viscous_structural()
        self.B = B
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
        A0 = Kc - h * Q0                     # g-method equation (Chen 2000) scaled by (b/V)^2
        A1 = s * self.B[None] - h * dQ
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
        """A root above the GAF table: k = Im p_bar by substitution (Q held, so one or two steps)."""
        for _ in range(20):
            k = float(lam.imag)
            lam, u = self._pick(k, lam, V, rho, mach)
            if abs(lam.imag - k) <= 1e-10 * max(abs(lam), 1e-12):
                break
        return complex(lam.real, float(lam.imag)), u

    def root_near(self, V: float, rho: float, mach: float, p_guess: complex):
        """The root nearest ``p_guess`` (rad/s) at one flight point, without a sweep.

        A real guess (Im p = 0) takes the nearest real eigenvalue at k = 0; otherwise a secant
        iteration on k solves Im p_bar(k) = k on the eigenvalue nearest the current estimate.

        Returns
        -------
        (p, u, converged) or None
            None where no such root is found (no real eigenvalue, k < 0, or no convergence).
        """
        s = self.b / V
        target = complex(p_guess) * s
        if target.imag == 0:
            lam, U, out = self.eig(np.zeros(1), V, rho, mach)
            real = np.flatnonzero(lam[0].imag == 0)
            if real.size == 0:
                return None
            j = real[np.argmin(np.abs(lam[0, real] - target))]
            return complex(lam[0, j].real / s, 0.0), U[0, j], True
        k0, (lam0, _) = target.imag, self._pick(target.imag, target, V, rho, mach, vectors=False)
        f0 = lam0.imag - k0
        k1 = k0 + f0 if f0 != 0 else k0
        for _ in range(30):
            if k1 < 0:
                return None
            lam1, _ = self._pick(k1, lam0, V, rho, mach, vectors=False)
            f1 = lam1.imag - k1
            if abs(f1) <= max(1e-8 * abs(lam1), 1e-10):
                lam, u = self._pick(k1, lam1, V, rho, mach)
                return complex(lam.real, k1) / s, u, not bool(self.interpolator(mach)(
                    np.array([k1]))[2][0])
            k0, f0, lam0, k1 = k1, f1, lam1, (k1 - f1 * (k1 - k0) / (f1 - f0) if f1 != f0
                                               else k1 + f1)
        return None

    # ----------------------------------------------------------------------------- outputs
    def damping(self, p: np.ndarray, V) -> np.ndarray:
        """g = 2 Re p / Im p; Nastran's g = p cbar / (V ln 2) for real roots (Im p = 0)."""
        p = np.asarray(p)
        with np.errstate(divide="ignore", invalid="ignore"):
            return np.where(p.imag == 0, p.real * 2 * self.b / (np.asarray(V) * LN2),
                            2.0 * p.real / np.where(p.imag == 0, 1.0, p.imag))


def _match(p_ref, u_ref, p, u, ok, out):
    """Exactly len(p_ref) roots out of the candidates (assignment; placeholders if too few)."""
    keep = ok | out                  # a sign change at a jump of the interpolant is no root
    if keep.sum() >= p_ref.size:
        p, u, ok, out = p[keep], u[keep], ok[keep], out[keep]
    n, m = p_ref.size, p.size
    if m < n:
        p = np.concatenate([p, np.full(n - m, _BIG + 0j)])
        u = np.concatenate([u, np.zeros((n - m, u.shape[1]), dtype=complex)])
        ok = np.concatenate([ok, np.zeros(n - m, dtype=bool)])
        out = np.concatenate([out, np.zeros(n - m, dtype=bool)])
    cols = assign(p_ref, u_ref, p, u)
    return p[cols], u[cols], ok[cols], out[cols], cols >= m


def _sweep(prob: GProblem, pts: list[tuple]):
    """Roots at every flight point, exactly n per point, tracked from the in-vacuo modes."""
    p_ref = 1j * prob.omega0.astype(complex)
    u_ref = (prob.system.mass @ prob.phi).T.astype(complex)   # in-vacuo modal participation
    P, Uv, C, O = [], [], [], []
    for i, pt in enumerate(pts):
        p, u, ok, out = prob.roots(*pt)
        if i >= 2:                       # extrapolated eigenvalues along the sweep
            h0, h1 = path_length(pts[i - 2], pts[i - 1]), path_length(pts[i - 1], pts[i])
            p_ref = P[-1] + (P[-1] - P[-2]) * (h1 / h0 if h0 > 0 else 0.0)
        elif i == 1:
            p_ref = P[-1]
        p, u, ok, out, missing = _match(p_ref, u_ref, p, u, ok, out)
        if missing.any():                # repeat the previous point (the in-vacuo mode at the first)
            p[missing] = P[-1][missing] if P else p_ref[missing]
            u[missing] = Uv[-1][missing] if P else unit_rows(u_ref[missing])
        P.append(p)
        Uv.append(u)
        C.append(ok & ~out & ~missing)
        O.append(out)
        u_ref = u
    return np.array(P), np.array(Uv), np.array(C), np.array(O)


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
    divergence crossing is already in that interval."""
    out = []
    seen = {c.index for c in crossings if c.kind == "divergence"}
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
            if not q0 < qd <= q1:
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
            Vc, rc, Mc = (a + t * (b - a) for a, b in zip(pts[i], pts[i + 1]))
            out.append((Crossing(root=r + 1, index=i, t=float(t), velocity=float(Vc),
                                 density=float(rc), mach=float(Mc), frequency=0.0,
                                 kind="divergence", converged=True, refined=True), ud))
    return out


def _refine_crossing(prob: GProblem, pts, P, U, r, i, g0, g1):
    """Zero of root r's damping between points i and i+1 by Illinois root-finding on the flight
    point. Each evaluation solves root r alone from its linear interpolation between the two points
    (:meth:`GProblem.root_near`); where that fails (e.g. the root turns real inside the bracket) a
    full reduced-frequency sweep is matched to the interpolated roots instead."""
    cache = {}

    def point(t):
        return tuple(a + t * (b - a) for a, b in zip(pts[i], pts[i + 1]))

    def fun(t):
        pt = point(t)
        guess = P[i] + t * (P[i + 1] - P[i])
        near = prob.root_near(*pt, guess[r])
        if near is not None:
            cache[t] = near
        else:
            p, u, ok, out = prob.roots(*pt)
            pr, ur, okr, outr, miss = _match(guess, U[i], p, u, ok, out)
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
        ``nk``: points of the k grid (default 60); ``rigid_hz``: rigid-body mode threshold [Hz]
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
        for velocity, density, mach in cases:
            V, rho, M = (a.astype(float).copy() for a in np.broadcast_arrays(
                *(np.atleast_1d(np.asarray(x, dtype=float)) for x in (velocity, density, mach))))
            check_sweep(V, rho, M, sweep)
            out.append(_case_dataset(prob, V, rho, M, sweep=sweep, interpolation=interpolation,
                                     refine=refine, g_tol=g_tol))
    return out


def _case_dataset(prob: GProblem, V, rho, M, *, sweep, interpolation, refine, g_tol) -> xr.Dataset:
    """Roots, warnings, crossings and the result Dataset of one sweep."""
    pts = list(zip(V, rho, M))
    p, u, conv, outside = _sweep(prob, pts)
    _warn_outside(prob, p, outside, V, M)
    g = prob.damping(p, V[:, None])
    crossings, vectors = [], []
    k_min = np.array([prob.interpolator(m).k_min for m in M])
    drift = drift_roots(p, V, prob.b, k_min, prob.omega0 < 2 * np.pi * prob.rigid_hz)
    for r, i in find_brackets(resolved_damping(g, drift), g_tol):
        if refine:
            t, pr, ur, ok = _refine_crossing(prob, pts, p, u, r, i, g[i, r], g[i + 1, r])
        else:
            t = interpolate_zero(g[i, r], g[i + 1, r])
            pr = p[i, r] + t * (p[i + 1, r] - p[i, r])
            ur, ok = (u[i, r] if t < 0.5 else u[i + 1, r]), True
        Vc, rc, Mc = (a + t * (b - a) for a, b in zip(pts[i], pts[i + 1]))
        real = pr.imag == 0
        vectors.append(ur)
        crossings.append(Crossing(root=r + 1, index=i, t=float(t), velocity=float(Vc),
                                  density=float(rc), mach=float(Mc),
                                  frequency=0.0 if real else float(pr.imag / (2 * np.pi)),
                                  kind="divergence" if real else "flutter",
                                  converged=bool(ok and conv[i, r] and conv[i + 1, r]),
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
