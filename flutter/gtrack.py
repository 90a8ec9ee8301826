"""The g-method's roots along a sweep of flight points: exactly one per mode, tracked by continuity.

First point. The reduced-frequency sweep (:meth:`flutter.gkernel.GProblem.roots`) gives every
candidate root; the candidates (real roots at k = 0 and the k > 0 roots) outnumber the modes (a
complex pair gives one root, its two real limits two), so exactly system.n are kept by optimal
assignment (flutter.tracking.assign) to references: elastic mode r at i omega_r with its in-vacuo
modal participation, and the rigid-body modes (in-vacuo frequency below ``rigid_hz``) at the
eigenvalue branches of the quasi-steady system at that point (:func:`flutter.rigid_start.
rigid_branches`, as p-k's start; each branch solved locally to its g-method root, which joins
the candidates: the sweep misses roots whose k lies below its first k > 0, such as the drift pair).
Without that, every rigid mode sits at i omega_r = 0 and the assignment prefers the near-zero real
candidates to the short period (the X-56-class example: its short period came out as a real root).

Next points. Each root is continued from the previous point (eigenvalue extrapolated along the
path) by the local solve :meth:`~flutter.gkernel.GProblem.correct`. A step is kept when every root
converged, stayed near its own prediction (jump below half the distance to the nearest other
prediction), kept its eigenvector (MAC >= ``MAC_MIN`` unless it hardly moved) and no two roots
landed on the same eigenpair (the checks of flutter.pk_solver); otherwise it is bisected up to
``MAX_DEPTH`` times, and a step still bad at the smallest size falls back to the sweep at its end
point, its candidates assigned to the roots that converged (their own solutions) and the
predictions of the others (eigenvector correlation and distance). This is how a complex pair that
splits into two real roots continues: as the nearer real root, the other real root stays a
candidate and is picked up when a root needs it; the near-zero plunge / flight-path cluster of a
free-free aircraft is either one complex root with tiny k or real roots, whichever continues the
root. Missing candidates (never seen in the tests) repeat the previous point, flagged.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from flutter.gkernel import GProblem
from flutter.linalg import path_length, unit_rows
from flutter.rigid_start import rigid_branches
from flutter.tracking import assign

MAC_MIN = 0.7   # eigenvector correlation below which a root that moved is a jump
MAX_DEPTH = 3   # bisections of a bad continuation step before the sweep is used
_BIG = 1e30     # eigenvalue of a placeholder candidate: never preferred by the assignment


@dataclass
class GState:
    """Roots at one flight point (internal working state): p (R,) rad/s, Im p >= 0, real roots
    exactly real; right / left vectors u, w (R, n); converged and outside-the-table flags (R,);
    slope dp per unit path length of the last step (predictor)."""

    p: np.ndarray
    u: np.ndarray
    w: np.ndarray
    converged: np.ndarray
    outside: np.ndarray
    slope: np.ndarray


def match(p_ref, u_ref, p, u, ok, out):
    """Exactly len(p_ref) roots out of the candidates (assignment; placeholders if too few).

    Parameters
    ----------
    p_ref : ndarray, shape (R,) complex
        Reference eigenvalues (rad/s).
    u_ref : ndarray, shape (R, n)
        Reference eigenvectors.
    p, u, ok, out : ndarray, shapes (m,), (m, n), (m,), (m,)
        Candidates from :meth:`GProblem.roots`.

    Returns
    -------
    p, u, ok, out : the chosen candidates, shapes (R,), (R, n), (R,), (R,)
    missing : ndarray of bool, shape (R,)
        No candidate was left for the root (placeholder).
    """
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


def sweep_roots(prob: GProblem, pts: list[tuple]):
    """Roots at every flight point, exactly n per point, tracked from the modes (module docstring).

    Parameters
    ----------
    prob : GProblem
    pts : list of (V, rho, mach)
        Flight points along the sweep.

    Returns
    -------
    p : ndarray, shape (npts, n) complex
        Roots (rad/s), root r starting from in-vacuo mode r.
    u, w : ndarray, shape (npts, n, n)
        Right and left eigenvectors (unit 2-norm).
    converged, outside : ndarray of bool, shape (npts, n)
    """
    state = _first(prob, pts[0])
    out = [state]
    for frm, to in zip(pts[:-1], pts[1:]):
        state = _advance(prob, state, frm, to, 0)
        out.append(state)
    return tuple(np.array([getattr(s, f) for s in out])
                 for f in ("p", "u", "w", "converged", "outside"))


def _first(prob: GProblem, pt: tuple) -> GState:
    """Roots at the first flight point: sweep candidates assigned to the modes' references."""
    V, rho, mach = pt
    n, s = prob.system.n, prob.b / V
    mphi = prob.system.mass @ prob.phi
    p_ref, u_ref = 1j * prob.omega0.astype(complex), mphi.T.astype(complex)
    rigid = np.flatnonzero(prob.omega0 < 2 * np.pi * prob.rigid_hz)
    if rigid.size:
        lam, U, _ = prob.eig(np.zeros(1), V, rho, mach)
        pick = rigid_branches(lam[0], U[0], mphi, rigid, 1e-3 * float(prob.omega0.max()) * s)
        flip = lam[0, pick].imag < 0
        pr = np.where(flip, lam[0, pick].conj(), lam[0, pick])
        ur = np.where(flip[:, None], U[0, pick].conj(), U[0, pick])
        # quasi-steady guess -> the g-method root (Im p_bar = k; real eigenvalues are roots)
        pc, uc, _, solved, _ = prob.correct(pr, ur, ur.conj(), V, rho, mach)
        pr, ur = np.where(solved, pc, pr), np.where(solved[:, None], uc, ur)
        p_ref[rigid], u_ref[rigid] = pr / s, ur
    p, u, ok, outside = prob.roots(V, rho, mach)
    if rigid.size and solved.any():  # the sweep misses roots below its first k > 0 (drift pair)
        tol = 1e-6 * np.maximum(np.abs(p), 1e-3 * float(prob.omega0.max()))
        new = (np.abs(p[:, None] - pr[solved][None, :] / s) > tol[:, None]).all(axis=1)
        p, u = np.concatenate([p[new], pr[solved] / s]), np.concatenate([u[new], ur[solved]])
        ok = np.concatenate([ok[new], np.ones(solved.sum(), dtype=bool)])
        outside = np.concatenate([outside[new], np.zeros(solved.sum(), dtype=bool)])
    p, u, ok, outside, missing = match(p_ref, u_ref, p, u, ok, outside)
    p[missing], u[missing] = p_ref[missing], unit_rows(u_ref[missing])
    return GState(p, u, u.conj(), ok & ~outside & ~missing, outside, np.zeros(n, dtype=complex))


