"""Root tracking between consecutive solutions by eigenvector correlation and eigenvalue continuity.

Used where a method returns all roots at once (k-method, state-space, full eigen-decompositions): the
roots of step i+1 are assigned to the roots of step i by the optimal assignment (Hungarian method,
scipy.optimize.linear_sum_assignment) on a cost combining the loss of eigenvector correlation
(1 - MAC) and the eigenvalue jump relative to the spread of the roots, never by sorting.
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment


def mac_matrix(u_old: np.ndarray, u_new: np.ndarray) -> np.ndarray:
    """Modal assurance criterion |u_i^H v_j|^2 / (|u_i|^2 |v_j|^2) between two vector sets.

    Parameters
    ----------
    u_old : ndarray, shape (r, n)
    u_new : ndarray, shape (s, n)

    Returns
    -------
    ndarray, shape (r, s)
    """
    num = np.abs(np.conj(u_old) @ u_new.T) ** 2
    den = np.outer(np.sum(np.abs(u_old) ** 2, axis=1), np.sum(np.abs(u_new) ** 2, axis=1))
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(den > 0, num / np.where(den > 0, den, 1), 0.0)


def assign(p_old: np.ndarray, u_old: np.ndarray, p_new: np.ndarray, u_new: np.ndarray,
           weight: float = 1.0) -> np.ndarray:
    """Order of the new roots that continues the old ones.

    Parameters
    ----------
    p_old, p_new : ndarray, shape (r,) complex
        Eigenvalues (or any complex root label, e.g. omega (1 + i g / 2)).
    u_old, u_new : ndarray, shape (r, n)
        Eigenvectors.
    weight : float
        Weight of the eigenvalue-distance term against (1 - MAC).

    Returns
    -------
    perm : ndarray of int, shape (r,)
        ``p_new[perm]`` continues ``p_old`` root by root.
    """
    mac = mac_matrix(u_old, u_new)
    spread = max(float(np.ptp(np.abs(p_old))), float(np.abs(p_old).max()) * 1e-3, 1e-12)
    dist = np.abs(p_old[:, None] - p_new[None, :]) / spread
    _, cols = linear_sum_assignment((1.0 - mac) + weight * dist)
    return cols
