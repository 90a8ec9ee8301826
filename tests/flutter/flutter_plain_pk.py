"""A plain per-root p-k (one full eigen-decomposition per root per iteration), kept as the reference.

Deliberately simple and independent of flutter.pk's continuation kernel: for each velocity and each
root, k is iterated with a full eigen-decomposition of the 2n x 2n first-order matrix
    A(k) = [[0, I], [-M^-1 (K - q Q^R), -M^-1 (B - rho b V Q^I / (2k))]]
(Nastran PK), taking the eigenvalue nearest the root's value at the previous velocity. Crossings are
located by bisection on V with the same procedure.
"""
from __future__ import annotations

import numpy as np
from scipy.interpolate import interp1d


def make_q(k_grid, Q):
    """Linear interpolants of Q^R and Q^I/k, held constant outside the table."""
    k_grid = np.asarray(k_grid, dtype=float)
    QR = interp1d(k_grid, Q.real, axis=0, bounds_error=False, fill_value=(Q.real[0], Q.real[-1]))
    D = Q.imag / k_grid[:, None, None]
    QD = interp1d(k_grid, D, axis=0, bounds_error=False, fill_value=(D[0], D[-1]))
    return lambda k: (QR(k), QD(k))


def root_at(M, K, B, q_of_k, b, V, rho, p_prev, g_s=0.0, tol=1e-10, max_iter=200):
    """One root at one velocity: iterate k with a full eigen-decomposition per iteration."""
    n = M.shape[0]
    Minv = np.linalg.inv(M)
    p = p_prev
    for _ in range(max_iter):
        k = b * abs(p.imag) / V
        QR, D = q_of_k(k)
        omega = k * V / b
        C = B - 0.5 * rho * b * V * D + (g_s / omega * K if (g_s and omega > 1e-12) else 0.0)
        Kt = K - 0.5 * rho * V * V * QR
        A = np.block([[np.zeros((n, n)), np.eye(n)], [-Minv @ Kt, -Minv @ C]])
        lam, X = np.linalg.eig(A)
        lam = np.where(lam.imag < 0, lam.conj(), lam)
        j = int(np.argmin(np.abs(lam - p)))
        p_new = lam[j]
        if abs(p_new - p) <= tol * max(abs(p_new), 1e-6):
            return p_new, X[:n, j]
        p = p_new
    return p, X[:n, j]


def sweep(M, K, B, q_of_k, b, velocities, rho, p0, g_s=0.0):
    """All roots along increasing velocities, each started from its previous value."""
    P = np.zeros((len(velocities), len(p0)), dtype=complex)
    p = np.asarray(p0, dtype=complex)
    for i, V in enumerate(velocities):
        p = np.array([root_at(M, K, B, q_of_k, b, V, rho, pr, g_s)[0] for pr in p])
        P[i] = p
    return P


def damping(p):
    """g = 2 Re(p) / Im(p) for oscillatory roots."""
    return 2 * p.real / p.imag


def crossing(M, K, B, q_of_k, b, V_lo, V_hi, rho, p_lo, g_s=0.0, vtol=1e-6):
    """Flutter crossing of one root between V_lo (g < 0) and V_hi (g > 0) by bisection."""
    p_a = p_lo
    lo, hi = V_lo, V_hi
    while hi - lo > vtol * hi:
        mid = 0.5 * (lo + hi)
        p_m = root_at(M, K, B, q_of_k, b, mid, rho, p_a, g_s)[0]
        if damping(p_m) < 0:
            lo, p_a = mid, p_m
        else:
            hi = mid
    p_c = root_at(M, K, B, q_of_k, b, 0.5 * (lo + hi), rho, p_a, g_s)[0]
    return 0.5 * (lo + hi), abs(p_c.imag) / (2 * np.pi)