def _advance(prob: GProblem, state: GState, frm: tuple, to: tuple, depth: int) -> GState:
    """Continue every root from ``frm`` to ``to`` by the local solve, bisecting bad steps."""
    V, rho, mach = to
    s, h = prob.b / V, path_length(frm, to)
    pred = state.p + state.slope * h
    pred = np.where(state.p.imag == 0, pred.real + 0j, np.where(pred.imag > 0, pred, state.p))
    pb, u, w, ok, outside = prob.correct(pred * s, state.u, state.w, V, rho, mach)
    p = pb / s
    good = _step_ok(prob, state, p, u, ok, pred)
    if good.all():
        return _accepted(state, GState(p, u, w, ok & ~outside, outside, state.slope), h)
    if depth < MAX_DEPTH:
        mid = tuple(0.5 * (a + b) for a, b in zip(frm, to))
        return _advance(prob, _advance(prob, state, frm, mid, depth + 1), mid, to, depth + 1)
    ref = np.where(good, p, pred)
    u_ref = np.where(good[:, None], u, state.u)
    pc, uc, okc, outc = prob.roots(V, rho, mach)
    pc, uc, okc, outc, missing = match(ref, u_ref, pc, uc, okc, outc)
    pc[missing], uc[missing] = state.p[missing], state.u[missing]
    new = GState(pc, uc, uc.conj(), okc & ~outc & ~missing, outc, state.slope)
    kind = (new.p.imag == 0) == (state.p.imag == 0)
    new = _accepted(state, new, h)
    new.slope = np.where(kind & ~missing, new.slope, 0.0)
    return new


def _accepted(old: GState, new: GState, h: float) -> GState:
    """``new`` with the predictor slope of the step from ``old``."""
    new.slope = (new.p - old.p) / h if h > 0 else np.zeros_like(new.p)
    return new


def _step_ok(prob: GProblem, old: GState, p, u, ok, pred) -> np.ndarray:
    """Roots that passed the step checks (module docstring), shape (R,) bool."""
    scale = 1e-3 * float(prob.omega0.max())
    sep = np.abs(pred[:, None] - pred[None, :])
    np.fill_diagonal(sep, np.inf)
    jump = np.abs(p - pred) / np.maximum(sep.min(axis=1), scale)
    mac = np.abs(np.einsum("ri,ri->r", old.u.conj(), u)) ** 2
    good = ok & (jump <= 0.5) & ((mac >= MAC_MIN) | (jump <= 0.05))
    dp = np.abs(p[:, None] - p[None, :])
    same = (dp <= 1e-6 * np.maximum(np.abs(p)[:, None], scale)) & \
        (np.abs(u.conj() @ u.T) ** 2 > 0.99)
    np.fill_diagonal(same, False)
    return good & ~same.any(axis=1)
