"""Rigid-body roots at the first flight point: the quasi-steady eigenvalue that starts each one.

A free aircraft's rigid-body roots cannot be followed up from V -> 0, where all of them sit at
p = 0: a continuation from there picks an eigenvalue branch at random (Nastran's bah_plane: two
slightly unstable ~0 Hz roots instead of a short period with g ~ -2.3). Both the p-k
(flutter.pk_solver) and the g-method (flutter.gtrack) start them instead from the eigenvalues of
the quasi-steady system [M p^2 + C(0) p + K_t(0)] at the first flight point (Q^R and Q^I/k at
k -> 0; the p-k and g-method equations coincide there), one root per eigenvalue branch
(:func:`rigid_branches`).
"""
from __future__ import annotations

import numpy as np
from scipy.optimize import linear_sum_assignment


def rigid_branches(lam: np.ndarray, U: np.ndarray, mphi: np.ndarray, rigid: np.ndarray,
                   scale: float) -> np.ndarray:
    """The eigenvalue branches that start the rigid-body roots, one per rigid mode.

    The 2 n_r eigenvalues whose eigenvectors lie most in the rigid modes (mass-weighted share of the
    in-vacuo rigid coordinates) are the rigid branches: every oscillatory pair gives one root
    (Im p > 0: the short period, the dutch roll, ...), and the real eigenvalues (the near-zero
    plunge / flight-path pair, or a pair already split) fill the remaining rigid roots, smallest
    |p| first. Each branch is given to the rigid mode it participates in most (assignment over
    the rigid modes).

    Parameters
    ----------
    lam : ndarray, shape (2n,) complex
        Eigenvalues of the first-order quasi-steady system (any consistent unit: p or p b / V).
    U : ndarray, shape (2n, n) complex
        Right eigenvectors u of the quadratic problem, one row per eigenvalue.
    mphi : ndarray, shape (n, n)
        M_hh Phi: mass matrix times the in-vacuo mode shapes (columns), for the modal coordinates.
    rigid : ndarray of int, shape (n_r,)
        Indices of the rigid-body modes.
    scale : float
        Eigenvalues with |Im| <= 1e-9 max(|lam|, scale) are real (same unit as ``lam``).

    Returns
    -------
    ndarray of int, shape (n_r,)
        Index into ``lam`` of the branch of each rigid mode, in the order of ``rigid`` (an
        oscillatory branch may be given by its Im < 0 member: the caller conjugates it).
    """
    nr = rigid.size
    c = np.abs(U @ mphi) ** 2                      # in-vacuo modal coordinates
    share = c[:, rigid].sum(axis=1) / np.maximum(c.sum(axis=1), 1e-300)
    ranked = np.argsort(-share, kind="stable")
    branch = ranked[:2 * nr]
    real = np.abs(lam.imag) <= 1e-9 * np.maximum(np.abs(lam), scale)
    osc = [j for j in branch if not real[j] and lam[j].imag > 0]
    unit = U / np.maximum(np.linalg.norm(U, axis=1, keepdims=True), 1e-300)

    def new_branch(j, taken):
        """Not a repeat of a taken eigenvector: a defective double root (surge or sway of a free
        aircraft, on which the aerodynamics act not at all) has one eigenvector twice."""
        return all(abs(np.vdot(unit[i], unit[j])) ** 2 < 0.99 for i in taken)

    pick = list(osc)
    for j in sorted((j for j in branch if real[j]), key=lambda j: abs(lam[j])):
        if len(pick) < nr and new_branch(j, pick):
            pick.append(j)
    for j in ranked[2 * nr:]:  # short of branches (repeats, an unpaired oscillatory eigenvalue)
        if len(pick) < nr and (real[j] or lam[j].imag > 0) and new_branch(j, pick):
            pick.append(j)
    pick = np.array(pick[:nr])
    rows, cols = linear_sum_assignment(-c[np.ix_(pick, rigid)])
    return pick[rows[np.argsort(cols)]]
